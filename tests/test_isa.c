/* test_isa.c - the wide BVH's traversal is chosen at run time, and every choice answers
 * alike.
 *
 * The traversal is compiled once per instruction set (src/accel/wbvh_*.c) and the library
 * picks one from what the CPU reports. Checked here: every ISA this CPU can run gives
 * bit for bit the hits (t, triangle, u, v) and the occlusion answers of the portable
 * scalar code on random rays through a few scenes; forcing an ISA routes
 * tr_intersect_scene through it; on a CPU with AVX2 the automatic choice is AVX2 or
 * AVX-512 although this test and the library around the traversal are compiled for
 * baseline x86-64 (a compile-time choice would give SSE2 here); the rule that turns
 * TRAC0R_ISA into a choice falls back to the best usable ISA for a name the CPU lacks or
 * that does not exist; and an ISA the CPU lacks cannot be forced. */
#define _POSIX_C_SOURCE 200112L /* unsetenv */
#include <stdlib.h>
#include <string.h>

#include "accel/wbvh.h"
#include "check.h"
#include "kernel/kernel.h"
#include "scene/scene_internal.h"
#include "scene_util.h"
#include "trac0r/trac0r.h"

#define RAYS 60000u

static uint32_t rng_below(tr_rng *r, uint32_t n) {
    return (uint32_t)(tr_rng_next(r) % n);
}

static tr_vec3 rand_unit(tr_rng *r) {
    float z = tr_rng_range(r, -1.0f, 1.0f);
    float phi = tr_rng_range(r, 0.0f, TR_TWO_PI);
    float s = sqrtf(fmaxf(0.0f, 1.0f - z * z));
    return v3(s * cosf(phi), s * sinf(phi), z);
}

static tr_aabb scene_bounds(const tr_scene_view *v) {
    tr_aabb b = {v3s(INFINITY), v3s(-INFINITY)};
    for (uint32_t i = 0; i < v->triangle_count; ++i) {
        const tr_triangle *t = &v->triangles[i];
        b.min = v3_min(b.min, v3_min(t->v0, v3_min(t->v1, t->v2)));
        b.max = v3_max(b.max, v3_max(t->v0, v3_max(t->v1, t->v2)));
    }
    return b;
}

/* A ray of one of several kinds: aimed at a point of a random triangle (mostly hits),
 * random from around the scene (many misses), exactly along an axis (inv_dir infinite on
 * two axes), in an axis plane (one direction component 0), with a short tmax, or with
 * tmin past the first surfaces. */
static tr_ray rand_ray(tr_rng *r, const tr_scene_view *v, tr_aabb b) {
    tr_vec3 ext = v3_sub(b.max, b.min);
    tr_vec3 lo = v3_sub(b.min, v3_scale(ext, 0.25f)), hi = v3_add(b.max, v3_scale(ext, 0.25f));
    tr_vec3 o =
        v3(tr_rng_range(r, lo.x, hi.x), tr_rng_range(r, lo.y, hi.y), tr_rng_range(r, lo.z, hi.z));
    const tr_triangle *t = &v->triangles[rng_below(r, v->triangle_count)];
    float a = tr_rng_float(r), c = tr_rng_float(r);
    if (a + c > 1.0f) {
        a = 1.0f - a;
        c = 1.0f - c;
    }
    tr_vec3 target = v3_madd(v3_madd(t->v0, v3_sub(t->v1, t->v0), a), v3_sub(t->v2, t->v0), c);
    tr_vec3 d;
    uint32_t kind = rng_below(r, 8);
    if (kind == 0) {
        d = rand_unit(r);
    } else if (kind == 1) {
        float comp[3] = {0.0f, 0.0f, 0.0f};
        comp[rng_below(r, 3)] = tr_rng_float(r) < 0.5f ? -1.0f : 1.0f;
        d = v3(comp[0], comp[1], comp[2]);
        o = v3_madd(target, d, -tr_rng_range(r, -0.2f, 2.0f) * v3_length(ext));
    } else {
        if (kind == 2) {
            uint32_t k = rng_below(r, 3);
            o = v3(k == 0 ? target.x : o.x, k == 1 ? target.y : o.y, k == 2 ? target.z : o.z);
        }
        d = v3_sub(target, o);
        d = v3_length(d) > 0.0f ? v3_normalize(d) : rand_unit(r);
    }
    float tmin = 0.0f, tmax = TR_INFINITY;
    if (rng_below(r, 6) == 0) {
        tmin = tr_rng_range(r, 0.0f, 0.5f * v3_length(ext));
    }
    if (rng_below(r, 4) == 0) {
        tmax = tr_rng_range(r, 0.0f, v3_length(ext));
    }
    return tr_ray_make(o, d, tmin, tmax);
}

static int same_bits(float a, float b) {
    return memcmp(&a, &b, sizeof a) == 0;
}

/* Every usable ISA against the scalar traversal, and the dispatcher forced to each. */
static void compare_isas(const char *name, tr_scene *s) {
    tr_scene_view v = tr_scene_view_of(s);
    CHECK(v.wbvh != NULL && v.triangle_count > 0, "%s: no wide BVH", name);
    if (!v.wbvh || v.triangle_count == 0) {
        return;
    }
    const unsigned mask = tr_wbvh_isa_mask();
    const tr_aabb b = scene_bounds(&v);
    for (int isa = 0; isa < TR_WBVH_ISA_COUNT; ++isa) {
        if (!(mask >> isa & 1u)) {
            continue;
        }
        tr_error err;
        CHECK(tr_wbvh_set_isa(isa, &err) == TR_OK, "%s: forcing %s: %s", name,
              tr_wbvh_isa_name(isa), err.msg);
        CHECK(strcmp(tr_wbvh_isa(), tr_wbvh_isa_name(isa)) == 0, "%s: forced %s, running %s", name,
              tr_wbvh_isa_name(isa), tr_wbvh_isa());
        tr_rng r;
        tr_rng_init(&r, 12345, (uint64_t)isa, 7);
        uint64_t hits = 0, misses = 0, hit_diff = 0, occ_diff = 0, dispatch_diff = 0;
        for (uint32_t k = 0; k < RAYS; ++k) {
            tr_ray ray = rand_ray(&r, &v, b);
            tr_hit hs, hi, hd;
            memset(&hs, 0, sizeof hs);
            memset(&hi, 0, sizeof hi);
            memset(&hd, 0, sizeof hd);
            int fs = tr_wbvh_trace_isa(TR_WBVH_ISA_SCALAR, v.wbvh, &ray, &hs, 0);
            int fi = tr_wbvh_trace_isa(isa, v.wbvh, &ray, &hi, 0);
            int os = tr_wbvh_trace_isa(TR_WBVH_ISA_SCALAR, v.wbvh, &ray, NULL, 1);
            int oi = tr_wbvh_trace_isa(isa, v.wbvh, &ray, NULL, 1);
            int fd = tr_intersect_scene(&v, &ray, &hd);
            int od = tr_occluded_scene(&v, &ray);
            hits += fs == 1;
            misses += fs == 0;
            int same =
                fs == fi && (fs != 1 || (same_bits(hs.t, hi.t) && hs.triangle == hi.triangle &&
                                         same_bits(hs.u, hi.u) && same_bits(hs.v, hi.v)));
            if (!same && hit_diff++ < 3) {
                fprintf(
                    stderr,
                    "  %s %s: ray %u: scalar %d t %a tri %u u %a v %a / %d t %a tri %u u %a v %a\n",
                    name, tr_wbvh_isa_name(isa), k, fs, (double)hs.t, hs.triangle, (double)hs.u,
                    (double)hs.v, fi, (double)hi.t, hi.triangle, (double)hi.u, (double)hi.v);
            }
            occ_diff += os != oi;
            dispatch_diff += fd != fi || od != oi ||
                             (fd == 1 && (!same_bits(hd.t, hi.t) || hd.triangle != hi.triangle));
        }
        CHECK(hit_diff == 0, "%s: %s: %llu of %u closest hits differ from the scalar code", name,
              tr_wbvh_isa_name(isa), (unsigned long long)hit_diff, RAYS);
        CHECK(occ_diff == 0, "%s: %s: %llu of %u occlusion answers differ from the scalar code",
              name, tr_wbvh_isa_name(isa), (unsigned long long)occ_diff, RAYS);
        CHECK(dispatch_diff == 0, "%s: %s forced: tr_intersect_scene differs on %llu rays", name,
              tr_wbvh_isa_name(isa), (unsigned long long)dispatch_diff);
        /* The ray set must exercise both answers, or the comparison proves little. */
        CHECK(hits > RAYS / 4 && misses > RAYS / 20, "%s: %llu hits and %llu misses of %u rays",
              name, (unsigned long long)hits, (unsigned long long)misses, RAYS);
    }
}

static void builtin_scene(const char *name) {
    tr_scene s = {0};
    tr_scene_init(&s);
    tr_error err;
    int ok = tr_scene_builtin(&s, name, 64, 48, &err) == TR_OK &&
             tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK;
    CHECK(ok, "%s: %s", name, err.msg);
    if (ok) {
        compare_isas(name, &s);
    }
    tr_scene_clear(&s);
}

/* Many overlapping boxes and icospheres at random places, turns and sizes: nodes with
 * all eight slots full, children whose boxes overlap, thin and flat boxes. */
static void random_shapes_scene(void) {
    tr_scene s = {0};
    tr_scene_init(&s);
    uint32_t mat = add_mat(&s, tr_material_diffuse(v3s(0.5f)));
    tr_rng r;
    tr_rng_init(&r, 99, 0, 0);
    for (int i = 0; i < 300; ++i) {
        tr_vec3 pos =
            v3(tr_rng_range(&r, -10, 10), tr_rng_range(&r, -10, 10), tr_rng_range(&r, -10, 10));
        tr_vec3 rot = v3(tr_rng_range(&r, 0, 6.3f), tr_rng_range(&r, 0, 6.3f),
                         i % 5 == 0 ? 0.0f : tr_rng_range(&r, 0, 6.3f));
        tr_vec3 scale = v3(tr_rng_range(&r, 0.05f, 3), tr_rng_range(&r, 0.05f, 3),
                           i % 7 == 0 ? 0.001f : tr_rng_range(&r, 0.05f, 3));
        add_shape(&s, i % 2 ? TR_SHAPE_BOX : TR_SHAPE_ICOSPHERE, mat, pos, rot, scale);
    }
    tr_error err;
    int ok = tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK;
    CHECK(ok, "random shapes: %s", err.msg);
    if (ok) {
        compare_isas("random shapes", &s);
    }
    tr_scene_clear(&s);
}

/* The TRAC0R_ISA rule on made-up CPUs: a usable request is honoured, anything else
 * (unset, unknown, or an ISA the mask lacks) gets the best of the mask. */
static void choose_rule(void) {
    const unsigned scalar = 1u << TR_WBVH_ISA_SCALAR, sse2 = 1u << TR_WBVH_ISA_SSE2,
                   avx2 = 1u << TR_WBVH_ISA_AVX2, avx512 = 1u << TR_WBVH_ISA_AVX512;
    const unsigned masks[] = {scalar, scalar | sse2, scalar | sse2 | avx2,
                              scalar | sse2 | avx2 | avx512};
    const int best[] = {TR_WBVH_ISA_SCALAR, TR_WBVH_ISA_SSE2, TR_WBVH_ISA_AVX2, TR_WBVH_ISA_AVX512};
    for (int m = 0; m < 4; ++m) {
        CHECK(tr_wbvh_isa_choose(NULL, masks[m]) == best[m], "unset, mask %#x: %d", masks[m],
              tr_wbvh_isa_choose(NULL, masks[m]));
        CHECK(tr_wbvh_isa_choose("avx3", masks[m]) == best[m], "unknown, mask %#x", masks[m]);
        CHECK(tr_wbvh_isa_choose("", masks[m]) == best[m], "empty, mask %#x", masks[m]);
        for (int isa = 0; isa < TR_WBVH_ISA_COUNT; ++isa) {
            int want = masks[m] >> isa & 1u ? isa : best[m];
            int got = tr_wbvh_isa_choose(tr_wbvh_isa_name(isa), masks[m]);
            CHECK(got == want, "TRAC0R_ISA=%s on mask %#x: %d, expected %d", tr_wbvh_isa_name(isa),
                  masks[m], got, want);
        }
    }
    for (int isa = 0; isa < TR_WBVH_ISA_COUNT; ++isa) {
        CHECK(tr_wbvh_isa_from_name(tr_wbvh_isa_name(isa)) == isa, "name of %d", isa);
    }
    CHECK(tr_wbvh_isa_from_name("AVX2") == -1 && tr_wbvh_isa_from_name(NULL) == -1,
          "names are exact");
    CHECK(tr_wbvh_isa_name(-1) == NULL && tr_wbvh_isa_name(TR_WBVH_ISA_COUNT) == NULL,
          "no name out of range");
}

/* The automatic choice on this CPU, before anything forces one. */
static void automatic_choice(void) {
    const unsigned mask = tr_wbvh_isa_mask();
    const char *isa = tr_wbvh_isa();
    CHECK(mask & 1u << TR_WBVH_ISA_SCALAR, "scalar is always usable");
    CHECK(strcmp(isa, tr_wbvh_isa_name(tr_wbvh_isa_choose(NULL, mask))) == 0,
          "chose %s, not the best of mask %#x", isa, mask);
#if defined(__x86_64__) || defined(__i386__)
    fprintf(stderr, "this file compiled with AVX2 enabled: %s; CPU AVX2: %d; chosen: %s\n",
#if defined(__AVX2__)
            "yes",
#else
            "no",
#endif
            __builtin_cpu_supports("avx2") != 0, isa);
    if (__builtin_cpu_supports("sse2")) {
        CHECK(mask & 1u << TR_WBVH_ISA_SSE2, "SSE2 CPU, but no SSE2 traversal");
    }
    if (__builtin_cpu_supports("avx2")) {
        CHECK(strcmp(isa, "avx2") == 0 || strcmp(isa, "avx512") == 0,
              "a CPU with AVX2 runs the %s traversal", isa);
    } else {
        CHECK(!(mask & 1u << TR_WBVH_ISA_AVX2), "AVX2 offered on a CPU without it");
    }
    if (!(__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl"))) {
        CHECK(!(mask & 1u << TR_WBVH_ISA_AVX512), "AVX-512 offered on a CPU without it");
    }
#endif
}

/* Forcing: out-of-range numbers and ISAs the CPU lacks fail and keep the choice. */
static void forcing(void) {
    const unsigned mask = tr_wbvh_isa_mask();
    tr_error err;
    CHECK(tr_wbvh_set_isa(TR_WBVH_ISA_SCALAR, &err) == TR_OK, "scalar: %s", err.msg);
    CHECK(tr_wbvh_set_isa(-1, &err) != TR_OK, "ISA -1 accepted");
    CHECK(tr_wbvh_set_isa(TR_WBVH_ISA_COUNT, &err) != TR_OK, "ISA %d accepted", TR_WBVH_ISA_COUNT);
    for (int isa = 0; isa < TR_WBVH_ISA_COUNT; ++isa) {
        if (!(mask >> isa & 1u)) {
            CHECK(tr_wbvh_set_isa(isa, &err) != TR_OK, "%s forced on a CPU without it",
                  tr_wbvh_isa_name(isa));
            CHECK(tr_wbvh_trace_isa(isa, NULL, NULL, NULL, 0) == -1, "%s traced",
                  tr_wbvh_isa_name(isa));
        }
    }
    CHECK(strcmp(tr_wbvh_isa(), "scalar") == 0, "a refused ISA changed the choice to %s",
          tr_wbvh_isa());
}

int main(void) {
    /* The automatic choice is what is tested first: a TRAC0R_ISA from outside would
     * override it. */
    unsetenv("TRAC0R_ISA");
    _Static_assert(sizeof(tr_wbvh_node) == 224, "one node layout for every ISA");
    automatic_choice();
    choose_rule();
    builtin_scene("cornell");
    builtin_scene("cornell-ico-5");
    random_shapes_scene();
    forcing();
    return check_finish("test_isa");
}
