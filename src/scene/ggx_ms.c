/* ggx_ms.c - the table of GGX's directional albedo that multiple-scattering compensation
 * reads (src/kernel/ggx_ms.h), computed once per process by integrating the kernel's own
 * single-scattering lobe: no copied numbers. */
#include <pthread.h>

#include "kernel/bsdf.h"
#include "scene/scene_internal.h"
#include "trac0r/render.h"

/* Stratified samples per integral: K x K jittered-free cell centres of the visible-normal
 * sampler's square. */
#define MS_K 32
/* mu values of E_avg's midpoint rule. */
#define MS_AVG_MU 64

static float ms_table[TR_GGX_MS_COUNT];
static pthread_once_t ms_once = PTHREAD_ONCE_INIT;

/* E(mu, alpha) with a white Fresnel: the mean of the visible-normal sampler's weight
 * G2 / G1(wo) (the reflection below the horizon counts 0); in *e5 the same weighted by
 * Schlick's (1 - wo.h)^5. */
static double albedo(double mu, float alpha, double *e5) {
    const float m = (float)mu;
    const tr_vec3 wo = v3(sqrtf(fmaxf(0.0f, 1.0f - m * m)), 0.0f, m);
    const float lo = tr_ggx_lambda(alpha, m);
    double sum = 0.0, sum5 = 0.0;
    for (int a = 0; a < MS_K; ++a) {
        for (int b = 0; b < MS_K; ++b) {
            const tr_vec3 h =
                tr_ggx_sample_vndf(alpha, wo, ((float)a + 0.5f) / MS_K, ((float)b + 0.5f) / MS_K);
            const tr_vec3 wi = v3_reflect(v3_neg(wo), h);
            if (wi.z > 0.0f) {
                const double g = (1.0 + lo) / (1.0 + lo + tr_ggx_lambda(alpha, wi.z));
                const double c = 1.0 - fmin(fmax((double)v3_dot(wo, h), 0.0), 1.0);
                sum += g;
                sum5 += (c * c) * (c * c) * c * g;
            }
        }
    }
    *e5 = sum5 / (MS_K * MS_K);
    return sum / (MS_K * MS_K);
}

/* The first two N x N tables and their averages. */
static void ms_build_albedos(void) {
    /* Each row is its own integrals, written to its own entries: the same numbers for any
     * thread count. */
#pragma omp parallel for schedule(dynamic) num_threads(tr_default_threads())
    for (int j = 0; j < TR_GGX_MS_N; ++j) {
        const float alpha = fmaxf((float)j / (TR_GGX_MS_N - 1), TR_GGX_MIN_ALPHA);
        double e5;
        for (int i = 0; i < TR_GGX_MS_N; ++i) {
            const double mu = fmax((double)i / (TR_GGX_MS_N - 1), TR_GGX_MS_MU0);
            ms_table[j * TR_GGX_MS_N + i] = (float)albedo(mu, alpha, &e5);
            ms_table[TR_GGX_MS_E5 + j * TR_GGX_MS_N + i] = (float)e5;
        }
        double avg = 0.0, avg5 = 0.0;
        for (int i = 0; i < MS_AVG_MU; ++i) {
            const double mu = (i + 0.5) / MS_AVG_MU;
            avg += 2.0 * albedo(mu, alpha, &e5) * mu / MS_AVG_MU;
            avg5 += 2.0 * e5 * mu / MS_AVG_MU;
        }
        ms_table[TR_GGX_MS_N * TR_GGX_MS_N + j] = (float)avg;
        ms_table[TR_GGX_MS_E5 + TR_GGX_MS_N * TR_GGX_MS_N + j] = (float)avg5;
    }
}

/* The Charlie sheen lobe's albedo E(mu, r) (bsdf_principled.h) with a white colour: the
 * midpoint rule over the hemisphere, cos theta_i by SHEEN_K and phi by 2 SHEEN_K cells
 * (its lobe is broad and smooth). */
#define SHEEN_K 32
static double sheen_albedo(double mu, float r) {
    const tr_vec3 wo = v3((float)sqrt(fmax(0.0, 1.0 - mu * mu)), 0.0f, (float)mu);
    double sum = 0.0;
    for (int a = 0; a < SHEEN_K; ++a) {
        const double ci = (a + 0.5) / SHEEN_K, si = sqrt(fmax(0.0, 1.0 - ci * ci));
        for (int b = 0; b < 2 * SHEEN_K; ++b) {
            const double phi = 3.14159265358979323846 * (b + 0.5) / SHEEN_K;
            const tr_vec3 wi = v3((float)(si * cos(phi)), (float)(si * sin(phi)), (float)ci);
            sum += tr_sheen_lobe(r, wo, wi, (float)mu, (float)ci) * ci;
        }
    }
    /* d omega = d(cos) d(phi): (1 / K) (pi / K) per cell. */
    return sum * 3.14159265358979323846 / ((double)SHEEN_K * SHEEN_K);
}

/* <E_c>: the coat layer's albedo (F0 0.04, alpha ac; read from the table's first two
 * parts, built before) over the directions the lobe of alpha ab reflects light arriving at
 * mu to, weighted as the lobe (G2 / G1 of COAT_K x COAT_K visible normals: a smooth mean,
 * coarser than the albedos'). */
#define COAT_K 16
static double coat_over_lobe(double mu, float ab, float ac) {
    const float m = (float)mu;
    const tr_vec3 wo = v3(sqrtf(fmaxf(0.0f, 1.0f - m * m)), 0.0f, m);
    const float lo = tr_ggx_lambda(ab, m);
    double num = 0.0, den = 0.0;
    for (int a = 0; a < COAT_K; ++a) {
        for (int b = 0; b < COAT_K; ++b) {
            const tr_vec3 h =
                tr_ggx_sample_vndf(ab, wo, ((float)a + 0.5f) / COAT_K, ((float)b + 0.5f) / COAT_K);
            const tr_vec3 wi = v3_reflect(v3_neg(wo), h);
            if (wi.z > 0.0f) {
                const double g = (1.0 + lo) / (1.0 + lo + tr_ggx_lambda(ab, wi.z));
                num += g * tr_ggx_ms_layer_e(ms_table, wi.z, ac, TR_PRINCIPLED_F0);
                den += g;
            }
        }
    }
    return den > 0.0 ? num / den : tr_ggx_ms_layer_e(ms_table, m, ac, TR_PRINCIPLED_F0);
}

static void ms_build(void) {
    ms_build_albedos();
#pragma omp parallel for schedule(dynamic) num_threads(tr_default_threads())
    for (int j = 0; j < TR_GGX_MS_N; ++j) {
        const float r = (float)j / (TR_GGX_MS_N - 1);
        for (int i = 0; i < TR_GGX_MS_N; ++i) {
            const double mu = fmax((double)i / (TR_GGX_MS_N - 1), TR_GGX_MS_MU0);
            ms_table[TR_GGX_MS_SHEEN + j * TR_GGX_MS_N + i] = (float)sheen_albedo(mu, r);
        }
    }
    /* The coat's part reads the albedos above, complete by now. */
#pragma omp parallel for schedule(dynamic) num_threads(tr_default_threads())
    for (int jb = 0; jb < TR_GGX_MS_NA; ++jb) {
        const float ab = fmaxf((float)jb / (TR_GGX_MS_NA - 1), TR_GGX_MIN_ALPHA);
        for (int jc = 0; jc < TR_GGX_MS_NA; ++jc) {
            const float ac = fmaxf((float)jc / (TR_GGX_MS_NA - 1), TR_GGX_MIN_ALPHA);
            for (int i = 0; i < TR_GGX_MS_N; ++i) {
                const double mu = fmax((double)i / (TR_GGX_MS_N - 1), TR_GGX_MS_MU0);
                ms_table[TR_GGX_MS_COAT + (jb * TR_GGX_MS_NA + jc) * TR_GGX_MS_N + i] =
                    (float)coat_over_lobe(mu, ab, ac);
            }
        }
    }
}

const float *tr_ggx_ms_table(void) {
    pthread_once(&ms_once, ms_build);
    return ms_table;
}
