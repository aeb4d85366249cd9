/* bsdf.h - the physically based materials of the `pt` integrator: each exposes eval
 * (the BSDF value f), pdf (solid angle density of its sampler) and sample.
 *
 * Conventions: every function takes the surface's tr_bsdf_params from the material stage
 * (material_eval.h), whose shading normal b->ns (either orientation) is the n below; wo
 * is the unit direction towards the previous vertex (minus the ray direction), wi the
 * unit direction towards the next one. Diffuse and glossy surfaces are two-sided: they
 * reflect on the side wo lies on. Glass needs n pointing outside (index 1).
 *
 *   diffuse  Lambertian, f = colour / pi, cosine-weighted sampling.
 *   glossy   roughness 0: a perfect mirror (delta) with Schlick's Fresnel;
 *            roughness > 0: a GGX microfacet conductor (Walter et al., "Microfacet
 *            Models for Refraction through Rough Surfaces", EGSR 2007) with the
 *            height-correlated Smith shadowing (Heitz, "Understanding the
 *            Masking-Shadowing Function in Microfacet-Based BRDFs", JCGT 2014),
 *            Schlick's Fresnel with F0 = colour, and sampling of the visible normals
 *            (Heitz, "Sampling the GGX Distribution of Visible Normals", JCGT 2018).
 *            alpha = tr_ggx_alpha(roughness), see docs/integrators.md.
 *   glass    smooth dielectric (delta): exact Fresnel, total internal reflection,
 *            the colour as a filter on both lobes (as the naive integrator does).
 *   principled  glTF metallic-roughness: diffuse base + GGX layer (bsdf_principled.h).
 *   emitter  emits only: its BSDF is black.
 */
#ifndef TR_KERNEL_BSDF_H
#define TR_KERNEL_BSDF_H

#include "compat.h"
#include "material.h"
#include "material_eval.h"
#include "rng.h"
#include "sampling.h"
#include "types.h"
#include "vec.h"

/* GGX alpha below this counts as this: the distribution's peak 1/(pi alpha^2) stays
 * finite in float. */
#define TR_GGX_MIN_ALPHA 1e-3f

typedef struct tr_scatter {
    tr_vec3 wi;     /* sampled direction (unit) */
    tr_vec3 weight; /* f |cos(wi, n)| / pdf; for delta lobes the lobe's weight */
    float pdf;      /* solid-angle pdf; for delta lobes the probability of the lobe */
    int delta;      /* 1 when wi came from a delta lobe (mirror, smooth glass) */
} tr_scatter;

/* The thesis's roughness r (its glossy cone's half-angle is r pi/2) mapped onto GGX's
 * alpha: the median angle between a sampled direction and the mirror direction is
 * asin(sin(r pi/2) / sqrt 2) for the thesis's cosine-weighted cone; GGX's median
 * half-vector angle is atan(alpha), and reflection doubles angles about the normal,
 * so alpha = tan(asin(sin(r pi/2) / sqrt 2) / 2). Written with sin and sqrt only:
 * tan(x/2) = sin x / (1 + cos x). r = 1 gives alpha = tan(pi/8) = 0.414. */
TR_FN float tr_ggx_alpha(float roughness) {
    float r = tr_fminf(tr_fmaxf(roughness, 0.0f), 1.0f);
    float s = tr_sinf(r * TR_HALF_PI) * 0.70710678118654752f;
    float a = s / (1.0f + tr_sqrtf(tr_fmaxf(0.0f, 1.0f - s * s)));
    return tr_fmaxf(a, TR_GGX_MIN_ALPHA);
}

/* Whether the material scatters only into isolated directions. */
TR_FN int tr_bsdf_is_delta(const tr_bsdf_params *m) {
    return m->type == TR_MATERIAL_GLASS || (m->type == TR_MATERIAL_GLOSSY && m->roughness <= 0.0f);
}

/* Schlick's approximation with a coloured F0. */
TR_FN tr_vec3 tr_fresnel_schlick(tr_vec3 f0, float cos_theta) {
    float c = tr_fminf(tr_fmaxf(1.0f - cos_theta, 0.0f), 1.0f);
    float c5 = (c * c) * (c * c) * c;
    return v3_add(f0, v3_scale(v3_sub(v3s(1.0f), f0), c5));
}

/* GGX normal distribution D(h) for cos(theta_h) = c (Walter et al. 2007, eq. 33). */
TR_FN float tr_ggx_d(float alpha, float c) {
    if (c <= 0.0f) {
        return 0.0f;
    }
    float a2 = alpha * alpha;
    float t = c * c * (a2 - 1.0f) + 1.0f;
    return a2 / (TR_PI * t * t);
}

/* Smith's Lambda for GGX for a direction with cos(theta) = c (Heitz 2014, eq. 72). */
TR_FN float tr_ggx_lambda(float alpha, float c) {
    float c2 = c * c;
    if (c2 <= 0.0f) {
        return 1e30f;
    }
    float tan2 = tr_fmaxf(0.0f, 1.0f - c2) / c2;
    return 0.5f * (tr_sqrtf(1.0f + alpha * alpha * tan2) - 1.0f);
}

/* Local frame around the normal on wo's side: returns the normal facing wo. */
TR_FN tr_vec3 tr_bsdf_facing(tr_vec3 n, tr_vec3 wo) {
    return v3_dot(wo, n) < 0.0f ? v3_neg(n) : n;
}

/* GGX conductor f for wo, wi on the side of the unit normal nf (cosines > 0). */
TR_FN tr_vec3 tr_ggx_eval(const tr_bsdf_params *m, tr_vec3 nf, tr_vec3 wo, tr_vec3 wi) {
    float co = v3_dot(wo, nf), ci = v3_dot(wi, nf);
    if (co <= 0.0f || ci <= 0.0f) {
        return v3s(0.0f);
    }
    float alpha = tr_ggx_alpha(m->roughness);
    tr_vec3 h = v3_normalize(v3_add(wo, wi));
    float d = tr_ggx_d(alpha, v3_dot(h, nf));
    float g2 = 1.0f / (1.0f + tr_ggx_lambda(alpha, co) + tr_ggx_lambda(alpha, ci));
    tr_vec3 f = tr_fresnel_schlick(m->color, v3_dot(wo, h));
    return v3_scale(f, d * g2 / (4.0f * co * ci));
}

/* Pdf of the visible-normal sampler: G1(wo) D(h) / (4 cos_o) (Heitz 2018, eq. 17 with
 * the reflection Jacobian 1 / (4 wo.h)). */
TR_FN float tr_ggx_pdf(const tr_bsdf_params *m, tr_vec3 nf, tr_vec3 wo, tr_vec3 wi) {
    float co = v3_dot(wo, nf), ci = v3_dot(wi, nf);
    if (co <= 0.0f || ci <= 0.0f) {
        return 0.0f;
    }
    float alpha = tr_ggx_alpha(m->roughness);
    tr_vec3 h = v3_normalize(v3_add(wo, wi));
    float g1 = 1.0f / (1.0f + tr_ggx_lambda(alpha, co));
    return g1 * tr_ggx_d(alpha, v3_dot(h, nf)) / (4.0f * co);
}

/* A visible normal for the local view direction v (v.z > 0), isotropic alpha
 * (Heitz 2018, section 3: stretch, sample the projected hemisphere, unstretch). */
TR_FN tr_vec3 tr_ggx_sample_vndf(float alpha, tr_vec3 v, float u1, float u2) {
    tr_vec3 vh = v3_normalize(v3(alpha * v.x, alpha * v.y, v.z));
    float len2 = vh.x * vh.x + vh.y * vh.y;
    tr_vec3 t1 =
        len2 > 0.0f ? v3_scale(v3(-vh.y, vh.x, 0.0f), 1.0f / tr_sqrtf(len2)) : v3(1.0f, 0.0f, 0.0f);
    tr_vec3 t2 = v3_cross(vh, t1);
    float r = tr_sqrtf(u1);
    float phi = TR_TWO_PI * u2;
    float p1 = r * tr_cosf(phi);
    float p2 = r * tr_sinf(phi);
    float s = 0.5f * (1.0f + vh.z);
    p2 = (1.0f - s) * tr_sqrtf(tr_fmaxf(0.0f, 1.0f - p1 * p1)) + s * p2;
    float p3 = tr_sqrtf(tr_fmaxf(0.0f, 1.0f - p1 * p1 - p2 * p2));
    tr_vec3 nh = v3_add(v3_add(v3_scale(t1, p1), v3_scale(t2, p2)), v3_scale(vh, p3));
    return v3_normalize(v3(alpha * nh.x, alpha * nh.y, tr_fmaxf(0.0f, nh.z)));
}

/* The principled material (glTF's metallic-roughness), built on the GGX helpers above. */
#include "bsdf_principled.h"

/* The principled functions are out of line (TR_FN_NOINLINE); these hand them copies, so
 * that no caller's tr_bsdf_params or tr_scatter has its address taken: the compiler keeps
 * those in registers for every other material instead of storing each field at every
 * vertex. */
TR_FN tr_vec3 tr_principled_eval_copy(tr_bsdf_params m, tr_vec3 nf, tr_vec3 wo, tr_vec3 wi) {
    return tr_principled_eval(&m, nf, wo, wi);
}
TR_FN float tr_principled_pdf_copy(tr_bsdf_params m, tr_vec3 nf, tr_vec3 wo, tr_vec3 wi) {
    return tr_principled_pdf(&m, nf, wo, wi);
}
TR_FN int tr_principled_sample_copy(tr_bsdf_params m, tr_vec3 nf, tr_vec3 wo, float ulobe, float u1,
                                    float u2, tr_scatter *s) {
    tr_scatter r;
    int ok = tr_principled_sample(&m, nf, wo, ulobe, u1, u2, &r);
    *s = r;
    return ok;
}

/* BSDF value f(wo, wi) (without the cosine). Zero for delta lobes and emitters. */
TR_FN_INLINE tr_vec3 tr_bsdf_eval(const tr_bsdf_params *m, tr_vec3 wo, tr_vec3 wi) {
    tr_vec3 nf = tr_bsdf_facing(m->ns, wo);
    switch (m->type) {
    case TR_MATERIAL_DIFFUSE:
        if (v3_dot(wi, nf) <= 0.0f) {
            return v3s(0.0f);
        }
        return v3_scale(m->color, TR_INV_PI);
    case TR_MATERIAL_GLOSSY:
        if (m->roughness <= 0.0f) {
            return v3s(0.0f);
        }
        return tr_ggx_eval(m, nf, wo, wi);
    case TR_MATERIAL_PRINCIPLED:
        return tr_principled_eval_copy(*m, nf, wo, wi);
    default:
        return v3s(0.0f);
    }
}

/* Solid-angle pdf with which tr_bsdf_sample draws wi. Zero for delta lobes. */
TR_FN_INLINE float tr_bsdf_pdf(const tr_bsdf_params *m, tr_vec3 wo, tr_vec3 wi) {
    tr_vec3 nf = tr_bsdf_facing(m->ns, wo);
    switch (m->type) {
    case TR_MATERIAL_DIFFUSE: {
        float c = v3_dot(wi, nf);
        return c > 0.0f ? c * TR_INV_PI : 0.0f;
    }
    case TR_MATERIAL_GLOSSY:
        if (m->roughness <= 0.0f) {
            return 0.0f;
        }
        return tr_ggx_pdf(m, nf, wo, wi);
    case TR_MATERIAL_PRINCIPLED:
        return tr_principled_pdf_copy(*m, nf, wo, wi);
    default:
        return 0.0f;
    }
}

/* Draws wi from the uniform numbers ulobe (the choice between lobes: glass's reflect or
 * refract) and (u1, u2) (the direction inside a lobe). Returns 0 when the path ends here
 * (emitters, directions below the surface, zero weight). */
TR_FN_INLINE int tr_bsdf_sample(const tr_bsdf_params *m, tr_vec3 wo, float ulobe, float u1,
                                float u2, tr_scatter *s) {
    tr_vec3 nf = tr_bsdf_facing(m->ns, wo);
    s->delta = 0;
    switch (m->type) {
    case TR_MATERIAL_DIFFUSE: {
        s->wi = tr_sample_cosine_hemisphere_u(u1, u2, nf);
        float c = v3_dot(s->wi, nf);
        if (c <= 0.0f) {
            return 0;
        }
        s->pdf = c * TR_INV_PI;
        s->weight = m->color; /* (colour / pi) cos / (cos / pi) */
        return 1;
    }
    case TR_MATERIAL_GLOSSY: {
        float co = v3_dot(wo, nf);
        if (m->roughness <= 0.0f) {
            s->wi = v3_reflect(v3_neg(wo), nf);
            s->delta = 1;
            s->pdf = 1.0f;
            s->weight = tr_fresnel_schlick(m->color, co);
            return 1;
        }
        float alpha = tr_ggx_alpha(m->roughness);
        tr_vec3 t, b;
        v3_basis(nf, &t, &b);
        tr_vec3 vl = v3(v3_dot(wo, t), v3_dot(wo, b), co);
        tr_vec3 hl = tr_ggx_sample_vndf(alpha, vl, u1, u2);
        tr_vec3 h = v3_add(v3_add(v3_scale(t, hl.x), v3_scale(b, hl.y)), v3_scale(nf, hl.z));
        s->wi = v3_normalize(v3_reflect(v3_neg(wo), h));
        float ci = v3_dot(s->wi, nf);
        if (ci <= 0.0f || co <= 0.0f) {
            return 0;
        }
        s->pdf = tr_ggx_pdf(m, nf, wo, s->wi);
        if (!(s->pdf > 0.0f)) {
            return 0;
        }
        /* F G2 / G1(wo), written through eval and pdf so that the three agree. */
        s->weight = v3_scale(tr_ggx_eval(m, nf, wo, s->wi), ci / s->pdf);
        return 1;
    }
    case TR_MATERIAL_GLASS: {
        /* The lobe's probability is its Fresnel weight, so the weight is the filter. */
        s->delta = 1;
        s->weight = m->color;
        tr_glass_sample(v3_neg(wo), m->ns, m->ior, ulobe, &s->wi, &s->pdf);
        return 1;
    }
    case TR_MATERIAL_PRINCIPLED:
        return tr_principled_sample_copy(*m, nf, wo, ulobe, u1, u2, s);
    default:
        return 0;
    }
}

/* Radiance a surface with parameters m emits towards w. Emitters are one-sided (the side
 * the geometric normal m->ng points to) unless TR_MATERIAL_TWO_SIDED is set. */
TR_FN tr_vec3 tr_emitted(const tr_bsdf_params *m, tr_vec3 w) {
    if (!(m->emittance > 0.0f)) {
        /* Emission of a non-emitter material (principled, glTF emissive). */
        if (m->emission.x > 0.0f || m->emission.y > 0.0f || m->emission.z > 0.0f) {
            if ((m->flags & TR_MATERIAL_TWO_SIDED) == 0u && v3_dot(w, m->ng) <= 0.0f) {
                return v3s(0.0f);
            }
            return m->emission;
        }
        return v3s(0.0f);
    }
    if ((m->flags & TR_MATERIAL_TWO_SIDED) == 0u && v3_dot(w, m->ng) <= 0.0f) {
        return v3s(0.0f);
    }
    return v3_scale(m->color, m->emittance);
}

/* tr_emitted(tr_material_eval(s, triangle, u, v, p, ng, .), w): what next-event estimation
 * needs of a light's material. Without vertex attributes or material extras it reads the
 * material alone, never building the whole tr_bsdf_params in memory. */
TR_FN tr_vec3 tr_emitted_at(const tr_scene_view *s, uint32_t triangle, float u, float v, tr_vec3 p,
                            tr_vec3 ng, tr_vec3 w) {
    uint32_t mi = s->triangles[triangle].material;
    if (triangle < s->tri_verts_count || s->material_ext_count > 0u) {
        tr_bsdf_params t;
        tr_material_eval_attributes(s, triangle, mi, u, v, p, ng, &t);
        return tr_emitted(&t, w);
    }
    tr_material m = s->materials[mi];
    tr_bsdf_params b = tr_material_params(&m, ng);
    return tr_emitted(&b, w);
}

#endif
