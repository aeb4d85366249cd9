/* test_coat_maps.c - glTF's clear coat maps (KHR_materials_clearcoat's clearcoatTexture and
 * clearcoatRoughnessTexture) from the import to the kernel's material stage.
 *
 *  (a) glTF import: a triangle whose material has a coat weight map and a coat roughness
 *      map (two different images) imports with no warning; the material's extras name
 *      both textures, and tr_material_apply_ext gives the coat weight = factor x the
 *      weight map's red / 255 and its roughness = factor x the roughness map's green / 255
 *      (both linear). With the coat's normal map beside them (test_sheen_coat_maps.c)
 *      there is still no warning, and the material names that map too.
 *  (b) the scene-file keys "clearcoat_texture" and "clearcoat_roughness_texture" read the
 *      two maps on a principled material; on a diffuse one they are refused (a parse
 *      error naming the file and the key); a coat without maps keeps its factors in the
 *      material stage. */
#define _POSIX_C_SOURCE 200809L
#include "check.h"
#include "model_util.h"
#include "kernel/kernel.h"
#include "scene/scene_internal.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* 2x2 PNGs of one RGBA colour each: A (64, 200, 10, 255), B (150, 30, 220, 255). A map
 * read from the wrong channel or the wrong image gives another number. */
#define PNG_A                                                                                      \
    "iVBORw0KGgoAAAANSUhEUgAAAAIAAAACCAYAAABytg0kAAAAEUlEQVR4nGNwOMH1H4QZYAwAR3gIRdn56ZMAAAAASU"   \
    "VORK5CYII="
#define PNG_B                                                                                      \
    "iVBORw0KGgoAAAANSUhEUgAAAAIAAAACCAYAAABytg0kAAAAEUlEQVR42mOYJnfnPwgzwBgAWDwKPdAux7sAAAAASU"   \
    "VORK5CYII="

/* A triangle with texture coordinates, its material coated (weight 0.9, roughness 0.7)
 * with weight map A and roughness map B, and with `normal` the coat's normal map (A). */
static int write_gltf(const char *path, int normal) {
    FILE *f = fopen(path, "w");
    if (!f) {
        return 0;
    }
    fprintf(f,
            "{\"asset\": {\"version\": \"2.0\"},\n"
            " \"extensionsUsed\": [\"KHR_materials_clearcoat\"],\n" GLTF_TRIANGLE_GEOMETRY
            " \"images\": [{\"uri\": \"data:image/png;base64," PNG_A "\"},\n"
            "            {\"uri\": \"data:image/png;base64," PNG_B "\"}],\n"
            " \"textures\": [{\"source\": 0}, {\"source\": 1}],\n"
            " \"materials\": [{\"name\": \"lacquer\", \"pbrMetallicRoughness\": "
            "{\"baseColorFactor\": [0.2, 0.3, 0.8, 1], \"roughnessFactor\": 0.5, "
            "\"metallicFactor\": 0},\n"
            "   \"extensions\": {\"KHR_materials_clearcoat\": {\"clearcoatFactor\": 0.9, "
            "\"clearcoatRoughnessFactor\": 0.7, \"clearcoatTexture\": {\"index\": 0}, "
            "\"clearcoatRoughnessTexture\": {\"index\": 1}%s}}}],\n" GLTF_TRIANGLE_SCENE,
            normal ? ", \"clearcoatNormalTexture\": {\"index\": 0}" : "");
    return fclose(f) == 0;
}

/* The material stage of material i at (0.3, 0.6), from a coated principled start. */
static tr_bsdf_params stage(const tr_scene *s, uint32_t i) {
    tr_scene_view v = tr_scene_view_of(s);
    tr_bsdf_params b;
    memset(&b, 0, sizeof b);
    b.type = TR_MATERIAL_PRINCIPLED;
    b.color = v3s(1.0f);
    b.roughness = 0.5f;
    tr_surface_attr a;
    memset(&a, 0, sizeof a);
    a.ns = v3(0.0f, 0.0f, 1.0f);
    a.tu = 0.3f;
    a.tv = 0.6f;
    tr_material_apply_ext(&v, i, &a, &b);
    return b;
}

/* (a) */
static void gltf_coat_maps(const char *dir) {
    char path[700];
    snprintf(path, sizeof path, "%s/lacquer.gltf", dir);
    for (int normal = 0; normal < 2; ++normal) {
        CHECK(write_gltf(path, normal), "cannot write %s", path);
        tr_scene s;
        tr_scene_file info;
        tr_error err;
        load_model_file(&s, path, &info);
        /* The weight and roughness maps are read, and the coat's normal map too. */
        CHECK(info.warning_count == 0, "%u warnings with%s a coat normal map", info.warning_count,
              normal ? "" : "out");
        for (uint32_t k = 0; k < info.warning_count; ++k) {
            printf("warning: %s\n", info.warnings[k]);
        }
        CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
        int found = 0;
        for (uint32_t i = 0; i < s.material_count && s.material_ext_count == s.material_count;
             ++i) {
            const tr_material_ext *e = &s.material_exts[i];
            if (e->clearcoat <= 0.0f) {
                continue;
            }
            found = 1;
            const uint32_t maps = tr_scene_material_maps(&s, i);
            CHECK(e->clearcoat == 0.9f && e->clearcoat_roughness == 0.7f &&
                      e->clearcoat_tex != TR_NO_INDEX && e->clearcoat_rough_tex != TR_NO_INDEX &&
                      e->clearcoat_tex != e->clearcoat_rough_tex &&
                      (e->clearcoat_normal_tex != TR_NO_INDEX) == (normal != 0) &&
                      (maps & TR_MAP_CLEARCOAT) != 0u && (maps & TR_MAP_CLEARCOAT_ROUGHNESS) != 0u,
                  "coat %g, roughness %g, maps %u and %u (flags %u)", (double)e->clearcoat,
                  (double)e->clearcoat_roughness, e->clearcoat_tex, e->clearcoat_rough_tex, maps);
            tr_bsdf_params b = stage(&s, i);
            CHECK_NEAR(b.clearcoat, 0.9 * 64.0 / 255.0, 1e-3, "coat weight x map A's red");
            CHECK_NEAR(b.clearcoat_roughness, 0.7 * 30.0 / 255.0, 1e-3,
                       "coat roughness x map B's green");
            CHECK_NEAR(b.roughness, 0.5, 0.0, "the base roughness untouched");
        }
        CHECK(found, "no coated material imported from %s", path);
        tr_scene_clear(&s);
    }
    unlink(path);
}

/* Parses a one-material scene file at dir/coat.json: the quad [-1, 1]^2. */
static int parse(tr_scene *s, const char *dir, const char *material, tr_error *err) {
    char path[700];
    snprintf(path, sizeof path, "%s/coat.json", dir);
    return parse_material_quad(s, path, material, -1.0, 1.0, err);
}

/* (b) */
static void scene_file_keys(const char *dir) {
    static const char *const names[2] = {"a.png", "b.png"};
    static const char *const b64[2] = {PNG_A, PNG_B};
    /* The PNGs as files: decoded from base64 here. */
    write_base64_files(dir, names, b64, 2, 0);
    tr_scene s;
    tr_error err;
    CHECK(parse(&s, dir,
                "{\"type\": \"principled\", \"color\": [1, 1, 1], \"clearcoat\": 0.8, "
                "\"clearcoat_roughness\": 0.5, \"clearcoat_texture\": \"a.png\", "
                "\"clearcoat_roughness_texture\": \"b.png\"}",
                &err) == TR_OK,
          "clear coat maps in a scene file: %s", err.msg);
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
    if (s.material_ext_count == s.material_count && s.material_count >= 1) {
        const tr_material_ext *e = &s.material_exts[0];
        CHECK(e->clearcoat_tex != TR_NO_INDEX && e->clearcoat_rough_tex != TR_NO_INDEX &&
                  e->clearcoat_tex != e->clearcoat_rough_tex,
              "the keys made maps %u and %u", e->clearcoat_tex, e->clearcoat_rough_tex);
        tr_bsdf_params b = stage(&s, 0);
        CHECK_NEAR(b.clearcoat, 0.8 * 64.0 / 255.0, 1e-3, "scene file: coat weight x red");
        CHECK_NEAR(b.clearcoat_roughness, 0.5 * 30.0 / 255.0, 1e-3,
                   "scene file: coat roughness x green");
    } else {
        CHECK(0, "the keys made no material extras");
    }
    tr_scene_clear(&s);

    /* Without maps the factors are the stage's. */
    CHECK(parse(&s, dir,
                "{\"type\": \"principled\", \"color\": [1, 1, 1], \"clearcoat\": 0.8, "
                "\"clearcoat_roughness\": 0.5}",
                &err) == TR_OK,
          "%s", err.msg);
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
    if (s.material_ext_count >= 1) {
        tr_bsdf_params b = stage(&s, 0);
        CHECK(b.clearcoat == 0.8f && b.clearcoat_roughness == 0.5f, "coat %g, roughness %g",
              (double)b.clearcoat, (double)b.clearcoat_roughness);
    }
    tr_scene_clear(&s);

    /* The principled material's keys alone. */
    char path[700];
    snprintf(path, sizeof path, "%s/coat.json", dir);
    check_key_refused(path, "coat.json", "clearcoat_texture", "\"a.png\"");
    check_key_refused(path, "coat.json", "clearcoat_roughness_texture", "\"a.png\"");
    write_base64_files(dir, names, b64, 2, 1);
}

int main(void) {
    char dir[] = "/tmp/trac0r-coat-XXXXXX";
    if (!mkdtemp(dir)) {
        CHECK(0, "mkdtemp");
        return check_finish("test_coat_maps");
    }
    gltf_coat_maps(dir);
    scene_file_keys(dir);
    rmdir(dir);
    return check_finish("test_coat_maps");
}
