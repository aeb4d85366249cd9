/* ggx_ms.h - multiple scattering for the GGX conductor lobe (Kulla and Conty, "Revisiting
 * Physically Based Shading at Imageworks", SIGGRAPH 2017 course).
 *
 * Single-scattering GGX loses the light that bounces between microfacets more than once:
 * its directional albedo E(mu) (with a white Fresnel) falls below 1 as alpha grows. The
 * compensation adds the lobe
 *
 *   f_ms = F_ms (1 - E(mu_o)) (1 - E(mu_i)) / (pi (1 - E_avg)),
 *   E_avg = 2 int_0^1 E(mu) mu dmu,
 *   F_ms = F_avg^2 E_avg / (1 - F_avg (1 - E_avg)),  F_avg = F0 + (1 - F0) / 21,
 *
 * which is reciprocal, makes a white conductor's albedo 1 at every angle (E + (1 - E) = 1)
 * and, for a coloured one, adds the light of the bounces that each multiply it by F_avg
 * (F_avg is Schlick's Fresnel's cosine-weighted mean). E and E_avg come from a table that
 * the host computes when a scene first needs it (src/scene/ggx_ms.c, by integrating this
 * kernel's own single-scattering lobe): TR_GGX_MS_N values of mu by TR_GGX_MS_N of alpha,
 * then E_avg at each alpha, read with bilinear interpolation. A material asks for it with
 * TR_MATERIAL_MULTISCATTER; the material stage hands the table to the BSDF
 * (tr_bsdf_params.ms), NULL where the scene has none. */
#ifndef TR_KERNEL_GGX_MS_H
#define TR_KERNEL_GGX_MS_H

#include "compat.h"
#include "vec.h"

#define TR_GGX_MS_N 32
/* The table's parts, one after the other: E with a white Fresnel (N x N) and its E_avg
 * (N); the part of E weighted by Schlick's (1 - wo.h)^5 (N x N: the layer's albedo with F0
 * f0 is f0 E + (1 - f0) E_5, Schlick's term being linear in F0) and its average (N); the
 * Charlie sheen lobe's albedo (N x N, bsdf_principled.h), by mu and sheen roughness. */
#define TR_GGX_MS_E5 (TR_GGX_MS_N * TR_GGX_MS_N + TR_GGX_MS_N)
#define TR_GGX_MS_SHEEN (2 * TR_GGX_MS_E5)
#define TR_GGX_MS_COAT (TR_GGX_MS_SHEEN + TR_GGX_MS_N * TR_GGX_MS_N)
/* Last, the clear coat's albedo (F0 0.04) averaged over the directions a GGX lobe under it
 * reflects light arriving at mu to: TR_GGX_MS_NA values of the lobe's alpha by
 * TR_GGX_MS_NA of the coat's alpha by TR_GGX_MS_N of mu (bsdf_principled.h). */
#define TR_GGX_MS_NA 16
#define TR_GGX_MS_COUNT (TR_GGX_MS_COAT + TR_GGX_MS_NA * TR_GGX_MS_NA * TR_GGX_MS_N)

/* The table's nodes: mu_i = max(i / (N - 1), TR_GGX_MS_MU0), alpha_j = j / (N - 1) (alpha
 * below TR_GGX_MIN_ALPHA counts as it, bsdf.h). */
#define TR_GGX_MS_MU0 1e-3f

/* Position x in [0, 1] on an axis of n nodes: the lower node and the weight of the next. */
TR_FN int tr_ggx_ms_cell_n(float x, int n, float *w) {
    float t = tr_fminf(tr_fmaxf(x, 0.0f), 1.0f) * (float)(n - 1);
    int i = (int)t;
    if (i > n - 2) {
        i = n - 2;
    }
    *w = t - (float)i;
    return i;
}

TR_FN int tr_ggx_ms_cell(float x, float *w) {
    return tr_ggx_ms_cell_n(x, TR_GGX_MS_N, w);
}

/* E(mu, alpha): the single-scattering lobe's directional albedo with a white Fresnel (the
 * table's first part; the other N x N parts read the same way from their offsets). */
TR_FN float tr_ggx_ms_e(TR_CONST_GLOBAL float *table, float mu, float alpha) {
    float wm, wa;
    const int i = tr_ggx_ms_cell(mu, &wm), j = tr_ggx_ms_cell(alpha, &wa);
    TR_CONST_GLOBAL float *r0 = table + j * TR_GGX_MS_N;
    TR_CONST_GLOBAL float *r1 = r0 + TR_GGX_MS_N;
    const float e0 = r0[i] + (r0[i + 1] - r0[i]) * wm;
    const float e1 = r1[i] + (r1[i + 1] - r1[i]) * wm;
    return e0 + (e1 - e0) * wa;
}

/* E_avg(alpha). */
TR_FN float tr_ggx_ms_eavg(TR_CONST_GLOBAL float *table, float alpha) {
    float wa;
    const int j = tr_ggx_ms_cell(alpha, &wa);
    TR_CONST_GLOBAL float *a = table + TR_GGX_MS_N * TR_GGX_MS_N;
    return a[j] + (a[j + 1] - a[j]) * wa;
}

/* The single-scattering GGX layer's directional albedo with Schlick's Fresnel of F0 f0
 * (scalar): f0 E + (1 - f0) E_5. */
TR_FN float tr_ggx_ms_layer_e(TR_CONST_GLOBAL float *table, float mu, float alpha, float f0) {
    return f0 * tr_ggx_ms_e(table, mu, alpha) +
           (1.0f - f0) * tr_ggx_ms_e(table + TR_GGX_MS_E5, mu, alpha);
}

/* Its cosine-weighted average over mu. */
TR_FN float tr_ggx_ms_layer_eavg(TR_CONST_GLOBAL float *table, float alpha, float f0) {
    return f0 * tr_ggx_ms_eavg(table, alpha) +
           (1.0f - f0) * tr_ggx_ms_eavg(table + TR_GGX_MS_E5, alpha);
}

/* The coat's albedo averaged over the lobe of alpha ab's directions from mu, under a coat
 * of alpha ac (the table's last part, trilinear). */
TR_FN float tr_ggx_ms_coat_e(TR_CONST_GLOBAL float *table, float mu, float ab, float ac) {
    float wm, wb, wc;
    const int i = tr_ggx_ms_cell(mu, &wm);
    const int jb = tr_ggx_ms_cell_n(ab, TR_GGX_MS_NA, &wb);
    const int jc = tr_ggx_ms_cell_n(ac, TR_GGX_MS_NA, &wc);
    float v[4];
    for (int q = 0; q < 4; ++q) {
        TR_CONST_GLOBAL float *r =
            table + TR_GGX_MS_COAT + ((jb + (q >> 1)) * TR_GGX_MS_NA + jc + (q & 1)) * TR_GGX_MS_N;
        v[q] = r[i] + (r[i + 1] - r[i]) * wm;
    }
    const float b0 = v[0] + (v[1] - v[0]) * wc, b1 = v[2] + (v[3] - v[2]) * wc;
    return b0 + (b1 - b0) * wb;
}

/* The compensation lobe's colour F_ms for Fresnel F0 f0 and E_avg eavg (Kulla and Conty
 * 2017): F_avg^2 E_avg / (1 - F_avg (1 - E_avg)), F_avg Schlick's cosine-weighted mean. */
TR_FN tr_vec3 tr_ggx_ms_fm(tr_vec3 f0, float eavg) {
    const tr_vec3 favg = v3_add(f0, v3_scale(v3_sub(v3s(1.0f), f0), 1.0f / 21.0f));
    return v3(favg.x * favg.x * eavg / (1.0f - favg.x * (1.0f - eavg)),
              favg.y * favg.y * eavg / (1.0f - favg.y * (1.0f - eavg)),
              favg.z * favg.z * eavg / (1.0f - favg.z * (1.0f - eavg)));
}

/* f_ms for cosines co, ci > 0 and Fresnel F0 f0. Its albedo towards co is F_ms (1 - E(co)). */
TR_FN tr_vec3 tr_ggx_ms_lobe(TR_CONST_GLOBAL float *table, float alpha, tr_vec3 f0, float co,
                             float ci) {
    const float eavg = tr_ggx_ms_eavg(table, alpha);
    if (!(eavg < 0.9999f)) {
        return v3s(0.0f);
    }
    const float fms = (1.0f - tr_ggx_ms_e(table, co, alpha)) *
                      (1.0f - tr_ggx_ms_e(table, ci, alpha)) / (TR_PI * (1.0f - eavg));
    return v3_scale(tr_ggx_ms_fm(f0, eavg), tr_fmaxf(fms, 0.0f));
}

#endif
