/* test_clearcoat.c - the principled material's clear coat (bsdf_principled.h) from scene
 * files to images; the BSDF itself is checked in test_bsdf.c.
 *
 *  (a) The keys: "clearcoat" and "clearcoat_roughness" of a principled material reach its
 *      extras; outside [0, 1] they are refused (TR_STATUS_PARSE, the key's path named), and
 *      other material types refuse them.
 *  (b) White furnace: a clear-coated white principled sphere filling the view under a
 *      uniform white environment creates no energy (the image's mean is at most 1 plus
 *      five standard errors of the pixels' spread) and, over a dielectric base, keeps it
 *      (mean above 0.9, within 0.03 of the same sphere without a coat).
 *  (c) Without the keys nothing changes: "clearcoat": 0 renders bit for bit as a file
 *      without it. */
#include "check.h"
#include "render_film.h"
#include "scene_util.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

enum { W = 48, H = 48, SPP = 48 };

static int parse(tr_scene *s, const char *mat, tr_error *err) {
    char text[2048];
    snprintf(text, sizeof text,
             "{\"camera\": {\"position\": [0, 0, 3], \"direction\": [0, 0, -1], \"fov\": 20},\n"
             " \"render\": {\"width\": %d, \"height\": %d},\n"
             " \"materials\": {\"m\": %s},\n"
             " \"shapes\": [{\"type\": \"icosphere\", \"material\": \"m\", \"subdivisions\": 5}],\n"
             " \"environment\": {\"color\": [1, 1, 1]}}",
             W, H, mat);
    tr_scene_init(s);
    return tr_scene_file_parse(s, "coat.json", text, strlen(text), NULL, NULL, err);
}

/* Renders the sphere of material `mat`; the mean radiance (green) and its standard error
 * from the pixels' spread. Keeps the film in *out when not NULL. */
static double furnace(const char *mat, double *se, tr_film *out) {
    tr_scene s;
    tr_error err;
    *se = 0.0;
    if (parse(&s, mat, &err) != TR_OK) {
        CHECK(0, "%s", err.msg);
        return -1.0;
    }
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
    tr_film f;
    const tr_render_config def = tr_render_config_default();
    render_film(&s, W, H, def.integrator, def.max_depth, 0, 21, 0, SPP, &f);
    double s1 = 0.0, s2 = 0.0;
    for (uint32_t y = 0; y < H; ++y) {
        for (uint32_t x = 0; x < W; ++x) {
            double v = tr_film_pixel(&f, x, y).y;
            s1 += v;
            s2 += v * v;
        }
    }
    const double n = W * H, mean = s1 / n;
    *se = sqrt(fmax(0.0, s2 / n - mean * mean) / n);
    if (out) {
        *out = f;
    } else {
        tr_film_free(&f);
    }
    tr_scene_clear(&s);
    return mean;
}

/* (a) */
static void keys(void) {
    tr_scene s;
    tr_error err;
    CHECK(parse(&s,
                "{\"type\": \"principled\", \"color\": [1, 1, 1], \"clearcoat\": 0.75, "
                "\"clearcoat_roughness\": 0.25}",
                &err) == TR_OK,
          "%s", err.msg);
    CHECK(s.material_ext_count == s.material_count && s.material_count >= 1 &&
              s.material_exts[0].clearcoat == 0.75f &&
              s.material_exts[0].clearcoat_roughness == 0.25f,
          "the coat's keys reach the material's extras");
    tr_scene_clear(&s);
    const char *bad[] = {
        "{\"type\": \"principled\", \"color\": [1, 1, 1], \"clearcoat\": 1.5}",
        "{\"type\": \"principled\", \"color\": [1, 1, 1], \"clearcoat\": -0.1}",
        "{\"type\": \"principled\", \"color\": [1, 1, 1], \"clearcoat_roughness\": 2}",
        "{\"type\": \"principled\", \"color\": [1, 1, 1], \"clearcoat\": \"yes\"}",
        "{\"type\": \"diffuse\", \"color\": [1, 1, 1], \"clearcoat\": 0.5}",
        "{\"type\": \"glossy\", \"color\": [1, 1, 1], \"roughness\": 0.2, "
        "\"clearcoat_roughness\": 0.5}"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        int rc = parse(&s, bad[i], &err);
        CHECK(rc != TR_OK && err.code == TR_STATUS_PARSE && strstr(err.msg, "materials.m"),
              "refused (%s): %s", rc != TR_OK ? err.msg : "accepted", bad[i]);
        tr_scene_clear(&s);
    }
}

/* (b) and (c) */
static void white_furnace(void) {
    const double coat_r[] = {0.0, 0.3, 1.0};
    double se0;
    const double bare = furnace("{\"type\": \"principled\", \"color\": [1, 1, 1], \"roughness\": "
                                "0.44}",
                                &se0, NULL);
    printf("uncoated white dielectric sphere: %.5f +- %.5f\n", bare, se0);
    for (int k = 0; k < 2; ++k) {
        for (int r = 0; r < 3; ++r) {
            char mat[256];
            snprintf(mat, sizeof mat,
                     "{\"type\": \"principled\", \"color\": [1, 1, 1], \"roughness\": 0.44, "
                     "\"metallic\": %d, \"clearcoat\": 1, \"clearcoat_roughness\": %g}",
                     k, coat_r[r]);
            double se;
            const double e = furnace(mat, &se, NULL);
            printf("coated (roughness %g) white %s sphere: %.5f +- %.5f\n", coat_r[r],
                   k ? "conductor" : "dielectric", e, se);
            CHECK(e <= 1.0 + 5.0 * se, "coat roughness %g, metallic %d: %.5f > 1 + 5 x %.5f",
                  coat_r[r], k, e, se);
            CHECK(k == 1 || (e > 0.9 && fabs(e - bare) <= 0.03),
                  "coat roughness %g over the dielectric: %.5f (uncoated %.5f)", coat_r[r], e,
                  bare);
        }
    }
    tr_film a, b;
    double se;
    furnace("{\"type\": \"principled\", \"color\": [0.8, 0.5, 0.2], \"roughness\": 0.3, "
            "\"metallic\": 0.5}",
            &se, &a);
    furnace("{\"type\": \"principled\", \"color\": [0.8, 0.5, 0.2], \"roughness\": 0.3, "
            "\"metallic\": 0.5, \"clearcoat\": 0, \"clearcoat_roughness\": 0.7}",
            &se, &b);
    int differ = 0;
    for (uint32_t y = 0; y < H; ++y) {
        for (uint32_t x = 0; x < W; ++x) {
            tr_vec3 pa = tr_film_pixel(&a, x, y), pb = tr_film_pixel(&b, x, y);
            differ += memcmp(&pa, &pb, sizeof pa) != 0;
        }
    }
    CHECK(differ == 0, "\"clearcoat\": 0 changes %d pixels", differ);
    tr_film_free(&a);
    tr_film_free(&b);
}

int main(void) {
    keys();
    white_furnace();
    return check_finish("test_clearcoat");
}
