/* bsdf_dielectric.h - a rough dielectric boundary: GGX microfacet reflection and
 * refraction (B. Walter, S. R. Marschner, H. Li, K. E. Torrance, "Microfacet Models for
 * Refraction through Rough Surfaces", EGSR 2007), the transmission lobe of the principled
 * material (glTF's KHR_materials_transmission, bsdf_principled.h).
 *
 * n is the unit normal pointing outside (index 1); the inside has index ior > 1. For wo
 * and wi on the same side the BSDF reflects, on opposite sides it refracts, about the
 * generalized half vector (Walter eq. 16)
 *
 *   h = normalize(eta wi + wo),  eta = n_i / n_o  (the indices on wi's and wo's sides)
 *
 * turned to n's side. With D the GGX distribution, G the height-correlated Smith G2
 * (bsdf.h) and F the exact unpolarised Fresnel reflectance at wo.h:
 *
 *   reflection  f_r = F D G / (4 |wo.n| |wi.n|)                          (Walter eq. 20)
 *   refraction  f_t = tint (1 - F) D G |wi.h| |wo.h| / (|wi.n| |wo.n| (wi.h + wo.h / eta)^2)
 *
 * f_t is Walter's eq. 21 without its factor 1/eta^2, as the smooth glass of bsdf.h carries
 * no such factor either (its refracted weight is the filter alone): the path carries
 * radiance divided by the square of the medium's index, which is the radiance itself
 * wherever the path meets a light or the camera in air. So f_r is reciprocal and f_t is
 * not: f_t(wi, wo) = f_t(wo, wi) / eta^2 (tests/test_transmission.c checks both).
 *
 * Sampling: a visible normal h of wo's side (Heitz 2018, bsdf.h), then reflection with
 * probability F(wo.h), else refraction through h; pdf = D_wo(h) |dh/dwi| times that
 * probability. Each sample's weight f |wi.n| / pdf is then G2 / G1(wo) <= 1 (times the
 * tint for refraction), so the boundary never creates energy. */
#ifndef TR_KERNEL_BSDF_DIELECTRIC_H
#define TR_KERNEL_BSDF_DIELECTRIC_H

/* The index the transmission lobe uses: an index of 1 would make refraction straight
 * through, where the half vector above is undefined. */
TR_FN float tr_rd_ior(float ior) {
    return tr_fmaxf(ior, 1.01f);
}

/* Fresnel reflectance at a microfacet whose normal makes cosine c with wo (c > 0: wo
 * outside). */
TR_FN float tr_rd_fresnel(float c, float ior) {
    float ct;
    return c >= 0.0f ? tr_fresnel_dielectric(c, 1.0f, ior, &ct)
                     : tr_fresnel_dielectric(-c, ior, 1.0f, &ct);
}

/* The generalized half vector of (wo, wi) on n's side, *eta the ratio n_i / n_o (1 for
 * reflection), *co and *ci the cosines with n. Returns 0 where the BSDF is zero: a
 * direction in the surface's plane, or a microfacet that one of them sees from behind. */
TR_FN int tr_rd_half(float ior, tr_vec3 n, tr_vec3 wo, tr_vec3 wi, tr_vec3 *h, float *eta,
                     float *co, float *ci) {
    *co = v3_dot(wo, n);
    *ci = v3_dot(wi, n);
    if (*co == 0.0f || *ci == 0.0f) {
        return 0;
    }
    *eta = 1.0f;
    if (*co * *ci < 0.0f) {
        *eta = *co > 0.0f ? ior : 1.0f / ior;
    }
    tr_vec3 m = v3_add(v3_scale(wi, *eta), wo);
    float l2 = v3_dot(m, m);
    if (!(l2 > 0.0f)) {
        return 0;
    }
    m = v3_scale(m, 1.0f / tr_sqrtf(l2));
    if (v3_dot(m, n) < 0.0f) {
        m = v3_neg(m);
    }
    if (v3_dot(m, wi) * *ci <= 0.0f || v3_dot(m, wo) * *co <= 0.0f) {
        return 0;
    }
    *h = m;
    return 1;
}

/* f(wo, wi) with GGX alpha, the refracted light multiplied by tint. */
TR_FN tr_vec3 tr_rd_eval(float alpha, float ior, tr_vec3 tint, tr_vec3 n, tr_vec3 wo, tr_vec3 wi) {
    tr_vec3 h;
    float eta, co, ci;
    if (!tr_rd_half(ior, n, wo, wi, &h, &eta, &co, &ci)) {
        return v3s(0.0f);
    }
    float hn = v3_dot(h, n), ho = v3_dot(h, wo), hi = v3_dot(h, wi);
    float d = tr_ggx_d(alpha, hn);
    float g2 = 1.0f / (1.0f + tr_ggx_lambda(alpha, co) + tr_ggx_lambda(alpha, ci));
    float f = tr_rd_fresnel(ho, ior);
    if (co * ci > 0.0f) {
        return v3s(f * d * g2 / tr_fabsf(4.0f * co * ci));
    }
    float den = hi + ho / eta;
    float t = (1.0f - f) * d * g2 * tr_fabsf(hi * ho / (ci * co * den * den));
    return v3_scale(tint, t);
}

/* Solid-angle pdf of tr_rd_sample. */
TR_FN float tr_rd_pdf(float alpha, float ior, tr_vec3 n, tr_vec3 wo, tr_vec3 wi) {
    tr_vec3 h;
    float eta, co, ci;
    if (!tr_rd_half(ior, n, wo, wi, &h, &eta, &co, &ci)) {
        return 0.0f;
    }
    float hn = v3_dot(h, n), ho = v3_dot(h, wo), hi = v3_dot(h, wi);
    /* Visible normals of wo's side: G1(wo) D(h) |wo.h| / |wo.n| (Heitz 2018, eq. 3). */
    float dv =
        tr_ggx_d(alpha, hn) * tr_fabsf(ho) / ((1.0f + tr_ggx_lambda(alpha, co)) * tr_fabsf(co));
    float f = tr_rd_fresnel(ho, ior);
    if (co * ci > 0.0f) {
        return f * dv / (4.0f * tr_fabsf(ho));
    }
    float den = hi + ho / eta;
    return (1.0f - f) * dv * tr_fabsf(hi) / (den * den);
}

/* Draws wi from uniform numbers ulobe (reflect or refract), u1, u2. Returns 0 where the
 * sample is lost (a direction on the wrong side of n). */
TR_FN int tr_rd_sample(float alpha, float ior, tr_vec3 tint, tr_vec3 n, tr_vec3 wo, float ulobe,
                       float u1, float u2, tr_scatter *s) {
    float co = v3_dot(wo, n);
    if (co == 0.0f) {
        return 0;
    }
    /* The visible normals of wo's side, in the frame of the normal on that side. */
    tr_vec3 nf = co > 0.0f ? n : v3_neg(n);
    tr_vec3 t, b;
    v3_basis(nf, &t, &b);
    tr_vec3 vl = v3(v3_dot(wo, t), v3_dot(wo, b), tr_fabsf(co));
    tr_vec3 hl = tr_ggx_sample_vndf(alpha, vl, u1, u2);
    tr_vec3 h =
        v3_normalize(v3_add(v3_add(v3_scale(t, hl.x), v3_scale(b, hl.y)), v3_scale(nf, hl.z)));
    float cos_i = v3_dot(wo, h);
    if (!(cos_i > 0.0f)) {
        return 0;
    }
    float cos_t;
    float eta = co > 0.0f ? 1.0f / ior : ior; /* n_o / n_i, Snell's ratio */
    float f = tr_fresnel_dielectric(cos_i, co > 0.0f ? 1.0f : ior, co > 0.0f ? ior : 1.0f, &cos_t);
    if (ulobe < f) {
        s->wi = v3_normalize(v3_sub(v3_scale(h, 2.0f * cos_i), wo));
        if (v3_dot(s->wi, n) * co <= 0.0f) {
            return 0;
        }
    } else {
        /* Snell's law about h: t = -eta wo + (eta cos_i - cos_t) h. */
        s->wi = v3_normalize(v3_add(v3_scale(wo, -eta), v3_scale(h, eta * cos_i - cos_t)));
        if (v3_dot(s->wi, n) * co >= 0.0f) {
            return 0;
        }
    }
    s->delta = 0;
    s->pdf = tr_rd_pdf(alpha, ior, n, wo, s->wi);
    if (!(s->pdf > 0.0f)) {
        return 0;
    }
    s->weight =
        v3_scale(tr_rd_eval(alpha, ior, tint, n, wo, s->wi), tr_fabsf(v3_dot(s->wi, n)) / s->pdf);
    return 1;
}

#endif
