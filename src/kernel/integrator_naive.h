/* integrator_naive.h - the thesis's integrator (listing 19) with its depth-based
 * Russian roulette (listing 15). */
#ifndef TR_KERNEL_INTEGRATOR_NAIVE_H
#define TR_KERNEL_INTEGRATOR_NAIVE_H

#include "bsdf.h"
#include "compat.h"
#include "film.h"
#include "material.h"
#include "material_eval.h"
#include "rng.h"
#include "scene_view.h"
#include "sun.h"
#include "types.h"
#include "vec.h"

/* Radiance arriving along `ray`. Before each intersection the path continues with
 * probability p = 1 - 1/(max_depth - depth) (depth counts from 1) and its energy is
 * divided by p, so the estimate stays unbiased up to the truncation at depth
 * max_depth - 1 where p reaches 0: a path meets at most max_depth - 2 surfaces.
 * Emission is added wherever a material has emittance (the thesis's emitters, which
 * also end the path); the thesis divided only the final emission by the last p,
 * we divide the throughput at every step, which is what keeps the mean right.
 * *rays counts the intersection queries made; `surface` (may be null) receives the
 * first hit that is not a perfect mirror or smooth glass, for the passes, and in
 * surface->direct the direct part of the radiance: as tr_trace_pt defines it, the emission
 * found up to and including the vertex after that surface S (naive has no light samples,
 * so at S only the BSDF's direction finds light). */
TR_FN tr_vec3 tr_trace_naive(const tr_scene_view *s, tr_ray ray, int max_depth, tr_rng *rng,
                             uint32_t *rays, tr_sample *surface) {
    tr_vec3 radiance = v3s(0.0f);
    tr_vec3 throughput = v3s(1.0f);
    int depth = 0;
    int direct_depth = max_depth + 1; /* the vertex whose emission ends the direct part */
    int direct_done = 0;
    tr_vec3 direct = v3s(0.0f);
    for (;;) {
        ++depth;
        int remaining = max_depth - depth;
        if (remaining <= 1) {
            break; /* p <= 0 */
        }
        float p = 1.0f - 1.0f / (float)remaining;
        if (tr_rng_float(rng) >= p) {
            break;
        }
        throughput = v3_scale(throughput, 1.0f / p);

        tr_hit hit;
        *rays += 1;
        if (!tr_intersect_scene(s, &ray, &hit)) {
            if (s->sun_count > 0u) { /* an escaping ray may see the sun */
                radiance = v3_add(radiance, v3_mul(throughput, tr_sun_radiance(s, ray.dir)));
            }
            if (surface && depth == 1) {
                surface->emission = radiance;
            }
            break;
        }
        tr_triangle tri_tmp;
        TR_CONST_GLOBAL tr_triangle *tri = tr_view_triangle(s, hit.triangle, &tri_tmp);
        tr_vec3 p_hit = v3_madd(ray.origin, ray.dir, hit.t);
        tr_bsdf_params m =
            tr_material_eval(s, hit.triangle, hit.u, hit.v, p_hit, tri->normal, ray.dir);
        if (surface) {
            tr_sample_surface(surface, &m, ray.dir, hit.t, hit.triangle);
        }
        if (direct_depth > max_depth && !tr_bsdf_is_delta(&m)) {
            direct_depth = depth + 1;
        }
        if (m.emittance > 0.0f) {
            radiance = v3_add(radiance, v3_scale(v3_mul(throughput, m.color), m.emittance));
        }
        if (surface && depth == 1) {
            /* The first hit's emission (TR_PASS_EMISSION), roulette's weight included. */
            surface->emission = radiance;
        }
        if (depth == direct_depth) {
            direct = radiance;
            direct_done = 1;
        }
        if (m.type == TR_MATERIAL_EMITTER) {
            break;
        }
        tr_vec3 origin, dir, weight;
        if (tr_material_scatter_naive(&m, ray.dir, p_hit, rng, &origin, &dir, &weight) !=
            TR_SCATTER_CONTINUE) {
            break;
        }
        throughput = v3_mul(throughput, weight);
        ray = tr_ray_make(origin, dir, 0.0f, TR_INFINITY);
    }
    if (surface) {
        surface->direct = direct_done ? direct : radiance;
    }
    return radiance;
}

#endif
