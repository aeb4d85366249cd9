/* checkpoint.c - see checkpoint.h. */
#define _POSIX_C_SOURCE 200809L
#include "checkpoint.h"

#include <errno.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "trac0r/outfile.h"

static const char magic[8] = {'T', 'R', 'A', 'C', '0', 'R', 'C', 'K'};
/* 2: the film's sums of squared radiance (TR_PASS_VARIANCE) after the primitive ids. */
#define CHECKPOINT_VERSION 2u
#define BYTE_ORDER_MARK 0x01020304u

/* FNV-1a, 64-bit (Fowler, Noll, Vo): a fast hash; checkpoints need to tell renders apart
 * and catch damage, not resist an adversary. */
#define FNV_OFFSET 14695981039346656037ull
#define FNV_PRIME 1099511628211ull

static uint64_t fnv(uint64_t h, const void *data, size_t n) {
    const unsigned char *p = data;
    for (size_t i = 0; i < n; ++i) {
        h = (h ^ p[i]) * FNV_PRIME;
    }
    return h;
}

static uint64_t fnv_floats(uint64_t h, const float *v, size_t n) {
    return fnv(h, v, n * sizeof *v);
}

static uint64_t fnv_u32(uint64_t h, uint32_t v) {
    return fnv(h, &v, sizeof v);
}

/* The scene file's bytes: its meshes are in the geometry hashed below, but settings the
 * geometry does not show (a light's sampling, a future field) are in the file. */
static int hash_file(uint64_t *h, const char *path, tr_error *err) {
    FILE *fp = fopen(path, "rb");
    if (!fp) {
        return tr_error_set(err, tr_status_from_errno(errno), "%s: cannot read: %s", path,
                            strerror(errno));
    }
    unsigned char buf[65536];
    size_t n;
    while ((n = fread(buf, 1, sizeof buf, fp)) > 0) {
        *h = fnv(*h, buf, n);
    }
    const int bad = ferror(fp);
    fclose(fp);
    if (bad) {
        return tr_error_set(err, TR_STATUS_IO, "%s: read error", path);
    }
    return TR_OK;
}

int checkpoint_identity(checkpoint_id *id, const cli_common *c, const tr_scene *scene, int stride,
                        uint32_t passes, tr_error *err) {
    memset(id, 0, sizeof *id);
    /* The sampler and the light selection decide the samples too: a film resumed with
     * other ones would mix two sequences of points. */
    const char *sampler = cli_sampler_name(c->sampler);
    snprintf(id->desc, sizeof id->desc,
             "size=%ux%u seed=%llu max-depth=%d integrator=%s accel=%s stride=%d passes=0x%x "
             "sampler=%s light-sampling=%s",
             c->width, c->height, (unsigned long long)c->seed, c->max_depth,
             tr_integrator_name(c->integrator), tr_accel_name(c->accel), stride, passes, sampler,
             c->light_sampling < 0 ? "scene" : tr_light_sampling_name(c->light_sampling));
    /* pt's roulette start decides the paths as well; named only when it is not the
     * default, so that a checkpoint of a default render keeps the identity it had before
     * the option existed. */
    const int rr = c->roulette_start ? c->roulette_start : TR_ROULETTE_START_PT;
    if (rr != TR_ROULETTE_START_PT) {
        const size_t used = strlen(id->desc);
        snprintf(id->desc + used, sizeof id->desc - used, " roulette-start=%d", rr);
    }
    uint64_t h = FNV_OFFSET;
    const uint32_t nt = tr_scene_triangle_count(scene);
    h = fnv_u32(h, nt);
    for (uint32_t i = 0; i < nt; ++i) {
        const tr_triangle t = tr_scene_triangle(scene, i);
        const float v[9] = {t.v0.x, t.v0.y, t.v0.z, t.v1.x, t.v1.y, t.v1.z, t.v2.x, t.v2.y, t.v2.z};
        h = fnv_u32(fnv_floats(h, v, 9), t.material);
    }
    const uint32_t nm = tr_scene_material_count(scene);
    h = fnv_u32(h, nm);
    for (uint32_t i = 0; i < nm; ++i) {
        const tr_material m = tr_scene_material(scene, i);
        const float v[6] = {m.color.x, m.color.y, m.color.z, m.roughness, m.ior, m.emittance};
        h = fnv_u32(fnv_u32(fnv_floats(h, v, 6), m.type), m.flags);
    }
    const tr_camera *cam = tr_scene_camera(scene);
    const float v[10] = {cam->pos.x,      cam->pos.y,       cam->pos.z,      cam->dir.x,
                         cam->dir.y,      cam->dir.z,       cam->world_up.x, cam->world_up.y,
                         cam->world_up.z, cam->vertical_fov};
    h = fnv_floats(h, v, 10);
    if (!cli_scene_is_builtin(c->scene) && hash_file(&h, c->scene, err) != TR_OK) {
        return TR_ERR;
    }
    id->scene_hash = h;
    return TR_OK;
}

/* The arrays a film keeps, in file order. */
typedef struct film_array {
    void *data;
    size_t bytes;
} film_array;

#define FILM_ARRAYS 7
static int film_arrays(const tr_film *f, film_array out[FILM_ARRAYS]) {
    const size_t n = (size_t)f->width * f->height;
    int k = 0;
    out[k++] = (film_array){f->sum, 3 * n * sizeof(float)};
    out[k++] = (film_array){f->count, n * sizeof(uint32_t)};
    if (f->albedo) {
        out[k++] = (film_array){f->albedo, 3 * n * sizeof(float)};
    }
    if (f->normal) {
        out[k++] = (film_array){f->normal, 3 * n * sizeof(float)};
    }
    if (f->depth) {
        out[k++] = (film_array){f->depth, n * sizeof(float)};
    }
    if (f->prim) {
        out[k++] = (film_array){f->prim, n * sizeof(uint32_t)};
    }
    if (f->sq) {
        out[k++] = (film_array){f->sq, 3 * n * sizeof(float)};
    }
    return k;
}

typedef struct hashed_writer {
    FILE *fp;
    uint64_t h;
} hashed_writer;

static void put(hashed_writer *w, const void *data, size_t n) {
    w->h = fnv(w->h, data, n);
    fwrite(data, 1, n, w->fp);
}

int checkpoint_write(const char *path, const checkpoint_id *id, uint32_t mode, const tr_film *film,
                     uint32_t samples, uint32_t spp, tr_error *err) {
    tr_outfile *out = tr_outfile_open(path, err);
    if (!out) {
        return TR_ERR;
    }
    hashed_writer w = {tr_outfile_stream(out), FNV_OFFSET};
    const uint32_t head[9] = {CHECKPOINT_VERSION,
                              BYTE_ORDER_MARK,
                              mode,
                              film->width,
                              film->height,
                              film->passes,
                              samples,
                              spp,
                              (uint32_t)strlen(id->desc)};
    put(&w, magic, sizeof magic);
    put(&w, head, sizeof head);
    put(&w, &id->scene_hash, sizeof id->scene_hash);
    put(&w, id->desc, head[8]);
    film_array arrays[FILM_ARRAYS];
    const int k = film_arrays(film, arrays);
    for (int i = 0; i < k; ++i) {
        put(&w, arrays[i].data, arrays[i].bytes);
    }
    const uint64_t sum = w.h;
    fwrite(&sum, sizeof sum, 1, w.fp);
    return tr_outfile_commit(out, err);
}

/* A cursor over the file's bytes. */
typedef struct reader {
    const unsigned char *p, *end;
} reader;

static int take(reader *r, void *out, size_t n) {
    if ((size_t)(r->end - r->p) < n) {
        return -1;
    }
    memcpy(out, r->p, n);
    r->p += n;
    return 0;
}

/* Names the first option of `want` whose value differs in `got` (both "key=value ..."). */
static void describe_difference(const char *got, const char *want, char *buf, size_t size) {
    /* got and want are at most 511 characters each: buf holds both. */
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

/* Opens a checkpoint when it is a regular file: without blocking first, so that a FIFO
 * named by --resume is refused rather than waited on forever. */
static FILE *open_regular(const char *path, tr_error *err) {
    const int fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    struct stat st;
    if (fd < 0 || fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        const int e = fd < 0 ? errno : 0;
        if (fd >= 0) {
            close(fd);
        }
        tr_error_set(err, e ? tr_status_from_errno(e) : TR_STATUS_IO, "%.200s: cannot open: %s",
                     path, e ? strerror(e) : "not a regular file");
        return NULL;
    }
    FILE *fp = fdopen(fd, "rb");
    if (!fp) {
        const int e = errno;
        close(fd);
        tr_error_set(err, tr_status_from_errno(e), "%.200s: cannot open: %s", path, strerror(e));
    }
    return fp;
}

int checkpoint_read(const char *path, const checkpoint_id *id, uint32_t *mode, tr_film *film,
                    uint32_t *samples, uint32_t *spp, tr_error *err) {
    memset(film, 0, sizeof *film);
    FILE *fp = open_regular(path, err);
    if (!fp) {
        return TR_ERR;
    }
    unsigned char *data = NULL;
    size_t size = 0, cap = 0;
    for (;;) {
        if (size == cap) {
            cap = cap ? 2 * cap : 1u << 20;
            unsigned char *grown = realloc(data, cap);
            if (!grown) {
                free(data);
                fclose(fp);
                return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "%s: out of memory", path);
            }
            data = grown;
        }
        const size_t n = fread(data + size, 1, cap - size, fp);
        size += n;
        if (n == 0) {
            break;
        }
    }
    const int bad = ferror(fp);
    fclose(fp);
    int rc = TR_OK;
    reader r = {data, data + size};
    char got_magic[8];
    uint32_t head[9] = {0};
    uint64_t scene_hash = 0, sum = 0;
    char desc[512];
    if (bad) {
        rc = tr_error_set(err, TR_STATUS_IO, "%s: read error", path);
    } else if (size < sizeof magic + sizeof sum || take(&r, got_magic, sizeof got_magic) != 0 ||
               memcmp(got_magic, magic, sizeof magic) != 0) {
        rc = tr_error_set(err, TR_STATUS_PARSE, "%s: not a trac0r checkpoint", path);
    } else if (take(&r, head, sizeof head) != 0) {
        rc = tr_error_set(err, TR_STATUS_PARSE, "%s: truncated checkpoint header", path);
    } else if (head[1] != BYTE_ORDER_MARK) {
        /* Before the checksum: a file of another version or machine is whole, and says so. */
        rc = tr_error_set(err, TR_STATUS_PARSE,
                          "%s: the checkpoint was written on a machine of another byte order "
                          "(mark 0x%08x, this one's 0x%08x)",
                          path, head[1], BYTE_ORDER_MARK);
    } else if (head[0] != CHECKPOINT_VERSION) {
        rc = tr_error_set(err, TR_STATUS_PARSE,
                          "%s: checkpoint format version %u, but this trac0r reads version %u "
                          "only: resume it with the trac0r that wrote it, or render again",
                          path, head[0], CHECKPOINT_VERSION);
    } else if (memcpy(&sum, data + size - sizeof sum, sizeof sum),
               fnv(FNV_OFFSET, data, size - sizeof sum) != sum) {
        rc = tr_error_set(err, TR_STATUS_PARSE, "%s: damaged checkpoint (checksum mismatch)", path);
    } else if (head[8] >= sizeof desc || take(&r, &scene_hash, sizeof scene_hash) != 0 ||
               take(&r, desc, head[8]) != 0) {
        rc = tr_error_set(err, TR_STATUS_PARSE, "%s: truncated checkpoint header", path);
    }
    if (rc == TR_OK) {
        desc[head[8]] = '\0';
        if (scene_hash != id->scene_hash) {
            rc = tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                              "%s: the checkpoint is of another scene (scene hash %016llx, this "
                              "render's %016llx)",
                              path, (unsigned long long)scene_hash,
                              (unsigned long long)id->scene_hash);
        } else if (strcmp(desc, id->desc) != 0) {
            char diff[1100];
            describe_difference(desc, id->desc, diff, sizeof diff);
            rc = tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                              "%s: the checkpoint is of a render with other options: %s", path,
                              diff);
        }
    }
    if (rc == TR_OK && tr_film_init_passes(film, head[3], head[4], head[5], err) != TR_OK) {
        rc = TR_ERR;
    }
    if (rc == TR_OK) {
        film_array arrays[FILM_ARRAYS];
        const int k = film_arrays(film, arrays);
        for (int i = 0; i < k && rc == TR_OK; ++i) {
            if (take(&r, arrays[i].data, arrays[i].bytes) != 0) {
                rc = tr_error_set(err, TR_STATUS_PARSE, "%s: truncated film", path);
            }
        }
        if (rc == TR_OK && (size_t)(r.end - r.p) != sizeof sum) {
            rc = tr_error_set(err, TR_STATUS_PARSE, "%s: trailing bytes after the film", path);
        }
        if (rc == TR_OK && (head[2] > CHECKPOINT_TILES || head[7] == 0 || head[6] > head[7])) {
            rc = tr_error_set(err, TR_STATUS_PARSE, "%s: bad sample counts %u of %u", path, head[6],
                              head[7]);
        }
    }
    free(data);
    if (rc != TR_OK) {
        tr_film_free(film);
        memset(film, 0, sizeof *film);
        return rc;
    }
    *mode = head[2];
    *samples = head[6];
    *spp = head[7];
    return TR_OK;
}

static volatile sig_atomic_t stop_signal;
/* The actions the render replaced: a second signal and the end of the render give them
 * back (another part of trac0r may clean up on these signals too). */
static struct sigaction previous_int, previous_term;

static void on_stop(int sig) {
    if (stop_signal) {
        /* Asked twice: do not wait for the pass to end. */
        const struct sigaction *prev = sig == SIGINT ? &previous_int : &previous_term;
        if (prev->sa_handler == SIG_IGN) {
            signal(sig, SIG_DFL);
        } else {
            sigaction(sig, prev, NULL);
        }
        raise(sig);
        return;
    }
    stop_signal = sig;
}

void render_stop_install(void) {
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_stop;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, &previous_int);
    sigaction(SIGTERM, &sa, &previous_term);
}

int render_stop_signal(void) {
    return (int)stop_signal;
}

void render_stop_uninstall(void) {
    sigaction(SIGINT, &previous_int, NULL);
    sigaction(SIGTERM, &previous_term, NULL);
}
