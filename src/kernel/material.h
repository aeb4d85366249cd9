/* material.h - the thesis's four materials (section 3.1.2) as used by the naive
 * integrator: each turns an incoming ray at a hit into the next ray and a colour
 * factor for the path's throughput. Dispatch is a switch on the material type; the
 * parameters come from the material stage (material_eval.h). The smooth dielectric's
 * Fresnel choice (tr_glass_sample) is shared with the pt integrator's BSDF (bsdf.h). */
#ifndef TR_KERNEL_MATERIAL_H
#define TR_KERNEL_MATERIAL_H

#include "compat.h"
#include "material_eval.h"
#include "rng.h"
#include "sampling.h"
#include "types.h"
#include "vec.h"

/* Unpolarised Fresnel reflectance of a smooth dielectric boundary, for light arriving
 * from the side of index n1 onto the side of index n2 with cos(theta_i) = cos_i >= 0.
 * Returns 1 on total internal reflection. The average of the s and p reflectances is
 * (Rs + Rp) / 2 - the thesis's code divided only Rp by two (the mis-parenthesised
 * average); this is the physical quantity.
 * *cos_t receives cos(theta_t) (0 on total internal reflection). */
TR_FN float tr_fresnel_dielectric(float cos_i, float n1, float n2, float *cos_t) {
    float eta = n1 / n2;
    float sin2_t = eta * eta * tr_fmaxf(0.0f, 1.0f - cos_i * cos_i);
    if (sin2_t >= 1.0f) {
        *cos_t = 0.0f;
        return 1.0f;
    }
    float ct = tr_sqrtf(1.0f - sin2_t);
    float rs = (n1 * cos_i - n2 * ct) / (n1 * cos_i + n2 * ct);
    float rp = (n2 * cos_i - n1 * ct) / (n2 * cos_i + n1 * ct);
    *cos_t = ct;
    return 0.5f * (rs * rs + rp * rp);
}

/* Moves a surface point off the surface along n, relative to its magnitude, so that the
 * next ray does not hit the triangle it starts on. */
TR_FN tr_vec3 tr_offset_origin(tr_vec3 p, tr_vec3 n) {
    float scale = tr_fmaxf(1.0f, v3_max_component(v3(tr_fabsf(p.x), tr_fabsf(p.y), tr_fabsf(p.z))));
    return v3_madd(p, n, 1e-4f * scale);
}

/* Where a ray leaving the surface along wi starts: just off the surface on wi's side of
 * the shading normal, from the terminator-corrected point b->ps (Hanika 2021, texture.h)
 * when that is the side the shading normal faces. Without vertex normals (ns == ng,
 * ps == p) this is tr_offset_origin(p, ng or -ng). */
TR_FN tr_vec3 tr_surface_origin(const tr_bsdf_params *b, tr_vec3 p, tr_vec3 wi) {
    int front = v3_dot(wi, b->ns) > 0.0f;
    return tr_offset_origin(front ? b->ps : p, front ? b->ns : v3_neg(b->ns));
}

/* The smooth dielectric's one random choice, shared by both integrators: light arriving
 * along unit direction d at a boundary whose unit normal n points to the outside (index 1;
 * the inside has index ior) is reflected with the exact Fresnel probability r, refracted
 * otherwise. Consumes one random number. *wi receives the new direction, *prob the
 * probability of the lobe taken (r or 1 - r). Returns 1 when reflected. */
TR_FN int tr_glass_sample(tr_vec3 d, tr_vec3 n, float ior, float u, tr_vec3 *wi, float *prob) {
    float cos_dn = v3_dot(d, n);
    /* The normal on the side the light came from. */
    tr_vec3 nf = cos_dn > 0.0f ? v3_neg(n) : n;
    /* Entering when the light meets the front of the normal, leaving otherwise. */
    int entering = cos_dn < 0.0f;
    float n1 = entering ? 1.0f : ior;
    float n2 = entering ? ior : 1.0f;
    float cos_i = tr_fabsf(cos_dn);
    float cos_t;
    float r = tr_fresnel_dielectric(cos_i, n1, n2, &cos_t);
    if (u < r) {
        *wi = v3_reflect(d, nf);
        *prob = r;
        return 1;
    }
    float eta = n1 / n2;
    /* Snell's law in vector form: t = eta d + (eta cos_i - cos_t) n. */
    *wi = v3_normalize(v3_add(v3_scale(d, eta), v3_scale(nf, eta * cos_i - cos_t)));
    *prob = 1.0f - r;
    return 0;
}

#define TR_SCATTER_ABSORBED 0
#define TR_SCATTER_CONTINUE 1

/* Scatters the ray arriving along unit direction `dir` at point p of a surface with the
 * parameters b (tr_material_eval; b->ns is the normal used). Diffuse and glossy surfaces
 * are two-sided; for glass, the normal must point to the outside (the side of index 1):
 * it decides whether the ray enters or leaves, so closed glass shapes need
 * outward-facing normals. On TR_SCATTER_CONTINUE, *next_origin / *next_dir hold the new
 * ray and *weight the factor to multiply the throughput by. Emitters do not scatter (the
 * caller ends the path there). */
TR_FN int tr_material_scatter_naive(const tr_bsdf_params *b, tr_vec3 dir, tr_vec3 p, tr_rng *rng,
                                    tr_vec3 *next_origin, tr_vec3 *next_dir, tr_vec3 *weight) {
    tr_vec3 n = b->ns;
    float cos_dn = v3_dot(dir, n);
    /* The normal on the side the ray came from. */
    tr_vec3 nf = cos_dn > 0.0f ? v3_neg(n) : n;
    *weight = b->color;
    switch (b->type) {
    case TR_MATERIAL_DIFFUSE: {
        /* Cosine-weighted sampling: the cosine and 1/pi of the Lambertian BRDF cancel
         * against the pdf, leaving the albedo as the weight. */
        *next_dir = tr_sample_cosine_hemisphere(rng, nf);
        *next_origin = tr_offset_origin(p, nf);
        return TR_SCATTER_CONTINUE;
    }
    case TR_MATERIAL_GLASS: {
        float prob;
        int reflected = tr_glass_sample(dir, n, b->ior, tr_rng_float(rng), next_dir, &prob);
        *next_origin = tr_offset_origin(p, reflected ? nf : v3_neg(nf));
        return TR_SCATTER_CONTINUE;
    }
    case TR_MATERIAL_GLOSSY: {
        /* A cosine-weighted cone around the mirror direction, half-angle roughness*pi/2
         * (roughness 0: a perfect mirror). Directions that fall below the surface are
         * absorbed. */
        tr_vec3 mirror = v3_reflect(dir, nf);
        float angle = tr_fminf(tr_fmaxf(b->roughness, 0.0f), 1.0f) * TR_HALF_PI;
        tr_vec3 d = angle > 0.0f ? tr_sample_cosine_cone(rng, mirror, angle) : mirror;
        if (v3_dot(d, nf) <= 0.0f) {
            return TR_SCATTER_ABSORBED;
        }
        *next_dir = d;
        *next_origin = tr_offset_origin(p, nf);
        return TR_SCATTER_CONTINUE;
    }
    default:
        return TR_SCATTER_ABSORBED;
    }
}

#endif
