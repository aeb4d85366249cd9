/* dfg.c - the GGX directional-albedo table (dfg.h). */
#include "post/dfg.h"

#include <pthread.h>

#include "kernel/bsdf.h"

float tr_post_dfg_mu(int i) {
    return tr_fmaxf((float)i / (float)(TR_DFG_N - 1), 1e-3f);
}

float tr_post_dfg_alpha(int j) {
    return tr_fmaxf((float)j / (float)(TR_DFG_N - 1), TR_GGX_MIN_ALPHA);
}

void tr_post_dfg_node(int i, int j, int s, float *a, float *b) {
    const float mu = tr_post_dfg_mu(i), alpha = tr_post_dfg_alpha(j);
    /* wo in the local frame (normal +z). */
    const tr_vec3 wo = v3(tr_sqrtf(tr_fmaxf(0.0f, 1.0f - mu * mu)), 0.0f, mu);
    const float g1 = 1.0f / (1.0f + tr_ggx_lambda(alpha, mu));
    double sa = 0.0, sb = 0.0;
    for (int v = 0; v < s; ++v) {
        for (int u = 0; u < s; ++u) {
            const float u1 = ((float)u + 0.5f) / (float)s, u2 = ((float)v + 0.5f) / (float)s;
            const tr_vec3 h = tr_ggx_sample_vndf(alpha, wo, u1, u2);
            const float oh = v3_dot(wo, h);
            const tr_vec3 wi = v3_sub(v3_scale(h, 2.0f * oh), wo);
            if (!(wi.z > 0.0f) || !(oh > 0.0f)) {
                continue; /* below the surface: f is zero there */
            }
            const float g2 = 1.0f / (1.0f + tr_ggx_lambda(alpha, mu) + tr_ggx_lambda(alpha, wi.z));
            const float wgt = g2 / g1;
            const float c = 1.0f - oh;
            const float fc = (c * c) * (c * c) * c;
            sa += (double)(wgt * (1.0f - fc));
            sb += (double)(wgt * fc);
        }
    }
    *a = (float)(sa / ((double)s * s));
    *b = (float)(sb / ((double)s * s));
}

static float dfg_table[2 * TR_DFG_N * TR_DFG_N];
static pthread_once_t dfg_once = PTHREAD_ONCE_INIT;

static void dfg_build(void) {
    for (int j = 0; j < TR_DFG_N; ++j) {
        for (int i = 0; i < TR_DFG_N; ++i) {
            const int k = 2 * (j * TR_DFG_N + i);
            tr_post_dfg_node(i, j, TR_DFG_SAMPLES, &dfg_table[k], &dfg_table[k + 1]);
        }
    }
}

const float *tr_post_dfg_table(void) {
    pthread_once(&dfg_once, dfg_build);
    return dfg_table;
}

void tr_post_dfg_lookup(const float *table, float mu, float alpha, float *a, float *b) {
    tr_post_dfg_at(table, mu, alpha, a, b);
}
