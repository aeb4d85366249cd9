/* psr.h - primary surface replacement: the passes of a pixel whose camera ray first meets a
 * perfect mirror or smooth glass describe the first surface behind that delta chain, as if it
 * stood where the camera sees its image. Followed here as A. Panteleev describes it for
 * Quake II RTX ("Rendering Perfect Reflections and Refractions in Path-Traced Games", NVIDIA
 * developer blog, 2020), which NVIDIA's NRD documents as "primary surface replacement": the
 * guides (albedo, normal, primitive) of the first non-delta vertex, its normal mirrored back
 * through the reflections of the chain, and the whole path length as the hit distance, so
 * that the virtual position - the camera plus the view direction times that length - is what
 * the temporal stage reprojects. Refraction bends the chain without mirroring the normal:
 * there the virtual position is an approximation, which the reprojection's plane test
 * tolerates only while the camera moves little.
 *
 * The chain is traced apart from the path, with the more probable lobe at every glass vertex
 * (reflection where the Fresnel weight is above one half, refraction otherwise): the path's
 * own choice changes from frame to frame at 1 sample per pixel, and guides that jump between
 * the reflected and the refracted surface make the temporal stage throw the history away at
 * every jump. With the guides fixed, the history averages both lobes' light over frames,
 * which is what the pixel's value is. It costs the chain's rays again, on the pixels that see
 * a delta surface first only.
 *
 * The albedo is the surface's own only where the chain keeps all of the pixel's light (a
 * mirror). At glass the other lobe's light - the sky reflected by a sphere whose refraction
 * the chain follows - is not modulated by that surface at all, and demodulating it by a dark
 * surface's albedo inflates it (then the filters average it with its neighbours and multiply
 * the dark albedo back: black speckles). So the albedo is k a + (1 - k), k the product of the
 * chain's lobe probabilities (1 - F or F per glass vertex): the followed lobes' share of the
 * light modulated by a, the rest taken as unmodulated. */
#ifndef TR_KERNEL_PSR_H
#define TR_KERNEL_PSR_H

#include "bsdf.h"
#include "compat.h"
#include "material.h"
#include "material_eval.h"
#include "scene_view.h"
#include "types.h"
#include "vec.h"

/* Delta vertices followed before the chain gives up (the pixel then takes the first delta
 * surface's passes: tr_psr_keep_first). */
#define TR_PSR_MAX_BOUNCES 4

/* Where the chain finds no surface (it leaves the scene - the sky a glass sphere's rim
 * reflects -, or ends after TR_PSR_MAX_BOUNCES delta vertices), the passes describe the
 * first delta surface itself: its primitive (marked TR_PRIM_PSR_CURVED: what it shows moves
 * over it as the camera moves), its normal facing the camera, its distance, albedo 1 (its
 * light is no surface's). Without a surface such a pixel kept no history and took no
 * neighbour's light: its one sample, often black, stood alone. */
TR_FN void tr_psr_keep_first(tr_sample *out, uint32_t first_prim, tr_vec3 n, float t) {
    if (first_prim == 0u) {
        return;
    }
    out->albedo = v3s(1.0f);
    out->normal = n;
    out->depth = t;
    out->prim = first_prim | TR_PRIM_PSR_CURVED;
}

/* The passes' surface for a camera ray `ray` whose first hit (hit, material m) is a delta
 * surface: albedo (k a + 1 - k: above), prim and the normal (turned to face the arriving
 * ray, then mirrored back through every reflection of the chain: the normal of the reflected
 * image) of the first non-delta vertex, and as depth the length of the chain up to it; the
 * primitive id carries TR_PRIM_PSR_CURVED where the chain refracted or met a smooth-shaded
 * surface. *out's other fields are left alone; where the chain leaves the scene or is longer
 * than TR_PSR_MAX_BOUNCES, the first delta surface's (tr_psr_keep_first). Returns the
 * intersection queries it made. */
TR_FN uint32_t tr_psr_surface(const tr_scene_view *s, tr_ray ray, tr_hit hit, tr_bsdf_params m,
                              tr_sample *out) {
    /* The rows of the product of the reflections met so far (Householder matrices
     * I - 2 n n^T, each symmetric): a normal seen through the chain is mirrored back by it. */
    tr_vec3 r0 = v3(1.0f, 0.0f, 0.0f), r1 = v3(0.0f, 1.0f, 0.0f), r2 = v3(0.0f, 0.0f, 1.0f);
    float len = 0.0f;
    int holes = 0;
    uint32_t rays = 0u;
    uint32_t curved = 0u; /* TR_PRIM_PSR_CURVED once the chain meets a curve or refracts */
    float kept = 1.0f;
    uint32_t first_prim = 0u;
    tr_vec3 first_n = v3s(0.0f);
    float first_t = 0.0f;
    out->prim = 0u;
    out->depth = 0.0f;
    for (int bounce = 0;;) {
        if (m.hole && holes < TR_MAX_HOLES) {
            /* A cut-out: the same ray goes on, its length still counted from its origin. */
            ++holes;
            ray.tmin = hit.t + 1e-5f * tr_fmaxf(1.0f, hit.t);
        } else {
            const tr_vec3 p = v3_madd(ray.origin, ray.dir, hit.t);
            len += hit.t;
            /* The normal on the side the ray arrives from. */
            const tr_vec3 wo = v3_neg(ray.dir);
            const tr_vec3 nf = tr_bsdf_facing(m.ns, wo);
            if (bounce == 0) {
                /* The first delta surface: the passes' surface where the chain finds none. */
                first_prim = hit.triangle + 1u;
                first_n = nf;
                first_t = len;
            }
            if (!tr_bsdf_is_delta(&m)) {
                out->albedo =
                    v3_add(v3_scale(tr_bsdf_guide_albedo(&m, wo), kept), v3s(1.0f - kept));
                out->normal = v3(v3_dot(r0, nf), v3_dot(r1, nf), v3_dot(r2, nf));
                out->depth = len;
                out->prim = (hit.triangle + 1u) | curved;
                return rays;
            }
            if (bounce >= TR_PSR_MAX_BOUNCES) {
                tr_psr_keep_first(out, first_prim, first_n, first_t);
                return rays;
            }
            tr_scatter bs;
            if (!tr_bsdf_sample(&m, wo, 0.5f, 0.5f, 0.5f, &bs)) {
                tr_psr_keep_first(out, first_prim, first_n, first_t);
                return rays;
            }
            kept *= bs.delta ? bs.pdf : 1.0f;
            if (v3_dot(bs.wi, nf) > 0.0f) { /* reflected: mirror the frame about nf */
                r0 = v3_sub(r0, v3_scale(nf, 2.0f * v3_dot(r0, nf)));
                r1 = v3_sub(r1, v3_scale(nf, 2.0f * v3_dot(r1, nf)));
                r2 = v3_sub(r2, v3_scale(nf, 2.0f * v3_dot(r2, nf)));
            } else {
                curved = TR_PRIM_PSR_CURVED;
            }
            if (tr_fabsf(v3_dot(m.ns, m.ng)) < 0.9999f) {
                curved = TR_PRIM_PSR_CURVED;
            }
            holes = 0;
            ++bounce;
            ray = tr_ray_make(tr_surface_origin(&m, p, bs.wi), bs.wi, 0.0f, TR_INFINITY);
        }
        ++rays;
        if (!tr_intersect_scene(s, &ray, &hit)) {
            tr_psr_keep_first(out, first_prim, first_n, first_t);
            return rays;
        }
        tr_triangle tri_tmp;
        TR_CONST_GLOBAL tr_triangle *tri = tr_view_triangle(s, hit.triangle, &tri_tmp);
        const tr_vec3 q = v3_madd(ray.origin, ray.dir, hit.t);
        m = tr_material_eval(s, hit.triangle, hit.u, hit.v, q, tri->normal, ray.dir);
    }
}

#endif
