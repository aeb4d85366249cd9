/* test_session.c - tr_session: defaults, progress and cancel, the time limit, adaptive
 * sampling, denoising, checkpoints and resume with every pass of the film, and the tile plan
 * of a render shared between processes (simulated here by sessions in one process). Every
 * image is compared bit for bit with passes rendered straight on a device. */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "scene_util.h"
#include "trac0r/trac0r.h"

#define W 70u
#define H 45u

static tr_scene *box(void) {
    return committed_builtin("cornell", W, H);
}

static tr_render_config config(uint32_t passes) {
    tr_render_config cfg = tr_render_config_default();
    cfg.passes = passes;
    cfg.seed = 11;
    return cfg;
}

/* Samples 0..spp-1 one pass at a time on a device of its own, into *out. */
static void straight(const tr_scene *s, const tr_render_config *cfg, uint32_t spp, tr_film *out) {
    tr_error err;
    tr_device *dev = tr_device_create("cpu", &err);
    CHECK(dev && tr_device_upload(dev, s, &err) == TR_OK, "%s", err.msg);
    for (uint32_t k = 0; k < spp; ++k) {
        CHECK(tr_device_render(dev, tr_scene_camera(s), cfg, k, 1, NULL, NULL, &err) == TR_OK, "%s",
              err.msg);
    }
    CHECK(tr_film_init_passes(out, W, H, cfg->passes, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_device_read_film(dev, out, &err) == TR_OK, "%s", err.msg);
    tr_device_destroy(dev);
}

/* Whether every array of the two films' layout holds the same bits. */
static int same_film(const tr_film *a, const tr_film *b) {
    if (!a || !b || a->width != b->width || a->height != b->height || a->passes != b->passes) {
        return 0;
    }
    const size_t n = (size_t)a->width * a->height;
    for (int i = 0; i < TR_FILM_ARRAYS; ++i) {
        const void *x = tr_film_array_data(a, i), *y = tr_film_array_data(b, i);
        if ((x == NULL) != (y == NULL) ||
            (x && memcmp(x, y, n * tr_film_array_pixel_bytes(i)) != 0)) {
            return 0;
        }
    }
    return 1;
}

typedef struct counter {
    uint32_t calls, stop_after, last_samples;
} counter;

static int count_passes(void *user, const tr_session_progress *p) {
    counter *c = user;
    ++c->calls;
    c->last_samples = p->samples;
    return c->stop_after && c->calls >= c->stop_after;
}

static void test_defaults_and_progress(tr_device *dev, const tr_scene *s) {
    tr_error err;
    /* A zeroed desc and no config: 16 samples with the default config. */
    tr_session *ses = tr_session_create(dev, s, NULL, &(tr_session_desc){0}, &err);
    CHECK(ses && tr_session_run(ses, &err) == TR_OK, "%s", err.msg);
    tr_session_progress p;
    tr_session_progress_get(ses, &p);
    CHECK(p.samples == TR_SESSION_SPP_DEFAULT && p.end == TR_SESSION_DONE, "%u, end %d", p.samples,
          (int)p.end);
    tr_render_config def = tr_render_config_default();
    tr_film ref;
    straight(s, &def, TR_SESSION_SPP_DEFAULT, &ref);
    CHECK(same_film(tr_session_film(ses, &err), &ref), "zeroed desc differs from 16 passes");
    tr_film_free(&ref);
    tr_session_destroy(ses);

    /* The callback after every pass; its nonzero answer stops at the pass boundary, and a
     * second run goes on to the end with the bits of an uninterrupted render. */
    counter c = {0, 3, 0};
    tr_session_desc d = {0};
    d.spp = 9;
    d.progress = count_passes;
    d.progress_user = &c;
    const tr_render_config cfg = config(TR_PASS_VARIANCE);
    ses = tr_session_create(dev, s, &cfg, &d, &err);
    CHECK(ses && tr_session_run(ses, &err) == TR_OK, "%s", err.msg);
    tr_session_progress_get(ses, &p);
    CHECK(c.calls == 3 && p.samples == 3 && p.end == TR_SESSION_CANCELLED,
          "%u calls, %u samples, end %d", c.calls, p.samples, (int)p.end);
    straight(s, &cfg, 3, &ref);
    CHECK(same_film(tr_session_film(ses, &err), &ref), "a render stopped after 3 passes");
    tr_film_free(&ref);
    c.stop_after = 0;
    CHECK(tr_session_run(ses, &err) == TR_OK, "%s", err.msg);
    tr_session_progress_get(ses, &p);
    CHECK(c.calls == 9 && c.last_samples == 9 && p.end == TR_SESSION_DONE, "%u calls, end %d",
          c.calls, (int)p.end);
    straight(s, &cfg, 9, &ref);
    CHECK(same_film(tr_session_film(ses, &err), &ref), "a render stopped and gone on");
    tr_film_free(&ref);

    /* A cancel before the run: no pass is made, and the run after it goes on. */
    tr_session_destroy(ses);
    c = (counter){0, 0, 0};
    ses = tr_session_create(dev, s, &cfg, &d, &err);
    CHECK(ses != NULL, "%s", err.msg);
    tr_session_cancel(ses);
    CHECK(tr_session_run(ses, &err) == TR_OK, "%s", err.msg);
    tr_session_progress_get(ses, &p);
    CHECK(p.samples == 0 && c.calls == 0 && p.end == TR_SESSION_CANCELLED, "%u samples", p.samples);
    tr_session_destroy(ses);
}

static void test_time_limit_and_adaptive(tr_device *dev, const tr_scene *s) {
    tr_error err;
    /* A limit no pass fits in: the first pass is made, no second. */
    tr_session_desc d = {0};
    d.spp = 50;
    d.time_limit = 1e-9;
    const tr_render_config cfg = config(0);
    tr_session *ses = tr_session_create(dev, s, &cfg, &d, &err);
    CHECK(ses && tr_session_run(ses, &err) == TR_OK, "%s", err.msg);
    tr_session_progress p;
    tr_session_progress_get(ses, &p);
    CHECK(p.samples == 1 && p.end == TR_SESSION_TIME_LIMIT, "%u samples, end %d", p.samples,
          (int)p.end);
    tr_film ref;
    straight(s, &cfg, 1, &ref);
    CHECK(same_film(tr_session_film(ses, &err), &ref), "time-limited render");
    tr_film_free(&ref);
    tr_session_destroy(ses);

    /* Adaptive: tiles stop between 16 and the spp, and the image is the same each time. */
    d = (tr_session_desc){0};
    d.spp = 256;
    d.noise_threshold = 0.05f;
    tr_film first = {0};
    for (int run = 0; run < 2; ++run) {
        ses = tr_session_create(dev, s, &cfg, &d, &err);
        CHECK(ses && tr_session_run(ses, &err) == TR_OK, "%s", err.msg);
        tr_session_progress_get(ses, &p);
        const tr_film *f = tr_session_film(ses, &err);
        uint32_t lo = UINT32_MAX, hi = 0;
        for (size_t i = 0; f && i < (size_t)W * H; ++i) {
            lo = f->count[i] < lo ? f->count[i] : lo;
            hi = f->count[i] > hi ? f->count[i] : hi;
        }
        CHECK(p.tiles > 0 && p.tiles_done > 0 && lo >= 16 && lo < 256 && hi <= 256,
              "tiles %u of %u converged, counts %u..%u", p.tiles_done, p.tiles, lo, hi);
        CHECK(p.pixel_samples < 256ull * W * H, "%llu pixel samples",
              (unsigned long long)p.pixel_samples);
        if (run == 0) {
            CHECK(tr_film_init_passes(&first, W, H, 0, &err) == TR_OK, "%s", err.msg);
            CHECK(f && tr_film_accumulate(&first, f, &err) == TR_OK, "%s", err.msg);
        } else {
            CHECK(same_film(f, &first), "two adaptive renders differ");
        }
        tr_session_destroy(ses);
    }
    tr_film_free(&first);
}

static void test_denoise(tr_device *dev, const tr_scene *s) {
    tr_error err;
    tr_session_desc d = {0};
    d.spp = 4;
    tr_session *ses = tr_session_create(dev, s, NULL, &d, &err);
    tr_film out;
    CHECK(ses && tr_session_run(ses, &err) == TR_OK, "%s", err.msg);
    CHECK_STATUS(tr_session_denoise(ses, &out, &err), err, TR_STATUS_INVALID_OPERATION,
                 "denoising without the guides");
    tr_session_destroy(ses);
    d.denoise = 1;
    ses = tr_session_create(dev, s, NULL, &d, &err);
    CHECK(ses && tr_session_run(ses, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_session_denoise(ses, &out, &err) == TR_OK, "%s", err.msg);
    /* Closer to a converged image than the 4-spp estimate it filtered. */
    const tr_film *raw = tr_session_film(ses, &err);
    tr_film ref;
    tr_render_config def = tr_render_config_default();
    straight(s, &def, 128, &ref);
    double e_raw = 0.0, e_den = 0.0;
    for (size_t i = 0; raw && i < (size_t)W * H; ++i) {
        CHECK(out.count[i] == 1u, "denoised pixel %zu has %u samples", i, out.count[i]);
        for (int ch = 0; ch < 3; ++ch) {
            /* On the display's range: the filter is not for fireflies. */
            const double want = fmin(1.0, (double)ref.sum[3 * i + ch] / ref.count[i]);
            const double r = fmin(1.0, (double)raw->sum[3 * i + ch] / raw->count[i]) - want;
            const double dn = fmin(1.0, (double)out.sum[3 * i + ch]) - want;
            e_raw += r * r;
            e_den += dn * dn;
        }
    }
    CHECK(e_den < e_raw, "squared error denoised %.3f, raw %.3f", e_den, e_raw);
    tr_film_free(&ref);
    /* And it is the offline denoiser of post.h on the film, nothing else. */
    float *by_hand = malloc(3u * W * H * sizeof *by_hand);
    CHECK(by_hand && raw && tr_denoise_film(raw, NULL, 0, by_hand, &err) == TR_OK, "%s", err.msg);
    CHECK(by_hand && memcmp(by_hand, out.sum, 3u * W * H * sizeof *by_hand) == 0,
          "tr_session_denoise is not tr_denoise_film");
    free(by_hand);
    tr_film_free(&out);
    tr_session_destroy(ses);
}

/* A render stopped after 5 passes checkpoints every pass of the film; a new session
 * resumes it to 12 samples with the bits of an uninterrupted render. */
static void test_checkpoint(tr_device *dev, const tr_scene *s, const char *dir) {
    tr_error err;
    char ck[600], bad[600];
    snprintf(ck, sizeof ck, "%s/all.ck", dir);
    snprintf(bad, sizeof bad, "%s/bad.ck", dir);
    const tr_render_config cfg = config(TR_PASS_MASK);
    counter c = {0, 5, 0};
    tr_session_desc d = {0};
    d.spp = 12;
    d.checkpoint = ck;
    d.progress = count_passes;
    d.progress_user = &c;
    tr_session *ses = tr_session_create(dev, s, &cfg, &d, &err);
    CHECK(ses && tr_session_run(ses, &err) == TR_OK, "%s", err.msg);
    tr_session_destroy(ses);
    tr_session_desc r = {0};
    r.resume = ck;
    ses = tr_session_create(dev, s, &cfg, &r, &err);
    tr_session_progress p = {0};
    if (ses) {
        tr_session_progress_get(ses, &p);
    }
    CHECK(ses && p.first == 5 && p.spp == 12, "%s (first %u of %u)", ses ? "" : err.msg, p.first,
          p.spp);
    CHECK(ses && tr_session_run(ses, &err) == TR_OK, "%s", err.msg);
    tr_film ref;
    straight(s, &cfg, 12, &ref);
    CHECK(ses && same_film(tr_session_film(ses, &err), &ref),
          "a resumed render with every pass differs from an uninterrupted one");
    tr_session_destroy(ses);

    /* Refused: another render, fewer samples than it holds, a damaged file. */
    tr_render_config other = cfg;
    other.seed = 12;
    CHECK_STATUS(tr_session_create(dev, s, &other, &r, &err) ? TR_OK : TR_ERR, err,
                 TR_STATUS_INVALID_ARGUMENT, "a checkpoint of another seed");
    r.spp = 3;
    CHECK_STATUS(tr_session_create(dev, s, &cfg, &r, &err) ? TR_OK : TR_ERR, err, TR_STATUS_LIMIT,
                 "fewer samples than the checkpoint holds");
    r.spp = 0;
    FILE *in = fopen(ck, "rb"), *out = fopen(bad, "wb");
    CHECK(in && out, "cannot copy %s", ck);
    for (int ch, k = 0; in && out && (ch = fgetc(in)) != EOF; ++k) {
        fputc(k == 5000 ? ch ^ 1 : ch, out); /* one bit of the film flipped */
    }
    if (in) {
        fclose(in);
    }
    if (out) {
        fclose(out);
    }
    r.resume = bad;
    CHECK_STATUS(tr_session_create(dev, s, &cfg, &r, &err) ? TR_OK : TR_ERR, err, TR_STATUS_PARSE,
                 "a damaged checkpoint");
    d.noise_threshold = 0.1f;
    CHECK_STATUS(tr_session_create(dev, s, &cfg, &d, &err) ? TR_OK : TR_ERR, err,
                 TR_STATUS_INVALID_ARGUMENT, "a noise threshold with checkpoints");
    tr_film_free(&ref);
    remove(ck);
    remove(bad);
}

/* Two "processes": a worker renders the odd tiles and packs them, the master renders the
 * even ones and puts the worker's in; its film is the straight render in every array. A
 * checkpoint the master writes half-way resumes in one session, tile by tile, to the same. */
static void test_tiles(const tr_scene *s, const char *dir) {
    tr_error err;
    char ck[600];
    snprintf(ck, sizeof ck, "%s/tiles.ck", dir);
    tr_device *d0 = tr_device_create("cpu", &err), *d1 = tr_device_create("cpu", &err);
    const tr_render_config cfg = config(TR_PASS_MASK);
    tr_session_desc d = {0};
    d.spp = 6;
    tr_session *master = tr_session_create(d0, s, &cfg, &d, &err);
    tr_session *worker = tr_session_create(d1, s, &cfg, &d, &err);
    CHECK(master && worker, "%s", err.msg);
    if (!master || !worker) {
        return;
    }
    const uint32_t n = tr_session_tile_count(master);
    CHECK(n == ((W + 31) / 32) * ((H + 31) / 32), "%u tiles", n);
    const size_t cap = 32u * 32u * tr_film_pixel_bytes(TR_PASS_MASK);
    unsigned char *buf = malloc(cap);
    for (uint32_t k = 0; buf && k < n; ++k) {
        tr_rect r;
        CHECK(tr_session_tile(master, k, &r, NULL, &err) == TR_OK, "%s", err.msg);
        if (k % 2 == 0) {
            CHECK(tr_session_render_tile(master, k, NULL, NULL, NULL, &err) == TR_OK, "%s",
                  err.msg);
        } else {
            const tr_film *wf = NULL;
            CHECK(tr_session_render_tile(worker, k, NULL, NULL, NULL, &err) == TR_OK &&
                      (wf = tr_session_film(worker, &err)) != NULL &&
                      tr_film_pack_rect(wf, &r, buf, cap, &err) == TR_OK &&
                      tr_session_put_tile(master, k, buf, cap, &err) == TR_OK,
                  "%s", err.msg);
        }
        if (k == n / 2) {
            CHECK(tr_session_checkpoint(master, ck, &err) == TR_OK, "%s", err.msg);
        }
    }
    tr_film ref;
    straight(s, &cfg, 6, &ref);
    CHECK(same_film(tr_session_film(master, &err), &ref), "tiles put together differ");
    CHECK_STATUS(tr_session_put_tile(master, 0, buf, 16, &err), err, TR_STATUS_INVALID_ARGUMENT,
                 "a tile's pixels in a buffer too small");
    CHECK_STATUS(tr_session_render_tile(master, n, NULL, NULL, NULL, &err), err,
                 TR_STATUS_INVALID_ARGUMENT, "a tile past the plan");
    tr_session_destroy(master);
    tr_session_destroy(worker);

    d.resume = ck;
    tr_session *again = tr_session_create(d0, s, &cfg, &d, &err);
    CHECK(again && tr_session_run(again, &err) == TR_OK, "%s", err.msg);
    CHECK(again && same_film(tr_session_film(again, &err), &ref),
          "a tile checkpoint resumed in one session differs");
    tr_session_destroy(again);
    tr_film_free(&ref);
    free(buf);
    tr_device_destroy(d0);
    tr_device_destroy(d1);
    remove(ck);
}

int main(void) {
    tr_error err;
    tr_scene *s = box();
    tr_device *dev = tr_device_create("cpu", &err);
    CHECK(dev != NULL, "%s", err.msg);
    const char *tmp = getenv("TMPDIR");
    char path[256];
    snprintf(path, sizeof path, "%s/trac0r-session-XXXXXX", tmp && *tmp ? tmp : "/tmp");
    CHECK(mkdtemp(path) != NULL, "cannot make a directory from %s", path);
    CHECK_STATUS(tr_session_create(NULL, s, NULL, NULL, &err) ? TR_OK : TR_ERR, err,
                 TR_STATUS_INVALID_ARGUMENT, "no device");
    if (s && dev) {
        test_defaults_and_progress(dev, s);
        test_time_limit_and_adaptive(dev, s);
        test_denoise(dev, s);
        test_checkpoint(dev, s, path);
        test_tiles(s, path);
    }
    rmdir(path);
    tr_device_destroy(dev);
    tr_scene_destroy(s);
    return check_finish("test_session");
}
