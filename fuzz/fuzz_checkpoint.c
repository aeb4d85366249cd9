/* fuzz_checkpoint.c - libFuzzer target for the checkpoint reader (tr_ck_read in
 * src/session/checkpoint.c), which `trac0r render --resume` and every MPI rank call on a
 * file a user names.
 *
 * The input is the file, written to a private directory (the reader takes a path). The
 * render it must belong to is taken from the input itself - its scene hash, description and
 * tile plan, where the input is long enough to hold them - so that the fuzzer gets past the
 * identity check into the tile counts, the film's arrays and the checksum. A file that reads
 * must give a film of the size its header claims, within the film limits, with tile counts
 * no larger than its spp, the film the identity names and no more samples than --spp
 * allows; one that fails must leave the film empty. -rss_limit_mb catches a
 * size that is allocated before it is checked against the file. Built by fuzz/build.sh; run
 * by fuzz/run.sh. */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "session/checkpoint.h"

static char dir[64];
static char path[96];

static void remove_dir(void) {
    unlink(path);
    rmdir(dir);
}

/* A little-endian uint32 at byte `at` of the input (0 past its end). */
static uint32_t word(const uint8_t *data, size_t size, size_t at) {
    uint32_t v = 0;
    if (at + 4 <= size) {
        memcpy(&v, data + at, 4);
    }
    return v;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    if (!dir[0]) {
        snprintf(dir, sizeof dir, "/tmp/trac0r-fuzz-ck-%ld", (long)getpid());
        if (mkdir(dir, 0700) != 0 && errno != EEXIST) {
            abort();
        }
        snprintf(path, sizeof path, "%s/input.ck", dir);
        atexit(remove_dir);
    }
    FILE *fp = fopen(path, "wb");
    if (!fp || fwrite(data, 1, size, fp) != size || fclose(fp) != 0) {
        abort();
    }
    /* magic (8), nine words (36), scene hash (8), description (word 8 bytes long). */
    tr_ck_id id;
    memset(&id, 0, sizeof id);
    const uint32_t desc_len = word(data, size, 8 + 4 * 8);
    if (size >= 52) {
        memcpy(&id.scene_hash, data + 44, 8);
    }
    if (desc_len < sizeof id.desc && 52 + (size_t)desc_len <= size) {
        memcpy(id.desc, data + 52, desc_len);
    }
    /* The film and sample limit the render expects: the header's own, so that the reader
     * goes on to the arrays (the limit on spp is the real one). */
    id.width = word(data, size, 8 + 4 * 2);
    id.height = word(data, size, 8 + 4 * 3);
    id.passes = word(data, size, 8 + 4 * 4);
    id.spp_max = 1000000u;
    const uint32_t plan_count = word(data, size, 8 + 4 * 7);
    tr_ck_tiles tiles = {word(data, size, 8 + 4 * 6), plan_count > 4096 ? 4096 : plan_count, NULL};
    tiles.samples = calloc(tiles.count ? tiles.count : 1, sizeof *tiles.samples);
    if (!tiles.samples) {
        abort();
    }
    tr_film film;
    tr_error err;
    uint32_t spp = 0;
    if (tr_ck_read(path, &id, &tiles, &film, &spp, &err) == TR_OK) {
        if (!film.sum || !film.count || film.width == 0 || film.height == 0 ||
            (uint64_t)film.width * film.height > TR_FILM_MAX_PIXELS || spp == 0) {
            abort();
        }
        for (uint32_t k = 0; k < tiles.count; ++k) {
            if (tiles.samples[k] > spp) {
                abort();
            }
        }
        if (film.width != id.width || film.height != id.height || film.passes != id.passes ||
            spp > id.spp_max) {
            abort();
        }
        /* Touch the last byte of every array: ASan checks the allocation's size. */
        const size_t n = (size_t)film.width * film.height;
        volatile unsigned char sink = 0;
        for (int i = 0; i < TR_FILM_ARRAYS; ++i) {
            const unsigned char *a = tr_film_array_data(&film, i);
            if (a) {
                sink ^= a[n * tr_film_array_pixel_bytes(i) - 1];
            }
        }
        (void)sink;
        tr_film_free(&film);
    } else if (film.sum || film.count) {
        abort();
    }
    free(tiles.samples);
    return 0;
}
