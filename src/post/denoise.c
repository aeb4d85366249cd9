/* denoise.c - the offline denoiser (tr_denoise_film, include/trac0r/post.h): a finished
 * film's radiance cleaned with the help of its feature passes, in three steps.
 *
 * 1. Outliers. A firefly is a pixel whose mean rests on one or two improbable samples.
 *    The film's sums of squares (TR_PASS_VARIANCE) say how much of a pixel's value its own
 *    samples can vouch for: a pixel that stands out of its 3x3 neighbourhood (above the
 *    second brightest neighbour plus three times the neighbourhood's typical standard
 *    error) loses the part of its excess that is within three of its own standard errors.
 *    A single-sample spike has a standard error as large as its mean, so it is brought back
 *    to its neighbourhood; a converged highlight has a small one and keeps its value, and
 *    as samples accumulate less is taken (the estimator stays consistent). This is the
 *    per-pixel form of the re-weighting of Zirr, Hanika and Dachsbacher 2018,
 *    "Re-weighting Firefly Samples for Improved Finite-Sample Monte Carlo Estimates"
 *    (Computer Graphics Forum 37(6)), which judges a sample by how probable its magnitude
 *    is given the samples around it; done before the filter so that no spike is spread.
 *
 * 2. Demodulation. The first hit's emission (TR_PASS_EMISSION, when kept) is taken out and
 *    added back at the end, unfiltered; the rest is divided by the albedo, so that texture
 *    and material edges come back sharp when the filtered illumination is multiplied by
 *    each pixel's own albedo (as in Zwicker et al. 2015 and SVGF).
 *
 * 3. First-order regression. Each pixel's illumination is the value at that pixel of a
 *    least-squares fit, over the (2r+1)^2 window around it, of an affine function of the
 *    features: shading normal, depth and screen position (Bitterli et al. 2016,
 *    "Nonlinearly Weighted First-Order Regression for Denoising Monte Carlo Renderings",
 *    Computer Graphics Forum 35(4), section 4; their regression with uniform weights, the
 *    local linear model of the guided filter, He et al. 2013). A depth or normal edge
 *    inside the window is a step in a regressor, so the fit follows it; a smooth gradient
 *    of light is the screen-position term. The window sums come from running column and
 *    row sums in double precision, so the cost per pixel does not grow with the window.
 *    A ridge term (relative and absolute) keeps features that are constant in the window
 *    out of the fit.
 *
 *    Each pixel's window fit is one estimate; the regression is run at window radii from
 *    the small one doubling up to the large one (1, 2, 4, 6 by default), and the pixel's
 *    own value is one more candidate. Each pixel takes the candidate of least estimated
 *    squared error, Stein's unbiased risk estimate (SURE) |f - y|^2 - var + 2 var L for a
 *    fit f of the noisy values y whose leverage at the pixel is L (the diagonal of the
 *    fit's hat matrix, exact per pixel from the window's feature covariance), smoothed
 *    over 5x5 pixels; var is the variance of the pixel's mean from the film's sums of
 *    squares. This is the per-pixel selection among candidate filters of Li, Wu and Chuang
 *    2012 ("SURE-based Optimization for Adaptive Sampling and Reconstruction", ACM TOG
 *    31(6)) that NFOR also makes. The pixel's own value has risk var: where its samples
 *    have converged (a small lamp's neighbourhood at 64 samples, a shadow edge no feature
 *    explains) a fit must agree with them to be taken, so the filter does not make a
 *    converged region worse.
 *
 * Every pixel's value is computed from read-only inputs in a fixed order: rows are taken in
 * strips whose boundaries do not depend on the thread count, so neither does the result. */
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "trac0r/film.h"
#include "trac0r/post.h"
#include "trac0r/render.h"

/* Regressors: normal x, y, z, depth, screen x, y. (The albedo is divided out before the
 * fit; as a regressor it only added noise on textures.) */
#define DN_F 6
/* Per-pixel sums: 1, the features, the three targets, the features' products with each
 * other (upper triangle) and with the targets. */
#define DN_FF (DN_F * (DN_F + 1) / 2)
#define DN_S (1 + DN_F + 3 + DN_FF + 3 * DN_F)
/* The scale of the film's variance in the risk estimate: 1 is Stein's; measured on the
 * shipped scenes against 0.7 and 1.5 (docs/log/2026-denoise.md): below 1 helps scenes whose
 * stratified samples make the sums of squares overstate the noise (many-lights), above 1
 * the glass box, and 1 keeps every scene at or above the a-trous filter. */
#define DN_SELECT 1.0f
/* Rows per strip: each strip starts its running sums afresh. */
#define DN_STRIP 48

tr_denoise_params tr_denoise_params_default(void) {
    tr_denoise_params p;
    memset(&p, 0, sizeof p);
    p.radius = 6;
    p.radius_small = 1;
    p.firefly_k = 3.0f;
    return p;
}

static float lum(const float *c) {
    return 0.2126f * c[0] + 0.7152f * c[1] + 0.0722f * c[2];
}

/* The planar inputs of the regression. */
typedef struct dn_img {
    int w, h;
    float *feat[DN_F]; /* the regressors, scaled to about unit range */
    float *y[3];       /* demodulated illumination */
    float *var;        /* variance of the mean of y's luminance (0 without the pass) */
} dn_img;

static void sort8(float *v) {
    for (int i = 1; i < 8; ++i) {
        const float x = v[i];
        int j = i - 1;
        while (j >= 0 && v[j] > x) {
            v[j + 1] = v[j];
            --j;
        }
        v[j + 1] = x;
    }
}

/* Step 1: the firefly re-weighting, in place on col (3 floats per pixel), from the
 * luminance lm and its standard error se. */
static long fireflies(int w, int h, float *col, const float *lm, const float *se, float k,
                      int threads) {
    long changed = 0;
#pragma omp parallel for num_threads(threads) schedule(static) reduction(+ : changed)
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            const size_t i = (size_t)y * w + x;
            float nl[8], ns[8];
            int n = 0;
            for (int dy = -1; dy <= 1; ++dy) {
                for (int dx = -1; dx <= 1; ++dx) {
                    const int xx = x + dx, yy = y + dy;
                    if ((dx || dy) && xx >= 0 && yy >= 0 && xx < w && yy < h) {
                        nl[n] = lm[(size_t)yy * w + xx];
                        ns[n] = se[(size_t)yy * w + xx];
                        ++n;
                    }
                }
            }
            /* Border pixels: fill with the pixel's own (they cannot raise the bound). */
            for (int m = n; m < 8; ++m) {
                nl[m] = n ? nl[0] : lm[i];
                ns[m] = n ? ns[0] : se[i];
            }
            sort8(nl);
            sort8(ns);
            const float bound = nl[6] + k * 0.5f * (ns[3] + ns[4]);
            const float l = lm[i];
            if (!(l > bound)) {
                continue;
            }
            const float take = fminf(l - bound, k * se[i]);
            if (take > 0.0f) {
                const float s = (l - take) / l;
                col[3 * i] *= s;
                col[3 * i + 1] *= s;
                col[3 * i + 2] *= s;
                ++changed;
            }
        }
    }
    return changed;
}

/* Solves (A) x = b for the symmetric positive definite n x n A (row-major, overwritten by
 * its Cholesky factor) and three right-hand sides b[3][n] (overwritten by x). Returns 0
 * when A is not positive definite. */
static int cholesky_solve(double *a, int n, double b[3][DN_F]) {
    for (int j = 0; j < n; ++j) {
        double d = a[j * n + j];
        for (int k = 0; k < j; ++k) {
            d -= a[j * n + k] * a[j * n + k];
        }
        if (!(d > 0.0)) {
            return 0;
        }
        d = sqrt(d);
        a[j * n + j] = d;
        for (int i = j + 1; i < n; ++i) {
            double s = a[i * n + j];
            for (int k = 0; k < j; ++k) {
                s -= a[i * n + k] * a[j * n + k];
            }
            a[i * n + j] = s / d;
        }
    }
    for (int c = 0; c < 3; ++c) {
        double *x = b[c];
        for (int i = 0; i < n; ++i) {
            double s = x[i];
            for (int k = 0; k < i; ++k) {
                s -= a[i * n + k] * x[k];
            }
            x[i] = s / a[i * n + i];
        }
        for (int i = n - 1; i >= 0; --i) {
            double s = x[i];
            for (int k = i + 1; k < n; ++k) {
                s -= a[k * n + i] * x[k];
            }
            x[i] = s / a[i * n + i];
        }
    }
    return 1;
}

/* The per-pixel products (DN_S of them) of pixel i into s. */
static void products(const dn_img *im, size_t i, double *s) {
    double f[DN_F], t[3];
    for (int j = 0; j < DN_F; ++j) {
        f[j] = im->feat[j][i];
    }
    for (int c = 0; c < 3; ++c) {
        t[c] = im->y[c][i];
    }
    int k = 0;
    s[k++] = 1.0;
    for (int j = 0; j < DN_F; ++j) {
        s[k++] = f[j];
    }
    for (int c = 0; c < 3; ++c) {
        s[k++] = t[c];
    }
    for (int a = 0; a < DN_F; ++a) {
        for (int b = a; b < DN_F; ++b) {
            s[k++] = f[a] * f[b];
        }
    }
    for (int c = 0; c < 3; ++c) {
        for (int j = 0; j < DN_F; ++j) {
            s[k++] = f[j] * t[c];
        }
    }
}

/* The fit of window sums s at pixel i into out[3]; its leverage (the weight of a pixel's
 * own value in the fit, for the error estimate) into *lev. */
static void fit(const dn_img *im, size_t i, const double *s, float out[3], float *lev) {
    const double n = s[0];
    const double inv = 1.0 / n;
    double mf[DN_F], my[3], a[DN_F * DN_F], b[3][DN_F], d[DN_F];
    for (int j = 0; j < DN_F; ++j) {
        mf[j] = s[1 + j] * inv;
        d[j] = im->feat[j][i] - mf[j];
    }
    for (int c = 0; c < 3; ++c) {
        my[c] = s[1 + DN_F + c] * inv;
    }
    const double *ff = s + 1 + DN_F + 3;
    const double *fy = ff + DN_FF;
    int k = 0;
    for (int p = 0; p < DN_F; ++p) {
        for (int q = p; q < DN_F; ++q) {
            const double cov = ff[k++] * inv - mf[p] * mf[q];
            a[p * DN_F + q] = cov;
            a[q * DN_F + p] = cov;
        }
    }
    /* Ridge: 1e-3 of each feature's own spread, and an absolute floor below which a
     * feature counts as constant (the features are scaled to about unit range). */
    for (int p = 0; p < DN_F; ++p) {
        const double v = a[p * DN_F + p];
        a[p * DN_F + p] = (v > 0.0 ? v : 0.0) * 1.001 + 1e-4;
    }
    for (int c = 0; c < 3; ++c) {
        for (int j = 0; j < DN_F; ++j) {
            b[c][j] = fy[c * DN_F + j] * inv - mf[j] * my[c];
        }
    }
    if (!cholesky_solve(a, DN_F, b)) {
        for (int c = 0; c < 3; ++c) {
            out[c] = (float)my[c];
        }
        *lev = (float)inv;
        return;
    }
    /* The pixel's leverage, the weight of its own value in its fit (the diagonal of the
     * hat matrix): (1 + d' C^-1 d) / n for the centred features d and their covariance C,
     * from the Cholesky factor L (C = L L') as (1 + |L^-1 d|^2) / n. */
    double z[DN_F], q = 0.0;
    for (int r = 0; r < DN_F; ++r) {
        double t = d[r];
        for (int k2 = 0; k2 < r; ++k2) {
            t -= a[r * DN_F + k2] * z[k2];
        }
        z[r] = t / a[r * DN_F + r];
        q += z[r] * z[r];
    }
    *lev = (float)fmin((1.0 + q) * inv, 1.0);
    for (int c = 0; c < 3; ++c) {
        double v = my[c];
        for (int j = 0; j < DN_F; ++j) {
            v += b[c][j] * d[j];
        }
        out[c] = (float)v;
    }
}

/* Step 3 at window radius r: the fit of every pixel into out (3 planes) and its leverage
 * into lev (may be NULL). */
static int regress(const dn_img *im, int r, float *const out[3], float *lev, int threads) {
    const int w = im->w, h = im->h;
    const int strips = (h + DN_STRIP - 1) / DN_STRIP;
    int failed = 0;
#pragma omp parallel num_threads(threads) reduction(| : failed)
    {
        double *col = malloc(sizeof(double) * DN_S * (size_t)w);
        double *prod = malloc(sizeof(double) * DN_S);
        double *win = malloc(sizeof(double) * DN_S);
        if (!col || !prod || !win) {
            failed = 1;
        }
#pragma omp for schedule(dynamic, 1)
        for (int st = 0; st < strips; ++st) {
            if (failed) {
                continue;
            }
            const int y0 = st * DN_STRIP;
            const int y1 = y0 + DN_STRIP < h ? y0 + DN_STRIP : h;
            /* Column sums over rows max(0, y0 - r) .. min(h - 1, y0 + r). */
            memset(col, 0, sizeof(double) * DN_S * (size_t)w);
            const int ra = y0 - r > 0 ? y0 - r : 0;
            const int rb = y0 + r < h - 1 ? y0 + r : h - 1;
            for (int yy = ra; yy <= rb; ++yy) {
                for (int x = 0; x < w; ++x) {
                    products(im, (size_t)yy * w + x, prod);
                    double *c = col + (size_t)x * DN_S;
                    for (int k = 0; k < DN_S; ++k) {
                        c[k] += prod[k];
                    }
                }
            }
            for (int y = y0; y < y1; ++y) {
                if (y > y0) {
                    const int add = y + r, sub = y - r - 1;
                    for (int x = 0; x < w; ++x) {
                        double *c = col + (size_t)x * DN_S;
                        if (add < h) {
                            products(im, (size_t)add * w + x, prod);
                            for (int k = 0; k < DN_S; ++k) {
                                c[k] += prod[k];
                            }
                        }
                        if (sub >= 0) {
                            products(im, (size_t)sub * w + x, prod);
                            for (int k = 0; k < DN_S; ++k) {
                                c[k] -= prod[k];
                            }
                        }
                    }
                }
                memset(win, 0, sizeof(double) * DN_S);
                for (int x = 0; x <= r && x < w; ++x) {
                    const double *c = col + (size_t)x * DN_S;
                    for (int k = 0; k < DN_S; ++k) {
                        win[k] += c[k];
                    }
                }
                for (int x = 0; x < w; ++x) {
                    if (x > 0) {
                        const int add = x + r, sub = x - r - 1;
                        if (add < w) {
                            const double *c = col + (size_t)add * DN_S;
                            for (int k = 0; k < DN_S; ++k) {
                                win[k] += c[k];
                            }
                        }
                        if (sub >= 0) {
                            const double *c = col + (size_t)sub * DN_S;
                            for (int k = 0; k < DN_S; ++k) {
                                win[k] -= c[k];
                            }
                        }
                    }
                    const size_t i = (size_t)y * w + x;
                    float o[3], l = 0.0f;
                    fit(im, i, win, o, &l);
                    out[0][i] = o[0];
                    out[1][i] = o[1];
                    out[2][i] = o[2];
                    if (lev) {
                        lev[i] = l;
                    }
                }
            }
        }
        free(col);
        free(prod);
        free(win);
    }
    return failed ? TR_ERR : TR_OK;
}

/* A (2*rad+1)^2 box mean of plane a into b, clipped at the borders. */
static void box_mean(int w, int h, const float *a, float *b, int rad, int threads) {
#pragma omp parallel for num_threads(threads) schedule(static)
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            double s = 0.0;
            int n = 0;
            for (int yy = y - rad; yy <= y + rad; ++yy) {
                for (int xx = x - rad; xx <= x + rad; ++xx) {
                    if (xx >= 0 && yy >= 0 && xx < w && yy < h) {
                        s += a[(size_t)yy * w + xx];
                        ++n;
                    }
                }
            }
            b[(size_t)y * w + x] = (float)(s / n);
        }
    }
}

int tr_denoise_film(const tr_film *film, const tr_denoise_params *params, int threads, float *out,
                    tr_error *err) {
    const uint32_t guides = TR_PASS_ALBEDO | TR_PASS_NORMAL | TR_PASS_DEPTH;
    if ((film->passes & guides) != guides) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "denoising needs the albedo, normal and depth passes");
    }
    const tr_denoise_params def = tr_denoise_params_default();
    tr_denoise_params p = params ? *params : def;
    p.radius = p.radius > 0 ? p.radius : def.radius;
    p.radius_small = p.radius_small > 0 ? p.radius_small : def.radius_small;
    p.firefly_k = p.firefly_k > 0.0f ? p.firefly_k : def.firefly_k;
    if (p.radius > 64 || p.radius_small > 64) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT, "denoise radius %d must be in 1..64",
                            p.radius > p.radius_small ? p.radius : p.radius_small);
    }
    threads = threads > 0 ? threads : omp_get_max_threads();
    const int w = (int)film->width, h = (int)film->height;
    const size_t n = (size_t)w * h;
    /* Planes: features, y (3), var, lum, se, the chosen value (3), a candidate fit (3),
     * its leverage, its risk, the risk smoothed, the chosen value's smoothed risk. */
    enum {
        P_Y = DN_F,
        P_VAR = DN_F + 3,
        P_LUM,
        P_SE,
        P_BEST,
        P_CUR = P_BEST + 3,
        P_LEV = P_CUR + 3,
        P_R,
        P_RS,
        P_RBEST,
        P_N
    };
    float *block = malloc(sizeof(float) * n * P_N);
    float *col = malloc(sizeof(float) * 3 * n);
    float *alb = malloc(sizeof(float) * 3 * n);
    float *emi = malloc(sizeof(float) * 3 * n);
    if (!block || !col || !alb || !emi) {
        free(block);
        free(col);
        free(alb);
        free(emi);
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory denoising %dx%d", w, h);
    }
    float *pl[P_N];
    for (int k = 0; k < P_N; ++k) {
        pl[k] = block + (size_t)k * n;
    }
    /* Means; the reflected part (radiance less the first hit's emission); its luminance and
     * standard error. */
    double dsum = 0.0;
    long dcount = 0;
    for (size_t i = 0; i < n; ++i) {
        const uint32_t c = film->count[i];
        const float inv = c ? 1.0f / (float)c : 0.0f;
        for (int k = 0; k < 3; ++k) {
            emi[3 * i + k] = film->emission ? film->emission[3 * i + k] * inv : 0.0f;
            col[3 * i + k] = film->sum[3 * i + k] * inv - emi[3 * i + k];
            alb[3 * i + k] = film->albedo[3 * i + k] * inv;
        }
        const float z = film->depth[i] * inv;
        if (z > 0.0f) {
            dsum += z;
            ++dcount;
        }
        pl[P_LUM][i] = lum(col + 3 * i);
        if (film->sq) {
            float s = 0.0f;
            s += 0.2126f * sqrtf(tr_film_variance(film, i, 0));
            s += 0.7152f * sqrtf(tr_film_variance(film, i, 1));
            s += 0.0722f * sqrtf(tr_film_variance(film, i, 2));
            pl[P_SE][i] = s;
        } else {
            pl[P_SE][i] = fmaxf(pl[P_LUM][i], 0.0f); /* no pass: a spike is not vouched for */
        }
    }
    fireflies(w, h, col, pl[P_LUM], pl[P_SE], p.firefly_k, threads);
    const float zscale = dcount ? (float)(dcount / dsum) : 1.0f;
    const float xscale = 1.0f / (float)(p.radius > 0 ? p.radius : 1);
#pragma omp parallel for num_threads(threads) schedule(static)
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            const size_t i = (size_t)y * w + x;
            const uint32_t c = film->count[i];
            const float inv = c ? 1.0f / (float)c : 0.0f;
            for (int k = 0; k < 3; ++k) {
                pl[k][i] = film->normal[3 * i + k] * inv;
                /* Demodulate where there is an albedo to divide by. */
                const float a = alb[3 * i + k];
                pl[P_Y + k][i] = a > 0.01f ? col[3 * i + k] / a : col[3 * i + k];
            }
            pl[3][i] = film->depth[i] * inv * zscale;
            pl[4][i] = (float)x * xscale;
            pl[5][i] = (float)y * xscale;
            /* The variance of the demodulated luminance. */
            const float la = lum(alb + 3 * i);
            const float se = pl[P_SE][i] / (la > 0.01f ? la : 1.0f);
            pl[P_VAR][i] = se * se;
        }
    }
    dn_img im;
    im.w = w;
    im.h = h;
    for (int j = 0; j < DN_F; ++j) {
        im.feat[j] = pl[j];
    }
    for (int k = 0; k < 3; ++k) {
        im.y[k] = pl[P_Y + k];
    }
    im.var = pl[P_VAR];
    /* The candidates: the pixel's own value, then the fits at the window radii from the
     * small one doubling up to the large one. Each pixel takes the candidate of least
     * estimated risk, Stein's unbiased risk estimate (Stein 1981; used to choose among
     * filters per pixel by Li, Wu and Chuang 2012 and by NFOR, Bitterli et al. 2016):
     * for a fit f linear in the noisy values y with leverage L at the pixel, the expected
     * squared error is |f - y|^2 - var + 2 var L, smoothed over a 5x5 window. The pixel's
     * own value (L = 1) has risk var: where the samples have converged no fit can win
     * unless it agrees with them, so a converged region is not made worse. */
    const float vs = DN_SELECT;
    int rc = TR_OK;
#pragma omp parallel for num_threads(threads) schedule(static)
    for (long i = 0; i < (long)n; ++i) {
        for (int k = 0; k < 3; ++k) {
            pl[P_BEST + k][i] = pl[P_Y + k][i];
        }
        pl[P_R][i] = vs * pl[P_VAR][i];
    }
    box_mean(w, h, pl[P_R], pl[P_RBEST], 2, threads);
    float *cur[3] = {pl[P_CUR], pl[P_CUR + 1], pl[P_CUR + 2]};
    for (int r = p.radius_small; rc == TR_OK; r = r * 2 < p.radius ? r * 2 : p.radius) {
        rc = regress(&im, r, cur, pl[P_LEV], threads);
        if (rc != TR_OK) {
            break;
        }
#pragma omp parallel for num_threads(threads) schedule(static)
        for (long i = 0; i < (long)n; ++i) {
            const float d = lum((float[3]){cur[0][i] - pl[P_Y][i], cur[1][i] - pl[P_Y + 1][i],
                                           cur[2][i] - pl[P_Y + 2][i]});
            const float v = vs * pl[P_VAR][i];
            pl[P_R][i] = d * d - v + 2.0f * v * pl[P_LEV][i];
        }
        box_mean(w, h, pl[P_R], pl[P_RS], 2, threads);
#pragma omp parallel for num_threads(threads) schedule(static)
        for (long i = 0; i < (long)n; ++i) {
            if (pl[P_RS][i] < pl[P_RBEST][i]) {
                pl[P_RBEST][i] = pl[P_RS][i];
                for (int k = 0; k < 3; ++k) {
                    pl[P_BEST + k][i] = cur[k][i];
                }
            }
        }
        if (r >= p.radius) {
            break;
        }
    }
    if (rc == TR_OK) {
#pragma omp parallel for num_threads(threads) schedule(static)
        for (long i = 0; i < (long)n; ++i) {
            for (int k = 0; k < 3; ++k) {
                const float v = pl[P_BEST + k][i];
                const float a = alb[3 * i + k];
                const float y = a > 0.01f ? v * a : v;
                out[3 * i + k] = fmaxf(y, 0.0f) + emi[3 * i + k];
            }
        }
    } else {
        tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory denoising %dx%d", w, h);
    }
    free(block);
    free(col);
    free(alb);
    free(emi);
    return rc;
}
