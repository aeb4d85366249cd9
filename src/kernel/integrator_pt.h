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
#include "sampler.h"
#include "scene_view.h"
#include "psr.h"
#include "punctual.h"
#include "sun.h"
#include "types.h"
#include "vec.h"

/* Russian roulette from this segment on. It is played on the throughput (which
 * includes earlier roulette's 1/q): a path survives with probability
 * q = min(1, sqrt(max RGB component)), so a path that could still carry as much as it
 * started with is never ended by chance, and a dim path is ended less often than its
 * throughput alone would say: its weight after surviving, 1/q, grows only as
 * 1/sqrt(throughput). On the classic Cornell box (256x256, 64 spp; docs/benchmarks.md)
 * q = max from segment 3 gave relative MSE 2.45e-3 with 20.9 M rays, sqrt from 3
 * 1.88e-3 with 22.6 M, max from 5 1.70e-3 with 26.5 M, sqrt from 5 1.50e-3 with 27.4 M:
 * the last has the least error per sample and per ray. Paths that stay bright end at
 * max_depth. */
#define TR_PT_RR_START 5

/* Veach's power heuristic (beta = 2): the weight of strategy a against strategy b. */
TR_FN float tr_mis_power(float pdf_a, float pdf_b) {
    float a = pdf_a * pdf_a, b = pdf_b * pdf_b;
    return a + b > 0.0f ? a / (a + b) : 0.0f;
}

TR_FN int tr_v3_is_zero(tr_vec3 a) {
    return a.x == 0.0f && a.y == 0.0f && a.z == 0.0f;
}

/* Next-event estimation towards the environment at vertex p of segment seg (surface m,
 * wo towards the viewer), MIS against the BSDF: the radiance it adds, throughput
 * included; *rays counts its shadow ray. Out of line, so that scenes without an
 * environment do not pay for a second copy of the BSDF's evaluation in tr_trace_pt (its
 * size kept the compiler from inlining the BSDF sampler there). */
TR_FN_NOINLINE tr_vec3 tr_pt_env_light(const tr_scene_view *s, const tr_sampler *smp, int seg,
                                       const tr_bsdf_params *m, tr_vec3 p, tr_vec3 wo,
                                       tr_vec3 throughput, uint32_t *rays) {
    float eu1, eu2;
    tr_sampler_2d(smp, tr_sampler_dim(seg, TR_DIM_ENV), &eu1, &eu2);
    tr_vec3 wi;
    float pe;
    tr_vec3 le_e = tr_env_sample(s, eu1, eu2, &wi, &pe);
    tr_vec3 f = pe > 0.0f ? tr_bsdf_eval(m, wo, wi) : v3s(0.0f);
    if (tr_v3_is_zero(le_e) || tr_v3_is_zero(f)) {
        return v3s(0.0f);
    }
    tr_ray shadow = tr_ray_make(tr_surface_origin(m, p, wi), wi, 0.0f, TR_INFINITY);
    *rays += 1;
    if (tr_occluded_masked(s, &shadow)) {
        return v3s(0.0f);
    }
    float w = tr_mis_power(pe, tr_bsdf_pdf(m, wo, wi));
    float c = tr_fabsf(v3_dot(wi, m->ns));
    return v3_scale(v3_mul(v3_mul(throughput, f), le_e), c * w / pe);
}

/* Radiance arriving along `ray`. A path has at most max_depth segments (the camera ray
 * is the first); Russian roulette on the throughput's largest component starts after
 * rr_start segments (tr_trace_pt: TR_PT_RR_START; a real-time frame, whose filter hides
 * what an earlier start adds to the noise, takes fewer: TR_ROULETTE_START_REALTIME). Every random
 * decision reads its own dimension of `smp` (sampler.h): at segment seg, the light (selection and
 * point, one pair), BSDF lobe, BSDF direction, roulette and the environment light each have a
 * dimension pair. *rays counts closest-hit and shadow queries; `surface` (may be null) receives the
 * first hit that is not a delta surface, for the passes, and the direct part of the radiance in
 * surface->direct.
 *
 * The direct part (TR_PASS_DIRECT) is everything added up to and including the light that
 * reaches the passes' surface S (the first hit that is not a delta surface) without another
 * bounce: emission seen before S (through mirrors and glass, or the environment and the sun
 * when the path leaves without finding S) and S's own emission; at S, the light sample (NEE
 * to an emitter, the environment, the sun) with its MIS weight; and at the next vertex, what
 * the BSDF sample from S finds: an emitter's emission, or the environment and the sun if it
 * leaves, each with its MIS weight (the two strategies' weights for the light at S sum to
 * one, so the direct part is unbiased on its own). Everything after that (NEE at the second
 * vertex on) is indirect. It is taken as a snapshot of the running sum right after that next
 * vertex's emission, so the radiance itself is computed exactly as without the pass.
 *
 * The specular part (TR_PASS_SPECULAR, with TR_FRAME_SPLIT_SPECULAR) is the light S reflects
 * through its specular lobes: each light sample at S weighed by tr_bsdf_spec_share at its
 * direction (the environment's and the sun's directions drawn again from the same sampler
 * dimensions; punctual lights, several per sample, by the share head-on), and everything
 * found after S's BSDF sample by that sample's share. It too is taken from differences of
 * the running sum, so the radiance is unchanged; radiance less the emission before S less
 * the specular part is the diffuse part. The distance to the vertex after S is recorded
 * where S's sample was mostly specular (its share's luminance above one half), for the
 * reconstruction's virtual motion. */
/* Firefly control, for frames a filter reconstructs (tr_trace_pt_ff): a contribution that
 * arrives over an indirect vertex - the light sample at any non-specular vertex after the
 * first, and what a BSDF sample finds after the vertex that follows it - is scaled down
 * to luminance `limit` (Rec. 709 weights) where it is above (the clamp of production
 * renderers, Cycles' "clamp indirect"). Direct light, by either strategy, is never
 * clamped. A biased estimate: what it takes away is measured in docs/realtime.md. */
TR_FN tr_vec3 tr_pt_clamp(tr_vec3 c, float limit) {
    float l = 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z;
    return l > limit ? v3_scale(c, limit / l) : c;
}

/* radiance + c, with c clamped to `limit` where `indirect` and limit > 0. */
TR_FN tr_vec3 tr_pt_add(tr_vec3 radiance, tr_vec3 c, int indirect, float limit) {
    if (indirect && limit > 0.0f) {
        c = tr_pt_clamp(c, limit);
    }
    return v3_add(radiance, c);
}

/* tr_trace_pt_rr with firefly control: contributions over indirect vertices clamped to
 * luminance clamp_indirect (0: none), and with TR_FRAME_REGULARIZE in `flags` the lobes
 * of vertices after the first non-specular one roughened (tr_bsdf_regularize). With
 * TR_FRAME_NO_PRIMARY_DIRECT the direct light at the camera ray's first surface, where that
 * is not specular, that light sampling can produce (its light samples, and emitters in the light
 * table, the environment or the sun found by its BSDF sample) is left out, for a stage that
 * estimates it (restir.h); the BSDF sample still finds emission no light sample can
 * (a principled material's), with weight 1 as before. With TR_FRAME_NO_PRIMARY_INDIRECT the
 * path ends at that surface (a stage estimates its indirect light), and with
 * TR_FRAME_NO_FIRST_LIGHT the emission the ray finds first (an emitter of the light table,
 * the environment, the sun) is left out: the stage's ray from the first surface then
 * carries indirect light only. With clamp 0 and no flags the
 * same numbers as without. integrator_pt_wf.h repeats this loop's body as the OpenCL
 * wavefront's stages: a change here is a change there (test_opencl_wavefront compares the
 * two films bit for bit). */
TR_FN tr_vec3 tr_trace_pt_ff(const tr_scene_view *s, tr_ray ray, int max_depth, int rr_start,
                             float clamp_indirect, uint32_t flags, const tr_sampler *smp,
                             uint32_t *rays, tr_sample *surface) {
    tr_vec3 radiance = v3s(0.0f);
    int first_nd = 0; /* the segment of the first non-specular vertex (0: none yet) */
    const int no_primary = (flags & TR_FRAME_NO_PRIMARY_DIRECT) != 0u;
    const int no_first = (flags & TR_FRAME_NO_FIRST_LIGHT) != 0u;
    tr_vec3 throughput = v3s(1.0f);
    float prev_pdf = 0.0f;
    tr_vec3 prev_p = ray.origin;    /* the vertex the last BSDF sample left, for MIS */
    tr_vec3 prev_n = v3s(0.0f);     /* its shading normal (the light tree weighs by it) */
    int prev_delta = 1;             /* the camera ray: no light strategy competes */
    int holes = 0;                  /* alpha cut-outs passed through */
    int direct_seg = max_depth + 1; /* the segment whose emission ends the direct part */
    int direct_done = 0;
    tr_vec3 direct = v3s(0.0f);
    int psr_done = 0; /* the passes' surface came from tr_psr_surface */
    /* TR_FRAME_SPLIT_SPECULAR: the specular part of the light S reflects (see above). */
    const int split = surface != 0 && (flags & TR_FRAME_SPLIT_SPECULAR) != 0u;
    tr_vec3 spec = v3s(0.0f);
    tr_vec3 cont_share = v3s(0.0f); /* the specular share of S's BSDF sample */
    tr_vec3 cont_from = v3s(0.0f);  /* the radiance when S's BSDF sample was drawn */
    int cont = 0;
    for (int seg = 1; seg <= max_depth; ++seg) {
        tr_hit hit;
        *rays += 1;
        if (!tr_intersect_scene(s, &ray, &hit)) {
            /* A ray leaving the scene sees the environment (BSDF strategy). */
            const int indirect = first_nd != 0 && seg > first_nd + 1;
            const int skip = (no_primary && first_nd == 1 && seg == 2) || (no_first && seg == 1);
            if (s->env_count > 0u && !skip) {
                tr_vec3 le = tr_env_radiance(s, ray.dir);
                float w = prev_delta ? 1.0f : tr_mis_power(prev_pdf, tr_env_pdf(s, ray.dir));
                radiance = tr_pt_add(radiance, v3_scale(v3_mul(throughput, le), w), indirect,
                                     clamp_indirect);
            }
            if (s->sun_count > 0u && !skip) { /* the sun, found by the BSDF strategy */
                float ps = prev_delta ? 0.0f : tr_sun_pdf(s, ray.dir);
                float w = prev_delta ? 1.0f : tr_mis_power(prev_pdf, ps);
                radiance = tr_pt_add(radiance,
                                     v3_scale(v3_mul(throughput, tr_sun_radiance(s, ray.dir)), w),
                                     indirect, clamp_indirect);
            }
            if (surface && seg == 1) {
                surface->emission = radiance; /* all the camera ray saw */
            }
            break;
        }
        tr_triangle tri_tmp;
        TR_CONST_GLOBAL tr_triangle *tri = tr_view_triangle(s, hit.triangle, &tri_tmp);
        tr_vec3 n = tri->normal;
        tr_vec3 wo = v3_neg(ray.dir);
        tr_vec3 p = v3_madd(ray.origin, ray.dir, hit.t);
        tr_bsdf_params m = tr_material_eval(s, hit.triangle, hit.u, hit.v, p, n, ray.dir);
        /* An alpha cut-out is no surface: the ray goes on as it was, and the segment (with
         * its sampler dimensions) is not used up. */
        if (m.hole && holes < TR_MAX_HOLES) {
            ++holes;
            --seg;
            ray.tmin = hit.t + 1e-5f * tr_fmaxf(1.0f, hit.t);
            continue;
        }
        tr_vec3 absorbed;
        if (tr_volume_attenuation(s, hit.triangle, ray.dir, n, hit.t, &absorbed)) {
            throughput = v3_mul(throughput, absorbed); /* the segment crossed a medium */
        }
        if (split && cont && seg == first_nd + 1 &&
            0.2126f * cont_share.x + 0.7152f * cont_share.y + 0.0722f * cont_share.z > 0.5f) {
            surface->spec_dist = hit.t; /* a specular sample from S: the reflection's distance */
        }
        if (surface && seg == 1 && (flags & TR_FRAME_PSR) != 0u && tr_bsdf_is_delta(&m)) {
            *rays += tr_psr_surface(s, ray, hit, m, surface);
            psr_done = 1;
        }
        if (surface && !psr_done) {
            tr_sample_surface(surface, &m, ray.dir, hit.t, hit.triangle);
        }
        if (surface && direct_seg > max_depth && !tr_bsdf_is_delta(&m)) {
            direct_seg = seg + 1; /* S is this vertex: the next one's emission is still direct */
        }
        /* Whether what arrives here (emission found by the BSDF sample) is indirect light,
         * and whether it is the first non-specular vertex's direct light. */
        const int indirect = first_nd != 0 && seg > first_nd + 1;
        const int primary_direct = first_nd != 0 && seg == first_nd + 1;
        if (first_nd != 0 && (flags & TR_FRAME_REGULARIZE) != 0u) {
            tr_bsdf_regularize(&m);
        }
        if (first_nd == 0 && !tr_bsdf_is_delta(&m)) {
            first_nd = seg;
        }
        const int at_s = split && first_nd == seg; /* S: its light is split by lobe */
        if (at_s) {
            surface->spec_f0 = tr_bsdf_spec_f0(&m, &surface->spec_alpha);
        }

        /* Emission found by the BSDF strategy (or the camera). */
        tr_vec3 le = tr_emitted(&m, wo);
        if (!tr_v3_is_zero(le) &&
            !(no_primary && primary_direct && first_nd == 1 && m.emittance > 0.0f) &&
            !(no_first && seg == 1 && m.emittance > 0.0f)) {
            float w = 1.0f;
            if (!prev_delta) {
                w = tr_mis_power(prev_pdf, tr_light_pdf_n(s, prev_p, prev_n, hit.triangle, p));
            }
            radiance =
                tr_pt_add(radiance, v3_scale(v3_mul(throughput, le), w), indirect, clamp_indirect);
        }
        /* The light samples here: indirect light unless this is the first non-specular
         * vertex, where a stage may estimate them instead. */
        const int nee_indirect = first_nd != seg;
        const int nee = !tr_bsdf_is_delta(&m) && !(no_primary && seg == 1 && !nee_indirect);
        if (surface && seg == 1) {
            surface->emission = radiance; /* the first hit's emission, nothing else yet */
        }
        if (seg == direct_seg) { /* never without `surface`: direct_seg stays past the end */
            direct = radiance;
            direct_done = 1;
        }
        if (seg == max_depth || m.type == TR_MATERIAL_EMITTER) {
            break;
        }

        /* A point or spot light the tree's walk reached (light_tree.h): lit with the other
         * punctual lights below. */
        tr_vec3 punct_tree = v3s(0.0f);
        /* Next-event estimation: one emitter point, one shadow ray. */
        if (nee && (s->light_count > 0 || s->light_node_count > 0u)) {
            uint32_t lt, pk; /* pk, pp: a punctual light the tree reached */
            tr_vec3 y;
            float lu, lv, l1, l2;
            tr_sampler_2d(smp, tr_sampler_dim(seg, TR_DIM_LIGHT), &l1, &l2);
            float pp;
            float pl = tr_light_sample_np(s, p, m.ns, l1, l2, &lt, &y, &lu, &lv, &pk, &pp);
            if (pp > 0.0f) {
                punct_tree = tr_punctual_one(s, &s->punctual[pk], pp, &m, wo, p, rays);
            }
            tr_triangle ltri_tmp;
            TR_CONST_GLOBAL tr_triangle *ltri = tr_view_triangle(s, lt, &ltri_tmp);
            tr_vec3 d = v3_sub(y, p);
            float dist = v3_length(d);
            if (pl > 0.0f && dist > 0.0f) {
                tr_vec3 wi = v3_scale(d, 1.0f / dist);
                tr_vec3 le_l = tr_emitted_at(s, lt, lu, lv, y, ltri->normal, v3_neg(wi));
                tr_vec3 f = tr_bsdf_eval(&m, wo, wi);
                if (!tr_v3_is_zero(le_l) && !tr_v3_is_zero(f)) {
                    float cos_i = tr_fabsf(v3_dot(wi, m.ns)); /* the shading normal */
                    tr_vec3 o = tr_surface_origin(&m, p, wi); /* shadow-terminator fix */
                    tr_vec3 od = v3_sub(y, o);
                    float len = v3_length(od);
                    tr_ray shadow =
                        tr_ray_make(o, v3_scale(od, 1.0f / len), 0.0f, len * (1.0f - 1e-4f));
                    *rays += 1;
                    if (!tr_occluded_masked(s, &shadow)) { /* cut-outs let light through */
                        float w = tr_mis_power(pl, tr_bsdf_pdf(&m, wo, wi));
                        const tr_vec3 r0 = radiance;
                        radiance = tr_pt_add(
                            radiance, v3_scale(v3_mul(v3_mul(throughput, f), le_l), cos_i * w / pl),
                            nee_indirect, clamp_indirect);
                        if (at_s) {
                            spec = v3_add(
                                spec, v3_mul(v3_sub(radiance, r0), tr_bsdf_spec_share(&m, wo, wi)));
                        }
                    }
                }
            }
        }

        /* Next-event estimation towards the environment, MIS against the BSDF. */
        if (nee && s->env_count > 0u) {
            tr_bsdf_params mc = m; /* a copy: m's address taken would keep it in memory */
            const tr_vec3 r0 = radiance;
            radiance =
                tr_pt_add(radiance, tr_pt_env_light(s, smp, seg, &mc, p, wo, throughput, rays),
                          nee_indirect, clamp_indirect);
            if (at_s) { /* the environment's direction again: the sampler is stateless */
                float eu1, eu2, pe;
                tr_vec3 wi;
                tr_sampler_2d(smp, tr_sampler_dim(seg, TR_DIM_ENV), &eu1, &eu2);
                tr_env_sample(s, eu1, eu2, &wi, &pe);
                spec = v3_add(spec, v3_mul(v3_sub(radiance, r0), tr_bsdf_spec_share(&m, wo, wi)));
            }
        }

        /* Next-event estimation towards the sun (sun.h), MIS against the BSDF. */
        if (nee && s->sun_count > 0u) {
            float su1, su2;
            tr_sampler_2d(smp, tr_sun_dim(seg), &su1, &su2);
            const tr_vec3 r0 = radiance;
            radiance =
                tr_pt_add(radiance, v3_mul(throughput, tr_sun_nee(s, &m, wo, p, su1, su2, rays)),
                          nee_indirect, clamp_indirect);
            if (at_s) {
                float pls;
                tr_vec3 wi;
                tr_sun_sample(s, su1, su2, &wi, &pls);
                spec = v3_add(spec, v3_mul(v3_sub(radiance, r0), tr_bsdf_spec_share(&m, wo, wi)));
            }
        }

        /* Next-event estimation towards the punctual lights (punctual.h): delta lights, which
         * BSDF samples never find, so without MIS. At the first vertex too when a stage
         * estimates the primary direct light (no_primary): it does not sample them. */
        if (!tr_bsdf_is_delta(&m) && s->punctual_count > 0u) {
            const float pu = tr_sampler_1d(smp, tr_punctual_dim(seg));
            const tr_vec3 r0 = radiance;
            radiance = tr_pt_add(
                radiance,
                v3_mul(throughput,
                       v3_add(tr_punctual_nee_pt(s, &m, wo, p, pu, !nee, rays), punct_tree)),
                nee_indirect, clamp_indirect);
            if (at_s) { /* several lights: their share taken head-on, an approximation */
                spec = v3_add(spec, v3_mul(v3_sub(radiance, r0),
                                           tr_bsdf_spec_share(&m, wo, tr_bsdf_facing(m.ns, wo))));
            }
        }

        /* The indirect light at the first surface is a stage's (ReSTIR GI, restir_gi.h). */
        if ((flags & TR_FRAME_NO_PRIMARY_INDIRECT) != 0u && seg == 1 && first_nd == 1) {
            break;
        }

        /* Continue with the BSDF's sample. */
        tr_scatter bs;
        float b1, b2;
        /* Only glass and the principled material choose a lobe: for the others the
         * dimension is left unread rather than hashed at every vertex. */
        float blobe = 0.0f;
        if (m.type == TR_MATERIAL_GLASS || m.type == TR_MATERIAL_PRINCIPLED) {
            blobe = tr_sampler_1d(smp, tr_sampler_dim(seg, TR_DIM_BSDF_LOBE));
        }
        tr_sampler_2d(smp, tr_sampler_dim(seg, TR_DIM_BSDF_DIR), &b1, &b2);
        if (!tr_bsdf_sample(&m, wo, blobe, b1, b2, &bs)) {
            break;
        }
        throughput = v3_mul(throughput, bs.weight);
        if (at_s) { /* everything after this sample is split by its share */
            cont_share = tr_bsdf_spec_share(&m, wo, bs.wi);
            cont_from = radiance;
            cont = 1;
        }
        prev_pdf = bs.pdf;
        prev_delta = bs.delta;
        prev_p = p;
        prev_n = m.ns;
        if (seg >= rr_start) {
            float q = tr_sqrtf(v3_max_component(throughput));
            if (q < 1.0f) {
                if (!(tr_sampler_1d(smp, tr_sampler_dim(seg, TR_DIM_ROULETTE)) < q)) {
                    break;
                }
                throughput = v3_scale(throughput, 1.0f / q);
            }
        }
        tr_vec3 o = tr_surface_origin(&m, p, bs.wi); /* shadow-terminator fix */
        ray = tr_ray_make(o, bs.wi, 0.0f, TR_INFINITY);
    }
    if (surface) {
        /* A path that ended before the vertex after S: all of it was direct. */
        surface->direct = direct_done ? direct : radiance;
        if (split) {
            if (cont) {
                spec = v3_add(spec, v3_mul(v3_sub(radiance, cont_from), cont_share));
            }
            surface->specular = spec;
        }
    }
    return radiance;
}

/* tr_trace_pt_ff without firefly control. */
TR_FN tr_vec3 tr_trace_pt_rr(const tr_scene_view *s, tr_ray ray, int max_depth, int rr_start,
                             const tr_sampler *smp, uint32_t *rays, tr_sample *surface) {
    return tr_trace_pt_ff(s, ray, max_depth, rr_start, 0.0f, 0u, smp, rays, surface);
}

/* The emission the camera ray `ray` sees at its first hit, as tr_trace_pt_rr's first
 * segment adds it (TR_PASS_EMISSION): cut-outs passed, an emitter's emission towards the
 * camera, or the environment and the sun where the ray leaves the scene. For resolving the
 * emission over a pixel's area (tr_resolve_emission). */
TR_FN tr_vec3 tr_pt_first_emission(const tr_scene_view *s, tr_ray ray) {
    for (int holes = 0;; ++holes) {
        tr_hit hit;
        if (!tr_intersect_scene(s, &ray, &hit)) {
            tr_vec3 le = v3s(0.0f);
            if (s->env_count > 0u) {
                le = tr_env_radiance(s, ray.dir);
            }
            if (s->sun_count > 0u) {
                le = v3_add(le, tr_sun_radiance(s, ray.dir));
            }
            return le;
        }
        tr_triangle tri_tmp;
        TR_CONST_GLOBAL tr_triangle *tri = tr_view_triangle(s, hit.triangle, &tri_tmp);
        tr_vec3 p = v3_madd(ray.origin, ray.dir, hit.t);
        tr_bsdf_params m = tr_material_eval(s, hit.triangle, hit.u, hit.v, p, tri->normal, ray.dir);
        if (!(m.hole && holes < TR_MAX_HOLES)) {
            return tr_emitted(&m, v3_neg(ray.dir));
        }
        ray.tmin = hit.t + 1e-5f * tr_fmaxf(1.0f, hit.t);
    }
}

/* tr_trace_pt_rr with roulette after TR_PT_RR_START segments, the offline default. */
TR_FN tr_vec3 tr_trace_pt(const tr_scene_view *s, tr_ray ray, int max_depth, const tr_sampler *smp,
                          uint32_t *rays, tr_sample *surface) {
    return tr_trace_pt_rr(s, ray, max_depth, TR_PT_RR_START, smp, rays, surface);
}

#endif
