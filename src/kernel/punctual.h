/* punctual.h - point, spot and directional lights (tr_punctual in attrib.h): delta
 * lights, of no area and no solid angle.
 *
 * A BSDF sample never finds a delta light, so next-event estimation is their only
 * strategy and its weight is 1 (no MIS). A scene of a few of them sends a shadow ray to
 * each at every vertex; with more, one light is picked per vertex by the lights' power CDF
 * (src/scene/punctual.c), one shadow ray is traced towards it, and its contribution is
 * divided by the pick's probability. Naive path tracing, which has no
 * next-event estimation, cannot see them (the host refuses it for a scene with punctual
 * lights); bdpt and vcm also start light subpaths from them and weigh this light sample
 * as one of their strategies (integrator_bdpt.h). */
#ifndef TR_KERNEL_PUNCTUAL_H
#define TR_KERNEL_PUNCTUAL_H

#include "attrib.h"
#include "bsdf.h"
#include "compat.h"
#include "light_tree.h"
#include "material.h"
#include "material_eval.h"
#include "scene_view.h"
#include "types.h"
#include "vec.h"

/* The punctual lights' sampler dimension at segment seg: outside every per-bounce block
 * of sampler.h and the sun's pairs, so that a scene without them draws the numbers it drew
 * before. */
TR_FN uint32_t tr_punctual_dim(int seg) {
    return 0x00900000u + (uint32_t)seg;
}

/* A spot's falloff at the cosine c of the angle from its axis: 1 inside cos_inner, 0
 * outside cos_outer, a smoothstep between (a hard edge where they are equal). */
TR_FN float tr_punctual_spot_falloff(TR_CONST_GLOBAL tr_punctual *l, float c) {
    if (c <= l->cos_outer) {
        return 0.0f;
    }
    if (c >= l->cos_inner) {
        return 1.0f;
    }
    const float t = (c - l->cos_outer) / (l->cos_inner - l->cos_outer);
    return t * t * (3.0f - 2.0f * t);
}

/* What light l gives at point p: the unit direction *wi towards it and its distance
 * *dist (TR_INFINITY for a directional light), and the incident light such that a surface
 * of BSDF f reflects f * value * |cos| (I falloff / r^2, or E). */
TR_FN tr_vec3 tr_punctual_incident(TR_CONST_GLOBAL tr_punctual *l, tr_vec3 p, tr_vec3 *wi,
                                   float *dist) {
    if (l->type == TR_PUNCTUAL_DIRECTIONAL) {
        *wi = v3_neg(l->dir);
        *dist = TR_INFINITY;
        return l->intensity;
    }
    const tr_vec3 d = v3_sub(l->pos, p);
    const float r2 = v3_dot(d, d);
    if (!(r2 > 0.0f)) {
        *wi = v3(0.0f, 0.0f, 1.0f);
        *dist = 0.0f;
        return v3s(0.0f);
    }
    const float r = tr_sqrtf(r2);
    *wi = v3_scale(d, 1.0f / r);
    *dist = r;
    float k = 1.0f / r2;
    if (l->type == TR_PUNCTUAL_SPOT) {
        k *= tr_punctual_spot_falloff(l, -v3_dot(*wi, l->dir));
    }
    return v3_scale(l->intensity, k);
}

TR_FN int tr_punctual_black(tr_vec3 a) {
    return a.x == 0.0f && a.y == 0.0f && a.z == 0.0f;
}

/* The light of the CDF's step that u in [0, 1) falls in, and its probability *prob. */
TR_FN uint32_t tr_punctual_pick(const tr_scene_view *s, float u, float *prob) {
    uint32_t lo = 0u, hi = s->punctual_count - 1u;
    while (lo < hi) {
        const uint32_t mid = (lo + hi) / 2u;
        if (u < s->punctual[mid].cdf) {
            hi = mid;
        } else {
            lo = mid + 1u;
        }
    }
    *prob = s->punctual[lo].cdf - (lo > 0u ? s->punctual[lo - 1u].cdf : 0.0f);
    return lo;
}

/* Light l's contribution at the non-delta surface m at p (outgoing wo), divided by prob:
 * f E |cos| / prob, before the path's throughput. *rays counts the shadow ray. */
TR_FN tr_vec3 tr_punctual_one(const tr_scene_view *s, TR_CONST_GLOBAL tr_punctual *l, float prob,
                              const tr_bsdf_params *m, tr_vec3 wo, tr_vec3 p, uint32_t *rays) {
    tr_vec3 wi;
    float dist;
    const tr_vec3 li = tr_punctual_incident(l, p, &wi, &dist);
    if (!(prob > 0.0f) || tr_punctual_black(li)) {
        return v3s(0.0f);
    }
    const tr_vec3 f = tr_bsdf_eval(m, wo, wi);
    if (tr_punctual_black(f)) {
        return v3s(0.0f);
    }
    const tr_vec3 o = tr_surface_origin(m, p, wi); /* shadow-terminator fix */
    tr_ray shadow;
    if (l->type == TR_PUNCTUAL_DIRECTIONAL) {
        shadow = tr_ray_make(o, wi, 0.0f, TR_INFINITY);
    } else {
        const tr_vec3 od = v3_sub(l->pos, o);
        const float len = v3_length(od);
        if (!(len > 0.0f)) {
            return v3s(0.0f);
        }
        shadow = tr_ray_make(o, v3_scale(od, 1.0f / len), 0.0f, len * (1.0f - 1e-4f));
    }
    *rays += 1;
    if (tr_occluded_masked(s, &shadow)) {
        return v3s(0.0f);
    }
    return v3_scale(v3_mul(f, li), tr_fabsf(v3_dot(wi, m->ns)) / prob);
}

/* Up to this many punctual lights, every vertex sends a shadow ray to each (no selection
 * noise); beyond, to one picked by the power CDF. */
#define TR_PUNCTUAL_ALL 8u

/* Next-event estimation of the punctual lights at the non-delta surface m at p (outgoing
 * wo): every light's contribution, or with more than TR_PUNCTUAL_ALL lights that of the
 * one u in [0, 1) picks, over its probability; before the path's throughput. */
TR_FN tr_vec3 tr_punctual_nee(const tr_scene_view *s, const tr_bsdf_params *m, tr_vec3 wo,
                              tr_vec3 p, float u, uint32_t *rays) {
    if (s->punctual_count <= TR_PUNCTUAL_ALL) {
        tr_vec3 sum = v3s(0.0f);
        for (uint32_t i = 0; i < s->punctual_count; ++i) {
            sum = v3_add(sum, tr_punctual_one(s, &s->punctual[i], 1.0f, m, wo, p, rays));
        }
        return sum;
    }
    float prob;
    const uint32_t k = tr_punctual_pick(s, u, &prob);
    return tr_punctual_one(s, &s->punctual[k], prob, m, wo, p, rays);
}

/* Whether the light tree holds the point and spot lights (light_tree.h): then pt's
 * next-event estimation reaches them through the tree, beside the emitters, and
 * tr_punctual_nee_pt lights with the directional ones only. */
TR_FN int tr_punctual_in_tree(const tr_scene_view *s) {
    return s->light_leaf_count > s->light_count;
}

/* pt's next-event estimation of the punctual lights the light tree does not hold: all of
 * them, as tr_punctual_nee, where the tree holds none; else the directional lights, a
 * shadow ray to each at every vertex (as the sun has; no box bounds them), and, where
 * `walk` is set (the first vertex when a stage estimates the emitters' direct light
 * there and pt draws no tree sample of its own), the point or spot light a walk of the
 * tree with u reaches (nothing where it reaches an emitter), over its probability. */
TR_FN tr_vec3 tr_punctual_nee_pt(const tr_scene_view *s, const tr_bsdf_params *m, tr_vec3 wo,
                                 tr_vec3 p, float u, int walk, uint32_t *rays) {
    if (!tr_punctual_in_tree(s)) {
        return tr_punctual_nee(s, m, wo, p, u, rays);
    }
    tr_vec3 sum = v3s(0.0f);
    for (uint32_t i = 0; i < s->punctual_count; ++i) {
        if (s->punctual[i].type == TR_PUNCTUAL_DIRECTIONAL) {
            sum = v3_add(sum, tr_punctual_one(s, &s->punctual[i], 1.0f, m, wo, p, rays));
        }
    }
    if (walk) {
        float prob;
        const uint32_t k = tr_light_tree_pick(s, p, m->ns, &u, &prob);
        if (prob > 0.0f && k >= s->light_count) {
            sum = v3_add(
                sum, tr_punctual_one(s, &s->punctual[k - s->light_count], prob, m, wo, p, rays));
        }
    }
    return sum;
}

#endif
