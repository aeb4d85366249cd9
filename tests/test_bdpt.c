/* test_bdpt.c - the bdpt integrator (src/kernel/integrator_bdpt.h).
 *
 *  (a) MIS: for random paths (from real camera and light subpaths, in a box with a
 *      two-sided and a one-sided lamp, diffuse, GGX, smooth-shaded, mirror and glass
 *      surfaces), the power-heuristic weights of every strategy that can make the path sum
 *      to one. Each strategy's subpaths are rebuilt with the densities its random walks
 *      would store, and the weight the walks' own bookkeeping gives matches the rebuilt one.
 *  (b) Each strategy (s, t) alone, unweighted, estimates the same image: for paths of 2 and
 *      3 segments, every strategy's 8x8-region means agree with next-event estimation's
 *      (s = 1) within 5 standard errors (from per-frame region means, fixed seeds).
 *  (c) Light tracing alone (t = 1) reproduces rho / pi times Lambert's irradiance under a
 *      square lamp (as test_pt's one-bounce case); a one-sided lamp turned away gives 0.
 *  (d) Determinism: bit-identical films with 1, 2 and 3 threads (light tracing splats).
 *  (e) bdpt and pt agree (region means within 5 standard errors) on every scene file in
 *      scenes/, and so do vcm and pt on those with a sky or a sun (light subpaths start
 *      there too; sun-caustic.json with its sun widened, so that pt converges); a max
 *      depth beyond TR_MAX_DEPTH_BDPT is refused.
 *  (a') as (a) in an open room under an environment map and the sun, with an area lamp:
 *      light subpaths from all three, and camera subpaths closed at infinity (the
 *      escape into the sky or the sun, s = 0), every strategy among the sums.
 *  (a'') as (a) and (a') with a point light, a spot and a directional light added: light
 *      subpaths from them too, strategy 0 (hitting a delta light) left out of the sums.
 *  (j) bdpt and vcm agree with pt per region on the diffuse Cornell box under a point
 *      light, a spot and a directional light (each beside the lamp), and under a spot
 *      whose caustic through the glass sphere pt cannot find, bdpt finds more light than
 *      pt and vcm agrees with bdpt.
 *  vcm (src/kernel/integrator_vcm.h):
 *  (f) with merges among the strategies (eta > 0) the weights of (a)'s paths, the merge
 *      at the camera subpath's first non-delta vertex included, still sum to one; the
 *      merge's O(1) weight (tr_vcm_merge_weight) equals the full one where the camera
 *      vertex lies on the light vertex.
 *  (g) with the merge radius 0 vcm renders bdpt's image bit for bit; its images do not
 *      depend on the thread count; a malformed TRAC0R_VCM_RADIUS is refused.
 *  (h) vcm agrees with bdpt (region means within 5 standard errors) on a floor lit only
 *      through a mirror, where merges carry much of the image (scaling the merges by 1.2
 *      fails this) and the smooth irradiance keeps the radius's bias small.
 *  (i) where light subpaths start from the sky, a merge at a ceiling's corner takes a
 *      light vertex on the ceiling and not one on the wall's outer face (tr_vcm_facing),
 *      and vcm agrees with bdpt looking into a corner of window-room.json. */
#define _DEFAULT_SOURCE
#include "check.h"
#include "scene_util.h"
#include "kernel/integrator_bdpt.h"
#include "kernel/integrator_vcm.h"
#include "kernel/kernel.h"
#include "scene/scene_internal.h"
#include "trac0r/trac0r.h"

#include <dirent.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PI_D 3.14159265358979323846
#define NSIGMA 5.0

/* Adds a point light, a spot and a directional light to the scene being built (the MIS
 * sums over paths from punctual lights) where set. */
static int g_punctual;

static void add_punctual_lights(tr_scene *s) {
    tr_error err;
    tr_punctual l[3];
    memset(l, 0, sizeof l);
    l[0].type = TR_PUNCTUAL_POINT;
    l[0].pos = v3(0.2f, 0.6f, -0.3f);
    l[0].intensity = v3(2.0f, 1.8f, 1.5f);
    l[1].type = TR_PUNCTUAL_SPOT;
    l[1].pos = v3(-0.6f, 0.8f, 0.6f);
    l[1].dir = v3(0.3f, -1.0f, -0.2f);
    l[1].intensity = v3(4.0f, 4.0f, 3.0f);
    l[1].cos_outer = 0.7f;
    l[1].cos_inner = 0.85f;
    l[2].type = TR_PUNCTUAL_DIRECTIONAL;
    l[2].dir = v3(0.3f, -1.0f, 0.5f);
    l[2].intensity = v3(1.5f, 1.5f, 1.4f);
    for (int i = 0; i < 3; ++i) {
        CHECK(tr_scene_add_punctual(s, &l[i], &err) == TR_OK, "punctual light: %s", err.msg);
    }
}

/* A closed diffuse box [-1,1]^3 with a red block, a smooth-shaded diffuse sphere, a GGX
 * sphere, a two-sided and a one-sided lamp (facing down); `specular` adds a glass sphere
 * and a mirror. */
static void build_box(tr_scene *s, int specular, uint32_t w, uint32_t h) {
    tr_error err;
    tr_scene_init(s);
    uint32_t white = add_mat(s, tr_material_diffuse(v3(0.7f, 0.7f, 0.7f)));
    uint32_t red = add_mat(s, tr_material_diffuse(v3(0.7f, 0.15f, 0.1f)));
    tr_material lamp = tr_material_emitter(v3(1.0f, 0.9f, 0.7f), 8.0f);
    lamp.flags = TR_MATERIAL_TWO_SIDED;
    uint32_t l1 = add_mat(s, lamp);
    uint32_t l2 = add_mat(s, tr_material_emitter(v3(0.3f, 0.5f, 1.0f), 6.0f));
    uint32_t g = add_mat(s, tr_material_glossy(v3(0.9f, 0.8f, 0.6f), 0.4f));
    add_shape(s, TR_SHAPE_BOX, white, v3(0, 0, 0), v3(0, 0, 0), v3(2, 2, 2));
    add_shape(s, TR_SHAPE_BOX, red, v3(0.3f, -0.6f, 0.4f), v3(0, 0.5f, 0), v3(0.6f, 0.8f, 0.6f));
    add_shape(s, TR_SHAPE_PLANE, l1, v3(-0.3f, 0.9f, 0.2f), v3((float)PI_D, 0, 0),
              v3(0.6f, 1, 0.5f));
    add_shape(s, TR_SHAPE_PLANE, l2, v3(0.5f, 0.95f, -0.5f), v3((float)PI_D, 0, 0),
              v3(0.3f, 1, 0.3f));
    add_shape(s, TR_SHAPE_ICOSPHERE, g, v3(-0.4f, -0.6f, 0.1f), v3(0, 0, 0), v3s(0.35f));
    add_shape(s, TR_SHAPE_ICOSPHERE_SMOOTH, white, v3(0.6f, -0.1f, -0.2f), v3(0, 0, 0), v3s(0.2f));
    if (specular) {
        uint32_t glass = add_mat(s, tr_material_glass(v3(1.0f, 1.0f, 1.0f), 1.5f));
        uint32_t mirror = add_mat(s, tr_material_glossy(v3(0.9f, 0.9f, 0.9f), 0.0f));
        add_shape(s, TR_SHAPE_ICOSPHERE, glass, v3(-0.5f, -0.1f, 0.5f), v3(0, 0, 0), v3s(0.25f));
        add_shape(s, TR_SHAPE_PLANE, mirror, v3(0.0f, 0.0f, 0.98f), v3((float)PI_D / 2.0f, 0, 0),
                  v3(1.2f, 1, 1.2f));
    }
    if (g_punctual) {
        add_punctual_lights(s);
    }
    CHECK(tr_camera_make(&s->camera, v3(0.0f, 0.0f, -0.95f), v3(0.0f, -0.1f, 1.0f),
                         v3(0.0f, 1.0f, 0.0f), 80.0f, 0.001f, 100.0f, w, h, &err) == TR_OK,
          "camera: %s", err.msg);
    CHECK(tr_scene_commit(s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "commit: %s", err.msg);
}

/* (a) ---------------------------------------------------------------------------------- */

static int vtx_delta(const tr_bdpt_vertex *v) {
    return v->kind == TR_BDPT_SURFACE && tr_bsdf_is_delta(&v->m);
}

/* Whether the integrator tries strategy k (light vertices) on path P of n vertices. */
static int strategy_used(const tr_bdpt_vertex *P, int n, int k) {
    if (k >= n || (k == 1 && n == 2) || (k == 0 && tr_bdpt_delta_light(&P[0]))) {
        return 0; /* ... and no camera subpath hits a delta light */
    }
    if (vtx_delta(&P[k]) || (k >= 1 && vtx_delta(&P[k - 1]))) {
        return 0;
    }
    return 1;
}

/* The weight of strategy k for path P (P[0] on an emitter, P[n-1] the pinhole), with the
 * subpaths rebuilt as the random walks would have stored them. */
static float rebuilt_weight_vm(const tr_scene_view *v, const tr_camera *cam,
                               const tr_bdpt_vertex *P, int n, int k, float eta, int merge,
                               tr_bdpt_vertex *lv_out) {
    tr_bdpt_vertex L[2 * TR_BDPT_MAX_VERTS], C[2 * TR_BDPT_MAX_VERTS], PL[2 * TR_BDPT_MAX_VERTS];
    for (int i = 0; i < n; ++i) {
        PL[i] = P[i];
        PL[i].kind =
            i == 0 ? (P[0].kind == TR_BDPT_INFINITE || tr_bdpt_delta_light(&P[0]) ? P[0].kind
                                                                                  : TR_BDPT_LIGHT)
                   : (i == n - 1 ? TR_BDPT_CAMERA : TR_BDPT_SURFACE);
        PL[i].delta = vtx_delta(&PL[i]);
    }
    /* Light side densities of P[i] (drawn from P[i-1]) and camera side (from P[i+1]). */
    float fl[2 * TR_BDPT_MAX_VERTS], fc[2 * TR_BDPT_MAX_VERTS];
    for (int i = 0; i < n; ++i) {
        fl[i] = i == 0 ? tr_bdpt_origin_pdf(v, &PL[0])
                       : tr_bdpt_pdf(cam, &PL[i - 1], i >= 2 ? &PL[i - 2] : NULL, &PL[i]);
        fc[i] = i == n - 1
                    ? 1.0f
                    : tr_bdpt_pdf(cam, &PL[i + 1], i + 2 <= n - 1 ? &PL[i + 2] : NULL, &PL[i]);
    }
    for (int i = 0; i < k; ++i) {
        L[i] = PL[i];
        L[i].pdf_fwd = fl[i];
        L[i].pdf_rev = fc[i];
    }
    if (k >= 1 && n >= 2) {
        L[0].pdf_nee = tr_bdpt_nee_pdf(v, &PL[0], &PL[1]);
    }
    for (int j = 0; j < n - k; ++j) {
        int i = n - 1 - j;
        C[j] = PL[i];
        if (i == 0 && PL[0].kind == TR_BDPT_LIGHT) {
            C[j].kind = TR_BDPT_SURFACE; /* the camera subpath found the emitter */
        }
        C[j].pdf_fwd = fc[i];
        C[j].pdf_rev = fl[i];
    }
    if (lv_out) {
        /* The light subpath as a walk that went on to P[k] would store it. */
        for (int i = 0; i <= k && i < n; ++i) {
            lv_out[i] = PL[i];
            lv_out[i].pdf_fwd = fl[i];
            lv_out[i].pdf_rev = fc[i];
            lv_out[i].wo =
                i == 0 ? PL[0].wo
                       : (tr_bdpt_far(&PL[i - 1]) ? PL[i - 1].wo
                                                  : v3_normalize(v3_sub(PL[i - 1].p, PL[i].p)));
        }
        lv_out[0].pdf_nee = tr_bdpt_nee_pdf(v, &PL[0], &PL[1]);
        lv_out[k].beta = v3s(1.0f);
    }
    return tr_bdpt_mis_weight_vm(v, cam, L, k, k == 1 && !merge ? &L[0] : NULL, C, n - k, eta,
                                 merge);
}

static float rebuilt_weight(const tr_scene_view *v, const tr_camera *cam, const tr_bdpt_vertex *P,
                            int n, int k) {
    return rebuilt_weight_vm(v, cam, P, n, k, 0.0f, 0, NULL);
}

/* The vertex vcm merges at on path P: the first non-delta one from the camera; 0 where
 * there is none past the light's origin. */
static int merge_vertex(const tr_bdpt_vertex *P, int n) {
    int v = n - 2;
    while (v >= 1 && vtx_delta(&P[v])) {
        --v;
    }
    return v;
}

/* The MIS sums of (a) and (f) over the paths of scene s, from its light subpaths (which
 * start on the sky and the sun too where it has them) and, with `sky`, the camera
 * subpaths closed by a vertex at infinity: the environment in a random direction, or the
 * sun's centre. */
static void mis_paths(tr_scene *s, const char *what, int sky);

static void mis_sum(void) {
    tr_scene s = {0};
    build_box(&s, 1, 8, 8);
    mis_paths(&s, "box", 0);
    tr_scene_clear(&s);
}

/* An open room under a sky (an environment map) and the sun, with an area lamp: the floor,
 * two walls, a block, a GGX sphere, a smooth-shaded sphere, a glass sphere and a mirror. */
static void build_sky_room(tr_scene *s, uint32_t w, uint32_t h) {
    tr_error err;
    tr_scene_init(s);
    uint32_t white = add_mat(s, tr_material_diffuse(v3(0.7f, 0.7f, 0.7f)));
    uint32_t red = add_mat(s, tr_material_diffuse(v3(0.7f, 0.15f, 0.1f)));
    uint32_t lamp = add_mat(s, tr_material_emitter(v3(1.0f, 0.9f, 0.7f), 3.0f));
    uint32_t g = add_mat(s, tr_material_glossy(v3(0.9f, 0.8f, 0.6f), 0.4f));
    uint32_t glass = add_mat(s, tr_material_glass(v3(1.0f, 1.0f, 1.0f), 1.5f));
    uint32_t mirror = add_mat(s, tr_material_glossy(v3(0.9f, 0.9f, 0.9f), 0.0f));
    add_shape(s, TR_SHAPE_PLANE, white, v3(0, -1, 0), v3(0, 0, 0), v3(4, 1, 4));
    add_shape(s, TR_SHAPE_PLANE, white, v3(0, 0, 1), v3(-(float)PI_D / 2.0f, 0, 0), v3(4, 1, 2));
    add_shape(s, TR_SHAPE_PLANE, mirror, v3(-1.2f, 0, 0), v3(0, 0, -(float)PI_D / 2.0f),
              v3(2, 1, 2));
    add_shape(s, TR_SHAPE_BOX, red, v3(0.3f, -0.6f, 0.4f), v3(0, 0.5f, 0), v3(0.6f, 0.8f, 0.6f));
    add_shape(s, TR_SHAPE_PLANE, lamp, v3(0.6f, 0.9f, 0.2f), v3((float)PI_D, 0, 0),
              v3(0.4f, 1, 0.4f));
    add_shape(s, TR_SHAPE_ICOSPHERE, g, v3(-0.4f, -0.6f, 0.1f), v3(0, 0, 0), v3s(0.35f));
    add_shape(s, TR_SHAPE_ICOSPHERE_SMOOTH, white, v3(0.6f, -0.1f, -0.2f), v3(0, 0, 0), v3s(0.2f));
    add_shape(s, TR_SHAPE_ICOSPHERE, glass, v3(-0.5f, -0.5f, -0.4f), v3(0, 0, 0), v3s(0.3f));
    /* A small map with a bright patch, so that its CDF is far from uniform. */
    float map[8 * 4 * 3];
    for (int i = 0; i < 8 * 4; ++i) {
        const float b = i == 9 ? 20.0f : 0.2f + 0.1f * (float)(i % 5);
        map[3 * i] = b;
        map[3 * i + 1] = 0.8f * b;
        map[3 * i + 2] = 0.6f * b + 0.1f;
    }
    CHECK(tr_scene_set_environment(s, v3(0.6f, 0.8f, 1.0f), 1.0f, 0.3f, map, 8, 4, &err) == TR_OK,
          "environment: %s", err.msg);
    CHECK(tr_scene_set_sun(s, v3(-0.4f, 1.0f, -0.6f), 3.0f, v3(4.0f, 3.8f, 3.4f), &err) == TR_OK,
          "sun: %s", err.msg);
    if (g_punctual) {
        add_punctual_lights(s);
    }
    CHECK(tr_camera_make(&s->camera, v3(0.0f, 0.2f, -2.5f), v3(0.0f, -0.2f, 1.0f),
                         v3(0.0f, 1.0f, 0.0f), 70.0f, 0.001f, 100.0f, w, h, &err) == TR_OK,
          "camera: %s", err.msg);
    CHECK(tr_scene_commit(s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "commit: %s", err.msg);
}

static void mis_sum_sky(void) {
    tr_scene s = {0};
    build_sky_room(&s, 8, 8);
    mis_paths(&s, "sky room", 1);
    tr_scene_clear(&s);
}

/* The same sums where light subpaths start from a point light, a spot and a directional
 * light too: in the box (beside its lamps) and in the sky room (beside the sky, the sun
 * and the lamp). Strategy 0 cannot make their paths; the camera side's light sample of
 * them (s = 1) and the connections and merges of their subpaths share the weight. */
static void mis_sum_punctual(void) {
    tr_scene s = {0};
    g_punctual = 1;
    build_box(&s, 1, 8, 8);
    mis_paths(&s, "box and punctual lights", 0);
    tr_scene_clear(&s);
    build_sky_room(&s, 8, 8);
    mis_paths(&s, "sky room and punctual lights", 1);
    tr_scene_clear(&s);
    g_punctual = 0;
}

static void mis_paths(tr_scene *sp, const char *what, int sky) {
    tr_scene_view v = tr_scene_view_of(sp);
    const tr_camera *cam = &sp->camera;
    const int depth = 8;
    int paths = 0, bad = 0, bookkeeping_bad = 0, with_delta = 0;
    int merged = 0, bad_vm = 0, fast_bad = 0, sky_paths = 0, closed = 0;
    int punct_paths = 0, dir_paths = 0;
    double worst = 0.0, worst_vm = 0.0;
    for (uint32_t k = 0; k < 3000; ++k) {
        tr_sampler smp = tr_sampler_make(77, k % 64u, k);
        tr_bdpt_vertex cv[TR_BDPT_MAX_VERTS], lv[TR_BDPT_MAX_VERTS];
        uint32_t rays = 0;
        tr_bdpt_escape esc;
        int nc = tr_bdpt_camera_subpath(&v, cam, (float)(k % 8u), (float)((k / 8u) % 8u), depth,
                                        &smp, cv, &rays, NULL, &esc);
        int nl = tr_bdpt_light_subpath(&v, depth, &smp, lv, &rays);
        sky_paths += nl >= 2 && lv[0].kind == TR_BDPT_INFINITE;
        punct_paths += nl >= 2 && tr_bdpt_delta_light(&lv[0]);
        dir_paths += nl >= 2 && lv[0].kind == TR_BDPT_DIRECTIONAL;
        if (sky && nc >= 2) {
            /* Camera subpaths closed at infinity: every prefix, the environment in a
             * direction from the sampler or the sun's centre. */
            for (int t = 2; t <= nc && t <= depth; ++t) {
                for (uint32_t which = TR_BDPT_SKY_ENV; which <= TR_BDPT_SKY_SUN; ++which) {
                    tr_bdpt_vertex P[2 * TR_BDPT_MAX_VERTS];
                    const int n = t + 1;
                    for (int i = 1; i < n; ++i) {
                        P[i] = cv[n - 1 - i];
                    }
                    float u1, u2, pdf;
                    tr_sampler_2d(&smp, 900u + (uint32_t)t, &u1, &u2);
                    P[0] = cv[t - 1];
                    P[0].kind = TR_BDPT_INFINITE;
                    P[0].tri = which;
                    P[0].delta = 0;
                    P[0].pdf_pos = tr_bdpt_disc_pdf(&v);
                    if (which == TR_BDPT_SKY_SUN) {
                        P[0].wo = v.sun[0].dir;
                    } else {
                        tr_env_sample(&v, u1, u2, &P[0].wo, &pdf);
                    }
                    if (vtx_delta(&P[1]) || P[1].m.type == TR_MATERIAL_EMITTER) {
                        continue;
                    }
                    double sum = 0.0, sum_vm = 0.0;
                    const float eta = 0.37f * (float)(1 + (k % 7u));
                    for (int kk = 0; kk < n; ++kk) {
                        if (strategy_used(P, n, kk)) {
                            sum += rebuilt_weight(&v, cam, P, n, kk);
                            sum_vm += rebuilt_weight_vm(&v, cam, P, n, kk, eta, 0, NULL);
                        }
                    }
                    const int mv = merge_vertex(P, n);
                    if (mv >= 1) {
                        sum_vm += rebuilt_weight_vm(&v, cam, P, n, mv, eta, 1, NULL);
                    }
                    const double dev = fmax(fabs(sum - 1.0), fabs(sum_vm - 1.0));
                    worst = dev > worst ? dev : worst;
                    bad += !(dev <= 2e-3);
                    ++closed;
                }
            }
        }
        for (int t = 1; t <= nc; ++t) {
            for (int ns = 2; ns <= nl; ++ns) {
                const int n = ns + t;
                if (n - 1 > depth || vtx_delta(&lv[ns - 1]) || vtx_delta(&cv[t - 1]) ||
                    lv[ns - 1].m.type == TR_MATERIAL_EMITTER ||
                    cv[t - 1].m.type == TR_MATERIAL_EMITTER) {
                    continue;
                }
                tr_bdpt_vertex P[2 * TR_BDPT_MAX_VERTS];
                int has_delta = 0;
                for (int i = 0; i < n; ++i) {
                    P[i] = i < ns ? lv[i] : cv[n - 1 - i];
                    has_delta |= vtx_delta(&P[i]);
                }
                double sum = 0.0;
                for (int kk = 0; kk < n; ++kk) {
                    if (strategy_used(P, n, kk)) {
                        float w = rebuilt_weight(&v, cam, P, n, kk);
                        sum += w;
                    }
                }
                /* (f) With merging among the strategies: the same sum, the merge included,
                 * and the merge's O(1) weight where the camera vertex lies on y. */
                const float eta = 0.37f * (float)(1 + (k % 7u));
                const int mv = merge_vertex(P, n);
                double sum_vm = 0.0;
                for (int kk = 0; kk < n; ++kk) {
                    if (strategy_used(P, n, kk)) {
                        sum_vm += rebuilt_weight_vm(&v, cam, P, n, kk, eta, 0, NULL);
                    }
                }
                if (mv >= 1) {
                    tr_bdpt_vertex ly[2 * TR_BDPT_MAX_VERTS], C[2 * TR_BDPT_MAX_VERTS];
                    const float wm = rebuilt_weight_vm(&v, cam, P, n, mv, eta, 1, ly);
                    sum_vm += wm;
                    ++merged;
                    /* The camera subpath up to P[mv], as its walk stores it. */
                    for (int j = 0; j < n - mv; ++j) {
                        const int i = n - 1 - j;
                        C[j] = P[i];
                        C[j].kind = i == n - 1 ? TR_BDPT_CAMERA : TR_BDPT_SURFACE;
                        C[j].delta = vtx_delta(&P[i]);
                        C[j].wo = i < n - 1 ? v3_normalize(v3_sub(P[i + 1].p, P[i].p)) : v3s(0.0f);
                        C[j].pdf_fwd = i == n - 1
                                           ? 1.0f
                                           : tr_bdpt_pdf(cam, &P[i + 1],
                                                         i + 2 <= n - 1 ? &P[i + 2] : NULL, &P[i]);
                    }
                    C[0].kind = TR_BDPT_CAMERA;
                    float a, b, g;
                    tr_vcm_light_sums(ly, mv, &a, &b, &g);
                    const float wf = tr_vcm_merge_weight(&C[n - mv - 1], n - mv, ly[mv].wo,
                                                         ly[mv].pdf_fwd, a, b, g, eta);
                    fast_bad += !(fabsf(wf - wm) <= 1e-3f * fmaxf(wm, 1e-3f));
                }
                const double dev_vm = fabs(sum_vm - 1.0);
                worst_vm = dev_vm > worst_vm ? dev_vm : worst_vm;
                bad_vm += !(dev_vm <= 2e-3);
                /* The walks' stored densities give the weight the rebuilt subpaths give. */
                float w_walk = tr_bdpt_mis_weight(&v, cam, lv, ns, NULL, cv, t);
                float w_rebuilt = rebuilt_weight(&v, cam, P, n, ns);
                bookkeeping_bad += !(fabsf(w_walk - w_rebuilt) <= 1e-3f * fmaxf(1.0f, w_rebuilt));
                double dev = fabs(sum - 1.0);
                worst = dev > worst ? dev : worst;
                bad += !(dev <= 2e-3);
                ++paths;
                with_delta += has_delta;
            }
        }
    }
    CHECK(paths > 2000 && with_delta > 100 && bad == 0,
          "MIS weights (%s): %d of %d paths (%d through mirror or glass) do not sum to 1 (worst "
          "%.2e)",
          what, bad, paths, with_delta, worst);
    CHECK(!sky || (sky_paths > 300 && closed > 1000),
          "%s: %d light subpaths from the sky, %d camera subpaths closed at infinity", what,
          sky_paths, closed);
    CHECK(!g_punctual || (punct_paths > 150 && dir_paths > 50),
          "%s: %d light subpaths from punctual lights (%d directional)", what, punct_paths,
          dir_paths);
    CHECK(bookkeeping_bad == 0, "%d of %d paths: the walks' densities give another weight",
          bookkeeping_bad, paths);
    printf("MIS (%s): %d paths (%d through delta vertices, %d light subpaths from the sky, %d "
           "from punctual lights, %d closed at infinity), worst |sum - 1| = %.2e\n",
           what, paths, with_delta, sky_paths, punct_paths, closed, worst);
    CHECK(merged > 2000 && bad_vm == 0,
          "MIS with merges: %d of %d paths (%d with a merge) do not sum to 1 (worst %.2e)", bad_vm,
          paths, merged, worst_vm);
    CHECK(fast_bad == 0, "%d of %d merges: tr_vcm_merge_weight differs from the full weight",
          fast_bad, merged);
    printf("MIS with merges (%s): %d paths with a merge, worst |sum - 1| = %.2e\n", what, merged,
           worst_vm);
}

/* Region statistics ---------------------------------------------------------------------- */

enum { RW = 16, RH = 16, RS = 8, NR = (RW / RS) * (RH / RS) };

typedef struct region_stats {
    double mean[NR][3];
    double se[NR][3];
} region_stats;

typedef struct region_acc {
    double s1[NR][3], s2[NR][3];
    int frames;
} region_acc;

static void acc_frame(region_acc *a, const double *img) {
    double reg[NR][3] = {{0}};
    for (int y = 0; y < RH; ++y) {
        for (int x = 0; x < RW; ++x) {
            int r = (y / RS) * (RW / RS) + x / RS;
            for (int c = 0; c < 3; ++c) {
                reg[r][c] += img[3 * (y * RW + x) + c] / (RS * RS);
            }
        }
    }
    for (int r = 0; r < NR; ++r) {
        for (int c = 0; c < 3; ++c) {
            a->s1[r][c] += reg[r][c];
            a->s2[r][c] += reg[r][c] * reg[r][c];
        }
    }
    a->frames++;
}

static region_stats acc_stats(const region_acc *a) {
    region_stats st;
    const double f = a->frames;
    for (int r = 0; r < NR; ++r) {
        for (int c = 0; c < 3; ++c) {
            double m = a->s1[r][c] / f;
            double var = fmax(0.0, a->s2[r][c] / f - m * m) * f / (f - 1.0);
            st.mean[r][c] = m;
            st.se[r][c] = sqrt(var / f);
        }
    }
    return st;
}

/* Region means of a and b agree within NSIGMA standard errors; returns the worst z. */
static double compare_regions(const char *what, const region_stats *a, const region_stats *b) {
    int bad = 0;
    double worst = 0.0;
    for (int r = 0; r < NR; ++r) {
        for (int c = 0; c < 3; ++c) {
            double se = sqrt(a->se[r][c] * a->se[r][c] + b->se[r][c] * b->se[r][c]);
            double d = fabs(a->mean[r][c] - b->mean[r][c]);
            double z = se > 0.0 ? d / se : (d > 0.0 ? 1e9 : 0.0);
            worst = z > worst ? z : worst;
            bad += !(z <= NSIGMA);
        }
    }
    CHECK(bad == 0, "%s: %d of %d region means differ by more than %.0f sigma (worst %.2f)", what,
          bad, 3 * NR, NSIGMA, worst);
    return worst;
}

/* One frame (one sample per pixel, sample index `frame`) of the whole RW x RH image with
 * strategy selection sel, single-threaded, splats folded in (scale 1: every pixel traced). */
static void bdpt_frame(const tr_scene_view *v, const tr_camera *cam, int depth, uint64_t seed,
                       uint32_t frame, tr_bdpt_select sel, double *img, int64_t *splat) {
    memset(splat, 0, sizeof(int64_t) * 3 * RW * RH);
    tr_bdpt_splat sp = {splat, 0, 0, RW, RH};
    for (uint32_t y = 0; y < RH; ++y) {
        for (uint32_t x = 0; x < RW; ++x) {
            tr_sampler smp = tr_sampler_make(seed, (uint64_t)y * RW + x, frame);
            uint32_t rays = 0;
            tr_vec3 c =
                tr_trace_bdpt(v, cam, (float)x, (float)y, depth, &smp, &sp, sel, &rays, NULL);
            img[3 * (y * RW + x)] = c.x;
            img[3 * (y * RW + x) + 1] = c.y;
            img[3 * (y * RW + x) + 2] = c.z;
        }
    }
    for (int i = 0; i < 3 * RW * RH; ++i) {
        img[i] += (double)splat[i] / TR_BDPT_SPLAT_ONE;
    }
}

/* (b) ---------------------------------------------------------------------------------- */

static void strategies(void) {
    tr_scene s = {0};
    build_box(&s, 0, RW, RH);
    tr_scene_view v = tr_scene_view_of(&s);
    static double img[3 * RW * RH];
    static int64_t splat[3 * RW * RH];
    const int frames = 160;
    for (int n = 3; n <= 4; ++n) {
        static region_acc acc[5];
        memset(acc, 0, sizeof acc);
        for (int k = 0; k < n; ++k) {
            if (k == 1 && n == 2) {
                continue;
            }
            tr_bdpt_select sel = {k, n - k};
            for (int f = 0; f < frames; ++f) {
                bdpt_frame(&v, &s.camera, n - 1, 0x5eedULL + (uint64_t)k, (uint32_t)f, sel, img,
                           splat);
                acc_frame(&acc[k], img);
            }
        }
        region_stats ref = acc_stats(&acc[1]);
        int lit = 0;
        for (int r = 0; r < NR; ++r) {
            lit += ref.mean[r][0] > 0.0 && ref.mean[r][2] > 0.0;
        }
        CHECK(lit == NR, "paths of %d vertices: only %d of %d regions lit", n, lit, NR);
        for (int k = 0; k < n; ++k) {
            if (k == 1) {
                continue;
            }
            char what[64];
            snprintf(what, sizeof what, "strategy (%d, %d) vs (1, %d)", k, n - k, n - 1);
            region_stats st = acc_stats(&acc[k]);
            double z = compare_regions(what, &st, &ref);
            printf("%s: worst %.2f sigma\n", what, z);
        }
    }
    tr_scene_clear(&s);
}

/* (c) ---------------------------------------------------------------------------------- */

static void light_tracing(void) {
    const double rho = 0.6, L = 5.0, hs = 0.3, h = 0.8;
    const double vtx[4][3] = {{-hs, h, -hs}, {hs, h, -hs}, {hs, h, hs}, {-hs, h, hs}};
    static double img[3 * RW * RH];
    static int64_t splat[3 * RW * RH];
    /* 0: lamp faces down; 1: one-sided, faces up; 2: two-sided, faces up. */
    for (int variant = 0; variant < 3; ++variant) {
        tr_scene s = {0};
        tr_scene_init(&s);
        tr_error err;
        uint32_t floor_m = add_mat(&s, tr_material_diffuse(v3s((float)rho)));
        tr_material lm = tr_material_emitter(v3s(1.0f), (float)L);
        lm.flags = variant == 2 ? TR_MATERIAL_TWO_SIDED : 0u;
        uint32_t lamp = add_mat(&s, lm);
        add_shape(&s, TR_SHAPE_PLANE, floor_m, v3(0, 0, 0), v3(0, 0, 0), v3(4.0f, 1, 4.0f));
        add_shape(&s, TR_SHAPE_PLANE, lamp, v3(0, (float)h, 0),
                  v3(variant == 0 ? (float)PI_D : 0.0f, 0, 0),
                  v3(2.0f * (float)hs, 1, 2.0f * (float)hs));
        /* Looking down at the floor from beside the lamp, with a wide lens: the camera's
         * importance varies by a third across the image. */
        CHECK(tr_camera_make(&s.camera, v3(1.2f, 0.6f, -1.0f), v3(-1.0f, -0.6f, 0.8f), v3(0, 1, 0),
                             60.0f, 0.001f, 100.0f, RW, RH, &err) == TR_OK,
              "camera: %s", err.msg);
        CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "commit: %s", err.msg);
        tr_scene_view v = tr_scene_view_of(&s);
        /* The expected image: rho / pi E at 4x4 points inside each pixel where the
         * camera ray meets the floor (y = 0). */
        static double expect[3 * RW * RH];
        for (uint32_t y = 0; y < RH; ++y) {
            for (uint32_t x = 0; x < RW; ++x) {
                double e = 0.0;
                for (int j = 0; j < 16; ++j) {
                    tr_ray r =
                        tr_camera_ray(&s.camera, (float)x, (float)y, ((float)(j % 4) + 0.5f) / 4.0f,
                                      ((float)(j / 4) + 0.5f) / 4.0f);
                    double t = -r.origin.y / r.dir.y;
                    double p[3] = {r.origin.x + t * r.dir.x, 0.0, r.origin.z + t * r.dir.z};
                    int on_floor = t > 0.0 && fabs(p[0]) < 2.0 && fabs(p[2]) < 2.0;
                    e += on_floor ? rho / PI_D * lambert_irradiance(vtx, 4, p, L) / 16.0 : 0.0;
                }
                expect[3 * (y * RW + x)] = variant == 1 ? 0.0 : e;
            }
        }
        region_acc acc;
        memset(&acc, 0, sizeof acc);
        tr_bdpt_select sel = {2, 1};
        const int frames = variant == 1 ? 8 : 400;
        int64_t nonzero = 0;
        for (int f = 0; f < frames; ++f) {
            bdpt_frame(&v, &s.camera, 2, 0x1a9ULL, (uint32_t)f, sel, img, splat);
            for (int i = 0; i < RW * RH; ++i) {
                nonzero += img[3 * i] != 0.0;
            }
            acc_frame(&acc, img);
        }
        region_stats got = acc_stats(&acc);
        if (variant == 1) {
            CHECK(nonzero == 0, "one-sided lamp facing away: %lld pixel samples lit",
                  (long long)nonzero);
        } else {
            region_acc ea;
            memset(&ea, 0, sizeof ea);
            acc_frame(&ea, expect);
            acc_frame(&ea, expect);
            for (int r = 0; r < NR; ++r) {
                double m = ea.s1[r][0] / 2.0;
                double d = fabs(got.mean[r][0] - m);
                CHECK(m > 0.0 && d <= NSIGMA * got.se[r][0] && got.se[r][0] < 0.03 * m,
                      "lamp variant %d, region %d: light tracing %.5f +- %.5f vs rho/pi E = %.5f",
                      variant, r, got.mean[r][0], got.se[r][0], m);
            }
        }
        tr_scene_clear(&s);
    }
}

/* (d) ---------------------------------------------------------------------------------- */

static void determinism(int integrator) {
    tr_scene s = {0};
    build_box(&s, 1, 24, 20);
    tr_error err;
    tr_film films[3];
    for (int i = 0; i < 3; ++i) {
        CHECK(tr_film_init(&films[i], 24, 20, &err) == TR_OK, "film: %s", err.msg);
        tr_render_config cfg = tr_render_config_default();
        cfg.integrator = integrator;
        cfg.seed = 99;
        cfg.threads = i + 1;
        cfg.tile = 4; /* many tiles, so threads interleave their splats */
        for (uint32_t f = 0; f < 3; ++f) {
            CHECK(tr_render_frame(&s, &s.camera, &cfg, &films[i], f, NULL, &err) == TR_OK,
                  "render: %s", err.msg);
        }
    }
    const size_t n = 3u * 24u * 20u;
    double total = 0.0;
    for (size_t k = 0; k < n; ++k) {
        total += films[0].sum[k];
    }
    CHECK(total > 0.0, "the film is black");
    for (int i = 1; i < 3; ++i) {
        CHECK(memcmp(films[0].sum, films[i].sum, n * sizeof(float)) == 0,
              "%s with %d threads differs from 1 thread", tr_integrator_name(integrator), i + 1);
        tr_film_free(&films[i]);
    }
    tr_film_free(&films[0]);
    tr_scene_clear(&s);
}

/* (g) ---------------------------------------------------------------------------------- */

/* Films of `frames` one-sample frames of the box with glass and mirror. */
static int render_box(tr_scene *s, int integrator, uint32_t frames, tr_film *film, tr_error *err) {
    CHECK(tr_film_init(film, 24, 20, err) == TR_OK, "film: %s", err->msg);
    tr_render_config cfg = tr_render_config_default();
    cfg.integrator = integrator;
    cfg.seed = 5;
    for (uint32_t f = 0; f < frames; ++f) {
        if (tr_render_frame(s, &s->camera, &cfg, film, f, NULL, err) != TR_OK) {
            return err->code;
        }
    }
    return TR_OK;
}

static int cancel_now(void *user) {
    (void)user;
    return 1;
}

static void vcm_radius(void) {
    tr_scene s = {0};
    build_box(&s, 1, 24, 20);
    tr_error err;
    tr_film a, b, c;
    const size_t n = 3u * 24u * 20u;
    CHECK(render_box(&s, TR_INTEGRATOR_BDPT, 3, &a, &err) == TR_OK, "bdpt: %s", err.msg);
    setenv("TRAC0R_VCM_RADIUS", "0", 1);
    CHECK(render_box(&s, TR_INTEGRATOR_VCM, 3, &b, &err) == TR_OK, "vcm, radius 0: %s", err.msg);
    CHECK(memcmp(a.sum, b.sum, n * sizeof(float)) == 0, "vcm with radius 0 differs from bdpt");
    unsetenv("TRAC0R_VCM_RADIUS");
    CHECK(render_box(&s, TR_INTEGRATOR_VCM, 3, &c, &err) == TR_OK, "vcm: %s", err.msg);
    CHECK(memcmp(a.sum, c.sum, n * sizeof(float)) != 0, "vcm's merges changed nothing");
    tr_film_free(&a);
    tr_film_free(&b);
    tr_film_free(&c);
    const char *bad[] = {"x", "-1", "1001", "2px", "nan", ""};
    for (size_t i = 0; i < sizeof bad / sizeof *bad; ++i) {
        setenv("TRAC0R_VCM_RADIUS", bad[i], 1);
        const int rc = render_box(&s, TR_INTEGRATOR_VCM, 1, &a, &err);
        /* The empty value is unset: the default. */
        CHECK(bad[i][0] ? rc == TR_STATUS_INVALID_ARGUMENT : rc == TR_OK,
              "TRAC0R_VCM_RADIUS=\"%s\": status %d", bad[i], rc);
        tr_film_free(&a);
    }
    unsetenv("TRAC0R_VCM_RADIUS");
    /* A cancelled frame stops with TR_STATUS_CANCELLED (the viewer's moving camera). */
    CHECK(tr_film_init(&a, 24, 20, &err) == TR_OK, "film: %s", err.msg);
    tr_render_config cfg = tr_render_config_default();
    cfg.integrator = TR_INTEGRATOR_VCM;
    cfg.cancel = cancel_now;
    CHECK(tr_render_frame(&s, &s.camera, &cfg, &a, 0, NULL, &err) == TR_ERR &&
              err.code == TR_STATUS_CANCELLED,
          "a cancelled vcm frame: status %d", err.code);
    tr_film_free(&a);
    tr_scene_clear(&s);
}

/* (h) ---------------------------------------------------------------------------------- */

static int run(const tr_scene *s, const tr_camera *cam, int integrator, int depth, int frames,
               uint64_t seed, region_stats *out, tr_error *err);

/* A floor lit only through a mirror: a lamp facing up under a mirror facing down, the
 * camera between them looking down. Every path is light -> mirror -> floor -> camera,
 * which only the camera hitting the lamp, light tracing and merges make, so the merges
 * carry much of the image; the floor's irradiance (a mirrored lamp) is smooth, so the
 * radius used (0.3 units on the floor) brings little bias. */
static void build_caustic_floor(tr_scene *s) {
    tr_error err;
    tr_scene_init(s);
    uint32_t white = add_mat(s, tr_material_diffuse(v3(0.8f, 0.8f, 0.8f)));
    uint32_t mirror = add_mat(s, tr_material_glossy(v3(0.9f, 0.9f, 0.9f), 0.0f));
    uint32_t lamp = add_mat(s, tr_material_emitter(v3(1.0f, 0.9f, 0.8f), 30.0f));
    add_shape(s, TR_SHAPE_PLANE, white, v3(0.0f, -1.0f, 0.0f), v3(0, 0, 0), v3(6, 1, 6));
    add_shape(s, TR_SHAPE_PLANE, mirror, v3(0.0f, 1.0f, 0.0f), v3((float)PI_D, 0, 0), v3(6, 1, 6));
    add_shape(s, TR_SHAPE_PLANE, lamp, v3(0.6f, 0.4f, 0.0f), v3(0, 0, 0), v3(0.4f, 1, 0.4f));
    CHECK(tr_camera_make(&s->camera, v3(0.0f, 0.2f, 0.0f), v3(0.0f, -1.0f, 0.0f),
                         v3(0.0f, 0.0f, 1.0f), 60.0f, 0.001f, 100.0f, RW, RH, &err) == TR_OK,
          "camera: %s", err.msg);
    CHECK(tr_scene_commit(s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "commit: %s", err.msg);
}

static void vcm_agrees(void) {
    tr_scene s = {0};
    build_caustic_floor(&s);
    tr_error err;
    static region_stats a, b;
    setenv("TRAC0R_VCM_RADIUS", "0.5", 1);
    CHECK(run(&s, &s.camera, TR_INTEGRATOR_VCM, 6, 384, 0xc3ULL, &b, &err) == TR_OK, "vcm: %s",
          err.msg);
    unsetenv("TRAC0R_VCM_RADIUS");
    CHECK(run(&s, &s.camera, TR_INTEGRATOR_BDPT, 6, 384, 0xb1ULL, &a, &err) == TR_OK, "bdpt: %s",
          err.msg);
    printf("floor lit through a mirror: worst |bdpt - vcm| = %.2f sigma\n",
           compare_regions("vcm vs bdpt", &a, &b));
    tr_scene_clear(&s);
}

/* (e) ---------------------------------------------------------------------------------- */

/* Frames of one sample per pixel of integrator `integrator` into region statistics;
 * returns the status of the first frame that failed (TR_OK when none). */
static int run(const tr_scene *s, const tr_camera *cam, int integrator, int depth, int frames,
               uint64_t seed, region_stats *out, tr_error *err) {
    tr_film film;
    CHECK(tr_film_init(&film, RW, RH, err) == TR_OK, "film: %s", err->msg);
    tr_render_config cfg = tr_render_config_default();
    cfg.integrator = integrator;
    cfg.max_depth = depth;
    cfg.seed = seed;
    static region_acc acc;
    static double img[3 * RW * RH];
    memset(&acc, 0, sizeof acc);
    int rc = TR_OK;
    for (int f = 0; f < frames && rc == TR_OK; ++f) {
        tr_film_clear(&film);
        if (tr_render_frame(s, cam, &cfg, &film, (uint32_t)f, NULL, err) != TR_OK) {
            rc = err->code;
            break;
        }
        for (uint32_t y = 0; y < RH; ++y) {
            for (uint32_t x = 0; x < RW; ++x) {
                tr_vec3 c = tr_film_pixel(&film, x, y);
                img[3 * (y * RW + x)] = c.x;
                img[3 * (y * RW + x) + 1] = c.y;
                img[3 * (y * RW + x) + 2] = c.z;
            }
        }
        acc_frame(&acc, img);
    }
    if (rc == TR_OK) {
        *out = acc_stats(&acc);
    }
    tr_film_free(&film);
    return rc;
}

static int by_name(const void *a, const void *b) {
    return strcmp(*(const char *const *)a, *(const char *const *)b);
}

static void shipped_scenes(void) {
    DIR *d = opendir(TR_SOURCE_DIR "/scenes");
    CHECK(d != NULL, "cannot list %s/scenes", TR_SOURCE_DIR);
    if (!d) {
        return;
    }
    char *names[64];
    int count = 0;
    struct dirent *e;
    while ((e = readdir(d)) != NULL && count < 64) {
        size_t len = strlen(e->d_name);
        if (len > 5 && strcmp(e->d_name + len - 5, ".json") == 0) {
            names[count++] = strdup(e->d_name);
        }
    }
    closedir(d);
    qsort(names, (size_t)count, sizeof *names, by_name);
    int glass_seen = 0;
    for (int i = 0; i < count; ++i) {
        char path[512];
        snprintf(path, sizeof path, "%s/scenes/%s", TR_SOURCE_DIR, names[i]);
        glass_seen |= strcmp(names[i], "cornell-glass.json") == 0;
        tr_error err;
        tr_scene *s = tr_scene_create(&err);
        CHECK(s != NULL, "scene: %s", err.msg);
        const char *note = "";
        if (tr_scene_file_load(s, path, NULL, NULL, &err) != TR_OK) {
            /* A model the file links to may not be installed here: the room without it. */
            tr_scene_file_options opt = {0, 0};
            CHECK(tr_scene_file_load(s, path, &opt, NULL, &err) == TR_OK, "%s", err.msg);
            note = " (without its mesh files)";
        }
        tr_camera cam = *tr_scene_camera(s);
        CHECK(tr_camera_resize(&cam, RW, RH, &err) == TR_OK, "%s", err.msg);
        if (strcmp(names[i], "sun-caustic.json") == 0) {
            /* pt finds the caustic of a sun of 0.5 degrees too rarely for its standard
             * errors from 48 frames to mean anything; a sun of 20 degrees in the same
             * direction, with the same irradiance, keeps the paths and lets it converge. */
            tr_scene_view v0 = tr_scene_view_of(s);
            CHECK(v0.sun_count == 1u && tr_scene_set_sun(s, v0.sun[0].dir, 20.0f,
                                                         v3(3.0f, 2.8f, 2.5f), &err) == TR_OK,
                  "%s: the sun", names[i]);
            note = " (its sun 20 degrees wide)";
        }
        CHECK(tr_scene_commit(s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s: %s", path, err.msg);
        tr_scene_view v = tr_scene_view_of(s);
        static region_stats a, b;
        const int depth = 6, frames = 48;
        int rc = run(s, &cam, TR_INTEGRATOR_BDPT, depth, frames, 0xb1ULL, &b, &err);
        /* Every shipped scene renders, the environment and the sun too (added along the
         * camera subpath), and the up-front query agrees. */
        CHECK(tr_integrator_supports(s, TR_INTEGRATOR_BDPT, &err) == TR_OK,
              "%s: tr_integrator_supports(bdpt) refused: %s", names[i], err.msg);
        CHECK(tr_integrator_supports(s, TR_INTEGRATOR_PT, &err) == TR_OK,
              "%s: tr_integrator_supports(pt) refused", names[i]);
        CHECK(rc == TR_OK, "%s: bdpt: %s", names[i], err.msg);
        CHECK(run(s, &cam, TR_INTEGRATOR_PT, depth, frames, 0xa1ULL, &a, &err) == TR_OK,
              "%s: pt: %s", names[i], err.msg);
        double z = compare_regions(names[i], &a, &b);
        printf("%s%s%s: worst |pt - bdpt| = %.2f sigma\n", names[i], note,
               v.env_count + v.sun_count > 0u ? " (sky or sun)" : "", z);
        if (v.env_count + v.sun_count > 0u) {
            /* Light subpaths start from the sky and the sun there: vcm too, with merges of
             * half a pixel so that their blur stays below the noise at this size. */
            setenv("TRAC0R_VCM_RADIUS", "0.5", 1);
            CHECK(run(s, &cam, TR_INTEGRATOR_VCM, depth, frames, 0xc1ULL, &b, &err) == TR_OK,
                  "%s: vcm: %s", names[i], err.msg);
            unsetenv("TRAC0R_VCM_RADIUS");
            printf("%s%s: worst |pt - vcm| = %.2f sigma\n", names[i], note,
                   compare_regions(names[i], &a, &b));
        }
        tr_scene_destroy(s);
        free(names[i]);
    }
    CHECK(count >= 5 && glass_seen, "%d scene files, cornell-glass.json %s", count,
          glass_seen ? "among them" : "missing");
}

/* Settings bdpt refuses. */
static void refusals(void) {
    tr_scene s = {0};
    build_box(&s, 0, 8, 8);
    tr_error err;
    tr_film film;
    CHECK(tr_film_init(&film, 8, 8, &err) == TR_OK, "film: %s", err.msg);
    tr_render_config cfg = tr_render_config_default();
    cfg.integrator = TR_INTEGRATOR_BDPT;
    cfg.max_depth = TR_MAX_DEPTH_BDPT + 1;
    CHECK(tr_render_frame(&s, &s.camera, &cfg, &film, 0, NULL, &err) == TR_ERR &&
              err.code == TR_STATUS_LIMIT,
          "max depth %d accepted", cfg.max_depth);
    cfg.max_depth = 0;
    CHECK(tr_default_max_depth(TR_INTEGRATOR_BDPT) == TR_MAX_DEPTH_BDPT &&
              tr_render_frame(&s, &s.camera, &cfg, &film, 0, NULL, &err) == TR_OK,
          "default depth: %s", err.msg);
    tr_film_free(&film);
    tr_scene_clear(&s);
}

/* An emitter and a sky at once: the box with its lamp under a sky seen through its open
 * front. bdpt's and vcm's estimate (BDPT for the lamp, the camera side's two strategies for
 * the sky) agrees with pt's per region, and the sky adds light (else the check would not
 * test it). */
static void lamp_and_sky(void) {
    tr_error err;
    tr_scene s = {0};
    tr_scene_init(&s);
    CHECK(tr_scene_builtin(&s, "cornell", RW, RH, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
    tr_camera cam = *tr_scene_camera(&s);
    CHECK(tr_camera_resize(&cam, RW, RH, &err) == TR_OK, "%s", err.msg);
    static region_stats dark, pt, bd, vc;
    const int depth = 6, frames = 48;
    CHECK(run(&s, &cam, TR_INTEGRATOR_PT, depth, frames, 0xa2ULL, &dark, &err) == TR_OK, "%s",
          err.msg);
    CHECK(tr_scene_set_environment(&s, v3(0.6f, 0.8f, 1.0f), 2.0f, 0.0f, NULL, 0, 0, &err) == TR_OK,
          "%s", err.msg);
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
    CHECK(run(&s, &cam, TR_INTEGRATOR_PT, depth, frames, 0xa3ULL, &pt, &err) == TR_OK, "pt: %s",
          err.msg);
    CHECK(run(&s, &cam, TR_INTEGRATOR_BDPT, depth, frames, 0xb3ULL, &bd, &err) == TR_OK, "bdpt: %s",
          err.msg);
    /* Merges of half a pixel: the default radius, 3 pixels of this 16-pixel image, blurs
     * the box's corners by more than the noise (the bias docs/integrators.md measures). */
    setenv("TRAC0R_VCM_RADIUS", "0.5", 1);
    CHECK(run(&s, &cam, TR_INTEGRATOR_VCM, depth, frames, 0xc3ULL, &vc, &err) == TR_OK, "vcm: %s",
          err.msg);
    unsetenv("TRAC0R_VCM_RADIUS");
    double sky = 0.0, se = 0.0;
    for (int r = 0; r < NR; ++r) {
        sky += pt.mean[r][2] - dark.mean[r][2];
        se += pt.se[r][2] * pt.se[r][2] + dark.se[r][2] * dark.se[r][2];
    }
    CHECK(sky > 5.0 * sqrt(se), "the sky adds %g (standard error %g): not seen", sky, sqrt(se));
    printf("lamp and sky: bdpt %.2f sigma, vcm %.2f sigma from pt\n",
           compare_regions("lamp and sky, bdpt", &pt, &bd),
           compare_regions("lamp and sky, vcm", &pt, &vc));
    tr_scene_clear(&s);
}

/* Punctual lights: the diffuse Cornell box lit by a point light, a spot, or a directional
 * light through its open front, beside its lamp, one at a time. bdpt's and vcm's
 * estimates (light subpaths from the punctual light, weighed with the camera side's light
 * sample of it) agree with pt's (the light sample alone) per region, and the light adds
 * light. With kind 3, the box with its glass sphere under the spot: pt cannot find
 * the caustic (a delta light seen through glass), bdpt and vcm do and agree. */
static void punctual_agree(void) {
    static const char *names[4] = {"point", "spot", "directional", "spot (caustic)"};
    for (uint32_t kind = 0; kind < 4; ++kind) {
        tr_error err;
        tr_scene s = {0};
        tr_scene_init(&s);
        CHECK(tr_scene_builtin(&s, kind == 3 ? "cornell" : "cornell-diffuse", RW, RH, &err) ==
                  TR_OK,
              "%s", err.msg);
        CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
        tr_camera cam = *tr_scene_camera(&s);
        CHECK(tr_camera_resize(&cam, RW, RH, &err) == TR_OK, "%s", err.msg);
        const tr_aabb b = tr_triangles_bounds(s.triangles, s.triangle_count);
        const tr_vec3 c = v3_scale(v3_add(b.min, b.max), 0.5f), e = v3_sub(b.max, b.min);
        static region_stats dark, pt, bd, vc;
        const int depth = 5, frames = kind == 3 ? 160 : 48;
        CHECK(run(&s, &cam, TR_INTEGRATOR_PT, depth, frames, 0xa4ULL, &dark, &err) == TR_OK, "%s",
              err.msg);
        tr_punctual l;
        memset(&l, 0, sizeof l);
        l.type = kind == 0 ? TR_PUNCTUAL_POINT
                           : (kind != 2 ? TR_PUNCTUAL_SPOT : TR_PUNCTUAL_DIRECTIONAL);
        /* Below the ceiling, a little off-centre; the spot aims at the floor's near half. */
        l.pos = v3_add(c, v3(0.15f * e.x, 0.3f * e.y, -0.1f * e.z));
        l.dir = kind & 1u ? v3(0.1f, -1.0f, -0.4f) : v3(0.2f, -0.5f, 1.0f);
        const float lamp = (kind == 2 ? 30.0f : 0.8f * v3_dot(e, e)) * (kind & 1u ? 6.0f : 1.0f);
        l.intensity = v3(lamp, 0.9f * lamp, 0.8f * lamp);
        l.cos_outer = 0.8f;
        l.cos_inner = 0.9f;
        CHECK(tr_scene_add_punctual(&s, &l, &err) == TR_OK, "%s", err.msg);
        CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
        tr_scene_view v = tr_scene_view_of(&s);
        CHECK(tr_bdpt_punctual_on(&v), "%s light: no light subpaths start from it", names[kind]);
        CHECK(run(&s, &cam, TR_INTEGRATOR_PT, depth, frames, 0xa5ULL, &pt, &err) == TR_OK, "pt: %s",
              err.msg);
        CHECK(run(&s, &cam, TR_INTEGRATOR_BDPT, depth, frames, 0xb5ULL, &bd, &err) == TR_OK,
              "bdpt: %s", err.msg);
        setenv("TRAC0R_VCM_RADIUS", "0.5", 1);
        CHECK(run(&s, &cam, TR_INTEGRATOR_VCM, depth, frames, 0xc5ULL, &vc, &err) == TR_OK,
              "vcm: %s", err.msg);
        unsetenv("TRAC0R_VCM_RADIUS");
        double add = 0.0, se = 0.0;
        for (int r = 0; r < NR; ++r) {
            add += pt.mean[r][1] - dark.mean[r][1];
            se += pt.se[r][1] * pt.se[r][1] + dark.se[r][1] * dark.se[r][1];
        }
        CHECK(add > 5.0 * sqrt(se), "the %s light adds %g (standard error %g): not seen",
              names[kind], add, sqrt(se));
        char what[64];
        if (kind == 3) {
            double more = 0.0, se2 = 0.0;
            for (int r = 0; r < NR; ++r) {
                more += bd.mean[r][2] - pt.mean[r][2];
                se2 += bd.se[r][2] * bd.se[r][2] + pt.se[r][2] * pt.se[r][2];
            }
            CHECK(more > 5.0 * sqrt(se2), "bdpt finds %g more than pt (standard error %g)", more,
                  sqrt(se2));
            snprintf(what, sizeof what, "%s light, vcm vs bdpt", names[kind]);
            printf("%s light: bdpt finds %.3f more than pt (%.1f sigma); vcm %.2f sigma from "
                   "bdpt\n",
                   names[kind], more, more / sqrt(se2), compare_regions(what, &bd, &vc));
            tr_scene_clear(&s);
            continue;
        }
        snprintf(what, sizeof what, "%s light, bdpt", names[kind]);
        const double zb = compare_regions(what, &pt, &bd);
        snprintf(what, sizeof what, "%s light, vcm", names[kind]);
        const double zv = compare_regions(what, &pt, &vc);
        printf("%s light: bdpt %.2f sigma, vcm %.2f sigma from pt\n", names[kind], zb, zv);
        tr_scene_clear(&s);
    }
}

/* Merges across a corner. A camera vertex x on a ceiling (facing down) at a wall's corner,
 * a light vertex y from the sky within r of it on the wall's outer face, reached from
 * below and outside (so that the ceiling's BSDF would take it), and a light vertex z on
 * the ceiling's underside beside x. With the grid's facing test (tr_vcm_facing: scenes
 * whose light subpaths start from the sky) y brings nothing and z is merged; without it y
 * leaks in. */
static void vcm_facing(void) {
    tr_material white = tr_material_diffuse(v3(0.8f, 0.8f, 0.8f));
    tr_bdpt_vertex cv[2], ly[2], lz[2];
    memset(cv, 0, sizeof cv);
    memset(ly, 0, sizeof ly);
    memset(lz, 0, sizeof lz);
    cv[0].p = v3(0.0f, -1.0f, 0.0f);
    cv[0].kind = TR_BDPT_CAMERA;
    cv[0].pdf_fwd = 1.0f;
    cv[1].m = tr_material_params(&white, v3(0.0f, -1.0f, 0.0f));
    cv[1].p = v3(0.0f, 0.0f, 0.0f);
    cv[1].wo = v3(0.0f, -1.0f, 0.0f);
    cv[1].beta = v3s(1.0f);
    cv[1].kind = TR_BDPT_SURFACE;
    cv[1].pdf_fwd = 1.0f;
    const tr_vec3 from_y = v3_normalize(v3(-1.0f, -0.4f, 0.0f)); /* towards the light */
    const tr_vec3 from_z = v3_normalize(v3(0.3f, -1.0f, 0.2f));
    tr_bdpt_vertex *paths[2] = {ly, lz};
    const tr_vec3 where[2] = {v3(-0.02f, -0.03f, 0.0f), v3(0.03f, 0.0f, 0.02f)};
    const tr_vec3 normal[2] = {v3(-1.0f, 0.0f, 0.0f), v3(0.0f, -1.0f, 0.0f)};
    const tr_vec3 dir[2] = {from_y, from_z};
    tr_vcm_entry entries[2];
    for (int k = 0; k < 2; ++k) {
        tr_bdpt_vertex *l = paths[k];
        l[0].kind = TR_BDPT_INFINITE;
        l[0].wo = dir[k];
        l[0].pdf_fwd = 0.1f;
        l[0].pdf_nee = 0.2f;
        l[0].pdf_pos = 0.05f;
        l[1].m = tr_material_params(&white, normal[k]);
        l[1].p = where[k];
        l[1].wo = dir[k];
        l[1].beta = v3s(2.0f);
        l[1].kind = TR_BDPT_SURFACE;
        l[1].pdf_fwd = 0.05f * fabsf(v3_dot(dir[k], normal[k]));
        l[1].pdf_rev = 0.3f;
        float a, b, g;
        tr_vcm_light_sums(l, 1, &a, &b, &g);
        entries[k] = tr_vcm_entry_of(l, 1, a, b, g);
    }
    const uint32_t first[2] = {0u, 2u};
    tr_vcm_grid g;
    memset(&g, 0, sizeof g);
    g.cell_first = first;
    g.entries = entries;
    g.cell_mask = 0u; /* one bucket: every cell's */
    g.origin = v3s(-4.0f);
    g.inv_cell = 0.5f / 0.1f;
    g.radius2 = 0.1f * 0.1f;
    g.eta = 100.0f * (float)PI_D * g.radius2;
    g.norm = 1.0f / g.eta;
    tr_vec3 both[2], alone[2];
    const uint32_t only_z[2] = {1u, 2u}; /* the bucket holds z alone */
    for (uint32_t facing = 0; facing < 2u; ++facing) {
        g.facing = facing;
        g.cell_first = first;
        both[facing] = tr_vcm_merge(cv, 2, 8, &g);
        g.cell_first = only_z;
        alone[facing] = tr_vcm_merge(cv, 2, 8, &g);
    }
    CHECK(both[0].x > alone[0].x * 1.01f && alone[0].x > 0.0f,
          "without the facing test the wall's outer vertex should be merged: %g with it, %g "
          "without",
          both[0].x, alone[0].x);
    CHECK(both[1].x == alone[1].x && alone[1].x == alone[0].x,
          "with the facing test only the ceiling's vertex is merged: %g, %g (alone %g)", both[1].x,
          alone[1].x, alone[0].x);
}

/* A closed room lit through its window by the sun and the sky, seen into the corner of the
 * ceiling and two walls: the light subpaths from outside land on the room's outer faces
 * too, and vcm, merging with a radius that reaches across the corner, agrees with bdpt per
 * region. */
static void vcm_closed_room(void) {
    char path[512];
    snprintf(path, sizeof path, "%s/scenes/window-room.json", TR_SOURCE_DIR);
    tr_error err;
    tr_scene *s = tr_scene_create(&err);
    CHECK(s != NULL, "scene: %s", err.msg);
    CHECK(tr_scene_file_load(s, path, NULL, NULL, &err) == TR_OK, "%s", err.msg);
    /* Looking into the corner of the ceiling and the two walls away from the window. */
    tr_camera cam;
    CHECK(tr_camera_make(&cam, v3(0.5f, 1.5f, 0.5f), v3(-3.0f, 3.0f, -3.0f), v3(0.0f, 1.0f, 0.0f),
                         60.0f, 0.001f, 100.0f, RW, RH, &err) == TR_OK,
          "camera: %s", err.msg);
    CHECK(tr_scene_commit(s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
    static region_stats a, b;
    setenv("TRAC0R_VCM_RADIUS", "1", 1);
    CHECK(run(s, &cam, TR_INTEGRATOR_VCM, 6, 64, 0xc5ULL, &b, &err) == TR_OK, "vcm: %s", err.msg);
    unsetenv("TRAC0R_VCM_RADIUS");
    CHECK(run(s, &cam, TR_INTEGRATOR_BDPT, 6, 64, 0xb5ULL, &a, &err) == TR_OK, "bdpt: %s", err.msg);
    printf("closed room under the sun, merges of a pixel: worst |bdpt - vcm| = %.2f sigma\n",
           compare_regions("window-room.json, vcm vs bdpt", &a, &b));
    tr_scene_destroy(s);
}

int main(void) {
    refusals();
    lamp_and_sky();
    mis_sum();
    mis_sum_sky();
    mis_sum_punctual();
    punctual_agree();
    light_tracing();
    strategies();
    determinism(TR_INTEGRATOR_BDPT);
    determinism(TR_INTEGRATOR_VCM);
    vcm_radius();
    vcm_agrees();
    vcm_facing();
    vcm_closed_room();
    shipped_scenes();
    return check_finish("test_bdpt");
}
