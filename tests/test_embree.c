/* test_embree.c - Embree (--accel embree) finds what the thesis's flat structure finds.
 *
 * For each mesh, random rays are traced through the flat structure (the reference:
 * every triangle of every shape box the ray meets) and through Embree. They must give
 * the same closest hit (triangle, distance, barycentrics); the only differences
 * accepted are ties between triangles at the same distance and rays through an edge
 * or vertex, where two non-watertight intersectors may disagree - both are counted
 * and bounded. Any-hit must agree with closest-hit, degenerate triangles must never
 * be hit, the interval (tmin, tmax) must be open at both ends as in the flat
 * structure, and the Cornell box must render (almost) the same image.
 *
 * The project's install script installs Embree, so a build without it fails here
 * instead of skipping. */
#include <float.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "kernel/kernel.h"
#include "scene/scene_internal.h"
#include "trac0r/trac0r.h"

#ifndef TRAC0R_HAVE_EMBREE

int main(void) {
    tr_scene s = {0};
    tr_error err;
    tr_scene_init(&s);
    int rc = tr_scene_commit(&s, TR_ACCEL_TYPE_EMBREE, &err);
    CHECK_STATUS(rc, err, TR_STATUS_UNSUPPORTED, "commit without Embree");
    CHECK(!tr_accel_available(TR_ACCEL_TYPE_EMBREE), "embree reported available");
    tr_scene_clear(&s);
    fprintf(stderr, "test_embree: this build has no Embree (TRAC0R_HAVE_EMBREE is not defined); "
                    "run scripts/install-deps and configure again\n");
    check_finish("test_embree");
    return 1;
}

#else

/* Rays per mesh; the icosphere is one shape box, so its flat reference is a
 * brute-force loop over 20 480 triangles and gets fewer. */
#define RAYS 100000u
#define ICO_RAYS 25000u
/* Same triangle: distance within this relative tolerance, barycentrics within BARY_TOL,
 * both widened for ill-conditioned hits (see tolerance_for). */
#define T_REL_TOL 1e-4
#define BARY_TOL 1e-4
/* A hit this close to an edge (smallest barycentric) may be seen by one intersector and
 * not the other. */
#define EDGE_BARY 1e-4f
/* Ties (different triangles at the same distance) and edge disagreements, each as a
 * fraction of the rays, must stay below these (duplicated triangles excepted). */
#define MAX_TIE_FRACTION 0.001
#define MAX_EDGE_FRACTION 0.001
/* Hits whose distance or barycentrics agree only within the conditioning-aware
 * tolerance (grazing rays, rays starting next to the triangle), as a fraction. */
#define MAX_ILL_FRACTION 0.005
/* Rendering: pixels whose value differs beyond PIXEL_REL_TOL (any channel). */
#define PIXEL_REL_TOL 1e-3
#define MAX_DIFF_PIXEL_FRACTION 0.01

/* ---- scenes --------------------------------------------------------------------------- */

static tr_vec3 rand_in(tr_rng *r, tr_aabb b) {
    return v3(tr_rng_range(r, b.min.x, b.max.x), tr_rng_range(r, b.min.y, b.max.y),
              tr_rng_range(r, b.min.z, b.max.z));
}

static tr_vec3 rand_dir(tr_rng *r) {
    float cz = tr_rng_range(r, -1.0f, 1.0f);
    float a = tr_rng_range(r, 0.0f, TR_TWO_PI);
    float sz = sqrtf(fmaxf(0.0f, 1.0f - cz * cz));
    return v3(sz * cosf(a), sz * sinf(a), cz);
}

/* Hands n triangles (malloc'd, taken over) to an empty scene with one material and a
 * flat structure of one box per `group` triangles. */
static void scene_take_triangles(tr_scene *s, tr_triangle *t, uint32_t n, uint32_t group) {
    tr_error err;
    tr_scene_init(s);
    CHECK(tr_scene_add_material(s, tr_material_diffuse(v3s(0.8f)), NULL, &err) == TR_OK, "%s",
          err.msg);
    for (uint32_t i = 0; i < n; ++i) {
        t[i].material = 0;
        tr_triangle_finish(&t[i]);
    }
    s->triangles = t;
    s->triangle_count = s->triangle_capacity = n;
    uint32_t boxes = n ? (n + group - 1) / group : 0;
    s->shapes = boxes ? calloc(boxes, sizeof *s->shapes) : NULL;
    CHECK(boxes == 0 || s->shapes != NULL, "out of memory");
    if (boxes && !s->shapes) {
        abort();
    }
    for (uint32_t b = 0; b < boxes; ++b) {
        s->shapes[b].first = b * group;
        s->shapes[b].count = b * group + group <= n ? group : n - b * group;
        /* Non-finite vertices would spoil a box; the flat structure of a real scene has
         * the same problem, so keep the boxes finite by bounding finite vertices only. */
        tr_aabb box = {v3s(INFINITY), v3s(-INFINITY)};
        for (uint32_t i = s->shapes[b].first; i < s->shapes[b].first + s->shapes[b].count; ++i) {
            const tr_vec3 p[3] = {t[i].v0, t[i].v1, t[i].v2};
            for (int k = 0; k < 3; ++k) {
                if (v3_is_finite(p[k])) {
                    box.min = v3_min(box.min, p[k]);
                    box.max = v3_max(box.max, p[k]);
                }
            }
        }
        s->shapes[b].box = box;
    }
    s->shape_count = s->shape_capacity = boxes;
}

/* Degenerate triangles in the soup: index -> kind. */
enum { DEGEN_REPEATED, DEGEN_COLLINEAR, DEGEN_NAN, DEGEN_INF, DEGEN_KINDS };

/* Random triangles in the unit cube, sizes from 0.005 to 0.5, after `*degenerate`
 * degenerate ones (first, so that Embree's primIDs would be shifted if it numbered the
 * triangles it keeps rather than all it was given) and followed by `*dups` exact copies
 * of random ones (coincident triangles: ties by construction). */
static void make_soup(tr_scene *s, tr_rng *r, uint32_t *dups, uint32_t *degenerate) {
    const uint32_t degen = 40, base = 3000, dup = 60;
    uint32_t n = degen + base + dup;
    tr_triangle *t = calloc(n, sizeof *t);
    if (!t) {
        abort();
    }
    tr_aabb cube = {v3s(0.0f), v3s(1.0f)};
    tr_aabb unit = {v3s(-1.0f), v3s(1.0f)};
    for (uint32_t i = 0; i < degen; ++i) {
        tr_vec3 a = rand_in(r, cube);
        switch (i % DEGEN_KINDS) {
        case DEGEN_REPEATED:
            t[i].v0 = a;
            t[i].v1 = a;
            t[i].v2 = rand_in(r, cube);
            break;
        case DEGEN_COLLINEAR: /* exactly collinear: along x, midpoint exact */
            t[i].v0 = a;
            t[i].v1 = v3(a.x + 0.25f, a.y, a.z);
            t[i].v2 = v3(a.x + 0.125f, a.y, a.z);
            break;
        case DEGEN_NAN:
            t[i].v0 = a;
            t[i].v1 = v3(a.x + 0.1f, NAN, a.z);
            t[i].v2 = v3(a.x, a.y + 0.1f, a.z);
            break;
        default:
            t[i].v0 = a;
            t[i].v1 = v3(a.x + 0.1f, a.y, a.z);
            t[i].v2 = v3(a.x, INFINITY, a.z);
            break;
        }
    }
    for (uint32_t i = degen; i < degen + base; ++i) {
        tr_vec3 c = rand_in(r, cube);
        float size = 0.005f * powf(100.0f, tr_rng_float(r));
        t[i].v0 = v3_madd(c, rand_in(r, unit), size);
        t[i].v1 = v3_madd(c, rand_in(r, unit), size);
        t[i].v2 = v3_madd(c, rand_in(r, unit), size);
    }
    for (uint32_t i = degen + base; i < n; ++i) {
        t[i] = t[degen + (uint32_t)(tr_rng_next(r) % base)];
    }
    /* Groups of 64 consecutive triangles: the random ones are spread over the cube, so
     * the boxes overlap and the flat reference stays a near brute-force loop. */
    scene_take_triangles(s, t, n, 64);
    *dups = dup;
    *degenerate = degen;
}

static void make_icosphere(tr_scene *s, uint32_t subdivisions) {
    tr_error err;
    tr_scene_init(s);
    uint32_t m = 0;
    CHECK(tr_scene_add_material(s, tr_material_diffuse(v3s(0.8f)), &m, &err) == TR_OK, "%s",
          err.msg);
    tr_shape_desc d = tr_shape_desc_default(TR_SHAPE_ICOSPHERE);
    d.subdivisions = subdivisions;
    d.material = m;
    d.transform.position = v3(0.1f, -0.2f, 0.3f);
    d.transform.scale = v3s(0.7f);
    CHECK(tr_scene_add_shape(s, &d, &err) == TR_OK, "%s", err.msg);
}

/* ---- comparing flat and Embree ------------------------------------------------------ */

typedef struct compare_stats {
    uint64_t rays, hits_flat, hits_embree;
    uint64_t feature_rays;   /* rays aimed exactly at a vertex or an edge midpoint */
    uint64_t ties;           /* different triangles at the same distance */
    uint64_t dup_ties;       /* ... where the two are exact copies */
    uint64_t edge;           /* one sees a hit at an edge or vertex, the other not */
    uint64_t feature_ties;   /* ties and edge cases of the feature rays */
    uint64_t ill;            /* same hit, within tolerance only thanks to conditioning */
    uint64_t failures;       /* anything else */
    uint64_t occluded_wrong; /* any-hit disagreeing with closest-hit */
    uint64_t degenerate_hit; /* hits on triangles that cannot be hit */
    double worst_t_rel;      /* same triangle: largest relative distance difference */
} compare_stats;

static int triangle_hittable(const tr_triangle *t) {
    return v3_is_finite(t->v0) && v3_is_finite(t->v1) && v3_is_finite(t->v2) && t->area > 0.0f;
}

static int same_triangle_geometry(const tr_triangle *a, const tr_triangle *b) {
    return memcmp(&a->v0, &b->v0, 3 * sizeof(tr_vec3)) == 0;
}

static double max_abs(tr_vec3 a) {
    return fmax(fabs((double)a.x), fmax(fabs((double)a.y), fabs((double)a.z)));
}

/* How far two single-precision evaluations of one ray/triangle hit may drift apart.
 * Both compute t and the barycentrics as a quotient whose numerator is rounded at the
 * scale L of the coordinates involved and whose denominator is proportional to the
 * cosine between ray and plane, so the error in t grows like eps * L / cos, and in the
 * barycentrics like that over the triangle's height. Rays far from grazing and not
 * starting on the triangle get tolerances of about T_REL_TOL and BARY_TOL. */
typedef struct hit_tolerance {
    double t;    /* absolute, on t */
    double bary; /* absolute, on u and v, and the width of the band counted as an edge */
    double t_rel_only;
    double bary_only;
} hit_tolerance;

static hit_tolerance tolerance_for(const tr_triangle *tri, const tr_ray *r, double t) {
    double len = v3_length(r->dir);
    double L = fmax(max_abs(r->origin), t * len);
    L = fmax(L, fmax(max_abs(tri->v0), fmax(max_abs(tri->v1), max_abs(tri->v2))));
    double c = fabs((double)v3_dot(tri->normal, r->dir)) / len;
    double drift = 16.0 * FLT_EPSILON * L / fmax(c, 1e-30);
    double e0 = v3_length(v3_sub(tri->v1, tri->v0)), e1 = v3_length(v3_sub(tri->v2, tri->v1)),
           e2 = v3_length(v3_sub(tri->v0, tri->v2));
    double longest = fmax(e0, fmax(e1, e2));
    double height = 2.0 * (double)tri->area / longest; /* the smallest height */
    hit_tolerance h;
    h.t_rel_only = T_REL_TOL * t;
    h.bary_only = BARY_TOL;
    h.t = h.t_rel_only + drift;
    h.bary = BARY_TOL + drift / fmax(height, 1e-30);
    return h;
}

static float min_bary(const tr_hit *h) {
    return fminf(fminf(h->u, h->v), 1.0f - h->u - h->v);
}

static void report_failure(const char *name, const tr_ray *r, int hf, const tr_hit *f, int he,
                           const tr_hit *e, const char *why) {
    fprintf(stderr,
            "%s: %s: ray o (%.9g, %.9g, %.9g) d (%.9g, %.9g, %.9g) (%.9g, %.9g): flat %s tri %u "
            "t %.9g u %.6g v %.6g, embree %s tri %u t %.9g u %.6g v %.6g\n",
            name, why, (double)r->origin.x, (double)r->origin.y, (double)r->origin.z,
            (double)r->dir.x, (double)r->dir.y, (double)r->dir.z, (double)r->tmin, (double)r->tmax,
            hf ? "hit" : "miss", hf ? f->triangle : 0u, hf ? (double)f->t : 0.0,
            hf ? (double)f->u : 0.0, hf ? (double)f->v : 0.0, he ? "hit" : "miss",
            he ? e->triangle : 0u, he ? (double)e->t : 0.0, he ? (double)e->u : 0.0,
            he ? (double)e->v : 0.0);
}

/* Traces one ray through both views and files the outcome in *st. `feature`: the ray
 * was aimed exactly at a vertex or an edge, where ties and edge cases are expected. */
static void compare_ray(const char *name, const tr_scene *s, const tr_scene_view *flat,
                        const tr_scene_view *emb, const tr_ray *ray, int feature,
                        compare_stats *st) {
    tr_hit f, e;
    memset(&f, 0, sizeof f);
    memset(&e, 0, sizeof e);
    int hf = tr_intersect_scene(flat, ray, &f);
    int he = tr_intersect_scene(emb, ray, &e);
    int oe = tr_occluded_scene(emb, ray);
    st->rays++;
    st->feature_rays += (uint64_t)feature;
    st->hits_flat += (uint64_t)hf;
    st->hits_embree += (uint64_t)he;
    if (oe != he) {
        st->occluded_wrong++;
        if (st->occluded_wrong <= 5) {
            report_failure(name, ray, hf, &f, he, &e, "occluded disagrees with closest hit");
        }
    }
    if (he && (e.triangle >= s->triangle_count || !triangle_hittable(&s->triangles[e.triangle]))) {
        st->degenerate_hit++;
        report_failure(name, ray, hf, &f, he, &e, "embree hit a degenerate triangle");
        return;
    }
    if (!hf && !he) {
        return;
    }
    hit_tolerance tf = {0, 0, 0, 0}, te = {0, 0, 0, 0};
    if (hf) {
        tf = tolerance_for(&s->triangles[f.triangle], ray, f.t);
    }
    if (he) {
        te = tolerance_for(&s->triangles[e.triangle], ray, e.t);
    }
    const char *why = NULL;
    int edge_case = (hf && min_bary(&f) < EDGE_BARY + tf.bary - BARY_TOL) ||
                    (he && min_bary(&e) < EDGE_BARY + te.bary - BARY_TOL);
    if (hf && he && f.triangle == e.triangle) {
        double dt = fabs((double)f.t - (double)e.t);
        double db = fmax(fabs((double)f.u - (double)e.u), fabs((double)f.v - (double)e.v));
        st->worst_t_rel = fmax(st->worst_t_rel, dt / fmax((double)f.t, 1e-30));
        if (dt > tf.t) {
            why = "same triangle, distances differ";
        } else if (db > tf.bary) {
            why = "same triangle, barycentrics differ";
        } else if (dt > tf.t_rel_only || db > tf.bary_only) {
            st->ill++;
        }
    } else if (hf && he && fabs((double)f.t - (double)e.t) <= fmax(tf.t, te.t)) {
        if (same_triangle_geometry(&s->triangles[f.triangle], &s->triangles[e.triangle])) {
            st->dup_ties++;
        } else if (feature) {
            st->feature_ties++;
        } else {
            st->ties++;
        }
    } else if (edge_case) {
        if (feature) {
            st->feature_ties++;
        } else {
            st->edge++;
        }
    } else {
        why = hf && he ? "different triangles at different distances"
              : hf     ? "embree missed"
                       : "embree hit where flat missed";
    }
    if (why) {
        st->failures++;
        if (st->failures <= 10) {
            report_failure(name, ray, hf, &f, he, &e, why);
        }
    }
}

/* A random ray for a scene bounded by `b`: from anywhere in the box grown by a fifth,
 * half of them aimed at a random point of a random triangle (one in 25 of those at one
 * of its vertices or edge midpoints exactly, where ties and edge cases live: *feature
 * is set for them), with a mix of intervals. */
static tr_ray random_ray(tr_rng *r, const tr_scene *s, tr_aabb b, int *feature) {
    tr_vec3 ext = v3_sub(b.max, b.min);
    float diag = v3_length(ext);
    tr_aabb grown = {v3_sub(b.min, v3_scale(ext, 0.2f)), v3_add(b.max, v3_scale(ext, 0.2f))};
    tr_vec3 o = rand_in(r, grown);
    tr_vec3 d = rand_dir(r);
    *feature = 0;
    if (s->triangle_count > 0 && tr_rng_float(r) < 0.5f) {
        const tr_triangle *t = &s->triangles[tr_rng_next(r) % s->triangle_count];
        float pick = tr_rng_float(r), a = tr_rng_float(r), c = tr_rng_float(r);
        if (a + c > 1.0f) {
            a = 1.0f - a;
            c = 1.0f - c;
        }
        tr_vec3 target;
        if (pick < 0.02f) {
            target = t->v1;
            *feature = 1;
        } else if (pick < 0.04f) {
            target = v3_scale(v3_add(t->v0, t->v2), 0.5f);
            *feature = 1;
        } else {
            target = v3_add(t->v0, v3_add(v3_scale(v3_sub(t->v1, t->v0), a),
                                          v3_scale(v3_sub(t->v2, t->v0), c)));
        }
        tr_vec3 to = v3_sub(target, o);
        if (v3_is_finite(to) && v3_length(to) > 1e-6f) {
            d = v3_normalize(to);
        } else {
            *feature = 0;
        }
    }
    float tmin = 0.0f, tmax = INFINITY;
    float which = tr_rng_float(r);
    if (which < 0.15f) {
        tmin = tr_rng_range(r, 0.0f, 0.5f * diag);
    } else if (which < 0.30f) {
        tmax = tr_rng_range(r, 0.0f, 1.5f * diag);
    } else if (which < 0.35f) {
        tmin = tr_rng_range(r, 0.0f, 0.5f * diag);
        tmax = tmin + tr_rng_range(r, 0.0f, diag);
    }
    return tr_ray_make(o, d, tmin, tmax);
}

/* Commits `s` to Embree and compares `rays` random rays with the flat structure. */
static void check_mesh(const char *name, tr_scene *s, uint32_t rays, uint32_t dups, uint64_t seed) {
    tr_error err;
    int rc = tr_scene_commit(s, TR_ACCEL_TYPE_EMBREE, &err);
    CHECK(rc == TR_OK, "%s: commit: %s", name, rc == TR_OK ? "" : err.msg);
    if (rc != TR_OK) {
        return;
    }
    CHECK(tr_scene_is_committed(s) && s->accel == TR_ACCEL_TYPE_EMBREE && s->embree.scene,
          "%s: not committed to embree", name);
    tr_scene_view emb = tr_scene_view_of(s);
    tr_scene_view flat = emb;
    flat.accel = TR_ACCEL_FLAT;
    CHECK(emb.accel == TR_ACCEL_EMBREE && emb.embree_scene == s->embree.scene,
          "%s: the view does not carry the Embree scene", name);

    tr_aabb b = s->triangle_count ? tr_triangles_bounds(s->triangles, s->triangle_count)
                                  : (tr_aabb){v3s(-1.0f), v3s(1.0f)};
    /* The soup's non-finite vertices would make the bounds useless: use the unit cube. */
    if (!v3_is_finite(b.min) || !v3_is_finite(b.max)) {
        b = (tr_aabb){v3s(0.0f), v3s(1.0f)};
    }
    compare_stats st;
    memset(&st, 0, sizeof st);
    tr_rng rng;
    tr_rng_init(&rng, seed, 0, 0);
    for (uint32_t i = 0; i < rays; ++i) {
        int feature;
        tr_ray ray = random_ray(&rng, s, b, &feature);
        compare_ray(name, s, &flat, &emb, &ray, feature, &st);
    }
    printf("%s: %u triangles, embree built in %.2f ms; %llu rays (%llu at vertices/edges), "
           "%llu flat hits, %llu embree hits; ties: %llu (+%llu between duplicates, +%llu "
           "ties/edge cases of vertex/edge rays); %llu edge disagreements; %llu ill-conditioned; "
           "%llu failures; worst relative t difference %.3g\n",
           name, s->triangle_count, s->embree.build_seconds * 1e3, (unsigned long long)st.rays,
           (unsigned long long)st.feature_rays, (unsigned long long)st.hits_flat,
           (unsigned long long)st.hits_embree, (unsigned long long)st.ties,
           (unsigned long long)st.dup_ties, (unsigned long long)st.feature_ties,
           (unsigned long long)st.edge, (unsigned long long)st.ill, (unsigned long long)st.failures,
           st.worst_t_rel);
    CHECK(st.failures == 0, "%s: %llu rays disagree beyond ties and edges", name,
          (unsigned long long)st.failures);
    CHECK(st.occluded_wrong == 0, "%s: any-hit disagrees with closest-hit on %llu rays", name,
          (unsigned long long)st.occluded_wrong);
    CHECK(st.degenerate_hit == 0, "%s: %llu hits on degenerate triangles", name,
          (unsigned long long)st.degenerate_hit);
    CHECK((double)st.ties <= MAX_TIE_FRACTION * (double)rays, "%s: %llu ties in %u rays", name,
          (unsigned long long)st.ties, rays);
    CHECK((double)st.edge <= MAX_EDGE_FRACTION * (double)rays,
          "%s: %llu edge disagreements in %u rays", name, (unsigned long long)st.edge, rays);
    CHECK((double)st.ill <= MAX_ILL_FRACTION * (double)rays,
          "%s: %llu ill-conditioned hits in %u rays", name, (unsigned long long)st.ill, rays);
    CHECK(dups > 0 || st.dup_ties == 0, "%s: ties between duplicates without duplicates", name);
    if (s->triangle_count > 0) {
        CHECK(st.hits_flat > rays / 10, "%s: only %llu of %u rays hit: the rays test too little",
              name, (unsigned long long)st.hits_flat, rays);
    } else {
        CHECK(st.hits_embree == 0, "%s: hits in an empty scene", name);
    }
}

static void test_random_meshes(void) {
    tr_error err;
    tr_scene s = {0};
    tr_rng rng;
    tr_rng_init(&rng, 42, 1, 0);
    uint32_t dups = 0, degenerate = 0;
    make_soup(&s, &rng, &dups, &degenerate);
    uint32_t unhittable = 0;
    for (uint32_t i = 0; i < s.triangle_count; ++i) {
        unhittable += !triangle_hittable(&s.triangles[i]);
    }
    CHECK(unhittable == degenerate, "soup: %u triangles cannot be hit, expected %u", unhittable,
          degenerate);
    check_mesh("soup", &s, RAYS, dups, 1);
    /* Rays straight at every degenerate triangle's first vertex. */
    tr_scene_view emb = tr_scene_view_of(&s);
    uint32_t degenerate_hits = 0;
    for (uint32_t i = 0; i < degenerate; ++i) {
        for (int k = 0; k < 16; ++k) {
            tr_vec3 d = rand_dir(&rng);
            tr_ray ray = tr_ray_make(v3_madd(s.triangles[i].v0, d, -2.0f), d, 0.0f, INFINITY);
            tr_hit h;
            if (tr_intersect_scene(&emb, &ray, &h) &&
                !triangle_hittable(&s.triangles[h.triangle])) {
                ++degenerate_hits;
            }
        }
    }
    CHECK(degenerate_hits == 0, "soup: %u rays hit degenerate triangles", degenerate_hits);
    tr_scene_clear(&s);

    make_icosphere(&s, 5);
    CHECK(s.triangle_count == 20480u, "icosphere: %u triangles", s.triangle_count);
    check_mesh("icosphere-5", &s, ICO_RAYS, 0, 2);
    tr_scene_clear(&s);

    CHECK(tr_scene_builtin(&s, "cornell", 64, 48, &err) == TR_OK, "%s", err.msg);
    check_mesh("cornell", &s, RAYS, 0, 3);
    tr_scene_clear(&s);

    tr_scene_init(&s);
    check_mesh("empty", &s, 10000, 0, 4);
    tr_scene_clear(&s);

    tr_triangle *one = calloc(1, sizeof *one);
    if (!one) {
        abort();
    }
    one->v0 = v3(-0.5f, -0.4f, 0.1f);
    one->v1 = v3(0.6f, -0.3f, -0.2f);
    one->v2 = v3(0.0f, 0.7f, 0.05f);
    scene_take_triangles(&s, one, 1, 1);
    check_mesh("single", &s, RAYS, 0, 5);
    tr_scene_clear(&s);
}

/* ---- exact cases -------------------------------------------------------------------- */

/* One triangle in the plane z = 1 (v0 at the origin's shadow), so that rays along z hit
 * it at t exactly 1: the ends of the interval are tested exactly. */
static void test_interval_and_conventions(void) {
    tr_error err;
    tr_scene s = {0};
    tr_triangle *t = calloc(1, sizeof *t);
    if (!t) {
        abort();
    }
    t->v0 = v3(0.0f, 0.0f, 1.0f);
    t->v1 = v3(1.0f, 0.0f, 1.0f);
    t->v2 = v3(0.0f, 1.0f, 1.0f);
    scene_take_triangles(&s, t, 1, 1);
    /* The flat reference's slab test misses rays lying in a face plane of a box (here
     * the rays along x = 0 or y = 0 through the edges): give it a box with room around
     * the triangle, so that it is the triangle test that decides. */
    s.shapes[0].box.min = v3_sub(s.shapes[0].box.min, v3s(1.0f));
    s.shapes[0].box.max = v3_add(s.shapes[0].box.max, v3s(1.0f));
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_EMBREE, &err) == TR_OK, "%s", err.msg);
    tr_scene_view emb = tr_scene_view_of(&s), flat = emb;
    flat.accel = TR_ACCEL_FLAT;

    const tr_vec3 o = v3(0.25f, 0.5f, 0.0f), up = v3(0.0f, 0.0f, 1.0f);
    const struct {
        float tmin, tmax;
        int hit;
    } cases[] = {
        {0.0f, INFINITY, 1},
        {1.0f, INFINITY, 0},               /* t == tmin: open at tmin */
        {nextafterf(1.0f, 0.0f), 2.0f, 1}, /* tmin just below */
        {0.0f, 1.0f, 0},                   /* t == tmax: open at tmax */
        {0.0f, nextafterf(1.0f, 2.0f), 1}, /* tmax just above */
        {nextafterf(1.0f, 0.0f), nextafterf(1.0f, 2.0f), 1},
        {2.0f, 1.0f, 0},      /* empty interval */
        {NAN, INFINITY, 0},   /* NaN interval */
        {0.5f, 0.5f, 0},      /* a point */
        {-1.0f, INFINITY, 1}, /* negative tmin: the hit ahead still counts */
        {0.0f, FLT_MAX, 1},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        tr_ray r = tr_ray_make(o, up, cases[i].tmin, cases[i].tmax);
        tr_hit hf = {0}, he = {0};
        int f = tr_intersect_scene(&flat, &r, &hf);
        int e = tr_intersect_scene(&emb, &r, &he);
        int oe = tr_occluded_scene(&emb, &r);
        CHECK(f == cases[i].hit && e == cases[i].hit && oe == cases[i].hit,
              "interval (%.9g, %.9g): flat %d, embree %d, occluded %d, expected %d",
              (double)cases[i].tmin, (double)cases[i].tmax, f, e, oe, cases[i].hit);
        if (e && f) {
            CHECK(he.t == 1.0f && he.triangle == 0 && he.u == hf.u && he.v == hf.v,
                  "interval case %zu: embree t %.9g tri %u u %.9g v %.9g, flat u %.9g v %.9g", i,
                  (double)he.t, he.triangle, (double)he.u, (double)he.v, (double)hf.u,
                  (double)hf.v);
        }
    }
    /* Barycentrics: p = (1-u-v) v0 + u v1 + v v2, so at (0.25, 0.5) u = 0.25, v = 0.5. */
    tr_hit h;
    tr_ray r = tr_ray_make(o, up, 0.0f, INFINITY);
    CHECK(tr_intersect_scene(&emb, &r, &h) && h.u == 0.25f && h.v == 0.5f,
          "barycentrics: u %.9g v %.9g, expected 0.25 0.5", (double)h.u, (double)h.v);
    /* Two-sided: from behind, the same point. */
    r = tr_ray_make(v3(0.25f, 0.5f, 3.0f), v3(0.0f, 0.0f, -1.0f), 0.0f, INFINITY);
    CHECK(tr_intersect_scene(&emb, &r, &h) && h.t == 2.0f && h.u == 0.25f && h.v == 0.5f,
          "back face: t %.9g u %.9g v %.9g", (double)h.t, (double)h.u, (double)h.v);
    CHECK(tr_occluded_scene(&emb, &r), "back face not occluded");
    /* A ray starting on the triangle does not hit it at t = 0, in either structure. */
    r = tr_ray_make(v3(0.25f, 0.5f, 1.0f), up, 0.0f, INFINITY);
    CHECK(!tr_intersect_scene(&emb, &r, &h) && !tr_intersect_scene(&flat, &r, &h) &&
              !tr_occluded_scene(&emb, &r),
          "a ray leaving the triangle hit it");
    /* Edges and vertices count as inside. */
    const tr_vec3 on_edge[] = {v3(0.0f, 0.0f, 0.0f), v3(0.5f, 0.5f, 0.0f), v3(0.0f, 0.5f, 0.0f),
                               v3(0.5f, 0.0f, 0.0f)};
    for (size_t i = 0; i < sizeof on_edge / sizeof on_edge[0]; ++i) {
        r = tr_ray_make(on_edge[i], up, 0.0f, INFINITY);
        tr_hit hf;
        int f = tr_intersect_scene(&flat, &r, &hf);
        int e = tr_intersect_scene(&emb, &r, &h);
        CHECK(f && e && h.t == 1.0f, "edge point %zu: flat %d embree %d", i, f, e);
    }
    /* Rays the flat structure can hit nothing with. */
    const tr_ray bad[] = {
        tr_ray_make(v3(0.25f, NAN, 0.0f), up, 0.0f, INFINITY),
        tr_ray_make(o, v3(NAN, 0.0f, 1.0f), 0.0f, INFINITY),
        tr_ray_make(o, v3(0.0f, 0.0f, 0.0f), 0.0f, INFINITY),
        tr_ray_make(v3(INFINITY, 0.5f, 0.0f), up, 0.0f, INFINITY),
        tr_ray_make(o, v3(1.0f, 0.0f, 0.0f), 0.0f, INFINITY), /* in a parallel plane */
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        tr_hit hf;
        int f = tr_intersect_scene(&flat, &bad[i], &hf);
        int e = tr_intersect_scene(&emb, &bad[i], &h);
        CHECK(!f && !e && !tr_occluded_scene(&emb, &bad[i]), "bad ray %zu: flat %d embree %d", i, f,
              e);
    }
    tr_scene_clear(&s);
}

/* Commit bookkeeping: names, availability, staleness, switching structures. */
static void test_commit(void) {
    tr_error err;
    CHECK(tr_accel_from_name("embree") == (int)TR_ACCEL_TYPE_EMBREE, "from_name");
    CHECK(strcmp(tr_accel_name(TR_ACCEL_TYPE_EMBREE), "embree") == 0, "name");
    CHECK(tr_accel_available(TR_ACCEL_TYPE_EMBREE) && tr_accel_available(TR_ACCEL_TYPE_BVH) &&
              tr_accel_available(TR_ACCEL_TYPE_FLAT),
          "availability");
    tr_scene s = {0};
    CHECK(tr_scene_builtin(&s, "cornell", 32, 24, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_EMBREE, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_scene_embree_build_seconds(&s) > 0.0, "build time %g",
          tr_scene_embree_build_seconds(&s));
    /* Recommitting releases the previous Embree scene (LeakSanitizer checks). */
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_EMBREE, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
    CHECK(s.embree.scene == NULL && s.embree.state == NULL &&
              tr_scene_embree_build_seconds(&s) == 0,
          "the BVH commit kept the Embree scene");
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_EMBREE, &err) == TR_OK, "%s", err.msg);
    /* Adding a shape makes the Embree scene stale: rendering must refuse it. */
    tr_shape_desc d = tr_shape_desc_default(TR_SHAPE_BOX);
    d.transform.scale = v3s(0.1f);
    CHECK(tr_scene_add_shape(&s, &d, &err) == TR_OK, "%s", err.msg);
    CHECK(!tr_scene_is_committed(&s), "stale Embree scene counted as committed");
    tr_film film;
    CHECK(tr_film_init(&film, 32, 24, &err) == TR_OK, "%s", err.msg);
    tr_render_config cfg = tr_render_config_default();
    CHECK_STATUS(tr_render_frame(&s, &s.camera, &cfg, &film, 0, NULL, &err), err,
                 TR_STATUS_STALE_SCENE, "rendering a stale Embree scene");
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_EMBREE, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_render_frame(&s, &s.camera, &cfg, &film, 0, NULL, &err) == TR_OK, "%s", err.msg);
    tr_film_free(&film);
    tr_scene_clear(&s);
    CHECK(s.embree.scene == NULL && s.embree.state == NULL, "tr_scene_clear kept Embree");
    /* Freeing twice, and a scene never committed, are fine. */
    tr_scene_clear(&s);
}

/* ---- rendering ---------------------------------------------------------------------- */

static int render_cornell(tr_accel_type accel, tr_film *film, uint64_t *rays) {
    tr_error err;
    tr_scene s = {0};
    int ok = tr_scene_builtin(&s, "cornell", 64, 48, &err) == TR_OK;
    CHECK(ok, "%s", err.msg);
    if (!ok) {
        return 0;
    }
    ok = tr_scene_commit(&s, accel, &err) == TR_OK;
    CHECK(ok, "commit %s: %s", tr_accel_name(accel), ok ? "" : err.msg);
    tr_render_config cfg = tr_render_config_default();
    cfg.seed = 7;
    *rays = 0;
    for (uint32_t i = 0; ok && i < 4; ++i) {
        tr_render_stats stats;
        ok = tr_render_frame(&s, &s.camera, &cfg, film, i, &stats, &err) == TR_OK;
        CHECK(ok, "render %s: %s", tr_accel_name(accel), ok ? "" : err.msg);
        *rays += stats.rays;
    }
    tr_scene_clear(&s);
    return ok;
}

static void test_render(void) {
    tr_error err;
    tr_film a, b;
    CHECK(tr_film_init(&a, 64, 48, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_film_init(&b, 64, 48, &err) == TR_OK, "%s", err.msg);
    uint64_t rays_flat = 0, rays_embree = 0;
    if (render_cornell(TR_ACCEL_TYPE_FLAT, &a, &rays_flat) &&
        render_cornell(TR_ACCEL_TYPE_EMBREE, &b, &rays_embree)) {
        uint32_t n = a.width * a.height, identical = 0, close = 0, differ = 0;
        double worst = 0.0;
        for (uint32_t i = 0; i < n; ++i) {
            if (memcmp(&a.sum[3 * i], &b.sum[3 * i], 3 * sizeof(float)) == 0) {
                ++identical;
                continue;
            }
            int beyond = 0;
            for (int c = 0; c < 3; ++c) {
                double x = a.sum[3 * i + c], y = b.sum[3 * i + c];
                double rel = fabs(x - y) / fmax(fmax(fabs(x), fabs(y)), 1e-6);
                worst = fmax(worst, rel);
                beyond |= rel > PIXEL_REL_TOL;
            }
            differ += (uint32_t)beyond;
            close += (uint32_t)!beyond;
        }
        printf("render: cornell 64x48, 4 spp: %u pixels identical, %u within %.0e, %u differ "
               "(largest relative difference %.3g); %llu rays flat, %llu rays embree\n",
               identical, close, PIXEL_REL_TOL, differ, worst, (unsigned long long)rays_flat,
               (unsigned long long)rays_embree);
        CHECK((double)differ <= MAX_DIFF_PIXEL_FRACTION * n,
              "render: %u of %u pixels differ between flat and embree", differ, n);
        CHECK(memcmp(a.count, b.count, n * sizeof(uint32_t)) == 0, "render: sample counts differ");
    }
    tr_film_free(&a);
    tr_film_free(&b);
}

int main(void) {
    test_commit();
    test_interval_and_conventions();
    test_random_meshes();
    test_render();
    return check_finish("test_embree");
}

#endif
