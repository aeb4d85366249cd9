/* ggx_ms.c - the table of GGX's directional albedo that multiple-scattering compensation
 * reads (src/kernel/ggx_ms.h), computed once per process by integrating the kernel's own
 * single-scattering lobe: no copied numbers. */
#include <pthread.h>

#include "kernel/bsdf.h"
#include "scene/scene_internal.h"

/* Stratified samples per integral: K x K jittered-free cell centres of the visible-normal
 * sampler's square. */
#define MS_K 32
/* mu values of E_avg's midpoint rule. */
#define MS_AVG_MU 64

static float ms_table[TR_GGX_MS_COUNT];
static pthread_once_t ms_once = PTHREAD_ONCE_INIT;

/* E(mu, alpha) with a white Fresnel: the mean of the visible-normal sampler's weight
 * G2 / G1(wo) (the reflection below the horizon counts 0). */
static double albedo(double mu, float alpha) {
    const float m = (float)mu;
    const tr_vec3 wo = v3(sqrtf(fmaxf(0.0f, 1.0f - m * m)), 0.0f, m);
    const float lo = tr_ggx_lambda(alpha, m);
    double sum = 0.0;
    for (int a = 0; a < MS_K; ++a) {
        for (int b = 0; b < MS_K; ++b) {
            const tr_vec3 h =
                tr_ggx_sample_vndf(alpha, wo, ((float)a + 0.5f) / MS_K, ((float)b + 0.5f) / MS_K);
            const tr_vec3 wi = v3_reflect(v3_neg(wo), h);
            if (wi.z > 0.0f) {
                sum += (1.0 + lo) / (1.0 + lo + tr_ggx_lambda(alpha, wi.z));
            }
        }
    }
    return sum / (MS_K * MS_K);
}

static void ms_build(void) {
    for (int j = 0; j < TR_GGX_MS_N; ++j) {
        const float alpha = fmaxf((float)j / (TR_GGX_MS_N - 1), TR_GGX_MIN_ALPHA);
        for (int i = 0; i < TR_GGX_MS_N; ++i) {
            const double mu = fmax((double)i / (TR_GGX_MS_N - 1), TR_GGX_MS_MU0);
            ms_table[j * TR_GGX_MS_N + i] = (float)albedo(mu, alpha);
        }
        double avg = 0.0;
        for (int i = 0; i < MS_AVG_MU; ++i) {
            const double mu = (i + 0.5) / MS_AVG_MU;
            avg += 2.0 * albedo(mu, alpha) * mu / MS_AVG_MU;
        }
        ms_table[TR_GGX_MS_N * TR_GGX_MS_N + j] = (float)avg;
    }
}

const float *tr_ggx_ms_table(void) {
    pthread_once(&ms_once, ms_build);
    return ms_table;
}
