/* albedo.h - the passes' albedo resolved over a pixel's area, per pixel: what
 * tr_resolve_albedo (src/post/emission.c) runs on the host.
 *
 * At one sample per pixel the albedo pass is the base colour at one jittered point of the
 * pixel, which on a texture's edge (or a material's) is one side or the other and changes
 * from frame to frame. The reconstruction multiplies its filtered illumination back by that
 * albedo, so every frame re-aliases the edge. Here a pixel's albedo is instead the mean base
 * colour over an n x n grid of camera rays: the colour a converged image shows there, for
 * the illumination to be multiplied by. */
#ifndef TR_KERNEL_ALBEDO_H
#define TR_KERNEL_ALBEDO_H

#include "camera.h"
#include "compat.h"
#include "film.h"
#include "integrator_pt.h"
#include "material_eval.h"
#include "psr.h"
#include "scene_view.h"
#include "vec.h"

/* The albedo the passes record for the camera ray `ray` (tr_sample_surface, or through a
 * perfect mirror or smooth glass tr_psr_surface's surface): cut-outs passed, the albedo
 * (tr_bsdf_guide_albedo) of the first surface that is not a delta one. Returns 0 where the
 * ray finds no such surface (it leaves the scene, or the delta chain gives up), 1
 * otherwise. */
TR_FN int tr_first_albedo(const tr_scene_view *s, tr_ray ray, tr_vec3 *albedo) {
    for (int holes = 0;; ++holes) {
        tr_hit hit;
        if (!tr_intersect_scene(s, &ray, &hit)) {
            return 0;
        }
        tr_triangle tri_tmp;
        TR_CONST_GLOBAL tr_triangle *tri = tr_view_triangle(s, hit.triangle, &tri_tmp);
        const tr_vec3 p = v3_madd(ray.origin, ray.dir, hit.t);
        const tr_bsdf_params m =
            tr_material_eval(s, hit.triangle, hit.u, hit.v, p, tri->normal, ray.dir);
        if (m.hole && holes < TR_MAX_HOLES) {
            ray.tmin = hit.t + 1e-5f * tr_fmaxf(1.0f, hit.t);
            continue;
        }
        if (!tr_bsdf_is_delta(&m)) {
            *albedo = tr_bsdf_guide_albedo(&m, ray.dir);
            return 1;
        }
        tr_sample chain;
        tr_sample_clear(&chain);
        (void)tr_psr_surface(s, ray, hit, m, &chain);
        *albedo = chain.albedo;
        return chain.prim != 0u;
    }
}

/* The mean albedo (tr_first_albedo) of the camera rays through the centres of an n x n grid
 * of cells over pixel (x, y) that find a surface; 0 where none does. The mean is over the
 * rays that hit: a pixel on an object's outline against the sky multiplies its illumination
 * (which only its rays on the object carry) by the object's colour, not by half of it. */
TR_FN tr_vec3 tr_albedo_resolve_pixel(const tr_scene_view *s, const tr_camera *cam, int x, int y,
                                      int n) {
    const float inv_n = 1.0f / (float)n;
    tr_vec3 sum = v3s(0.0f);
    int hits = 0;
    for (int sy = 0; sy < n; ++sy) {
        for (int sx = 0; sx < n; ++sx) {
            const tr_ray ray = tr_camera_ray(cam, (float)x, (float)y, ((float)sx + 0.5f) * inv_n,
                                             ((float)sy + 0.5f) * inv_n);
            tr_vec3 a;
            if (tr_first_albedo(s, ray, &a)) {
                sum = v3_add(sum, a);
                ++hits;
            }
        }
    }
    return hits > 0 ? v3_scale(sum, 1.0f / (float)hits) : v3s(0.0f);
}

#endif
