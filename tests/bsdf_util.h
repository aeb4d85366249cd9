/* bsdf_util.h - what the BSDF tests share: directions on the unit sphere, reciprocity over
 * random pairs, a bit-for-bit comparison of two parameter sets, and albedo estimates. */
#ifndef TR_TEST_BSDF_UTIL_H
#define TR_TEST_BSDF_UTIL_H

#include "kernel/kernel.h"

#include <math.h>
#include <stdint.h>
#include <string.h>

#define BSDF_PI 3.14159265358979323846

/* The direction of cosine cos_t to +z and azimuth phi. */
static inline tr_vec3 dir_of(double cos_t, double phi) {
    double s = sqrt(fmax(0.0, 1.0 - cos_t * cos_t));
    return v3((float)(s * cos(phi)), (float)(s * sin(phi)), (float)cos_t);
}

/* Of 20000 random direction pairs (streams seed, 3, 4), how many give f(a, b) and f(b, a)
 * apart by more than 1e-3 of f(a, b) (at least 1e-6) in a channel; *nonzero counts the
 * pairs with f(a, b).x > 0. */
static inline int bsdf_not_reciprocal(const tr_bsdf_params *m, uint64_t seed, int *nonzero) {
    tr_rng rng;
    tr_rng_init(&rng, seed, 3, 4);
    int bad = 0;
    *nonzero = 0;
    for (int k = 0; k < 20000; ++k) {
        tr_vec3 a = dir_of(tr_rng_float(&rng), 2.0 * BSDF_PI * tr_rng_float(&rng));
        tr_vec3 b = dir_of(tr_rng_float(&rng), 2.0 * BSDF_PI * tr_rng_float(&rng));
        tr_vec3 fab = tr_bsdf_eval(m, a, b), fba = tr_bsdf_eval(m, b, a);
        *nonzero += fab.x > 0.0f;
        float scale = fmaxf(fab.x, 1e-6f);
        if (!(fabsf(fab.x - fba.x) <= 1e-3f * scale && fabsf(fab.y - fba.y) <= 1e-3f * scale &&
              fabsf(fab.z - fba.z) <= 1e-3f * scale)) {
            ++bad;
        }
    }
    return bad;
}

/* Of 2000 random (wo, wi, lobe numbers) from seed, how many give p0 and p1 a different
 * value, pdf or sample, bit for bit. */
static inline int bsdf_differences(const tr_bsdf_params *p0, const tr_bsdf_params *p1,
                                   uint64_t seed) {
    tr_rng rng;
    tr_rng_init(&rng, seed, seed + 1, seed + 2);
    int differ = 0;
    for (int k = 0; k < 2000; ++k) {
        tr_vec3 wo = dir_of(tr_rng_float(&rng), 2.0 * BSDF_PI * tr_rng_float(&rng));
        tr_vec3 wi = dir_of(tr_rng_float(&rng), 2.0 * BSDF_PI * tr_rng_float(&rng));
        tr_vec3 f0 = tr_bsdf_eval(p0, wo, wi), f1 = tr_bsdf_eval(p1, wo, wi);
        float q0 = tr_bsdf_pdf(p0, wo, wi), q1 = tr_bsdf_pdf(p1, wo, wi);
        float ul = tr_rng_float(&rng), u1 = tr_rng_float(&rng), u2 = tr_rng_float(&rng);
        tr_scatter s0, s1;
        memset(&s0, 0, sizeof s0);
        memset(&s1, 0, sizeof s1);
        int k0 = tr_bsdf_sample(p0, wo, ul, u1, u2, &s0);
        int k1 = tr_bsdf_sample(p1, wo, ul, u1, u2, &s1);
        differ += memcmp(&f0, &f1, sizeof f0) != 0 || memcmp(&q0, &q1, sizeof q0) != 0 ||
                  k0 != k1 || memcmp(&s0, &s1, sizeof s0) != 0;
    }
    return differ;
}

/* The albedo towards wo from n draws of rng: the sampler's mean weight (red channel) and a
 * uniform-hemisphere estimate of f cos, each with its standard error. With `inconsistent`
 * (may be NULL) it counts the samples whose pdf or weight is not tr_bsdf_pdf's or
 * eval cos / pdf within 1e-4, or that claim a delta lobe. Each sample draws five numbers. */
static inline void bsdf_albedo(const tr_bsdf_params *m, tr_vec3 wo, int n, tr_rng *rng,
                               double *sampled, double *se_sampled, double *uniform,
                               double *se_uniform, int *inconsistent) {
    double s1 = 0.0, s2 = 0.0, u1 = 0.0, u2 = 0.0;
    if (inconsistent) {
        *inconsistent = 0;
    }
    for (int k = 0; k < n; ++k) {
        tr_scatter s;
        double w = 0.0;
        if (tr_bsdf_sample(m, wo, tr_rng_float(rng), tr_rng_float(rng), tr_rng_float(rng), &s)) {
            w = s.weight.x;
            if (inconsistent) {
                const float pdf = tr_bsdf_pdf(m, wo, s.wi);
                const float ww = tr_bsdf_eval(m, wo, s.wi).x * s.wi.z / pdf;
                *inconsistent += s.delta || !(fabsf(pdf - s.pdf) <= 1e-4f * pdf) ||
                                 !(fabsf(ww - s.weight.x) <= 1e-4f * fmaxf(1.0f, ww));
            }
        }
        s1 += w;
        s2 += w * w;
        const tr_vec3 d = dir_of(tr_rng_float(rng), 2.0 * BSDF_PI * tr_rng_float(rng));
        const double v = tr_bsdf_eval(m, wo, d).x * d.z * 2.0 * BSDF_PI;
        u1 += v;
        u2 += v * v;
    }
    *sampled = s1 / n;
    *se_sampled = sqrt(fmax(0.0, s2 / n - *sampled * *sampled) / n);
    *uniform = u1 / n;
    *se_uniform = sqrt(fmax(0.0, u2 / n - *uniform * *uniform) / n);
}

#endif
