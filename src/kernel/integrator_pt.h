/* integrator_pt.h - unidirectional path tracing with next-event estimation and
 * multiple importance sampling (Veach, "Robust Monte Carlo Methods for Light Transport
 * Simulation", PhD thesis, Stanford 1997, chapter 9: the power heuristic, beta = 2).
 *
 * At every non-delta vertex two strategies produce paths that end on an emitter:
 * sampling a point on an emitter (light sample, with a shadow ray) and continuing
 * with the BSDF's sample and hitting an emitter. Each contribution is weighted by
 * w_s = p_s^2 / (p_light^2 + p_bsdf^2), both pdfs in solid angle at the vertex, so
 * the weights of the two strategies sum to one for every path. After delta vertices
 * (mirror, smooth glass) and for the camera ray only the BSDF strategy exists, and
 * emission counts with weight 1. */
#ifndef TR_KERNEL_INTEGRATOR_PT_H
#define TR_KERNEL_INTEGRATOR_PT_H

#include "bsdf.h"
#include "compat.h"
#include "envmap.h"
#include "film.h"
#include "light.h"
#include "material.h"
#include "material_eval.h"
#include "rng.h"
#include "scene_view.h"
#include "types.h"
#include "vec.h"

/* Russian roulette starts after this many segments. */
#define TR_PT_RR_START 3

/* Veach's power heuristic (beta = 2): the weight of strategy a against strategy b. */
TR_FN float tr_mis_power(float pdf_a, float pdf_b) {
    float a = pdf_a * pdf_a, b = pdf_b * pdf_b;
    return a + b > 0.0f ? a / (a + b) : 0.0f;
}

/* Solid-angle density, seen from a point at distance dist along direction w (unit,
 * pointing from the point to the emitter), with which light sampling picks the emitter
 * point on triangle tri. The emitter table weighs the material's constants (lights.c),
 * so this reads the material itself, not the material stage's output. */
TR_FN float tr_pt_light_pdf(const tr_scene_view *s, TR_CONST_GLOBAL tr_triangle *tri, tr_vec3 w,
                            float dist) {
    float cos_l = tr_fabsf(v3_dot(w, tri->normal));
    if (!(cos_l > 0.0f)) {
        return 0.0f;
    }
    tr_material m = s->materials[tri->material];
    return tr_light_pdf_area(s, &m, tri->area) * dist * dist / cos_l;
}

TR_FN int tr_v3_is_zero(tr_vec3 a) {
    return a.x == 0.0f && a.y == 0.0f && a.z == 0.0f;
}

/* Radiance arriving along `ray`. A path has at most max_depth segments (the camera ray
 * is the first); Russian roulette on the throughput's largest component starts after
 * TR_PT_RR_START segments. *rays counts closest-hit and shadow queries; `surface` (may
 * be null) receives the first hit that is not a delta surface, for the passes. */
TR_FN tr_vec3 tr_trace_pt(const tr_scene_view *s, tr_ray ray, int max_depth, tr_rng *rng,
                          uint32_t *rays, tr_sample *surface) {
    tr_vec3 radiance = v3s(0.0f);
    tr_vec3 throughput = v3s(1.0f);
    float prev_pdf = 0.0f;
    int prev_delta = 1; /* the camera ray: no light strategy competes */
    int holes = 0;      /* issue 14: alpha cut-outs passed through */
    for (int seg = 1; seg <= max_depth; ++seg) {
        tr_hit hit;
        *rays += 1;
        if (!tr_intersect_scene(s, &ray, &hit)) {
            /* issue 14: a ray leaving the scene sees the environment (BSDF strategy). */
            if (s->env_count > 0u) {
                tr_vec3 le = tr_env_radiance(s, ray.dir);
                float w = prev_delta ? 1.0f : tr_mis_power(prev_pdf, tr_env_pdf(s, ray.dir));
                radiance = v3_add(radiance, v3_scale(v3_mul(throughput, le), w));
            }
            break;
        }
        TR_CONST_GLOBAL tr_triangle *tri = &s->triangles[hit.triangle];
        tr_vec3 n = tri->normal;
        tr_vec3 wo = v3_neg(ray.dir);
        tr_vec3 p = v3_madd(ray.origin, ray.dir, hit.t);
        tr_bsdf_params m = tr_material_eval(s, hit.triangle, hit.u, hit.v, p, n, ray.dir);
        /* issue 14: an alpha cut-out is no surface; the ray goes on as it was. */
        if (m.hole && holes < TR_MAX_HOLES) {
            ++holes;
            --seg;
            ray.tmin = hit.t + 1e-5f * tr_fmaxf(1.0f, hit.t);
            continue;
        }
        if (surface) {
            tr_sample_surface(surface, &m, ray.dir, hit.t, hit.triangle);
        }

        /* Emission found by the BSDF strategy (or the camera). */
        tr_vec3 le = tr_emitted(&m, wo);
        if (!tr_v3_is_zero(le)) {
            float w = 1.0f;
            if (!prev_delta) {
                w = tr_mis_power(prev_pdf, tr_pt_light_pdf(s, tri, ray.dir, hit.t));
            }
            radiance = v3_add(radiance, v3_scale(v3_mul(throughput, le), w));
        }
        if (seg == max_depth || m.type == TR_MATERIAL_EMITTER) {
            break;
        }

        /* Next-event estimation: one emitter point, one shadow ray. */
        if (!tr_bsdf_is_delta(&m) && s->light_count > 0) {
            uint32_t lt;
            tr_vec3 y;
            float lu, lv;
            float pa = tr_light_sample(s, rng, &lt, &y, &lu, &lv);
            TR_CONST_GLOBAL tr_triangle *ltri = &s->triangles[lt];
            tr_vec3 d = v3_sub(y, p);
            float dist = v3_length(d);
            if (pa > 0.0f && dist > 0.0f) {
                tr_vec3 wi = v3_scale(d, 1.0f / dist);
                tr_bsdf_params lm = tr_material_eval(s, lt, lu, lv, y, ltri->normal, wi);
                tr_vec3 le_l = tr_emitted(&lm, v3_neg(wi));
                tr_vec3 f = tr_bsdf_eval(&m, wo, wi);
                float pl = tr_pt_light_pdf(s, ltri, wi, dist);
                if (!tr_v3_is_zero(le_l) && !tr_v3_is_zero(f) && pl > 0.0f) {
                    float cos_i = tr_fabsf(v3_dot(wi, m.ns)); /* issue 14: shading normal */
                    tr_vec3 o = tr_surface_origin(&m, p, wi); /* issue 14: terminator fix */
                    tr_vec3 od = v3_sub(y, o);
                    float len = v3_length(od);
                    tr_ray shadow =
                        tr_ray_make(o, v3_scale(od, 1.0f / len), 0.0f, len * (1.0f - 1e-4f));
                    *rays += 1;
                    if (!tr_occluded_masked(s, &shadow)) { /* issue 14: cut-outs */
                        float w = tr_mis_power(pl, tr_bsdf_pdf(&m, wo, wi));
                        radiance = v3_add(radiance, v3_scale(v3_mul(v3_mul(throughput, f), le_l),
                                                             cos_i * w / pl));
                    }
                }
            }
        }

        /* issue 14: next-event estimation towards the environment, MIS against the BSDF. */
        if (!tr_bsdf_is_delta(&m) && s->env_count > 0u) {
            float eu1 = tr_rng_float(rng);
            float eu2 = tr_rng_float(rng);
            tr_vec3 wi;
            float pe;
            tr_vec3 le_e = tr_env_sample(s, eu1, eu2, &wi, &pe);
            tr_vec3 f = pe > 0.0f ? tr_bsdf_eval(&m, wo, wi) : v3s(0.0f);
            if (!tr_v3_is_zero(le_e) && !tr_v3_is_zero(f)) {
                tr_ray shadow = tr_ray_make(tr_surface_origin(&m, p, wi), wi, 0.0f, TR_INFINITY);
                *rays += 1;
                if (!tr_occluded_masked(s, &shadow)) {
                    float w = tr_mis_power(pe, tr_bsdf_pdf(&m, wo, wi));
                    float c = tr_fabsf(v3_dot(wi, m.ns));
                    radiance =
                        v3_add(radiance, v3_scale(v3_mul(v3_mul(throughput, f), le_e), c * w / pe));
                }
            }
        }

        /* Continue with the BSDF's sample. */
        tr_scatter bs;
        if (!tr_bsdf_sample(&m, wo, rng, &bs)) {
            break;
        }
        throughput = v3_mul(throughput, bs.weight);
        prev_pdf = bs.pdf;
        prev_delta = bs.delta;
        if (seg >= TR_PT_RR_START) {
            float q = tr_fminf(v3_max_component(throughput), 0.95f);
            if (!(tr_rng_float(rng) < q)) {
                break;
            }
            throughput = v3_scale(throughput, 1.0f / q);
        }
        tr_vec3 o = tr_surface_origin(&m, p, bs.wi); /* issue 14: terminator fix */
        ray = tr_ray_make(o, bs.wi, 0.0f, TR_INFINITY);
    }
    return radiance;
}

#endif
