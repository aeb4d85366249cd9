/* test_specular.c - diffuse and specular light apart (TR_PASS_SPECULAR, the DFG table and
 * SVGF with svgf_specular).
 *
 * 1. On random rooms (spheres of random materials: diffuse, rough and mirror glossy,
 *    principled with random metallic, roughness and clear coat, glass; with and without the
 *    sky and the sun) asking for the specular pass changes no bit of the radiance or of the
 *    other passes; the specular part lies between 0 and the reflected light (radiance less
 *    the first hit's emission), so the diffuse rest is never negative; it is exactly 0 where
 *    every surface is diffuse and equals the reflected light, to float rounding, where every
 *    surface is rough glossy. The two parts then sum to the radiance pass.
 * 2. The DFG table (A, B over the view cosine and GGX alpha, integrated by visible-normal
 *    quadrature) agrees with a Monte Carlo integration of the kernel's GGX lobe done another
 *    way (uniform hemisphere directions, a fixed seed) within five standard deviations of the
 *    estimate, and a white lobe reflects at most what arrives.
 * 3. A static glossy scene under SVGF with the specular part apart converges to the
 *    reference: after 32 frames of 1 sample its squared error is below half of one raw
 *    frame's (at 40 x 30 a few pixels of the metal sphere's highlight, which SVGF smears
 *    split or not, hold most of it) and at most 1.25 times the unsplit filter's, and the
 *    image's mean is within
 *    10 % of a 1024-sample reference's (SVGF's own bias at this length is about 7 % here,
 *    split or not: a wrong remodulation, dropping or doubling the specular part, is far
 *    outside). */
#include "check.h"
#include "render_film.h"
#include "post/dfg.h"
#include "kernel/bsdf.h"
#include "trac0r/post.h"
#include "trac0r/scene_file.h"
#include "trac0r/trac0r.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define W 40
#define H 30

static uint64_t rng_state;
static double urand(void) {
    rng_state = rng_state * 6364136223846793005ull + 1442695040888963407ull;
    return (double)(rng_state >> 11) * (1.0 / 9007199254740992.0);
}

/* kind 0: random materials, 1: all diffuse, 2: all rough glossy. */
static const char *material_json(int kind, int k, char *buf, size_t len) {
    const double r = 0.2 + 0.7 * urand(), g = 0.2 + 0.7 * urand(), b = 0.2 + 0.7 * urand();
    int type = kind == 1 ? 0 : kind == 2 ? 1 : (int)(urand() * 5.0);
    switch (type) {
    case 0:
        snprintf(buf, len, "\"m%d\": {\"type\": \"diffuse\", \"color\": [%.3f, %.3f, %.3f]}", k, r,
                 g, b);
        break;
    case 1:
        snprintf(buf, len,
                 "\"m%d\": {\"type\": \"glossy\", \"color\": [%.3f, %.3f, %.3f], \"roughness\": "
                 "%.3f}",
                 k, r, g, b, 0.1 + 0.8 * urand());
        break;
    case 2:
        snprintf(buf, len,
                 "\"m%d\": {\"type\": \"glossy\", \"color\": [%.3f, %.3f, %.3f], \"roughness\": 0}",
                 k, r, g, b);
        break;
    case 3:
        snprintf(
            buf, len,
            "\"m%d\": {\"type\": \"principled\", \"color\": [%.3f, %.3f, %.3f], \"roughness\": "
            "%.3f, \"metallic\": %.3f, \"clearcoat\": %.3f, \"clearcoat_roughness\": %.3f}",
            k, r, g, b, 0.05 + 0.9 * urand(), urand() < 0.5 ? 0.0 : urand(),
            urand() < 0.5 ? 0.0 : urand(), urand());
        break;
    default:
        snprintf(buf, len, "\"m%d\": {\"type\": \"glass\", \"color\": [1, 1, 1], \"ior\": 1.5}", k);
        break;
    }
    return buf;
}

/* A closed room 10 wide with a lamp under its ceiling, walls of materials m0..m4 and three
 * spheres of m5..m7; with sky, an opening in the ceiling (no ceiling), the environment and
 * the sun. */
static tr_scene *random_room(int kind, int sky, uint64_t seed) {
    rng_state = seed * 7919u + 17u;
    char mats[8][256], text[8192];
    for (int k = 0; k < 8; ++k) {
        material_json(kind, k, mats[k], sizeof mats[k]);
    }
    double sp[3][4];
    for (int k = 0; k < 3; ++k) {
        sp[k][3] = 0.8 + 0.9 * urand();
        sp[k][0] = -3.0 + 6.0 * urand();
        sp[k][1] = sp[k][3];
        sp[k][2] = -2.0 + 5.0 * urand();
    }
    const char *ceiling = sky ? ""
                              : "{\"type\": \"quad\", \"vertices\": [[-5, 8, -5], [-5, 8, 5], [5, "
                                "8, 5], [5, 8, -5]], \"material\": \"m1\"},";
    const char *light = sky ? "\"environment\": {\"color\": [0.5, 0.7, 1.0], \"strength\": 1.0}, "
                              "\"sun\": {\"direction\": [-0.4, 1.0, 0.3], \"angle\": 0.5, "
                              "\"irradiance\": [6, 5.5, 5]},"
                            : "";
    snprintf(text, sizeof text,
             "{\"version\": 1, %s"
             "\"camera\": {\"position\": [0, 4, -12], \"look_at\": [0, 3, 0], \"up\": [0, 1, 0], "
             "\"fov\": 50},"
             "\"materials\": {\"lamp\": {\"type\": \"emitter\", \"color\": [1, 0.9, 0.8], "
             "\"emittance\": 12}, %s, %s, %s, %s, %s, %s, %s, %s},"
             "\"shapes\": ["
             "{\"type\": \"quad\", \"vertices\": [[5, 0, -5], [-5, 0, -5], [-5, 0, 5], [5, 0, 5]], "
             "\"material\": \"m0\"}, %s"
             "{\"type\": \"quad\", \"vertices\": [[5, 0, 5], [-5, 0, 5], [-5, 8, 5], [5, 8, 5]], "
             "\"material\": \"m2\"},"
             "{\"type\": \"quad\", \"vertices\": [[-5, 0, 5], [-5, 0, -5], [-5, 8, -5], [-5, 8, "
             "5]], \"material\": \"m3\"},"
             "{\"type\": \"quad\", \"vertices\": [[5, 0, -5], [5, 0, 5], [5, 8, 5], [5, 8, -5]], "
             "\"material\": \"m4\"},"
             "{\"type\": \"quad\", \"vertices\": [[-1.5, 7.9, -1.5], [1.5, 7.9, -1.5], [1.5, 7.9, "
             "1.5], [-1.5, 7.9, 1.5]], \"material\": \"lamp\"},"
             "{\"type\": \"icosphere\", \"position\": [%.3f, %.3f, %.3f], \"scale\": %.3f, "
             "\"subdivisions\": 3, \"smooth\": true, \"material\": \"m5\"},"
             "{\"type\": \"icosphere\", \"position\": [%.3f, %.3f, %.3f], \"scale\": %.3f, "
             "\"subdivisions\": 3, \"smooth\": true, \"material\": \"m6\"},"
             "{\"type\": \"icosphere\", \"position\": [%.3f, %.3f, %.3f], \"scale\": %.3f, "
             "\"subdivisions\": 3, \"smooth\": true, \"material\": \"m7\"}]}",
             light, mats[0], mats[1], mats[2], mats[3], mats[4], mats[5], mats[6], mats[7], ceiling,
             sp[0][0], sp[0][1], sp[0][2], sp[0][3], sp[1][0], sp[1][1], sp[1][2], sp[1][3],
             sp[2][0], sp[2][1], sp[2][2], sp[2][3]);
    tr_error err;
    tr_scene *s = tr_scene_create(&err);
    CHECK(s && tr_scene_file_parse(s, "room.json", text, strlen(text), NULL, NULL, &err) == TR_OK,
          "%s", err.msg);
    tr_camera cam = *tr_scene_camera(s);
    CHECK(tr_camera_resize(&cam, W, H, &err) == TR_OK, "%s", err.msg);
    tr_scene_set_camera(s, &cam);
    CHECK(tr_scene_commit(s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
    return s;
}

static void test_pass(int kind, int sky, uint64_t seed) {
    tr_scene *s = random_room(kind, sky, seed);
    const uint32_t base = TR_PASS_ALL | TR_PASS_EMISSION | TR_PASS_DIRECT;
    tr_film a, b;
    render_film(s, W, H, TR_INTEGRATOR_PT, 6, base, seed, 0, 4, &a);
    render_film(s, W, H, TR_INTEGRATOR_PT, 6, base | TR_PASS_SPECULAR, seed, 0, 4, &b);
    const size_t n = (size_t)W * H;
    CHECK(memcmp(a.sum, b.sum, 3 * n * sizeof(float)) == 0 &&
              memcmp(a.albedo, b.albedo, 3 * n * sizeof(float)) == 0 &&
              memcmp(a.normal, b.normal, 3 * n * sizeof(float)) == 0 &&
              memcmp(a.depth, b.depth, n * sizeof(float)) == 0 &&
              memcmp(a.prim, b.prim, n * sizeof(uint32_t)) == 0 &&
              memcmp(a.direct, b.direct, 3 * n * sizeof(float)) == 0 &&
              memcmp(a.emission, b.emission, 3 * n * sizeof(float)) == 0,
          "kind %d sky %d seed %llu: the specular pass changed the radiance or a pass", kind, sky,
          (unsigned long long)seed);
    int below = 0, above = 0, off = 0;
    double spec = 0.0, refl = 0.0;
    for (size_t i = 0; i < n; ++i) {
        for (int c = 0; c < 3; ++c) {
            const float sum = b.sum[3 * i + c], r = sum - b.emission[3 * i + c];
            const float sv = b.specular[8 * i + c];
            const float tol = 1e-5f * (fabsf(sum) + 1e-3f);
            below += sv < -tol;
            above += sv > r + tol;
            spec += sv;
            refl += r;
            if (kind == 1) {
                off += sv != 0.0f;
            } else if (kind == 2) {
                off += fabsf(sv - r) > tol;
            }
        }
    }
    CHECK(below == 0 && above == 0,
          "kind %d sky %d seed %llu: %d channels of the specular part below 0, %d above the "
          "reflected light",
          kind, sky, (unsigned long long)seed, below, above);
    CHECK(off == 0, "kind %d seed %llu: %d channels of the specular part not %s", kind,
          (unsigned long long)seed, off,
          kind == 1 ? "0 in a diffuse room" : "the reflected light in a glossy room");
    CHECK(refl > 0.0, "the room is dark");
    if (kind == 0) {
        CHECK(spec >= 0.0 && spec <= refl, "specular %g of reflected %g", spec, refl);
    }
    tr_film_free(&a);
    tr_film_free(&b);
    tr_scene_destroy(s);
}

static void test_passes(void) {
    int mixed = 0;
    for (uint64_t seed = 1; seed <= 6; ++seed) {
        test_pass(0, (int)(seed & 1u), seed);
        ++mixed;
    }
    test_pass(1, 0, 7);
    test_pass(1, 1, 8);
    test_pass(2, 0, 9);
    test_pass(2, 1, 10);
    CHECK(mixed == 6, "rooms");
    /* The pass needs pt; its name and mean through the film API. */
    tr_error err;
    tr_scene *s = random_room(0, 0, 3);
    tr_film f;
    CHECK(tr_film_init_passes(&f, W, H, TR_PASS_SPECULAR, &err) == TR_OK, "%s", err.msg);
    tr_render_config cfg = tr_render_config_default();
    cfg.passes = TR_PASS_SPECULAR;
    cfg.integrator = TR_INTEGRATOR_NAIVE;
    CHECK(tr_render_frame(s, tr_scene_camera(s), &cfg, &f, 0, NULL, &err) == TR_ERR &&
              err.code == TR_STATUS_INVALID_ARGUMENT,
          "naive with the specular pass was not refused");
    cfg.integrator = TR_INTEGRATOR_PT;
    CHECK(tr_render_frame(s, tr_scene_camera(s), &cfg, &f, 0, NULL, &err) == TR_OK, "%s", err.msg);
    float v[3];
    CHECK(tr_film_pass_pixel(&f, TR_PASS_SPECULAR, W / 2, H / 2, v, &err) == TR_OK, "%s", err.msg);
    const size_t c = (size_t)(H / 2) * W + W / 2;
    CHECK(v[1] == f.specular[8 * c + 1] / (float)f.count[c], "the pass's mean");
    CHECK(tr_pass_name(TR_PASS_SPECULAR) && strcmp(tr_pass_name(TR_PASS_SPECULAR), "specular") == 0,
          "pass name");
    tr_film_free(&f);
    tr_scene_destroy(s);
}

/* E = int f cos over the hemisphere for F0 = f0 (grey), by uniform directions: the mean and
 * the estimate's standard deviation. */
static void mc_albedo(float mu, float alpha, float f0, int count, double *mean, double *sd) {
    const tr_vec3 nf = v3(0.0f, 0.0f, 1.0f);
    const tr_vec3 wo = v3(sqrtf(fmaxf(0.0f, 1.0f - mu * mu)), 0.0f, mu);
    double s = 0.0, q = 0.0;
    for (int k = 0; k < count; ++k) {
        const double z = urand(), phi = 6.283185307179586 * urand();
        const double r = sqrt(fmax(0.0, 1.0 - z * z));
        const tr_vec3 wi = v3((float)(r * cos(phi)), (float)(r * sin(phi)), (float)z);
        double x = 0.0;
        if (wi.z > 0.0f) {
            const tr_vec3 f = tr_principled_spec(alpha, v3s(f0), nf, wo, wi, mu, wi.z);
            x = (double)f.x * wi.z * 6.283185307179586; /* over the pdf 1 / (2 pi) */
        }
        s += x;
        q += x * x;
    }
    *mean = s / count;
    *sd = sqrt(fmax(0.0, q / count - *mean * *mean) / count);
}

static void test_dfg(void) {
    const float *t = tr_post_dfg_table();
    rng_state = 12345u;
    const int is[4] = {6, 14, 22, 31}, js[4] = {8, 14, 22, 31};
    int checked = 0;
    for (int a = 0; a < 4; ++a) {
        for (int b = 0; b < 4; ++b) {
            const int i = is[a], j = js[b];
            const float mu = tr_post_dfg_mu(i), alpha = tr_post_dfg_alpha(j);
            const float A = t[2 * (j * TR_DFG_N + i)], B = t[2 * (j * TR_DFG_N + i) + 1];
            double e1, s1, e0, s0;
            mc_albedo(mu, alpha, 1.0f, 200000, &e1, &s1);
            mc_albedo(mu, alpha, 0.0f, 200000, &e0, &s0);
            /* The bound: the estimate's 5 sigma and the table's quadrature error. */
            CHECK(fabs((A + B) - e1) <= 5.0 * s1 + 2e-3,
                  "mu %g alpha %g: A + B = %g, Monte Carlo %g +- %g", mu, alpha, A + B, e1, s1);
            CHECK(fabs(B - e0) <= 5.0 * s0 + 1e-3, "mu %g alpha %g: B = %g, Monte Carlo %g +- %g",
                  mu, alpha, B, e0, s0);
            ++checked;
        }
    }
    CHECK(checked == 16, "nodes");
    /* A white lobe loses light to single scattering but never gains: 0 <= A + B <= 1; the
     * smoothest one seen head-on reflects all of it. */
    int bad = 0;
    for (int k = 0; k < TR_DFG_N * TR_DFG_N; ++k) {
        bad += !(t[2 * k] >= 0.0f && t[2 * k + 1] >= 0.0f && t[2 * k] + t[2 * k + 1] <= 1.0001f);
    }
    CHECK(bad == 0, "%d nodes outside 0 <= A + B <= 1", bad);
    float A, B;
    tr_post_dfg_lookup(t, 1.0f, 0.0f, &A, &B);
    CHECK(fabsf(A + B - 1.0f) < 1e-2f, "a mirror seen head-on reflects %g", A + B);
    tr_post_dfg_lookup(t, tr_post_dfg_mu(9), tr_post_dfg_alpha(17), &A, &B);
    CHECK(A == t[2 * (17 * TR_DFG_N + 9)] && B == t[2 * (17 * TR_DFG_N + 9) + 1],
          "a node's lookup is its entry");
}

/* A room with a glossy principled floor, a rough metal sphere and a diffuse one. */
static const char glossy_room[] =
    "{\"version\": 1, \"camera\": {\"position\": [0, 4, -12], \"look_at\": [0, 2, 0], \"up\": [0, "
    "1, 0], \"fov\": 50},"
    "\"materials\": {\"lamp\": {\"type\": \"emitter\", \"color\": [1, 0.9, 0.8], \"emittance\": "
    "12}, \"white\": {\"type\": \"diffuse\", \"color\": [0.7, 0.7, 0.7]}, \"floor\": {\"type\": "
    "\"principled\", \"color\": [0.3, 0.3, 0.35], \"roughness\": 0.35}, \"metal\": {\"type\": "
    "\"principled\", \"color\": [0.9, 0.7, 0.4], \"roughness\": 0.5, \"metallic\": 1}},"
    "\"shapes\": ["
    "{\"type\": \"quad\", \"vertices\": [[5, 0, -5], [-5, 0, -5], [-5, 0, 5], [5, 0, 5]], "
    "\"material\": \"floor\"},"
    "{\"type\": \"quad\", \"vertices\": [[-5, 8, -5], [-5, 8, 5], [5, 8, 5], [5, 8, -5]], "
    "\"material\": \"white\"},"
    "{\"type\": \"quad\", \"vertices\": [[5, 0, 5], [-5, 0, 5], [-5, 8, 5], [5, 8, 5]], "
    "\"material\": \"white\"},"
    "{\"type\": \"quad\", \"vertices\": [[-1.5, 7.9, -1.5], [1.5, 7.9, -1.5], [1.5, 7.9, 1.5], "
    "[-1.5, 7.9, 1.5]], \"material\": \"lamp\"},"
    "{\"type\": \"icosphere\", \"position\": [-1.8, 1.5, 0], \"scale\": 1.5, \"subdivisions\": 3, "
    "\"smooth\": true, \"material\": \"metal\"},"
    "{\"type\": \"icosphere\", \"position\": [2, 1.2, 1], \"scale\": 1.2, \"subdivisions\": 3, "
    "\"smooth\": true, \"material\": \"white\"}]}";

/* The squared error and the means of the reflected light: a less its emission em (the
 * frame's, which the reconstruction adds back as it is: the lamp's edge is the emission
 * resolve's business, not this filter's), against the reference's reflected light r. */
static double image_mse(const float *a, const float *em, const float *r, size_t n3, double *mean_a,
                        double *mean_r) {
    double e = 0.0, sa = 0.0, sr = 0.0;
    size_t used = 0;
    for (size_t k = 0; k < n3; ++k) {
        ++used;
        const double d = (double)a[k] - em[k] - r[k];
        e += d * d;
        sa += (double)a[k] - em[k];
        sr += r[k];
    }
    *mean_a = sa / (double)used;
    *mean_r = sr / (double)used;
    return e / (double)used;
}

static void test_converges(void) {
    tr_error err;
    tr_scene *s = tr_scene_create(&err);
    CHECK(s && tr_scene_file_parse(s, "glossy.json", glossy_room, strlen(glossy_room), NULL, NULL,
                                   &err) == TR_OK,
          "%s", err.msg);
    tr_camera cam = *tr_scene_camera(s);
    CHECK(tr_camera_resize(&cam, W, H, &err) == TR_OK, "%s", err.msg);
    tr_scene_set_camera(s, &cam);
    CHECK(tr_scene_commit(s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
    const uint32_t passes = TR_PASS_ALL | TR_PASS_EMISSION | TR_PASS_SPECULAR;
    const size_t n3 = 3u * W * H;
    tr_film ref;
    render_film(s, W, H, TR_INTEGRATOR_PT, 0, TR_PASS_EMISSION, 77, 0, 1024, &ref);
    tr_render_config cfg = tr_render_config_default();
    cfg.threads = 2;
    float *refimg = malloc(n3 * sizeof(float)), *out[2];
    for (size_t i = 0; i < n3 / 3; ++i) {
        for (int c = 0; c < 3; ++c) {
            refimg[3 * i + c] =
                (ref.sum[3 * i + c] - ref.emission[3 * i + c]) / (float)ref.count[i];
        }
    }
    tr_recon r[2];
    tr_gbuffer g;
    CHECK(tr_gbuffer_init(&g, W, H, &err) == TR_OK, "%s", err.msg);
    tr_recon_params p[2] = {tr_recon_params_default(), tr_recon_params_default()};
    p[1].svgf_specular = 1;
    for (int m = 0; m < 2; ++m) {
        CHECK(tr_recon_init(&r[m], W, H, &err) == TR_OK, "%s", err.msg);
        out[m] = malloc(n3 * sizeof(float));
    }
    tr_film f;
    CHECK(tr_film_init_passes(&f, W, H, passes, &err) == TR_OK, "%s", err.msg);
    cfg.passes = passes;
    cfg.seed = 5;
    for (uint32_t k = 0; k < 32; ++k) {
        tr_film_clear(&f);
        CHECK(tr_render_frame(s, &cam, &cfg, &f, k, NULL, &err) == TR_OK, "%s", err.msg);
        CHECK(tr_gbuffer_from_film(&g, &f, &err) == TR_OK && g.has_specular, "%s", err.msg);
        for (int m = 0; m < 2; ++m) {
            CHECK(tr_recon_frame(&r[m], &g, &cam, TR_RECON_SVGF, &p[m], 2, out[m], &err) == TR_OK,
                  "%s", err.msg);
        }
    }
    double ma[2], mr, e[2], mraw;
    for (int m = 0; m < 2; ++m) {
        e[m] = image_mse(out[m], g.emission, refimg, n3, &ma[m], &mr);
    }
    const double eraw = image_mse(g.color, g.emission, refimg, n3, &mraw, &mr); /* one frame */
    printf("static glossy room after 32 frames: mean %.5f (unsplit %.5f, reference %.5f), MSE "
           "%.3g (unsplit %.3g, one raw frame %.3g)\n",
           ma[1], ma[0], mr, e[1], e[0], eraw);
    CHECK(fabs(ma[1] - mr) < 0.1 * mr, "split: mean %g, reference %g", ma[1], mr);
    CHECK(e[1] <= 1.25 * e[0], "split: MSE %g above the unsplit filter's %g", e[1], e[0]);
    CHECK(e[1] < 0.5 * eraw, "split: MSE %g, not below half of one raw frame's %g", e[1], eraw);
    /* The specular history is really used: it differs from the unsplit output. */
    CHECK(memcmp(out[0], out[1], n3 * sizeof(float)) != 0, "the split changed nothing");
    /* Pixels whose passes primary surface replacement took through a refraction or a
     * curved mirror keep all their light in the diffuse part: with every pixel marked so,
     * the split filters the frame as the unsplit filter does. */
    for (size_t i = 0; i < n3 / 3; ++i) {
        g.prim[i] |= TR_PRIM_PSR_CURVED;
    }
    double worst = 0.0;
    for (int m = 0; m < 2; ++m) {
        tr_recon_free(&r[m]);
        CHECK(tr_recon_init(&r[m], W, H, &err) == TR_OK, "%s", err.msg);
        CHECK(tr_recon_frame(&r[m], &g, &cam, TR_RECON_SVGF, &p[m], 2, out[m], &err) == TR_OK, "%s",
              err.msg);
    }
    for (size_t k = 0; k < n3; ++k) {
        worst = fmax(worst, fabs((double)out[1][k] - out[0][k]) / fmax(1.0, fabs(out[0][k])));
    }
    CHECK(worst < 1e-4, "replaced through a curve: the split differs by %g", worst);
    for (int m = 0; m < 2; ++m) {
        tr_recon_free(&r[m]);
        free(out[m]);
    }
    tr_gbuffer_free(&g);
    tr_film_free(&f);
    tr_film_free(&ref);
    free(refimg);
    tr_scene_destroy(s);
}

int main(void) {
    test_passes();
    test_dfg();
    test_converges();
    return check_finish("test_specular");
}
