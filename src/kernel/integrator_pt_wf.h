/* integrator_pt_wf.h - pt as stages over a path's state, for the OpenCL wavefront path
 * tracer (Laine, Karras and Aila, "Megakernels Considered Harmful: Wavefront Path Tracing
 * on GPUs", HPG 2013; entry.cl's tr_cl_wf_* kernels, docs/opencl.md).
 *
 * tr_trace_pt_ff (integrator_pt.h) runs a path's segments in one loop. Here its loop body
 * is cut where the loop traces a ray: a path's state (tr_pt_wf_path) lives in a device
 * buffer between the stages, and each stage is one call on it:
 *
 *   generate  the camera ray and the state tr_trace_pt_ff starts its loop with
 *   extend    the closest hit of the path's ray (the loop's first query; entry.cl's
 *             tr_cl_wf_extend, which reads and writes only the ray and the hit)
 *   shade     everything the loop does with the hit (or the miss) up to the next ray:
 *             emission, the light samples, the BSDF's sample and roulette; the light
 *             sample's shadow ray is left in the state for connect
 *   connect   traces that shadow ray and adds the vertex's light samples to the radiance
 *   finish    what tr_trace_pt_ff and tr_render_pixel_sample_kind do after the loop
 *
 * Every statement is tr_trace_pt_ff's, in its order, with the loop's locals in the state;
 * the radiance receives the same contributions in the same order (connect adds the area
 * light's sample, then the environment's, the sun's and the punctual lights', as the loop
 * does), so a path's radiance, passes and ray count are the loop's bit for bit
 * (tests/test_opencl_wavefront.c compares the films). The environment's, the sun's and the
 * punctual lights' shadow rays are traced inside shade by the functions the loop calls
 * (tr_pt_env_light, tr_sun_nee, tr_punctual_nee); only the area light's goes through
 * connect. */
#ifndef TR_KERNEL_INTEGRATOR_PT_WF_H
#define TR_KERNEL_INTEGRATOR_PT_WF_H

#include "camera.h"
#include "compat.h"
#include "film.h"
#include "integrator_pt.h"
#include "sampler.h"
#include "scene_view.h"
#include "types.h"
#include "vec.h"

/* tr_pt_wf_path.pending: which of the vertex's light samples connect adds. */
#define TR_PT_WF_LIGHT 1u /* the area light's, if its shadow ray is unoccluded */
#define TR_PT_WF_ENV 2u
#define TR_PT_WF_SUN 4u
#define TR_PT_WF_PUNCTUAL 8u

/* One path between stages: tr_trace_pt_ff's locals, the sample it fills and the shadow
 * ray connect traces. 32-bit fields only, the same layout in C and OpenCL C. */
typedef struct tr_pt_wf_path {
    tr_ray ray;     /* the segment extend traces */
    tr_hit hit;     /* extend's answer */
    uint32_t found; /* whether extend found a hit */
    tr_sampler smp;
    tr_sample out;    /* the sample's passes and rays; radiance and direct set by finish */
    uint32_t surface; /* whether the film keeps what `out` records beside the radiance */
    tr_vec3 radiance, throughput, prev_p, prev_n, direct;
    float prev_pdf;
    int32_t seg, first_nd, prev_delta, holes, direct_seg, direct_done, psr_done;
    /* The vertex's light samples, added by connect. */
    uint32_t pending;
    int32_t nee_indirect;
    tr_ray shadow;
    tr_vec3 c_light, c_env, c_sun, c_punctual;
} tr_pt_wf_path;
/* The host sizes the device's buffer of paths by it: no padding, on either side. */
TR_STATIC_ASSERT(sizeof(tr_pt_wf_path) == 380, "tr_pt_wf_path layout");

/* Generate: sample `sample` of pixel (x, y), the pixel_index-th of the image, as
 * tr_render_pixel_sample_kind starts it for pt, and the state tr_trace_pt_ff has before
 * its first segment. Returns whether the path has a segment to trace (max_depth >= 1). */
TR_FN int tr_pt_wf_generate(tr_pt_wf_path *p, const tr_camera *cam, uint64_t seed, int max_depth,
                            uint32_t sampler, uint32_t passes, uint32_t x, uint32_t y,
                            uint64_t pixel_index, uint32_t sample) {
    tr_sample_clear(&p->out);
    p->surface = (passes & (TR_PASS_ALL | TR_PASS_DIRECT | TR_PASS_EMISSION)) != 0u ? 1u : 0u;
    float jx, jy;
    p->smp = tr_sampler_make_pixel(seed, pixel_index, x, y, sample, sampler);
    tr_sampler_2d(&p->smp, TR_DIM_CAMERA, &jx, &jy);
    tr_ray ray = tr_camera_ray(cam, (float)x, (float)y, jx, jy);
    if (cam->lens_radius > 0.0f) {
        float lu, lv;
        tr_sampler_2d(&p->smp, TR_DIM_LENS, &lu, &lv);
        ray = tr_camera_ray_lens(cam, (float)x, (float)y, jx, jy, lu, lv);
    }
    p->ray = ray;
    p->found = 0u;
    p->radiance = v3s(0.0f);
    p->first_nd = 0;
    p->throughput = v3s(1.0f);
    p->prev_pdf = 0.0f;
    p->prev_p = ray.origin;
    p->prev_n = v3s(0.0f);
    p->prev_delta = 1;
    p->holes = 0;
    p->direct_seg = max_depth + 1;
    p->direct_done = 0;
    p->direct = v3s(0.0f);
    p->psr_done = 0;
    p->seg = 1;
    p->pending = 0u;
    p->nee_indirect = 0;
    return max_depth >= 1;
}

/* Shade: tr_trace_pt_ff's loop body after its closest-hit query, for the path's segment
 * p->seg. Returns 1 if the path goes on (p->ray is its next segment, or the same segment
 * past an alpha cut-out), 0 if it ends here; either way p->pending says what connect
 * adds. */
TR_FN int tr_pt_wf_shade(const tr_scene_view *s, tr_pt_wf_path *p, int max_depth, int rr_start,
                         float clamp_indirect, uint32_t flags) {
    const int seg = p->seg;
    const int no_primary = (flags & TR_FRAME_NO_PRIMARY_DIRECT) != 0u;
    const int no_first = (flags & TR_FRAME_NO_FIRST_LIGHT) != 0u;
    tr_sample *surface = p->surface ? &p->out : 0;
    uint32_t *rays = &p->out.rays;
    const tr_sampler smp = p->smp;
    const tr_ray ray = p->ray;
    const tr_hit hit = p->hit;
    const int first_nd_in = p->first_nd;
    p->pending = 0u;
    if (!p->found) {
        /* A ray leaving the scene sees the environment (BSDF strategy). */
        const int indirect = first_nd_in != 0 && seg > first_nd_in + 1;
        const int skip = (no_primary && first_nd_in == 1 && seg == 2) || (no_first && seg == 1);
        if (s->env_count > 0u && !skip) {
            tr_vec3 le = tr_env_radiance(s, ray.dir);
            float w = p->prev_delta ? 1.0f : tr_mis_power(p->prev_pdf, tr_env_pdf(s, ray.dir));
            p->radiance = tr_pt_add(p->radiance, v3_scale(v3_mul(p->throughput, le), w), indirect,
                                    clamp_indirect);
        }
        if (s->sun_count > 0u && !skip) { /* the sun, found by the BSDF strategy */
            float ps = p->prev_delta ? 0.0f : tr_sun_pdf(s, ray.dir);
            float w = p->prev_delta ? 1.0f : tr_mis_power(p->prev_pdf, ps);
            p->radiance = tr_pt_add(p->radiance,
                                    v3_scale(v3_mul(p->throughput, tr_sun_radiance(s, ray.dir)), w),
                                    indirect, clamp_indirect);
        }
        if (surface && seg == 1) {
            surface->emission = p->radiance; /* all the camera ray saw */
        }
        return 0;
    }
    tr_triangle tri_tmp;
    TR_CONST_GLOBAL tr_triangle *tri = tr_view_triangle(s, hit.triangle, &tri_tmp);
    tr_vec3 n = tri->normal;
    tr_vec3 wo = v3_neg(ray.dir);
    tr_vec3 pos = v3_madd(ray.origin, ray.dir, hit.t);
    tr_bsdf_params m = tr_material_eval(s, hit.triangle, hit.u, hit.v, pos, n, ray.dir);
    /* An alpha cut-out is no surface: the ray goes on as it was, and the segment (with
     * its sampler dimensions) is not used up. */
    if (m.hole && p->holes < TR_MAX_HOLES) {
        ++p->holes;
        p->ray.tmin = hit.t + 1e-5f * tr_fmaxf(1.0f, hit.t);
        return 1;
    }
    tr_vec3 absorbed;
    if (tr_volume_attenuation(s, hit.triangle, ray.dir, n, hit.t, &absorbed)) {
        p->throughput = v3_mul(p->throughput, absorbed); /* the segment crossed a medium */
    }
    if (surface && seg == 1 && (flags & TR_FRAME_PSR) != 0u && tr_bsdf_is_delta(&m)) {
        *rays += tr_psr_surface(s, ray, hit, m, surface);
        p->psr_done = 1;
    }
    if (surface && !p->psr_done) {
        tr_sample_surface(surface, &m, ray.dir, hit.t, hit.triangle);
    }
    if (surface && p->direct_seg > max_depth && !tr_bsdf_is_delta(&m)) {
        p->direct_seg = seg + 1;
    }
    const int indirect = first_nd_in != 0 && seg > first_nd_in + 1;
    const int primary_direct = first_nd_in != 0 && seg == first_nd_in + 1;
    if (first_nd_in != 0 && (flags & TR_FRAME_REGULARIZE) != 0u) {
        tr_bsdf_regularize(&m);
    }
    if (first_nd_in == 0 && !tr_bsdf_is_delta(&m)) {
        p->first_nd = seg;
    }
    const int first_nd = p->first_nd;
    const tr_vec3 throughput = p->throughput;

    /* Emission found by the BSDF strategy (or the camera). */
    tr_vec3 le = tr_emitted(&m, wo);
    if (!tr_v3_is_zero(le) &&
        !(no_primary && primary_direct && first_nd == 1 && m.emittance > 0.0f) &&
        !(no_first && seg == 1 && m.emittance > 0.0f)) {
        float w = 1.0f;
        if (!p->prev_delta) {
            w = tr_mis_power(p->prev_pdf,
                             tr_light_pdf_n(s, p->prev_p, p->prev_n, hit.triangle, pos));
        }
        p->radiance =
            tr_pt_add(p->radiance, v3_scale(v3_mul(throughput, le), w), indirect, clamp_indirect);
    }
    const int nee_indirect = first_nd != seg;
    const int nee = !tr_bsdf_is_delta(&m) && !(no_primary && seg == 1 && !nee_indirect);
    p->nee_indirect = nee_indirect;
    if (surface && seg == 1) {
        surface->emission = p->radiance;
    }
    if (seg == p->direct_seg) {
        p->direct = p->radiance;
        p->direct_done = 1;
    }
    if (seg == max_depth || m.type == TR_MATERIAL_EMITTER) {
        return 0;
    }

    /* A point or spot light the tree's walk reached (light_tree.h): lit with the other
     * punctual lights below. */
    tr_vec3 punct_tree = v3s(0.0f);
    /* Next-event estimation: one emitter point; its shadow ray is connect's. */
    if (nee && (s->light_count > 0 || s->light_node_count > 0u)) {
        uint32_t lt, pk; /* pk, pp: a punctual light the tree reached */
        tr_vec3 y;
        float lu, lv, l1, l2;
        tr_sampler_2d(&smp, tr_sampler_dim(seg, TR_DIM_LIGHT), &l1, &l2);
        float pp;
        float pl = tr_light_sample_np(s, pos, m.ns, l1, l2, &lt, &y, &lu, &lv, &pk, &pp);
        if (pp > 0.0f) {
            punct_tree = tr_punctual_one(s, &s->punctual[pk], pp, &m, wo, pos, rays);
        }
        tr_triangle ltri_tmp;
        TR_CONST_GLOBAL tr_triangle *ltri = tr_view_triangle(s, lt, &ltri_tmp);
        tr_vec3 d = v3_sub(y, pos);
        float dist = v3_length(d);
        if (pl > 0.0f && dist > 0.0f) {
            tr_vec3 wi = v3_scale(d, 1.0f / dist);
            tr_vec3 le_l = tr_emitted_at(s, lt, lu, lv, y, ltri->normal, v3_neg(wi));
            tr_vec3 f = tr_bsdf_eval(&m, wo, wi);
            if (!tr_v3_is_zero(le_l) && !tr_v3_is_zero(f)) {
                float cos_i = tr_fabsf(v3_dot(wi, m.ns));
                tr_vec3 o = tr_surface_origin(&m, pos, wi);
                tr_vec3 od = v3_sub(y, o);
                float len = v3_length(od);
                p->shadow = tr_ray_make(o, v3_scale(od, 1.0f / len), 0.0f, len * (1.0f - 1e-4f));
                *rays += 1;
                float w = tr_mis_power(pl, tr_bsdf_pdf(&m, wo, wi));
                p->c_light = v3_scale(v3_mul(v3_mul(throughput, f), le_l), cos_i * w / pl);
                p->pending |= TR_PT_WF_LIGHT;
            }
        }
    }
    if (nee && s->env_count > 0u) {
        tr_bsdf_params mc = m;
        p->c_env = tr_pt_env_light(s, &smp, seg, &mc, pos, wo, throughput, rays);
        p->pending |= TR_PT_WF_ENV;
    }
    if (nee && s->sun_count > 0u) {
        float su1, su2;
        tr_sampler_2d(&smp, tr_sun_dim(seg), &su1, &su2);
        p->c_sun = v3_mul(throughput, tr_sun_nee(s, &m, wo, pos, su1, su2, rays));
        p->pending |= TR_PT_WF_SUN;
    }
    if (!tr_bsdf_is_delta(&m) && s->punctual_count > 0u) {
        const float pu = tr_sampler_1d(&smp, tr_punctual_dim(seg));
        p->c_punctual = v3_mul(
            throughput, v3_add(tr_punctual_nee_pt(s, &m, wo, pos, pu, !nee, rays), punct_tree));
        p->pending |= TR_PT_WF_PUNCTUAL;
    }

    /* The indirect light at the first surface is a stage's (ReSTIR GI, restir_gi.h). */
    if ((flags & TR_FRAME_NO_PRIMARY_INDIRECT) != 0u && seg == 1 && first_nd == 1) {
        return 0;
    }

    /* Continue with the BSDF's sample. */
    tr_scatter bs;
    float b1, b2;
    float blobe = 0.0f;
    if (m.type == TR_MATERIAL_GLASS || m.type == TR_MATERIAL_PRINCIPLED) {
        blobe = tr_sampler_1d(&smp, tr_sampler_dim(seg, TR_DIM_BSDF_LOBE));
    }
    tr_sampler_2d(&smp, tr_sampler_dim(seg, TR_DIM_BSDF_DIR), &b1, &b2);
    if (!tr_bsdf_sample(&m, wo, blobe, b1, b2, &bs)) {
        return 0;
    }
    p->throughput = v3_mul(throughput, bs.weight);
    p->prev_pdf = bs.pdf;
    p->prev_delta = bs.delta;
    p->prev_p = pos;
    p->prev_n = m.ns;
    if (seg >= rr_start) {
        float q = tr_sqrtf(v3_max_component(p->throughput));
        if (q < 1.0f) {
            if (!(tr_sampler_1d(&smp, tr_sampler_dim(seg, TR_DIM_ROULETTE)) < q)) {
                return 0;
            }
            p->throughput = v3_scale(p->throughput, 1.0f / q);
        }
    }
    tr_vec3 o = tr_surface_origin(&m, pos, bs.wi);
    p->ray = tr_ray_make(o, bs.wi, 0.0f, TR_INFINITY);
    p->seg = seg + 1;
    return 1;
}

/* Connect: the area light's shadow ray, then the vertex's light samples added to the
 * radiance in tr_trace_pt_ff's order. */
TR_FN void tr_pt_wf_connect(const tr_scene_view *s, tr_pt_wf_path *p, float clamp_indirect) {
    const uint32_t pending = p->pending;
    const int ind = p->nee_indirect;
    if ((pending & TR_PT_WF_LIGHT) != 0u && !tr_occluded_masked(s, &p->shadow)) {
        p->radiance = tr_pt_add(p->radiance, p->c_light, ind, clamp_indirect);
    }
    if ((pending & TR_PT_WF_ENV) != 0u) {
        p->radiance = tr_pt_add(p->radiance, p->c_env, ind, clamp_indirect);
    }
    if ((pending & TR_PT_WF_SUN) != 0u) {
        p->radiance = tr_pt_add(p->radiance, p->c_sun, ind, clamp_indirect);
    }
    if ((pending & TR_PT_WF_PUNCTUAL) != 0u) {
        p->radiance = tr_pt_add(p->radiance, p->c_punctual, ind, clamp_indirect);
    }
    p->pending = 0u;
}

/* Finish: the sample the path leaves, as tr_trace_pt_ff and tr_render_pixel_sample_kind
 * end it, into *out. */
TR_FN void tr_pt_wf_finish(const tr_pt_wf_path *p, tr_sample *out) {
    *out = p->out;
    if (p->surface) {
        out->direct = p->direct_done ? p->direct : p->radiance;
    }
    out->radiance = p->radiance;
    tr_sample_finish(out);
}

#endif
