/* denoise_eval.c - the offline denoiser measured against the raw render and the à-trous
 * filter on one scene (docs/log/2026-denoise.md records the runs).
 *
 *     denoise_eval SCENE WIDTH HEIGHT REF_SPP CACHE_DIR SPP [SPP ...]
 *
 * Renders SCENE (a scene file, or builtin:NAME) at REF_SPP with seed 7777 as the
 * reference (kept in CACHE_DIR, reused when present), then for each SPP with seed 1 (or
 * the environment's DENOISE_EVAL_SEED, to check a setting on other films; the films of
 * other seeds are cached under their own names) on two threads: the raw image, tr_filter_atrous
 * with the real-time defaults (what `render --denoise` wrote before the offline denoiser) and
 * tr_denoise_film. Prints the PSNR of each against the reference on values clamped to [0, 1] (as
 * `trac0r compare`), the same with the reference's own noise taken out (estimated from the raw
 * images: with two or more SPP the raw squared error is fitted as a / spp + r, and a / REF_SPP is
 * the reference's; the film's own variance pass overstates it, as pt's samples are stratified), the
 * denoiser's CPU and wall time, and where the denoiser's squared error lies: pixels that saw
 * emission at their first hit, pixels next to a depth or normal edge, and the rest (share of the
 * total and the same split for à-trous). Uses the public API only. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>

#include "trac0r/trac0r.h"

typedef struct ref_img {
    uint32_t w, h;
    float *rgb; /* 3 per pixel */
    float *var; /* the variance of the mean, clamped-space estimate, 1 per pixel */
} ref_img;

static double cpu_seconds(void) {
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    return ru.ru_utime.tv_sec + ru.ru_stime.tv_sec +
           1e-6 * (double)(ru.ru_utime.tv_usec + ru.ru_stime.tv_usec);
}

static double wall_seconds(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec + 1e-9 * t.tv_nsec;
}

static float clamp01(float v) {
    return v < 0.0f ? 0.0f : (v > 1.0f ? 1.0f : v);
}

/* Renders scene_path at w x h with spp and seed, keeping the denoiser's passes; the film
 * is copied into *out (tr_film_free it). */
static int render(const char *scene_path, uint32_t w, uint32_t h, uint32_t spp, uint64_t seed,
                  tr_film *out) {
    tr_error err;
    tr_scene *s = tr_scene_create(&err);
    tr_scene_open_desc od;
    memset(&od, 0, sizeof od);
    od.request.width = w;
    od.request.height = h;
    od.request.spp = spp;
    tr_render_settings set;
    tr_device *dev = NULL;
    tr_session *ses = NULL;
    int rc = s ? TR_OK : TR_ERR;
    rc = rc == TR_OK ? tr_scene_open(s, scene_path, &od, NULL, &set, &err) : rc;
    if (rc == TR_OK) {
        dev = tr_device_create("cpu", &err);
        rc = dev ? TR_OK : TR_ERR;
    }
    if (rc == TR_OK) {
        tr_render_config cfg = set.config;
        cfg.seed = seed;
        tr_session_desc d = {0};
        d.spp = spp;
        d.denoise = 1;
        ses = tr_session_create(dev, s, &cfg, &d, &err);
        rc = ses ? TR_OK : TR_ERR;
    }
    rc = rc == TR_OK ? tr_session_run(ses, &err) : rc;
    const tr_film *f = rc == TR_OK ? tr_session_film(ses, &err) : NULL;
    rc = f ? rc : TR_ERR;
    if (rc == TR_OK) {
        /* A full copy of every kept pass. */
        rc = tr_film_init_passes(out, f->width, f->height, f->passes, &err);
    }
    if (rc == TR_OK) {
        const size_t n = (size_t)f->width * f->height;
        memcpy(out->sum, f->sum, sizeof(float) * 3 * n);
        memcpy(out->count, f->count, sizeof(uint32_t) * n);
        memcpy(out->albedo, f->albedo, sizeof(float) * 3 * n);
        memcpy(out->normal, f->normal, sizeof(float) * 3 * n);
        memcpy(out->depth, f->depth, sizeof(float) * n);
        memcpy(out->sq, f->sq, sizeof(float) * 3 * n);
        memcpy(out->emission, f->emission, sizeof(float) * 3 * n);
    }
    if (rc != TR_OK) {
        fprintf(stderr, "denoise_eval: %s: %s\n", scene_path, err.msg);
    }
    tr_session_destroy(ses);
    tr_device_destroy(dev);
    tr_scene_destroy(s);
    return rc;
}

static int get_ref(const char *scene, uint32_t w, uint32_t h, uint32_t spp, const char *dir,
                   ref_img *r) {
    char path[1024];
    const char *base = strrchr(scene, '/');
    base = base ? base + 1 : scene;
    snprintf(path, sizeof path, "%s/%s-%ux%u-%u.ref", dir, base, w, h, spp);
    r->w = w;
    r->h = h;
    const size_t n = (size_t)w * h;
    r->rgb = malloc(sizeof(float) * 3 * n);
    r->var = malloc(sizeof(float) * n);
    FILE *fp = fopen(path, "rb");
    if (fp) {
        const int ok = fread(r->rgb, sizeof(float), 3 * n, fp) == 3 * n &&
                       fread(r->var, sizeof(float), n, fp) == n;
        fclose(fp);
        if (ok) {
            return TR_OK;
        }
    }
    tr_film f;
    const double t0 = wall_seconds();
    if (render(scene, w, h, spp, 7777, &f) != TR_OK) {
        return TR_ERR;
    }
    fprintf(stderr, "reference %s: %.1f s\n", path, wall_seconds() - t0);
    for (size_t i = 0; i < n; ++i) {
        double v = 0.0;
        for (int c = 0; c < 3; ++c) {
            r->rgb[3 * i + c] = f.sum[3 * i + c] / (float)f.count[i];
            /* Clamped values vary less; the unclamped variance where the mean is inside. */
            v += r->rgb[3 * i + c] < 1.0f ? tr_film_variance(&f, i, c) : 0.0;
        }
        r->var[i] = (float)(v / 3.0);
    }
    tr_film_free(&f);
    fp = fopen(path, "wb");
    if (fp) {
        fwrite(r->rgb, sizeof(float), 3 * n, fp);
        fwrite(r->var, sizeof(float), n, fp);
        fclose(fp);
    }
    return TR_OK;
}

/* The film of scene at spp with seed 1 (or DENOISE_EVAL_SEED), rendered once and kept in
 * dir. */
static int film_cached(const char *scene, uint32_t w, uint32_t h, uint32_t spp, const char *dir,
                       tr_film *f) {
    char path[1024];
    const char *base = strrchr(scene, '/');
    base = base ? base + 1 : scene;
    const char *se = getenv("DENOISE_EVAL_SEED");
    const uint64_t seed = se && atoi(se) > 1 ? (uint64_t)atoi(se) : 1u;
    if (seed == 1u) {
        snprintf(path, sizeof path, "%s/%s-%ux%u-%u.film", dir, base, w, h, spp);
    } else {
        snprintf(path, sizeof path, "%s/%s-%ux%u-%u-s%u.film", dir, base, w, h, spp,
                 (unsigned)seed);
    }
    const size_t n = (size_t)w * h;
    tr_error err;
    const uint32_t passes =
        TR_PASS_ALBEDO | TR_PASS_NORMAL | TR_PASS_DEPTH | TR_PASS_VARIANCE | TR_PASS_EMISSION;
    FILE *fp = fopen(path, "rb");
    if (fp) {
        if (tr_film_init_passes(f, w, h, passes, &err) != TR_OK) {
            fclose(fp);
            return TR_ERR;
        }
        size_t got = fread(f->sum, sizeof(float), 3 * n, fp);
        got += fread(f->count, sizeof(uint32_t), n, fp);
        got += fread(f->albedo, sizeof(float), 3 * n, fp);
        got += fread(f->normal, sizeof(float), 3 * n, fp);
        got += fread(f->depth, sizeof(float), n, fp);
        got += fread(f->sq, sizeof(float), 3 * n, fp);
        got += fread(f->emission, sizeof(float), 3 * n, fp);
        fclose(fp);
        if (got == 17 * n) {
            return TR_OK;
        }
        tr_film_free(f);
    }
    if (render(scene, w, h, spp, seed, f) != TR_OK) {
        return TR_ERR;
    }
    fp = fopen(path, "wb");
    if (fp) {
        fwrite(f->sum, sizeof(float), 3 * n, fp);
        fwrite(f->count, sizeof(uint32_t), n, fp);
        fwrite(f->albedo, sizeof(float), 3 * n, fp);
        fwrite(f->normal, sizeof(float), 3 * n, fp);
        fwrite(f->depth, sizeof(float), n, fp);
        fwrite(f->sq, sizeof(float), 3 * n, fp);
        fwrite(f->emission, sizeof(float), 3 * n, fp);
        fclose(fp);
    }
    return TR_OK;
}

/* Pixel classes: 0 emission seen, 1 next to a depth or normal edge, 2 the rest. */
static void classify(const tr_film *f, unsigned char *cls) {
    const int w = (int)f->width, h = (int)f->height;
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            const size_t i = (size_t)y * w + x;
            const float inv = f->count[i] ? 1.0f / (float)f->count[i] : 0.0f;
            const float *e = f->emission + 3 * i;
            if ((e[0] + e[1] + e[2]) * inv > 0.0f) {
                cls[i] = 0;
                continue;
            }
            cls[i] = 2;
            const float z = f->depth[i] * inv;
            for (int dy = -1; dy <= 1; ++dy) {
                for (int dx = -1; dx <= 1; ++dx) {
                    const int xx = x + dx, yy = y + dy;
                    if (xx < 0 || yy < 0 || xx >= w || yy >= h) {
                        continue;
                    }
                    const size_t j = (size_t)yy * w + xx;
                    const float invj = f->count[j] ? 1.0f / (float)f->count[j] : 0.0f;
                    const float zj = f->depth[j] * invj;
                    float dot = 0.0f;
                    for (int c = 0; c < 3; ++c) {
                        dot += f->normal[3 * i + c] * inv * f->normal[3 * j + c] * invj;
                    }
                    if (fabsf(zj - z) > 0.05f * fmaxf(z, 1e-3f) || dot < 0.9f) {
                        cls[i] = 1;
                    }
                }
            }
        }
    }
}

/* Squared error per class of img (3 per pixel) against the reference. */
static double score(const ref_img *r, const float *img, const unsigned char *cls, double part[3]) {
    const size_t n = (size_t)r->w * r->h;
    double total = 0.0;
    part[0] = part[1] = part[2] = 0.0;
    for (size_t i = 0; i < n; ++i) {
        double e = 0.0;
        for (int c = 0; c < 3; ++c) {
            const double d = clamp01(img[3 * i + c]) - clamp01(r->rgb[3 * i + c]);
            e += d * d;
        }
        total += e;
        part[cls[i]] += e;
    }
    return total / (3.0 * n);
}

static double psnr(double mse) {
    return mse > 0.0 ? -10.0 * log10(mse) : INFINITY;
}

int main(int argc, char **argv) {
    if (argc < 7) {
        fprintf(stderr, "usage: denoise_eval SCENE WIDTH HEIGHT REF_SPP CACHE_DIR SPP...\n");
        return 2;
    }
    const char *scene = argv[1];
    const uint32_t w = (uint32_t)atoi(argv[2]), h = (uint32_t)atoi(argv[3]);
    const uint32_t ref_spp = (uint32_t)atoi(argv[4]);
    ref_img ref;
    if (get_ref(scene, w, h, ref_spp, argv[5], &ref) != TR_OK) {
        return 1;
    }
    const size_t n = (size_t)w * h;
    double floor_mse = 0.0;
    for (size_t i = 0; i < n; ++i) {
        floor_mse += ref.var[i];
    }
    floor_mse /= (double)n;
    (void)floor_mse;
    enum { MAXS = 16 };
    double res[MAXS][12];
    int nres = 0;
    float *img = malloc(sizeof(float) * 3 * n);
    float *at = malloc(sizeof(float) * 3 * n);
    float *dn = malloc(sizeof(float) * 3 * n);
    unsigned char *cls = malloc(n);
    for (int k = 6; k < argc; ++k) {
        const uint32_t spp = (uint32_t)atoi(argv[k]);
        tr_film f;
        tr_error err;
        if (film_cached(scene, w, h, spp, argv[5], &f) != TR_OK) {
            return 1;
        }
        classify(&f, cls);
        for (size_t i = 0; i < 3 * n; ++i) {
            img[i] = f.sum[i] / (float)f.count[i / 3];
        }
        tr_gbuffer g = {0};
        const tr_recon_params p = tr_recon_params_default();
        int rc = tr_gbuffer_init(&g, w, h, &err);
        rc = rc == TR_OK ? tr_gbuffer_from_film(&g, &f, &err) : rc;
        rc = rc == TR_OK ? tr_filter_atrous(&g, g.color, at, &p, 2, &err) : rc;
        tr_gbuffer_free(&g);
        const double c0 = cpu_seconds(), w0 = wall_seconds();
        rc = rc == TR_OK ? tr_denoise_film(&f, NULL, 2, dn, &err) : rc;
        const double cpu = cpu_seconds() - c0, wall = wall_seconds() - w0;
        if (rc != TR_OK) {
            fprintf(stderr, "denoise_eval: %s\n", err.msg);
            return 1;
        }
        if (getenv("DN_DUMP")) { /* the images as raw floats, for a look */
            char path[1024];
            snprintf(path, sizeof path, "%s/dump-%u.f32", argv[5], spp);
            FILE *fp = fopen(path, "wb");
            if (fp) {
                fwrite(img, sizeof(float), 3 * n, fp);
                fwrite(at, sizeof(float), 3 * n, fp);
                fwrite(dn, sizeof(float), 3 * n, fp);
                fwrite(ref.rgb, sizeof(float), 3 * n, fp);
                fclose(fp);
            }
        }
        double pr[3], pa[3], pn[3];
        const double mr = score(&ref, img, cls, pr);
        const double ma = score(&ref, at, cls, pa);
        const double mn = score(&ref, dn, cls, pn);
        const double tn = pn[0] + pn[1] + pn[2] + 1e-30, ta = pa[0] + pa[1] + pa[2] + 1e-30;
        if (nres < MAXS) {
            const double row[12] = {spp,        mr,         ma,         mn,
                                    cpu,        wall,       pn[0] / tn, pn[1] / tn,
                                    pn[2] / tn, pa[0] / ta, pa[1] / ta, pa[2] / ta};
            memcpy(res[nres++], row, sizeof row);
        }
        tr_film_free(&f);
    }
    double fl = 0.0;
    if (nres >= 2 && res[0][0] != res[1][0]) {
        const double a = (res[0][1] - res[1][1]) / (1.0 / res[0][0] - 1.0 / res[1][0]);
        fl = a > 0.0 ? a / ref_spp : 0.0;
    }
    printf("# %s %ux%u, reference %u spp (its own noise estimated at %.2f dB)\n", scene, w, h,
           ref_spp, psnr(fl));
    printf("# spp  raw  atrous  new  (noise-corrected: raw atrous new)  new-raw  new-atrous  "
           "cpu_s wall_s  new err share emit/edge/rest  atrous share\n");
    for (int k = 0; k < nres; ++k) {
        const double *q = res[k];
        const double cr = fmax(q[1] - fl, 1e-12), ca = fmax(q[2] - fl, 1e-12),
                     cn = fmax(q[3] - fl, 1e-12);
        printf("%4.0f %6.2f %6.2f %6.2f  (%6.2f %6.2f %6.2f)  %+5.2f %+5.2f  %.3f %.3f  "
               "%.2f/%.2f/%.2f  %.2f/%.2f/%.2f\n",
               q[0], psnr(q[1]), psnr(q[2]), psnr(q[3]), psnr(cr), psnr(ca), psnr(cn),
               psnr(cn) - psnr(cr), psnr(cn) - psnr(ca), q[4], q[5], q[6], q[7], q[8], q[9], q[10],
               q[11]);
    }
    return 0;
}
