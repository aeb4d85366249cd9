/* test_sheen.c - the principled material's sheen (KHR_materials_sheen, bsdf_principled.h)
 * from scene files and glTF files to images, and the scene files' specular keys
 * (KHR_materials_specular); the BSDFs themselves are checked in test_bsdf.c.
 *
 *  (a) The keys: "sheen_color" and "sheen_roughness" of a principled material reach its
 *      extras; outside [0, 1] they are refused (TR_STATUS_PARSE, the key's path named), and
 *      other material types refuse them. A scene with a sheen carries the albedo table.
 *  (b) glTF: a material with KHR_materials_sheen imports its colour and roughness factors
 *      with no warning about it; KHR_materials_specular and KHR_materials_emissive_strength,
 *      which Assimp 5.2 does not pass on, are read from the file's JSON: the factors reach
 *      the extras (the colour clamped to the scene key's [0, 10]) and one warning more
 *      than without them, naming the material and the specular map it does not read.
 *  (c) White furnace: a white principled sphere with a white sheen under a uniform white
 *      environment creates no energy (mean at most 1 plus five standard errors) and
 *      reflects more than the same sphere's base alone loses to the sheen's scaling (the
 *      sheen is seen: the mean differs from the sheen-less sphere's).
 *  (d) "sheen_color": [0, 0, 0] renders bit for bit as a file without the keys.
 *  (e) "specular" and "specular_color" reach the extras (with TR_MATEXT_SPECULAR), are
 *      refused out of range or on other types; 1 and white render bit for bit as a file
 *      without them, another value changes the image. */
#define _POSIX_C_SOURCE 200809L
#include "check.h"
#include "render_film.h"
#include "scene_util.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

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
    return tr_scene_file_parse(s, "sheen.json", text, strlen(text), NULL, NULL, err);
}

/* The sphere's mean radiance (green) and its standard error; the film in *out if wanted. */
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
    render_film(&s, W, H, def.integrator, def.max_depth, 0, 23, 0, SPP, &f);
    double s1 = 0.0, s2 = 0.0;
    for (uint32_t y = 0; y < H; ++y) {
        for (uint32_t x = 0; x < W; ++x) {
            const double v = tr_film_pixel(&f, x, y).y;
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
                "{\"type\": \"principled\", \"color\": [1, 1, 1], \"sheen_color\": [0.5, 0.25, "
                "1], \"sheen_roughness\": 0.375}",
                &err) == TR_OK,
          "%s", err.msg);
    CHECK(s.material_ext_count == s.material_count && s.material_count >= 1 &&
              s.material_exts[0].sheen_color.x == 0.5f &&
              s.material_exts[0].sheen_color.y == 0.25f &&
              s.material_exts[0].sheen_color.z == 1.0f &&
              s.material_exts[0].sheen_roughness == 0.375f,
          "the sheen's keys reach the material's extras");
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_scene_view_of(&s).ggx_ms_count == TR_GGX_MS_COUNT,
          "a scene with a sheen carries the albedo table");
    tr_scene_clear(&s);
    const char *bad[] = {
        "{\"type\": \"principled\", \"color\": [1, 1, 1], \"sheen_color\": [1.5, 0, 0]}",
        "{\"type\": \"principled\", \"color\": [1, 1, 1], \"sheen_color\": [0, -0.1, 0]}",
        "{\"type\": \"principled\", \"color\": [1, 1, 1], \"sheen_color\": 0.5}",
        "{\"type\": \"principled\", \"color\": [1, 1, 1], \"sheen_roughness\": 2}",
        "{\"type\": \"principled\", \"color\": [1, 1, 1], \"sheen_roughness\": \"soft\"}",
        "{\"type\": \"diffuse\", \"color\": [1, 1, 1], \"sheen_color\": [1, 1, 1]}",
        "{\"type\": \"glossy\", \"color\": [1, 1, 1], \"roughness\": 0.2, "
        "\"sheen_roughness\": 0.5}"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        const int rc = parse(&s, bad[i], &err);
        CHECK(rc != TR_OK && err.code == TR_STATUS_PARSE && strstr(err.msg, "materials.m"),
              "refused (%s): %s", rc != TR_OK ? err.msg : "accepted", bad[i]);
        tr_scene_clear(&s);
    }
}

/* (b): one triangle of a material with a sheen (and, with `specular`, the specular
 * extension as well). */
static const char gltf_fmt[] =
    "{\"asset\": {\"version\": \"2.0\"}, \"extensionsUsed\": [\"KHR_materials_sheen\"%s],\n"
    " \"scene\": 0, \"scenes\": [{\"nodes\": [0]}], \"nodes\": [{\"mesh\": 0}],%s\n"
    " \"materials\": [{\"name\": \"velvet\", \"pbrMetallicRoughness\": {\"baseColorFactor\": "
    "[0.5, 0.5, 0.5, 1], \"metallicFactor\": 0, \"roughnessFactor\": 0.8},%s\n"
    "   \"extensions\": {\"KHR_materials_sheen\": {\"sheenColorFactor\": [0.75, 0.5, 0.25], "
    "\"sheenRoughnessFactor\": 0.625}%s}}],\n"
    " \"meshes\": [{\"primitives\": [{\"attributes\": {\"POSITION\": 0}, \"material\": 0}]}],\n"
    " \"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, \"count\": 3, \"type\": "
    "\"VEC3\", \"min\": [0, 0, 0], \"max\": [1, 1, 0]}],\n"
    " \"bufferViews\": [{\"buffer\": 0, \"byteOffset\": 0, \"byteLength\": 36}],\n"
    " \"buffers\": [{\"byteLength\": 36, \"uri\": \"data:application/octet-stream;base64,"
    "AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA\"}]}\n";

static int load_gltf(const char *dir, int specular, tr_scene *s, tr_scene_file *info) {
    char path[600], text[4096];
    snprintf(path, sizeof path, "%s/sheen%d.gltf", dir, specular);
    /* A 2x2 PNG as the specular map (only its presence matters). */
    static const char png[] = "iVBORw0KGgoAAAANSUhEUgAAAAIAAAACCAYAAABytg0kAAAAEUlEQVR4nGNwOMH1H"
                              "4QZYAwAR3gIRdn56ZMAAAAASUVORK5CYII=";
    char images[256];
    snprintf(images, sizeof images,
             " \"textures\": [{\"source\": 0}], \"images\": [{\"uri\": "
             "\"data:image/png;base64,%s\"}],",
             png);
    snprintf(text, sizeof text, gltf_fmt,
             specular ? ", \"KHR_materials_specular\", \"KHR_materials_emissive_strength\"" : "",
             specular ? images : "", specular ? " \"emissiveFactor\": [0.5, 0.25, 0.125]," : "",
             specular
                 ? ", \"KHR_materials_specular\": {\"specularFactor\": 0.5, "
                   "\"specularColorFactor\": [2, 1, 12], \"specularTexture\": {\"index\": 0}}, "
                   "\"KHR_materials_emissive_strength\": {\"emissiveStrength\": 4}"
                 : "");
    FILE *f = fopen(path, "w");
    CHECK(f && fputs(text, f) >= 0 && fclose(f) == 0, "writing %s", path);
    tr_error err;
    tr_model_options opt = {0, 1.0f, 0, 0, NULL};
    tr_scene_init(s);
    const int rc = tr_scene_model_load(s, path, &opt, info, &err);
    CHECK(rc == TR_OK, "%s", err.msg);
    unlink(path);
    return rc;
}

static void gltf(void) {
    char dir[512];
    const char *tmp = getenv("TMPDIR");
    snprintf(dir, sizeof dir, "%s/trac0r-sheen-XXXXXX", tmp && tmp[0] ? tmp : "/tmp");
    if (!mkdtemp(dir)) {
        CHECK(0, "mkdtemp %s", dir);
        return;
    }
    tr_scene s;
    tr_scene_file info;
    if (load_gltf(dir, 0, &s, &info) == TR_OK) {
        int found = 0;
        for (uint32_t i = 0; i < s.material_count && i < s.material_ext_count; ++i) {
            const tr_material_ext *e = &s.material_exts[i];
            found += s.materials[i].type == TR_MATERIAL_PRINCIPLED && e->sheen_color.x == 0.75f &&
                     e->sheen_color.y == 0.5f && e->sheen_color.z == 0.25f &&
                     e->sheen_roughness == 0.625f;
        }
        CHECK(found == 1, "the glTF's sheen factors reach one principled material (%d)", found);
        int sheen_warned = 0;
        for (uint32_t w = 0; w < info.warning_count; ++w) {
            sheen_warned += strstr(info.warnings[w], "sheen") != NULL;
            printf("warning: %s\n", info.warnings[w]);
        }
        CHECK(sheen_warned == 0, "%d warnings name the sheen", sheen_warned);
        const uint32_t plain = info.warning_count;
        tr_scene_clear(&s);
        if (load_gltf(dir, 1, &s, &info) == TR_OK) {
            int read = 0;
            for (uint32_t i = 0; i < s.material_count && i < s.material_ext_count; ++i) {
                const tr_material_ext *e = &s.material_exts[i];
                read += (e->flags & TR_MATEXT_SPECULAR) != 0u && e->specular == 0.5f &&
                        e->specular_color.x == 2.0f && e->specular_color.y == 1.0f &&
                        e->specular_color.z == 10.0f && e->emission.x == 2.0f &&
                        e->emission.y == 1.0f && e->emission.z == 0.5f;
            }
            CHECK(read == 1, "the specular and emissive-strength factors reach no material");
            /* One warning more than without the extensions: the one naming the material
             * and the specular map (an extension not read would add its own). */
            int ext_named = 0, map_named = 0;
            for (uint32_t w = 0; w < info.warning_count; ++w) {
                printf("warning: %s\n", info.warnings[w]);
                ext_named += strstr(info.warnings[w], "KHR_materials_emissive_strength") != NULL;
                map_named += strstr(info.warnings[w], "velvet") != NULL &&
                             strstr(info.warnings[w], "specularTexture") != NULL;
            }
            CHECK(ext_named == 0 && map_named == 1 && info.warning_count == plain + 1,
                  "%d warnings name emissive strength, %d the specular map, %u in all (%u "
                  "without)",
                  ext_named, map_named, info.warning_count, plain);
            tr_scene_clear(&s);
        }
    }
    rmdir(dir);
}

/* (c) and (d) */
static void white_furnace(void) {
    double se0, se1, se2;
    const double bare = furnace("{\"type\": \"principled\", \"color\": [1, 1, 1], \"roughness\": "
                                "0.5, \"multiscatter\": true}",
                                &se0, NULL);
    const double sheen = furnace("{\"type\": \"principled\", \"color\": [1, 1, 1], \"roughness\": "
                                 "0.5, \"multiscatter\": true, \"sheen_color\": [1, 1, 1], "
                                 "\"sheen_roughness\": 0.5}",
                                 &se1, NULL);
    const double dark = furnace("{\"type\": \"principled\", \"color\": [0.1, 0.1, 0.1], "
                                "\"roughness\": 0.5, \"sheen_color\": [1, 1, 1], "
                                "\"sheen_roughness\": 0.5}",
                                &se2, NULL);
    printf("white sphere %.5f +- %.5f, with a white sheen %.5f +- %.5f, a dark one with a white "
           "sheen %.5f +- %.5f\n",
           bare, se0, sheen, se1, dark, se2);
    CHECK(bare <= 1.0 + 5.0 * se0 && sheen <= 1.0 + 5.0 * se1 && dark <= 1.0 + 5.0 * se2,
          "no energy created: %.5f, %.5f, %.5f", bare, sheen, dark);
    CHECK(sheen > 0.85, "a white sheen over a white base keeps most of the light: %.5f", sheen);
    double sed;
    const double dark_bare = furnace("{\"type\": \"principled\", \"color\": [0.1, 0.1, 0.1], "
                                     "\"roughness\": 0.5}",
                                     &sed, NULL);
    CHECK(dark > dark_bare + 5.0 * sqrt(se2 * se2 + sed * sed),
          "a sheen brightens a dark base: %.5f vs %.5f", dark, dark_bare);
    tr_film a, b;
    memset(&a, 0, sizeof a);
    memset(&b, 0, sizeof b);
    double se;
    furnace("{\"type\": \"principled\", \"color\": [0.8, 0.5, 0.2], \"roughness\": 0.3}", &se, &a);
    furnace("{\"type\": \"principled\", \"color\": [0.8, 0.5, 0.2], \"roughness\": 0.3, "
            "\"sheen_color\": [0, 0, 0], \"sheen_roughness\": 0.7}",
            &se, &b);
    int differ = 0;
    for (uint32_t y = 0; y < H; ++y) {
        for (uint32_t x = 0; x < W; ++x) {
            tr_vec3 pa = tr_film_pixel(&a, x, y), pb = tr_film_pixel(&b, x, y);
            differ += memcmp(&pa, &pb, sizeof pa) != 0;
        }
    }
    CHECK(differ == 0, "a black sheen changes %d pixels", differ);
    tr_film_free(&a);
    tr_film_free(&b);
}

/* (e) */
static void specular(void) {
    tr_scene s;
    tr_error err;
    CHECK(parse(&s,
                "{\"type\": \"principled\", \"color\": [1, 1, 1], \"specular\": 0.5, "
                "\"specular_color\": [2, 1, 0.25]}",
                &err) == TR_OK,
          "%s", err.msg);
    CHECK(s.material_ext_count == s.material_count && s.material_count >= 1 &&
              (s.material_exts[0].flags & TR_MATEXT_SPECULAR) != 0u &&
              s.material_exts[0].specular == 0.5f && s.material_exts[0].specular_color.x == 2.0f &&
              s.material_exts[0].specular_color.z == 0.25f,
          "the specular keys reach the material's extras");
    tr_scene_clear(&s);
    const char *bad[] = {
        "{\"type\": \"principled\", \"color\": [1, 1, 1], \"specular\": 1.5}",
        "{\"type\": \"principled\", \"color\": [1, 1, 1], \"specular_color\": [11, 0, 0]}",
        "{\"type\": \"principled\", \"color\": [1, 1, 1], \"specular_color\": [0, -1, 0]}",
        "{\"type\": \"diffuse\", \"color\": [1, 1, 1], \"specular\": 0.5}"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        const int rc = parse(&s, bad[i], &err);
        CHECK(rc != TR_OK && err.code == TR_STATUS_PARSE && strstr(err.msg, "materials.m"),
              "refused (%s): %s", rc != TR_OK ? err.msg : "accepted", bad[i]);
        tr_scene_clear(&s);
    }
    tr_film a, b, c;
    memset(&a, 0, sizeof a);
    memset(&b, 0, sizeof b);
    memset(&c, 0, sizeof c);
    double se;
    furnace("{\"type\": \"principled\", \"color\": [0.8, 0.5, 0.2], \"roughness\": 0.3}", &se, &a);
    furnace("{\"type\": \"principled\", \"color\": [0.8, 0.5, 0.2], \"roughness\": 0.3, "
            "\"specular\": 1, \"specular_color\": [1, 1, 1]}",
            &se, &b);
    furnace("{\"type\": \"principled\", \"color\": [0.8, 0.5, 0.2], \"roughness\": 0.3, "
            "\"specular\": 0.3}",
            &se, &c);
    int same = 0, other = 0;
    for (uint32_t y = 0; y < H; ++y) {
        for (uint32_t x = 0; x < W; ++x) {
            tr_vec3 pa = tr_film_pixel(&a, x, y), pb = tr_film_pixel(&b, x, y);
            tr_vec3 pc = tr_film_pixel(&c, x, y);
            same += memcmp(&pa, &pb, sizeof pa) != 0;
            other += memcmp(&pa, &pc, sizeof pa) != 0;
        }
    }
    CHECK(same == 0, "specular 1 and white change %d pixels", same);
    CHECK(other > 0, "specular 0.3 changes no pixel");
    tr_film_free(&a);
    tr_film_free(&b);
    tr_film_free(&c);
}

int main(void) {
    specular();
    keys();
    gltf();
    white_furnace();
    return check_finish("test_sheen");
}
