/* bsdf_principled.h - the principled material: glTF 2.0's metallic-roughness model
 * (base colour, metallic, roughness; Khronos glTF 2.0 specification, appendix B) as a
 * diffuse base under a GGX specular layer, importance-sampled by lobe.
 *
 *   f = (1 - metallic) f_diffuse + f_spec(F0),   F0 = mix(0.04, base, metallic)
 *
 * f_spec is bsdf.h's GGX microfacet reflection (Walter et al. 2007, height-correlated
 * Smith G2, Schlick's Fresnel) with alpha = roughness^2 (glTF's convention; the mix of
 * two Schlick terms, dielectric and metal, is the Schlick term of the mixed F0).
 * f_diffuse couples the base to the layer above it so that the sum never reflects more
 * than arrives, with Ashikhmin and Shirley's energy-conserving diffuse term ("An
 * Anisotropic Phong BRDF Model", JGT 2000, eq. 5):
 *
 *   f_diffuse = 28 / (23 pi) base (1 - F0) (1 - (1 - cos_i / 2)^5) (1 - (1 - cos_o / 2)^5)
 *
 * Sampling: the specular lobe (visible normals, Heitz 2018) with probability p_spec from
 * the lobes' estimated albedos, else the cosine-weighted hemisphere; the pdf is the
 * mixture's, so MIS in pt sees the one density. The sampler takes its uniform numbers
 * explicitly (ulobe, u1, u2). Included by bsdf.h after the GGX helpers it uses.
 *
 * Clear coat (glTF's KHR_materials_clearcoat; weight c = clearcoat in [0, 1], its own
 * roughness): a second GGX layer of index 1.5 (F0 0.04, alpha = clearcoat_roughness^2)
 * over the material above, which it attenuates by the coat's Fresnel reflectance on the
 * way in and on the way out:
 *
 *   f_coated = c f_coat + (1 - c F_c(cos_o)) (1 - c F_c(cos_i)) (f_spec + f_diffuse / (1 - c
 * F_avg)), F_c(x) = 0.04 + 0.96 (1 - x)^5,   F_avg = 0.04 + 0.96 / 21
 *
 * glTF's layering formula attenuates by (1 - c F_c(cos_o)) alone, which is not reciprocal;
 * the product of both directions' factors is (bdpt and vcm trace light both ways). For the
 * diffuse part, dividing by 1 - c F_avg (F_avg: F_c's cosine-weighted mean) gives back
 * glTF's energy: a Lambertian base keeps exactly (1 - c F_c(cos_o)) of its albedo, the
 * light the coat reflects back inside escaping after further bounces. The specular part,
 * narrow around the mirror direction, keeps about (1 - c F_c(cos_o))^2. Since a smooth coat
 * reflects exactly c F_c(cos_o) and a rough one less, the sum reflects no more than arrives
 * (test_bsdf's white furnace, within its statistical bound). Sampling draws the coat's
 * visible normals with probability from c F_c(cos_o) against the attenuated base's
 * weights (at least 10 % each way), else the base as above. Without a coat (c = 0) none of
 * this runs. */
#ifndef TR_KERNEL_BSDF_PRINCIPLED_H
#define TR_KERNEL_BSDF_PRINCIPLED_H

/* Dielectric F0 of glTF's default index of refraction 1.5. */
#define TR_PRINCIPLED_F0 0.04f

TR_FN float tr_principled_alpha(float roughness) {
    float r = tr_fminf(tr_fmaxf(roughness, 0.0f), 1.0f);
    return tr_fmaxf(r * r, TR_GGX_MIN_ALPHA);
}

/* The dielectric F0 of the material's index of refraction (KHR_materials_ior):
 * ((ior - 1) / (ior + 1))^2. glTF's default 1.5 and an index below 1 (parameters built
 * by hand, whose ior is 0) give TR_PRINCIPLED_F0 itself. */
TR_FN float tr_principled_f0d(const tr_bsdf_params *m) {
    if (m->ior == 1.5f || !(m->ior >= 1.0f)) {
        return TR_PRINCIPLED_F0;
    }
    float r = (m->ior - 1.0f) / (m->ior + 1.0f);
    return r * r;
}

TR_FN tr_vec3 tr_principled_f0(const tr_bsdf_params *m) {
    float k = tr_fminf(tr_fmaxf(m->metallic, 0.0f), 1.0f);
    return v3_add(v3s(tr_principled_f0d(m) * (1.0f - k)), v3_scale(m->color, k));
}

/* 1 - (1 - c/2)^5 */
TR_FN float tr_as_factor(float c) {
    float x = 1.0f - 0.5f * c;
    float x2 = x * x;
    return 1.0f - x2 * x2 * x;
}

/* GGX reflection with alpha and F0 given, for wo, wi on nf's side (cosines > 0). */
TR_FN tr_vec3 tr_principled_spec(float alpha, tr_vec3 f0, tr_vec3 nf, tr_vec3 wo, tr_vec3 wi,
                                 float co, float ci) {
    tr_vec3 h = v3_normalize(v3_add(wo, wi));
    float d = tr_ggx_d(alpha, v3_dot(h, nf));
    float g2 = 1.0f / (1.0f + tr_ggx_lambda(alpha, co) + tr_ggx_lambda(alpha, ci));
    tr_vec3 f = tr_fresnel_schlick(f0, v3_dot(wo, h));
    return v3_scale(f, d * g2 / (4.0f * co * ci));
}

/* The clear coat's Fresnel reflectance F_c at cosine x (Schlick, F0 0.04). */
TR_FN float tr_coat_fresnel(float x) {
    float c = tr_fminf(tr_fmaxf(1.0f - x, 0.0f), 1.0f);
    return TR_PRINCIPLED_F0 + (1.0f - TR_PRINCIPLED_F0) * ((c * c) * (c * c) * c);
}

TR_FN float tr_coat_weight(const tr_bsdf_params *m) {
    return tr_fminf(tr_fmaxf(m->clearcoat, 0.0f), 1.0f);
}

/* The coated BSDF from the base's specular part spec and diffuse part diff, for co, ci > 0
 * (the formula above). */
TR_FN tr_vec3 tr_coat_layer(const tr_bsdf_params *m, tr_vec3 spec, tr_vec3 diff, tr_vec3 nf,
                            tr_vec3 wo, tr_vec3 wi, float co, float ci) {
    float c = tr_coat_weight(m);
    float att = (1.0f - c * tr_coat_fresnel(co)) * (1.0f - c * tr_coat_fresnel(ci));
    float fav = TR_PRINCIPLED_F0 + (1.0f - TR_PRINCIPLED_F0) * (1.0f / 21.0f);
    tr_vec3 fc = tr_principled_spec(tr_principled_alpha(m->clearcoat_roughness),
                                    v3s(TR_PRINCIPLED_F0), nf, wo, wi, co, ci);
    tr_vec3 base = v3_add(v3_scale(spec, att), v3_scale(diff, att / (1.0f - c * fav)));
    return v3_add(base, v3_scale(fc, c));
}

TR_FN_NOINLINE tr_vec3 tr_principled_eval(const tr_bsdf_params *m, tr_vec3 nf, tr_vec3 wo,
                                          tr_vec3 wi) {
    float co = v3_dot(wo, nf), ci = v3_dot(wi, nf);
    if (co <= 0.0f || ci <= 0.0f) {
        return v3s(0.0f);
    }
    float k = tr_fminf(tr_fmaxf(m->metallic, 0.0f), 1.0f);
    tr_vec3 f0 = tr_principled_f0(m);
    tr_vec3 f = tr_principled_spec(tr_principled_alpha(m->roughness), f0, nf, wo, wi, co, ci);
    if ((m->flags & TR_MATERIAL_MULTISCATTER) != 0u && m->ms && k > 0.0f) {
        /* The conductor's share of the layer (the dielectric one couples to the base). */
        f = v3_add(
            f, v3_scale(tr_ggx_ms_lobe(m->ms, tr_principled_alpha(m->roughness), f0, co, ci), k));
    }
    float kd = (1.0f - k) * (28.0f / 23.0f) * TR_INV_PI * (1.0f - tr_principled_f0d(m)) *
               tr_as_factor(ci) * tr_as_factor(co);
    if (m->clearcoat > 0.0f) {
        return tr_coat_layer(m, f, v3_scale(m->color, kd), nf, wo, wi, co, ci);
    }
    return v3_add(f, v3_scale(m->color, kd));
}

/* Probability of sampling the specular lobe for outgoing cosine co: its Fresnel weight at
 * co against the diffuse base's albedo (luminance-free: the RGB mean). */
TR_FN float tr_principled_spec_prob(const tr_bsdf_params *m, float co) {
    float k = tr_fminf(tr_fmaxf(m->metallic, 0.0f), 1.0f);
    tr_vec3 fs = tr_fresnel_schlick(tr_principled_f0(m), co);
    float ws = (fs.x + fs.y + fs.z) * (1.0f / 3.0f);
    float wd = (1.0f - k) * (m->color.x + m->color.y + m->color.z) * (1.0f / 3.0f) *
               (1.0f - tr_principled_f0d(m)) * tr_as_factor(co);
    if (!(ws + wd > 0.0f)) {
        return 1.0f;
    }
    /* At least 10 % each way where both lobes exist: a dark base must not starve the
     * specular lobe of samples or the other way round. */
    float p = ws / (ws + wd);
    return wd > 0.0f ? tr_fminf(tr_fmaxf(p, 0.1f), 0.9f) : 1.0f;
}

/* Probability of sampling the clear coat for outgoing cosine co: c F_c(co) against the
 * attenuated base's lobe weights (those of tr_principled_spec_prob). */
TR_FN float tr_coat_prob(const tr_bsdf_params *m, float co) {
    float k = tr_fminf(tr_fmaxf(m->metallic, 0.0f), 1.0f);
    tr_vec3 fs = tr_fresnel_schlick(tr_principled_f0(m), co);
    float wb = (fs.x + fs.y + fs.z) * (1.0f / 3.0f) +
               (1.0f - k) * (m->color.x + m->color.y + m->color.z) * (1.0f / 3.0f) *
                   (1.0f - tr_principled_f0d(m)) * tr_as_factor(co);
    float wc = tr_coat_weight(m) * tr_coat_fresnel(co);
    wb *= 1.0f - wc;
    if (!(wb > 0.0f)) {
        return 1.0f;
    }
    if (!(wc > 0.0f)) {
        return 0.0f;
    }
    return tr_fminf(tr_fmaxf(wc / (wc + wb), 0.1f), 0.9f);
}

TR_FN_NOINLINE float tr_principled_pdf(const tr_bsdf_params *m, tr_vec3 nf, tr_vec3 wo,
                                       tr_vec3 wi) {
    float co = v3_dot(wo, nf), ci = v3_dot(wi, nf);
    if (co <= 0.0f || ci <= 0.0f) {
        return 0.0f;
    }
    float alpha = tr_principled_alpha(m->roughness);
    tr_vec3 h = v3_normalize(v3_add(wo, wi));
    float g1 = 1.0f / (1.0f + tr_ggx_lambda(alpha, co));
    float pspec = g1 * tr_ggx_d(alpha, v3_dot(h, nf)) / (4.0f * co);
    float ps = tr_principled_spec_prob(m, co);
    float p = ps * pspec + (1.0f - ps) * ci * TR_INV_PI;
    if (m->clearcoat > 0.0f) {
        float pc = tr_coat_prob(m, co);
        float ac = tr_principled_alpha(m->clearcoat_roughness);
        float g1c = 1.0f / (1.0f + tr_ggx_lambda(ac, co));
        float pcoat = g1c * tr_ggx_d(ac, v3_dot(h, nf)) / (4.0f * co);
        p = pc * pcoat + (1.0f - pc) * p;
    }
    return p;
}

/* Draws wi from uniform numbers ulobe, u1, u2 in [0, 1). Returns 0 when wi falls below
 * the surface (the path ends). */
TR_FN_NOINLINE int tr_principled_sample(const tr_bsdf_params *m, tr_vec3 nf, tr_vec3 wo,
                                        float ulobe, float u1, float u2, tr_scatter *s) {
    float co = v3_dot(wo, nf);
    if (co <= 0.0f) {
        return 0;
    }
    tr_vec3 t, b;
    v3_basis(nf, &t, &b);
    int coat = 0;
    if (m->clearcoat > 0.0f) {
        /* The coat first; else ulobe, stretched back over [0, 1), picks the base's lobe. */
        float pc = tr_coat_prob(m, co);
        if (ulobe < pc) {
            coat = 1;
        } else {
            ulobe = tr_fminf((ulobe - pc) / (1.0f - pc), 0.99999994f);
        }
    }
    if (coat || ulobe < tr_principled_spec_prob(m, co)) {
        tr_vec3 vl = v3(v3_dot(wo, t), v3_dot(wo, b), co);
        float a = tr_principled_alpha(coat ? m->clearcoat_roughness : m->roughness);
        tr_vec3 hl = tr_ggx_sample_vndf(a, vl, u1, u2);
        tr_vec3 h = v3_add(v3_add(v3_scale(t, hl.x), v3_scale(b, hl.y)), v3_scale(nf, hl.z));
        s->wi = v3_normalize(v3_reflect(v3_neg(wo), h));
    } else {
        /* Cosine-weighted (Malley's method: the unit disk's concentric map lifted). */
        float r = tr_sqrtf(u1), phi = TR_TWO_PI * u2;
        float z = tr_sqrtf(tr_fmaxf(0.0f, 1.0f - u1));
        s->wi = v3_add(v3_add(v3_scale(t, r * tr_cosf(phi)), v3_scale(b, r * tr_sinf(phi))),
                       v3_scale(nf, z));
    }
    float ci = v3_dot(s->wi, nf);
    if (ci <= 0.0f) {
        return 0;
    }
    s->pdf = tr_principled_pdf(m, nf, wo, s->wi);
    if (!(s->pdf > 0.0f)) {
        return 0;
    }
    s->delta = 0;
    s->weight = v3_scale(tr_principled_eval(m, nf, wo, s->wi), ci / s->pdf);
    return 1;
}

/* ---- Transmission (KHR_materials_transmission, KHR_materials_ior) ----------------------
 *
 * glTF mixes its dielectric base between the diffuse lobe and a specular transmission
 * lobe by the transmission factor t, under the same Fresnel-weighted reflection; at t = 1
 * the dielectric is a rough boundary that reflects F and refracts 1 - F, Walter's
 * (bsdf_dielectric.h). Here the whole opaque material above is mixed with that boundary:
 *
 *   f = (1 - w) f_opaque + w f_boundary,   w = t (1 - metallic)
 *
 * with the boundary's index the material's ior, its alpha roughness^2, its refraction
 * tinted by the base colour (glTF's). A convex mix of two BSDFs that conserve energy
 * conserves it, and the sampler picks the part by w. It equals glTF's for metallic 0 or 1;
 * in between the conductor's share is (1 - w) metallic instead of metallic. The clear coat
 * lies on the opaque part only. The boundary needs b->ns pointing outside, as glass. */

TR_FN float tr_principled_tr_weight(const tr_bsdf_params *m) {
    float k = tr_fminf(tr_fmaxf(m->metallic, 0.0f), 1.0f);
    return tr_fminf(tr_fmaxf(m->transmission, 0.0f), 1.0f) * (1.0f - k);
}

TR_FN_NOINLINE tr_vec3 tr_principled_tr_eval(tr_bsdf_params m, tr_vec3 nf, tr_vec3 wo, tr_vec3 wi) {
    float w = tr_principled_tr_weight(&m);
    tr_vec3 fb =
        tr_rd_eval(tr_principled_alpha(m.roughness), tr_rd_ior(m.ior), m.color, m.ns, wo, wi);
    tr_vec3 fo = tr_principled_eval(&m, nf, wo, wi);
    return v3_add(v3_scale(fo, 1.0f - w), v3_scale(fb, w));
}

TR_FN_NOINLINE float tr_principled_tr_pdf(tr_bsdf_params m, tr_vec3 nf, tr_vec3 wo, tr_vec3 wi) {
    float w = tr_principled_tr_weight(&m);
    float pb = tr_rd_pdf(tr_principled_alpha(m.roughness), tr_rd_ior(m.ior), m.ns, wo, wi);
    float po = w < 1.0f ? tr_principled_pdf(&m, nf, wo, wi) : 0.0f;
    return (1.0f - w) * po + w * pb;
}

/* ulobe below w picks the boundary (and, stretched over [0, 1), its reflection or
 * refraction), else the opaque part's lobes. */
TR_FN_NOINLINE int tr_principled_tr_sample(tr_bsdf_params m, tr_vec3 nf, tr_vec3 wo, float ulobe,
                                           float u1, float u2, tr_scatter *s) {
    float w = tr_principled_tr_weight(&m);
    tr_scatter r;
    int ok;
    if (ulobe < w) {
        ok = tr_rd_sample(tr_principled_alpha(m.roughness), tr_rd_ior(m.ior), m.color, m.ns, wo,
                          tr_fminf(ulobe / w, 0.99999994f), u1, u2, &r);
    } else {
        ok = tr_principled_sample(&m, nf, wo, tr_fminf((ulobe - w) / (1.0f - w), 0.99999994f), u1,
                                  u2, &r);
    }
    if (!ok) {
        return 0;
    }
    r.pdf = tr_principled_tr_pdf(m, nf, wo, r.wi);
    if (!(r.pdf > 0.0f)) {
        return 0;
    }
    r.delta = 0;
    r.weight =
        v3_scale(tr_principled_tr_eval(m, nf, wo, r.wi), tr_fabsf(v3_dot(r.wi, m.ns)) / r.pdf);
    *s = r;
    return 1;
}

#endif
