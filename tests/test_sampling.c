/* test_sampling.c - the direction samplers and pixel jitter of sampling.h.
 *
 * Every sampler draws z = cos(theta) about its axis from a density proportional to
 * z^n on [c, 1] and phi uniformly, so one model covers them all: the uniform sphere is
 * n = 0, c = -1, and the cone of half-angle a is c = cos(a). Its CDF in z is
 *   F(x) = (x^(n+1) - c^(n+1)) / (1 - c^(n+1)),
 * the integral of the solid-angle pdf (n+1) z^n / (2 pi (1 - c^(n+1))) over the band
 * between c and x. Bins of equal expected probability are then F^-1(k/K), i.e. sample
 * z goes to bin floor(K F(z)).
 *
 * Seeds are fixed so a run is deterministic, but every bound comes from the sampling
 * distribution of its statistic (chi-square quantile at p = 1e-4, or 5 standard
 * errors), not from the values one run happened to produce. */
#include "check.h"
#include "kernel/kernel.h"
#include "scene/scene_internal.h"
#include "dvec.h"
#include "kernel/sampling.h"

#include <stdint.h>

enum { N_SAMPLES = 200000, Z_BINS = 20, PHI_BINS = 24, JOINT_Z = 8, JOINT_PHI = 8 };

#define PI_D 3.14159265358979323846

/* Pearson's statistic for bins that all expect the same count. */
static double chi2_uniform(const long *counts, int bins, long total) {
    double expected = (double)total / bins, chi2 = 0.0;
    for (int i = 0; i < bins; ++i) {
        double d = (double)counts[i] - expected;
        chi2 += d * d / expected;
    }
    return chi2;
}

/* A frame around n built independently of v3_basis, so that the phi test also checks
 * the kernel's frame: any rotationally symmetric distribution has uniform phi in it. */
static void dbasis(dvec n, dvec *t, dvec *b) {
    dvec helper = {1.0, 0.0, 0.0};
    if (fabs(n.x) > 0.9) {
        helper.x = 0.0;
        helper.y = 1.0;
    }
    *t = dnormalize(dcross(helper, n));
    *b = dcross(n, *t);
}

enum sampler_kind { UNIFORM_SPHERE, UNIFORM_HEMISPHERE, COSINE_HEMISPHERE, COSINE_CONE, LOBE };

typedef struct sampler_case {
    const char *name;
    enum sampler_kind kind;
    float power; /* LOBE only (the others imply theirs) */
    float angle; /* COSINE_CONE and LOBE */
} sampler_case;

static tr_vec3 draw(const sampler_case *sc, tr_rng *r, tr_vec3 dir) {
    switch (sc->kind) {
    case UNIFORM_SPHERE:
        return tr_sample_uniform_sphere(r);
    case UNIFORM_HEMISPHERE:
        return tr_sample_uniform_hemisphere(r, dir);
    case COSINE_HEMISPHERE:
        return tr_sample_cosine_hemisphere(r, dir);
    case COSINE_CONE:
        return tr_sample_cosine_cone(r, dir, sc->angle);
    case LOBE:
    default:
        return tr_sample_hemisphere(r, dir, sc->power, sc->angle);
    }
}

/* The z^n-on-[c,1] model of a sampler. */
typedef struct zmodel {
    double n, c;
} zmodel;

static zmodel model_of(const sampler_case *sc) {
    zmodel m;
    switch (sc->kind) {
    case UNIFORM_SPHERE:
        m.n = 0.0;
        m.c = -1.0;
        return m;
    case UNIFORM_HEMISPHERE:
        m.n = 0.0;
        m.c = 0.0;
        return m;
    case COSINE_HEMISPHERE:
        m.n = 1.0;
        m.c = 0.0;
        return m;
    case COSINE_CONE:
        m.n = 1.0;
        break;
    case LOBE:
    default:
        m.n = sc->power;
        break;
    }
    /* The documented range is 0 < angle <= pi/2; the float pi/2 lies 4e-8 beyond it. */
    m.c = fmax(cos((double)sc->angle), 0.0);
    return m;
}

/* z^(n+1) for z in [c, 1]; only n = 0 ever sees a negative z (the sphere). */
static double zpow(double z, double n) {
    return n == 0.0 ? z : pow(z, n + 1.0);
}

static double model_cdf(zmodel m, double x) {
    return (zpow(x, m.n) - zpow(m.c, m.n)) / (1.0 - zpow(m.c, m.n));
}

/* E[z^k] = (n+1)/(n+k+1) (1 - c^(n+k+1)) / (1 - c^(n+1)). */
static double model_moment(zmodel m, int k) {
    double e = m.n + 1.0, ek = m.n + k + 1.0;
    return e / ek * (1.0 - pow(m.c, ek)) / (1.0 - pow(m.c, e));
}

static int bin_of(double f, int bins) {
    int i = (int)floor(f * bins);
    return i < 0 ? 0 : (i >= bins ? bins - 1 : i);
}

/* Running mean and variance (Welford), for standard errors from the sample itself. */
typedef struct moments {
    long n;
    double mean, m2;
} moments;

static void moments_add(moments *s, double x) {
    ++s->n;
    double d = x - s->mean;
    s->mean += d / (double)s->n;
    s->m2 += d * (x - s->mean);
}

/* Standard error of the mean: sqrt(sample variance / n). */
static double moments_se(const moments *s) {
    return sqrt(s->m2 / (double)(s->n - 1) / (double)s->n);
}

static void check_mean(const moments *s, double expected, const char *what, const char *name,
                       int dir_index) {
    double se = moments_se(s);
    /* 5 standard errors: a correct sampler fails with probability ~6e-7. */
    CHECK(fabs(s->mean - expected) <= 5.0 * se + 1e-12, "%s, dir %d: %s %.6f vs %.6f (5 SE = %.2g)",
          name, dir_index, what, s->mean, expected, 5.0 * se);
}

/* (a) unit length and inside the cone, (b) chi-square in z, phi and (z, phi) against
 * the model, (c) the first two moments of z and the mean of the tangential components. */
static void check_sampler(const sampler_case *sc, tr_vec3 dir, int dir_index, uint64_t seed) {
    zmodel m = model_of(sc);
    dvec n = dnormalize(dv(dir)), t, b;
    dbasis(n, &t, &b);
    /* The sphere's "cone" is everything; elsewhere the bound is cos(angle). */
    double zmin = sc->kind == UNIFORM_SPHERE ? -1.0 : m.c;

    long zc[Z_BINS] = {0}, pc[PHI_BINS] = {0}, jc[JOINT_Z * JOINT_PHI] = {0};
    moments mz = {0, 0.0, 0.0}, mz2 = {0, 0.0, 0.0}, mt = {0, 0.0, 0.0}, mb = {0, 0.0, 0.0};
    int bad_length = 0, outside = 0, not_finite = 0;
    double worst_length = 1.0, worst_z = 1.0;

    tr_rng r;
    tr_rng_init(&r, seed, (uint64_t)dir_index, 0);
    for (int i = 0; i < N_SAMPLES; ++i) {
        tr_vec3 d = draw(sc, &r, dir);
        if (!v3_is_finite(d)) {
            ++not_finite;
            continue;
        }
        dvec dd = dv(d);
        double len = sqrt(ddot(dd, dd));
        if (fabs(len - 1.0) >= 1e-5) {
            ++bad_length;
            worst_length = fabs(len - 1.0) > fabs(worst_length - 1.0) ? len : worst_length;
        }
        double z = ddot(dd, n);
        if (z < zmin - 1e-5) {
            ++outside;
            worst_z = fmin(worst_z, z);
        }
        double zc_clamped = fmin(fmax(z, zmin), 1.0);
        double f = model_cdf(m, zc_clamped);
        double phi = atan2(ddot(dd, b), ddot(dd, t)) + PI_D; /* [0, 2 pi] */
        double g = phi / (2.0 * PI_D);
        zc[bin_of(f, Z_BINS)]++;
        pc[bin_of(g, PHI_BINS)]++;
        jc[bin_of(f, JOINT_Z) * JOINT_PHI + bin_of(g, JOINT_PHI)]++;
        moments_add(&mz, z);
        moments_add(&mz2, z * z);
        moments_add(&mt, ddot(dd, t));
        moments_add(&mb, ddot(dd, b));
    }
    CHECK(not_finite == 0, "%s, dir %d: %d non-finite directions", sc->name, dir_index, not_finite);
    CHECK(bad_length == 0, "%s, dir %d: %d directions not unit length (e.g. %.9g)", sc->name,
          dir_index, bad_length, worst_length);
    CHECK(outside == 0, "%s, dir %d: %d directions outside the cone (z %.9g < %.9g)", sc->name,
          dir_index, outside, worst_z, zmin);

    long total = N_SAMPLES - not_finite;
    double x_z = chi2_uniform(zc, Z_BINS, total);
    double x_p = chi2_uniform(pc, PHI_BINS, total);
    double x_j = chi2_uniform(jc, JOINT_Z * JOINT_PHI, total);
    /* The model is fully specified (nothing fitted), so dof = bins - 1. */
    double k_z = chi2_critical(Z_BINS - 1);
    double k_p = chi2_critical(PHI_BINS - 1);
    double k_j = chi2_critical(JOINT_Z * JOINT_PHI - 1);
    CHECK(x_z < k_z, "%s, dir %d: chi-square in cos(theta) %.2f >= %.2f", sc->name, dir_index, x_z,
          k_z);
    CHECK(x_p < k_p, "%s, dir %d: chi-square in phi %.2f >= %.2f", sc->name, dir_index, x_p, k_p);
    CHECK(x_j < k_j, "%s, dir %d: chi-square in (cos(theta), phi) %.2f >= %.2f", sc->name,
          dir_index, x_j, k_j);

    double ez = model_moment(m, 1), ez2 = model_moment(m, 2);
    check_mean(&mz, ez, "mean cos(theta)", sc->name, dir_index);
    check_mean(&mz2, ez2, "mean cos^2(theta)", sc->name, dir_index);
    check_mean(&mt, 0.0, "mean tangential component", sc->name, dir_index);
    check_mean(&mb, 0.0, "mean bitangential component", sc->name, dir_index);

    printf("%-26s dir %d: chi2 z(%d) %6.2f  phi(%d) %6.2f  joint(%d) %6.2f  "
           "E[cos] %.5f vs %.5f (%+.2f SE)\n",
           sc->name, dir_index, Z_BINS - 1, x_z, PHI_BINS - 1, x_p, JOINT_Z * JOINT_PHI - 1, x_j,
           mz.mean, ez, (mz.mean - ez) / moments_se(&mz));
}

/* Containment and unit length only, for axis-aligned and nearly-axis directions, where
 * the branch-free frame of v3_basis is closest to its singularity. */
static void check_sampler_axes(const sampler_case *sc) {
    const tr_vec3 axes[] = {v3(0.0f, 0.0f, 1.0f),  v3(0.0f, 0.0f, -1.0f), v3(1.0f, 0.0f, 0.0f),
                            v3(0.0f, -1.0f, 0.0f), v3(0.0f, 1.0f, -0.0f), v3(1e-4f, 0.0f, -1.0f)};
    double zmin = sc->kind == UNIFORM_SPHERE ? -1.0 : model_of(sc).c;
    tr_rng r;
    tr_rng_init(&r, 77, 0, 0);
    for (int a = 0; a < (int)(sizeof axes / sizeof axes[0]); ++a) {
        tr_vec3 dir = v3_normalize(axes[a]);
        int bad = 0;
        for (int i = 0; i < 20000; ++i) {
            tr_vec3 d = draw(sc, &r, dir);
            double len = v3_length(d);
            double z = ddot(dv(d), dv(dir));
            bad += !v3_is_finite(d) || fabs(len - 1.0) >= 1e-5 || z < zmin - 1e-5;
        }
        CHECK(bad == 0, "%s around axis %d: %d bad directions", sc->name, a, bad);
    }
}

/* The pdf the integrator would divide by agrees with the density the sampler draws. */
static void check_pdfs(void) {
    const float powers[] = {0.0f, 1.0f, 1.0f, 1.0f, 0.0f, 8.0f};
    const float angles[] = {TR_HALF_PI, TR_HALF_PI, 0.3f, 0.8f, 0.7f, 0.9f};
    for (int i = 0; i < 6; ++i) {
        sampler_case sc = {"pdf", LOBE, powers[i], angles[i]};
        zmodel m = model_of(&sc);
        double integral = 0.0, worst = 0.0;
        const int steps = 2000; /* midpoint rule; the error is far below the tolerance */
        for (int k = 0; k < steps; ++k) {
            double z = m.c + (1.0 - m.c) * (k + 0.5) / steps;
            double p = tr_pdf_cone(powers[i], angles[i], (float)z);
            /* d/dz of the model CDF, per unit solid angle (2 pi per unit z). */
            double want = (m.n + 1.0) * pow(z, m.n) / (1.0 - pow(m.c, m.n + 1.0)) / (2.0 * PI_D);
            worst = fmax(worst, fabs(p - want) / want);
            integral += 2.0 * PI_D * p * (1.0 - m.c) / steps;
        }
        /* Float evaluation of the closed form is good to a few ulps of 1 - c^(n+1). */
        CHECK(worst <= 1e-4, "tr_pdf_cone(power %g, angle %g) is off the model density by %.3g",
              (double)powers[i], (double)angles[i], worst);
        CHECK_NEAR(integral, 1.0, 1e-4, "tr_pdf_cone integrates to 1 over the cone");
        if (angles[i] < TR_HALF_PI) {
            float below = (float)(m.c - 1e-3);
            CHECK(tr_pdf_cone(powers[i], angles[i], below) == 0.0f,
                  "tr_pdf_cone is non-zero outside the cone (power %g, angle %g)",
                  (double)powers[i], (double)angles[i]);
        }
    }
    CHECK_NEAR(tr_pdf_uniform_sphere(), 1.0 / (4.0 * PI_D), 1e-8, "uniform sphere pdf");
    CHECK_NEAR(tr_pdf_cone(0.0f, TR_HALF_PI, 0.5f), 1.0 / (2.0 * PI_D), 1e-7,
               "uniform hemisphere pdf");
    CHECK_NEAR(tr_pdf_cone(1.0f, TR_HALF_PI, 0.5f), 0.5 / PI_D, 1e-7, "cosine hemisphere pdf");
}

/* Inverse of an odd number modulo 2^64 (Newton's iteration doubles the correct bits). */
static uint64_t inverse_mod_2_64(uint64_t a) {
    uint64_t x = a; /* correct to 3 bits, since a * a = 1 mod 8 for odd a */
    for (int i = 0; i < 5; ++i) {
        x *= 2 - a * x;
    }
    return x;
}

/* The inverse of w -> w ^ (w >> 30). */
static uint64_t unshift30(uint64_t y) {
    return y ^ (y >> 30) ^ (y >> 60);
}

/* A generator state whose output number `which` (0 or 1) is all ones, the value that
 * maps to the largest float: xorshift1024* with a zero neighbour word reduces to
 * w ^ (w >> 30) followed by the multiplier, both of which invert. */
static void rng_forcing_max(tr_rng *r, int which) {
    uint64_t w = ~(uint64_t)0 * inverse_mod_2_64((uint64_t)1181783497276652981ULL);
    for (int i = 0; i < 16; ++i) {
        r->s[i] = (uint64_t)i + 1;
    }
    r->p = 0;
    r->s[1] = 0;
    if (which == 0) {
        r->s[0] = unshift30(w);
    } else {
        r->s[2] = 0;
        r->s[0] = unshift30(unshift30(w));
    }
}

/* Uniform on [0,1)^2, never reaching 1, and the two coordinates independent. */
static void check_jitter(void) {
    enum { N = 400000, G = 16 };
    static long grid[G * G];
    long gx[G] = {0}, gy[G] = {0};
    moments mx = {0, 0.0, 0.0}, my = {0, 0.0, 0.0}, mxy = {0, 0.0, 0.0};
    tr_rng r;
    tr_rng_init(&r, 5, 6, 7);
    int out = 0;
    for (int i = 0; i < N; ++i) {
        float dx, dy;
        tr_sample_pixel_jitter(&r, &dx, &dy);
        if (!(dx >= 0.0f && dx < 1.0f && dy >= 0.0f && dy < 1.0f)) {
            ++out;
            continue;
        }
        int ix = (int)(dx * G), iy = (int)(dy * G);
        grid[iy * G + ix]++;
        gx[ix]++;
        gy[iy]++;
        moments_add(&mx, dx);
        moments_add(&my, dy);
        moments_add(&mxy, (dx - 0.5) * (dy - 0.5));
    }
    CHECK(out == 0, "%d jitter offsets outside [0,1)^2", out);
    double x_g = chi2_uniform(grid, G * G, N - out);
    double x_x = chi2_uniform(gx, G, N - out);
    double x_y = chi2_uniform(gy, G, N - out);
    double k_g = chi2_critical(G * G - 1), k_1 = chi2_critical(G - 1);
    CHECK(x_g < k_g, "jitter: chi-square on the %dx%d grid %.2f >= %.2f", G, G, x_g, k_g);
    CHECK(x_x < k_1, "jitter: chi-square of dx %.2f >= %.2f", x_x, k_1);
    CHECK(x_y < k_1, "jitter: chi-square of dy %.2f >= %.2f", x_y, k_1);
    check_mean(&mx, 0.5, "mean dx", "jitter", 0);
    check_mean(&my, 0.5, "mean dy", "jitter", 0);
    check_mean(&mxy, 0.0, "covariance of dx and dy", "jitter", 0);
    printf("%-26s       chi2 grid(%d) %6.2f (crit %.2f)  dx(%d) %6.2f  dy(%d) %6.2f (crit "
           "%.2f)\n",
           "pixel jitter", G * G - 1, x_g, k_g, G - 1, x_x, G - 1, x_y, k_1);

    /* The largest generator output, which random draws would almost never produce. */
    for (int which = 0; which < 2; ++which) {
        rng_forcing_max(&r, which);
        float dx, dy;
        tr_sample_pixel_jitter(&r, &dx, &dy);
        float hi = which == 0 ? dx : dy;
        CHECK(hi < 1.0f, "jitter from the maximal output reaches %.9g", (double)hi);
        CHECK(hi > 0.9999f, "the forced state did not produce the maximal output (%.9g)",
              (double)hi);
    }
}

int main(void) {
    const sampler_case cases[] = {
        {"uniform sphere", UNIFORM_SPHERE, 0.0f, 0.0f},
        {"uniform hemisphere", UNIFORM_HEMISPHERE, 0.0f, 0.0f},
        {"cosine hemisphere", COSINE_HEMISPHERE, 0.0f, 0.0f},
        {"cosine cone 0.3", COSINE_CONE, 1.0f, 0.3f},
        {"cosine cone 0.8", COSINE_CONE, 1.0f, 0.8f},
        {"cosine cone pi/2", COSINE_CONE, 1.0f, TR_HALF_PI},
        {"lobe power 0 angle pi/2", LOBE, 0.0f, TR_HALF_PI},
        {"lobe power 1 angle pi/2", LOBE, 1.0f, TR_HALF_PI},
        {"lobe power 0 angle 0.7", LOBE, 0.0f, 0.7f},
        {"lobe power 1 angle 1.1", LOBE, 1.0f, 1.1f},
        {"lobe power 8 angle 0.9", LOBE, 8.0f, 0.9f},
    };
    /* Non-axis directions on either side of the z = 0 switch in v3_basis. */
    const tr_vec3 dirs[] = {v3_normalize(v3(0.36f, -0.48f, 0.8f)),
                            v3_normalize(v3(-0.2f, 0.3f, -0.93f))};
    printf("chi-square critical values at p = 1e-4: dof %d: %.2f, dof %d: %.2f, dof %d: %.2f\n",
           Z_BINS - 1, chi2_critical(Z_BINS - 1), PHI_BINS - 1, chi2_critical(PHI_BINS - 1),
           JOINT_Z * JOINT_PHI - 1, chi2_critical(JOINT_Z * JOINT_PHI - 1));
    for (int c = 0; c < (int)(sizeof cases / sizeof cases[0]); ++c) {
        for (int d = 0; d < 2; ++d) {
            check_sampler(&cases[c], dirs[d], d, 1000 + (uint64_t)c);
        }
        check_sampler_axes(&cases[c]);
    }
    check_pdfs();
    check_jitter();
    return check_finish("test_sampling");
}
