/* test_sun.c - the sun: a distant disc with an angular size (src/kernel/sun.h).
 *
 * 1. Sampling: every drawn direction lies in the cone, the mean cosine to the axis is the
 *    uniform cone's 1 - (1 - cos t) / 2, and the density tr_sun_pdf gives is 1 / the
 *    cone's solid angle inside and 0 outside.
 * 2. Analytic: a diffuse plane facing up under a sun 60 degrees from the zenith renders
 *    albedo / pi x E x cos 60 (the cone's integral of the cosine is exact for any disc
 *    above the horizon), with pt (light sampling + MIS) and with naive (escaping rays
 *    only), each within 5 standard errors estimated from the pixels' spread.
 * 3. MIS: the reflection of a 12-degree sun in a rough glossy plane, where both strategies
 *    matter, rendered by pt (light sampling and BSDF sampling weighted by MIS) agrees
 *    within 5 combined standard errors with BSDF sampling alone and with light sampling
 *    alone (Monte Carlo in the test over the same material).
 * 4. Scene files: a sun with a zero direction, a negative or too large angle, a negative
 *    irradiance or an unknown key is refused with a parse error and no sun; a good one
 *    sets the disc so that radiance x pi sin^2 t is the irradiance; that scene's image by
 *    bdpt and vcm (light subpaths from the sun among their strategies) agrees with pt's.
 * 5. The sun's limit, a directional light (src/kernel/punctual.h) of irradiance E from 60
 *    degrees: the plane renders albedo / pi x E x cos 60 with pt, and with bdpt and vcm,
 *    whose light subpaths start from it on the disc that covers the scene as the sun's. */
#define _DEFAULT_SOURCE
#include "check.h"
#include "scene_util.h"
#include "kernel/sun.h"
#include "trac0r/device.h"
#include "trac0r/scene_file.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define PI_D 3.14159265358979323846

static void test_sampling(void) {
    tr_scene s = {0};
    tr_scene_init(&s);
    tr_error err;
    CHECK(tr_scene_set_sun(&s, v3(1.0f, 2.0f, -0.5f), 8.0f, v3s(1.0f), &err) == TR_OK, "%s",
          err.msg);
    tr_scene_view v = tr_scene_view_of(&s);
    const double omc = 1.0 - cos(4.0 * PI_D / 180.0);
    CHECK(fabs(s.sun.one_minus_cos - omc) < 1e-6 * omc, "1 - cos t %g vs %g",
          (double)s.sun.one_minus_cos, omc);
    tr_rng rng;
    tr_rng_init(&rng, 7u, 1u, 0u);
    const int n = 200000;
    double sum_cos = 0.0;
    int outside = 0;
    for (int i = 0; i < n; ++i) {
        tr_vec3 d;
        float pdf;
        tr_sun_sample(&v, tr_rng_float(&rng), tr_rng_float(&rng), &d, &pdf);
        outside += !tr_sun_contains(&s.sun, d) || fabsf(v3_length(d) - 1.0f) > 1e-5f;
        sum_cos += v3_dot(d, s.sun.dir);
        CHECK(pdf == tr_sun_pdf(&v, d), "sample's pdf");
    }
    /* cos is uniform on [1 - omc, 1]: variance omc^2 / 12. */
    const double mean = sum_cos / n, want = 1.0 - 0.5 * omc, se = omc / sqrt(12.0 * n);
    CHECK(outside == 0, "%d of %d directions outside the cone", outside, n);
    CHECK(fabs(mean - want) <= 5.0 * se + 1e-7, "mean cos %.8f vs %.8f (se %.2g)", mean, want, se);
    CHECK(fabs((double)s.sun.pdf * 2.0 * PI_D * omc - 1.0) < 1e-5, "pdf x solid angle");
    tr_vec3 away = v3_normalize(v3(1.0f, 2.0f, 0.5f));
    CHECK(tr_sun_pdf(&v, away) == 0.0f && tr_sun_radiance(&v, away).x == 0.0f,
          "outside the cone: no density, no radiance");
    tr_scene_clear(&s);
}

/* Renders spp samples of a w x w image of scene s from straight above with integrator
 * `integ`; returns the mean and the standard error of channel c over the pixels. */
static void render_mean(tr_scene *s, int integ, uint32_t w, uint32_t spp, int c, double *mean,
                        double *se) {
    tr_error err;
    tr_camera cam;
    CHECK(tr_camera_make(&cam, v3(0.0f, 2.0f, 0.0f), v3(0.0f, -1.0f, 0.0f), v3(0.0f, 0.0f, -1.0f),
                         30.0f, 1e-3f, 1e3f, w, w, &err) == TR_OK,
          "%s", err.msg);
    tr_film film;
    CHECK(tr_film_init(&film, w, w, &err) == TR_OK, "%s", err.msg);
    tr_render_config cfg = tr_render_config_default();
    cfg.integrator = integ;
    cfg.max_depth = 8;
    cfg.seed = 11u;
    for (uint32_t k = 0; k < spp; ++k) {
        CHECK(tr_render_frame(s, &cam, &cfg, &film, k, NULL, &err) == TR_OK, "%s", err.msg);
    }
    double m = 0.0, m2 = 0.0;
    const double n = (double)w * w;
    for (uint32_t y = 0; y < w; ++y) {
        for (uint32_t x = 0; x < w; ++x) {
            tr_vec3 p = tr_film_pixel(&film, x, y);
            double val = c == 0 ? p.x : c == 1 ? p.y : p.z;
            m += val / n;
            m2 += val * val / n;
        }
    }
    *mean = m;
    *se = sqrt(fmax(0.0, m2 - m * m) / (n - 1.0));
    tr_film_free(&film);
}

/* A plane of albedo (material mat) facing +y, under a sun 60 degrees from the zenith. */
static void sun_plane(tr_scene *s, tr_material mat, float angle, tr_vec3 e) {
    tr_error err;
    tr_scene_init(s);
    uint32_t m = add_mat(s, mat);
    add_shape(s, TR_SHAPE_PLANE, m, v3s(0.0f), v3s(0.0f), v3(100.0f, 1.0f, 100.0f));
    CHECK(tr_scene_set_sun(s, v3(sinf(1.04719755f), cosf(1.04719755f), 0.0f), angle, e, &err) ==
              TR_OK,
          "%s", err.msg);
    CHECK(tr_scene_commit(s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
}

static void test_analytic(void) {
    const float albedo = 0.6f;
    const tr_vec3 e = v3(1.0f, 2.0f, 3.0f);
    tr_scene s;
    /* pt: a small disc (the Sun's size), found by light sampling. */
    sun_plane(&s, tr_material_diffuse(v3s(albedo)), 0.526f, e);
    for (int c = 0; c < 3; ++c) {
        const double ec = c == 0 ? e.x : c == 1 ? e.y : e.z;
        const double want = albedo / PI_D * ec * 0.5;
        double m, se;
        render_mean(&s, TR_INTEGRATOR_PT, 16, 4, c, &m, &se);
        CHECK(fabs(m - want) <= 5.0 * se + 1e-4 * want, "pt channel %d: %.5f vs %.5f (se %.2g)", c,
              m, want, se);
        printf("sun pt channel %d: %.5f vs analytic %.5f (se %.2g)\n", c, m, want, se);
    }
    tr_scene_clear(&s);
    /* naive: a wider disc, which escaping rays find often enough. */
    sun_plane(&s, tr_material_diffuse(v3s(albedo)), 40.0f, e);
    const double want = albedo / PI_D * e.y * 0.5;
    double m, se;
    render_mean(&s, TR_INTEGRATOR_NAIVE, 16, 256, 1, &m, &se);
    CHECK(fabs(m - want) <= 5.0 * se && se < 0.05 * want, "naive: %.5f vs %.5f (se %.2g)", m, want,
          se);
    printf("sun naive: %.5f vs analytic %.5f (se %.2g)\n", m, want, se);
    tr_scene_clear(&s);
}

/* One-bounce radiance off the glossy plane towards wo by the BSDF strategy alone (a
 * sampled direction that meets the disc) and by light sampling alone: mean and standard
 * error over n samples. */
static void one_bounce(const tr_scene_view *v, const tr_bsdf_params *m, tr_vec3 wo, int bsdf, int n,
                       double *mean, double *se) {
    tr_rng rng;
    tr_rng_init(&rng, 99u, bsdf ? 1u : 2u, 0u);
    double s1 = 0.0, s2 = 0.0;
    for (int i = 0; i < n; ++i) {
        double x = 0.0;
        if (bsdf) {
            tr_scatter bs;
            float a = tr_rng_float(&rng), b = tr_rng_float(&rng), c = tr_rng_float(&rng);
            if (tr_bsdf_sample(m, wo, a, b, c, &bs) && !bs.delta) {
                x = bs.weight.x * tr_sun_radiance(v, bs.wi).x;
            }
        } else {
            tr_vec3 wi;
            float pl;
            tr_vec3 le = tr_sun_sample(v, tr_rng_float(&rng), tr_rng_float(&rng), &wi, &pl);
            x = tr_bsdf_eval(m, wo, wi).x * le.x * fabsf(v3_dot(wi, m->ns)) / pl;
        }
        s1 += x;
        s2 += x * x;
    }
    *mean = s1 / n;
    *se = sqrt(fmax(0.0, s2 / n - *mean * *mean) / (n - 1.0));
}

static void test_mis(void) {
    tr_scene s;
    sun_plane(&s, tr_material_glossy(v3s(0.8f), 0.3f), 12.0f, v3s(1.0f));
    /* Seen from far along the sun's mirror direction through a narrow lens: every pixel
     * shows the plane's reflection of the disc from (nearly) the same wo. */
    const tr_vec3 wo = v3(-sinf(1.04719755f), cosf(1.04719755f), 0.0f);
    tr_error err;
    tr_camera cam;
    CHECK(tr_camera_make(&cam, v3_scale(wo, 1000.0f), v3_neg(wo), v3(0.0f, 1.0f, 0.0f), 0.02f,
                         1e-3f, 1e4f, 8, 8, &err) == TR_OK,
          "%s", err.msg);
    tr_film film;
    CHECK(tr_film_init(&film, 8, 8, &err) == TR_OK, "%s", err.msg);
    tr_render_config cfg = tr_render_config_default();
    cfg.max_depth = 8;
    for (uint32_t k = 0; k < 256; ++k) {
        CHECK(tr_render_frame(&s, &cam, &cfg, &film, k, NULL, &err) == TR_OK, "%s", err.msg);
    }
    double mp = 0.0, m2 = 0.0;
    for (uint32_t y = 0; y < 8; ++y) {
        for (uint32_t x = 0; x < 8; ++x) {
            double val = tr_film_pixel(&film, x, y).x;
            mp += val / 64.0;
            m2 += val * val / 64.0;
        }
    }
    const double sp = sqrt(fmax(0.0, m2 - mp * mp) / 63.0);
    tr_film_free(&film);
    tr_scene_view v = tr_scene_view_of(&s);
    tr_bsdf_params m =
        tr_material_eval(&v, 0, 0.3f, 0.3f, v3s(0.0f), s.triangles[0].normal, v3_neg(wo));
    double mb, sb, ml, sl;
    one_bounce(&v, &m, wo, 1, 400000, &mb, &sb);
    one_bounce(&v, &m, wo, 0, 100000, &ml, &sl);
    CHECK(fabs(mp - mb) <= 5.0 * sqrt(sp * sp + sb * sb) && sb < 0.03 * mb,
          "pt (MIS) %.5f vs BSDF sampling alone %.5f (se %.2g, %.2g)", mp, mb, sp, sb);
    CHECK(fabs(mp - ml) <= 5.0 * sqrt(sp * sp + sl * sl) && sl < 0.03 * ml,
          "pt (MIS) %.5f vs light sampling alone %.5f (se %.2g, %.2g)", mp, ml, sp, sl);
    printf("sun on glossy: pt (MIS) %.5f (se %.2g), BSDF alone %.5f (se %.2g), light alone %.5f "
           "(se %.2g)\n",
           mp, sp, mb, sb, ml, sl);
    tr_scene_clear(&s);
}

static int parse(const char *sun, tr_scene *s, tr_error *err) {
    char text[1024];
    snprintf(text, sizeof text,
             "{\"camera\": {\"position\": [0, 2, 0.01], \"look_at\": [0, 0, 0], \"fov\": 40},"
             " \"materials\": {\"w\": {\"type\": \"diffuse\", \"color\": [0.5, 0.5, 0.5]}},"
             " \"shapes\": [{\"type\": \"plane\", \"material\": \"w\"}], \"sun\": %s}",
             sun);
    return tr_scene_file_parse(s, "sun.json", text, strlen(text), NULL, NULL, err);
}

static void test_scene_file(void) {
    static const char *const bad[] = {
        "{\"direction\": [0, 0, 0]}",
        "{\"direction\": [0, 1]}",
        "{\"direction\": [0, 1, 0], \"angle\": -1}",
        "{\"direction\": [0, 1, 0], \"angle\": 0}",
        "{\"direction\": [0, 1, 0], \"angle\": 120}",
        "{\"direction\": [0, 1, 0], \"irradiance\": -2}",
        "{\"direction\": [0, 1, 0], \"irradiance\": [1, -1, 1]}",
        "{\"direction\": [0, 1, 0], \"strength\": 1}",
        "{\"angle\": 1}",
        "[0, 1, 0]",
    };
    tr_scene s;
    tr_scene_init(&s);
    tr_error err;
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        err.code = TR_STATUS_OK;
        CHECK(parse(bad[i], &s, &err) == TR_ERR && err.code == TR_STATUS_PARSE && s.sun_count == 0,
              "sun %s: expected a parse error (got code %d)", bad[i], (int)err.code);
    }
    CHECK(parse("{\"direction\": [0, 3, 4], \"angle\": 2, \"irradiance\": [1, 2, 4]}", &s, &err) ==
              TR_OK,
          "%s", err.msg);
    CHECK(s.sun_count == 1 && fabsf(s.sun.dir.y - 0.6f) < 1e-6f &&
              fabsf(s.sun.dir.z - 0.8f) < 1e-6f,
          "direction normalised");
    const double st = sin(1.0 * PI_D / 180.0);
    CHECK(fabs(s.sun.radiance.z * PI_D * st * st - 4.0) < 1e-4, "radiance x pi sin^2 t = E");
    /* bdpt and vcm start light subpaths from the sun too (a direction in its cone, an
     * origin on the disc that covers the scene) and weigh them with the camera side's
     * light samples and escapes: their image agrees with pt's. Per-frame image sums, 96
     * frames each; the means must agree within 5 standard errors (from the frames' spread),
     * and the difference must be small in absolute terms too. */
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
    tr_film film;
    CHECK(tr_film_init(&film, 8, 8, &err) == TR_OK, "film: %s", err.msg);
    tr_camera cam = *tr_scene_camera(&s);
    CHECK(tr_camera_resize(&cam, 8, 8, &err) == TR_OK, "%s", err.msg);
    const int integrators[3] = {TR_INTEGRATOR_PT, TR_INTEGRATOR_BDPT, TR_INTEGRATOR_VCM};
    double mean[3], se[3];
    setenv("TRAC0R_VCM_RADIUS", "0.5", 1);
    for (int k = 0; k < 3; ++k) {
        tr_render_config cfg = tr_render_config_default();
        cfg.max_depth = 6;
        cfg.integrator = integrators[k];
        cfg.seed = 11u + (uint64_t)k;
        const int frames = 96;
        double s1 = 0.0, s2 = 0.0;
        for (int f = 0; f < frames; ++f) {
            tr_film_clear(&film);
            CHECK(tr_render_frame(&s, &cam, &cfg, &film, (uint32_t)f, NULL, &err) == TR_OK,
                  "%s with a sun: %s", tr_integrator_name(integrators[k]), err.msg);
            double sum = 0.0;
            for (uint32_t y = 0; y < 8u; ++y) {
                for (uint32_t x = 0; x < 8u; ++x) {
                    const tr_vec3 a = tr_film_pixel(&film, x, y);
                    sum += a.x + a.y + a.z;
                }
            }
            s1 += sum;
            s2 += sum * sum;
        }
        mean[k] = s1 / frames;
        se[k] = sqrt(fmax(s2 / frames - mean[k] * mean[k], 0.0) / (frames - 1));
    }
    unsetenv("TRAC0R_VCM_RADIUS");
    for (int k = 1; k < 3; ++k) {
        const double d = fabs(mean[k] - mean[0]), e = sqrt(se[0] * se[0] + se[k] * se[k]);
        CHECK(mean[0] > 0.0 && d <= 5.0 * e && d <= 0.02 * mean[0],
              "%s with a sun: image sum %g, pt's %g (standard error %g)",
              tr_integrator_name(integrators[k]), mean[k], mean[0], e);
        printf("sun, %s against pt: %.2f standard errors (%.3g%%)\n",
               tr_integrator_name(integrators[k]), d / e, 100.0 * d / mean[0]);
    }
    tr_film_free(&film);
    tr_scene_clear(&s);
}

static void test_directional(void) {
    const float albedo = 0.6f;
    const tr_vec3 e = v3(1.0f, 2.0f, 3.0f);
    tr_error err;
    tr_scene s;
    tr_scene_init(&s);
    uint32_t m = add_mat(&s, tr_material_diffuse(v3s(albedo)));
    add_shape(&s, TR_SHAPE_PLANE, m, v3s(0.0f), v3s(0.0f), v3(4.0f, 1.0f, 4.0f));
    tr_punctual l;
    memset(&l, 0, sizeof l);
    l.type = TR_PUNCTUAL_DIRECTIONAL;
    l.dir = v3(-sinf(1.04719755f), -cosf(1.04719755f), 0.0f); /* the way the light travels */
    l.intensity = e;
    CHECK(tr_scene_add_punctual(&s, &l, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
    const int integ[3] = {TR_INTEGRATOR_PT, TR_INTEGRATOR_BDPT, TR_INTEGRATOR_VCM};
    for (int k = 0; k < 3; ++k) {
        for (int c = 0; c < 3; c += 2) {
            const double ec = c == 0 ? e.x : e.z;
            const double want = albedo / PI_D * ec * 0.5;
            double mean, se;
            render_mean(&s, integ[k], 16, 16, c, &mean, &se);
            CHECK(fabs(mean - want) <= 5.0 * se + 1e-3 * want,
                  "directional light, %s channel %d: %.5f vs %.5f (se %.2g)",
                  tr_integrator_name(integ[k]), c, mean, want, se);
            printf("directional light, %s channel %d: %.5f vs analytic %.5f (se %.2g)\n",
                   tr_integrator_name(integ[k]), c, mean, want, se);
        }
    }
    tr_scene_clear(&s);
}

int main(void) {
    test_sampling();
    test_analytic();
    test_mis();
    test_scene_file();
    test_directional();
    return check_finish("test_sun");
}
