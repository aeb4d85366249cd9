/* test_texture_transform.c - glTF's KHR_texture_transform (a texture's coordinates moved
 * by an offset, a rotation and a scale before the lookup, src/kernel/texture.h).
 *
 *  (a) The matrix: tr_texture_transform_glTF gives KHR_texture_transform's T R S, checked
 *      against coordinates worked out by hand for an offset, a quarter turn and a scale.
 *  (b) The lookup: a 4x4 texture of distinct texels seen through a transformed entry gives,
 *      at hand-picked (u, v), the texel whose centre the transform sends them to; the
 *      identity adds no entry.
 *  (c) Scene-file keys: a texture object's "offset", "rotation" and "scale" make the
 *      material's map a transformed entry over the same texels; without them the map is the
 *      plain texture; a malformed value is refused (TR_STATUS_PARSE).
 *  (d) glTF import: a glTF written here whose base colour map has the extension becomes a
 *      transformed entry with the file's offset, rotation and scale (through Assimp's own
 *      form of the transform and back), and no warning names the extension. */
#define _POSIX_C_SOURCE 200809L
#include "check.h"
#include "model_util.h"
#include "kernel/kernel.h"
#include "scene/scene_internal.h"
#include "trac0r/trac0r.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static char dir[600];

/* (a) */
static void matrix(void) {
    float xf[6];
    /* offset (0.25, 0.5), rotation pi/2, scale (2, 1):
     * u' = cos(r) 2 u + sin(r) v + 0.25 = v + 0.25, v' = -sin(r) 2 u + cos(r) v + 0.5 = -2u + 0.5
     */
    tr_texture_transform_glTF(xf, 0.25f, 0.5f, 1.57079632679f, 2.0f, 1.0f);
    const float want[6] = {0.0f, 1.0f, 0.25f, -2.0f, 0.0f, 0.5f};
    for (int k = 0; k < 6; ++k) {
        CHECK(fabsf(xf[k] - want[k]) < 1e-6f, "xf[%d] = %g, by hand %g", k, (double)xf[k],
              (double)want[k]);
    }
}

/* A 4x4 texture whose texel (x, y) is (16 x, 16 y, 200) in RGB. */
static uint32_t add_grid(tr_scene *s) {
    uint32_t px[16], idx = TR_NO_INDEX;
    for (uint32_t y = 0; y < 4; ++y) {
        for (uint32_t x = 0; x < 4; ++x) {
            px[y * 4 + x] = (16u * x) | (16u * y) << 8 | 200u << 16 | 255u << 24;
        }
    }
    tr_error err;
    CHECK(tr_scene_add_texture(s, px, 4, 4, TR_TEXTURE_CLAMP, &idx, &err) == TR_OK, "%s", err.msg);
    return idx;
}

/* (b) */
static void lookup(void) {
    tr_scene s;
    tr_scene_init(&s);
    const uint32_t base = add_grid(&s);
    float xf[6], id[6];
    tr_texture_transform_glTF(xf, 0.25f, 0.5f, 1.57079632679f, 2.0f, 1.0f);
    tr_texture_transform_glTF(id, 0.0f, 0.0f, 0.0f, 1.0f, 1.0f);
    uint32_t moved = TR_NO_INDEX, same = TR_NO_INDEX;
    tr_error err;
    CHECK(tr_scene_texture_transformed(&s, base, xf, &moved, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_scene_texture_transformed(&s, base, id, &same, &err) == TR_OK, "%s", err.msg);
    CHECK(same == base && s.texture_count == 2 && moved == 1,
          "identity %u (base %u), moved %u, %u entries", same, base, moved, s.texture_count);
    CHECK(s.textures[moved].offset == s.textures[base].offset &&
              (s.textures[moved].flags & TR_TEXTURE_TRANSFORM) != 0u,
          "the transformed entry shares the texels");
    const tr_scene_view v = tr_scene_view_of(&s);
    /* (u, v) -> (v + 0.25, -2u + 0.5): texel centres are at (i + 0.5) / 4. */
    const float uv[3][2] = {{-0.0625f, 0.125f}, {-0.1875f, 0.625f}, {-0.1875f, -0.125f}};
    const int texel[3][2] = {{1, 2}, {3, 3}, {0, 3}};
    for (int k = 0; k < 3; ++k) {
        float a;
        tr_vec3 got = tr_texture_sample(&v, moved, uv[k][0], uv[k][1], 0, &a);
        const float wx = 16.0f * (float)texel[k][0] / 255.0f,
                    wy = 16.0f * (float)texel[k][1] / 255.0f;
        CHECK(fabsf(got.x - wx) < 1e-4f && fabsf(got.y - wy) < 1e-4f &&
                  fabsf(got.z - 200.0f / 255.0f) < 1e-4f,
              "(%g, %g): (%g, %g, %g), texel (%d, %d) expected", (double)uv[k][0], (double)uv[k][1],
              (double)got.x, (double)got.y, (double)got.z, texel[k][0], texel[k][1]);
    }
    const float bad[6] = {1.0f, 0.0f, NAN, 0.0f, 1.0f, 0.0f};
    CHECK_STATUS(tr_scene_texture_transformed(&s, base, bad, &same, &err), err,
                 TR_STATUS_INVALID_ARGUMENT, "a NaN in the transform");
    CHECK_STATUS(tr_scene_texture_transformed(&s, 7, xf, &same, &err), err, TR_STATUS_NOT_FOUND,
                 "texture 7 of 2");
    tr_scene_clear(&s);
}

static void write_png(const char *path) {
    tr_error err;
    tr_film film;
    CHECK(tr_film_init(&film, 4, 4, &err) == TR_OK, "%s", err.msg);
    for (size_t i = 0; i < 16; ++i) {
        film.count[i] = 1;
        film.sum[3 * i] = film.sum[3 * i + 1] = film.sum[3 * i + 2] = (float)(i % 2);
    }
    CHECK(tr_film_write_png(&film, path, 0.0f, &err) == TR_OK, "%s", err.msg);
    tr_film_free(&film);
}

static int parse(tr_scene *s, const char *tex, tr_error *err) {
    char text[2048], path[700];
    snprintf(text, sizeof text,
             "{\"camera\": {\"position\": [0, 0, 3], \"direction\": [0, 0, -1], \"fov\": 40},\n"
             " \"materials\": {\"m\": {\"type\": \"diffuse\", \"color\": [1, 1, 1], "
             "\"texture\": %s}},\n"
             " \"shapes\": [{\"type\": \"plane\", \"material\": \"m\"}],\n"
             " \"environment\": {\"color\": [1, 1, 1]}}",
             tex);
    snprintf(path, sizeof path, "%s/t.json", dir);
    tr_scene_init(s);
    return tr_scene_file_parse(s, path, text, strlen(text), NULL, NULL, err);
}

/* (c) */
static void keys(void) {
    tr_scene s;
    tr_error err;
    CHECK(parse(&s,
                "{\"path\": \"c.png\", \"offset\": [0.25, 0.5], \"rotation\": 0.3, "
                "\"scale\": [2, 3]}",
                &err) == TR_OK,
          "%s", err.msg);
    if (s.material_ext_count > 0 && s.material_exts[0].base_tex < s.texture_count) {
        const tr_texture *t = &s.textures[s.material_exts[0].base_tex];
        float want[6];
        tr_texture_transform_glTF(want, 0.25f, 0.5f, 0.3f, 2.0f, 3.0f);
        CHECK((t->flags & TR_TEXTURE_TRANSFORM) != 0u && memcmp(t->xf, want, sizeof want) == 0,
              "the keys' transform reaches the map (flags %u)", t->flags);
    } else {
        CHECK(0, "no base map");
    }
    tr_scene_clear(&s);
    CHECK(parse(&s, "{\"path\": \"c.png\", \"wrap\": \"clamp\"}", &err) == TR_OK, "%s", err.msg);
    CHECK(s.texture_count == 1 && s.material_exts[0].base_tex == 0 &&
              (s.textures[0].flags & TR_TEXTURE_TRANSFORM) == 0u,
          "without the keys the map is the plain texture");
    tr_scene_clear(&s);
    const char *bad[] = {"{\"path\": \"c.png\", \"offset\": [1]}",
                         "{\"path\": \"c.png\", \"scale\": \"big\"}",
                         "{\"path\": \"c.png\", \"rotation\": [1, 2]}",
                         "{\"path\": \"c.png\", \"offset\": [1, 1e9]}"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        int rc = parse(&s, bad[i], &err);
        CHECK(rc != TR_OK && err.code == TR_STATUS_PARSE && strstr(err.msg, "materials.m.texture"),
              "refused (%s): %s", rc != TR_OK ? err.msg : "accepted", bad[i]);
        tr_scene_clear(&s);
    }
}

/* (d) */
static void gltf_import(void) {
    static const char *gltf =
        "{\"asset\": {\"version\": \"2.0\"},\n"
        " \"extensionsUsed\": [\"KHR_texture_transform\"],\n"
        " \"buffers\": [{\"byteLength\": 60, \"uri\": \"data:application/octet-stream;base64,"
        "AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAAAAAAAAAAAAAIA/AAAAAAAAAAAAAIA/\"}],\n"
        " \"bufferViews\": [{\"buffer\": 0, \"byteOffset\": 0, \"byteLength\": 36},\n"
        "                 {\"buffer\": 0, \"byteOffset\": 36, \"byteLength\": 24}],\n"
        " \"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, \"count\": 3, \"type\": "
        "\"VEC3\", \"min\": [0, 0, 0], \"max\": [1, 1, 0]},\n"
        "               {\"bufferView\": 1, \"componentType\": 5126, \"count\": 3, \"type\": "
        "\"VEC2\"}],\n"
        " \"images\": [{\"uri\": \"c.png\"}], \"textures\": [{\"source\": 0}],\n"
        " \"materials\": [{\"name\": \"atlas\", \"pbrMetallicRoughness\": {\"baseColorTexture\": "
        "{\"index\": 0, \"extensions\": {\"KHR_texture_transform\": {\"offset\": [0.25, 0.5], "
        "\"rotation\": 0.3, \"scale\": [2, 3]}}}, \"metallicFactor\": 0}}],\n"
        " \"meshes\": [{\"primitives\": [{\"attributes\": {\"POSITION\": 0, \"TEXCOORD_0\": 1}, "
        "\"material\": 0}]}],\n"
        " \"nodes\": [{\"mesh\": 0}], \"scenes\": [{\"nodes\": [0]}], \"scene\": 0}\n";
    char path[700];
    snprintf(path, sizeof path, "%s/atlas.gltf", dir);
    FILE *f = fopen(path, "w");
    CHECK(f && fputs(gltf, f) >= 0 && fclose(f) == 0, "cannot write %s", path);
    tr_scene s;
    tr_scene_file info;
    load_model_file(&s, path, &info);
    float want[6];
    tr_texture_transform_glTF(want, 0.25f, 0.5f, 0.3f, 2.0f, 3.0f);
    int found = 0;
    for (uint32_t i = 0; i < s.material_ext_count; ++i) {
        const uint32_t b = s.material_exts[i].base_tex;
        if (b == TR_NO_INDEX || b >= s.texture_count) {
            continue;
        }
        found = 1;
        const tr_texture *t = &s.textures[b];
        CHECK((t->flags & TR_TEXTURE_TRANSFORM) != 0u, "the imported map has no transform");
        for (int k = 0; k < 6; ++k) {
            CHECK(fabsf(t->xf[k] - want[k]) < 1e-5f, "imported xf[%d] = %g, the file's %g", k,
                  (double)t->xf[k], (double)want[k]);
        }
    }
    CHECK(found, "no textured material imported");
    CHECK(info.warning_count == 0, "%u warnings", info.warning_count);
    tr_scene_clear(&s);
    unlink(path);
}

int main(void) {
    const char *tmp = getenv("TMPDIR");
    snprintf(dir, sizeof dir, "%s/trac0r-test-uvxf-XXXXXX", tmp && *tmp ? tmp : "/tmp");
    if (!mkdtemp(dir)) {
        perror("mkdtemp");
        return 1;
    }
    char png[700];
    snprintf(png, sizeof png, "%s/c.png", dir);
    write_png(png);
    matrix();
    lookup();
    keys();
    gltf_import();
    unlink(png);
    rmdir(dir);
    return check_finish("test_texture_transform");
}
