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
 *   principled  glTF metallic-roughness: diffuse base + GGX layer (bsdf_principled.h),
 *            mixed with a rough dielectric boundary where it transmits
 *            (bsdf_dielectric.h).
 *   emitter  emits only: its BSDF is black.
 */
#ifndef TR_KERNEL_BSDF_H
#define TR_KERNEL_BSDF_H

#include "compat.h"
#include "ggx_ms.h"
#include "material.h"
#include "material_eval.h"
#include "rng.h"
#include "sampling.h"
#include "types.h"
#include "vec.h"

/* GGX alpha below this counts as this: the distribution's peak 1/(pi alpha^2) stays
 * finite in float. */
#define TR_GGX_MIN_ALPHA 1e-3f

/* tr_bsdf_params.flags: smooth glass regularized (tr_bsdf_regularize, below). */
#define TR_BSDF_REGULARIZED 0x80000000u

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
    return (m->type == TR_MATERIAL_GLASS && (m->flags & TR_BSDF_REGULARIZED) == 0u) ||
           (m->type == TR_MATERIAL_GLOSSY && m->roughness <= 0.0f);
}

/* ---- Path regularization --------------------------------------------------------------
 *
 * A path that has met a non-specular surface can reach a small bright emitter (the sun, a
 * small lamp) over a specular or very glossy vertex only by its BSDF sample, which
 * finds it rarely and then with a huge weight: the fireflies of caustics seen on a diffuse
 * floor, which no light sample can take (the specular vertex has no light strategy).
 * Regularization trades them for bias by roughening such lobes after the first
 * non-specular vertex, so that light sampling works there too (A. S. Kaplanyan and C.
 * Dachsbacher, "Path Space Regularization for Holistic and Robust Light Transport",
 * Computer Graphics Forum 32(2), Eurographics 2013: delta BSDFs mollified over a cone;
 * J. Jendersie and T. Grosch, "Microfacet Model Regularization for Robust Light
 * Transport", Computer Graphics Forum 38(4), EGSR 2019: the microfacet roughness raised
 * instead). The camera's own view of mirrors and glass stays sharp: only vertices after a
 * non-specular one are changed (tr_trace_pt_ff). The radius is fixed, not shrinking with
 * the sample count as Kaplanyan and Dachsbacher's consistent variant does: it is meant for
 * real-time frames, and the bias it adds is measured in docs/realtime.md. */

/* Glossy (thesis roughness) and principled (glTF roughness) lobes are raised to at least
 * these: both give GGX alpha 0.16. */
#define TR_REG_ROUGHNESS_GLOSSY 0.3f
#define TR_REG_ROUGHNESS_PRINCIPLED 0.4f
/* Smooth glass becomes its two delta lobes, each spread uniformly over a cone of this
 * half-angle's cosine (0.25 rad) around the reflected or refracted direction, with the
 * lobe's Fresnel weight (Kaplanyan and Dachsbacher's mollifier). */
#define TR_REG_CONE_COS 0.96891242f

/* m roughened for a vertex after a non-specular one. */
TR_FN void tr_bsdf_regularize(tr_bsdf_params *m) {
    if (m->type == TR_MATERIAL_GLOSSY) {
        m->roughness = tr_fmaxf(m->roughness, TR_REG_ROUGHNESS_GLOSSY);
    } else if (m->type == TR_MATERIAL_PRINCIPLED) {
        m->roughness = tr_fmaxf(m->roughness, TR_REG_ROUGHNESS_PRINCIPLED);
        m->clearcoat_roughness = tr_fmaxf(m->clearcoat_roughness, TR_REG_ROUGHNESS_PRINCIPLED);
    } else if (m->type == TR_MATERIAL_GLASS) {
        m->flags |= TR_BSDF_REGULARIZED;
    }
}

/* Regularized glass: the reflected direction *r, the refracted one *t (zero on total
 * internal reflection) and the Fresnel reflectance, for light arriving along -wo. */
TR_FN float tr_reg_glass_dirs(const tr_bsdf_params *m, tr_vec3 wo, tr_vec3 *r, tr_vec3 *t) {
    tr_vec3 d = v3_neg(wo);
    float cos_dn = v3_dot(d, m->ns);
    tr_vec3 nf = cos_dn > 0.0f ? v3_neg(m->ns) : m->ns;
    int entering = cos_dn < 0.0f;
    float n1 = entering ? 1.0f : m->ior;
    float n2 = entering ? m->ior : 1.0f;
    float cos_i = tr_fabsf(cos_dn);
    float cos_t;
    float fr = tr_fresnel_dielectric(cos_i, n1, n2, &cos_t);
    *r = v3_reflect(d, nf);
    *t = v3s(0.0f);
    if (fr < 1.0f) {
        float eta = n1 / n2;
        *t = v3_normalize(v3_add(v3_scale(d, eta), v3_scale(nf, eta * cos_i - cos_t)));
    }
    return fr;
}

/* Regularized glass: the sum of the lobes' probabilities whose cone holds wi, per unit
 * solid angle: the pdf; the BSDF is the colour times it over |cos(wi, n)|. */
TR_FN_NOINLINE float tr_reg_glass_density(tr_bsdf_params m, tr_vec3 wo, tr_vec3 wi) {
    tr_vec3 r, t;
    float fr = tr_reg_glass_dirs(&m, wo, &r, &t);
    float p = 0.0f;
    if (v3_dot(wi, r) >= TR_REG_CONE_COS) {
        p += fr;
    }
    if (fr < 1.0f && v3_dot(wi, t) >= TR_REG_CONE_COS) {
        p += 1.0f - fr;
    }
    return p / (TR_TWO_PI * (1.0f - TR_REG_CONE_COS));
}

TR_FN_NOINLINE tr_vec3 tr_reg_glass_eval(tr_bsdf_params m, tr_vec3 wo, tr_vec3 wi) {
    float c = tr_fabsf(v3_dot(wi, m.ns));
    if (!(c > 1e-4f)) {
        return v3s(0.0f);
    }
    return v3_scale(m.color, tr_reg_glass_density(m, wo, wi) / c);
}

/* Draws a lobe by its Fresnel weight (ulobe) and a direction uniform in its cone. */
TR_FN_NOINLINE int tr_reg_glass_sample(tr_bsdf_params m, tr_vec3 wo, float ulobe, float u1,
                                       float u2, tr_scatter *s) {
    tr_vec3 r, t;
    float fr = tr_reg_glass_dirs(&m, wo, &r, &t);
    tr_vec3 axis = ulobe < fr ? r : t;
    float ct = 1.0f - u1 * (1.0f - TR_REG_CONE_COS);
    float st = tr_sqrtf(tr_fmaxf(0.0f, 1.0f - ct * ct));
    float phi = TR_TWO_PI * u2;
    tr_vec3 a, b;
    v3_basis(axis, &a, &b);
    s->wi = v3_normalize(v3_add(v3_scale(axis, ct), v3_add(v3_scale(a, st * tr_cosf(phi)),
                                                           v3_scale(b, st * tr_sinf(phi)))));
    s->delta = 0;
    s->pdf = tr_reg_glass_density(m, wo, s->wi);
    if (!(s->pdf > 0.0f)) {
        return 0;
    }
    /* f |cos| / pdf: the colour, however many cones hold wi. */
    s->weight = m.color;
    return 1;
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
    tr_vec3 r = v3_scale(f, d * g2 / (4.0f * co * ci));
    if ((m->flags & TR_MATERIAL_MULTISCATTER) != 0u && m->ms) {
        r = v3_add(r, tr_ggx_ms_lobe(m->ms, alpha, m->color, co, ci));
    }
    return r;
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

/* The rough dielectric boundary and the principled material (glTF's metallic-roughness),
 * built on the GGX helpers above. */
#include "bsdf_dielectric.h"
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
        if (m->transmission > 0.0f) {
            return tr_principled_tr_eval(*m, nf, wo, wi);
        }
        return tr_principled_eval_copy(*m, nf, wo, wi);
    case TR_MATERIAL_GLASS:
        return (m->flags & TR_BSDF_REGULARIZED) != 0u ? tr_reg_glass_eval(*m, wo, wi) : v3s(0.0f);
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
        if (m->transmission > 0.0f) {
            return tr_principled_tr_pdf(*m, nf, wo, wi);
        }
        return tr_principled_pdf_copy(*m, nf, wo, wi);
    case TR_MATERIAL_GLASS:
        return (m->flags & TR_BSDF_REGULARIZED) != 0u ? tr_reg_glass_density(*m, wo, wi) : 0.0f;
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
        if ((m->flags & TR_BSDF_REGULARIZED) != 0u) {
            return tr_reg_glass_sample(*m, wo, ulobe, u1, u2, s);
        }
        /* The lobe's probability is its Fresnel weight, so the weight is the filter. */
        s->delta = 1;
        s->weight = m->color;
        tr_glass_sample(v3_neg(wo), m->ns, m->ior, ulobe, &s->wi, &s->pdf);
        return 1;
    }
    case TR_MATERIAL_PRINCIPLED:
        if (m->transmission > 0.0f) {
            return tr_principled_tr_sample(*m, nf, wo, ulobe, u1, u2, s);
        }
        return tr_principled_sample_copy(*m, nf, wo, ulobe, u1, u2, s);
    default:
        return 0;
    }
}

/* ---- Diffuse and specular apart (TR_PASS_SPECULAR) ------------------------------------
 *
 * Per channel, the share of f(wo, wi) that the specular lobes reflect (the GGX layer and
 * the clear coat) rather than a diffuse base: 0 for diffuse, 1 for the lobes with nothing
 * diffuse (glossy, regularized glass), f_spec / f for the principled material. Where f is
 * zero the share is that of the lobes' kind (0 for a principled material). */
TR_FN_NOINLINE tr_vec3 tr_principled_spec_share(tr_bsdf_params m, tr_vec3 wo, tr_vec3 wi) {
    tr_vec3 nf = tr_bsdf_facing(m.ns, wo);
    float co = v3_dot(wo, nf), ci = v3_dot(wi, nf);
    if (co <= 0.0f || ci <= 0.0f) {
        return v3s(0.0f);
    }
    tr_vec3 f = tr_principled_eval(&m, nf, wo, wi);
    /* The diffuse part, as tr_principled_eval and tr_coat_layer weigh it. */
    float k = tr_fminf(tr_fmaxf(m.metallic, 0.0f), 1.0f);
    float kd = (1.0f - k) * (28.0f / 23.0f) * TR_INV_PI * (1.0f - TR_PRINCIPLED_F0) *
               tr_as_factor(ci) * tr_as_factor(co);
    if (m.clearcoat > 0.0f) {
        float c = tr_coat_weight(&m);
        float xo = co, xi = ci;
        if (m.coat_n != 0u) {
            /* The coat's Fresnel at its own normal's cosines (tr_coat_layer_tilted). */
            tr_vec3 nc = tr_coat_normal(&m, nf);
            xo = tr_fmaxf(v3_dot(wo, nc), 0.0f);
            xi = tr_fmaxf(v3_dot(wi, nc), 0.0f);
        }
        float att = (1.0f - c * tr_coat_fresnel(xo)) * (1.0f - c * tr_coat_fresnel(xi));
        float fav = TR_PRINCIPLED_F0 + (1.0f - TR_PRINCIPLED_F0) * (1.0f / 21.0f);
        kd *= att / (1.0f - c * fav);
    }
    tr_vec3 d = v3_scale(m.color, kd);
    return v3(f.x > 0.0f ? tr_fminf(tr_fmaxf(1.0f - d.x / f.x, 0.0f), 1.0f) : 0.0f,
              f.y > 0.0f ? tr_fminf(tr_fmaxf(1.0f - d.y / f.y, 0.0f), 1.0f) : 0.0f,
              f.z > 0.0f ? tr_fminf(tr_fmaxf(1.0f - d.z / f.z, 0.0f), 1.0f) : 0.0f);
}

TR_FN tr_vec3 tr_bsdf_spec_share(const tr_bsdf_params *m, tr_vec3 wo, tr_vec3 wi) {
    if (m->type == TR_MATERIAL_PRINCIPLED) {
        return tr_principled_spec_share(*m, wo, wi);
    }
    return v3s(m->type == TR_MATERIAL_DIFFUSE || m->type == TR_MATERIAL_EMITTER ? 0.0f : 1.0f);
}

/* The specular lobe's Fresnel F0 and GGX alpha (for its directional albedo, which the
 * reconstruction demodulates the specular part by); F0 0 where there is none. */
TR_FN tr_vec3 tr_bsdf_spec_f0(const tr_bsdf_params *m, float *alpha) {
    if (m->type == TR_MATERIAL_PRINCIPLED) {
        *alpha = tr_principled_alpha(m->roughness);
        return tr_principled_f0(m);
    }
    if (m->type == TR_MATERIAL_GLOSSY) {
        *alpha = tr_ggx_alpha(m->roughness);
        return m->color;
    }
    *alpha = 1.0f;
    return v3s(0.0f);
}

/* The albedo the passes record for a surface seen from direction wo (either way round):
 * the share of uniform light it reflects towards wo, which the reconstruction divides a
 * pixel's light by and multiplies the filtered light back with, and a denoiser's albedo
 * guide. For a diffuse surface that is its colour. With a GGX layer it is the layer's
 * directional albedo, F0 (E - E5) + F90 E5 from the multiple-scattering table's E(mu,
 * alpha) and E5 parts (and the conductor's compensation lobe's (1 - E) F_ms, Kulla and
 * Conty 2017), plus a principled base's colour weighed as tr_principled_eval weighs it:
 * (1 - metallic)(1 - E_layer) with the energy compensation, (1 - metallic)(1 - F0) times
 * Ashikhmin and Shirley's factor without it (whose integral over the other direction is
 * 23/28, which the BRDF's 28/23 cancels). Without the table the layer's albedo is Karis's
 * analytic fit ("Physically Based Shading on Mobile", 2014, after Lazarov 2013). The sheen,
 * the clear coat and a transmissive base are left out, and the other materials keep their
 * colour. Why: a glossy floor's reflected light is white whatever its texture's colour;
 * divided by the base colour alone, a blue tile's red channel made its filtered light red,
 * and the white tiles' beside it. */
TR_FN tr_vec3 tr_bsdf_guide_albedo(const tr_bsdf_params *m, tr_vec3 wo) {
    const int principled = m->type == TR_MATERIAL_PRINCIPLED && !(m->transmission > 0.0f);
    if (!principled && (m->type != TR_MATERIAL_GLOSSY || !(m->roughness > 0.0f))) {
        return m->color;
    }
    const float mu = tr_fminf(tr_fabsf(v3_dot(m->ns, wo)), 1.0f);
    const float r = tr_fminf(tr_fmaxf(m->roughness, 0.0f), 1.0f);
    const float alpha = principled ? tr_principled_alpha(r) : tr_ggx_alpha(r);
    float e, e5; /* the single-scattering lobe's albedo with F = 1, and Schlick's (1 - x)^5 share */
    if (m->ms) {
        e = tr_ggx_ms_e(m->ms, mu, alpha);
        e5 = tr_ggx_ms_e(m->ms + TR_GGX_MS_E5, mu, alpha);
    } else {
        /* Karis's fit F0 A + B: with c0 = 1 - r, c1 = 0.0425 - 0.0275 r and t = min(c0^2,
         * 2^(-9.28 mu)) c0 + c1, A = 1.04 (1 - t) - 0.572 r, B = 1.04 t - 0.04 + 0.022 r;
         * so e = A + B and e5 = B. */
        const float c0 = 1.0f - r;
        const float t = tr_fminf(c0 * c0, tr_expf(-6.4324f * mu)) * c0 + 0.0425f - 0.0275f * r;
        e5 = tr_fminf(tr_fmaxf(1.04f * t - 0.04f + 0.022f * r, 0.0f), 1.0f);
        e = tr_fminf(tr_fmaxf(1.04f * (1.0f - t) - 0.572f * r, 0.0f) + e5, 1.0f);
    }
    if (!principled) {
        /* The glossy material: one GGX lobe, Schlick's Fresnel from its colour to 1. */
        return v3_add(v3_scale(m->color, e - e5), v3s(e5));
    }
    const float k = tr_fminf(tr_fmaxf(m->metallic, 0.0f), 1.0f);
    const float sp = tr_fminf(tr_fmaxf(tr_principled_specular(m), 0.0f), 1.0f);
    const tr_vec3 f0 = tr_principled_f0(m);
    tr_vec3 layer = v3_add(v3_scale(f0, e - e5), v3s((sp * (1.0f - k) + k) * e5));
    if ((m->flags & TR_MATERIAL_MULTISCATTER) != 0u && m->ms && k > 0.0f) {
        /* tr_ggx_ms_lobe's albedo, the conductor's share of it */
        const float eavg = tr_ggx_ms_eavg(m->ms, alpha);
        if (eavg < 0.9999f) {
            layer = v3_add(layer, v3_scale(tr_ggx_ms_fm(f0, eavg), k * (1.0f - e)));
        }
    }
    const float f0d = tr_principled_f0d(m);
    const float base =
        tr_principled_comp(m) ? 1.0f - sp * (f0d * (e - e5) + e5) : (1.0f - f0d) * tr_as_factor(mu);
    return v3_add(v3_scale(m->color, (1.0f - k) * tr_fmaxf(base, 0.0f)), layer);
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
    uint32_t mi = tr_view_material(s, triangle);
    if (tr_view_has_verts(s, triangle) || s->material_ext_count > 0u) {
        tr_bsdf_params t;
        tr_material_eval_attributes(s, triangle, mi, u, v, p, ng, &t);
        return tr_emitted(&t, w);
    }
    tr_material m = s->materials[mi];
    tr_bsdf_params b = tr_material_params(&m, ng);
    return tr_emitted(&b, w);
}

#endif
