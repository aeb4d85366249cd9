/* checkpoint.c - the session's checkpoint files (checkpoint.h). */
#define _POSIX_C_SOURCE 200809L
#include "session/checkpoint.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "trac0r/outfile.h"

static const char magic[8] = {'T', 'R', 'A', 'C', '0', 'R', 'C', 'K'};
/* 3: one format for renders in one process and in many: per-tile sample counts, and every
 * array of the film's layout (the direct and emission passes too). */
#define CK_VERSION 3u
#define BYTE_ORDER_MARK 0x01020304u
#define HEAD_WORDS 9

/* FNV-1a, 64-bit (Fowler, Noll, Vo): a fast hash; checkpoints need to tell renders apart
 * and catch damage, not resist an adversary. */
#define FNV_PRIME 1099511628211ull

uint64_t tr_ck_fnv(uint64_t h, const void *data, size_t n) {
    const unsigned char *p = data;
    for (size_t i = 0; i < n; ++i) {
        h = (h ^ p[i]) * FNV_PRIME;
    }
    return h;
}

/* The bytes of the film's arrays for a film of w x h keeping `passes`. */
static uint64_t film_bytes(uint32_t w, uint32_t h, uint32_t passes) {
    return (uint64_t)w * h * tr_film_pixel_bytes(passes);
}

typedef struct hashed_writer {
    FILE *fp;
    uint64_t h;
} hashed_writer;

static void put(hashed_writer *w, const void *data, size_t n) {
    w->h = tr_ck_fnv(w->h, data, n);
    fwrite(data, 1, n, w->fp);
}

int tr_ck_write(const char *path, const tr_ck_id *id, const tr_film *film, uint32_t spp,
                const tr_ck_tiles *tiles, tr_error *err) {
    tr_outfile *out = tr_outfile_create(path, err);
    if (!out) {
        return TR_ERR;
    }
    hashed_writer w = {tr_outfile_stream(out), TR_CK_FNV_OFFSET};
    const uint32_t head[HEAD_WORDS] = {CK_VERSION,   BYTE_ORDER_MARK, film->width,
                                       film->height, film->passes,    spp,
                                       tiles->side,  tiles->count,    (uint32_t)strlen(id->desc)};
    put(&w, magic, sizeof magic);
    put(&w, head, sizeof head);
    put(&w, &id->scene_hash, sizeof id->scene_hash);
    put(&w, id->desc, head[8]);
    put(&w, tiles->samples, (size_t)tiles->count * sizeof *tiles->samples);
    const size_t n = (size_t)film->width * film->height;
    for (int i = 0; i < TR_FILM_ARRAYS; ++i) {
        const void *a = tr_film_array_data(film, i);
        if (a) {
            put(&w, a, n * tr_film_array_pixel_bytes(i));
        }
    }
    const uint64_t sum = w.h;
    fwrite(&sum, sizeof sum, 1, w.fp);
    return tr_outfile_commit(out, err);
}

/* Names the first setting of `want` whose value differs in `got` (both "key=value ..."). */
static void describe_difference(const char *got, const char *want, char *buf, size_t size) {
    const char *g = got, *w = want;
    while (*g && *w) {
        const size_t gl = strcspn(g, " "), wl = strcspn(w, " ");
        if (gl != wl || strncmp(g, w, gl) != 0) {
            snprintf(buf, size, "it has %.*s, this render %.*s", (int)gl, g, (int)wl, w);
            return;
        }
        g += gl + (g[gl] == ' ');
        w += wl + (w[wl] == ' ');
    }
    snprintf(buf, size, "it has '%s', this render '%s'", got, want);
}

/* Opens a checkpoint when it is a regular file, without blocking first (a FIFO is refused
 * rather than waited on forever); *size gets its length. */
static FILE *open_regular(const char *path, uint64_t *size, tr_error *err) {
    const int fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    struct stat st;
    if (fd < 0 || fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        const int e = fd < 0 ? errno : 0;
        if (fd >= 0) {
            close(fd);
        }
        /* A name that is no file, or not a regular one, is the caller's mistake (a usage
         * error), as opposed to a file that cannot be read. */
        tr_error_set(err,
                     !e           ? TR_STATUS_INVALID_ARGUMENT
                     : e == ELOOP ? TR_STATUS_NOT_FOUND
                                  : tr_status_from_errno(e),
                     "%.200s: cannot open: %s", path, e ? strerror(e) : "not a regular file");
        return NULL;
    }
    *size = (uint64_t)st.st_size;
    FILE *fp = fdopen(fd, "rb");
    if (!fp) {
        const int e = errno;
        close(fd);
        tr_error_set(err, tr_status_from_errno(e), "%.200s: cannot open: %s", path, strerror(e));
    }
    return fp;
}

typedef struct hashed_reader {
    FILE *fp;
    uint64_t h;
} hashed_reader;

static int take(hashed_reader *r, void *out, size_t n) {
    if (fread(out, 1, n, r->fp) != n) {
        return -1;
    }
    r->h = tr_ck_fnv(r->h, out, n);
    return 0;
}

/* The header: magic, words, scene hash and description, checked against what the file's
 * size and this reader allow. */
static int read_header(hashed_reader *r, const char *path, uint64_t size, uint32_t head[HEAD_WORDS],
                       uint64_t *scene_hash, char desc[512], tr_error *err) {
    char got[8];
    if (take(r, got, sizeof got) != 0 || memcmp(got, magic, sizeof magic) != 0) {
        return tr_error_set(err, TR_STATUS_PARSE, "%s: not a trac0r checkpoint", path);
    }
    if (take(r, head, HEAD_WORDS * sizeof *head) != 0) {
        return tr_error_set(err, TR_STATUS_PARSE, "%s: truncated checkpoint header", path);
    }
    if (head[1] != BYTE_ORDER_MARK) {
        return tr_error_set(err, TR_STATUS_PARSE,
                            "%s: the checkpoint was written on a machine of another byte order "
                            "(mark 0x%08x, this one's 0x%08x)",
                            path, head[1], BYTE_ORDER_MARK);
    }
    if (head[0] != CK_VERSION) {
        return tr_error_set(err, TR_STATUS_PARSE,
                            "%s: checkpoint format version %u, but this trac0r reads version %u "
                            "only: resume it with the trac0r that wrote it, or render again",
                            path, head[0], CK_VERSION);
    }
    tr_error size_err;
    if (tr_film_check_size(head[2], head[3], &size_err) != TR_OK || (head[4] & ~TR_PASS_MASK) ||
        head[8] >= 512 || head[7] == 0 || head[7] > TR_FILM_MAX_PIXELS) {
        return tr_error_set(err, TR_STATUS_PARSE, "%s: bad checkpoint header", path);
    }
    const uint64_t want = sizeof magic + HEAD_WORDS * 4u + 8u + head[8] + 4ull * head[7] +
                          film_bytes(head[2], head[3], head[4]) + 8u;
    if (size != want) {
        return tr_error_set(err, TR_STATUS_PARSE,
                            "%s: the checkpoint has %llu bytes where its header says %llu", path,
                            (unsigned long long)size, (unsigned long long)want);
    }
    if (take(r, scene_hash, sizeof *scene_hash) != 0 || take(r, desc, head[8]) != 0) {
        return tr_error_set(err, TR_STATUS_PARSE, "%s: truncated checkpoint header", path);
    }
    desc[head[8]] = '\0';
    return TR_OK;
}

/* The rest: tile samples and the film's arrays, then the checksum. */
static int read_body(hashed_reader *r, const char *path, const uint32_t head[HEAD_WORDS],
                     tr_ck_tiles *tiles, tr_film *film, tr_error *err) {
    if (take(r, tiles->samples, (size_t)tiles->count * sizeof *tiles->samples) != 0) {
        return tr_error_set(err, TR_STATUS_PARSE, "%s: truncated tiles", path);
    }
    if (tr_film_init_passes(film, head[2], head[3], head[4], err) != TR_OK) {
        return TR_ERR;
    }
    const size_t n = (size_t)film->width * film->height;
    for (int i = 0; i < TR_FILM_ARRAYS; ++i) {
        void *a = tr_film_array_data(film, i);
        if (a && take(r, a, n * tr_film_array_pixel_bytes(i)) != 0) {
            return tr_error_set(err, TR_STATUS_PARSE, "%s: truncated film", path);
        }
    }
    const uint64_t h = r->h;
    uint64_t sum = 0;
    if (fread(&sum, sizeof sum, 1, r->fp) != 1 || sum != h) {
        return tr_error_set(err, TR_STATUS_PARSE, "%s: damaged checkpoint (checksum mismatch)",
                            path);
    }
    for (uint32_t k = 0; k < tiles->count; ++k) {
        if (tiles->samples[k] > head[5]) {
            return tr_error_set(err, TR_STATUS_PARSE, "%s: tile %u holds %u samples of %u", path, k,
                                tiles->samples[k], head[5]);
        }
    }
    /* Every pixel holds the samples of its tile (a preview's blocks fill every pixel of a
     * tile alike): a tile claimed rendered with pixels that are not would resume with a
     * hole, one claimed empty would add samples twice. */
    const uint32_t side = tiles->side, nx = (film->width + side - 1) / side;
    for (uint32_t y = 0; y < film->height; ++y) {
        for (uint32_t x = 0; x < film->width; ++x) {
            const uint32_t k = (y / side) * nx + x / side;
            const uint32_t c = film->count[(size_t)y * film->width + x];
            if (k >= tiles->count || c != tiles->samples[k]) {
                return tr_error_set(err, TR_STATUS_PARSE,
                                    "%s: pixel (%u, %u) holds %u samples where its tile holds %u",
                                    path, x, y, c, k < tiles->count ? tiles->samples[k] : 0u);
            }
        }
    }
    return TR_OK;
}

int tr_ck_read(const char *path, const tr_ck_id *id, tr_ck_tiles *tiles, tr_film *film,
               uint32_t *spp, tr_error *err) {
    memset(film, 0, sizeof *film);
    uint64_t size = 0;
    FILE *fp = open_regular(path, &size, err);
    if (!fp) {
        return TR_ERR;
    }
    hashed_reader r = {fp, TR_CK_FNV_OFFSET};
    uint32_t head[HEAD_WORDS] = {0};
    uint64_t scene_hash = 0;
    char desc[512];
    int rc = read_header(&r, path, size, head, &scene_hash, desc, err);
    if (rc == TR_OK && scene_hash != id->scene_hash) {
        rc = tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                          "%s: the checkpoint is of another scene (scene hash %016llx, this "
                          "render's %016llx)",
                          path, (unsigned long long)scene_hash, (unsigned long long)id->scene_hash);
    } else if (rc == TR_OK && strcmp(desc, id->desc) != 0) {
        char diff[1100];
        describe_difference(desc, id->desc, diff, sizeof diff);
        rc = tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                          "%s: the checkpoint is of a render with other options: %s", path, diff);
    } else if (rc == TR_OK && (head[6] != tiles->side || head[7] != tiles->count)) {
        /* The plan follows from the size and stride, which the identity holds. */
        rc = tr_error_set(err, TR_STATUS_PARSE, "%s: bad tile plan (%u tiles of %u)", path, head[7],
                          head[6]);
    } else if (rc == TR_OK &&
               (head[2] != id->width || head[3] != id->height || head[4] != id->passes)) {
        /* The description names them too, but a file can say one thing there and another
         * in its header. */
        rc = tr_error_set(err, TR_STATUS_PARSE,
                          "%s: the checkpoint's film is %ux%u with passes 0x%x where its render's "
                          "is %ux%u with passes 0x%x",
                          path, head[2], head[3], head[4], id->width, id->height, id->passes);
    } else if (rc == TR_OK && head[5] == 0) {
        rc = tr_error_set(err, TR_STATUS_PARSE, "%s: bad sample count 0", path);
    } else if (rc == TR_OK && head[5] > id->spp_max) {
        rc = tr_error_set(err, TR_STATUS_LIMIT,
                          "%s: the checkpoint asks for %u samples per pixel, more than the %u a "
                          "render may (--spp)",
                          path, head[5], id->spp_max);
    }
    if (rc == TR_OK) {
        rc = read_body(&r, path, head, tiles, film, err);
    }
    if (rc == TR_OK && ferror(fp)) {
        rc = tr_error_set(err, TR_STATUS_IO, "%s: read error", path);
    }
    fclose(fp);
    if (rc != TR_OK) {
        tr_film_free(film);
        return TR_ERR;
    }
    *spp = head[5];
    return TR_OK;
}
