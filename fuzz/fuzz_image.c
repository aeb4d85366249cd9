/* fuzz_image.c - libFuzzer target for the image readers of `trac0r compare`
 * (tr_image_read_png and tr_image_read_pfm in src/io/image.c, tr_image_read_exr in
 * src/io/exr.c through OpenEXRCore).
 *
 * The first byte picks the reader (its value mod 3: PFM, PNG, EXR), the rest is the file, written
 * to a private directory (the readers take paths). An image that reads must have a size within the
 * film limits and finite-or-not floats in a buffer of exactly that size (ASan checks the bounds);
 * one that fails must leave the image empty. -rss_limit_mb catches a header whose
 * declared size is allocated before it is checked. Built by fuzz/build.sh; run by
 * fuzz/run.sh. */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <unistd.h>

#include "trac0r/film.h"
#include "trac0r/image.h"

static char dir[64];

/* The private directory goes when libFuzzer exits. */
static void remove_dir(void) {
    static const char *const names[] = {"model.obj", "model.ply", "model.gltf",
                                        "model.glb", "model.stl", "model.off",
                                        "image.png", "image.pfm", "image.exr"};
    for (size_t i = 0; i < sizeof names / sizeof names[0]; ++i) {
        char p[128];
        snprintf(p, sizeof p, "%s/%s", dir, names[i]);
        unlink(p);
    }
    rmdir(dir);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    if (size < 1) {
        return 0;
    }
    if (!dir[0]) {
        snprintf(dir, sizeof dir, "/tmp/trac0r-fuzz-image-%ld", (long)getpid());
        if (mkdir(dir, 0700) != 0 && errno != EEXIST) {
            abort();
        }
        atexit(remove_dir);
    }
    static const char *const ext[] = {"pfm", "png", "exr"};
    const int kind = data[0] % 3;
    char path[128];
    snprintf(path, sizeof path, "%s/image.%s", dir, ext[kind]);
    FILE *fp = fopen(path, "wb");
    if (!fp || fwrite(data + 1, 1, size - 1, fp) != size - 1 || fclose(fp) != 0) {
        abort();
    }
    tr_image img;
    tr_error err;
    const int rc = kind == 1   ? tr_image_read_png(&img, path, &err)
                   : kind == 2 ? tr_image_read_exr(&img, path, NULL, &err)
                               : tr_image_read_pfm(&img, path, &err);
    if (rc == TR_OK) {
        if (img.width == 0 || img.height == 0 || img.width > TR_FILM_MAX_SIDE ||
            img.height > TR_FILM_MAX_SIDE ||
            (uint64_t)img.width * img.height > TR_FILM_MAX_PIXELS || !img.rgb) {
            abort();
        }
        volatile float sink = 0.0f;
        const size_t n = (size_t)img.width * img.height * 3;
        sink += img.rgb[0] + img.rgb[n - 1]; /* both ends of the buffer exist */
        (void)sink;
        tr_image_free(&img);
    } else if (img.rgb || img.width || img.height) {
        abort();
    }
    return 0;
}
