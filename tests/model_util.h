/* model_util.h - what the model-import tests share: a file written from base64 (the small
 * PNGs they embed) and a model file loaded as `trac0r render FILE` loads it, and a material
 * on a quad in a scene file, for the texture-map keys. */
#ifndef TR_TEST_MODEL_UTIL_H
#define TR_TEST_MODEL_UTIL_H

#include "check.h"
#include "scene/scene_internal.h"
#include "trac0r/trac0r.h"

#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

/* A glTF file's one triangle (0, 0, 0), (1, 0, 0), (0, 1, 0) with texture coordinates
 * (0, 0), (1, 0), (0, 1): its buffer, views and accessors (POSITION 0, TEXCOORD_0 1), and
 * after the materials its mesh (material 0), node and scene, closing the file. Members of
 * the top-level object, each line ending in ",\n" but the scene's. */
#define GLTF_TRIANGLE_GEOMETRY                                                                     \
    " \"buffers\": [{\"byteLength\": 60, \"uri\": "                                                \
    "\"data:application/octet-stream;base64,"                                                      \
    "AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAAAAAAAAAAAAAIA/"                             \
    "AAAAAAAAAAAAAIA/\"}],\n"                                                                      \
    " \"bufferViews\": [{\"buffer\": 0, \"byteOffset\": 0, \"byteLength\": 36},\n"                 \
    "                 {\"buffer\": 0, \"byteOffset\": 36, \"byteLength\": 24}],\n"                 \
    " \"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, \"count\": 3, "                 \
    "\"type\": \"VEC3\", \"min\": [0, 0, 0], \"max\": [1, 1, 0]},\n"                               \
    "               {\"bufferView\": 1, \"componentType\": 5126, \"count\": 3, "                   \
    "\"type\": \"VEC2\"}],\n"
#define GLTF_TRIANGLE_SCENE                                                                        \
    " \"meshes\": [{\"primitives\": [{\"attributes\": {\"POSITION\": 0, "                          \
    "\"TEXCOORD_0\": 1}, \"material\": 0}]}],\n"                                                   \
    " \"nodes\": [{\"mesh\": 0}], \"scenes\": [{\"nodes\": [0]}], \"scene\": 0}\n"

/* Writes the bytes base64 text b64 encodes (at most 4096) to path; 0 on failure. */
static inline int write_base64_file(const char *path, const char *b64) {
    static const char alpha[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    unsigned char bytes[4096];
    size_t n = 0;
    uint32_t acc = 0;
    int bits = 0;
    for (const char *q = b64; *q && *q != '=' && n < sizeof bytes; ++q) {
        const char *at = strchr(alpha, *q);
        if (!at) {
            return 0;
        }
        acc = (acc << 6) | (uint32_t)(at - alpha);
        bits += 6;
        if (bits >= 8) {
            bits -= 8;
            bytes[n++] = (unsigned char)(acc >> bits);
        }
    }
    FILE *f = fopen(path, "wb");
    return f && fwrite(bytes, 1, n, f) == n && fclose(f) == 0;
}

/* Loads model file `path` into *s (initialised here) with the command line's defaults
 * (no up axis, scale 1, the file's camera or the framing one), checking that it loads. */
static inline int load_model_file(tr_scene *s, const char *path, tr_scene_file *info) {
    const tr_model_options opt = {0, 1.0f, 0, 0, NULL};
    tr_error err;
    tr_scene_init(s);
    const int rc = tr_scene_model_load(s, path, &opt, info, &err);
    CHECK(rc == TR_OK, "%s: %s", path, err.msg);
    return rc;
}

/* Parses, as scene file `path` (not written: the text is handed to the parser, and map
 * paths resolve beside it), one material `material` (JSON) on the square [lo, hi]^2 in the
 * plane z = 0, seen from +z through a narrow camera above its centre, under a white
 * environment. The quad's corners are (lo, lo), (hi, lo), (hi, hi), (lo, hi), at texture
 * coordinates (0, 0), (1, 0), (1, 1), (0, 1). */
static inline int parse_material_quad(tr_scene *s, const char *path, const char *material,
                                      double lo, double hi, tr_error *err) {
    char text[1024];
    const double c = 0.5 * (lo + hi);
    snprintf(text, sizeof text,
             "{\"camera\": {\"position\": [%g, %g, 5], \"direction\": [0, 0, -1], \"fov\": 4},\n"
             " \"materials\": {\"m\": %s},\n"
             " \"shapes\": [{\"type\": \"quad\", \"vertices\": [[%g, %g, 0], [%g, %g, 0], "
             "[%g, %g, 0], [%g, %g, 0]], \"material\": \"m\"}],\n"
             " \"environment\": {\"color\": [1, 1, 1]}}",
             c, c, material, lo, lo, hi, lo, hi, hi, lo, hi);
    tr_scene_init(s);
    return tr_scene_file_parse(s, path, text, strlen(text), NULL, NULL, err);
}

/* Writes the n base64-encoded images b64[k] as dir/names[k] (remove: deletes them). */
static inline void write_base64_files(const char *dir, const char *const *names,
                                      const char *const *b64, int n, int remove) {
    for (int k = 0; k < n; ++k) {
        char path[700];
        snprintf(path, sizeof path, "%s/%s", dir, names[k]);
        if (remove) {
            unlink(path);
        } else {
            CHECK(write_base64_file(path, b64[k]), "cannot write %s", path);
        }
    }
}

/* A diffuse material carrying the principled key `key` (value `value`, JSON) is refused
 * with TR_STATUS_PARSE, and the refusal names the file (`file`, its last part) and the key. */
static inline void check_key_refused(const char *path, const char *file, const char *key,
                                     const char *value) {
    char material[256];
    snprintf(material, sizeof material, "{\"type\": \"diffuse\", \"color\": [1, 1, 1], \"%s\": %s}",
             key, value);
    tr_scene s;
    tr_error err;
    const int rc = parse_material_quad(&s, path, material, 0.0, 1.0, &err);
    CHECK_STATUS(rc, err, TR_STATUS_PARSE, key);
    CHECK(rc != TR_OK && strstr(err.msg, file) && strstr(err.msg, key),
          "the refusal of %s on a diffuse material names neither file nor key: %s", key,
          rc != TR_OK ? err.msg : "accepted");
    tr_scene_clear(&s);
}

#endif
