/* test_multiscatter.c - Kulla and Conty's multiple-scattering compensation of the GGX
 * conductor lobe (src/kernel/ggx_ms.h, src/scene/ggx_ms.c).
 *
 *  (a) White furnace: a white conductor (glossy, and principled with metallic 1; colour 1)
 *      under a uniform white environment reflects all of it, so every pixel's radiance is
 *      the furnace's, 1. A large plane seen by pt at grazing, middle and steep angles
 *      (cosines about 0.1 to 1) renders within 0.5 % of 1 at roughness 0.5, 0.75 and 1
 *      with "multiscatter": true, where single scattering alone renders measurably darker
 *      (principled at roughness 1: below 0.9).
 *  (b) The table: E lies in (0, 1] and at normal incidence falls with alpha; E_avg is E's
 *      cosine-weighted mean; the lobe is reciprocal.
 *  (c) The defaults: glossy without the key renders bit for bit as with "multiscatter":
 *      false (the thesis's material keeps its images), and a scene that asks for nothing
 *      has no table; principled without the key renders bit for bit as with true, and a
 *      principled material imported from a glTF file has the flag. */
#define _POSIX_C_SOURCE 200809L
#include "check.h"
#include "model_util.h"
#include "render_film.h"
#include "scene_util.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

enum { W = 64, H = 32, SPP = 64 };

/* Renders a plane of material `mat` (JSON) under a white furnace, seen from a camera
 * looking down at `depression` degrees; returns the mean radiance (green) and, through
 * *film_out when not NULL, the film. */
static double furnace(const char *mat, double depression, tr_film *film_out) {
    const double d = depression * 3.14159265358979323846 / 180.0;
    char text[2048];
    snprintf(text, sizeof text,
             "{\"camera\": {\"position\": [0, 1, 0], \"direction\": [0, %.9f, %.9f], "
             "\"fov\": 16},\n"
             " \"render\": {\"width\": %d, \"height\": %d},\n"
             " \"materials\": {\"m\": %s},\n"
             " \"shapes\": [{\"type\": \"plane\", \"material\": \"m\", \"scale\": [4000, 1, "
             "4000]}],\n"
             " \"environment\": {\"color\": [1, 1, 1]}}",
             -sin(d), cos(d), W, H, mat);
    tr_scene s = {0};
    tr_error err;
    if (tr_scene_file_parse(&s, "furnace.json", text, strlen(text), NULL, NULL, &err) != TR_OK) {
        CHECK(0, "%s", err.msg);
        return -1.0;
    }
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
    tr_film f;
    const tr_render_config def = tr_render_config_default();
    render_film(&s, W, H, def.integrator, def.max_depth, 0, 9, 0, SPP, &f);
    double sum = 0.0;
    for (uint32_t y = 0; y < H; ++y) {
        for (uint32_t x = 0; x < W; ++x) {
            sum += tr_film_pixel(&f, x, y).y;
        }
    }
    if (film_out) {
        *film_out = f;
    } else {
        tr_film_free(&f);
    }
    tr_scene_clear(&s);
    return sum / (W * H);
}

/* (a) */
static void white_furnace(void) {
    const double depressions[3] = {8.0, 40.0, 80.0};
    const char *kinds[2] = {"\"type\": \"glossy\"", "\"type\": \"principled\", \"metallic\": 1"};
    const double rough[3] = {0.5, 0.75, 1.0};
    for (int k = 0; k < 2; ++k) {
        for (int r = 0; r < 3; ++r) {
            for (int v = 0; v < 3; ++v) {
                char mat[256];
                snprintf(mat, sizeof mat,
                         "{%s, \"color\": [1, 1, 1], \"roughness\": %g, \"multiscatter\": true}",
                         kinds[k], rough[r]);
                const double e = furnace(mat, depressions[v], NULL);
                printf("%s, roughness %g, seen at %g degrees: %.5f\n", kinds[k], rough[r],
                       depressions[v], e);
                CHECK(fabs(e - 1.0) <= 0.005, "%s roughness %g at %g degrees: %.5f (furnace 1)",
                      kinds[k], rough[r], depressions[v], e);
            }
        }
    }
    /* Single scattering alone loses light where compensation matters. */
    const double ss = furnace("{\"type\": \"principled\", \"metallic\": 1, \"color\": [1, 1, 1], "
                              "\"roughness\": 1, \"multiscatter\": false}",
                              40.0, NULL);
    printf("principled, roughness 1, single scattering: %.5f\n", ss);
    CHECK(ss < 0.9, "single scattering at roughness 1 renders %.5f: the test would not notice", ss);
}

/* (b) */
static void table(void) {
    const float *t = tr_ggx_ms_table();
    const int n = TR_GGX_MS_N;
    int bad = 0;
    for (int j = 0; j < n; ++j) {
        for (int i = 0; i < n; ++i) {
            const float e = t[j * n + i];
            bad += !(e > 0.0f && e <= 1.0f + 1e-6f);
            if (j > 0 && i == n - 1) {
                /* At normal incidence a rougher lobe reflects less in one bounce. (Near
                 * grazing E is not monotonic: it tends to 1 as mu falls, for every alpha.) */
                bad += !(e < t[(j - 1) * n + i] + 1e-5f);
            }
        }
        /* E_avg against the table's own cosine-weighted mean (trapezoids over mu). */
        double avg = 0.0;
        for (int i = 0; i + 1 < n; ++i) {
            const double m0 = (double)i / (n - 1), m1 = (double)(i + 1) / (n - 1);
            avg += (t[j * n + i] * m0 + t[j * n + i + 1] * m1) / (n - 1);
        }
        CHECK(fabs(avg - t[n * n + j]) <= 2e-3, "alpha %d: E_avg %.5f vs the table's %.5f", j,
              (double)t[n * n + j], avg);
    }
    CHECK(bad == 0, "%d table entries out of range, or not falling with alpha at normal incidence",
          bad);
    CHECK(t[0 * n + n - 1] > 0.999f && t[(n - 1) * n + n - 1] < 0.8f,
          "E at normal incidence: %.5f smooth, %.5f at alpha 1", (double)t[n - 1],
          (double)t[(n - 1) * n + n - 1]);
    /* Reciprocity of the lobe. */
    const tr_vec3 f0 = v3(0.9f, 0.6f, 0.3f);
    const tr_vec3 a = tr_ggx_ms_lobe(t, 0.7f, f0, 0.3f, 0.8f);
    const tr_vec3 b = tr_ggx_ms_lobe(t, 0.7f, f0, 0.8f, 0.3f);
    CHECK(a.x == b.x && a.y == b.y && a.z == b.z && a.x > 0.0f, "f_ms reciprocal: %g vs %g",
          (double)a.x, (double)b.x);
}

/* (c) */
static void unchanged(void) {
    tr_film a, b;
    const double ea = furnace("{\"type\": \"glossy\", \"color\": [0.9, 0.8, 0.7], \"roughness\": "
                              "0.6}",
                              40.0, &a);
    const double eb = furnace("{\"type\": \"glossy\", \"color\": [0.9, 0.8, 0.7], \"roughness\": "
                              "0.6, \"multiscatter\": false}",
                              40.0, &b);
    CHECK(ea == eb && memcmp(a.sum, b.sum, 3u * W * H * sizeof(float)) == 0,
          "multiscatter false changes the image");
    tr_film_free(&a);
    tr_film_free(&b);
    tr_scene s = {0};
    tr_scene_init(&s);
    tr_error err;
    CHECK(tr_scene_builtin(&s, "cornell", 16, 12, &err) == TR_OK, "%s", err.msg);
    const tr_scene_view v = tr_scene_view_of(&s);
    CHECK(v.ggx_ms_count == 0 && v.ggx_ms == NULL, "a scene without the key has no table");
    tr_scene_clear(&s);

    /* principled: compensated unless told otherwise. */
    const char *pm = "{\"type\": \"principled\", \"color\": [0.9, 0.8, 0.7], \"metallic\": 0.5, "
                     "\"roughness\": 0.8%s}";
    char m0[256], m1[256], m2[256];
    snprintf(m0, sizeof m0, pm, "");
    snprintf(m1, sizeof m1, pm, ", \"multiscatter\": true");
    snprintf(m2, sizeof m2, pm, ", \"multiscatter\": false");
    tr_film c;
    const double e0 = furnace(m0, 40.0, &a), e1 = furnace(m1, 40.0, &b), e2 = furnace(m2, 40.0, &c);
    CHECK(e0 == e1 && memcmp(a.sum, b.sum, 3u * W * H * sizeof(float)) == 0,
          "principled without the key is not the compensated material");
    CHECK(e2 < e0, "\"multiscatter\": false does not turn compensation off (%.5f vs %.5f)", e2, e0);
    tr_film_free(&a);
    tr_film_free(&b);
    tr_film_free(&c);
}

/* A glTF file's material (every imported material is principled) is compensated. */
static void imported(void) {
    char dir[] = "/tmp/trac0r-ms-XXXXXX";
    if (!mkdtemp(dir)) {
        CHECK(0, "mkdtemp");
        return;
    }
    char path[700];
    snprintf(path, sizeof path, "%s/tri.gltf", dir);
    FILE *f = fopen(path, "w");
    CHECK(f != NULL, "cannot write %s", path);
    if (!f) {
        return;
    }
    /* One triangle (three VEC3 positions, base64) with a rough metal. */
    fprintf(f, "{\"asset\": {\"version\": \"2.0\"},\n"
               " \"buffers\": [{\"byteLength\": 36, \"uri\": "
               "\"data:application/octet-stream;base64,"
               "AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA\"}],\n"
               " \"bufferViews\": [{\"buffer\": 0, \"byteOffset\": 0, \"byteLength\": 36}],\n"
               " \"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, \"count\": 3, "
               "\"type\": \"VEC3\", \"min\": [0, 0, 0], \"max\": [1, 1, 0]}],\n"
               " \"materials\": [{\"name\": \"metal\", \"pbrMetallicRoughness\": "
               "{\"baseColorFactor\": [1, 1, 1, 1], \"roughnessFactor\": 0.9, "
               "\"metallicFactor\": 1}}],\n"
               " \"meshes\": [{\"primitives\": [{\"attributes\": {\"POSITION\": 0}, "
               "\"material\": 0}]}],\n"
               " \"nodes\": [{\"mesh\": 0}], \"scenes\": [{\"nodes\": [0]}], \"scene\": 0}\n");
    CHECK(fclose(f) == 0, "cannot write %s", path);
    tr_scene s;
    tr_scene_file info;
    load_model_file(&s, path, &info);
    int principled = 0;
    for (uint32_t i = 0; i < s.material_count; ++i) {
        if (s.materials[i].type == TR_MATERIAL_PRINCIPLED) {
            ++principled;
            CHECK((s.materials[i].flags & TR_MATERIAL_MULTISCATTER) != 0u,
                  "imported material %u is not compensated (flags %u)", i, s.materials[i].flags);
        }
    }
    CHECK(principled == 1, "%d principled materials imported from %s", principled, path);
    tr_scene_clear(&s);
    unlink(path);
    rmdir(dir);
}

int main(void) {
    table();
    unchanged();
    imported();
    white_furnace();
    return check_finish("test_multiscatter");
}
