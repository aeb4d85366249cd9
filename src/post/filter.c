/* filter.c - the host side of real-time reconstruction: runs the per-pixel operators of
 * src/post/filter.h over images, rows spread over OpenMP threads. Every output pixel is
 * computed from read-only inputs in a fixed tap order, so results do not depend on the
 * thread count. */
/* The filters' inner loops (below) vectorise only when gcc may if-convert the clamps
 * of tr_post_exp_neg, which it does not while it must keep floating-point exceptions
 * exact. Nothing here reads the exception flags, and the values computed are the same
 * either way. (CMakeLists.txt adds -fno-math-errno, for the square roots.) */
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC optimize("no-trapping-math")
#endif
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "post/dfg.h"
#include "post/filter.h"
#include "post/recon_params.h"
#include "trac0r/film.h"
#include "trac0r/post.h"
#include "trac0r/render.h"

static int nthreads(int threads) {
    return threads > 0 ? threads : omp_get_max_threads();
}

/* Pixels per chunk of a row: the accumulators live on the stack, in L1. */
#define TR_POST_CHUNK 256
/* Pixels per block of the register-blocked loops: a 512-bit vector of floats. */
#define TR_POST_BLOCK 16

/* The planes of the scratch block (each w * h floats). */
enum {
    WS_CA = 0,  /* colour ping (r, g, b planes) */
    WS_CB = 3,  /* colour pong */
    WS_LA = 6,  /* luminance of ping, of pong */
    WS_LB = 7,  /* */
    WS_VA = 8,  /* variance ping, pong */
    WS_VB = 9,  /* */
    WS_KL = 10, /* SVGF's luminance coefficient of this iteration */
    WS_KZ = 11, /* SVGF's depth coefficient; à-trous's 1 / depth */
    WS_KN = 12, /* SVGF's normal exponent (sigma_n, or 0 without a normal) */
    WS_N = 13,  /* normal x, y, z planes */
    WS_A = 16,  /* albedo r, g, b planes */
    WS_PLANES = 19
};

/* The planes of r->temporal (each w * h floats): the surface points of the two newest
 * frames (x, y, z planes; slot k as hist_color[k]), then this frame's projection into
 * the previous camera. */
enum { TP_FX = 6, TP_FY = 7, TP_DIST = 8, TP_PLANES = 9 };

typedef struct post_ws {
    int w, h;
    float *p[WS_PLANES];
    /* Asked between the filters' iterations (tr_recon.cancel): nonzero ends them early. */
    int (*cancel)(void *user);
    void *cancel_user;
} post_ws;

int tr_gbuffer_init(tr_gbuffer *g, uint32_t width, uint32_t height, tr_error *err) {
    memset(g, 0, sizeof *g);
    if (tr_film_check_size(width, height, err) != TR_OK) {
        return TR_ERR;
    }
    const size_t n = (size_t)width * height;
    g->width = width;
    g->height = height;
    g->color = calloc(3 * n, sizeof *g->color);
    g->albedo = calloc(3 * n, sizeof *g->albedo);
    g->normal = calloc(3 * n, sizeof *g->normal);
    g->depth = calloc(n, sizeof *g->depth);
    g->prim = calloc(n, sizeof *g->prim);
    g->direct = calloc(3 * n, sizeof *g->direct);
    g->emission = calloc(3 * n, sizeof *g->emission);
    g->emission_resolved = calloc(3 * n, sizeof *g->emission_resolved);
    g->scratch = calloc(3 * n, 1);
    g->specular = calloc(8 * n, sizeof *g->specular);
    if (!g->specular || !g->color || !g->albedo || !g->normal || !g->depth || !g->prim ||
        !g->direct || !g->emission || !g->emission_resolved || !g->scratch) {
        tr_gbuffer_free(g);
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory for a %ux%u frame", width,
                            height);
    }
    return TR_OK;
}

void tr_gbuffer_free(tr_gbuffer *g) {
    free(g->color);
    free(g->albedo);
    free(g->normal);
    free(g->depth);
    free(g->prim);
    free(g->direct);
    free(g->emission);
    free(g->emission_resolved);
    free(g->scratch);
    free(g->specular);
    memset(g, 0, sizeof *g);
}

int tr_gbuffer_from_film(tr_gbuffer *g, const struct tr_film *f, tr_error *err) {
    if (g->width != f->width || g->height != f->height) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "gbuffer: %ux%u frame for a %ux%u film", g->width, g->height, f->width,
                            f->height);
    }
    const size_t n = (size_t)f->width * f->height;
    for (size_t i = 0; i < n; ++i) {
        const uint32_t c = f->count[i];
        const float inv = c ? 1.0f / (float)c : 0.0f;
        for (int k = 0; k < 3; ++k) {
            g->color[3 * i + k] = f->sum[3 * i + k] * inv;
            g->albedo[3 * i + k] = f->albedo ? f->albedo[3 * i + k] * inv : 1.0f;
            g->normal[3 * i + k] = f->normal ? f->normal[3 * i + k] * inv : 0.0f;
            g->direct[3 * i + k] = f->direct ? f->direct[3 * i + k] * inv : 0.0f;
            g->emission[3 * i + k] = f->emission ? f->emission[3 * i + k] * inv : 0.0f;
        }
        g->depth[i] = f->depth ? f->depth[i] * inv : 0.0f;
        g->prim[i] = f->prim ? f->prim[i] : 0u;
        for (int k = 0; k < 8 && f->specular; ++k) {
            g->specular[8 * i + k] = f->specular[8 * i + k] * inv;
        }
    }
    g->has_specular = f->specular != NULL;
    g->has_direct = f->direct != NULL;
    g->has_emission = f->emission != NULL;
    g->has_resolved = 0;
    return TR_OK;
}

static const char *const recon_names[TR_RECON_COUNT] = {"off", "accumulate", "bilateral", "atrous",
                                                        "svgf"};

const char *tr_recon_name(int method) {
    return method >= 0 && method < TR_RECON_COUNT ? recon_names[method] : NULL;
}

int tr_recon_parse(const char *name) {
    for (int m = 0; m < TR_RECON_COUNT; ++m) {
        if (strcmp(name, recon_names[m]) == 0) {
            return m;
        }
    }
    return -1;
}

tr_recon_params tr_recon_params_default(void) {
    tr_recon_params p;
    p.alpha_min = 0.1f;
    p.max_len = 64.0f;
    /* A moving surface's shading changes as it moves (its lighting, its reflections), and
     * a long history lags behind: 4 frames measured best for SVGF on the bench's moving
     * shapes (docs/realtime.md, "A moving shape stops"). */
    p.max_len_moving = 4.0f;
    p.bilateral_radius = 3;
    p.bilateral_sigma_s = 2.0f;
    p.bilateral_sigma_r = 0.3f;
    p.atrous_iterations = 5;
    /* Dammertz et al.'s colour sigma acts on demodulated illumination in [0, ~1]. */
    p.atrous_sigma_c = 0.6f;
    p.atrous_sigma_n = 0.3f;
    p.atrous_sigma_z = 0.05f;
    p.atrous_sigma_a = 0.1f;
    /* Schied et al.'s values are sigma_l 4, sigma_n 128, sigma_z 1 and 5 iterations with
     * TAA after them, and the first iteration's output fed back as the next history. On
     * the classic box at 1 spp 3 iterations measured better, and TAA (alpha 0.1 or 0.3)
     * worse, so it is off unless asked for. The feedback is off: each frame's history is
     * then the previous one blurred once more by a 5x5 level, so over the ~10 frames an
     * EMA of weight 0.1 remembers the blur compounds (shadow and sun-patch edges, the
     * indirect light's detail), and the error grew with the history's length; without it,
     * and with the paper's sigma_l 4 instead of 8, SVGF measured better on all six bench
     * scenes, by 0.1 dB (glass box) to 2.6 dB (window room) (docs/realtime.md, "The hard
     * scenes"). */
    p.svgf_sigma_l = 4.0f;
    p.svgf_iterations = 3;
    p.svgf_sigma_n = 128.0f;
    p.svgf_sigma_z = 1.0f;
    p.svgf_feedback = 0;
    /* 4 x 4 rays per pixel on an emitter's edge: coverage to 1/16 at most 16 rays a pixel. */
    p.emission_samples = 4;
    p.svgf_taa_alpha = 0.0f;
    /* Direct and indirect apart, as the paper does, measured 0.4 dB (160x120) to 0.9 dB
     * (320x240) lower on the classic box at 1 spp and costs twice the instructions
     * (docs/realtime.md), so the sum is filtered unless asked for. */
    p.svgf_split = 0;
    /* Temporal gradients (tr_realtime): see docs/realtime.md, "Lights that change". */
    p.gradients = 0;
    /* Diffuse and specular apart: opt-in (docs/realtime.md has where it measures better). */
    p.svgf_specular = 0;
    /* The sample's own albedo unless asked (tr_resolve_albedo; docs/realtime.md). */
    p.albedo_samples = 0;
    p.albedo_alpha = 0.35f; /* texture edges average over the frames (docs/realtime.md) */
    /* SVGF's history remembers less than the other methods' (the paper's 0.2): the
     * reprojection resamples the history bilinearly every frame, a blur that compounds
     * with the history's age, and after SVGF's spatial filter that blur costs more than
     * the noise a longer history removes (docs/realtime.md, "The hard scenes"). Without
     * the spatial filter the longer history is better, so alpha_min stays 0.1. */
    p.svgf_alpha_min = 0.2f;
    /* Upscaled frames multiply by the output's own albedo: at a quarter of the pixels
     * traced, 1.0 dB on the classic box and 1.05 dB on the textured demo (docs/realtime.md). */
    p.upscale_albedo = 1;
    /* The pixels without history traced at 4 samples in all (tr_realtime): measured better
     * on all six bench scenes, by 0.2 to 0.8 dB mean and 0.4 to 2.2 dB worst frame
     * (docs/realtime.md, "The hard scenes"). */
    p.fresh_spp = 0; /* off: on the hard scenes it costs 25-45 % of a frame (docs/realtime.md) */
    return p;
}

int tr_recon_init(tr_recon *r, uint32_t width, uint32_t height, tr_error *err) {
    memset(r, 0, sizeof *r);
    if (tr_film_check_size(width, height, err) != TR_OK) {
        return TR_ERR;
    }
    const size_t n = (size_t)width * height;
    r->width = width;
    r->height = height;
    int bad = 0;
    for (int k = 0; k < 2; ++k) {
        r->hist_color[k] = calloc(3 * n, sizeof(float));
        r->hist_albedo[k] = calloc(3 * n, sizeof(float));
        r->hist_moments[k] = calloc(2 * n, sizeof(float));
        r->hist_len[k] = calloc(n, sizeof(float));
        bad |= !r->hist_color[k] || !r->hist_albedo[k] || !r->hist_moments[k] || !r->hist_len[k];
        r->hist_direct[k] = calloc(3 * n, sizeof(float));
        r->hist_dmoments[k] = calloc(2 * n, sizeof(float));
        bad |= !r->hist_direct[k] || !r->hist_dmoments[k];
    }
    for (int k = 0; k < 2; ++k) {
        r->hist_spec[k] = calloc(3 * n, sizeof(float));
        r->hist_smoments[k] = calloc(2 * n, sizeof(float));
        r->hist_slen[k] = calloc(n, sizeof(float));
        bad |= !r->hist_spec[k] || !r->hist_smoments[k] || !r->hist_slen[k];
    }
    r->illum_s = calloc(3 * n, sizeof(float));
    r->spec_alb = calloc(3 * n, sizeof(float));
    r->diffuse = calloc(3 * n, sizeof(float));
    bad |= !r->illum_s || !r->spec_alb || !r->diffuse;
    r->illum_d = calloc(3 * n, sizeof(float));
    r->reflected = calloc(3 * n, sizeof(float));
    r->reflected_d = calloc(3 * n, sizeof(float));
    bad |= !r->illum_d || !r->reflected || !r->reflected_d;
    r->hist_depth = calloc(n, sizeof(float));
    r->hist_normal = calloc(3 * n, sizeof(float));
    r->hist_prim = calloc(n, sizeof(uint32_t));
    r->illum = calloc(3 * n, sizeof(float));
    r->soa = calloc((size_t)WS_PLANES * n, sizeof(float));
    r->taa = calloc(3 * n, sizeof(float));
    r->temporal = calloc((size_t)TP_PLANES * n, sizeof(float));
    bad |= !r->hist_depth || !r->hist_normal || !r->hist_prim || !r->illum || !r->soa || !r->taa;
    bad |= !r->temporal;
    if (bad) {
        tr_recon_free(r);
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY,
                            "out of memory for a %ux%u reconstruction", width, height);
    }
    return TR_OK;
}

void tr_recon_free(tr_recon *r) {
    for (int k = 0; k < 2; ++k) {
        free(r->hist_color[k]);
        free(r->hist_albedo[k]);
        free(r->hist_moments[k]);
        free(r->hist_len[k]);
        free(r->hist_direct[k]);
        free(r->hist_dmoments[k]);
        free(r->hist_spec[k]);
        free(r->hist_smoments[k]);
        free(r->hist_slen[k]);
    }
    free(r->illum_s);
    free(r->spec_alb);
    free(r->diffuse);
    free(r->illum_d);
    free(r->reflected);
    free(r->reflected_d);
    free(r->hist_depth);
    free(r->hist_normal);
    free(r->hist_prim);
    free(r->illum);
    free(r->soa);
    free(r->taa);
    free(r->temporal);
    memset(r, 0, sizeof *r);
}

void tr_recon_clear(tr_recon *r) {
    r->have_history = 0;
}

static int check_frame(uint32_t w, uint32_t h, const tr_gbuffer *g, tr_error *err) {
    if (g->width != w || g->height != h) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "reconstruction: %ux%u frame for a %ux%u state", g->width, g->height, w,
                            h);
    }
    return TR_OK;
}

/* ---- The spatial filters on the host -------------------------------------------
 *
 * The per-pixel operators of filter.h loop over their taps inside one pixel, which a
 * device runs one work item per pixel. On the CPU that shape does not vectorise, so the
 * host turns the loops round: for each tap (in the operators' order) it runs along a
 * chunk of a row, accumulating every pixel's sums, on planar (structure-of-arrays)
 * copies of the colour and the guides. Each pixel's sums take the same terms in the
 * same order as its operator (test_recon checks the agreement), so the result is still
 * independent of the thread count, and the one exponential per tap is filter.h's
 * branch-free tr_post_exp_neg, which gcc vectorises. */

/* The hot row loops three times, for AVX-512, AVX2 and the baseline, chosen at load time
 * (gcc's ifunc clones): the same operations per lane either way (no FMA:
 * -ffp-contract=off), so the numbers do not depend on the CPU. AVX-512 took SVGF's spatial
 * stage from 6.69 to 5.86 ms and the bilateral filter's from 2.71 to 1.73 ms at 320x240
 * on the 2-core EPYC (docs/realtime.md), with the same images. */
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && defined(__linux__)
#define TR_POST_CLONES __attribute__((target_clones("avx512f", "avx2", "default")))
#else
#define TR_POST_CLONES
#endif

static void ws_bind(post_ws *ws, float *block, int w, int h) {
    ws->w = w;
    ws->h = h;
    ws->cancel = NULL;
    ws->cancel_user = NULL;
    for (int k = 0; k < WS_PLANES; ++k) {
        ws->p[k] = block + (size_t)k * w * h;
    }
}

/* Whether the caller asked to stop (post_ws.cancel). */
static int ws_cancelled(const post_ws *ws) {
    return ws->cancel && ws->cancel(ws->cancel_user);
}

static int imax(int a, int b) {
    return a > b ? a : b;
}
static int imin(int a, int b) {
    return a < b ? a : b;
}

/* Interleaved RGB `in` (times 1 / albedo when demod, times albedo when remod, else as
 * it is) into the three planes at dst. */
static void to_planes(const tr_gbuffer *g, const float *in, float *const dst[3], int demod,
                      int threads) {
    const long n = (long)g->width * g->height;
#pragma omp parallel for num_threads(threads) schedule(static)
    for (long i = 0; i < n; ++i) {
        for (int k = 0; k < 3; ++k) {
            const float a = tr_post_demod_factor(g->albedo[3 * i + k]);
            const float v = in[3 * i + k];
            dst[k][i] = demod > 0 ? v / a : demod < 0 ? v * a : v;
        }
    }
}

/* Three planes times the albedo added to interleaved RGB out (SVGF's second component). */
static void add_from_planes(const tr_gbuffer *g, const float *const src[3], float *out,
                            int threads) {
    const long n = (long)g->width * g->height;
#pragma omp parallel for num_threads(threads) schedule(static)
    for (long i = 0; i < n; ++i) {
        for (int k = 0; k < 3; ++k) {
            out[3 * i + k] += src[k][i] * tr_post_demod_factor(g->albedo[3 * i + k]);
        }
    }
}

/* Three planes into interleaved RGB out, times the albedo when remod. */
static void from_planes(const tr_gbuffer *g, const float *const src[3], float *out, int remod,
                        int threads) {
    const long n = (long)g->width * g->height;
#pragma omp parallel for num_threads(threads) schedule(static)
    for (long i = 0; i < n; ++i) {
        for (int k = 0; k < 3; ++k) {
            out[3 * i + k] =
                remod ? src[k][i] * tr_post_demod_factor(g->albedo[3 * i + k]) : src[k][i];
        }
    }
}

static void luminance_plane(const float *const c[3], float *lum, long n, int threads) {
#pragma omp parallel for num_threads(threads) schedule(static)
    for (long i = 0; i < n; ++i) {
        lum[i] = tr_post_luminance(c[0][i], c[1][i], c[2][i]);
    }
}

/* The guides as planes: normals, albedo, and the per-pixel coefficients that do not
 * change between iterations. */
static void prep_guides(const tr_gbuffer *g, const post_ws *ws, const tr_recon_params *p,
                        int svgf_coeffs, int threads) {
    const int w = ws->w, h = ws->h;
#pragma omp parallel for num_threads(threads) schedule(static)
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            const int c = y * w + x;
            const float nx = g->normal[3 * c], ny = g->normal[3 * c + 1], nz = g->normal[3 * c + 2];
            ws->p[WS_N][c] = nx;
            ws->p[WS_N + 1][c] = ny;
            ws->p[WS_N + 2][c] = nz;
            for (int k = 0; k < 3; ++k) {
                ws->p[WS_A + k][c] = g->albedo[3 * c + k];
            }
            if (svgf_coeffs) {
                ws->p[WS_KZ][c] = tr_post_svgf_kz(g->depth, w, h, x, y, p->svgf_sigma_z);
                ws->p[WS_KN][c] = nx * nx + ny * ny + nz * nz > 0.25f ? p->svgf_sigma_n : 0.0f;
            } else {
                const float cz = g->depth[c];
                ws->p[WS_KZ][c] = 1.0f / (cz > 1e-6f ? cz : 1.0f);
            }
        }
    }
}

/* The bilateral filter (tr_post_bilateral_pixel) of planes src into interleaved out. */
TR_POST_CLONES static void bilateral_rows(const post_ws *ws, const float *const src[3], float *out,
                                          const tr_recon_params *p, int y0, int y1) {
    const int w = ws->w, h = ws->h, rad = p->bilateral_radius;
    const float is = 1.0f / (2.0f * p->bilateral_sigma_s * p->bilateral_sigma_s);
    const float ir = 1.0f / (2.0f * p->bilateral_sigma_r * p->bilateral_sigma_r);
    const float *restrict r = src[0], *restrict gg = src[1], *restrict b = src[2];
    for (int y = y0; y < y1; ++y) {
        for (int x0 = 0; x0 < w; x0 += TR_POST_CHUNK) {
            const int x1 = imin(w, x0 + TR_POST_CHUNK);
            float ar[TR_POST_CHUNK] = {0}, ag[TR_POST_CHUNK] = {0}, ab[TR_POST_CHUNK] = {0},
                  aw[TR_POST_CHUNK] = {0};
            for (int dy = -rad; dy <= rad; ++dy) {
                const int ty = y + dy;
                if (ty < 0 || ty >= h) {
                    continue;
                }
                for (int dx = -rad; dx <= rad; ++dx) {
                    const int xa = imax(x0, -dx), xb = imin(x1, w - dx);
                    const float es = (float)(dx * dx + dy * dy) * is;
                    const int row = ty * w + dx, crow = y * w;
                    for (int x = xa; x < xb; ++x) {
                        const int i = row + x, c = crow + x, a = x - x0;
                        const float dr = r[i] - r[c], dg = gg[i] - gg[c], db = b[i] - b[c];
                        const float wt = tr_post_exp_neg(es + (dr * dr + dg * dg + db * db) * ir);
                        ar[a] += wt * r[i];
                        ag[a] += wt * gg[i];
                        ab[a] += wt * b[i];
                        aw[a] += wt;
                    }
                }
            }
            for (int x = x0; x < x1; ++x) {
                const size_t c = (size_t)y * w + x;
                const int a = x - x0;
                out[3 * c] = ar[a] / aw[a];
                out[3 * c + 1] = ag[a] / aw[a];
                out[3 * c + 2] = ab[a] / aw[a];
            }
        }
    }
}

static void bilateral_planes(const post_ws *ws, const float *const src[3], float *out,
                             const tr_recon_params *p, int threads) {
#pragma omp parallel for num_threads(threads) schedule(static)
    for (int y = 0; y < ws->h; ++y) {
        bilateral_rows(ws, src, out, p, y, y + 1);
    }
}

/* The 25 taps of one step of an edge-avoiding à-trous filter (5x5, holes of `step`) over
 * the run of n pixels from x0 in row y of a w x h image, in the operator's order: each
 * tap calls TAP(k, y, ty, x0, kx, ky, xa, xb) for the run's pixels x0 + a, a in
 * [xa, xb). `inner` (a block of TR_POST_BLOCK pixels whose taps all lie in the image):
 * the taps unrolled, so that the compiler keeps TAP's accumulators in vector registers
 * across them; otherwise each tap's run is clipped to the image, in a loop. */
#define POST_RUN_TAPS(TAP, k, y, x0, n, w, h, step, inner)                                         \
    do {                                                                                           \
        if (inner) {                                                                               \
            _Pragma("GCC unroll 5") for (int ky = -2; ky <= 2; ++ky) {                             \
                const int ty = (y) + ky * (step);                                                  \
                _Pragma("GCC unroll 5") for (int kx = -2; kx <= 2; ++kx) {                         \
                    TAP(k, y, ty, x0, kx, ky, 0, TR_POST_BLOCK);                                   \
                }                                                                                  \
            }                                                                                      \
        } else {                                                                                   \
            for (int ky = -2; ky <= 2; ++ky) {                                                     \
                const int ty = (y) + ky * (step);                                                  \
                if (ty < 0 || ty >= (h)) {                                                         \
                    continue;                                                                      \
                }                                                                                  \
                for (int kx = -2; kx <= 2; ++kx) {                                                 \
                    const int off = kx * (step);                                                   \
                    TAP(k, y, ty, x0, kx, ky, imax(0, -off - (x0)), imin(n, (w)-off - (x0)));      \
                }                                                                                  \
            }                                                                                      \
        }                                                                                          \
    } while (0)

/* One à-trous iteration's inputs (planes), its weights' reciprocal squared sigmas and
 * its accumulators for a run of pixels. */
typedef struct atrous_run_ctx {
    const float *r, *g, *b, *z, *nx, *ny, *nz, *a0, *a1, *a2, *icz;
    float ic, in2, iz, ia;
    int w, step;
    float ar[TR_POST_CHUNK], ag[TR_POST_CHUNK], ab[TR_POST_CHUNK], aw[TR_POST_CHUNK];
} atrous_run_ctx;

/* Tap (kx, ky) of one edge-avoiding à-trous iteration (tr_post_atrous_pixel's terms)
 * for the pixels x0 + a, a in [xa, xb), of row y (the tap's row ty), added into the
 * run's accumulators. */
static inline __attribute__((always_inline)) void
atrous_tap(atrous_run_ctx *restrict k, int y, int ty, int x0, int kx, int ky, int xa, int xb) {
    const float *restrict r = k->r, *restrict gg = k->g, *restrict b = k->b, *restrict z = k->z,
                          *restrict nx = k->nx, *restrict ny = k->ny, *restrict nz = k->nz,
                          *restrict a0 = k->a0, *restrict a1 = k->a1, *restrict a2 = k->a2,
                          *restrict icz = k->icz;
    const float ic = k->ic, in2 = k->in2, iz = k->iz, ia = k->ia;
    const int off = kx * k->step;
    const float bk = tr_post_b3(kx) * tr_post_b3(ky);
    const int row = ty * k->w + off + x0, crow = y * k->w + x0;
    for (int a = xa; a < xb; ++a) {
        const int i = row + a, c = crow + a;
        const float dr = r[i] - r[c], dg = gg[i] - gg[c], db = b[i] - b[c];
        const float dnx = nx[i] - nx[c], dny = ny[i] - ny[c], dnz = nz[i] - nz[c];
        const float dz = (z[i] - z[c]) * icz[c];
        const float da0 = a0[i] - a0[c], da1 = a1[i] - a1[c], da2 = a2[i] - a2[c];
        const float e = (dr * dr + dg * dg + db * db) * ic +
                        (dnx * dnx + dny * dny + dnz * dnz) * in2 + dz * dz * iz +
                        (da0 * da0 + da1 * da1 + da2 * da2) * ia;
        const float wt = bk * tr_post_exp_neg(e);
        k->ar[a] += wt * r[i];
        k->ag[a] += wt * gg[i];
        k->ab[a] += wt * b[i];
        k->aw[a] += wt;
    }
}

/* One à-trous iteration (tr_post_atrous_pixel) of the run of n pixels from x0 in row y
 * into dst; `inner` as in POST_RUN_TAPS. */
static inline __attribute__((always_inline)) void atrous_run(atrous_run_ctx *restrict k,
                                                             float *const dst[3], int h, int y,
                                                             int x0, int n, int inner) {
    const int w = k->w, step = k->step;
    for (int a = 0; a < n; ++a) {
        k->ar[a] = k->ag[a] = k->ab[a] = k->aw[a] = 0.0f;
    }
    POST_RUN_TAPS(atrous_tap, k, y, x0, n, w, h, step, inner);
    for (int a = 0; a < n; ++a) {
        const int c = y * w + x0 + a;
        dst[0][c] = k->ar[a] / k->aw[a];
        dst[1][c] = k->ag[a] / k->aw[a];
        dst[2][c] = k->ab[a] / k->aw[a];
    }
}

/* Rows y0 .. y1 - 1 of one edge-avoiding à-trous iteration (tr_post_atrous_pixel) of
 * planes src into dst, blocked as svgf_rows. */
TR_POST_CLONES static void atrous_rows(const post_ws *ws, const float *depth,
                                       const float *const src[3], float *const dst[3], int step,
                                       float sigma_c, const tr_recon_params *p, int y0, int y1) {
    const int w = ws->w, h = ws->h, reach = 2 * step;
    atrous_run_ctx k;
    k.ic = 1.0f / (sigma_c * sigma_c);
    k.in2 = 1.0f / (p->atrous_sigma_n * p->atrous_sigma_n);
    k.iz = 1.0f / (p->atrous_sigma_z * p->atrous_sigma_z);
    k.ia = 1.0f / (p->atrous_sigma_a * p->atrous_sigma_a);
    k.r = src[0];
    k.g = src[1];
    k.b = src[2];
    k.z = depth;
    k.nx = ws->p[WS_N];
    k.ny = ws->p[WS_N + 1];
    k.nz = ws->p[WS_N + 2];
    k.a0 = ws->p[WS_A];
    k.a1 = ws->p[WS_A + 1];
    k.a2 = ws->p[WS_A + 2];
    k.icz = ws->p[WS_KZ];
    k.w = w;
    k.step = step;
    for (int y = y0; y < y1; ++y) {
        const int rows_in = y >= reach && y + reach < h;
        int x0 = 0;
        while (x0 < w) {
            if (rows_in && x0 >= reach && x0 + TR_POST_BLOCK + reach <= w) {
                atrous_run(&k, dst, h, y, x0, TR_POST_BLOCK, 1);
                x0 += TR_POST_BLOCK;
            } else {
                const int n = rows_in && x0 < reach ? reach - x0 : imin(w - x0, TR_POST_CHUNK);
                atrous_run(&k, dst, h, y, x0, n, 0);
                x0 += n;
            }
        }
    }
}

static void atrous_planes(const post_ws *ws, const float *depth, const float *const src[3],
                          float *const dst[3], int step, float sigma_c, const tr_recon_params *p,
                          int threads) {
#pragma omp parallel for num_threads(threads) schedule(static)
    for (int y = 0; y < ws->h; ++y) {
        atrous_rows(ws, depth, src, dst, step, sigma_c, p, y, y + 1);
    }
}

/* Dammertz et al.'s iterations on the planes at WS_CA: the planes of the result
 * returned (WS_CA or WS_CB); sigma_c halves each step as in the paper. */
static int atrous(const post_ws *ws, const float *depth, const tr_recon_params *p, int threads) {
    int src = WS_CA, dst = WS_CB;
    for (int it = 0; it < p->atrous_iterations && !(it > 0 && ws_cancelled(ws)); ++it) {
        const float *const s3[3] = {ws->p[src], ws->p[src + 1], ws->p[src + 2]};
        float *const d3[3] = {ws->p[dst], ws->p[dst + 1], ws->p[dst + 2]};
        atrous_planes(ws, depth, s3, d3, 1 << it, p->atrous_sigma_c / (float)(1 << it), p, threads);
        const int t = src;
        src = dst;
        dst = t;
    }
    return src;
}

/* SVGF's prefiltered luminance coefficient (tr_post_var3x3, tr_post_svgf_kl) of every
 * pixel from variance plane var, into WS_KL. */
static void svgf_kl(const post_ws *ws, const float *var, float sigma_l, int threads) {
    const int w = ws->w, h = ws->h;
    float *restrict kl = ws->p[WS_KL];
#pragma omp parallel for num_threads(threads) schedule(static)
    for (int y = 0; y < h; ++y) {
        for (int x0 = 0; x0 < w; x0 += TR_POST_CHUNK) {
            const int x1 = imin(w, x0 + TR_POST_CHUNK);
            float av[TR_POST_CHUNK] = {0}, aw[TR_POST_CHUNK] = {0};
            for (int dy = -1; dy <= 1; ++dy) {
                const int ty = y + dy;
                if (ty < 0 || ty >= h) {
                    continue;
                }
                for (int dx = -1; dx <= 1; ++dx) {
                    const int xa = imax(x0, -dx), xb = imin(x1, w - dx);
                    const float k = (dx ? 0.5f : 1.0f) * (dy ? 0.5f : 1.0f);
                    const float *restrict v = var + ty * w + dx;
                    for (int x = xa; x < xb; ++x) {
                        av[x - x0] += k * v[x];
                        aw[x - x0] += k;
                    }
                }
            }
            for (int x = x0; x < x1; ++x) {
                kl[y * w + x] = tr_post_svgf_kl(av[x - x0] / aw[x - x0], sigma_l);
            }
        }
    }
}

/* One SVGF iteration's inputs (planes) and its accumulators for a run of pixels. */
typedef struct svgf_run_ctx {
    const float *r, *g, *b, *l, *v, *z, *nx, *ny, *nz, *kz, *kl, *kn;
    int w, step;
    float ar[TR_POST_CHUNK], ag[TR_POST_CHUNK], ab[TR_POST_CHUNK], aw[TR_POST_CHUNK],
        av[TR_POST_CHUNK];
} svgf_run_ctx;

/* Tap (kx, ky) of one SVGF iteration (tr_post_svgf_pixel's terms) for the pixels
 * x0 + a, a in [xa, xb), of row y (the tap's row ty), added into the run's accumulators. */
static inline __attribute__((always_inline)) void svgf_tap(svgf_run_ctx *restrict k, int y, int ty,
                                                           int x0, int kx, int ky, int xa, int xb) {
    const float *restrict r = k->r, *restrict gg = k->g, *restrict b = k->b, *restrict l = k->l,
                          *restrict v = k->v, *restrict z = k->z, *restrict nx = k->nx,
                          *restrict ny = k->ny, *restrict nz = k->nz, *restrict kz = k->kz,
                          *restrict kl = k->kl, *restrict kn = k->kn;
    const int off = kx * k->step;
    const float bk = tr_post_b3(kx) * tr_post_b3(ky);
    const float id = tr_post_svgf_idist(kx, ky, k->step);
    const int row = ty * k->w + off + x0, crow = y * k->w + x0;
    for (int a = xa; a < xb; ++a) {
        const int i = row + a, c = crow + a;
        const float nd = nx[c] * nx[i] + ny[c] * ny[i] + nz[c] * nz[i];
        const float e =
            tr_post_svgf_exponent(z[i] - z[c], kz[c], id, l[i] - l[c], kl[c], kn[c], nd);
        const float wt = bk * tr_post_exp_neg(e);
        k->ar[a] += wt * r[i];
        k->ag[a] += wt * gg[i];
        k->ab[a] += wt * b[i];
        k->av[a] += wt * wt * v[i];
        k->aw[a] += wt;
    }
}

/* One SVGF iteration (tr_post_svgf_pixel) of the run of n pixels from x0 in row y into
 * dst, dlum, dvar; `inner` as in POST_RUN_TAPS (the unrolled taps 1.3x faster,
 * docs/realtime.md). */
static inline __attribute__((always_inline)) void
svgf_run(svgf_run_ctx *restrict k, float *const dst[3], float *restrict dlum, float *restrict dvar,
         int h, int y, int x0, int n, int inner) {
    const int w = k->w, step = k->step;
    for (int a = 0; a < n; ++a) {
        k->ar[a] = k->ag[a] = k->ab[a] = k->aw[a] = k->av[a] = 0.0f;
    }
    POST_RUN_TAPS(svgf_tap, k, y, x0, n, w, h, step, inner);
    for (int a = 0; a < n; ++a) {
        const int c = y * w + x0 + a;
        const float ro = k->ar[a] / k->aw[a], go = k->ag[a] / k->aw[a], bo = k->ab[a] / k->aw[a];
        dst[0][c] = ro;
        dst[1][c] = go;
        dst[2][c] = bo;
        dlum[c] = tr_post_luminance(ro, go, bo);
        dvar[c] = k->av[a] / (k->aw[a] * k->aw[a]);
    }
}

/* Rows y0 .. y1 - 1 of one SVGF iteration (tr_post_svgf_pixel) of planes src
 * (luminance lum, variance var) into dst, dlum, dvar: blocks whose taps all lie in the
 * image take the unrolled fixed-width path, the rest (near the edges) the clipped one. */
TR_POST_CLONES static void svgf_rows(const post_ws *ws, const float *depth,
                                     const float *const src[3], const float *lum, const float *var,
                                     float *const dst[3], float *dlum, float *dvar, int step,
                                     int y0, int y1) {
    const int w = ws->w, h = ws->h, reach = 2 * step;
    svgf_run_ctx k;
    k.r = src[0];
    k.g = src[1];
    k.b = src[2];
    k.l = lum;
    k.v = var;
    k.z = depth;
    k.nx = ws->p[WS_N];
    k.ny = ws->p[WS_N + 1];
    k.nz = ws->p[WS_N + 2];
    k.kz = ws->p[WS_KZ];
    k.kl = ws->p[WS_KL];
    k.kn = ws->p[WS_KN];
    k.w = w;
    k.step = step;
    for (int y = y0; y < y1; ++y) {
        const int rows_in = y >= reach && y + reach < h;
        int x0 = 0;
        while (x0 < w) {
            if (rows_in && x0 >= reach && x0 + TR_POST_BLOCK + reach <= w) {
                svgf_run(&k, dst, dlum, dvar, h, y, x0, TR_POST_BLOCK, 1);
                x0 += TR_POST_BLOCK;
            } else {
                /* Up to the first full block, or the rest of the row. */
                const int n = rows_in && x0 < reach ? reach - x0 : imin(w - x0, TR_POST_CHUNK);
                svgf_run(&k, dst, dlum, dvar, h, y, x0, n, 0);
                x0 += n;
            }
        }
    }
}

static void svgf_planes(const post_ws *ws, const float *depth, const float *const src[3],
                        const float *lum, const float *var, float *const dst[3], float *dlum,
                        float *dvar, int step, int threads) {
#pragma omp parallel for num_threads(threads) schedule(static)
    for (int y = 0; y < ws->h; ++y) {
        svgf_rows(ws, depth, src, lum, var, dst, dlum, dvar, step, y, y + 1);
    }
}

/* SVGF's iterations on the planes at WS_CA with luminance WS_LA and variance WS_VA; the planes of
 * the result returned. After the first iteration its output goes to `feedback` (interleaved) when
 * that is not NULL: Schied et al. feed it back as the next frame's history. */
static int svgf(const post_ws *ws, const float *depth, const tr_recon_params *p, float *feedback,
                int threads) {
    int src = WS_CA, dst = WS_CB, ls = WS_LA, ld = WS_LB, vs = WS_VA, vd = WS_VB;
    const long n = (long)ws->w * ws->h;
    for (int it = 0; it < p->svgf_iterations && !(it > 0 && ws_cancelled(ws)); ++it) {
        const float *const s3[3] = {ws->p[src], ws->p[src + 1], ws->p[src + 2]};
        float *const d3[3] = {ws->p[dst], ws->p[dst + 1], ws->p[dst + 2]};
        svgf_kl(ws, ws->p[vs], p->svgf_sigma_l, threads);
        svgf_planes(ws, depth, s3, ws->p[ls], ws->p[vs], d3, ws->p[ld], ws->p[vd], 1 << it,
                    threads);
        if (it == 0 && feedback) {
            for (long i = 0; i < n; ++i) {
                for (int k = 0; k < 3; ++k) {
                    feedback[3 * i + k] = d3[k][i];
                }
            }
        }
        int t = src;
        src = dst;
        dst = t;
        t = ls;
        ls = ld;
        ld = t;
        t = vs;
        vs = vd;
        vd = t;
    }
    return src;
}

static void demodulate(const tr_gbuffer *g, const float *in, float *out, int threads) {
    const long n = (long)g->width * g->height;
#pragma omp parallel for num_threads(threads) schedule(static)
    for (long i = 0; i < n; ++i) {
        for (int k = 0; k < 3; ++k) {
            out[3 * i + k] = in[3 * i + k] / tr_post_demod_factor(g->albedo[3 * i + k]);
        }
    }
}

static void remodulate(const tr_gbuffer *g, const float *in, float *out, int threads) {
    const long n = (long)g->width * g->height;
#pragma omp parallel for num_threads(threads) schedule(static)
    for (long i = 0; i < n; ++i) {
        for (int k = 0; k < 3; ++k) {
            out[3 * i + k] = in[3 * i + k] * tr_post_demod_factor(g->albedo[3 * i + k]);
        }
    }
}

static float *ws_alloc(const tr_gbuffer *g) {
    return malloc((size_t)WS_PLANES * g->width * g->height * sizeof(float));
}

static void planes_of(const post_ws *ws, int k, float *out3[3]) {
    out3[0] = ws->p[k];
    out3[1] = ws->p[k + 1];
    out3[2] = ws->p[k + 2];
}

int tr_filter_bilateral(const tr_gbuffer *g, const float *in, float *out, const tr_recon_params *p,
                        int threads, tr_error *err) {
    const tr_recon_params resolved = tr_recon_params_resolve(p);
    p = &resolved;
    float *block = ws_alloc(g);
    if (!block) {
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory for a %ux%u filter",
                            g->width, g->height);
    }
    threads = nthreads(threads);
    post_ws ws;
    ws_bind(&ws, block, (int)g->width, (int)g->height);
    float *c3[3];
    planes_of(&ws, WS_CA, c3);
    to_planes(g, in, c3, 0, threads);
    bilateral_planes(&ws, (const float *const *)c3, out, p, threads);
    free(block);
    return TR_OK;
}

int tr_filter_atrous(const tr_gbuffer *g, const float *in, float *out, const tr_recon_params *p,
                     int threads, tr_error *err) {
    const tr_recon_params resolved = tr_recon_params_resolve(p);
    p = &resolved;
    float *block = ws_alloc(g);
    if (!block) {
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory for a %ux%u filter",
                            g->width, g->height);
    }
    threads = nthreads(threads);
    post_ws ws;
    ws_bind(&ws, block, (int)g->width, (int)g->height);
    float *c3[3];
    planes_of(&ws, WS_CA, c3);
    to_planes(g, in, c3, 1, threads);
    prep_guides(g, &ws, p, 0, threads);
    planes_of(&ws, atrous(&ws, g->depth, p, threads), c3);
    from_planes(g, (const float *const *)c3, out, 1, threads);
    free(block);
    return TR_OK;
}

/* SVGF's variance of every pixel (tr_post_svgf_variance_pixel) from the luminance plane
 * lum of the illumination, turned round like the filters: the spatial estimate's 5x5
 * sums for every pixel of a chunk, tap by tap, then the temporal moments where the
 * history is long enough. */
TR_POST_CLONES static void svgf_variance_rows(const post_ws *ws, const float *lum,
                                              const float *moments, const float *len, float *var,
                                              int y0, int y1) {
    const int w = ws->w, h = ws->h;
    const float *restrict nx = ws->p[WS_N], *restrict ny = ws->p[WS_N + 1],
                          *restrict nz = ws->p[WS_N + 2], *restrict l = lum;
    for (int y = y0; y < y1; ++y) {
        for (int x0 = 0; x0 < w; x0 += TR_POST_CHUNK) {
            const int x1 = imin(w, x0 + TR_POST_CHUNK);
            float a1[TR_POST_CHUNK] = {0}, a2[TR_POST_CHUNK] = {0}, aw[TR_POST_CHUNK] = {0};
            for (int dy = -2; dy <= 2; ++dy) {
                const int ty = y + dy;
                if (ty < 0 || ty >= h) {
                    continue;
                }
                for (int dx = -2; dx <= 2; ++dx) {
                    const int xa = imax(x0, -dx), xb = imin(x1, w - dx);
                    const int row = ty * w + dx, crow = y * w, centre = dx == 0 && dy == 0;
                    for (int x = xa; x < xb; ++x) {
                        const int i = row + x, c = crow + x, a = x - x0;
                        const float nd = nx[c] * nx[i] + ny[c] * ny[i] + nz[c] * nz[i];
                        const float wt = centre || nd > 0.9f ? 1.0f : 0.0f;
                        a1[a] += wt * l[i];
                        a2[a] += wt * l[i] * l[i];
                        aw[a] += wt;
                    }
                }
            }
            for (int x = x0; x < x1; ++x) {
                const int c = y * w + x, a = x - x0;
                if (len[c] >= 4.0f) {
                    const float m = moments[2 * c];
                    var[c] = tr_fmaxf(moments[2 * c + 1] - m * m, 0.0f);
                } else {
                    const float m = a1[a] / aw[a];
                    var[c] =
                        tr_fmaxf(a2[a] / aw[a] - m * m, 0.0f) * (TR_POST_SVGF_SHORT_BOOST / len[c]);
                }
            }
        }
    }
}

static void svgf_variance(const post_ws *ws, const float *lum, const float *moments,
                          const float *len, float *var, int threads) {
#pragma omp parallel for num_threads(threads) schedule(static)
    for (int y = 0; y < ws->h; ++y) {
        svgf_variance_rows(ws, lum, moments, len, var, y, y + 1);
    }
}

/* ---- The temporal stage on the host ---------------------------------------------
 *
 * tr_post_temporal_pixel finds, for every pixel, its surface point and the surface
 * points of the up to four previous pixels around its reprojection: five normalised
 * camera rays a pixel, in scalar, branching code. The host instead computes every
 * frame's points once, in a loop gcc vectorises, and keeps them: the next frame's taps
 * read them instead of recomputing them (the same operations on the same operands as
 * tr_camera_point_at, so the same bits). The projection into the previous camera is
 * vectorised along with them. What is left per pixel - the taps' tests
 * (tr_reproject_consistent) and the blend (tr_post_temporal_blend) - are the operator's own
 * functions, in its order; test_recon checks the host against tr_post_temporal_pixel. */

/* Rows [y0, y1): each pixel's surface point (tr_camera_point_at at its depth) into
 * pt's planes. Branch-free, so that gcc vectorises it (as the next one). */
TR_POST_CLONES static void temporal_points_rows(const tr_camera *cam, const float *depth,
                                                float *const pt[3], int y0, int y1) {
    const tr_camera c = *cam;
    const int w = (int)c.screen_width;
    float *restrict px = pt[0], *restrict py = pt[1], *restrict pz = pt[2];
    const float *restrict dep = depth;
    for (int y = y0; y < y1; ++y) {
        for (int x = 0; x < w; ++x) {
            const int i = y * w + x;
            const tr_vec3 p = tr_camera_point_at(&c, (float)x, (float)y, dep[i]);
            px[i] = p.x;
            py[i] = p.y;
            pz[i] = p.z;
        }
    }
}

/* Rows [y0, y1) of points pt (at depths depth) projected into the previous camera pc:
 * tr_camera_project's position less 0.5 (fx, fy; fx -2 where tr_post_reproject stops
 * early: nothing hit, behind the camera or off screen) and the distance. */
TR_POST_CLONES static void temporal_project_rows(const tr_camera *pc, int w,
                                                 const float *restrict dep,
                                                 const float *restrict px, const float *restrict py,
                                                 const float *restrict pz, float *restrict fx,
                                                 float *restrict fy, float *restrict dist, int y0,
                                                 int y1) {
    /* The previous camera's fields as scalars: loads from a struct in the loop would
     * keep gcc from vectorising it. */
    const tr_vec3 qo = pc->pos, qd = pc->dir, qr = pc->right, qu = pc->up;
    const float cw = pc->canvas_width, ch = pc->canvas_height;
    const float pw = (float)pc->screen_width, ph = (float)pc->screen_height;
    const float ox = qo.x, oy = qo.y, oz = qo.z, dx = qd.x, dy = qd.y, dz = qd.z;
    const float rx = qr.x, ry = qr.y, rz = qr.z, ux = qu.x, uy = qu.y, uz = qu.z;
    for (int y = y0; y < y1; ++y) {
        for (int x = 0; x < w; ++x) {
            const int i = y * w + x;
            /* tr_camera_project's arithmetic, in its order, its test folded into the flag. */
            const float vx = px[i] - ox, vy = py[i] - oy, vz = pz[i] - oz;
            const float z = vx * dx + vy * dy + vz * dz;
            const float cx = (vx * rx + vy * ry + vz * rz) / z;
            const float cy = (vx * ux + vy * uy + vz * uz) / z;
            const float sx = (cx / cw + 0.5f) * pw - 0.5f;
            const float sy = (0.5f - cy / ch) * ph - 0.5f;
            const int ok =
                (dep[i] > 0.0f) & (z > 1e-6f) & (sx > -1.0f) & (sy > -1.0f) & (sx < pw) & (sy < ph);
            fx[i] = ok ? sx : -2.0f;
            fy[i] = sy;
            dist[i] = tr_sqrtf(vx * vx + vy * vy + vz * vz);
        }
    }
}

/* Rows [y0, y1) of points pt followed back by their primitives' motion (id prim[i],
 * motion[id] where id < motion_count) into pm: tr_post_reproject_moving's p - motion. */
static void temporal_moved_rows(const float *const pt[3], const uint32_t *prim,
                                const tr_vec3 *motion, uint32_t motion_count, float *const pm[3],
                                int w, int y0, int y1) {
    for (int y = y0; y < y1; ++y) {
        for (int x = 0; x < w; ++x) {
            const int i = y * w + x;
            const uint32_t id = prim[i];
            const tr_vec3 m = id < motion_count ? motion[id] : v3s(0.0f);
            pm[0][i] = pt[0][i] - m.x;
            pm[1][i] = pt[1][i] - m.y;
            pm[2][i] = pt[2][i] - m.z;
        }
    }
}

/* Rows [y0, y1) of the temporal stage: tr_post_temporal_pixel_moving of every pixel,
 * from the points (followed back by their motion, if any) and projection of
 * temporal_points_rows, temporal_moved_rows and temporal_project_rows, and the previous
 * frame's points pq. */
static void temporal_rows(const tr_recon *r, const tr_gbuffer *g, const float *const pt[3],
                          const float *const pq[3], const float *fxs, const float *fys,
                          const float *dists, const tr_vec3 *motion, uint32_t motion_count,
                          const float *pcol, const float *pmom, const float *plen,
                          const tr_recon_params *p, float *hc, float *hm, float *hl, int y0,
                          int y1) {
    const int w = (int)g->width, h = (int)g->height;
    float *const na = p->albedo_alpha > 0.0f ? r->hist_albedo[1 - r->cur] : NULL;
    for (int y = y0; y < y1; ++y) {
        for (int x = 0; x < w; ++x) {
            const int i = y * w + x;
            const float cr = r->illum[3 * i], cg = r->illum[3 * i + 1], cb = r->illum[3 * i + 2];
            float wt[4] = {0.0f, 0.0f, 0.0f, 0.0f}, total = 0.0f;
            int ix = 0, iy = 0;
            const float fx = fxs ? fxs[i] : -2.0f;
            if (fx > -1.0f) {
                const float fy = fys[i];
                /* tr_post_reproject's taps, its world points read from pq. */
                ix = fx < 0.0f ? -1 : (int)fx;
                iy = fy < 0.0f ? -1 : (int)fy;
                const float ax = fx - (float)ix, ay = fy - (float)iy;
                const tr_vec3 pp = v3(pt[0][i], pt[1][i], pt[2][i]);
                const tr_vec3 n = v3(g->normal[3 * i], g->normal[3 * i + 1], g->normal[3 * i + 2]);
                for (int k = 0; k < 4; ++k) {
                    const int tx = ix + (k & 1), ty = iy + (k >> 1);
                    if (tx < 0 || ty < 0 || tx >= w || ty >= h) {
                        continue;
                    }
                    const int j = ty * w + tx;
                    if (!(r->hist_depth[j] > 0.0f)) {
                        continue;
                    }
                    const tr_vec3 pn = v3(r->hist_normal[3 * j], r->hist_normal[3 * j + 1],
                                          r->hist_normal[3 * j + 2]);
                    const tr_vec3 q = v3(pq[0][j], pq[1][j], pq[2][j]);
                    if (!tr_reproject_consistent(g->prim[i], pp, n, dists[i], r->hist_prim[j], q,
                                                 pn)) {
                        continue;
                    }
                    const float bw = ((k & 1) ? ax : 1.0f - ax) * ((k >> 1) ? ay : 1.0f - ay);
                    wt[k] = bw;
                    total += bw;
                }
            }
            if (total > 0.05f) {
                const uint32_t id = g->prim[i];
                const tr_vec3 m = motion && id < motion_count ? motion[id] : v3s(0.0f);
                float cap = tr_post_max_len(m, p->max_len, p->max_len_moving);
                if (r->len_cap) {
                    cap = tr_fminf(cap, r->len_cap[i]); /* the shading changed here */
                }
                tr_post_temporal_blend(cr, cg, cb, total, wt, ix, iy, w, pcol, pmom, plen,
                                       p->alpha_min, cap, hc + 3 * i, hm + 2 * i, hl + i);
                if (na && r->have_albedo) {
                    tr_post_albedo_blend(g->albedo + 3 * i, total, wt, ix, iy, w,
                                         r->hist_albedo[r->cur],
                                         tr_fmaxf(1.0f / hl[i], p->albedo_alpha), na + 3 * i);
                } else if (na) {
                    memcpy(na + 3 * i, g->albedo + 3 * i, 3 * sizeof *na);
                }
            } else {
                if (na) {
                    memcpy(na + 3 * i, g->albedo + 3 * i, 3 * sizeof *na);
                }
                const float l = tr_post_luminance(cr, cg, cb);
                hc[3 * i] = cr;
                hc[3 * i + 1] = cg;
                hc[3 * i + 2] = cb;
                hm[2 * i] = l;
                hm[2 * i + 1] = l * l;
                hl[i] = 1.0f;
            }
        }
    }
}

/* The direct part's temporal stage when SVGF filters direct and indirect apart
 * (tr_recon_params.svgf_split, opt-in): r->illum_d reprojected with the same taps as
 * the sum's (the per-pixel operator; the lengths it writes equal the sum's) into the
 * direct histories of slot `next`, or a fresh history when hist is 0. */
static void direct_temporal(tr_recon *r, const tr_gbuffer *g, const tr_camera *cam,
                            const tr_camera *pc, const tr_vec3 *motion, uint32_t motion_count,
                            int hist, int prev, int next, const tr_recon_params *p, int threads) {
    const int w = (int)g->width, h = (int)g->height;
    float *hd = r->hist_direct[next], *hdm = r->hist_dmoments[next], *hl = r->hist_len[next];
    const float *plen = r->hist_len[prev];
#pragma omp parallel for num_threads(threads) schedule(static)
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            const size_t i = (size_t)y * w + x;
            if (hist) {
                const uint32_t id = g->prim[i];
                const tr_vec3 m = motion && id < motion_count ? motion[id] : v3s(0.0f);
                tr_post_temporal_pixel_moving(
                    cam, pc, (uint32_t)x, (uint32_t)y, m, r->illum_d, g->normal, g->depth, g->prim,
                    r->hist_direct[prev], r->hist_dmoments[prev], plen, r->hist_depth,
                    r->hist_normal, r->hist_prim, p->alpha_min,
                    r->len_cap
                        ? tr_fminf(tr_post_max_len(m, p->max_len, p->max_len_moving), r->len_cap[i])
                        : tr_post_max_len(m, p->max_len, p->max_len_moving),
                    hd + 3 * i, hdm + 2 * i, hl + i);
            } else {
                const float ld = tr_post_luminance(r->illum_d[3 * i], r->illum_d[3 * i + 1],
                                                   r->illum_d[3 * i + 2]);
                memcpy(hd + 3 * i, r->illum_d + 3 * i, 3 * sizeof *hd);
                hdm[2 * i] = ld;
                hdm[2 * i + 1] = ld * ld;
            }
        }
    }
}

/* Diffuse and specular apart (tr_recon_params.svgf_specular): this frame's specular albedo
 * (F0 A + B from the DFG table, dfg.h, at the pixel's mean F0 and alpha and the cosine
 * between its normal and its ray; 0 where the surface has no specular lobe) into
 * r->spec_alb, its specular light over it into r->illum_s, and the rest of its colour, the
 * diffuse light, into r->diffuse. A pixel whose passes primary surface replacement took
 * through a refraction or a curved mirror (TR_PRIM_PSR_CURVED) keeps all its light in the
 * diffuse part: the DFG lookup and the virtual motion both take the camera's ray, which
 * after a refraction is not the ray that reached the replaced surface, and split there
 * the glass sphere of scenes/window-room.json filled with bright speckles (measured:
 * docs/realtime.md, "Diffuse and specular apart"). */
static void spec_prepare(tr_recon *r, const tr_gbuffer *g, const tr_camera *cam, int threads) {
    const float *dfg = tr_post_dfg_table();
    const int w = (int)g->width, h = (int)g->height;
#pragma omp parallel for num_threads(threads) schedule(static)
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            const size_t i = (size_t)y * w + x;
            const tr_vec3 n = v3(g->normal[3 * i], g->normal[3 * i + 1], g->normal[3 * i + 2]);
            tr_post_spec_split_pixel(cam, (uint32_t)x, (uint32_t)y, n, g->prim[i],
                                     g->specular + 8 * i, dfg, g->color + 3 * i,
                                     r->spec_alb + 3 * i, r->illum_s + 3 * i, r->diffuse + 3 * i);
        }
    }
}

/* The specular part's temporal stage (svgf_specular): r->illum_s reprojected by virtual
 * motion (tr_post_reproject_virtual, the reflection's distance weighed by
 * tr_post_spec_virtual) with a history cap from the roughness (tr_post_spec_max_len) into
 * the specular histories of slot `next`, or a fresh history when hist is 0. */
static void spec_temporal(tr_recon *r, const tr_gbuffer *g, const tr_camera *cam,
                          const tr_camera *pc, const tr_vec3 *motion, uint32_t motion_count,
                          int hist, int prev, int next, const tr_recon_params *p, int threads) {
    const int w = (int)g->width, h = (int)g->height;
    float *hs = r->hist_spec[next], *hsm = r->hist_smoments[next], *hsl = r->hist_slen[next];
#pragma omp parallel for num_threads(threads) schedule(static)
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            const size_t i = (size_t)y * w + x;
            const uint32_t id = g->prim[i];
            const tr_vec3 m = motion && id < motion_count ? motion[id] : v3s(0.0f);
            const tr_vec3 n = v3(g->normal[3 * i], g->normal[3 * i + 1], g->normal[3 * i + 2]);
            float cap = tr_post_max_len(m, p->max_len, p->max_len_moving);
            if (r->len_cap) {
                cap = tr_fminf(cap, r->len_cap[i]);
            }
            tr_post_spec_temporal_pixel(
                cam, pc, (uint32_t)x, (uint32_t)y, w, r->illum_s + 3 * i, n, g->depth[i], id, m,
                g->specular[8 * i + 6], g->specular[8 * i + 7], hist, r->hist_spec[prev],
                r->hist_smoments[prev], r->hist_slen[prev], r->hist_depth, r->hist_normal,
                r->hist_prim, p->alpha_min, cap, hs + 3 * i, hsm + 2 * i, hsl + i);
        }
    }
}

/* The temporal stage of tr_recon_frame (r->illum holds this frame's illumination): the
 * history of slot `prev` reprojected and blended into hc, hm, hl; this frame's points
 * into slot `next`. */
static void temporal_stage(tr_recon *r, const tr_gbuffer *g, const tr_camera *cam,
                           const tr_vec3 *motion, uint32_t motion_count, int split, int prev,
                           int next, const tr_recon_params *p, int threads, float *hc, float *hm,
                           float *hl) {
    const int h = (int)g->height;
    const size_t n = (size_t)g->width * g->height;
    float *const tp = r->temporal;
    float *const pt[3] = {tp + (size_t)(3 * next) * n, tp + (size_t)(3 * next + 1) * n,
                          tp + (size_t)(3 * next + 2) * n};
    const float *const pq[3] = {tp + (size_t)(3 * prev) * n, tp + (size_t)(3 * prev + 1) * n,
                                tp + (size_t)(3 * prev + 2) * n};
    float *fx = tp + (size_t)TP_FX * n, *fy = tp + (size_t)TP_FY * n;
    float *dist = tp + (size_t)TP_DIST * n;
    /* A history kept with the other split (direct and indirect apart or not) starts over. */
    const int hist = r->have_history && r->hist_split == split;
    const tr_camera pc = r->prev_cam;
    /* With moving primitives (view --animate) each pixel's point is followed back by its
     * primitive's motion before it is projected and tested, into scratch planes (the
     * spatial filters' workspace, unused until they run); pt keeps the points themselves
     * for the next frame. */
    const int moving = hist && motion;
    float *const pm[3] = {r->soa, r->soa + n, r->soa + 2 * n};
    const float *const proj[3] = {moving ? pm[0] : pt[0], moving ? pm[1] : pt[1],
                                  moving ? pm[2] : pt[2]};
#pragma omp parallel for num_threads(threads) schedule(static)
    for (int y = 0; y < h; ++y) {
        temporal_points_rows(cam, g->depth, pt, y, y + 1);
        if (moving) {
            temporal_moved_rows((const float *const *)pt, g->prim, motion, motion_count, pm,
                                (int)g->width, y, y + 1);
        }
        if (hist) {
            temporal_project_rows(&pc, (int)g->width, g->depth, proj[0], proj[1], proj[2], fx, fy,
                                  dist, y, y + 1);
        }
    }
    const float *pcol = r->hist_color[prev], *pmom = r->hist_moments[prev],
                *plen = r->hist_len[prev];
#pragma omp parallel for num_threads(threads) schedule(static)
    for (int y = 0; y < h; ++y) {
        temporal_rows(r, g, proj, pq, hist ? fx : NULL, fy, dist, moving ? motion : NULL,
                      motion_count, pcol, pmom, plen, p, hc, hm, hl, y, y + 1);
    }
    if (split) {
        direct_temporal(r, g, cam, &pc, hist ? motion : NULL, motion_count, hist, prev, next, p,
                        threads);
    }
    r->hist_split = split;
}

/* SVGF on one illumination history h (moments hm, lengths hl): the variance, the
 * iterations (the first one's output fed back into h), remodulated into out, or added to
 * it when add. prep_guides must have run. */
static void svgf_part(const tr_gbuffer *g, const post_ws *ws, float *h, const float *hm,
                      const float *hl, const tr_recon_params *p, float *out, int add, int threads) {
    const long n = (long)ws->w * ws->h;
    float *c3[3];
    planes_of(ws, WS_CA, c3);
    to_planes(g, h, c3, 0, threads);
    luminance_plane((const float *const *)c3, ws->p[WS_LA], n, threads);
    svgf_variance(ws, ws->p[WS_LA], hm, hl, ws->p[WS_VA], threads);
    planes_of(ws, svgf(ws, g->depth, p, p->svgf_feedback ? h : NULL, threads), c3);
    if (add) {
        add_from_planes(g, (const float *const *)c3, out, threads);
    } else {
        from_planes(g, (const float *const *)c3, out, 1, threads);
    }
}

/* Demodulated illumination `illum` split into its direct part (the direct pass over the
 * albedo, into direct) and the rest, the indirect part (left in illum). */
static void split_illum(const tr_gbuffer *g, float *illum, float *direct, int threads) {
    const long n = (long)g->width * g->height;
#pragma omp parallel for num_threads(threads) schedule(static)
    for (long i = 0; i < n; ++i) {
        for (int k = 0; k < 3; ++k) {
            const float d = g->direct[3 * i + k] / tr_post_demod_factor(g->albedo[3 * i + k]);
            direct[3 * i + k] = d;
            illum[3 * i + k] -= d;
        }
    }
}

/* The geometry this frame's history was seen with, for the next frame's tests. */
static void keep_geometry(tr_recon *r, const tr_gbuffer *g, const tr_camera *cam) {
    const size_t n = (size_t)g->width * g->height;
    memcpy(r->hist_depth, g->depth, n * sizeof *r->hist_depth);
    memcpy(r->hist_normal, g->normal, 3 * n * sizeof *r->hist_normal);
    memcpy(r->hist_prim, g->prim, n * sizeof *r->hist_prim);
    r->prev_cam = *cam;
    r->have_history = 1;
}

/* The caller stopped the spatial stage (tr_recon.cancel): out is left unfinished, and the
 * history, whose temporal stage ran, is kept with this frame's geometry, so that the next
 * frame reprojects it as if this one had been shown (only TAA's history starts over). */
static int spatial_cancelled(tr_recon *r, const tr_gbuffer *g, const tr_camera *cam, double t1,
                             tr_error *err) {
    keep_geometry(r, g, cam);
    r->ms_spatial = (tr_time_now() - t1) * 1e3;
    return tr_error_set(err, TR_STATUS_CANCELLED, "reconstruction cancelled");
}

int tr_recon_frame(tr_recon *r, const tr_gbuffer *g, const tr_camera *cam, int method,
                   const tr_recon_params *p, int threads, float *out, tr_error *err) {
    return tr_recon_frame_moving(r, g, cam, NULL, 0, method, p, threads, out, err);
}

/* A frame with the emission pass: its colour (and direct part) without the first hit's
 * emission into r's scratch, as a gbuffer `ge` that shares g's other passes. */
static void take_out_emission(tr_recon *r, const tr_gbuffer *g, int split, tr_gbuffer *ge,
                              int threads) {
    *ge = *g;
    ge->color = r->reflected;
    ge->direct = r->reflected_d;
    const long n = 3L * g->width * g->height;
#pragma omp parallel for num_threads(threads) schedule(static)
    for (long i = 0; i < n; ++i) {
        r->reflected[i] = g->color[i] - g->emission[i];
        if (split) {
            r->reflected_d[i] = g->direct[i] - g->emission[i];
        }
    }
}

/* Adds back the emission take_out_emission took out: the estimate resolved over each
 * pixel's area where the caller made one (tr_resolve_emission), else the frame's own. */
static void put_back_emission(const tr_gbuffer *g, float *out, int threads) {
    const float *e = g->has_resolved ? g->emission_resolved : g->emission;
    const long n = 3L * g->width * g->height;
#pragma omp parallel for num_threads(threads) schedule(static)
    for (long i = 0; i < n; ++i) {
        out[i] += e[i];
    }
}

int tr_recon_frame_moving(tr_recon *r, const tr_gbuffer *frame, const tr_camera *cam,
                          const tr_vec3 *motion, uint32_t motion_count, int method,
                          const tr_recon_params *p, int threads, float *out, tr_error *err) {
    const tr_gbuffer *g = frame;
    const tr_recon_params resolved = tr_recon_params_for(p, method);
    p = &resolved;
    if (check_frame(r->width, r->height, g, err) != TR_OK) {
        return TR_ERR;
    }
    if (!tr_recon_name(method)) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT, "reconstruction: unknown method %d",
                            method);
    }
    if (cam->screen_width != g->width || cam->screen_height != g->height) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "reconstruction: a %ux%u camera for a %ux%u frame", cam->screen_width,
                            cam->screen_height, g->width, g->height);
    }
    threads = nthreads(threads);
    const int w = (int)g->width, h = (int)g->height;
    const size_t n = (size_t)w * h;
    r->ms_temporal = r->ms_spatial = 0.0;
    if (method == TR_RECON_OFF) {
        memcpy(out, g->color, 3 * n * sizeof *out);
        r->have_history = 0;
        return TR_OK;
    }
    const double t0 = tr_time_now();
    /* SVGF apart: direct and indirect illumination each get a history (split_illum). */
    /* SVGF with the diffuse and the specular light apart (spec_prepare), before the split
     * into direct and indirect light, which it replaces. */
    const int spec = method == TR_RECON_SVGF && p->svgf_specular && g->has_specular;
    const int split = method == TR_RECON_SVGF && p->svgf_split && g->has_direct && !spec;
    /* With the emission pass the filters see only reflected light: an emitter's edge is
     * not spread onto its neighbours, and the emission comes back after them. */
    tr_gbuffer reflected;
    if (frame->has_emission) {
        take_out_emission(r, frame, split, &reflected, threads);
        g = &reflected;
    }
    tr_gbuffer diffuse;
    if (spec) {
        spec_prepare(r, g, cam, threads);
        diffuse = *g;
        diffuse.color = r->diffuse;
        g = &diffuse;
    }
    if (r->hist_spec_split != spec) {
        r->have_history = 0; /* a history kept with the other split starts over */
    }
    demodulate(g, g->color, r->illum, threads);
    if (split) {
        split_illum(g, r->illum, r->illum_d, threads);
    }
    const int prev = r->cur, next = 1 - r->cur;
    float *hc = r->hist_color[next], *hm = r->hist_moments[next], *hl = r->hist_len[next];
    temporal_stage(r, g, cam, motion, motion_count, split, prev, next, p, threads, hc, hm, hl);
    if (spec) {
        const tr_camera pc = r->prev_cam;
        spec_temporal(r, g, cam, &pc, motion, motion_count, r->have_history, prev, next, p,
                      threads);
    }
    r->hist_spec_split = spec;
    r->cur = next;
    r->have_albedo = p->albedo_alpha > 0.0f;
    const double t1 = tr_time_now();
    r->ms_temporal = (t1 - t0) * 1e3;

    const int had_taa = r->have_taa && r->have_history;
    r->have_taa = 0;
    if (method == TR_RECON_ACCUMULATE) {
        remodulate(g, hc, out, threads);
        if (frame->has_emission) {
            put_back_emission(frame, out, threads);
        }
        keep_geometry(r, g, cam);
        r->ms_spatial = (tr_time_now() - t1) * 1e3;
        return TR_OK;
    }
    post_ws ws;
    ws_bind(&ws, r->soa, w, h);
    ws.cancel = r->cancel;
    ws.cancel_user = r->cancel_user;
    float *c3[3];
    planes_of(&ws, WS_CA, c3);
    if (method == TR_RECON_BILATERAL) {
        to_planes(g, hc, c3, -1, threads);
        bilateral_planes(&ws, (const float *const *)c3, out, p, threads);
    } else if (method == TR_RECON_ATROUS) {
        to_planes(g, hc, c3, 0, threads);
        prep_guides(g, &ws, p, 0, threads);
        planes_of(&ws, atrous(&ws, g->depth, p, threads), c3);
        if (ws_cancelled(&ws)) {
            return spatial_cancelled(r, g, cam, t1, err);
        }
        from_planes(g, (const float *const *)c3, out, 1, threads);
    } else {
        prep_guides(g, &ws, p, 1, threads);
        /* The sum's (or the diffuse part's) remodulation by the albedo history. */
        tr_gbuffer gav = *g;
        if (p->albedo_alpha > 0.0f) {
            gav.albedo = r->hist_albedo[r->cur];
        }
        const tr_gbuffer *ga = &gav;
        /* With TAA the remodulated output goes to r->illum (free by now) first. */
        float *res = p->svgf_taa_alpha > 0.0f ? r->illum : out;
        if (spec) {
            /* Each part steered by its own variance, remodulated by its own albedo. */
            svgf_part(ga, &ws, hc, hm, hl, p, res, 0, threads);
            tr_gbuffer gs = *g;
            gs.albedo = r->spec_alb;
            svgf_part(&gs, &ws, r->hist_spec[next], r->hist_smoments[next], r->hist_slen[next], p,
                      res, 1, threads);
        } else if (split) {
            /* Schied et al. filter direct and indirect illumination apart, each steered by
             * its own variance, and add them after remodulation. */
            svgf_part(ga, &ws, r->hist_direct[next], r->hist_dmoments[next], hl, p, res, 0,
                      threads);
            svgf_part(ga, &ws, hc, hm, hl, p, res, 1, threads);
        } else {
            svgf_part(ga, &ws, hc, hm, hl, p, res, 0, threads);
        }
        if (ws_cancelled(&ws)) {
            return spatial_cancelled(r, g, cam, t1, err);
        }
        if (p->svgf_taa_alpha > 0.0f) {
            /* Schied et al.'s last stage: temporal antialiasing of the remodulated
             * output against its own reprojected history. */
            const tr_camera pc = r->prev_cam;
#pragma omp parallel for num_threads(threads) schedule(static)
            for (int y = 0; y < h; ++y) {
                for (int x = 0; x < w; ++x) {
                    tr_post_taa_pixel(cam, &pc, x, y, r->illum, g->normal, g->depth, g->prim,
                                      had_taa ? r->taa : NULL, r->hist_depth, r->hist_normal,
                                      r->hist_prim, p->svgf_taa_alpha,
                                      out + 3 * ((size_t)y * w + x));
                }
            }
            memcpy(r->taa, out, 3 * n * sizeof *out);
            r->have_taa = 1;
        }
    }
    if (frame->has_emission) {
        put_back_emission(frame, out, threads);
    }
    keep_geometry(r, g, cam);
    r->ms_spatial = (tr_time_now() - t1) * 1e3;
    return TR_OK;
}
