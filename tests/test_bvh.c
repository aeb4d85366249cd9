/* test_bvh.c - the BVH finds what the thesis's flat structure finds.
 *
 * The flat structure tests every triangle of every shape box a ray meets, so it is the
 * reference: for each mesh, random rays must give the same closest hit through both
 * (the same triangle and distance, or, where two triangles lie at the same distance, a
 * floating-point tie), the same misses, and any-hit must agree with closest-hit. The
 * tree itself is checked node by node, degenerate input must neither crash the builder
 * nor ever be hit, refitting after a move must keep the answers right, and a rendered
 * image must not change when the acceleration structure does.
 *
 * A BVH view is traced three ways, each compared with the flat structure: through the
 * wide BVH with the SIMD code chosen at run time (what tr_intersect_scene does), through
 * the same wide BVH with the portable scalar code (tr_wbvh_trace_isa; test_isa.c compares
 * every ISA with it hit for hit), and through the binary BVH alone (--accel bvh2, and what
 * devices trace). */
#include <stdlib.h>
#include <string.h>

#include <omp.h>

#include "check.h"
#include "accel/wbvh.h"
#include "kernel/kernel.h"
#include "scene/scene_internal.h"
#include "trac0r/trac0r.h"
#include "util/bigmem.h"

/* Rays per mesh for the main comparisons (the brief asks for at least 100 000) and
 * for the stress meshes, whose flat traversal is a brute-force loop. */
#define RAYS 100000u
#define STRESS_RAYS 5000u
/* Same triangle: distances within this relative tolerance. */
#define SAME_T_TOL 1e-4
/* Different triangle: accepted only as a tie, at the same distance within this. */
#define TIE_T_TOL 1e-6
/* Ties between triangles that are not duplicates of one another (shared edges and
 * vertices) must stay below this fraction of the hits. */
#define MAX_TIE_FRACTION 0.005
/* Triangles per flat node for the hand-built meshes. The flat structure is correct
 * with any grouping; small, spatially sorted groups only make the reference fast. */
#define FLAT_CHUNK 32u

/* ---- small helpers ------------------------------------------------------------------ */

static float get_comp(tr_vec3 v, int k) {
    return k == 0 ? v.x : k == 1 ? v.y : v.z;
}

static tr_vec3 with_comp(tr_vec3 v, int k, float value) {
    if (k == 0) {
        v.x = value;
    } else if (k == 1) {
        v.y = value;
    } else {
        v.z = value;
    }
    return v;
}

static uint32_t rng_below(tr_rng *r, uint32_t n) {
    return (uint32_t)(tr_rng_next(r) % n);
}

static tr_vec3 rand_unit(tr_rng *r) {
    float z = tr_rng_range(r, -1.0f, 1.0f);
    float phi = tr_rng_range(r, 0.0f, TR_TWO_PI);
    float s = sqrtf(fmaxf(0.0f, 1.0f - z * z));
    return v3(s * cosf(phi), s * sinf(phi), z);
}

static tr_vec3 rand_in_box(tr_rng *r, tr_aabb b) {
    return v3(tr_rng_range(r, b.min.x, b.max.x), tr_rng_range(r, b.min.y, b.max.y),
              tr_rng_range(r, b.min.z, b.max.z));
}

/* A uniform point on the triangle (the square folded onto it). */
static tr_vec3 rand_on_tri(tr_rng *r, const tr_triangle *t) {
    float u = tr_rng_float(r), v = tr_rng_float(r);
    if (u + v > 1.0f) {
        u = 1.0f - u;
        v = 1.0f - v;
    }
    tr_vec3 p = v3_madd(t->v0, v3_sub(t->v1, t->v0), u);
    return v3_madd(p, v3_sub(t->v2, t->v0), v);
}

static int tri_valid(const tr_triangle *t) {
    return t->area > 0.0f && v3_is_finite(t->v0) && v3_is_finite(t->v1) && v3_is_finite(t->v2);
}

static int vec_eq(tr_vec3 a, tr_vec3 b) {
    return a.x == b.x && a.y == b.y && a.z == b.z;
}

/* Whether two triangles have the same vertex set: hitting either is a tie by design. */
static int tri_duplicates(const tr_triangle *a, const tr_triangle *b) {
    tr_vec3 av[3] = {a->v0, a->v1, a->v2}, bv[3] = {b->v0, b->v1, b->v2};
    for (int i = 0; i < 3; ++i) {
        int in_b = 0, in_a = 0;
        for (int j = 0; j < 3; ++j) {
            in_b |= vec_eq(av[i], bv[j]);
            in_a |= vec_eq(bv[i], av[j]);
        }
        if (!in_b || !in_a) {
            return 0;
        }
    }
    return 1;
}

/* The box of the valid triangles (the builder's root box), or the unit cube if none. */
static tr_aabb valid_bounds(const tr_triangle *t, uint32_t n) {
    tr_aabb b = {v3s(INFINITY), v3s(-INFINITY)};
    for (uint32_t i = 0; i < n; ++i) {
        if (tri_valid(&t[i])) {
            b.min = v3_min(b.min, v3_min(t[i].v0, v3_min(t[i].v1, t[i].v2)));
            b.max = v3_max(b.max, v3_max(t[i].v0, v3_max(t[i].v1, t[i].v2)));
        }
    }
    if (!(b.min.x <= b.max.x)) {
        b.min = v3s(0.0f);
        b.max = v3s(1.0f);
    }
    return b;
}

/* ---- hand-built scenes ------------------------------------------------------------- */

/* Replaces the scene's shape list by runs of `chunk` consecutive triangles, each with its
 * exact box, so that the flat structure culls; chunk 0 makes one node over everything. */
static void set_flat_nodes(tr_scene *s, uint32_t chunk) {
    free(s->shapes);
    s->shapes = NULL;
    s->shape_count = s->shape_capacity = 0;
    uint32_t n = s->triangle_count;
    if (n == 0) {
        return;
    }
    if (chunk == 0) {
        chunk = n;
    }
    uint32_t count = (n + chunk - 1) / chunk;
    s->shapes = malloc((size_t)count * sizeof *s->shapes);
    if (!s->shapes) {
        abort();
    }
    for (uint32_t c = 0; c < count; ++c) {
        tr_flat_node *node = &s->shapes[c];
        node->first = c * chunk;
        node->count = node->first + chunk <= n ? chunk : n - node->first;
        node->box = tr_triangles_bounds(s->triangles + node->first, node->count);
    }
    s->shape_count = s->shape_capacity = count;
}

/* A scene owning `tris` (malloc'd, n of them, taken over), one diffuse material, every
 * triangle finished, and a flat structure of FLAT_CHUNK-triangle nodes. */
static void scene_from_triangles(tr_scene *s, tr_triangle *tris, uint32_t n) {
    tr_error err;
    tr_scene_init(s);
    CHECK(tr_scene_add_material(s, tr_material_diffuse(v3s(0.5f)), NULL, &err) == TR_OK, "%s",
          err.msg);
    for (uint32_t i = 0; i < n; ++i) {
        tris[i].material = 0;
        tr_triangle_finish(&tris[i]);
    }
    s->triangles = tris;
    s->triangle_count = s->triangle_capacity = n;
    set_flat_nodes(s, FLAT_CHUNK);
}

static tr_triangle *alloc_tris(uint32_t n) {
    tr_triangle *t = calloc(n ? n : 1, sizeof *t);
    if (!t) {
        abort();
    }
    return t;
}

/* Morton order of triangle centroids, so that runs of consecutive triangles are compact
 * and the flat reference's nodes cull well. */
typedef struct keyed {
    uint64_t key;
    tr_triangle tri;
} keyed;

static int keyed_cmp(const void *a, const void *b) {
    uint64_t x = ((const keyed *)a)->key, y = ((const keyed *)b)->key;
    return x < y ? -1 : x > y;
}

static uint64_t spread_bits(uint64_t v) {
    uint64_t r = 0;
    for (int i = 0; i < 10; ++i) {
        r |= ((v >> i) & 1u) << (3 * i);
    }
    return r;
}

static void sort_spatially(tr_triangle *t, uint32_t n) {
    if (n < 2) {
        return;
    }
    tr_aabb b = {v3s(INFINITY), v3s(-INFINITY)};
    for (uint32_t i = 0; i < n; ++i) {
        tr_vec3 c = v3_scale(v3_add(v3_add(t[i].v0, t[i].v1), t[i].v2), 1.0f / 3.0f);
        b.min = v3_min(b.min, c);
        b.max = v3_max(b.max, c);
    }
    keyed *k = malloc((size_t)n * sizeof *k);
    if (!k) {
        abort();
    }
    for (uint32_t i = 0; i < n; ++i) {
        tr_vec3 c = v3_scale(v3_add(v3_add(t[i].v0, t[i].v1), t[i].v2), 1.0f / 3.0f);
        uint64_t key = 0;
        for (int a = 0; a < 3; ++a) {
            float lo = get_comp(b.min, a), ext = get_comp(b.max, a) - lo;
            float f = ext > 0.0f ? (get_comp(c, a) - lo) / ext : 0.0f;
            uint64_t q = (uint64_t)(fminf(fmaxf(f, 0.0f), 1.0f) * 1023.0f);
            key |= spread_bits(q) << a;
        }
        k[i].key = key;
        k[i].tri = t[i];
    }
    qsort(k, n, sizeof *k, keyed_cmp);
    for (uint32_t i = 0; i < n; ++i) {
        t[i] = k[i].tri;
    }
    free(k);
}

/* 20 000 triangles in the unit cube: 19 800 small ones of sizes from 0.002 to 0.1, and
 * 200 with vertices anywhere in the cube, which overlap everything. */
static tr_triangle *make_soup(tr_rng *r, uint32_t *n_out) {
    const uint32_t small = 19800, big = 200, n = small + big;
    tr_triangle *t = alloc_tris(n);
    tr_aabb cube = {v3s(0.0f), v3s(1.0f)};
    tr_aabb unit = {v3s(-1.0f), v3s(1.0f)};
    for (uint32_t i = 0; i < small; ++i) {
        tr_vec3 c = rand_in_box(r, cube);
        float size = 0.002f * powf(50.0f, tr_rng_float(r));
        t[i].v0 = v3_madd(c, rand_in_box(r, unit), size);
        t[i].v1 = v3_madd(c, rand_in_box(r, unit), size);
        t[i].v2 = v3_madd(c, rand_in_box(r, unit), size);
    }
    sort_spatially(t, small);
    for (uint32_t i = small; i < n; ++i) {
        t[i].v0 = rand_in_box(r, cube);
        t[i].v1 = rand_in_box(r, cube);
        t[i].v2 = rand_in_box(r, cube);
    }
    *n_out = n;
    return t;
}

/* Long thin triangles: 0.2 long, 2e-5 wide (aspect ratio 1e4), any orientation. */
static tr_triangle *make_slivers(tr_rng *r, uint32_t *n_out) {
    const uint32_t n = 3000;
    tr_triangle *t = alloc_tris(n);
    tr_aabb cube = {v3s(0.0f), v3s(1.0f)};
    for (uint32_t i = 0; i < n; ++i) {
        tr_vec3 c = rand_in_box(r, cube);
        tr_vec3 along = rand_unit(r), side = v3_normalize(v3_cross(along, rand_unit(r)));
        t[i].v0 = v3_madd(c, along, -0.1f);
        t[i].v1 = v3_madd(c, along, 0.1f);
        t[i].v2 = v3_madd(c, side, 2e-5f);
    }
    sort_spatially(t, n);
    *n_out = n;
    return t;
}

/* Two grids of coplanar quads (one in z = 0.5, one in the tilted plane x = y) with every
 * triangle present three times: most hits are ties by construction. The grid's
 * coordinates are multiples of 1/32, so shared edges are exactly shared. */
static tr_triangle *make_coplanar(uint32_t *n_out) {
    const uint32_t g = 24, copies = 3, n = 2 * g * g * 2 * copies;
    tr_triangle *t = alloc_tris(n);
    uint32_t k = 0;
    for (uint32_t plane = 0; plane < 2; ++plane) {
        for (uint32_t i = 0; i < g; ++i) {
            for (uint32_t j = 0; j < g; ++j) {
                float a0 = (float)i / 32.0f, a1 = (float)(i + 1) / 32.0f;
                float b0 = (float)j / 32.0f, b1 = (float)(j + 1) / 32.0f;
                tr_vec3 p00, p10, p11, p01;
                if (plane == 0) {
                    p00 = v3(a0, b0, 0.5f), p10 = v3(a1, b0, 0.5f);
                    p11 = v3(a1, b1, 0.5f), p01 = v3(a0, b1, 0.5f);
                } else {
                    p00 = v3(a0, a0, b0), p10 = v3(a1, a1, b0);
                    p11 = v3(a1, a1, b1), p01 = v3(a0, a0, b1);
                }
                for (uint32_t c = 0; c < copies; ++c) {
                    t[k].v0 = p00, t[k].v1 = p10, t[k].v2 = p11, ++k;
                    t[k].v0 = p00, t[k].v1 = p11, t[k].v2 = p01, ++k;
                }
            }
        }
    }
    *n_out = k;
    return t;
}

/* ---- the comparison ---------------------------------------------------------------- */

typedef struct ray_gen {
    tr_rng rng;
    tr_aabb bounds;
    tr_vec3 center;
    float radius; /* half the bounds' diagonal */
    const tr_triangle *tris;
    uint32_t *targets; /* triangles rays are aimed at */
    uint32_t target_count;
} ray_gen;

/* Aims at every triangle for which `aim` holds (all valid ones when aim is NULL). */
static void ray_gen_init(ray_gen *g, uint64_t seed, const tr_triangle *tris, uint32_t n,
                         int (*aim)(const tr_triangle *)) {
    tr_rng_init(&g->rng, seed, 0, 0);
    g->bounds = valid_bounds(tris, n);
    g->center = v3_scale(v3_add(g->bounds.min, g->bounds.max), 0.5f);
    g->radius = fmaxf(0.5f * v3_length(v3_sub(g->bounds.max, g->bounds.min)), 1e-3f);
    g->tris = tris;
    g->targets = malloc((size_t)(n ? n : 1) * sizeof *g->targets);
    if (!g->targets) {
        abort();
    }
    g->target_count = 0;
    for (uint32_t i = 0; i < n; ++i) {
        if (aim ? aim(&tris[i]) : tri_valid(&tris[i])) {
            g->targets[g->target_count++] = i;
        }
    }
}

static void ray_gen_free(ray_gen *g) {
    free(g->targets);
}

/* A random ray: origins inside and outside the bounds; random directions, directions at
 * random points of random triangles (so that many hit), directions along an axis or with
 * one component exactly +-0 (infinite reciprocals in the slab test); infinite or random
 * finite tmax, and now and then a tmin above zero. */
static tr_ray next_ray(ray_gen *g) {
    tr_rng *r = &g->rng;
    tr_vec3 o;
    if (tr_rng_float(r) < 0.5f) {
        /* Inside, or just outside: the bounds grown by a quarter. */
        tr_vec3 grow = v3_scale(v3_sub(g->bounds.max, g->bounds.min), 0.25f);
        tr_aabb b = {v3_sub(g->bounds.min, grow), v3_add(g->bounds.max, grow)};
        o = rand_in_box(r, b);
    } else {
        o = v3_madd(g->center, rand_unit(r), g->radius * tr_rng_range(r, 1.2f, 3.0f));
    }
    uint32_t kind = rng_below(r, 8);
    tr_vec3 d;
    if (kind <= 1 || g->target_count == 0) {
        d = rand_unit(r);
        if (kind == 1) {
            /* Two components zero half the time, one otherwise. */
            int k = (int)rng_below(r, 3);
            d = with_comp(d, k, tr_rng_float(r) < 0.5f ? 0.0f : -0.0f);
            if (tr_rng_float(r) < 0.5f) {
                d = with_comp(d, (k + 1) % 3, 0.0f);
            }
            if (vec_eq(d, v3s(0.0f))) {
                d = v3(0.0f, 0.0f, 1.0f);
            }
            d = v3_normalize(d);
        }
    } else {
        const tr_triangle *t = &g->tris[g->targets[rng_below(r, g->target_count)]];
        tr_vec3 target = rand_on_tri(r, t);
        if (kind == 5) {
            /* Exactly along an axis, from in front of or behind the point. */
            int k = (int)rng_below(r, 3);
            float sign = tr_rng_float(r) < 0.5f ? -1.0f : 1.0f;
            d = with_comp(v3s(0.0f), k, sign);
            o = v3_madd(target, d, -g->radius * tr_rng_range(r, -0.5f, 3.0f));
        } else {
            if (kind == 6) {
                /* In the axis plane through the point: one direction component is 0. */
                int k = (int)rng_below(r, 3);
                o = with_comp(o, k, get_comp(target, k));
            }
            d = v3_sub(target, o);
            if (!(v3_length(d) > 0.0f)) {
                d = rand_unit(r);
            }
            d = v3_normalize(d);
        }
    }
    float tmin = 0.0f, tmax = TR_INFINITY;
    if (rng_below(r, 8) == 0) {
        tmin = tr_rng_range(r, 0.0f, 0.05f * g->radius);
    }
    if (rng_below(r, 3) == 0) {
        tmax = tr_rng_range(r, 0.0f, 4.0f * g->radius);
    }
    return tr_ray_make(o, d, tmin, tmax);
}

/* The ways a BVH view is traced (see the top of the file). */
enum { V_WIDE, V_WIDE_SCALAR, V_BVH2, VARIANTS };
static const char *const variant_name[VARIANTS] = {"wide bvh", "wide bvh (scalar)", "bvh2"};

typedef struct cmp_stats {
    uint64_t rays, hits, mismatches, anyhit_mismatches;
    uint64_t ties, dup_ties; /* of the wide BVH with this build's SIMD code */
    uint64_t variant_ties[VARIANTS], variant_dup_ties[VARIANTS];
} cmp_stats;

/* How many ways the view is traced: three for a view with a wide BVH, else one. */
static int variants_of(const tr_scene_view *v) {
    return v->accel == TR_ACCEL_BVH && v->wbvh ? VARIANTS : 1;
}

static int trace_variant(const tr_scene_view *v, int variant, const tr_ray *ray, tr_hit *hit,
                         int any_hit) {
    tr_scene_view bin = *v;
    switch (variant) {
    case V_WIDE_SCALAR:
        return tr_wbvh_trace_isa(TR_WBVH_ISA_SCALAR, v->wbvh, ray, hit, any_hit);
    case V_BVH2:
        bin.wbvh = NULL;
        return any_hit ? tr_occluded_scene(&bin, ray) : tr_intersect_scene(&bin, ray, hit);
    default:
        return any_hit ? tr_occluded_scene(v, ray) : tr_intersect_scene(v, ray, hit);
    }
}

static void print_ray(const char *name, const char *what, const tr_ray *ray) {
    fprintf(stderr, "  %s: %s: origin (%a, %a, %a) dir (%a, %a, %a) tmin %a tmax %a\n", name, what,
            (double)ray->origin.x, (double)ray->origin.y, (double)ray->origin.z, (double)ray->dir.x,
            (double)ray->dir.y, (double)ray->dir.z, (double)ray->tmin, (double)ray->tmax);
}

/* Traces one ray through both views (the BVH view each way it has) and records how the
 * answers compare. */
static void compare_ray(const char *name, const tr_scene_view *flat, const tr_scene_view *bvh,
                        const tr_ray *ray, cmp_stats *st) {
    tr_hit hf;
    memset(&hf, 0, sizeof hf);
    int f = tr_intersect_scene(flat, ray, &hf);
    st->rays++;
    st->hits += (uint64_t)f;
    for (int var = 0; var < variants_of(bvh); ++var) {
        const char *vn = variant_name[bvh->wbvh ? var : V_BVH2];
        tr_hit hb;
        memset(&hb, 0, sizeof hb);
        int b = trace_variant(bvh, var, ray, &hb, 0);
        int any = trace_variant(bvh, var, ray, NULL, 1);
        if (any != b) {
            if (st->anyhit_mismatches++ < 5) {
                fprintf(stderr, "  %s:\n", vn);
                print_ray(name, any ? "any-hit hits, closest-hit misses" : "any-hit misses", ray);
            }
        }
        if (f != b) {
            if (st->mismatches++ < 5) {
                fprintf(stderr, "  %s:\n", vn);
                print_ray(name, f ? "flat hits, bvh misses" : "bvh hits, flat misses", ray);
                fprintf(stderr, "    flat %d t %.9g tri %u / bvh %d t %.9g tri %u\n", f,
                        (double)hf.t, f ? hf.triangle : 0, b, (double)hb.t, b ? hb.triangle : 0);
            }
            continue;
        }
        if (!f) {
            continue;
        }
        int ok;
        if (hb.triangle >= bvh->triangle_count || !(hb.t > ray->tmin && hb.t < ray->tmax) ||
            !tri_valid(&bvh->triangles[hb.triangle])) {
            ok = 0;
        } else if (hb.triangle == hf.triangle) {
            ok = fabs((double)hb.t - (double)hf.t) <= SAME_T_TOL * fabs((double)hf.t);
        } else {
            ok = fabs((double)hb.t - (double)hf.t) <= TIE_T_TOL * fabs((double)hf.t);
            if (ok) {
                int dup =
                    tri_duplicates(&flat->triangles[hf.triangle], &bvh->triangles[hb.triangle]);
                st->variant_ties[var]++;
                st->variant_dup_ties[var] += (uint64_t)dup;
                if (var == V_WIDE) {
                    st->ties++;
                    st->dup_ties += (uint64_t)dup;
                }
            }
        }
        if (!ok && st->mismatches++ < 5) {
            fprintf(stderr, "  %s:\n", vn);
            print_ray(name, "different hits", ray);
            fprintf(stderr, "    flat t %.9g tri %u / bvh t %.9g tri %u\n", (double)hf.t,
                    hf.triangle, (double)hb.t, hb.triangle);
        }
    }
}

/* Compares `rays` random rays through the flat and BVH views of one scene and checks the
 * outcome; max_tie_fraction < 0 leaves the non-duplicate ties unbounded. */
static cmp_stats compare_views(const char *name, const tr_scene_view *flat,
                               const tr_scene_view *bvh, ray_gen *g, uint32_t rays,
                               double max_tie_fraction) {
    cmp_stats st;
    memset(&st, 0, sizeof st);
    double t0 = tr_time_now();
    for (uint32_t i = 0; i < rays; ++i) {
        tr_ray ray = next_ray(g);
        compare_ray(name, flat, bvh, &ray, &st);
    }
    printf("%-22s %7llu rays %7llu hits %6llu ties (%llu between duplicates), %d ways, %.2f s\n",
           name, (unsigned long long)st.rays, (unsigned long long)st.hits,
           (unsigned long long)st.ties, (unsigned long long)st.dup_ties, variants_of(bvh),
           tr_time_now() - t0);
    CHECK(st.mismatches == 0, "%s: %llu answers to %llu rays differ between flat and bvh", name,
          (unsigned long long)st.mismatches, (unsigned long long)st.rays);
    CHECK(st.anyhit_mismatches == 0, "%s: any-hit and closest-hit disagree %llu times", name,
          (unsigned long long)st.anyhit_mismatches);
    if (max_tie_fraction >= 0.0) {
        for (int var = 0; var < variants_of(bvh); ++var) {
            uint64_t other = st.variant_ties[var] - st.variant_dup_ties[var];
            CHECK((double)other <= max_tie_fraction * (double)(st.hits ? st.hits : 1),
                  "%s: %s: %llu ties between distinct triangles in %llu hits", name,
                  variant_name[var], (unsigned long long)other, (unsigned long long)st.hits);
        }
    }
    return st;
}

/* ---- structure --------------------------------------------------------------------- */

static int box_contains_box(tr_aabb outer, tr_aabb inner) {
    return outer.min.x <= inner.min.x && outer.min.y <= inner.min.y && outer.min.z <= inner.min.z &&
           outer.max.x >= inner.max.x && outer.max.y >= inner.max.y && outer.max.z >= inner.max.z;
}

static int box_contains_point(tr_aabb b, tr_vec3 p) {
    return b.min.x <= p.x && b.min.y <= p.y && b.min.z <= p.z && b.max.x >= p.x && b.max.y >= p.y &&
           b.max.z >= p.z;
}

/* Walks the whole tree from the root and checks every invariant the traversal and the
 * device upload rely on. */
static void check_structure(const char *name, const tr_bvh *bvh, const tr_triangle *tris,
                            uint32_t n) {
    uint32_t valid = 0;
    for (uint32_t i = 0; i < n; ++i) {
        valid += (uint32_t)tri_valid(&tris[i]);
    }
    CHECK(bvh->index_count == valid, "%s: %u indices for %u valid triangles", name,
          bvh->index_count, valid);
    CHECK(bvh->skipped == n - valid, "%s: skipped %u, expected %u", name, bvh->skipped, n - valid);
    if (valid == 0) {
        CHECK(bvh->node_count == 0 && bvh->leaf_count == 0, "%s: empty tree has %u nodes", name,
              bvh->node_count);
        return;
    }
    CHECK(bvh->node_count == 2 * bvh->leaf_count - 1, "%s: %u nodes, %u leaves", name,
          bvh->node_count, bvh->leaf_count);
    CHECK(bvh->depth < TR_BVH_STACK_SIZE, "%s: depth %u", name, bvh->depth);

    uint32_t *seen = calloc(n ? n : 1, sizeof *seen);
    uint32_t *visits = calloc(bvh->node_count, sizeof *visits);
    uint32_t *stack = malloc((size_t)bvh->node_count * sizeof *stack);
    uint32_t *depth = malloc((size_t)bvh->node_count * sizeof *depth);
    if (!seen || !visits || !stack || !depth) {
        abort();
    }
    uint32_t top = 0, leaves = 0, max_depth = 0, slots = 0;
    int bad_links = 0, bad_boxes = 0, bad_leaves = 0;
    stack[top++] = 0;
    depth[0] = 0;
    while (top > 0) {
        uint32_t i = stack[--top];
        const tr_bvh_node *node = &bvh->nodes[i];
        if (visits[i]++ > 0) {
            ++bad_links; /* reached twice: not a tree */
            continue;
        }
        if (node->count == 0) {
            uint32_t l = node->left_first;
            /* Children come after their parent, which also rules out cycles. */
            if (l <= i || l + 1 >= bvh->node_count) {
                ++bad_links;
                continue;
            }
            for (uint32_t c = l; c <= l + 1; ++c) {
                bad_boxes += !box_contains_box(node->box, bvh->nodes[c].box);
                depth[c] = depth[i] + 1;
                stack[top++] = c;
            }
            continue;
        }
        ++leaves;
        max_depth = depth[i] > max_depth ? depth[i] : max_depth;
        if ((uint64_t)node->left_first + node->count > bvh->index_count) {
            ++bad_leaves;
            continue;
        }
        for (uint32_t k = node->left_first; k < node->left_first + node->count; ++k) {
            uint32_t t = bvh->indices[k];
            ++slots;
            if (t >= n || !tri_valid(&tris[t])) {
                ++bad_leaves;
                continue;
            }
            seen[t]++;
            bad_boxes += !box_contains_point(node->box, tris[t].v0) ||
                         !box_contains_point(node->box, tris[t].v1) ||
                         !box_contains_point(node->box, tris[t].v2);
        }
    }
    uint32_t unreached = 0, not_once = 0;
    for (uint32_t i = 0; i < bvh->node_count; ++i) {
        unreached += visits[i] == 0;
    }
    for (uint32_t i = 0; i < n; ++i) {
        not_once += tri_valid(&tris[i]) && seen[i] != 1;
    }
    CHECK(bad_links == 0 && unreached == 0, "%s: %d bad child links, %u nodes unreachable", name,
          bad_links, unreached);
    CHECK(bad_boxes == 0, "%s: %d boxes do not contain their children or triangles", name,
          bad_boxes);
    CHECK(bad_leaves == 0, "%s: %d leaf entries out of range or not valid triangles", name,
          bad_leaves);
    CHECK(not_once == 0 && slots == valid,
          "%s: %u valid triangles not in exactly one leaf slot "
          "(%u slots for %u)",
          name, not_once, slots, valid);
    CHECK(leaves == bvh->leaf_count, "%s: %u leaves reached, leaf_count %u", name, leaves,
          bvh->leaf_count);
    CHECK(max_depth == bvh->depth, "%s: deepest leaf %u, depth %u", name, max_depth, bvh->depth);
    free(seen);
    free(visits);
    free(stack);
    free(depth);
}

/* The same for the wide BVH: every valid triangle in exactly one packet lane, copied
 * exactly from the binary BVH's leaf triangles, unused lanes all zero, unused child slots
 * empty, each child's box holding its subtree (and equal to a binary node's box, so
 * that the wide traversal's box tests are the binary one's), children after parents. */
static void check_wide_structure(const char *name, const tr_wbvh *w, const tr_bvh *bvh,
                                 const tr_triangle *tris, uint32_t n) {
    CHECK(w->bvh_refits == bvh->refits, "%s: the wide BVH is stale", name);
    if (bvh->node_count == 0) {
        CHECK(w->node_count == 0 && w->packet_count == 0, "%s: empty wide tree has %u nodes", name,
              w->node_count);
        return;
    }
    CHECK(w->node_count >= 1 && w->node_count <= bvh->node_count, "%s: %u wide nodes for %u", name,
          w->node_count, bvh->node_count);
    CHECK(w->depth <= bvh->depth, "%s: wide depth %u > binary depth %u", name, w->depth,
          bvh->depth);
    uint32_t *seen = calloc(n ? n : 1, sizeof *seen);
    uint32_t *visits = calloc(w->node_count, sizeof *visits);
    uint32_t *pvisits = calloc(w->packet_count ? w->packet_count : 1, sizeof *pvisits);
    uint32_t *stack = malloc((size_t)w->node_count * sizeof *stack);
    if (!seen || !visits || !pvisits || !stack) {
        abort();
    }
    /* Every wide child box is the box of some binary node: collect them. */
    int bad_links = 0, bad_boxes = 0, bad_lanes = 0, bad_empty = 0;
    uint32_t top = 0, leaves = 0, lanes = 0;
    stack[top++] = 0;
    while (top > 0) {
        uint32_t i = stack[--top];
        if (visits[i]++ > 0) {
            ++bad_links;
            continue;
        }
        const tr_wbvh_node *node = &w->nodes[i];
        for (int c = 0; c < TR_WBVH_WIDTH; ++c) {
            uint32_t ch = node->child[c];
            tr_aabb box = {v3(node->bounds[0][c], node->bounds[2][c], node->bounds[4][c]),
                           v3(node->bounds[1][c], node->bounds[3][c], node->bounds[5][c])};
            if (ch == TR_WBVH_EMPTY) {
                bad_empty +=
                    !(box.min.x == INFINITY && box.min.y == INFINITY && box.min.z == INFINITY &&
                      box.max.x == -INFINITY && box.max.y == -INFINITY && box.max.z == -INFINITY);
                continue;
            }
            if (!(ch & TR_WBVH_LEAF_BIT)) {
                if (ch <= i || ch >= w->node_count) {
                    ++bad_links;
                    continue;
                }
                const tr_wbvh_node *kid = &w->nodes[ch];
                for (int k = 0; k < TR_WBVH_WIDTH; ++k) {
                    if (kid->child[k] != TR_WBVH_EMPTY) {
                        tr_aabb kb = {v3(kid->bounds[0][k], kid->bounds[2][k], kid->bounds[4][k]),
                                      v3(kid->bounds[1][k], kid->bounds[3][k], kid->bounds[5][k])};
                        bad_boxes += !box_contains_box(box, kb);
                    }
                }
                stack[top++] = ch;
                continue;
            }
            ++leaves;
            uint32_t first = ch & ((1u << TR_WBVH_LEAF_SHIFT) - 1u);
            uint32_t packets = (ch & ~TR_WBVH_LEAF_BIT) >> TR_WBVH_LEAF_SHIFT;
            if (packets == 0 || (uint64_t)first + packets > w->packet_count) {
                ++bad_links;
                continue;
            }
            for (uint32_t p = first; p < first + packets; ++p) {
                const tr_wbvh_tri4 *q = &w->packets[p];
                pvisits[p]++;
                for (int l = 0; l < 4; ++l) {
                    int zero = 1;
                    for (int a = 0; a < 3; ++a) {
                        zero &= q->v0[a][l] == 0.0f && q->e1[a][l] == 0.0f && q->e2[a][l] == 0.0f;
                    }
                    uint32_t t = q->index[l];
                    if (zero && t == 0) {
                        continue; /* an unused lane (a valid triangle has non-zero edges) */
                    }
                    ++lanes;
                    if (t >= n || !tri_valid(&tris[t])) {
                        ++bad_lanes;
                        continue;
                    }
                    seen[t]++;
                    const tr_triangle *tr = &tris[t];
                    tr_vec3 v0 = v3(q->v0[0][l], q->v0[1][l], q->v0[2][l]);
                    tr_vec3 e1 = v3(q->e1[0][l], q->e1[1][l], q->e1[2][l]);
                    tr_vec3 e2 = v3(q->e2[0][l], q->e2[1][l], q->e2[2][l]);
                    bad_lanes += !vec_eq(v0, tr->v0) || !vec_eq(e1, v3_sub(tr->v1, tr->v0)) ||
                                 !vec_eq(e2, v3_sub(tr->v2, tr->v0));
                    bad_boxes += !box_contains_point(box, tr->v0) ||
                                 !box_contains_point(box, tr->v1) ||
                                 !box_contains_point(box, tr->v2);
                }
            }
        }
    }
    uint32_t unreached = 0, packets_not_once = 0, not_once = 0, valid = 0;
    for (uint32_t i = 0; i < w->node_count; ++i) {
        unreached += visits[i] == 0;
    }
    for (uint32_t p = 0; p < w->packet_count; ++p) {
        packets_not_once += pvisits[p] != 1;
    }
    for (uint32_t i = 0; i < n; ++i) {
        valid += (uint32_t)tri_valid(&tris[i]);
        not_once += tri_valid(&tris[i]) && seen[i] != 1;
    }
    CHECK(bad_links == 0 && unreached == 0 && packets_not_once == 0,
          "%s: wide BVH: %d bad links, %u nodes unreachable, %u packets not used once", name,
          bad_links, unreached, packets_not_once);
    CHECK(bad_boxes == 0, "%s: wide BVH: %d boxes do not contain their subtrees", name, bad_boxes);
    CHECK(bad_empty == 0, "%s: wide BVH: %d empty slots without the empty box", name, bad_empty);
    CHECK(bad_lanes == 0 && not_once == 0 && lanes == valid,
          "%s: wide BVH: %d bad lanes, %u valid triangles not in exactly one lane (%u lanes for "
          "%u)",
          name, bad_lanes, not_once, lanes, valid);
    CHECK(leaves == w->leaf_count, "%s: wide BVH: %u leaves reached, leaf_count %u", name, leaves,
          w->leaf_count);
    free(seen);
    free(visits);
    free(pvisits);
    free(stack);
}

/* ---- the tests --------------------------------------------------------------------- */

/* Commits the scene's BVH, checks the tree, and compares it with the flat structure. */
static void check_mesh(const char *name, tr_scene *s, uint64_t seed, uint32_t rays,
                       double max_tie_fraction) {
    tr_error err;
    CHECK(tr_scene_commit(s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s: %s", name, err.msg);
    check_structure(name, &s->bvh, s->triangles, s->triangle_count);
    check_wide_structure(name, &s->wbvh, &s->bvh, s->triangles, s->triangle_count);
    tr_scene_view bvh = tr_scene_view_of(s), flat = bvh;
    CHECK(bvh.accel == TR_ACCEL_BVH, "%s: the view is not a BVH view", name);
    CHECK(bvh.wbvh == &s->wbvh, "%s: the view does not trace the wide BVH", name);
    flat.accel = TR_ACCEL_FLAT;
    ray_gen g;
    ray_gen_init(&g, seed, s->triangles, s->triangle_count, NULL);
    compare_views(name, &flat, &bvh, &g, rays, max_tie_fraction);
    ray_gen_free(&g);
}

static void test_meshes(void) {
    tr_error err;
    tr_rng r;
    tr_rng_init(&r, 2024, 1, 0);
    tr_scene s = {0};
    uint32_t n;
    tr_triangle *t;

    t = make_soup(&r, &n);
    scene_from_triangles(&s, t, n);
    check_mesh("soup", &s, 1, RAYS, MAX_TIE_FRACTION);
    tr_scene_clear(&s);

    /* The icosphere's triangles come in subdivision order, so runs of 64 are the
     * descendants of one level-2 face: compact flat nodes. */
    tr_scene_init(&s);
    CHECK(tr_scene_add_material(&s, tr_material_diffuse(v3s(0.5f)), NULL, &err) == TR_OK, "%s",
          err.msg);
    tr_shape_desc ico = tr_shape_desc_default(TR_SHAPE_ICOSPHERE);
    ico.subdivisions = 5;
    CHECK(tr_scene_add_shape(&s, &ico, &err) == TR_OK, "%s", err.msg);
    CHECK(s.triangle_count == 20480, "icosphere has %u triangles", s.triangle_count);
    set_flat_nodes(&s, 64);
    check_mesh("icosphere(5)", &s, 2, RAYS, MAX_TIE_FRACTION);
    tr_scene_clear(&s);

    CHECK(tr_scene_builtin(&s, "cornell", 64, 48, &err) == TR_OK, "%s", err.msg);
    check_mesh("cornell", &s, 3, RAYS, MAX_TIE_FRACTION);
    tr_scene_clear(&s);

    t = make_slivers(&r, &n);
    scene_from_triangles(&s, t, n);
    check_mesh("slivers(1e4:1)", &s, 4, RAYS, MAX_TIE_FRACTION);
    tr_scene_clear(&s);

    /* The tilted grid meets the flat one exactly along the diagonals of the flat one's
     * quads, so rays aimed at the line x = y in z = 0.5 hit a shared edge: about 1.2% of
     * the hits are ties between distinct triangles there, correctly. */
    t = make_coplanar(&n);
    scene_from_triangles(&s, t, n);
    check_mesh("coplanar+duplicates", &s, 5, RAYS, 0.03);
    tr_scene_clear(&s);

    t = alloc_tris(1);
    t[0].v0 = v3(0.1f, 0.2f, 0.3f);
    t[0].v1 = v3(0.9f, 0.25f, 0.4f);
    t[0].v2 = v3(0.3f, 0.8f, 0.7f);
    scene_from_triangles(&s, t, 1);
    check_mesh("single", &s, 6, RAYS, MAX_TIE_FRACTION);
    CHECK(s.bvh.node_count == 1 && s.bvh.leaf_count == 1 && s.bvh.depth == 0,
          "single triangle: %u nodes, %u leaves, depth %u", s.bvh.node_count, s.bvh.leaf_count,
          s.bvh.depth);
    tr_scene_clear(&s);

    /* No triangles: nothing is ever hit and nothing crashes. */
    scene_from_triangles(&s, alloc_tris(0), 0);
    check_mesh("empty", &s, 7, RAYS, MAX_TIE_FRACTION);
    CHECK(s.bvh.node_count == 0, "empty scene: %u nodes", s.bvh.node_count);
    tr_scene_clear(&s);
}

/* Meshes on which the SAH finds no split or only lopsided ones: the builder must fall
 * back to median splits and keep the depth within the traversal stack. */
static void test_stress(void) {
    const uint32_t n = 5000;
    tr_rng r;
    tr_rng_init(&r, 77, 0, 0);
    tr_scene s = {0};
    tr_triangle *t;
    const tr_vec3 c = v3(0.5f, 0.5f, 0.5f);

    t = alloc_tris(n);
    for (uint32_t i = 0; i < n; ++i) {
        t[i].v0 = v3(0.2f, 0.3f, 0.4f);
        t[i].v1 = v3(0.8f, 0.35f, 0.5f);
        t[i].v2 = v3(0.4f, 0.9f, 0.6f);
    }
    scene_from_triangles(&s, t, n);
    check_mesh("identical x5000", &s, 11, STRESS_RAYS, MAX_TIE_FRACTION);
    printf("  depth %u, %u leaves\n", s.bvh.depth, s.bvh.leaf_count);
    tr_scene_clear(&s);

    /* v0 + v1 + v2 = 3c exactly (offsets are multiples of 2^-12): one centroid. */
    t = alloc_tris(n);
    for (uint32_t i = 0; i < n; ++i) {
        tr_vec3 a = v3_scale(
            v3((float)rng_below(&r, 1024), (float)rng_below(&r, 1024), (float)rng_below(&r, 1024)),
            1.0f / 4096.0f);
        tr_vec3 b = v3_scale(
            v3((float)rng_below(&r, 1024), (float)rng_below(&r, 1024), (float)rng_below(&r, 1024)),
            -1.0f / 4096.0f);
        t[i].v0 = v3_add(c, a);
        t[i].v1 = v3_add(c, b);
        t[i].v2 = v3_sub(v3_sub(c, a), b);
    }
    scene_from_triangles(&s, t, n);
    check_mesh("same centroid x5000", &s, 12, STRESS_RAYS, MAX_TIE_FRACTION);
    printf("  depth %u, %u leaves\n", s.bvh.depth, s.bvh.leaf_count);
    tr_scene_clear(&s);

    /* The builder bins box centres: v0 = c + p, v1 = c - p and v2 inside the box they
     * span give every triangle the box centre c, so no bin plane separates any two. */
    t = alloc_tris(n);
    for (uint32_t i = 0; i < n; ++i) {
        tr_vec3 p = v3_scale(v3((float)(1 + rng_below(&r, 1024)), (float)(1 + rng_below(&r, 1024)),
                                (float)(1 + rng_below(&r, 1024))),
                             1.0f / 4096.0f);
        t[i].v0 = v3_add(c, p);
        t[i].v1 = v3_sub(c, p);
        t[i].v2 = v3_add(c, v3(p.x, -p.y, 0.5f * p.z));
    }
    scene_from_triangles(&s, t, n);
    check_mesh("same box centre x5000", &s, 13, STRESS_RAYS, MAX_TIE_FRACTION);
    printf("  depth %u, %u leaves\n", s.bvh.depth, s.bvh.leaf_count);
    tr_scene_clear(&s);

    /* Parallel squares at x = 0.8^k: each SAH split peels a few off the far end, so the
     * SAH alone would build a chain thousands deep. Far down the planes are closer than
     * a float can tell apart from a distance, so distinct triangles tie often there and
     * the tie count is not bounded. */
    t = alloc_tris(n);
    for (uint32_t i = 0; i < n; ++i) {
        float x = powf(0.8f, (float)(i % 400)) + (float)(i / 400);
        t[i].v0 = v3(x, 0.0f, 0.0f);
        t[i].v1 = v3(x, 1.0f, 0.0f);
        t[i].v2 = v3(x, 0.0f, 1.0f);
    }
    scene_from_triangles(&s, t, n);
    check_mesh("geometric planes", &s, 14, STRESS_RAYS, -1.0);
    printf("  depth %u, %u leaves\n", s.bvh.depth, s.bvh.leaf_count);
    CHECK(s.bvh.depth > 32, "geometric planes: depth %u never reached the median fallback",
          s.bvh.depth);
    tr_scene_clear(&s);

    /* Box centres one float apart near 1e-31 on x: the centroid extent is so small that
     * BINS / extent overflows, which the binning must survive (the other axes split). */
    const uint32_t tiny = 64;
    t = alloc_tris(tiny);
    for (uint32_t i = 0; i < tiny; ++i) {
        float e = 1e-31f, x1 = i % 2 ? e : nextafterf(e, 1.0f);
        t[i].v0 = v3(-e, 0.0f, (float)i);
        t[i].v1 = v3(x1, 1.0f, (float)i);
        t[i].v2 = v3(0.0f, 0.0f, (float)i + 1.0f);
    }
    scene_from_triangles(&s, t, tiny);
    check_mesh("tiny centroid spread", &s, 15, STRESS_RAYS, MAX_TIE_FRACTION);
    tr_scene_clear(&s);
}

/* The kinds of degenerate triangle mixed into a valid mesh. */
enum { DEGENERATE_KINDS = 9 };

static tr_triangle degenerate(tr_rng *r, uint32_t kind, tr_vec3 near) {
    const float nan = NAN, inf = INFINITY;
    /* On a 1/1024 grid, so that collinear points stay exactly collinear in floats. */
    tr_vec3 p = v3(floorf(near.x * 1024.0f) / 1024.0f, floorf(near.y * 1024.0f) / 1024.0f,
                   floorf(near.z * 1024.0f) / 1024.0f);
    tr_vec3 q = v3_madd(
        p, v3((float)rng_below(r, 17), (float)rng_below(r, 17), (float)rng_below(r, 17) + 1.0f),
        1.0f / 1024.0f);
    tr_vec3 w = v3_madd(p, v3s(1.0f / 1024.0f), 5.0f);
    tr_triangle t;
    memset(&t, 0, sizeof t);
    switch (kind) {
    case 0:
        t.v0 = p, t.v1 = p, t.v2 = q;
        break;
    case 1:
        t.v0 = p, t.v1 = q, t.v2 = q;
        break;
    case 2:
        t.v0 = q, t.v1 = p, t.v2 = q;
        break;
    case 3:
        t.v0 = p, t.v1 = p, t.v2 = p;
        break;
    case 4: /* collinear: q - p = d / 1024 with integer d, third point at p - 2 d / 1024 */
        t.v0 = p, t.v1 = q, t.v2 = v3_madd(p, v3_sub(q, p), -2.0f);
        break;
    case 5:
        t.v0 = p, t.v1 = v3(q.x, nan, q.z), t.v2 = w;
        break;
    case 6:
        t.v0 = p, t.v1 = q, t.v2 = v3(w.x, w.y, inf);
        break;
    case 7:
        t.v0 = v3(-inf, p.y, nan), t.v1 = q, t.v2 = w;
        break;
    default:
        t.v0 = v3s(nan), t.v1 = v3s(nan), t.v2 = v3s(nan);
        break;
    }
    return t;
}

static int tri_finite(const tr_triangle *t) {
    return v3_is_finite(t->v0) && v3_is_finite(t->v1) && v3_is_finite(t->v2);
}

/* Degenerate triangles: the builder leaves them out and counts them, nothing hits them,
 * and the valid triangles around them are found as the flat structure finds them. */
static void test_degenerate(void) {
    tr_error err;
    tr_rng r;
    tr_rng_init(&r, 99, 0, 0);
    const uint32_t valid = 4000, every = 6;
    const uint32_t n = valid + valid / (every - 1);
    /* Valid triangles in Morton order (for a fast flat reference), with a degenerate one
     * after every fifth, placed where its neighbours are. */
    tr_triangle *good = alloc_tris(valid);
    tr_aabb cube = {v3s(0.0f), v3s(1.0f)}, unit = {v3s(-1.0f), v3s(1.0f)};
    for (uint32_t i = 0; i < valid; ++i) {
        tr_vec3 c = rand_in_box(&r, cube);
        float size = 0.004f * powf(25.0f, tr_rng_float(&r));
        good[i].v0 = v3_madd(c, rand_in_box(&r, unit), size);
        good[i].v1 = v3_madd(c, rand_in_box(&r, unit), size);
        good[i].v2 = v3_madd(c, rand_in_box(&r, unit), size);
    }
    sort_spatially(good, valid);
    tr_triangle *t = alloc_tris(n);
    uint32_t bad = 0, next_good = 0;
    for (uint32_t i = 0; i < n; ++i) {
        if (i % every == every - 1) {
            t[i] = degenerate(&r, bad++ % DEGENERATE_KINDS, t[i - 1].v0);
        } else {
            t[i] = good[next_good++];
        }
    }
    free(good);
    tr_scene s = {0};
    scene_from_triangles(&s, t, n);
    uint32_t zero_area = 0;
    for (uint32_t i = 0; i < n; ++i) {
        zero_area += !tri_valid(&s.triangles[i]);
    }
    CHECK(zero_area == bad, "%u triangles are degenerate after tr_triangle_finish, made %u",
          zero_area, bad);
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
    CHECK(s.bvh.skipped == bad, "bvh.skipped %u, expected %u", s.bvh.skipped, bad);
    check_structure("degenerate mix", &s.bvh, s.triangles, s.triangle_count);

    /* The reference: the same mesh with each degenerate triangle collapsed to one finite
     * point, which no ray/triangle test can hit (both edges are exactly zero), so the
     * flat structure sees only the valid triangles, at the same indices. */
    tr_scene clean = {0};
    tr_triangle *ct = alloc_tris(n);
    memcpy(ct, s.triangles, (size_t)n * sizeof *ct);
    for (uint32_t i = 0; i < n; ++i) {
        if (!tri_valid(&ct[i])) {
            tr_vec3 p = ct[i - 1].v0;
            ct[i].v0 = ct[i].v1 = ct[i].v2 = p;
        }
    }
    scene_from_triangles(&clean, ct, n);
    tr_scene_view bvh = tr_scene_view_of(&s), flat = tr_scene_view_of(&clean);
    flat.accel = TR_ACCEL_FLAT;
    tr_scene_view flat_mixed = bvh;
    flat_mixed.accel = TR_ACCEL_FLAT;

    /* Half the rays aim at the degenerate triangles that have finite vertices. */
    ray_gen g_valid, g_bad;
    ray_gen_init(&g_valid, 21, s.triangles, n, NULL);
    ray_gen_init(&g_bad, 22, s.triangles, n, tri_finite);
    g_bad.bounds = g_valid.bounds;
    g_bad.center = g_valid.center;
    g_bad.radius = g_valid.radius;
    cmp_stats st;
    memset(&st, 0, sizeof st);
    uint64_t bvh_on_bad = 0, flat_on_bad = 0;
    for (uint32_t i = 0; i < RAYS; ++i) {
        tr_ray ray = next_ray(i % 2 ? &g_bad : &g_valid);
        compare_ray("degenerate mix", &flat, &bvh, &ray, &st);
        tr_hit h;
        if (tr_intersect_scene(&bvh, &ray, &h) && !tri_valid(&s.triangles[h.triangle])) {
            ++bvh_on_bad;
        }
        if (tr_intersect_scene(&flat_mixed, &ray, &h) && !tri_valid(&s.triangles[h.triangle])) {
            ++flat_on_bad;
        }
    }
    printf("%-22s %7llu rays %7llu hits %6llu ties; %u degenerate triangles skipped\n",
           "degenerate mix", (unsigned long long)st.rays, (unsigned long long)st.hits,
           (unsigned long long)st.ties, s.bvh.skipped);
    /* Not a BVH check: the flat structure's own hits on zero-area triangles, for the
     * record (the ray/triangle test's determinant threshold is absolute). */
    printf("  flat structure hits degenerate triangles on %llu rays\n",
           (unsigned long long)flat_on_bad);
    CHECK(bvh_on_bad == 0, "the bvh hit degenerate triangles on %llu rays",
          (unsigned long long)bvh_on_bad);
    CHECK(st.mismatches == 0, "degenerate mix: %llu rays differ from the clean flat reference",
          (unsigned long long)st.mismatches);
    CHECK(st.anyhit_mismatches == 0, "degenerate mix: any-hit disagrees on %llu rays",
          (unsigned long long)st.anyhit_mismatches);
    CHECK(st.ties - st.dup_ties <= MAX_TIE_FRACTION * (double)st.hits,
          "degenerate mix: %llu ties in %llu hits", (unsigned long long)st.ties,
          (unsigned long long)st.hits);
    ray_gen_free(&g_valid);
    ray_gen_free(&g_bad);
    tr_scene_clear(&clean);

    /* Nothing valid at all: an empty tree. */
    tr_triangle *only_bad = alloc_tris(DEGENERATE_KINDS);
    for (uint32_t k = 0; k < DEGENERATE_KINDS; ++k) {
        only_bad[k] = degenerate(&r, k, v3s(0.5f));
    }
    tr_scene_clear(&s);
    scene_from_triangles(&s, only_bad, DEGENERATE_KINDS);
    check_mesh("only degenerate", &s, 23, STRESS_RAYS, MAX_TIE_FRACTION);
    CHECK(s.bvh.skipped == DEGENERATE_KINDS && s.bvh.node_count == 0,
          "only degenerate: skipped %u, %u nodes", s.bvh.skipped, s.bvh.node_count);
    tr_scene_clear(&s);
}

/* Moves every triangle: v -> v * scale + sign * offset. */
static void move_triangles(tr_scene *s, tr_vec3 scale, tr_vec3 offset, float sign) {
    const tr_vec3 d = v3_scale(offset, sign);
    for (uint32_t i = 0; i < s->triangle_count; ++i) {
        tr_triangle *tri = &s->triangles[i];
        tri->v0 = v3_add(v3_mul(tri->v0, scale), d);
        tri->v1 = v3_add(v3_mul(tri->v1, scale), d);
        tri->v2 = v3_add(v3_mul(tri->v2, scale), d);
        tr_triangle_finish(tri);
    }
}

/* Refit: move every triangle (non-uniform scale and translation), refit the tree, and
 * the BVH must still find what the flat structure finds. */
static void test_refit(void) {
    tr_error err;
    tr_rng r;
    tr_rng_init(&r, 555, 0, 0);
    tr_scene s = {0};
    uint32_t n;
    tr_triangle *t = make_soup(&r, &n);
    scene_from_triangles(&s, t, n);
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
    uint32_t nodes = s.bvh.node_count;
    const tr_vec3 scale = v3(1.5f, 0.5f, 2.25f), offset = v3(3.0f, -1.0f, 0.25f);
    move_triangles(&s, scale, offset, 1.0f);
    tr_bvh_refit(&s.bvh, s.triangles);
    set_flat_nodes(&s, FLAT_CHUNK); /* the flat boxes moved too */
    CHECK(s.bvh.node_count == nodes, "refit changed the node count %u -> %u", nodes,
          s.bvh.node_count);
    check_structure("refit soup", &s.bvh, s.triangles, n);
    tr_scene_view bvh = tr_scene_view_of(&s), flat = bvh;
    /* The wide BVH was collapsed before the refit: the view must not use it. */
    CHECK(bvh.wbvh == NULL, "a view after tr_bvh_refit traces the stale wide BVH");
    flat.accel = TR_ACCEL_FLAT;
    ray_gen g;
    ray_gen_init(&g, 31, s.triangles, n, NULL);
    compare_views("refit soup (bvh2)", &flat, &bvh, &g, RAYS, MAX_TIE_FRACTION);
    ray_gen_free(&g);

    /* Move again and refit the scene: both trees follow. */
    move_triangles(&s, scale, offset, -1.0f);
    CHECK(tr_scene_refit(&s, &err) == TR_OK, "%s", err.msg);
    set_flat_nodes(&s, FLAT_CHUNK);
    check_structure("scene refit soup", &s.bvh, s.triangles, n);
    check_wide_structure("scene refit soup", &s.wbvh, &s.bvh, s.triangles, n);
    bvh = tr_scene_view_of(&s);
    flat = bvh;
    flat.accel = TR_ACCEL_FLAT;
    CHECK(bvh.wbvh == &s.wbvh, "a view after tr_scene_refit does not trace the wide BVH");
    ray_gen_init(&g, 32, s.triangles, n, NULL);
    compare_views("scene refit soup", &flat, &bvh, &g, RAYS, MAX_TIE_FRACTION);
    ray_gen_free(&g);

    /* Once more, now with a wide BVH as current as the binary one: tr_scene_refit refits
     * it in place (tr_wbvh_refit), keeping its node and packet counts. */
    const uint32_t wide_nodes = s.wbvh.node_count, packets = s.wbvh.packet_count;
    move_triangles(&s, scale, offset, 1.0f);
    CHECK(tr_scene_refit(&s, &err) == TR_OK, "%s", err.msg);
    set_flat_nodes(&s, FLAT_CHUNK);
    CHECK(s.wbvh.node_count == wide_nodes && s.wbvh.packet_count == packets,
          "the in-place refit changed the wide tree: %u -> %u nodes, %u -> %u packets", wide_nodes,
          s.wbvh.node_count, packets, s.wbvh.packet_count);
    check_structure("wide refit soup", &s.bvh, s.triangles, n);
    check_wide_structure("wide refit soup", &s.wbvh, &s.bvh, s.triangles, n);
    bvh = tr_scene_view_of(&s);
    flat = bvh;
    flat.accel = TR_ACCEL_FLAT;
    CHECK(bvh.wbvh == &s.wbvh, "a view after the in-place refit does not trace the wide BVH");
    ray_gen_init(&g, 33, s.triangles, n, NULL);
    compare_views("wide refit soup", &flat, &bvh, &g, RAYS, MAX_TIE_FRACTION);
    ray_gen_free(&g);
    tr_scene_clear(&s);
}

/* Triangles big enough that the square of their cross product's length overflows a
 * float are still ordinary triangles: the flat structure hits them, so must the BVH. */
static void test_huge_triangles(void) {
    tr_error err;
    tr_scene s = {0};
    tr_scene_init(&s);
    CHECK(tr_scene_add_material(&s, tr_material_diffuse(v3s(0.5f)), NULL, &err) == TR_OK, "%s",
          err.msg);
    tr_shape_desc ground = tr_shape_desc_default(TR_SHAPE_PLANE);
    ground.transform.scale = v3(1e12f, 1.0f, 1e12f); /* a "ground to the horizon" */
    tr_shape_desc box = tr_shape_desc_default(TR_SHAPE_BOX);
    box.transform.position = v3(0.0f, 0.5f, 0.0f);
    CHECK(tr_scene_add_shape(&s, &ground, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_scene_add_shape(&s, &box, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
    CHECK(s.bvh.skipped == 0, "huge plane: %u valid triangles skipped as degenerate (area %g)",
          s.bvh.skipped, (double)s.triangles[0].area);
    tr_scene_view bvh = tr_scene_view_of(&s), flat = bvh;
    flat.accel = TR_ACCEL_FLAT;
    tr_rng r;
    tr_rng_init(&r, 41, 0, 0);
    cmp_stats st;
    memset(&st, 0, sizeof st);
    for (int i = 0; i < 1000; ++i) {
        /* From above, downwards: every ray meets the ground or the box. */
        tr_vec3 o = v3(tr_rng_range(&r, -5, 5), tr_rng_range(&r, 0.1f, 5), tr_rng_range(&r, -5, 5));
        tr_vec3 d = rand_unit(&r);
        d.y = -fabsf(d.y) - 0.01f;
        tr_ray ray = tr_ray_make(o, v3_normalize(d), 0.0f, TR_INFINITY);
        compare_ray("huge plane", &flat, &bvh, &ray, &st);
    }
    CHECK(st.mismatches == 0, "huge plane: %llu of %llu rays differ between flat and bvh",
          (unsigned long long)st.mismatches, (unsigned long long)st.rays);
    tr_scene_clear(&s);
}

static int films_equal_pixel(const tr_film *a, const tr_film *b, size_t i) {
    return memcmp(&a->sum[3 * i], &b->sum[3 * i], 3 * sizeof(float)) == 0 &&
           a->count[i] == b->count[i];
}

/* The same Cornell image through flat and bvh: identical but for pixels where a path met
 * a tie (two triangles at one distance, e.g. on a box edge) and went on differently. */
static void test_render(void) {
    const uint32_t w = 64, h = 48, spp = 4;
    tr_error err;
    tr_scene s = {0};
    CHECK(tr_scene_builtin(&s, "cornell", w, h, &err) == TR_OK, "%s", err.msg);
    tr_film ff, fb, f2;
    CHECK(tr_film_init(&ff, w, h, &err) == TR_OK && tr_film_init(&fb, w, h, &err) == TR_OK &&
              tr_film_init(&f2, w, h, &err) == TR_OK,
          "%s", err.msg);
    tr_render_config cfg = tr_render_config_default();
    cfg.seed = 12345;
    /* flat, bvh (the wide BVH on the CPU) and bvh2 (the binary one). */
    tr_film *films[3] = {&ff, &fb, &f2};
    const tr_accel_type accels[3] = {TR_ACCEL_TYPE_FLAT, TR_ACCEL_TYPE_BVH, TR_ACCEL_TYPE_BVH2};
    for (int k = 0; k < 3; ++k) {
        CHECK(tr_scene_commit(&s, accels[k], &err) == TR_OK, "%s", err.msg);
        tr_scene_view v = tr_scene_view_of(&s);
        CHECK(k == 0 || (v.accel == TR_ACCEL_BVH && (v.wbvh != NULL) == (k == 1)),
              "%s: view accel %u, wide BVH %p", tr_accel_name(accels[k]), v.accel,
              (const void *)v.wbvh);
        for (uint32_t i = 0; i < spp; ++i) {
            CHECK(tr_render_frame(&s, &s.camera, &cfg, films[k], i, NULL, &err) == TR_OK, "%s",
                  err.msg);
        }
    }
    for (int k = 1; k < 3; ++k) {
        uint32_t differ = 0;
        for (size_t i = 0; i < (size_t)w * h; ++i) {
            differ += !films_equal_pixel(&ff, films[k], i);
        }
        printf("render: %u of %u pixels differ between flat and %s\n", differ, w * h,
               tr_accel_name(accels[k]));
        CHECK(differ * 200u <= w * h, "%u of %u pixels differ between flat and %s (> 0.5%%)",
              differ, w * h, tr_accel_name(accels[k]));
    }
    tr_film_free(&f2);

    /* A BVH older than the scene's triangles must not be traced; a new commit fixes it.
     * The flat structure has nothing to build, but its scene still takes edits at commit
     * only (the emitter table, and devices' uploads, follow the commit). */
    tr_shape_desc extra = tr_shape_desc_default(TR_SHAPE_BOX);
    extra.transform.scale = v3s(0.1f);
    CHECK(tr_scene_add_shape(&s, &extra, &err) == TR_OK, "%s", err.msg);
    CHECK(!tr_scene_is_committed(&s), "a stale BVH counts as committed");
    CHECK(tr_render_frame(&s, &s.camera, &cfg, &fb, 0, NULL, &err) == TR_ERR,
          "rendering with a stale BVH succeeded");
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_render_frame(&s, &s.camera, &cfg, &fb, 0, NULL, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_FLAT, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_scene_add_shape(&s, &extra, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_render_frame(&s, &s.camera, &cfg, &fb, 0, NULL, &err) == TR_ERR,
          "rendering a flat scene edited since its commit succeeded");
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_FLAT, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_render_frame(&s, &s.camera, &cfg, &fb, 0, NULL, &err) == TR_OK, "%s", err.msg);
    tr_film_free(&ff);
    tr_film_free(&fb);
    tr_scene_clear(&s);
}

/* A scene holding one icosphere of the given level (6: 81 920 triangles, large enough for
 * the builder's parallel phase; 7: 327 680, for the collapse's too). */
static void icosphere_scene(tr_scene *s, uint32_t level) {
    tr_error err;
    tr_scene_init(s);
    uint32_t m;
    CHECK(tr_scene_add_material(s, tr_material_diffuse(v3s(0.5f)), &m, &err) == TR_OK, "%s",
          err.msg);
    tr_shape_desc d = tr_shape_desc_default(TR_SHAPE_ICOSPHERE);
    d.subdivisions = level;
    CHECK(tr_scene_add_shape(s, &d, &err) == TR_OK, "%s", err.msg);
}

/* The parallel build must give the same arrays whatever the thread count, or images
 * could differ where two triangles tie. Level 6 (81 920 triangles) is large enough for
 * the builder's parallel phase. */
static void test_parallel_build_deterministic(void) {
    tr_error err;
    tr_scene s = {0};
    icosphere_scene(&s, 6);
    tr_bvh one, two;
    omp_set_num_threads(1);
    CHECK(tr_bvh_build(&one, s.triangles, s.triangle_count, &err) == TR_OK, "%s", err.msg);
    omp_set_num_threads(2);
    CHECK(tr_bvh_build(&two, s.triangles, s.triangle_count, &err) == TR_OK, "%s", err.msg);
    CHECK(one.node_count == two.node_count && one.index_count == two.index_count &&
              memcmp(one.nodes, two.nodes, one.node_count * sizeof *one.nodes) == 0 &&
              memcmp(one.indices, two.indices, one.index_count * sizeof *one.indices) == 0,
          "BVH built with 1 and 2 threads differs");
    tr_bvh_free(&one);
    tr_bvh_free(&two);
    tr_scene_clear(&s);
}

/* Blocks of bigmem's cache: a freed big block is kept and handed out again for a request it
 * holds (where the build keeps them), and a tree built in kept blocks, filled with another
 * byte first, is the one built in fresh memory, binary and wide. */
static void test_kept_blocks(void) {
    tr_bigmem_trim();
    CHECK(tr_bigmem_kept() == 0, "%zu bytes kept after a trim", tr_bigmem_kept());
    const size_t big = (size_t)8 << 20;
    void *a = tr_bigmem_malloc(big);
    CHECK(a != NULL, "no block of %zu bytes", big);
    tr_bigmem_free(a);
    if (tr_bigmem_keeps()) {
        CHECK(tr_bigmem_kept() >= big, "a freed block of %zu bytes not kept (%zu)", big,
              tr_bigmem_kept());
        void *b = tr_bigmem_malloc(big / 2);
        CHECK(b == a, "a request for half the kept block did not get it");
        tr_bigmem_free(b);
        void *c = tr_bigmem_malloc(2 * big);
        CHECK(c != a && tr_bigmem_kept() >= big, "a request larger than the kept block took it");
        tr_bigmem_free(c);
        /* A block is handed out for at least a quarter of its size, not less. */
        tr_bigmem_trim();
        void *e = tr_bigmem_malloc(4 * big);
        tr_bigmem_free(e);
        void *d = tr_bigmem_malloc(big / 2 + 1);
        CHECK(d != e && tr_bigmem_kept() >= 4 * big,
              "a request for an eighth of a kept block took it");
        free(d);
        d = tr_bigmem_malloc(big + big / 2);
        CHECK(d == e, "a request for over a quarter of the kept block did not get it");
        tr_bigmem_free(d);
        void *small = malloc(1024);
        const size_t before = tr_bigmem_kept();
        tr_bigmem_free(small);
        CHECK(tr_bigmem_kept() == before, "a small block was kept");
        tr_bigmem_trim();
        CHECK(tr_bigmem_kept() == 0, "%zu bytes kept after a trim", tr_bigmem_kept());
    } else {
        CHECK(tr_bigmem_kept() == 0, "a build that keeps no blocks kept %zu bytes",
              tr_bigmem_kept());
    }
    tr_bigmem_free(NULL);

    tr_error err;
    tr_scene s = {0};
    icosphere_scene(&s, 7); /* 327 680 triangles: its big arrays are over TR_BIGMEM_MIN */
    tr_bvh fresh, again;
    tr_wbvh wfresh, wagain;
    CHECK(tr_bvh_build_wide(&fresh, s.triangles, s.triangle_count, NULL, &err) == TR_OK, "%s",
          err.msg);
    CHECK(tr_wbvh_build(&wfresh, &fresh, &err) == TR_OK, "%s", err.msg);
    /* A second tree in blocks given back by a first, filled with 0xA5 in between. */
    tr_bvh first;
    tr_wbvh wfirst;
    CHECK(tr_bvh_build_wide(&first, s.triangles, s.triangle_count, NULL, &err) == TR_OK, "%s",
          err.msg);
    CHECK(tr_wbvh_build(&wfirst, &first, &err) == TR_OK, "%s", err.msg);
    tr_wbvh_free(&wfirst);
    tr_bvh_free(&first);
    const size_t kept = tr_bigmem_kept();
    if (tr_bigmem_keeps()) {
        CHECK(kept > 0, "a freed tree over %u triangles left nothing kept", s.triangle_count);
    }
    tr_bigmem_fill_kept(0xA5);
    CHECK(tr_bvh_build_wide(&again, s.triangles, s.triangle_count, NULL, &err) == TR_OK, "%s",
          err.msg);
    CHECK(tr_wbvh_build(&wagain, &again, &err) == TR_OK, "%s", err.msg);
    if (tr_bigmem_keeps()) {
        CHECK(tr_bigmem_kept() < kept, "the rebuild took no kept block (%zu bytes kept)", kept);
    }
    CHECK(again.node_count == fresh.node_count && again.index_count == fresh.index_count &&
              memcmp(again.nodes, fresh.nodes, fresh.node_count * sizeof *fresh.nodes) == 0 &&
              memcmp(again.indices, fresh.indices, fresh.index_count * sizeof *fresh.indices) ==
                  0 &&
              memcmp(again.tris, fresh.tris, fresh.index_count * sizeof *fresh.tris) == 0,
          "the binary BVH built in kept blocks differs");
    CHECK(
        wagain.node_count == wfresh.node_count && wagain.packet_count == wfresh.packet_count &&
            wagain.leaf_count == wfresh.leaf_count &&
            memcmp(wagain.nodes, wfresh.nodes, wfresh.node_count * sizeof *wfresh.nodes) == 0 &&
            memcmp(wagain.packets, wfresh.packets, wfresh.packet_count * sizeof *wfresh.packets) ==
                0 &&
            memcmp(wagain.leaves, wfresh.leaves, wfresh.leaf_count * sizeof *wfresh.leaves) == 0 &&
            memcmp(wagain.slot_src, wfresh.slot_src,
                   (size_t)TR_WBVH_WIDTH * wfresh.node_count * sizeof *wfresh.slot_src) == 0,
        "the wide BVH built in kept blocks differs");
    tr_wbvh_free(&wagain);
    tr_bvh_free(&again);
    tr_wbvh_free(&wfresh);
    tr_bvh_free(&fresh);
    tr_bigmem_trim();
    tr_scene_clear(&s);
}

static int cmp_u32(const void *a, const void *b) {
    const uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    return (x > y) - (x < y);
}

/* tr_bvh_build_wide stops splitting at TR_WBVH_LEAF_MERGE triangles, where the collapse
 * merges a subtree into one leaf anyway: the wide BVH collapsed from it must have the same
 * nodes bit for bit and the same leaves (packets, runs and the triangles in each run, in
 * any order) as the one collapsed from tr_bvh_build's tree, and its binary tree must split
 * no node of that size. An icosphere large enough for the parallel phase, and a soup of
 * random triangles whose small nodes the SAH splits unevenly. */
static void check_wide_build(const char *name, const tr_triangle *tris, uint32_t n) {
    tr_error err;
    tr_bvh full, cut;
    tr_wbvh wa, wb;
    CHECK(tr_bvh_build(&full, tris, n, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_bvh_build_wide(&cut, tris, n, NULL, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_wbvh_build(&wa, &full, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_wbvh_build(&wb, &cut, &err) == TR_OK, "%s", err.msg);
    check_structure(name, &cut, tris, n);
    check_wide_structure(name, &wa, &full, tris, n);
    check_wide_structure(name, &wb, &cut, tris, n);
    uint32_t small_split = 0;
    for (uint32_t i = 0; i < cut.node_count; ++i) {
        const tr_bvh_node *nd = &cut.nodes[i];
        if (nd->count == 0) {
            const tr_bvh_node *l = &cut.nodes[nd->left_first], *r = &cut.nodes[nd->left_first + 1];
            /* Both children leaves: the node held their two runs. */
            small_split +=
                l->count > 0 && r->count > 0 && l->count + r->count <= TR_WBVH_LEAF_MERGE;
        }
    }
    CHECK(small_split == 0, "%s: %u nodes of at most %u triangles split", name, small_split,
          TR_WBVH_LEAF_MERGE);
    CHECK(cut.node_count < full.node_count, "%s: %u binary nodes, no fewer than %u", name,
          cut.node_count, full.node_count);
    CHECK(wa.node_count == wb.node_count && wa.leaf_count == wb.leaf_count &&
              wa.packet_count == wb.packet_count,
          "%s: wide trees of %u/%u nodes, %u/%u leaves, %u/%u packets", name, wa.node_count,
          wb.node_count, wa.leaf_count, wb.leaf_count, wa.packet_count, wb.packet_count);
    if (wa.node_count == wb.node_count && wa.leaf_count == wb.leaf_count) {
        CHECK(memcmp(wa.nodes, wb.nodes, (size_t)wa.node_count * sizeof *wa.nodes) == 0,
              "%s: the wide nodes differ", name);
        uint32_t differ = 0;
        for (uint32_t i = 0; i < wa.leaf_count; ++i) {
            const tr_wbvh_leaf *a = &wa.leaves[i], *b = &wb.leaves[i];
            if (a->packet != b->packet || a->first != b->first || a->count != b->count) {
                ++differ;
                continue;
            }
            /* A leaf holds at most its packets' four lanes each. */
            uint32_t ia[4 * TR_WBVH_LEAF_MAX_PACKETS], ib[4 * TR_WBVH_LEAF_MAX_PACKETS];
            const uint32_t c = a->count;
            if (c > 4 * TR_WBVH_LEAF_MAX_PACKETS) {
                ++differ;
                continue;
            }
            for (uint32_t k = 0; k < c; ++k) {
                ia[k] = full.indices[a->first + k];
                ib[k] = cut.indices[b->first + k];
            }
            qsort(ia, c, sizeof *ia, cmp_u32);
            qsort(ib, c, sizeof *ib, cmp_u32);
            differ += memcmp(ia, ib, c * sizeof *ia) != 0;
        }
        CHECK(differ == 0, "%s: %u of %u wide leaves hold other triangles", name, differ,
              wa.leaf_count);
    }
    tr_wbvh_free(&wa);
    tr_wbvh_free(&wb);
    tr_bvh_free(&full);
    tr_bvh_free(&cut);
}

static void test_wide_build(void) {
    tr_scene s = {0};
    icosphere_scene(&s, 6);
    check_wide_build("icosphere 6", s.triangles, s.triangle_count);
    tr_scene_clear(&s);
    icosphere_scene(&s, 7); /* over 2^17 binary nodes: the collapse's runs by all threads */
    check_wide_build("icosphere 7", s.triangles, s.triangle_count);
    tr_scene_clear(&s);
    tr_rng r;
    tr_rng_init(&r, 77, 1, 0);
    uint32_t n = 0;
    tr_triangle *soup = make_soup(&r, &n);
    for (uint32_t i = 0; i < n; ++i) {
        tr_triangle_finish(&soup[i]);
    }
    check_wide_build("soup", soup, n);
    free(soup);
}

/* Triangles that can never be hit are marked by all threads and squeezed out before the
 * build, and the parallel build puts its subtrees in regions of the node array: a big
 * mesh with such triangles interleaved (zero area, NaN) must give node for node the tree
 * of the same mesh without them, its entries naming the same triangles by their indices
 * in the longer array, on one thread and on two. */
static void test_build_skips_in_parallel(void) {
    tr_error err;
    tr_scene s = {0};
    icosphere_scene(&s, 6);
    const uint32_t n = s.triangle_count;
    tr_triangle *mixed = malloc((size_t)(2 * n) * sizeof *mixed);
    uint32_t *where = malloc((size_t)n * sizeof *where);
    uint32_t total = 0;
    for (uint32_t i = 0; i < n; ++i) {
        if (i % 5 == 1) {
            tr_triangle flat = s.triangles[i];
            flat.v1 = flat.v2 = flat.v0;
            flat.area = 0.0f;
            mixed[total++] = flat;
        }
        if (i % 7 == 3) {
            tr_triangle bad = s.triangles[i];
            bad.v2.y = NAN;
            mixed[total++] = bad;
        }
        where[i] = total;
        mixed[total++] = s.triangles[i];
    }
    for (int threads = 1; threads <= 2; ++threads) {
        omp_set_num_threads(threads);
        tr_bvh clean, dirty;
        CHECK(tr_bvh_build(&clean, s.triangles, n, &err) == TR_OK, "%s", err.msg);
        CHECK(tr_bvh_build(&dirty, mixed, total, &err) == TR_OK, "%s", err.msg);
        CHECK(dirty.skipped == total - n && dirty.index_count == n && clean.index_count == n,
              "%d threads: %u of %u triangles skipped, %u entries", threads, dirty.skipped, total,
              dirty.index_count);
        CHECK(dirty.node_count == clean.node_count &&
                  memcmp(dirty.nodes, clean.nodes, clean.node_count * sizeof *clean.nodes) == 0,
              "%d threads: the nodes differ with unhittable triangles interleaved", threads);
        uint32_t wrong = 0;
        for (uint32_t k = 0; k < n && dirty.index_count == n; ++k) {
            wrong += dirty.indices[k] != where[clean.indices[k]] ||
                     dirty.tris[k].index != dirty.indices[k] ||
                     memcmp(&dirty.tris[k].v0, &clean.tris[k].v0, 3 * sizeof(tr_vec3)) != 0;
        }
        CHECK(wrong == 0, "%d threads: %u entries name other triangles", threads, wrong);
        tr_bvh_free(&clean);
        tr_bvh_free(&dirty);
    }
    free(mixed);
    free(where);
    tr_scene_clear(&s);
}

int main(void) {
    double t0 = tr_time_now();
    test_parallel_build_deterministic();
    test_kept_blocks();
    test_build_skips_in_parallel();
    test_wide_build();
    test_meshes();
    test_stress();
    test_degenerate();
    test_refit();
    test_huge_triangles();
    test_render();
    printf("test_bvh: %.2f s\n", tr_time_now() - t0);
    return check_finish("test_bvh");
}
