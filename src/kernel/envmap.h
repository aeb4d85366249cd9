/* envmap.h - the environment light: radiance from directions that leave the scene,
 * sampled for next-event estimation.
 *
 * A constant environment is sampled uniformly over the sphere. A map is equirectangular:
 * texel (i, j) of a W x H map covers u in [i, i+1)/W, v in [j, j+1)/H with the local
 * direction (sin t sin p, cos t, -sin t cos p), t = v pi (row 0 at +y), p = (u - 1/2) 2 pi
 * (the map's centre column looks down -z). It is sampled by a piecewise-constant 2D
 * distribution over (u, v) with weights luminance x sin t at the row's centre, drawn by
 * inverting the marginal CDF of the rows and then the chosen row's CDF (Pharr, Jakob and
 * Humphreys, Physically Based Rendering, 3rd ed., sections 13.6.7 and 14.2.4); the density
 * in solid angle is p(u, v) / (2 pi^2 sin t). Radiance lookups take the nearest texel, so
 * the sampled density follows the radiance texel for texel. The samplers take their
 * uniform numbers explicitly. */
#ifndef TR_KERNEL_ENVMAP_H
#define TR_KERNEL_ENVMAP_H

#include "attrib.h"
#include "compat.h"
#include "scene_view.h"
#include "types.h"
#include "vec.h"

TR_FN float tr_env_luminance(tr_vec3 c) {
    return 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z;
}

/* World direction to the map's frame (the rotation undone) and back. */
TR_FN tr_vec3 tr_env_to_local(TR_CONST_GLOBAL tr_env *e, tr_vec3 d) {
    return v3(e->rot_cos * d.x - e->rot_sin * d.z, d.y, e->rot_sin * d.x + e->rot_cos * d.z);
}
TR_FN tr_vec3 tr_env_to_world(TR_CONST_GLOBAL tr_env *e, tr_vec3 l) {
    return v3(e->rot_cos * l.x + e->rot_sin * l.z, l.y, -e->rot_sin * l.x + e->rot_cos * l.z);
}

/* The texel a unit local direction falls in, and sin t there. */
TR_FN uint32_t tr_env_texel_of(TR_CONST_GLOBAL tr_env *e, tr_vec3 l, float *sin_t) {
    float y = tr_fminf(tr_fmaxf(l.y, -1.0f), 1.0f);
    float t = tr_acosf(y);
    float p = tr_atan2f(l.x, -l.z);
    float u = 0.5f + p * (0.5f * TR_INV_PI), v = t * TR_INV_PI;
    uint32_t i = (uint32_t)tr_fminf(tr_fmaxf(u * (float)e->width, 0.0f), (float)e->width - 1.0f);
    uint32_t j = (uint32_t)tr_fminf(tr_fmaxf(v * (float)e->height, 0.0f), (float)e->height - 1.0f);
    *sin_t = tr_sqrtf(tr_fmaxf(0.0f, 1.0f - y * y));
    return j * e->width + i;
}

TR_FN tr_vec3 tr_env_texel(const tr_scene_view *s, uint32_t k) {
    return v3(s->env_texels[3u * k], s->env_texels[3u * k + 1u], s->env_texels[3u * k + 2u]);
}

/* Radiance arriving along -d, from the environment in direction d (unit). */
TR_FN_NOINLINE tr_vec3 tr_env_radiance(const tr_scene_view *s, tr_vec3 d) {
    TR_CONST_GLOBAL tr_env *e = &s->env[0];
    tr_vec3 c = v3_scale(e->color, e->strength);
    if (e->width == 0u) {
        return c;
    }
    float sin_t;
    uint32_t k = tr_env_texel_of(e, tr_env_to_local(e, d), &sin_t);
    return v3_mul(c, tr_env_texel(s, k));
}

/* Sampling weight of texel k (row j): luminance x sin t at the row's centre. */
TR_FN float tr_env_weight(const tr_scene_view *s, uint32_t k, uint32_t j) {
    TR_CONST_GLOBAL tr_env *e = &s->env[0];
    float st = tr_sinf(((float)j + 0.5f) * TR_PI / (float)e->height);
    return tr_fmaxf(tr_env_luminance(tr_env_texel(s, k)), 0.0f) * st;
}

/* Solid-angle density with which tr_env_sample draws direction d. */
TR_FN_NOINLINE float tr_env_pdf(const tr_scene_view *s, tr_vec3 d) {
    TR_CONST_GLOBAL tr_env *e = &s->env[0];
    if (e->width == 0u) {
        return 0.25f * TR_INV_PI;
    }
    if (!(e->weight_sum > 0.0f)) {
        return 0.0f;
    }
    float sin_t;
    uint32_t k = tr_env_texel_of(e, tr_env_to_local(e, d), &sin_t);
    if (!(sin_t > 0.0f)) {
        return 0.0f;
    }
    float p_uv =
        tr_env_weight(s, k, k / e->width) * (float)e->width * (float)e->height / e->weight_sum;
    return p_uv / (2.0f * TR_PI * TR_PI * sin_t);
}

/* The last index in cdf[0 .. n] (non-decreasing, cdf[0] = 0, cdf[n] = 1) with
 * cdf[index] <= u, for u in [0, 1): the piece u falls in. */
TR_FN uint32_t tr_env_find(const tr_scene_view *s, uint32_t first, uint32_t n, float u) {
    uint32_t lo = 0u, hi = n - 1u;
    while (lo < hi) {
        uint32_t mid = lo + (hi - lo + 1u) / 2u;
        if (s->env_cdf[first + mid] <= u) {
            lo = mid;
        } else {
            hi = mid - 1u;
        }
    }
    return lo;
}

/* Draws a direction *d from uniform numbers u1, u2 in [0, 1); *pdf its solid-angle
 * density (0: none drawn). Returns the radiance from there. */
TR_FN_NOINLINE tr_vec3 tr_env_sample(const tr_scene_view *s, float u1, float u2, tr_vec3 *d,
                                     float *pdf) {
    TR_CONST_GLOBAL tr_env *e = &s->env[0];
    if (e->width == 0u) {
        float z = 1.0f - 2.0f * u1;
        float r = tr_sqrtf(tr_fmaxf(0.0f, 1.0f - z * z));
        float phi = TR_TWO_PI * u2;
        *d = v3(r * tr_cosf(phi), r * tr_sinf(phi), z);
        *pdf = 0.25f * TR_INV_PI;
        return v3_scale(e->color, e->strength);
    }
    *pdf = 0.0f;
    *d = v3(0.0f, 1.0f, 0.0f);
    if (!(e->weight_sum > 0.0f)) {
        return v3s(0.0f);
    }
    uint32_t w = e->width, h = e->height;
    uint32_t j = tr_env_find(s, 0u, h, u2);
    float m0 = s->env_cdf[j], m1 = s->env_cdf[j + 1u];
    if (!(m1 > m0)) {
        return v3s(0.0f);
    }
    float dv = (u2 - m0) / (m1 - m0);
    uint32_t row = (h + 1u) + j * (w + 1u);
    uint32_t i = tr_env_find(s, row, w, u1);
    float c0 = s->env_cdf[row + i], c1 = s->env_cdf[row + i + 1u];
    if (!(c1 > c0)) {
        return v3s(0.0f);
    }
    float du = (u1 - c0) / (c1 - c0);
    float u = ((float)i + tr_fminf(du, 0.99999f)) / (float)w;
    float v = ((float)j + tr_fminf(dv, 0.99999f)) / (float)h;
    float t = v * TR_PI, p = (u - 0.5f) * TR_TWO_PI;
    float st = tr_sinf(t);
    tr_vec3 l = v3(st * tr_sinf(p), tr_cosf(t), -st * tr_cosf(p));
    *d = v3_normalize(tr_env_to_world(e, l));
    *pdf = tr_env_pdf(s, *d);
    return tr_env_radiance(s, *d);
}

#endif
