/* test_punctual.c - point, spot and directional lights (src/kernel/punctual.h,
 * src/scene/punctual.c).
 *
 *  (a) A diffuse plane of albedo rho seen from above under each kind of light, rendered by
 *      pt: every pixel's mean matches the closed form rho/pi * I falloff cos / r^2 (point,
 *      spot) or rho/pi * E cos (directional), averaged over the pixel's footprint (8 x 8
 *      points), within 5 standard errors of the pixel's mean (the film's variance pass)
 *      plus 1e-4 of the value for the footprint's quadrature. Nine point lights (more than
 *      are each sampled at every vertex) exercise the power CDF's pick and its 1/prob.
 *  (b) The spot's falloff: 1 inside the inner cone, 0 outside the outer one, the
 *      smoothstep between, as the scene file's cone_angle and blend define the cones.
 *  (c) The CDF's steps are the lights' powers' shares.
 *  (d) Scene files: the keys and their refusals (file and key named), and naive refused
 *      for a scene with such lights when the file is applied, and by the renderer itself;
 *      bdpt and vcm (light subpaths from the lights, weighed with the camera side's light
 *      sample of them) agree with pt over the image. */
#define _DEFAULT_SOURCE /* setenv */
#include "check.h"
#include "scene_util.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define PI_D 3.14159265358979323846

enum { W = 32, H = 32 };

static const double RHO = 0.6;

/* What the plane y = 0 receives at x from light l, in double. */
static double irradiance(const tr_punctual *l, const double x[3]) {
    const double e = l->intensity.y; /* the tests use grey lights */
    if (l->type == TR_PUNCTUAL_DIRECTIONAL) {
        const double c = -(double)l->dir.y;
        return c > 0.0 ? e * c : 0.0;
    }
    const double d[3] = {l->pos.x - x[0], l->pos.y - x[1], l->pos.z - x[2]};
    const double r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2], r = sqrt(r2);
    const double c = d[1] / r;
    if (c <= 0.0) {
        return 0.0;
    }
    double k = 1.0;
    if (l->type == TR_PUNCTUAL_SPOT) {
        const double ca = -(d[0] * l->dir.x + d[1] * l->dir.y + d[2] * l->dir.z) / r;
        if (ca <= l->cos_outer) {
            k = 0.0;
        } else if (ca < l->cos_inner) {
            const double t = (ca - l->cos_outer) / ((double)l->cos_inner - l->cos_outer);
            k = t * t * (3.0 - 2.0 * t);
        }
    }
    return e * k * c / r2;
}

static tr_punctual light(uint32_t type, tr_vec3 pos, tr_vec3 dir, float intensity, float cone_deg,
                         float blend) {
    tr_punctual l;
    memset(&l, 0, sizeof l);
    l.type = type;
    l.pos = pos;
    l.dir = v3_normalize(dir);
    l.intensity = v3s(intensity);
    const double h = 0.5 * cone_deg * PI_D / 180.0;
    l.cos_outer = (float)cos(h);
    l.cos_inner = (float)cos(h * (1.0 - blend));
    return l;
}

/* (a) */
static void plane_under(const tr_punctual *lights, int n, const char *what) {
    tr_scene s = {0};
    tr_scene_init(&s);
    tr_error err;
    add_shape(&s, TR_SHAPE_PLANE, add_mat(&s, tr_material_diffuse(v3s((float)RHO))), v3s(0.0f),
              v3s(0.0f), v3(6.0f, 1.0f, 6.0f));
    for (int i = 0; i < n; ++i) {
        CHECK(tr_scene_add_punctual(&s, &lights[i], &err) == TR_OK, "%s: light: %s", what, err.msg);
    }
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "commit: %s", err.msg);
    tr_camera cam;
    CHECK(tr_camera_make(&cam, v3(0.0f, 2.5f, 0.0f), v3(0, -1, 0), v3(0, 0, 1), 70.0f, 0.001f,
                         1e30f, W, H, &err) == TR_OK,
          "camera: %s", err.msg);
    tr_film f;
    CHECK(tr_film_init_passes(&f, W, H, TR_PASS_VARIANCE, &err) == TR_OK, "%s", err.msg);
    tr_render_config cfg = tr_render_config_default();
    cfg.seed = 5;
    cfg.threads = 2;
    cfg.passes = TR_PASS_VARIANCE;
    for (uint32_t k = 0; k < 64; ++k) {
        CHECK(tr_render_frame(&s, &cam, &cfg, &f, k, NULL, &err) == TR_OK, "frame: %s", err.msg);
    }
    int bad = 0;
    double worst = 0.0, lit = 0.0;
    for (uint32_t y = 0; y < H; ++y) {
        for (uint32_t x = 0; x < W; ++x) {
            double expect = 0.0;
            for (int j = 0; j < 64; ++j) {
                const tr_ray r = tr_camera_ray(&cam, (float)x, (float)y, ((j % 8) + 0.5f) / 8.0f,
                                               ((j / 8) + 0.5f) / 8.0f);
                const double t = -(double)r.origin.y / r.dir.y;
                const double p[3] = {r.origin.x + t * r.dir.x, 0.0, r.origin.z + t * r.dir.z};
                for (int i = 0; i < n; ++i) {
                    expect += RHO / PI_D * irradiance(&lights[i], p) / 64.0;
                }
            }
            const tr_vec3 got = tr_film_pixel(&f, x, y);
            float var[3];
            CHECK(tr_film_pass_pixel(&f, TR_PASS_VARIANCE, x, y, var, &err) == TR_OK, "%s",
                  err.msg);
            const double bound = 5.0 * sqrt((double)var[1]) + 1e-4 * expect + 1e-7;
            const double e = fabs((double)got.y - expect);
            bad += e > bound;
            worst = fmax(worst, e / bound);
            lit += expect > 0.0;
            if (e > bound && bad <= 3) {
                fprintf(stderr, "%s: pixel (%u, %u): %.6g, closed form %.6g (bound %.3g)\n", what,
                        x, y, (double)got.y, expect, bound);
            }
        }
    }
    CHECK(bad == 0, "%s: %d pixels off the closed form", what, bad);
    CHECK(lit > W * H / 8, "%s: only %g pixels lit", what, lit);
    printf("%s: worst error %.3f of its bound\n", what, worst);
    tr_film_free(&f);
    tr_scene_clear(&s);
}

static void renders(void) {
    const tr_punctual point =
        light(TR_PUNCTUAL_POINT, v3(0.3f, 1.0f, -0.2f), v3s(0.0f), 2.0f, 0, 0);
    plane_under(&point, 1, "point");
    const tr_punctual spot =
        light(TR_PUNCTUAL_SPOT, v3(-0.2f, 1.2f, 0.1f), v3(0.3f, -1.0f, 0.2f), 3.0f, 60.0f, 0.4f);
    plane_under(&spot, 1, "spot");
    const tr_punctual hard =
        light(TR_PUNCTUAL_SPOT, v3(0.2f, 0.9f, 0.0f), v3(0.0f, -1.0f, 0.0f), 1.5f, 80.0f, 0.0f);
    plane_under(&hard, 1, "spot without blend");
    const tr_punctual sun =
        light(TR_PUNCTUAL_DIRECTIONAL, v3s(0.0f), v3(1.0f, -2.0f, 0.5f), 1.3f, 0, 0);
    plane_under(&sun, 1, "directional");
    tr_punctual many[9];
    for (int i = 0; i < 9; ++i) {
        many[i] =
            light(TR_PUNCTUAL_POINT, v3(-1.2f + 0.3f * i, 0.6f + 0.1f * (i % 3), 0.4f * (i % 2)),
                  v3s(0.0f), 0.2f + 0.1f * i, 0, 0);
    }
    plane_under(many, 9, "nine point lights");
}

/* (b) and (c) */
static void falloff_and_cdf(void) {
    tr_scene s = {0};
    tr_scene_init(&s);
    tr_error err;
    add_shape(&s, TR_SHAPE_PLANE, add_mat(&s, tr_material_diffuse(v3s(0.5f))), v3s(0.0f), v3s(0.0f),
              v3(2.0f, 1.0f, 2.0f));
    /* cone_angle 40, blend 0.25: the outer cone's half-angle 20 degrees, the inner 15. */
    const tr_punctual spot =
        light(TR_PUNCTUAL_SPOT, v3(0.0f, 1.0f, 0.0f), v3(0, -1, 0), 4.0f, 40.0f, 0.25f);
    const tr_punctual point = light(TR_PUNCTUAL_POINT, v3(1, 1, 1), v3s(0.0f), 2.0f, 0, 0);
    const tr_punctual dir = light(TR_PUNCTUAL_DIRECTIONAL, v3s(0.0f), v3(0, -1, 0), 0.5f, 0, 0);
    CHECK(tr_scene_add_punctual(&s, &spot, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_scene_add_punctual(&s, &point, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_scene_add_punctual(&s, &dir, &err) == TR_OK, "%s", err.msg);
    tr_scene_view v = tr_scene_view_of(&s);
    CHECK(v.punctual_count == 0, "lights before a commit are not exposed (%u)", v.punctual_count);
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "commit: %s", err.msg);
    v = tr_scene_view_of(&s);
    CHECK(v.punctual_count == 3, "3 lights exposed (%u)", v.punctual_count);
    const double deg = PI_D / 180.0;
    for (int k = 0; k <= 40; ++k) {
        const double a = 0.5 * k * deg; /* 0 .. 20 degrees from the axis */
        const tr_vec3 p = v3((float)tan(a), 0.0f, 0.0f);
        tr_vec3 wi;
        float dist;
        const tr_vec3 li = tr_punctual_incident(&v.punctual[0], p, &wi, &dist);
        const double r2 = 1.0 + tan(a) * tan(a);
        double f = 1.0;
        if (a >= 20.0 * deg - 1e-6) {
            f = 0.0;
        } else if (a > 15.0 * deg + 1e-6) {
            const double t = (cos(a) - cos(20.0 * deg)) / (cos(15.0 * deg) - cos(20.0 * deg));
            f = t * t * (3.0 - 2.0 * t);
        }
        CHECK(fabs(li.x - 4.0 * f / r2) <= 2e-4 * 4.0 / r2 + 1e-6,
              "spot at %.1f degrees: %.6g, expected %.6g", a / deg, (double)li.x, 4.0 * f / r2);
        CHECK_NEAR(dist, sqrt(r2), 1e-5, "distance to the spot");
    }
    /* The directional light: E from -dir, at no distance. */
    tr_vec3 wi;
    float dist;
    tr_vec3 e = tr_punctual_incident(&v.punctual[2], v3(5, 0, 5), &wi, &dist);
    CHECK(e.x == 0.5f && wi.y == 1.0f && isinf(dist), "directional: %g from (%g, %g, %g)",
          (double)e.x, (double)wi.x, (double)wi.y, (double)wi.z);
    /* Powers: the spot's cone to the middle of its blend, the point's sphere, the
     * directional light's disc of the bounding sphere (the 2 x 2 plane: radius sqrt 2). */
    const double pw[3] = {2.0 * PI_D * (1.0 - 0.5 * (cos(15.0 * deg) + cos(20.0 * deg))) * 4.0,
                          4.0 * PI_D * 2.0, PI_D * 2.0 * 0.5};
    const double total = pw[0] + pw[1] + pw[2];
    double prev = 0.0, acc = 0.0;
    for (int i = 0; i < 3; ++i) {
        acc += pw[i];
        CHECK(fabs(v.punctual[i].cdf - prev - pw[i] / total) <= 1e-5, "light %d: p %.6f vs %.6f", i,
              v.punctual[i].cdf - prev, pw[i] / total);
        float prob;
        const uint32_t k = tr_punctual_pick(&v, (float)(prev + 0.5 * pw[i] / total), &prob);
        CHECK(k == (uint32_t)i && fabs(prob - pw[i] / total) <= 1e-5, "pick %d: %u, p %g", i, k,
              (double)prob);
        prev = v.punctual[i].cdf;
    }
    CHECK(v.punctual[2].cdf == 1.0f, "the CDF ends at 1");
    /* Refused lights. */
    tr_punctual bad = point;
    bad.intensity = v3(-1.0f, 0.0f, 0.0f);
    CHECK_STATUS(tr_scene_add_punctual(&s, &bad, &err), err, TR_STATUS_INVALID_ARGUMENT,
                 "negative intensity");
    bad = spot;
    bad.dir = v3s(0.0f);
    CHECK_STATUS(tr_scene_add_punctual(&s, &bad, &err), err, TR_STATUS_INVALID_ARGUMENT,
                 "zero direction");
    bad = spot;
    bad.cos_inner = bad.cos_outer - 0.1f;
    CHECK_STATUS(tr_scene_add_punctual(&s, &bad, &err), err, TR_STATUS_INVALID_ARGUMENT,
                 "inner cone outside the outer");
    bad = point;
    bad.type = 7;
    CHECK_STATUS(tr_scene_add_punctual(&s, &bad, &err), err, TR_STATUS_INVALID_ARGUMENT, "type 7");
    /* naive refuses the scene; bdpt, vcm and pt render it. */
    tr_film f;
    CHECK(tr_film_init(&f, 8, 8, &err) == TR_OK, "%s", err.msg);
    tr_camera cam;
    CHECK(tr_camera_make(&cam, v3(0, 2, 0), v3(0, -1, 0), v3(0, 0, 1), 60.0f, 0.001f, 1e30f, 8, 8,
                         &err) == TR_OK,
          "%s", err.msg);
    const int integrators[4] = {TR_INTEGRATOR_NAIVE, TR_INTEGRATOR_BDPT, TR_INTEGRATOR_VCM,
                                TR_INTEGRATOR_PT};
    /* Light subpaths start from the lights (a plane lit directly: light tracing and the
     * light sample share the weight), so bdpt's and vcm's images are other estimates of
     * pt's: their sums over the image and frames agree with pt's within 2 %. */
    static tr_vec3 img[4][64];
    double sums[4] = {0.0, 0.0, 0.0, 0.0};
    /* Merges of a quarter pixel: the default radius, 3 pixels of this 8-pixel image,
     * would lose the light its merges miss beyond the plane's edges. */
    setenv("TRAC0R_VCM_RADIUS", "0.25", 1);
    for (int k = 0; k < 4; ++k) {
        tr_render_config cfg = tr_render_config_default();
        cfg.integrator = integrators[k];
        cfg.threads = 1;
        cfg.max_depth = 5;
        tr_film_clear(&f);
        const int rc = tr_render_frame(&s, &cam, &cfg, &f, 0, NULL, &err);
        if (k < 1) { /* naive has no next-event estimation */
            CHECK_STATUS(rc, err, TR_STATUS_UNSUPPORTED, tr_integrator_name(integrators[k]));
            CHECK_STATUS(tr_integrator_supports(&s, integrators[k], &err), err,
                         TR_STATUS_UNSUPPORTED, tr_integrator_name(integrators[k]));
            continue;
        }
        CHECK(rc == TR_OK, "%s: %s", tr_integrator_name(integrators[k]), err.msg);
        for (uint32_t fr = 1; fr <= 64u && rc == TR_OK; ++fr) {
            for (uint32_t i = 0; i < 64u; ++i) {
                img[k][i] = tr_film_pixel(&f, i % 8u, i / 8u);
                sums[k] += (double)img[k][i].x + img[k][i].y + img[k][i].z;
            }
            if (fr < 64u) {
                tr_film_clear(&f);
                CHECK(tr_render_frame(&s, &cam, &cfg, &f, fr, NULL, &err) == TR_OK, "%s: %s",
                      tr_integrator_name(integrators[k]), err.msg);
            }
        }
    }
    unsetenv("TRAC0R_VCM_RADIUS");
    for (int k = 1; k < 3; ++k) {
        CHECK(sums[3] > 0.0 && fabs(sums[k] - sums[3]) <= 0.02 * sums[3],
              "%s against pt: image sum %g, pt's %g", tr_integrator_name(integrators[k]), sums[k],
              sums[3]);
        printf("%s against pt: image sums %g, %g\n", tr_integrator_name(integrators[k]), sums[k],
               sums[3]);
    }
    tr_film_free(&f);
    tr_scene_clear(&s);
}

static int parse(const char *lights, tr_scene *s, tr_scene_file *info, tr_error *err) {
    char text[2048];
    snprintf(text, sizeof text,
             "{\"camera\": {\"position\": [0, 2, -3], \"look_at\": [0, 0, 0], \"fov\": 40},\n"
             " \"materials\": {\"w\": {\"type\": \"diffuse\", \"color\": [0.5, 0.5, 0.5]}},\n"
             " \"shapes\": [{\"type\": \"plane\", \"material\": \"w\"}],\n"
             " \"lights\": %s}",
             lights);
    return tr_scene_file_parse(s, "lights.json", text, strlen(text), NULL, info, err);
}

/* (d) */
static void scene_files(void) {
    tr_error err;
    tr_scene s = {0};
    tr_scene_file info;
    const char *good =
        "[{\"type\": \"point\", \"position\": [0, 1, 0], \"intensity\": 2, \"color\": [1, 0.5, "
        "0.25]},\n"
        " {\"type\": \"spot\", \"name\": \"key\", \"position\": [1, 2, 0], \"direction\": [0, -2, "
        "0], \"cone_angle\": 60, \"blend\": 0.5},\n"
        " {\"type\": \"directional\", \"direction\": [0, -1, 1], \"irradiance\": 3}]";
    CHECK(parse(good, &s, &info, &err) == TR_OK, "lights: %s", err.msg);
    CHECK(s.punctual_count == 3, "3 lights (%u)", s.punctual_count);
    if (s.punctual_count == 3) {
        const tr_punctual *l = s.punctual;
        CHECK(l[0].type == TR_PUNCTUAL_POINT && l[0].intensity.x == 2.0f &&
                  l[0].intensity.y == 1.0f && l[0].intensity.z == 0.5f,
              "point: intensity x colour");
        CHECK(l[1].type == TR_PUNCTUAL_SPOT && l[1].intensity.x == 1.0f && l[1].dir.y == -1.0f,
              "spot: defaults and a unit axis");
        CHECK_NEAR(l[1].cos_outer, cos(30.0 * PI_D / 180.0), 1e-6, "spot: outer cone");
        CHECK_NEAR(l[1].cos_inner, cos(15.0 * PI_D / 180.0), 1e-6, "spot: inner cone");
        CHECK(l[2].type == TR_PUNCTUAL_DIRECTIONAL && l[2].intensity.z == 3.0f &&
                  fabsf(l[2].dir.z - sqrtf(0.5f)) < 1e-6f,
              "directional");
    }
    CHECK(info.allow_no_emitter && info.emissive_triangles == 0,
          "lights are enough: no emitter needed");
    const char *names[4] = {"naive", "bdpt", "vcm", "pt"};
    for (int k = 0; k < 4; ++k) {
        tr_render_request req = {0};
        req.integrator = names[k];
        tr_render_settings st;
        const int rc = tr_scene_file_apply(&s, "lights.json", &info, &req, &st, &err);
        if (k < 1) {
            CHECK_STATUS(rc, err, TR_STATUS_UNSUPPORTED, names[k]);
            CHECK(strstr(err.msg, "lights.json") && strstr(err.msg, "lights"),
                  "%s: the refusal names the file and the key: %s", names[k], err.msg);
        } else {
            CHECK(rc == TR_OK, "%s: %s", names[k], err.msg);
        }
    }
    tr_scene_clear(&s);
    /* Each refusal names the file and the key at fault. */
    const char *bad[] = {
        "{\"type\": \"point\"}",
        "[{\"type\": \"area\", \"position\": [0, 1, 0]}]",
        "[{\"type\": \"point\", \"position\": [0, 1, 0], \"intensity\": -1}]",
        "[{\"type\": \"point\", \"position\": [0, 1, 0], \"direction\": [0, -1, 0]}]",
        "[{\"type\": \"spot\", \"position\": [0, 1, 0]}]",
        "[{\"type\": \"spot\", \"position\": [0, 1, 0], \"direction\": [0, 0, 0]}]",
        "[{\"type\": \"spot\", \"position\": [0, 1, 0], \"direction\": [0, -1, 0], \"blend\": 2}]",
        "[{\"type\": \"spot\", \"position\": [0, 1, 0], \"direction\": [0, -1, 0], "
        "\"cone_angle\": 0}]",
        "[{\"type\": \"directional\", \"direction\": [0, -1, 0], \"intensity\": 1}]",
        "[{\"type\": \"directional\"}]",
        "[{\"type\": \"point\", \"position\": [0, 1, 0], \"color\": [1, -1, 0]}]"};
    const char *key[] = {"lights",
                         "lights[0].type",
                         "lights[0].intensity",
                         "lights[0]",
                         "lights[0].direction",
                         "lights[0].direction",
                         "lights[0].blend",
                         "lights[0].cone_angle",
                         "lights[0]",
                         "lights[0].direction",
                         "lights[0].color"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        tr_scene b = {0};
        CHECK_STATUS(parse(bad[i], &b, NULL, &err), err, TR_STATUS_PARSE, bad[i]);
        CHECK(strstr(err.msg, "lights.json") && strstr(err.msg, key[i]),
              "refusal %zu names the file and %s: %s", i, key[i], err.msg);
    }
}

int main(void) {
    falloff_and_cdf();
    scene_files();
    renders();
    return check_finish("test_punctual");
}
