/* test_lens.c - the thin-lens camera (tr_camera_set_lens, src/kernel/camera.h).
 *
 *  (a) Circle of confusion: a small emissive sphere on the axis, off the plane in focus,
 *      images as a uniform disc whose diameter the thin-lens formula gives,
 *      2 A |1/F - 1/z| on the image plane at distance 1.
 *
 *      The formula: a thin lens of focal length f and aperture radius A focused at
 *      distance F has its sensor at v_F behind it, 1/f = 1/F + 1/v_F; a point at distance
 *      z comes to a focus at v_z, 1/f = 1/z + 1/v_z. Its rays fill the cone from the
 *      aperture's disc to that focus, which the sensor cuts in a disc of diameter
 *      c = 2 A |v_F - v_z| / v_z (similar triangles). Seen from the lens's centre, the
 *      sensor at v_F maps to an image plane at distance 1 by 1 / v_F:
 *      c / v_F = 2 A |1/v_z - 1/v_F| = 2 A |(1/f - 1/z) - (1/f - 1/F)| = 2 A |1/F - 1/z|,
 *      in which f has gone: trac0r's camera (image plane at distance 1, the lens's rays
 *      aimed at the pinhole ray's point on the plane in focus, camera.h) is that lens.
 *
 *      Two measurements of the disc's radius R: the image's second moment about its
 *      centroid (a uniform disc of radius R has <r^2> = R^2 / 2; the sphere's own image, a
 *      disc of radius rho, adds rho^2 / 2 and a pixel's box 1/6 px^2), and its flux over
 *      its plateau (the disc spreads the sphere's flux evenly: inside, where the sphere's
 *      whole blur overlaps, every pixel holds flux / (pi R^2), whatever rho). Both must be
 *      within 2 % of the formula's diameter, for a sphere behind and one in front of the
 *      plane in focus, with pt and naive; in focus the image is the sphere's alone.
 *  (b) A radius of 0 renders bit for bit as a camera that never had a lens, whatever the
 *      focus distance, with pt and naive.
 *  (c) Lens rays: every ray through a pixel point meets the pinhole ray's point on the
 *      plane in focus, and starts on the lens's disc; the lens points are uniform on the
 *      disc (chi-square over rings and sectors of equal area).
 *  (d) Argument checks: negative, NaN or infinite radius, a focus distance <= 0; the
 *      f-number's radius; bdpt and vcm refuse a camera with an aperture.
 *  (e) Scene files: aperture_radius, f_number (with sensor_height), focus_distance and
 *      its default (look_at's distance along the view), and the refusals.
 *  (f) Focusing on a screen point (tr_scene_focus_distance, the viewer's F key): the
 *      distance along the view to a sphere under the point, against the ray-sphere
 *      intersection worked out here (within the icosphere's faceting); 0 off the sphere,
 *      off the screen and for an uncommitted scene. */
#include "check.h"
#include "scene_util.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define PI_D 3.14159265358979323846

enum { W = 96, H = 96 };

/* Second moment of the image's luminance about its centroid, in px^2 (pixel centres). */
static double image_second_moment(const tr_film *f) {
    double s0 = 0.0, sx = 0.0, sy = 0.0;
    for (uint32_t y = 0; y < f->height; ++y) {
        for (uint32_t x = 0; x < f->width; ++x) {
            tr_vec3 p = tr_film_pixel(f, x, y);
            double v = (double)p.x + p.y + p.z;
            s0 += v;
            sx += v * (x + 0.5);
            sy += v * (y + 0.5);
        }
    }
    if (!(s0 > 0.0)) {
        return -1.0;
    }
    const double cx = sx / s0, cy = sy / s0;
    double m2 = 0.0;
    for (uint32_t y = 0; y < f->height; ++y) {
        for (uint32_t x = 0; x < f->width; ++x) {
            tr_vec3 p = tr_film_pixel(f, x, y);
            double v = (double)p.x + p.y + p.z;
            double dx = x + 0.5 - cx, dy = y + 0.5 - cy;
            m2 += v * (dx * dx + dy * dy);
        }
    }
    return m2 / s0;
}

/* The diameter of a uniform disc image, 2 sqrt(flux / (pi plateau)), in px: the plateau
 * is the mean of the pixels within radius `inner` of the centroid. */
static double flux_diameter(const tr_film *f, double inner) {
    double s0 = 0.0, sx = 0.0, sy = 0.0;
    for (uint32_t y = 0; y < f->height; ++y) {
        for (uint32_t x = 0; x < f->width; ++x) {
            tr_vec3 p = tr_film_pixel(f, x, y);
            double v = (double)p.x + p.y + p.z;
            s0 += v;
            sx += v * (x + 0.5);
            sy += v * (y + 0.5);
        }
    }
    if (!(s0 > 0.0)) {
        return -1.0;
    }
    const double cx = sx / s0, cy = sy / s0;
    double in = 0.0;
    int n = 0;
    for (uint32_t y = 0; y < f->height; ++y) {
        for (uint32_t x = 0; x < f->width; ++x) {
            const double dx = x + 0.5 - cx, dy = y + 0.5 - cy;
            if (dx * dx + dy * dy <= inner * inner) {
                tr_vec3 p = tr_film_pixel(f, x, y);
                in += (double)p.x + p.y + p.z;
                ++n;
            }
        }
    }
    if (n == 0 || !(in > 0.0)) {
        return -1.0;
    }
    return 2.0 * sqrt(s0 / (in / n) / PI_D);
}

/* A scene of one emissive sphere of radius rs at distance z on the axis of a camera at the
 * origin looking down +z (vertical field of view 30 degrees, W x H). */
static void sphere_scene(tr_scene *s, double rs, double z) {
    tr_scene_init(s);
    tr_error err;
    uint32_t em = add_mat(s, tr_material_emitter(v3s(1.0f), 1.0f));
    tr_shape_desc d = tr_shape_desc_default(TR_SHAPE_ICOSPHERE);
    d.material = em;
    d.transform.position = v3(0.0f, 0.0f, (float)z);
    d.transform.scale = v3s((float)rs);
    d.subdivisions = 4;
    CHECK(tr_scene_add_shape(s, &d, &err) == TR_OK, "sphere: %s", err.msg);
    CHECK(tr_scene_commit(s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "commit: %s", err.msg);
}

static void make_camera(tr_camera *cam) {
    tr_error err;
    CHECK(tr_camera_make(cam, v3s(0.0f), v3(0, 0, 1), v3(0, 1, 0), 30.0f, 0.001f, 1e30f, W, H,
                         &err) == TR_OK,
          "camera: %s", err.msg);
}

static void render(const tr_scene *s, const tr_camera *cam, int integrator, uint32_t spp,
                   tr_film *f) {
    tr_error err;
    CHECK(tr_film_init(f, cam->screen_width, cam->screen_height, &err) == TR_OK, "%s", err.msg);
    tr_render_config cfg = tr_render_config_default();
    cfg.integrator = integrator;
    cfg.seed = 11;
    cfg.threads = 2;
    for (uint32_t k = 0; k < spp; ++k) {
        CHECK(tr_render_frame(s, cam, &cfg, f, k, NULL, &err) == TR_OK, "frame: %s", err.msg);
    }
}

/* (a) */
static void circle_of_confusion(void) {
    /* Spheres behind and in front of the plane in focus, and one in it. */
    const struct {
        double z, focus, radius;
        int integrator;
    } cases[] = {{4.0, 2.0, 0.4, TR_INTEGRATOR_PT},
                 {1.5, 3.0, 0.15, TR_INTEGRATOR_PT},
                 {4.0, 2.0, 0.4, TR_INTEGRATOR_NAIVE},
                 {3.0, 3.0, 0.3, TR_INTEGRATOR_PT}};
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        const double z = cases[i].z, F = cases[i].focus, A = cases[i].radius;
        const double rs = 0.028 * z; /* the sphere's image: about 5 px in radius */
        tr_scene s = {0};
        sphere_scene(&s, rs, z);
        tr_camera cam;
        make_camera(&cam);
        tr_error err;
        CHECK(tr_camera_set_lens(&cam, (float)A, (float)F, &err) == TR_OK, "lens: %s", err.msg);
        tr_film f;
        render(&s, &cam, cases[i].integrator, 256, &f);
        const double px = (double)H / (double)cam.canvas_height; /* pixels per canvas unit */
        /* The sphere's silhouette from the lens's centre: a cone of half-angle asin(rs/z). */
        const double rho = tan(asin(rs / z)) * px;
        const double m2 = image_second_moment(&f);
        const double expect_d = 2.0 * A * fabs(1.0 / F - 1.0 / z) * px;
        const double disc = m2 - rho * rho / 2.0 - 1.0 / 6.0;
        if (expect_d > 0.0) {
            const double got_d = 2.0 * sqrt(2.0 * (disc > 0.0 ? disc : 0.0));
            printf("circle of confusion %zu (%s, z %g, focus %g, radius %g): %.3f px, thin lens "
                   "%.3f px\n",
                   i, tr_integrator_name(cases[i].integrator), z, F, A, got_d, expect_d);
            CHECK(fabs(got_d - expect_d) <= 0.02 * expect_d,
                  "case %zu: circle of confusion %.3f px across, thin lens says %.3f", i, got_d,
                  expect_d);
            const double flat_d = flux_diameter(&f, 0.5 * (expect_d / 2.0 - rho));
            printf("  by flux over plateau: %.3f px\n", flat_d);
            CHECK(fabs(flat_d - expect_d) <= 0.02 * expect_d,
                  "case %zu: flux over plateau gives %.3f px across, thin lens says %.3f", i,
                  flat_d, expect_d);
        } else {
            printf("in focus %zu: second moment %.4f px^2, the sphere's %.4f\n", i, m2,
                   rho * rho / 2.0 + 1.0 / 6.0);
            /* In focus: the sphere's image alone (a 2 % error on a 5 px radius is 0.2 px^2
             * in the second moment). */
            CHECK(fabs(disc) <= 0.04 * rho * rho / 2.0 + 0.05,
                  "case %zu: in focus, second moment %.4f px^2 vs the sphere's %.4f", i, m2,
                  rho * rho / 2.0 + 1.0 / 6.0);
        }
        tr_film_free(&f);
        tr_scene_clear(&s);
    }
}

/* (b) */
static void pinhole_unchanged(void) {
    tr_scene s = {0};
    tr_scene_init(&s);
    tr_error err;
    CHECK(tr_scene_builtin(&s, "cornell", 48, 36, &err) == TR_OK, "builtin: %s", err.msg);
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "commit: %s", err.msg);
    const int integrators[2] = {TR_INTEGRATOR_PT, TR_INTEGRATOR_NAIVE};
    for (int k = 0; k < 2; ++k) {
        tr_camera plain = *tr_scene_camera(&s), zero = plain, lens = plain;
        CHECK(plain.lens_radius == 0.0f, "a made camera is a pinhole");
        CHECK(tr_camera_set_lens(&zero, 0.0f, 7.5f, &err) == TR_OK, "zero: %s", err.msg);
        CHECK(tr_camera_set_lens(&lens, 0.05f, 7.5f, &err) == TR_OK, "lens: %s", err.msg);
        tr_film a, b, c;
        render(&s, &plain, integrators[k], 4, &a);
        render(&s, &zero, integrators[k], 4, &b);
        render(&s, &lens, integrators[k], 4, &c);
        const size_t bytes = 3u * (size_t)a.width * a.height * sizeof(float);
        CHECK(memcmp(a.sum, b.sum, bytes) == 0, "%s: radius 0 changes the image",
              tr_integrator_name(integrators[k]));
        CHECK(memcmp(a.sum, c.sum, bytes) != 0, "%s: a lens changes nothing",
              tr_integrator_name(integrators[k]));
        tr_film_free(&a);
        tr_film_free(&b);
        tr_film_free(&c);
    }
    tr_scene_clear(&s);
}

/* (c) */
static void lens_rays(void) {
    tr_camera cam;
    make_camera(&cam);
    tr_error err;
    const float A = 0.25f, F = 2.5f;
    CHECK(tr_camera_set_lens(&cam, A, F, &err) == TR_OK, "lens: %s", err.msg);
    tr_rng rng;
    tr_rng_init(&rng, 3, 0, 0);
    enum { RINGS = 4, SECTORS = 8, N = 64000 };
    double count[RINGS * SECTORS] = {0};
    double worst_focus = 0.0, worst_disc = 0.0;
    for (int k = 0; k < N; ++k) {
        const float x = (float)(k % W), y = (float)((k / W) % H);
        const float jx = tr_rng_float(&rng), jy = tr_rng_float(&rng);
        const float lu = tr_rng_float(&rng), lv = tr_rng_float(&rng);
        tr_ray pin = tr_camera_ray(&cam, x, y, jx, jy);
        tr_ray r = tr_camera_ray_lens(&cam, x, y, jx, jy, lu, lv);
        /* The pinhole ray's point on the plane in focus, and the lens ray's. */
        const tr_vec3 fp = v3_scale(pin.dir, F / v3_dot(pin.dir, cam.dir));
        const float t = (F - v3_dot(v3_sub(r.origin, cam.pos), cam.dir)) / v3_dot(r.dir, cam.dir);
        const tr_vec3 fr = v3_add(r.origin, v3_scale(r.dir, t));
        const double e = v3_length(v3_sub(fr, fp));
        worst_focus = e > worst_focus ? e : worst_focus;
        const tr_vec3 o = v3_sub(r.origin, cam.pos);
        const double ox = v3_dot(o, cam.right) / A, oy = v3_dot(o, cam.up) / A;
        const double od = fabs(v3_dot(o, cam.dir));
        worst_disc = od > worst_disc ? od : worst_disc;
        const double rr = ox * ox + oy * oy; /* in [0, 1]: rings of equal area */
        int ring = (int)(rr * RINGS),
            sector = (int)((atan2(oy, ox) + PI_D) / (2.0 * PI_D) * SECTORS);
        CHECK(rr <= 1.0 + 1e-5, "lens point %g outside the disc", sqrt(rr));
        ring = ring < RINGS ? ring : RINGS - 1;
        sector = sector < SECTORS ? (sector < 0 ? 0 : sector) : SECTORS - 1;
        count[ring * SECTORS + sector] += 1.0;
    }
    CHECK(worst_focus < 1e-5 * F, "lens rays miss the pinhole's point in focus by %g", worst_focus);
    CHECK(worst_disc < 1e-6, "lens points leave the lens plane by %g", worst_disc);
    double chi2 = 0.0;
    const double e = (double)N / (RINGS * SECTORS);
    for (int i = 0; i < RINGS * SECTORS; ++i) {
        chi2 += (count[i] - e) * (count[i] - e) / e;
    }
    CHECK(chi2 < chi2_critical(RINGS * SECTORS - 1), "lens points: chi2 %.2f (critical %.2f)", chi2,
          chi2_critical(RINGS * SECTORS - 1));
    /* A pinhole camera's lens ray is the pinhole ray. */
    tr_camera pin;
    make_camera(&pin);
    tr_ray a = tr_camera_ray(&pin, 7.0f, 9.0f, 0.25f, 0.75f);
    tr_ray b = tr_camera_ray_lens(&pin, 7.0f, 9.0f, 0.25f, 0.75f, 0.9f, 0.1f);
    CHECK(memcmp(&a, &b, sizeof a) == 0, "radius 0: the pinhole's ray");
}

/* (d) */
static void arguments(void) {
    tr_camera cam;
    make_camera(&cam);
    tr_error err;
    CHECK_STATUS(tr_camera_set_lens(&cam, -0.1f, 1.0f, &err), err, TR_STATUS_INVALID_ARGUMENT,
                 "negative radius");
    CHECK_STATUS(tr_camera_set_lens(&cam, NAN, 1.0f, &err), err, TR_STATUS_INVALID_ARGUMENT,
                 "NaN radius");
    CHECK_STATUS(tr_camera_set_lens(&cam, INFINITY, 1.0f, &err), err, TR_STATUS_INVALID_ARGUMENT,
                 "infinite radius");
    CHECK_STATUS(tr_camera_set_lens(&cam, 0.1f, 0.0f, &err), err, TR_STATUS_INVALID_ARGUMENT,
                 "focus 0");
    CHECK_STATUS(tr_camera_set_lens(&cam, 0.1f, -2.0f, &err), err, TR_STATUS_INVALID_ARGUMENT,
                 "negative focus");
    CHECK(cam.lens_radius == 0.0f && cam.focus_dist == 1.0f, "a refused lens leaves the camera");
    /* 24 mm high, 50 mm focal length (vertical field 2 atan(12/50)); f/2: radius 12.5 mm. */
    tr_camera c35;
    CHECK(tr_camera_make(&c35, v3s(0.0f), v3(0, 0, 1), v3(0, 1, 0),
                         (float)(2.0 * atan(12.0 / 50.0) * 180.0 / PI_D), 0.001f, 1e30f, 36, 24,
                         &err) == TR_OK,
          "35 mm: %s", err.msg);
    CHECK_NEAR(tr_camera_lens_radius_for(&c35, 2.0f, 0.024f), 0.0125, 1e-7, "f/2 at 50 mm");
    CHECK(tr_camera_lens_radius_for(&c35, 0.0f, 0.024f) == 0.0f, "f-number 0");
    CHECK(tr_camera_lens_radius_for(&c35, 2.0f, -1.0f) == 0.0f, "negative sensor");
    /* bdpt and vcm refuse a lens, not a pinhole. */
    tr_scene s = {0};
    sphere_scene(&s, 0.1, 3.0);
    tr_film f;
    CHECK(tr_film_init(&f, W, H, &err) == TR_OK, "%s", err.msg);
    tr_render_config cfg = tr_render_config_default();
    cfg.threads = 1;
    const int bidir[2] = {TR_INTEGRATOR_BDPT, TR_INTEGRATOR_VCM};
    for (int k = 0; k < 2; ++k) {
        cfg.integrator = bidir[k];
        tr_camera lens = cam;
        CHECK(tr_camera_set_lens(&lens, 0.1f, 3.0f, &err) == TR_OK, "%s", err.msg);
        CHECK_STATUS(tr_render_frame(&s, &lens, &cfg, &f, 0, NULL, &err), err,
                     TR_STATUS_UNSUPPORTED, tr_integrator_name(bidir[k]));
        CHECK(tr_render_frame(&s, &cam, &cfg, &f, 0, NULL, &err) == TR_OK, "%s pinhole: %s",
              tr_integrator_name(bidir[k]), err.msg);
    }
    tr_film_free(&f);
    tr_scene_clear(&s);
}

static int parse_camera(const char *camera, tr_camera *out, tr_error *err) {
    char text[1024];
    snprintf(text, sizeof text,
             "{\"camera\": {%s},\n"
             " \"materials\": {\"l\": {\"type\": \"emitter\", \"color\": [1, 1, 1], "
             "\"emittance\": 1}},\n"
             " \"shapes\": [{\"type\": \"plane\", \"material\": \"l\"}]}",
             camera);
    tr_scene s = {0};
    int rc = tr_scene_file_parse(&s, "lens.json", text, strlen(text), NULL, NULL, err);
    if (rc == TR_OK) {
        *out = *tr_scene_camera(&s);
        tr_scene_clear(&s);
    }
    return rc;
}

/* (e) */
static void scene_files(void) {
    tr_camera c;
    tr_error err;
    const char *base = "\"position\": [0, 0, -3], \"fov\": 40";
    char cam[512];
    snprintf(cam, sizeof cam, "%s, \"look_at\": [0, 4, 0]", base);
    CHECK(parse_camera(cam, &c, &err) == TR_OK && c.lens_radius == 0.0f, "no lens: %s", err.msg);
    snprintf(cam, sizeof cam, "%s, \"look_at\": [0, 4, 0], \"aperture_radius\": 0.05", base);
    CHECK(parse_camera(cam, &c, &err) == TR_OK, "aperture: %s", err.msg);
    CHECK_NEAR(c.lens_radius, 0.05, 1e-7, "aperture_radius");
    CHECK_NEAR(c.focus_dist, 5.0, 1e-5, "focus at look_at's distance");
    snprintf(cam, sizeof cam,
             "%s, \"direction\": [0, 0, 1], \"aperture_radius\": 0.05, \"focus_distance\": 2.5",
             base);
    CHECK(parse_camera(cam, &c, &err) == TR_OK, "focus: %s", err.msg);
    CHECK_NEAR(c.focus_dist, 2.5, 1e-7, "focus_distance");
    /* fov 2 atan(12/50) with sensor 24: focal 50, f/4: radius 6.25. */
    snprintf(cam, sizeof cam,
             "\"position\": [0, 0, -3], \"fov\": %.9f, \"look_at\": [0, 0, 0], "
             "\"f_number\": 4, \"sensor_height\": 24",
             2.0 * atan(12.0 / 50.0) * 180.0 / PI_D);
    CHECK(parse_camera(cam, &c, &err) == TR_OK, "f_number: %s", err.msg);
    CHECK_NEAR(c.lens_radius, 6.25, 1e-4, "f_number's radius");
    /* The default sensor is 0.024 high (35 mm film in metres). */
    snprintf(cam, sizeof cam,
             "\"position\": [0, 0, -3], \"fov\": %.9f, \"look_at\": [0, 0, 0], \"f_number\": 4",
             2.0 * atan(12.0 / 50.0) * 180.0 / PI_D);
    CHECK(parse_camera(cam, &c, &err) == TR_OK, "f_number: %s", err.msg);
    CHECK_NEAR(c.lens_radius, 0.00625, 1e-7, "f_number's radius, default sensor");
    /* bdpt and vcm: refused when the file's render defaults are applied, naming the file
     * and the camera's key; pt takes the lens. */
    {
        const char *text =
            "{\"camera\": {\"position\": [0, 0, -3], \"fov\": 40, \"look_at\": [0, 0, 0], "
            "\"f_number\": 2},\n"
            " \"materials\": {\"l\": {\"type\": \"emitter\", \"color\": [1, 1, 1], "
            "\"emittance\": 1}},\n"
            " \"shapes\": [{\"type\": \"plane\", \"material\": \"l\"}]}";
        const char *names[3] = {"bdpt", "vcm", "pt"};
        for (int k = 0; k < 3; ++k) {
            tr_scene s = {0};
            tr_scene_file info;
            CHECK(tr_scene_file_parse(&s, "lens.json", text, strlen(text), NULL, &info, &err) ==
                      TR_OK,
                  "%s", err.msg);
            tr_render_request req = {0};
            req.integrator = names[k];
            tr_render_settings st;
            const int rc = tr_scene_file_apply(&s, "lens.json", &info, &req, &st, &err);
            if (k < 2) {
                CHECK_STATUS(rc, err, TR_STATUS_UNSUPPORTED, names[k]);
                CHECK(strstr(err.msg, "lens.json") && strstr(err.msg, "camera."),
                      "%s: the refusal names the file and the key: %s", names[k], err.msg);
            } else {
                CHECK(rc == TR_OK && tr_scene_camera(&s)->lens_radius > 0.0f, "pt: %s", err.msg);
            }
            tr_scene_clear(&s);
        }
    }
    /* Refusals: each names the key. */
    const char *bad[] = {
        "\"direction\": [0, 0, 1], \"aperture_radius\": 0.1",
        "\"look_at\": [0, 0, 0], \"aperture_radius\": -0.1",
        "\"look_at\": [0, 0, 0], \"aperture_radius\": 0.1, \"f_number\": 2",
        "\"look_at\": [0, 0, 0], \"aperture_radius\": 0.1, \"focus_distance\": 0",
        "\"look_at\": [0, 0, 0], \"aperture_radius\": \"wide\"",
        "\"look_at\": [0, 0, 0], \"f_number\": 0",
        "\"look_at\": [0, 0, 0], \"aperture_radius\": 0.1, \"sensor_height\": 0.024",
        "\"look_at\": [0, 0, 0], \"aperture_radius\": 0.1, \"focus_distanse\": 2"};
    const char *key[] = {"focus_distance",  "aperture_radius", "camera",        "focus_distance",
                         "aperture_radius", "f_number",        "sensor_height", "focus_distanse"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        snprintf(cam, sizeof cam, "%s, %s", base, bad[i]);
        CHECK_STATUS(parse_camera(cam, &c, &err), err, TR_STATUS_PARSE, bad[i]);
        CHECK(strstr(err.msg, "lens.json") && strstr(err.msg, key[i]),
              "refusal %zu names the file and %s: %s", i, key[i], err.msg);
    }
}

/* (f) */
static void focus_on_point(void) {
    tr_scene scene = {0}, *s = &scene;
    sphere_scene(s, 1.0, 10.0);
    tr_camera cam;
    make_camera(&cam);
    const float pts[3][2] = {{W / 2.0f, H / 2.0f},
                             {W / 2.0f + 2.5f, H / 2.0f - 1.5f},
                             {W / 2.0f - 3.25f, H / 2.0f + 2.75f}};
    for (int i = 0; i < 3; ++i) {
        /* The pinhole ray through the point, and where it meets the unit sphere at z = 10. */
        const double sx = (pts[i][0] / W - 0.5) * cam.canvas_width;
        const double sy = (0.5 - pts[i][1] / H) * cam.canvas_height;
        const double dx = cam.right.x * sx + cam.up.x * sy, dy = cam.right.y * sx + cam.up.y * sy;
        const double dz = 1.0 + cam.right.z * sx + cam.up.z * sy;
        const double n = sqrt(dx * dx + dy * dy + dz * dz);
        const double b = 10.0 * dz / n, disc = b * b - 99.0; /* |t d - c|^2 = 1, |c| = 10 */
        const double want = (b - sqrt(disc)) * dz / n;
        float got = 0.0f;
        CHECK(disc > 0.0 && tr_scene_focus_distance(s, &cam, pts[i][0], pts[i][1], &got) == 1 &&
                  fabs(got - want) < 0.01,
              "point %d: focus distance %g, the sphere at %g", i, got, want);
    }
    float d = -1.0f;
    CHECK(tr_scene_focus_distance(s, &cam, 1.5f, 1.5f, &d) == 0 && d == -1.0f, "off the sphere");
    CHECK(tr_scene_focus_distance(s, &cam, -1.0f, 3.0f, &d) == 0 &&
              tr_scene_focus_distance(s, &cam, (float)W, 3.0f, &d) == 0 &&
              tr_scene_focus_distance(s, &cam, NAN, 3.0f, &d) == 0 && d == -1.0f,
          "off the screen");
    add_mat(s, tr_material_emitter(v3s(1.0f), 1.0f)); /* an edit: no longer committed */
    CHECK(tr_scene_focus_distance(s, &cam, W / 2.0f, H / 2.0f, &d) == 0, "uncommitted scene");
    tr_scene_clear(s);
}

int main(void) {
    focus_on_point();
    lens_rays();
    arguments();
    scene_files();
    pinhole_unchanged();
    circle_of_confusion();
    return check_finish("test_lens");
}
