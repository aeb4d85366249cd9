/* model_util.h - what the model-import tests share: a file written from base64 (the small
 * PNGs they embed) and a model file loaded as `trac0r render FILE` loads it. */
#ifndef TR_TEST_MODEL_UTIL_H
#define TR_TEST_MODEL_UTIL_H

#include "check.h"
#include "scene/scene_internal.h"
#include "trac0r/trac0r.h"

#include <stdint.h>
#include <stdio.h>
#include <string.h>

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

#endif
