/* sun.h - the sun: a distant disc of uniform radiance seen under a small cone of
 * directions (tr_sun in attrib.h), the light of a directional lamp with an angular size.
 *
 * Next-event estimation draws directions uniformly in the cone (pdf 1 / (2 pi (1 - cos t))
 * in solid angle); a BSDF ray that leaves the scene inside the cone sees the sun, so the
 * two strategies combine by Veach's power heuristic like the other lights (thesis,
 * chapter 9). In the naive integrator only escaping rays find it. */
#ifndef TR_KERNEL_SUN_H
#define TR_KERNEL_SUN_H

#include "attrib.h"
#include "bsdf.h"
#include "compat.h"
#include "material.h"
#include "material_eval.h"
#include "sampler.h"
#include "scene_view.h"
#include "types.h"
#include "vec.h"

/* The sun's dimension pair at segment seg: outside every per-bounce block of sampler.h
 * (the sampler hashes any dimension number), so that a scene without a sun draws the
 * very numbers it drew before the sun existed. */
TR_FN uint32_t tr_sun_dim(int seg) {
    return 0x00800000u + (uint32_t)seg;
}

/* Whether the unit direction d lies inside the cone: |d - dir|^2 = 2 (1 - cos), which
 * keeps its precision for discs far smaller than a float's 1 - cos resolves. */
TR_FN int tr_sun_contains(TR_CONST_GLOBAL tr_sun *sun, tr_vec3 d) {
    tr_vec3 e = v3_sub(d, sun->dir);
    return v3_dot(e, e) <= 2.0f * sun->one_minus_cos;
}

/* Radiance arriving along -d from direction d (unit) of an escaping ray. */
TR_FN tr_vec3 tr_sun_radiance(const tr_scene_view *s, tr_vec3 d) {
    TR_CONST_GLOBAL tr_sun *sun = &s->sun[0];
    return tr_sun_contains(sun, d) ? sun->radiance : v3s(0.0f);
}

/* Solid-angle density with which tr_sun_sample draws d. */
TR_FN float tr_sun_pdf(const tr_scene_view *s, tr_vec3 d) {
    TR_CONST_GLOBAL tr_sun *sun = &s->sun[0];
    return tr_sun_contains(sun, d) ? sun->pdf : 0.0f;
}

/* A direction uniform in the cone from u1, u2 in [0, 1): cos = 1 - u1 (1 - cos t), with
 * sin^2 = x (2 - x) for x = u1 (1 - cos t) to keep small cones precise. */
TR_FN tr_vec3 tr_sun_sample(const tr_scene_view *s, float u1, float u2, tr_vec3 *d, float *pdf) {
    TR_CONST_GLOBAL tr_sun *sun = &s->sun[0];
    float x = u1 * sun->one_minus_cos;
    float c = 1.0f - x;
    float st = tr_sqrtf(tr_fmaxf(0.0f, x * (2.0f - x)));
    float phi = TR_TWO_PI * u2;
    tr_vec3 t, b;
    v3_basis(sun->dir, &t, &b);
    *d = v3_normalize(v3_add(v3_scale(sun->dir, c), v3_add(v3_scale(t, st * tr_cosf(phi)),
                                                           v3_scale(b, st * tr_sinf(phi)))));
    *pdf = sun->pdf;
    return sun->radiance;
}

/* One light sample of the sun from the non-delta surface m at p (outgoing wo), weighted
 * against BSDF sampling by the power heuristic: f L cos w / pdf, before the path's
 * throughput. *rays counts the shadow ray. */
TR_FN tr_vec3 tr_sun_nee(const tr_scene_view *s, const tr_bsdf_params *m, tr_vec3 wo, tr_vec3 p,
                         float u1, float u2, uint32_t *rays) {
    tr_vec3 wi;
    float pl;
    tr_vec3 le = tr_sun_sample(s, u1, u2, &wi, &pl);
    tr_vec3 f = tr_bsdf_eval(m, wo, wi);
    if (!(pl > 0.0f) || (f.x == 0.0f && f.y == 0.0f && f.z == 0.0f)) {
        return v3s(0.0f);
    }
    tr_ray shadow = tr_ray_make(tr_surface_origin(m, p, wi), wi, 0.0f, TR_INFINITY);
    *rays += 1;
    if (tr_occluded_masked(s, &shadow)) {
        return v3s(0.0f);
    }
    float pb = tr_bsdf_pdf(m, wo, wi);
    float w = pl * pl / (pl * pl + pb * pb);
    return v3_scale(v3_mul(f, le), tr_fabsf(v3_dot(wi, m->ns)) * w / pl);
}

#endif
