/* denoise.c - the offline denoiser (tr_denoise_film, include/trac0r/post.h): a finished
 * film's radiance cleaned with the help of its feature passes, in four steps.
 *
 * 1. Outliers, and their energy spread. A firefly is a pixel whose mean rests on one or two
 *    improbable samples. The film's sums of squares (TR_PASS_VARIANCE) say how much of a
 *    pixel's value its own samples can vouch for: a pixel that stands out of its 5x5
 *    neighbourhood (above the second brightest neighbour plus three times the
 *    neighbourhood's median standard error) gives up the part of its excess that is within
 *    three of its own standard errors. A single-sample spike has a standard error as large
 *    as its mean, so it is brought back to its neighbourhood; a converged highlight has a
 *    small one and keeps its value, and as samples accumulate less is taken. A pixel whose
 *    energy rests on two samples or fewer ((sum of the luminances)^2 / (sum of their
 *    squares) <= 2) is judged against its neighbours' median instead of the second
 *    brightest, so that the pixels of an undersampled caustic or glossy highlight, each
 *    with one bright sample and a few of them together, are taken too: left to the filters
 *    below, a few bright pixels become bright squares. What is taken is not dropped: it is
 *    spread, after the filters, over the pixels around that show the same surface (normal,
 *    depth, and the denoised luminance), with weights normalised per source so that the
 *    total energy is kept, over a window that holds DN_SPREAD_K outlier pixels and a
 *    Gaussian shaped by their second moments (see spread()). A sparse caustic becomes a
 *    smooth patch of the right energy instead of a few bright pixels, or none. This is an
 *    energy-preserving variant of the re-weighting of Zirr, Hanika and Dachsbacher 2018,
 *    "Re-weighting Firefly Samples for Improved Finite-Sample Monte Carlo Estimates"
 *    (Computer Graphics Forum 37(6)), which judges samples by how probable their magnitude
 *    is given the samples around them and re-weights the improbable ones; here the
 *    judgement is per pixel, from the sums the film keeps, so a render needs no extra
 *    buffers. The standard errors are the reflected part's: where the emission pass is
 *    kept, the squares of the samples that met an emitter are taken out. A pixel that met
 *    no surface loses its spike as before (there is no surface to spread it over).
 *
 * 2. Demodulation. The first hit's emission (TR_PASS_EMISSION, when kept) is taken out; the
 *    rest is divided by the albedo (held at 0.01 or above), so that texture and material
 *    edges come back sharp when the filtered illumination is multiplied by each pixel's own
 *    albedo (as in Zwicker et al. 2015 and SVGF).
 *
 * 3. Candidates for the illumination, and the choice among them.
 *    a. First-order regression. Each pixel's illumination is the value at that pixel of a
 *       least-squares fit, over the (2r+1)^2 window around it, of an affine function of
 *       the features: shading normal, depth and screen position (Bitterli et al. 2016,
 *       "Nonlinearly Weighted First-Order Regression for Denoising Monte Carlo Renderings",
 *       Computer Graphics Forum 35(4), section 4; their regression with uniform weights,
 *       the local linear model of the guided filter, He et al. 2013). A depth or normal
 *       edge inside the window is a step in a regressor, so the fit follows it; a smooth
 *       gradient of light is the screen-position term. The window sums come from running
 *       column and row sums in double precision, so the cost per pixel does not grow with
 *       the window. A ridge term (relative and absolute) keeps features that are constant
 *       in the window out of the fit. Run at radii from the small one doubling up to the
 *       large one (1, 2, 4 by default); the leverage L (the diagonal of the fit's hat
 *       matrix) is exact per pixel from the window's feature covariance.
 *    b. Edge-stopping filter. The levels of an a-trous transform (Dammertz et al. 2010: the
 *       5x5 B3 kernel at steps 1, 2, 4, 8) whose taps are weighted by the differences in
 *       normal and relative depth and, weakly, in luminance against the noise expected of
 *       it (SVGF's term, at 16 standard errors); each level's result is a candidate. Where
 *       a window straddles small facets (a model's silhouette, a thin bar) the regression's
 *       affine model does not hold and the weights keep the facets apart. Its leverage is
 *       approximated by the centre tap's normalised weight, multiplied over the levels,
 *       as Li, Wu and Chuang 2012 do for their cross-bilateral candidates; with a strong
 *       luminance term the weights follow the noise and that approximation understates
 *       the leverage (window-room at 64 spp: 46.0 dB with SVGF's 4 standard errors,
 *       49.6 dB with 16).
 *    c. The pixel's own value, leverage 1.
 *    Each pixel takes the candidate of least estimated squared error, Stein's unbiased
 *    risk estimate (SURE) |f - y|^2 - var + 2 var L, smoothed over 5x5 pixels, with var the
 *    variance of the pixel's mean from the film's sums of squares. This is the per-pixel
 *    selection among candidate filters of Li, Wu and Chuang 2012 ("SURE-based Optimization
 *    for Adaptive Sampling and Reconstruction", ACM TOG 31(6), SIGGRAPH Asia) that NFOR also
 *    makes. The pixel's own value has risk var: where its samples have converged (a small
 *    lamp's neighbourhood at 64 samples, a shadow edge no feature explains) a candidate
 *    must agree with them to be taken, so the filter does not make a converged region
 *    worse. A pixel none of whose samples met a surface keeps its own value: it has no
 *    reflected light, and a fit would reach past the silhouette beside it.
 *
 * 4. Emission. The first hit's emission varies from pixel to pixel only where a pixel sees
 *    an emitter's edge: at 16 samples a row of pixels under a lamp's edge that covers 5 %
 *    of each has one sample on the lamp in some pixels and none in others, 1.0 or 0.05
 *    against 0.8. Its candidates are its own value and boxes of half-width 1, 2 and 4 along
 *    rows and along columns; each pixel takes the one of least risk, unsmoothed, with the
 *    variance the candidate implies: samples between 0 and the brightest emission around
 *    (3x3), L, with mean f vary by at most f (L - f) (Bhatia and Davis 2000), halved for
 *    the stratified samples, over the pixel's count. A pixel whose samples all missed
 *    the lamp beside it shows no spread of its own; the candidate's mean says what it
 *    should have been. Along a straight edge a box averages pixels that see the same share
 *    of the lamp; across it the difference makes its risk large.
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
#include "filter.h"

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
/* The edge-stopping candidate's normal and relative-depth scales (the a-trous filter's
 * defaults) and its luminance scale in standard errors (SVGF's 4), and its levels. */
#define DN_SIGMA_N 0.3f
#define DN_SIGMA_Z 0.05f
#define DN_SIGMA_L 16.0f
#define DN_LEVELS 4
/* The smallest albedo the illumination is divided by. */
#define DN_ALBEDO_MIN 0.01f
/* The firefly step's neighbourhood, (2 DN_FIREFLY_R + 1)^2 pixels. */
#define DN_FIREFLY_R 2
/* A pixel whose energy rests on this many samples or fewer ((sum of the luminances)^2 / (sum
 * of their squares)) is judged against its neighbours' median, not the second brightest. */
#define DN_SPARSE_NEFF 2.0f
/* The spread of the outliers' energy: the count of outlier pixels its window must hold,
 * the largest half-width, the growth of the relative-depth tolerance with the distance (in
 * DN_SIGMA_Z per pixel), the weight of the difference of the denoised luminance, and the
 * scale of the outliers' second moments (3/4: for outliers spread evenly over a window of
 * half-width r, a Gaussian of standard deviation r / 2). */
#define DN_SPREAD_K 12
#define DN_SPREAD_RMAX 32
#define DN_SPREAD_ZS 0.1f
#define DN_SPREAD_IB 16.0f
#define DN_SPREAD_MOMENTS 0.75
/* The emission's binomial bound on its variance, scaled for stratified samples. */
#define DN_EMIT_VAR 0.5f

/* The emission's candidates: boxes along rows and along columns of these half-widths. */
#define DN_EMIT_R 4
/* Rows per strip: each strip starts its running sums afresh. */
#define DN_STRIP 48

tr_denoise_params tr_denoise_params_default(void) {
    tr_denoise_params p;
    memset(&p, 0, sizeof p);
    p.radius = 4;
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

static void sortn(float *v, int n) {
    for (int i = 1; i < n; ++i) {
        const float x = v[i];
        int j = i - 1;
        while (j >= 0 && v[j] > x) {
            v[j + 1] = v[j];
            --j;
        }
        v[j + 1] = x;
    }
}

/* Step 1: the firefly step. lm, se: each pixel's luminance and standard error; neff: the
 * number of samples that carry its energy, (sum of the luminances)^2 / (sum of their
 * squares), INFINITY where not known (NULL: none known). The part taken from a pixel that
 * met a surface (depth > 0) is kept in ex (3 per pixel), to be spread; from one that met
 * none it is dropped. */
static long fireflies(int w, int h, float *col, const float *lm, const float *se, const float *neff,
                      const float *depth, float k, float *ex, int threads) {
    long changed = 0;
    const int fr = DN_FIREFLY_R;
#pragma omp parallel for num_threads(threads) schedule(static) reduction(+ : changed)
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            const size_t i = (size_t)y * w + x;
            const float l = lm[i];
            /* An outlier of a cluster: its energy rests on one sample or two. */
            const int sparse = neff && neff[i] <= DN_SPARSE_NEFF;
            /* The brightest and second brightest neighbour inside the image. */
            float b1 = -INFINITY, b2 = -INFINITY;
            int n = 0;
            float ns[(2 * DN_FIREFLY_R + 1) * (2 * DN_FIREFLY_R + 1)];
            for (int dy = -fr; dy <= fr; ++dy) {
                for (int dx = -fr; dx <= fr; ++dx) {
                    const int xx = x + dx, yy = y + dy;
                    if ((dx || dy) && xx >= 0 && yy >= 0 && xx < w && yy < h) {
                        const float v = lm[(size_t)yy * w + xx];
                        if (v > b1) {
                            b2 = b1;
                            b1 = v;
                        } else if (v > b2) {
                            b2 = v;
                        }
                        ns[n++] = v;
                    }
                }
            }
            if (n < 2 || !(l > (sparse ? -INFINITY : b2))) {
                continue; /* no firefly: most pixels stop here */
            }
            /* The level the pixel is judged against: the second brightest neighbour, or
             * for a pixel whose energy rests on one or two samples the neighbours'
             * median, so that a cluster of them (a caustic, a glossy highlight that the
             * samples undersample) is taken too. */
            float level = b2;
            if (sparse) {
                sortn(ns, n);
                level = ns[n / 2];
                if (!(l > level)) {
                    continue;
                }
            }
            n = 0;
            for (int dy = -fr; dy <= fr; ++dy) {
                for (int dx = -fr; dx <= fr; ++dx) {
                    const int xx = x + dx, yy = y + dy;
                    if ((dx || dy) && xx >= 0 && yy >= 0 && xx < w && yy < h) {
                        ns[n++] = se[(size_t)yy * w + xx];
                    }
                }
            }
            sortn(ns, n);
            const float med = n & 1 ? ns[n / 2] : 0.5f * (ns[n / 2 - 1] + ns[n / 2]);
            const float bound = level + k * med;
            if (!(l > bound)) {
                continue;
            }
            const float take = fminf(l - bound, k * se[i]);
            if (take > 0.0f) {
                const float s = (l - take) / l;
                for (int c = 0; c < 3; ++c) {
                    const float v = col[3 * i + c];
                    col[3 * i + c] = v * s;
                    if (depth[i] > 0.0f) {
                        ex[3 * i + c] = v - v * s;
                    }
                }
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
    /* Separable: the row sums of each row's 2 rad + 1 rows, then along the row; in double,
     * term by term in a fixed order. */
#pragma omp parallel for num_threads(threads) schedule(static)
    for (int y = 0; y < h; ++y) {
        double col[4096 + 1];
        const int y0 = y - rad > 0 ? y - rad : 0, y1 = y + rad < h - 1 ? y + rad : h - 1;
        for (int x0 = 0; x0 < w; x0 += 4096 - 2 * 64) {
            /* Chunks of columns with a margin of rad on either side (rad <= 64). */
            const int xa = x0 - rad > 0 ? x0 - rad : 0;
            const int xe = x0 + 4096 - 2 * 64 < w ? x0 + 4096 - 2 * 64 : w;
            const int xb = xe + rad < w ? xe + rad : w;
            for (int x = xa; x < xb; ++x) {
                double s = 0.0;
                for (int yy = y0; yy <= y1; ++yy) {
                    s += a[(size_t)yy * w + x];
                }
                col[x - xa] = s;
            }
            for (int x = x0; x < xe; ++x) {
                const int c0 = x - rad > 0 ? x - rad : 0, c1 = x + rad < w - 1 ? x + rad : w - 1;
                double s = 0.0;
                for (int xx = c0; xx <= c1; ++xx) {
                    s += col[xx - xa];
                }
                b[(size_t)y * w + x] = (float)(s / ((double)(c1 - c0 + 1) * (y1 - y0 + 1)));
            }
        }
    }
}

/* The weight of receiver j in the spread of source i's outlier energy: a Gaussian of
 * standard deviation half the radius in the image plane, times the agreement of the
 * surface (normal, and relative depth with a tolerance that grows with the distance, as
 * a floor in perspective changes depth along it). 0 for a pixel that met no surface. */
/* The weight of receiver j in the spread of source i's outlier energy: a Gaussian of the
 * offset (dx, dy) with inverse covariance ic (xx, xy, yy) times the agreement of the surface:
 * normal, relative depth with a tolerance that grows with the distance (a floor in
 * perspective changes depth along it), and the denoised luminance without the outliers
 * (base), which keeps the energy of a caustic on a floor out of the floor seen through the
 * glass beside it. 0 for a pixel that met no surface. */
static float spread_weight(const dn_img *im, const float *base, size_t i, size_t j, int dx, int dy,
                           const float *ic) {
    const float zj = im->feat[3][j];
    if (!(zj > 0.0f)) {
        return 0.0f;
    }
    const float d0 = im->feat[0][j] - im->feat[0][i], d1 = im->feat[1][j] - im->feat[1][i],
                d2 = im->feat[2][j] - im->feat[2][i];
    const float zi = im->feat[3][i];
    const float fx = (float)dx, fy = (float)dy;
    const float dist = sqrtf(fx * fx + fy * fy);
    const float dz = (zj - zi) / (zi * DN_SIGMA_Z * fmaxf(1.0f, dist * DN_SPREAD_ZS));
    const float db = (base[j] - base[i]) / (fabsf(base[i]) + fabsf(base[j]) + 1e-4f);
    const float q = 0.5f * (ic[0] * fx * fx + 2.0f * ic[1] * fx * fy + ic[2] * fy * fy);
    return tr_post_exp_neg(q + (d0 * d0 + d1 * d1 + d2 * d2) * (1.0f / (DN_SIGMA_N * DN_SIGMA_N)) +
                           dz * dz + db * db * DN_SPREAD_IB);
}

/* Step 1's second half: the energy the firefly step took (ex, 3 per pixel) is spread over
 * the pixels around that show the same surface and added into out (3 per pixel), each
 * source's weights normalised to 1, so the total is kept: a sparse caustic becomes a
 * smooth patch of its energy instead of a few bright pixels or none. This is the simple,
 * energy-preserving counterpart of Zirr, Hanika and Dachsbacher 2018 ("Re-Weighting Firefly
 * Samples for Improved Finite-Sample Monte Carlo Estimates", Computer Graphics Forum 37(6)),
 * who keep such samples in cascades by brightness and weigh each cascade by its agreement
 * with the neighbourhood's. The window's half-width is the smallest of 2, 4, ..., 32 that
 * holds DN_SPREAD_K outlier pixels (a k-nearest-neighbour bandwidth: sparse samples spread
 * over the area that holds enough of them to say how bright it is on average), and the
 * Gaussian follows the second moments of the outliers' offsets in it, so that an elongated
 * glossy highlight stays elongated. base: the denoised luminance; flag, cnt, rad, wsum:
 * scratch planes. Each receiver adds its sources in a fixed order, in strips of rows, so the
 * result does not depend on the thread count. */
static int spread(const dn_img *im, const float *ex, const float *base, float *flag, float *cnt,
                  float *rad, float *wsum, float *out, int threads) {
    const int w = im->w, h = im->h;
    const long n = (long)w * h;
    long ns = 0;
    for (long i = 0; i < n; ++i) {
        const int on = lum(ex + 3 * i) > 0.0f;
        flag[i] = on ? 1.0f : 0.0f;
        rad[i] = 0.0f;
        ns += on;
    }
    if (ns == 0) {
        return TR_OK;
    }
    long *src = malloc(sizeof(long) * (size_t)ns);
    float *kic = malloc(sizeof(float) * 3 * (size_t)ns);
    if (!src || !kic) {
        free(src);
        free(kic);
        return TR_ERR;
    }
    ns = 0;
    for (long i = 0; i < n; ++i) {
        if (flag[i] > 0.0f) {
            src[ns++] = i;
        }
    }
    for (int r = 2; r <= DN_SPREAD_RMAX; r *= 2) {
        box_mean(w, h, flag, cnt, r, threads);
        for (long s = 0; s < ns; ++s) {
            const long i = src[s];
            const int x = (int)(i % w), y = (int)(i / w);
            const int ax = (x + r < w - 1 ? x + r : w - 1) - (x - r > 0 ? x - r : 0) + 1;
            const int ay = (y + r < h - 1 ? y + r : h - 1) - (y - r > 0 ? y - r : 0) + 1;
            if (rad[i] == 0.0f &&
                (cnt[i] * (float)(ax * ay) >= DN_SPREAD_K - 0.5f || r * 2 > DN_SPREAD_RMAX)) {
                rad[i] = (float)r;
            }
        }
    }
#pragma omp parallel for num_threads(threads) schedule(dynamic, 64)
    for (long s = 0; s < ns; ++s) {
        const long i = src[s];
        const int x = (int)(i % w), y = (int)(i / w), r = (int)rad[i];
        const int xa = x - r > 0 ? x - r : 0, xb = x + r < w - 1 ? x + r : w - 1;
        const int ya = y - r > 0 ? y - r : 0, yb = y + r < h - 1 ? y + r : h - 1;
        /* The second moments of the outliers' offsets in the window (the source's among
         * them), with those of DN_SPREAD_K - m outliers spread evenly over it where it holds
         * only m < DN_SPREAD_K (a lone firefly spreads over the whole window), scaled, and
         * half a pixel's variance. */
        double m = 0.0, sxx = 0.0, sxy = 0.0, syy = 0.0;
        for (int yy = ya; yy <= yb; ++yy) {
            for (int xx = xa; xx <= xb; ++xx) {
                if (flag[(size_t)yy * w + xx] > 0.0f) {
                    const double dx = xx - x, dy = yy - y;
                    m += 1.0;
                    sxx += dx * dx;
                    sxy += dx * dy;
                    syy += dy * dy;
                }
            }
        }
        if (m < DN_SPREAD_K) {
            const double u = (DN_SPREAD_K - m) * (double)r * (r + 1) / 3.0;
            sxx += u;
            syy += u;
            m = DN_SPREAD_K;
        }
        const double a = DN_SPREAD_MOMENTS * sxx / m + 0.5, b = DN_SPREAD_MOMENTS * sxy / m,
                     c = DN_SPREAD_MOMENTS * syy / m + 0.5;
        const double det = a * c - b * b;
        float *ic = kic + 3 * s;
        ic[0] = (float)(c / det);
        ic[1] = (float)(-b / det);
        ic[2] = (float)(a / det);
        double t = 0.0;
        for (int yy = ya; yy <= yb; ++yy) {
            for (int xx = xa; xx <= xb; ++xx) {
                t += spread_weight(im, base, (size_t)i, (size_t)yy * w + xx, xx - x, yy - y, ic);
            }
        }
        wsum[i] = (float)t;
    }
    const int strips = (h + DN_STRIP - 1) / DN_STRIP;
#pragma omp parallel for num_threads(threads) schedule(dynamic, 1)
    for (int st = 0; st < strips; ++st) {
        const int y0 = st * DN_STRIP, y1 = y0 + DN_STRIP < h ? y0 + DN_STRIP : h;
        for (long s = 0; s < ns; ++s) {
            const long i = src[s];
            const int x = (int)(i % w), y = (int)(i / w), r = (int)rad[i];
            if (y + r < y0 || y - r >= y1 || !(wsum[i] > 0.0f)) {
                continue;
            }
            const float *ic = kic + 3 * s;
            const float inv = 1.0f / wsum[i];
            const float e0 = ex[3 * i] * inv, e1 = ex[3 * i + 1] * inv, e2 = ex[3 * i + 2] * inv;
            const int ya = y - r > y0 ? y - r : y0, yb = y + r < y1 - 1 ? y + r : y1 - 1;
            const int xa = x - r > 0 ? x - r : 0, xb = x + r < w - 1 ? x + r : w - 1;
            for (int yy = ya; yy <= yb; ++yy) {
                for (int xx = xa; xx <= xb; ++xx) {
                    const size_t j = (size_t)yy * w + xx;
                    const float wt = spread_weight(im, base, (size_t)i, j, xx - x, yy - y, ic);
                    out[3 * j] += wt * e0;
                    out[3 * j + 1] += wt * e1;
                    out[3 * j + 2] += wt * e2;
                }
            }
        }
    }
    free(src);
    free(kic);
    return TR_OK;
}

/* One level of the edge-stopping candidate: an a-trous step (the 5x5 B3 kernel with holes
 * of `step` pixels, Dammertz et al. 2010) of the planes src into dst, each tap weighted by
 * the differences in normal and relative depth (the a-trous filter's scales) and by the
 * difference in luminance against the noise expected of it, |l_j - l_i| / (sigma_l
 * sqrt(var_i)) as in SVGF (Schied et al. 2017); the variance of the result goes into dvar
 * (the squared weights times the taps' variances). The weights depend on the values only
 * through that luminance term, so the weight of the pixel's own value in its result is
 * about the centre tap's normalised weight, as Li, Wu and Chuang 2012 take it for their
 * cross-bilateral candidates; over the levels it is the product, kept in lev (lev_in NULL
 * for the first level). lsrc: scratch, the luminance of src. The taps run in the outer
 * loops and the pixels of a row in the inner one, so that it vectorises. */
static int estop_level(const dn_img *im, const float *const src[3], const float *svar,
                       float *const dst[3], float *dvar, const float *lev_in, float *lev_out,
                       float *lsrc, int step, float sigma_l, int threads) {
    const int w = im->w, h = im->h;
    const float in2 = 1.0f / (DN_SIGMA_N * DN_SIGMA_N), iz = 1.0f / (DN_SIGMA_Z * DN_SIGMA_Z);
    const long n = (long)w * h;
#pragma omp parallel for num_threads(threads) schedule(static)
    for (long i = 0; i < n; ++i) {
        lsrc[i] = lum((float[3]){src[0][i], src[1][i], src[2][i]});
    }
    int failed = 0;
#pragma omp parallel num_threads(threads) reduction(| : failed)
    {
        float *acc = malloc(sizeof(float) * 7 * (size_t)w);
        if (!acc) {
            failed = 1;
        }
#pragma omp for schedule(static)
        for (int y = 0; y < h; ++y) {
            if (!acc) {
                continue;
            }
            float *restrict s0 = acc, *restrict s1 = acc + w, *restrict s2 = acc + 2 * w;
            float *restrict sv = acc + 3 * w, *restrict sw = acc + 4 * w;
            float *restrict icz = acc + 5 * w, *restrict il = acc + 6 * w;
            const size_t row = (size_t)y * w;
            for (int x = 0; x < w; ++x) {
                const float z = im->feat[3][row + x];
                icz[x] = 1.0f / (z > 1e-3f ? z : 1e-3f);
                il[x] = 1.0f / (sigma_l * sqrtf(fmaxf(svar[row + x], 0.0f)) + 1e-6f);
                s0[x] = s1[x] = s2[x] = sv[x] = sw[x] = 0.0f;
            }
            const float *restrict n0 = im->feat[0] + row, *restrict n1 = im->feat[1] + row,
                                  *restrict n2 = im->feat[2] + row,
                                  *restrict z0 = im->feat[3] + row, *restrict l0 = lsrc + row;
            for (int ky = -2; ky <= 2; ++ky) {
                const int ty = y + ky * step;
                if (ty < 0 || ty >= h) {
                    continue;
                }
                for (int kx = -2; kx <= 2; ++kx) {
                    const int off = kx * step;
                    const int xa = off < 0 ? -off : 0, xb = off > 0 ? w - off : w;
                    const float bw = tr_post_b3(kx) * tr_post_b3(ky);
                    const size_t tr = (size_t)ty * w + off;
                    const float *restrict m0 = im->feat[0] + tr, *restrict m1 = im->feat[1] + tr,
                                          *restrict m2 = im->feat[2] + tr,
                                          *restrict mz = im->feat[3] + tr, *restrict ml = lsrc + tr;
                    const float *restrict c0 = src[0] + tr, *restrict c1 = src[1] + tr,
                                          *restrict c2 = src[2] + tr, *restrict cv = svar + tr;
                    for (int x = xa; x < xb; ++x) {
                        const float d0 = m0[x] - n0[x], d1 = m1[x] - n1[x], d2 = m2[x] - n2[x];
                        const float dz = (mz[x] - z0[x]) * icz[x];
                        const float dl = fabsf(ml[x] - l0[x]);
                        const float e =
                            (d0 * d0 + d1 * d1 + d2 * d2) * in2 + dz * dz * iz + dl * il[x];
                        const float wt = bw * tr_post_exp_neg(e);
                        s0[x] += wt * c0[x];
                        s1[x] += wt * c1[x];
                        s2[x] += wt * c2[x];
                        sv[x] += wt * wt * cv[x];
                        sw[x] += wt;
                    }
                }
            }
            for (int x = 0; x < w; ++x) {
                const size_t c = row + x;
                const float inv = 1.0f / sw[x];
                dst[0][c] = s0[x] * inv;
                dst[1][c] = s1[x] * inv;
                dst[2][c] = s2[x] * inv;
                dvar[c] = sv[x] * inv * inv;
                lev_out[c] = (lev_in ? lev_in[c] : 1.0f) * tr_post_b3(0) * tr_post_b3(0) * inv;
            }
        }
        free(acc);
    }
    return failed ? TR_ERR : TR_OK;
}

/* Risk of the candidate cand (3 planes) with leverage lev against the pixel values y and
 * variance var (Stein's unbiased risk estimate, smoothed over 5x5 into rs via r); where
 * it is below the best so far (rbest), the candidate becomes the pixel's best. */
static void consider(int w, int h, const float *const y[3], const float *var,
                     const float *const cand[3], const float *lev, float *r, float *rs,
                     float *rbest, float *const best[3], int threads) {
    const long n = (long)w * h;
#pragma omp parallel for num_threads(threads) schedule(static)
    for (long i = 0; i < n; ++i) {
        const float d =
            lum((float[3]){cand[0][i] - y[0][i], cand[1][i] - y[1][i], cand[2][i] - y[2][i]});
        const float v = DN_SELECT * var[i];
        r[i] = d * d - v + 2.0f * v * lev[i];
    }
    box_mean(w, h, r, rs, 2, threads);
#pragma omp parallel for num_threads(threads) schedule(static)
    for (long i = 0; i < n; ++i) {
        if (rs[i] < rbest[i]) {
            rbest[i] = rs[i];
            for (int k = 0; k < 3; ++k) {
                best[k][i] = cand[k][i];
            }
        }
    }
}

/* A box of half-width r along rows (dx 1, dy 0) or columns of the planes a into b. */
static void box_line(int w, int h, const float *const a[3], float *const b[3], int r, int dx,
                     int dy, int threads) {
#pragma omp parallel for num_threads(threads) schedule(static)
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            float s0 = 0.0f, s1 = 0.0f, s2 = 0.0f;
            int m = 0;
            for (int k = -r; k <= r; ++k) {
                const int xx = x + k * dx, yy = y + k * dy;
                if (xx >= 0 && yy >= 0 && xx < w && yy < h) {
                    const size_t j = (size_t)yy * w + xx;
                    s0 += a[0][j];
                    s1 += a[1][j];
                    s2 += a[2][j];
                    ++m;
                }
            }
            const size_t i = (size_t)y * w + x;
            b[0][i] = s0 / (float)m;
            b[1][i] = s1 / (float)m;
            b[2][i] = s2 / (float)m;
        }
    }
}

/* The first hit's emission is noisy only where a pixel sees an emitter's edge: some of its
 * samples hit the lamp, some what lies beside it, and at a few samples per pixel the
 * count of hits varies from pixel to pixel along the edge. Its candidates are the pixel's
 * own value and boxes along rows and along columns (half-widths 1, 2, 4): along a straight
 * edge one of them averages pixels that see the same share of the lamp, across it the
 * difference of the values makes its risk large. Each pixel takes the one of least
 * smoothed risk as the illumination's candidates, with the variance of the pixel's mean
 * (its standard error se squared: where the emission varies it dominates the pixel's
 * noise). e: the emission, 3 floats per pixel; ep, cand, best: 3 planes each; var, lev,
 * r, rs, rbest: scratch planes. */
static void emission_select(int w, int h, const float *e, const uint32_t *count, float *const ep[3],
                            float *const cand[3], float *const best[3], float *top, float *r,
                            float *rbest, int threads) {
    const long n = (long)w * h;
#pragma omp parallel for num_threads(threads) schedule(static)
    for (long i = 0; i < n; ++i) {
        for (int k = 0; k < 3; ++k) {
            ep[k][i] = e[3 * i + k];
            best[k][i] = e[3 * i + k];
        }
        r[i] = lum(e + 3 * i);
        rbest[i] = 0.0f;
    }
    /* The brightest emission around each pixel (3x3), L: samples of the emission lie
     * between 0 and about L. */
#pragma omp parallel for num_threads(threads) schedule(static)
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            float t = 0.0f;
            for (int yy = y > 0 ? y - 1 : 0; yy <= y + 1 && yy < h; ++yy) {
                for (int xx = x > 0 ? x - 1 : 0; xx <= x + 1 && xx < w; ++xx) {
                    t = fmaxf(t, r[(size_t)yy * w + xx]);
                }
            }
            top[(size_t)y * w + x] = t;
        }
    }
    for (int dir = 0; dir < 2; ++dir) {
        for (int rad = 1; rad <= DN_EMIT_R; rad *= 2) {
            box_line(w, h, (const float *const *)ep, cand, rad, dir == 0, dir == 1, threads);
            const float l = 1.0f / (float)(2 * rad + 1);
#pragma omp parallel for num_threads(threads) schedule(static)
            for (long i = 0; i < n; ++i) {
                const float f = lum((float[3]){cand[0][i], cand[1][i], cand[2][i]});
                const float d = f - lum((float[3]){ep[0][i], ep[1][i], ep[2][i]});
                /* The variance of the pixel's mean if the candidate is right: samples
                 * between 0 and L of mean f vary by at most f (L - f) (Bhatia and Davis
                 * 2000); the pixel's own count of them. A pixel none of whose samples
                 * met the lamp beside it has no spread of its own to show. */
                const float c = count[i] > 1u ? (float)count[i] : 1.0f;
                const float v = DN_EMIT_VAR * fmaxf(f, 0.0f) * fmaxf(top[i] - f, 0.0f) / c;
                /* Its risk less that of the pixel's own value (v). */
                const float rk = d * d - 2.0f * v + 2.0f * v * l;
                if (rk < rbest[i]) {
                    rbest[i] = rk;
                    for (int k = 0; k < 3; ++k) {
                        best[k][i] = cand[k][i];
                    }
                }
            }
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
        P_AT,             /* the edge-stopping candidate's other level (3) */
        P_AV0 = P_AT + 3, /* its variances, in and out */
        P_AV1,
        P_ALEV, /* its leverage */
        P_N
    };
    float *block = malloc(sizeof(float) * n * P_N);
    float *col = malloc(sizeof(float) * 3 * n);
    float *alb = malloc(sizeof(float) * 3 * n);
    float *emi = malloc(sizeof(float) * 3 * n);
    float *ex = calloc(3 * n, sizeof(float)); /* the outliers' energy, step 1 */
    if (!block || !col || !alb || !emi || !ex) {
        free(block);
        free(col);
        free(alb);
        free(emi);
        free(ex);
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
    }
    /* The standard error of the reflected part. Where the first hit's emission is kept, its
     * share of the sums of squares is taken out: a sample that meets an emitter reflects
     * nothing there, so the squares add, sum v^2 = sum e^2 + sum r^2, and the emission's
     * squares are about L sum e for the brightest emission around, L (3x3), the value its
     * samples take. Without that, a pixel under a lamp's edge, whose few samples on the lamp
     * make its radiance vary a great deal, would count as noisy reflected light and draw
     * the fits of its neighbours towards its own. */
#pragma omp parallel for num_threads(threads) schedule(static)
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            const size_t i = (size_t)y * w + x;
            const uint32_t c = film->count[i];
            if (!film->sq) {
                pl[P_SE][i] = fmaxf(pl[P_LUM][i], 0.0f); /* no pass: a spike is not vouched for */
                continue;
            }
            float se = 0.0f;
            for (int k = 0; k < 3; ++k) {
                double v = tr_film_variance(film, i, k);
                if (film->emission && c > 1u) {
                    float top = 0.0f;
                    for (int yy = y > 0 ? y - 1 : 0; yy <= y + 1 && yy < h; ++yy) {
                        for (int xx = x > 0 ? x - 1 : 0; xx <= x + 1 && xx < w; ++xx) {
                            top = fmaxf(top, emi[3 * ((size_t)yy * w + xx) + k]);
                        }
                    }
                    const double es = film->emission[3 * i + k];
                    const double q = film->sq[3 * i + k] - (double)top * es;
                    const double sr = film->sum[3 * i + k] - es;
                    v = (q - sr * sr / c) / (double)(c - 1u) / (double)c;
                    v = v > 0.0 ? v : 0.0;
                }
                se += (k == 0 ? 0.2126f : k == 1 ? 0.7152f : 0.0722f) * sqrtf((float)v);
            }
            pl[P_SE][i] = se;
        }
    }
    /* How many samples carry each pixel's energy (luminance-weighted sums of the channels'
     * sums and squares): 1 for a pixel whose value rests on one sample. Unknown without the
     * variance pass and where the first hit's emission is part of the sums. */
    float *neff = pl[P_R];
#pragma omp parallel for num_threads(threads) schedule(static)
    for (long i = 0; i < (long)n; ++i) {
        neff[i] = INFINITY;
        if (film->sq && film->count[i] > 0u) {
            double sl = 0.0, ql = 0.0, e = 0.0;
            for (int k = 0; k < 3; ++k) {
                const double wc = k == 0 ? 0.2126 : k == 1 ? 0.7152 : 0.0722;
                sl += wc * film->sum[3 * i + k];
                ql += wc * film->sq[3 * i + k];
                e += film->emission ? film->emission[3 * i + k] : 0.0;
            }
            if (e == 0.0 && ql > 0.0) {
                neff[i] = (float)(sl * sl / ql);
            }
        }
    }
    fireflies(w, h, col, pl[P_LUM], pl[P_SE], neff, film->depth, p.firefly_k, ex, threads);
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
                /* Demodulate by the albedo, held at DN_ALBEDO_MIN or above: the same factor
                 * in every channel and pixel divides and multiplies back, so a channel whose
                 * albedo is nearly black is not mixed, undivided, with its neighbours'
                 * divided values. */
                pl[P_Y + k][i] = col[3 * i + k] / fmaxf(alb[3 * i + k], DN_ALBEDO_MIN);
            }
            pl[3][i] = film->depth[i] * inv * zscale;
            pl[4][i] = (float)x * xscale;
            pl[5][i] = (float)y * xscale;
            /* The variance of the demodulated luminance. */
            const float la = lum((float[3]){fmaxf(alb[3 * i], DN_ALBEDO_MIN),
                                            fmaxf(alb[3 * i + 1], DN_ALBEDO_MIN),
                                            fmaxf(alb[3 * i + 2], DN_ALBEDO_MIN)});
            const float se = pl[P_SE][i] / la;
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
    float *best[3] = {pl[P_BEST], pl[P_BEST + 1], pl[P_BEST + 2]};
    float *at[3] = {pl[P_AT], pl[P_AT + 1], pl[P_AT + 2]};
    const float *yv[3] = {pl[P_Y], pl[P_Y + 1], pl[P_Y + 2]};
    for (int r = p.radius_small; rc == TR_OK; r = r * 2 < p.radius ? r * 2 : p.radius) {
        rc = regress(&im, r, cur, pl[P_LEV], threads);
        if (rc != TR_OK) {
            break;
        }
        consider(w, h, yv, pl[P_VAR], (const float *const *)cur, pl[P_LEV], pl[P_R], pl[P_RS],
                 pl[P_RBEST], best, threads);
        if (r >= p.radius) {
            break;
        }
    }
    /* The edge-stopping candidates: the a-trous levels at steps 1, 2, 4, 8, each level's
     * result one candidate; the luminance term starts from the variance smoothed over 3x3. */
    if (rc == TR_OK) {
        box_mean(w, h, pl[P_VAR], pl[P_AV0], 1, threads);
        const float *src[3] = {yv[0], yv[1], yv[2]};
        float *sv = pl[P_AV0], *dv = pl[P_AV1];
        for (int l = 0; l < DN_LEVELS && rc == TR_OK; ++l) {
            float *const *dst = (l & 1) ? cur : at;
            rc = estop_level(&im, src, sv, dst, dv, l ? pl[P_ALEV] : NULL, pl[P_ALEV], pl[P_LEV],
                             1 << l, DN_SIGMA_L, threads);
            if (rc != TR_OK) {
                break;
            }
            consider(w, h, yv, pl[P_VAR], (const float *const *)dst, pl[P_ALEV], pl[P_R], pl[P_RS],
                     pl[P_RBEST], best, threads);
            for (int k = 0; k < 3; ++k) {
                src[k] = dst[k];
            }
            float *t = sv;
            sv = dv;
            dv = t;
        }
    }
    if (rc == TR_OK) {
#pragma omp parallel for num_threads(threads) schedule(static)
        for (long i = 0; i < (long)n; ++i) {
            /* A pixel none of whose samples met a surface has no reflected light to clean:
             * its value is what the samples saw, not a fit that reaches past the
             * silhouette of the surfaces beside it. */
            const int nohit = film->depth[i] == 0.0f;
            for (int k = 0; k < 3; ++k) {
                const float v = nohit ? pl[P_Y + k][i] : pl[P_BEST + k][i];
                const float a = alb[3 * i + k];
                const float y = v * fmaxf(a, DN_ALBEDO_MIN);
                out[3 * i + k] = fmaxf(y, 0.0f);
            }
        }
        /* The outliers' energy, spread over their surfaces. */
        float *base = pl[P_AV0];
#pragma omp parallel for num_threads(threads) schedule(static)
        for (long i = 0; i < (long)n; ++i) {
            base[i] = lum(out + 3 * i);
        }
        rc = spread(&im, ex, base, pl[P_LEV], pl[P_RS], pl[P_AV1], pl[P_ALEV], out, threads);
    }
    if (rc == TR_OK) {
        if (film->emission) {
            float *eb[3] = {pl[P_BEST], pl[P_BEST + 1], pl[P_BEST + 2]};
            emission_select(w, h, emi, film->count, at, cur, eb, pl[P_AV0], pl[P_R], pl[P_RBEST],
                            threads);
#pragma omp parallel for num_threads(threads) schedule(static)
            for (long i = 0; i < (long)n; ++i) {
                for (int k = 0; k < 3; ++k) {
                    out[3 * i + k] += eb[k][i];
                }
            }
        }
    } else {
        tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory denoising %dx%d", w, h);
    }
    free(block);
    free(col);
    free(alb);
    free(emi);
    free(ex);
    return rc;
}
