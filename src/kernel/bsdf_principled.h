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

/* glTF's KHR_materials_specular from the material's extras: the dielectric layer's F90
 * and F0 scale (1 without) and its F0 tint (white without). */
TR_FN float tr_principled_specular(const tr_bsdf_params *m) {
    return m->ext && (m->ext->flags & TR_MATEXT_SPECULAR) != 0u ? m->ext->specular : 1.0f;
}

TR_FN tr_vec3 tr_principled_specular_color(const tr_bsdf_params *m) {
    return m->ext && (m->ext->flags & TR_MATEXT_SPECULAR) != 0u ? m->ext->specular_color
                                                                : v3s(1.0f);
}

/* Whether the dielectric layer has glTF's KHR_materials_specular (not 1 and white). */
TR_FN int tr_principled_has_spec(const tr_bsdf_params *m) {
    if (!m->ext || (m->ext->flags & TR_MATEXT_SPECULAR) == 0u) {
        return 0;
    }
    tr_vec3 c = m->ext->specular_color;
    return m->ext->specular != 1.0f || c.x != 1.0f || c.y != 1.0f || c.z != 1.0f;
}

/* The dielectric layer's F0 with KHR_materials_specular: min(F0(ior) specular_color, 1)
 * specular (its F90 is specular). */
TR_FN tr_vec3 tr_principled_f0d_spec(const tr_bsdf_params *m) {
    float f = tr_principled_f0d(m);
    float s = tr_fminf(tr_fmaxf(tr_principled_specular(m), 0.0f), 1.0f);
    tr_vec3 c = tr_principled_specular_color(m);
    return v3(tr_fminf(f * c.x, 1.0f) * s, tr_fminf(f * c.y, 1.0f) * s,
              tr_fminf(f * c.z, 1.0f) * s);
}

TR_FN tr_vec3 tr_principled_f0(const tr_bsdf_params *m) {
    float k = tr_fminf(tr_fmaxf(m->metallic, 0.0f), 1.0f);
    if (tr_principled_has_spec(m)) {
        return v3_add(v3_scale(tr_principled_f0d_spec(m), 1.0f - k), v3_scale(m->color, k));
    }
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

/* ---- Energy compensation (with "multiscatter": TR_MATERIAL_MULTISCATTER and the table)
 *
 * Kulla and Conty's coupling of a diffuse base to the dielectric layer above it ("Revisiting
 * Physically Based Shading at Imageworks", SIGGRAPH 2017 course): the base receives what
 * the layer does not reflect, 1 - E_l(cos), on the way in and on the way out,
 *
 *   f_diffuse = (1 - metallic) base (1 - E_l(cos_o)) (1 - E_l(cos_i)) / (pi (1 - E_l,avg))
 *
 * E_l the GGX layer's directional albedo with the dielectric F0 (ggx_ms.h's tables:
 * F0 E + (1 - F0) E_5) and E_l,avg its cosine-weighted mean, so that a white base reflects
 * E_l(cos_o) + (1 - E_l(cos_o)) = 1 of a furnace at every angle. It replaces Ashikhmin and
 * Shirley's coupling, whose white dielectric keeps 0.81 to 0.87 of a furnace. Under a clear
 * coat of weight c, the coat's albedo E_c = c (0.04 E + 0.96 E_5) (at its own alpha) takes
 * the place of F_c, and each part of the base is attenuated by what the coat lets through
 * both ways, divided by what the coat sends back down to that part again:
 *
 *   part (1 - E_c(cos_o)) (1 - E_c(cos_i)) / sqrt(N(cos_o) N(cos_i)),  N(x) = 1 - <E_c>(x)
 *
 * <E_c>(x) the coat's albedo averaged over the directions the part reflects light arriving
 * at x to: for the diffuse part its cosine lobe weighted by 1 - E_l, for the conductor's
 * multiple scattering by 1 - E (both constant in x, TR_COAT_QUAD points), for the
 * single-scattering lobe the lobe itself (ggx_ms.h's last table, by x, the lobe's alpha
 * and the coat's). A white mirror under a coat then reflects E_c + (1 - E_c) = 1, a white
 * Lambertian base E_c + (1 - E_c) as well; the white furnace table is in
 * docs/integrators.md (tests/test_furnace_principled.c). Without the flag nothing of this
 * runs (same bits as before). */
#define TR_COAT_QUAD 16
TR_FN int tr_principled_comp(const tr_bsdf_params *m) {
    return (m->flags & TR_MATERIAL_MULTISCATTER) != 0u && m->ms;
}

/* ---- Sheen (glTF's KHR_materials_sheen) ---------------------------------------------
 *
 * Estevez and Kulla's Charlie sheen ("Production Friendly Microfacet Sheen BRDF", 2017)
 * with the glTF extension's visibility:
 *
 *   f_sheen = sheen_color D(h) / ((1 + L(cos_o) + L(cos_i)) 4 cos_o cos_i),
 *   D(h) = (2 + 1/a) sin(theta_h)^(1/a) / (2 pi),   a = r^2 (r the sheen roughness),
 *
 * L Estevez and Kulla's fitted Lambda (their curve l(x) and its coefficients, mixed by
 * (1 - a)^2). The layer sits on the base (under a clear coat) and scales it by glTF's
 * albedo scaling, min(1 - s E_sh(cos_o), 1 - s E_sh(cos_i)), s = max(sheen_color), E_sh
 * the lobe's albedo with a white colour (ggx_ms.h's third table, computed by the host
 * from this lobe), so the sum reflects no more than arrives. r below TR_SHEEN_MIN_R counts
 * as it (the lobe becomes a grazing spike no table resolves). Sampled as a lobe of its own
 * (cosine-weighted) with probability s E_sh(cos_o), clamped to [0.1, 0.9]. */
#define TR_SHEEN_MIN_R 0.07f

TR_FN float tr_sheen_l(float x, float a) {
    float t = (1.0f - a) * (1.0f - a);
    float ca = 21.5473f + (25.3245f - 21.5473f) * t;
    float cb = 3.82987f + (3.32435f - 3.82987f) * t;
    float cc = 0.19823f + (0.16801f - 0.19823f) * t;
    float cd = -1.97760f + (-1.27393f + 1.97760f) * t;
    float ce = -4.32054f + (-4.85967f + 4.32054f) * t;
    return ca / (1.0f + cb * tr_powf(x, cc)) + cd * x + ce;
}

TR_FN float tr_sheen_lambda(float c, float a) {
    return c < 0.5f ? tr_expf(tr_sheen_l(c, a))
                    : tr_expf(2.0f * tr_sheen_l(0.5f, a) - tr_sheen_l(1.0f - c, a));
}

/* The lobe with a white colour for roughness r, wo and wi above the normal +z of their
 * frame (co, ci their cosines > 0). */
TR_FN float tr_sheen_lobe(float r, tr_vec3 wo, tr_vec3 wi, float co, float ci) {
    float rr = tr_fminf(tr_fmaxf(r, TR_SHEEN_MIN_R), 1.0f);
    float a = rr * rr;
    tr_vec3 h = v3_normalize(v3_add(wo, wi));
    float sin2 = tr_fmaxf(0.0f, 1.0f - h.z * h.z);
    float d = (2.0f + 1.0f / a) * tr_powf(sin2, 0.5f / a) * (0.5f * TR_INV_PI);
    float v = 1.0f / ((1.0f + tr_sheen_lambda(co, a) + tr_sheen_lambda(ci, a)) * 4.0f * co * ci);
    return d * v;
}

/* The sheen's colour (black without: no extras) and roughness, from the extras, times
 * their maps at this hit (material_eval.h's sheen_rg, sheen_ba; 0 for none). */
TR_FN tr_vec3 tr_sheen_color(const tr_bsdf_params *m) {
    if (!m->ext) {
        return v3s(0.0f);
    }
    tr_vec3 c = m->ext->sheen_color;
    if ((m->sheen_rg | (m->sheen_ba & 65535u)) != 0u) {
        c = v3_mul(c, v3(tr_unpack_map16(m->sheen_rg), tr_unpack_map16(m->sheen_rg >> 16),
                         tr_unpack_map16(m->sheen_ba)));
    }
    return c;
}

TR_FN float tr_sheen_roughness(const tr_bsdf_params *m) {
    if (!m->ext) {
        return 0.0f;
    }
    float r = m->ext->sheen_roughness;
    return (m->sheen_ba >> 16) != 0u ? r * tr_unpack_map16(m->sheen_ba >> 16) : r;
}

TR_FN float tr_sheen_weight(const tr_bsdf_params *m) {
    tr_vec3 c = tr_sheen_color(m);
    return tr_fmaxf(tr_fmaxf(c.x, c.y), c.z);
}

/* s E_sh(cos) (0 without the table). */
TR_FN float tr_sheen_albedo(const tr_bsdf_params *m, float c) {
    if (!m->ms) {
        return 0.0f;
    }
    return tr_sheen_weight(m) *
           tr_ggx_ms_e(m->ms + TR_GGX_MS_SHEEN, c,
                       tr_fminf(tr_fmaxf(tr_sheen_roughness(m), TR_SHEEN_MIN_R), 1.0f));
}

/* The sheen lobe in the frame of nf (wo, wi on its side). */
TR_FN tr_vec3 tr_sheen_eval(const tr_bsdf_params *m, tr_vec3 nf, tr_vec3 wo, tr_vec3 wi, float co,
                            float ci) {
    tr_vec3 t, b;
    v3_basis(nf, &t, &b);
    tr_vec3 lo = v3(v3_dot(wo, t), v3_dot(wo, b), co);
    tr_vec3 li = v3(v3_dot(wi, t), v3_dot(wi, b), ci);
    return v3_scale(tr_sheen_color(m), tr_sheen_lobe(tr_sheen_roughness(m), lo, li, co, ci));
}

/* KHR_materials_specular: the GGX layer with Schlick's Fresnel from F0 to F90 =
 * mix(specular, 1, metallic), and the diffuse part's factor per channel (the energy
 * compensation's coupling with the layer's albedo F0 (E - E_5) + F90 E_5, else Ashikhmin
 * and Shirley's with 1 - F0). */
TR_FN tr_vec3 tr_principled_spec_f90(const tr_bsdf_params *m, tr_vec3 f0, tr_vec3 nf, tr_vec3 wo,
                                     tr_vec3 wi, float co, float ci) {
    float alpha = tr_principled_alpha(m->roughness);
    float k = tr_fminf(tr_fmaxf(m->metallic, 0.0f), 1.0f);
    float f90 = tr_fminf(tr_fmaxf(tr_principled_specular(m), 0.0f), 1.0f) * (1.0f - k) + k;
    tr_vec3 h = v3_normalize(v3_add(wo, wi));
    float d = tr_ggx_d(alpha, v3_dot(h, nf));
    float g2 = 1.0f / (1.0f + tr_ggx_lambda(alpha, co) + tr_ggx_lambda(alpha, ci));
    float x = tr_fminf(tr_fmaxf(1.0f - v3_dot(wo, h), 0.0f), 1.0f);
    float x5 = (x * x) * (x * x) * x;
    tr_vec3 f = v3_add(f0, v3_scale(v3_sub(v3s(f90), f0), x5));
    return v3_scale(f, d * g2 / (4.0f * co * ci));
}

TR_FN float tr_spec_layer_e(const tr_bsdf_params *m, float mu, float a, float f0, float f90) {
    float e = tr_ggx_ms_e(m->ms, mu, a), e5 = tr_ggx_ms_e(m->ms + TR_GGX_MS_E5, mu, a);
    return f0 * (e - e5) + f90 * e5;
}

TR_FN float tr_spec_layer_eavg(const tr_bsdf_params *m, float a, float f0, float f90) {
    float e = tr_ggx_ms_eavg(m->ms, a), e5 = tr_ggx_ms_eavg(m->ms + TR_GGX_MS_E5, a);
    return f0 * (e - e5) + f90 * e5;
}

TR_FN float tr_spec_kd(const tr_bsdf_params *m, float f0, float co, float ci) {
    float k = tr_fminf(tr_fmaxf(m->metallic, 0.0f), 1.0f);
    if (tr_principled_comp(m)) {
        float a = tr_principled_alpha(m->roughness);
        float s = tr_fminf(tr_fmaxf(tr_principled_specular(m), 0.0f), 1.0f);
        return (1.0f - k) * TR_INV_PI * (1.0f - tr_spec_layer_e(m, co, a, f0, s)) *
               (1.0f - tr_spec_layer_e(m, ci, a, f0, s)) / (1.0f - tr_spec_layer_eavg(m, a, f0, s));
    }
    return (1.0f - k) * (28.0f / 23.0f) * TR_INV_PI * (1.0f - f0) * tr_as_factor(ci) *
           tr_as_factor(co);
}

/* The clear coat's Fresnel reflectance F_c at cosine x (Schlick, F0 0.04). */
TR_FN float tr_coat_fresnel(float x) {
    float c = tr_fminf(tr_fmaxf(1.0f - x, 0.0f), 1.0f);
    return TR_PRINCIPLED_F0 + (1.0f - TR_PRINCIPLED_F0) * ((c * c) * (c * c) * c);
}

TR_FN float tr_coat_weight(const tr_bsdf_params *m) {
    return tr_fminf(tr_fmaxf(m->clearcoat, 0.0f), 1.0f);
}

/* ---- The clear coat's own normal (glTF's clearcoatNormalTexture; coat_n not 0) ----------
 *
 * The coat's lobe, its Fresnel factors and (with the energy compensation) its albedos
 * take their cosines from the coat's normal n_c (on nf's side), the base's from nf. A
 * direction below the coat's horizon finds a coat that reflects nothing its way and lets
 * 1 - c through (F_c at cosine 0 is 1). The coat's lobe, defined with n_c's cosines, is
 * weighed by min(1, cos_c,i / cos_i) min(1, cos_c,o / cos_o): symmetric in the two
 * directions, and with it the lobe integrated against nf's cosine reflects no more than
 * against n_c's, so that the coat still sends back at most c F_c(cos_c,o) and the base
 * keeps the share that passes it. With coat_n 0 (no map) none of this runs. */

/* The coat's albedo <E_c> (weight c, alpha ac) over the directions the base's broad parts
 * scatter into, for the compensation of tr_coat_layer and tr_coat_layer_tilted: into *ed
 * the diffuse part's (its cosine lobe weighted by 1 - E_l), into *em the conductor's
 * multiple scattering's (weighted by 1 - E); the midpoint rule in cos^2, the measure of
 * 2 cos dcos. */
TR_FN void tr_coat_broad_albedos(const tr_bsdf_params *m, float c, float ac, float *ed, float *em) {
    float a = tr_principled_alpha(m->roughness), f0d = tr_principled_f0d(m);
    float nd = 0.0f, dd = 0.0f, nm = 0.0f, dm = 0.0f;
    for (int q = 0; q < TR_COAT_QUAD; ++q) {
        float mu = tr_sqrtf(((float)q + 0.5f) * (1.0f / (float)TR_COAT_QUAD));
        float ec = c * tr_ggx_ms_layer_e(m->ms, mu, ac, TR_PRINCIPLED_F0);
        float wd = 1.0f - tr_ggx_ms_layer_e(m->ms, mu, a, f0d);
        float wm = 1.0f - tr_ggx_ms_e(m->ms, mu, a);
        nd += wd * ec;
        dd += wd;
        nm += wm * ec;
        dm += wm;
    }
    float ea = c * tr_ggx_ms_layer_eavg(m->ms, ac, TR_PRINCIPLED_F0);
    *ed = dd > 0.0f ? nd / dd : ea;
    *em = dm > 0.0f ? nm / dm : ea;
}

/* The coat's normal on nf's side. */
TR_FN tr_vec3 tr_coat_normal(const tr_bsdf_params *m, tr_vec3 nf) {
    tr_vec3 n = tr_unpack_oct(m->coat_n);
    return v3_dot(nf, m->ns) < 0.0f ? v3_neg(n) : n;
}

TR_FN_NOINLINE tr_vec3 tr_coat_layer_tilted(const tr_bsdf_params *m, tr_vec3 spec, tr_vec3 ms,
                                            tr_vec3 diff, tr_vec3 nf, tr_vec3 wo, tr_vec3 wi,
                                            float co, float ci) {
    tr_vec3 nc = tr_coat_normal(m, nf);
    float xo = v3_dot(wo, nc), xi = v3_dot(wi, nc);
    float c = tr_coat_weight(m), ac = tr_principled_alpha(m->clearcoat_roughness);
    tr_vec3 fc = v3s(0.0f);
    if (xo > 0.0f && xi > 0.0f) {
        float g = tr_fminf(1.0f, xo / co) * tr_fminf(1.0f, xi / ci);
        fc = v3_scale(tr_principled_spec(ac, v3s(TR_PRINCIPLED_F0), nc, wo, wi, xo, xi), c * g);
    }
    xo = tr_fmaxf(xo, 0.0f);
    xi = tr_fmaxf(xi, 0.0f);
    if (tr_principled_comp(m)) {
        /* As tr_coat_layer's compensation, the coat's albedos at its own cosines. */
        float eo = xo > 0.0f ? c * tr_ggx_ms_layer_e(m->ms, xo, ac, TR_PRINCIPLED_F0) : c;
        float ei = xi > 0.0f ? c * tr_ggx_ms_layer_e(m->ms, xi, ac, TR_PRINCIPLED_F0) : c;
        float att = (1.0f - eo) * (1.0f - ei);
        float a = tr_principled_alpha(m->roughness), ed, em;
        tr_coat_broad_albedos(m, c, ac, &ed, &em);
        float no = xo > 0.0f ? 1.0f - c * tr_ggx_ms_coat_e(m->ms, xo, a, ac) : 1.0f - c;
        float ni = xi > 0.0f ? 1.0f - c * tr_ggx_ms_coat_e(m->ms, xi, a, ac) : 1.0f - c;
        float nsq = no * ni;
        tr_vec3 r = v3_add(v3_scale(spec, nsq > 0.0f ? att / tr_sqrtf(nsq) : 0.0f),
                           v3_scale(diff, att / (1.0f - ed)));
        return v3_add(v3_add(r, v3_scale(ms, att / (1.0f - em))), fc);
    }
    float att = (1.0f - c * tr_coat_fresnel(xo)) * (1.0f - c * tr_coat_fresnel(xi));
    float fav = TR_PRINCIPLED_F0 + (1.0f - TR_PRINCIPLED_F0) * (1.0f / 21.0f);
    tr_vec3 base = v3_add(v3_scale(spec, att), v3_scale(diff, att / (1.0f - c * fav)));
    return v3_add(base, fc);
}

/* The coated BSDF from the base's specular part spec and diffuse part diff, for co, ci > 0
 * (the formula above). */
TR_FN tr_vec3 tr_coat_layer(const tr_bsdf_params *m, tr_vec3 spec, tr_vec3 ms, tr_vec3 diff,
                            tr_vec3 nf, tr_vec3 wo, tr_vec3 wi, float co, float ci) {
    if (m->coat_n != 0u) {
        return tr_coat_layer_tilted(m, spec, ms, diff, nf, wo, wi, co, ci);
    }
    float c = tr_coat_weight(m);
    float att = (1.0f - c * tr_coat_fresnel(co)) * (1.0f - c * tr_coat_fresnel(ci));
    float fav = TR_PRINCIPLED_F0 + (1.0f - TR_PRINCIPLED_F0) * (1.0f / 21.0f);
    tr_vec3 fc = tr_principled_spec(tr_principled_alpha(m->clearcoat_roughness),
                                    v3s(TR_PRINCIPLED_F0), nf, wo, wi, co, ci);
    if (tr_principled_comp(m)) {
        float ac = tr_principled_alpha(m->clearcoat_roughness);
        float eo = c * tr_ggx_ms_layer_e(m->ms, co, ac, TR_PRINCIPLED_F0);
        float ei = c * tr_ggx_ms_layer_e(m->ms, ci, ac, TR_PRINCIPLED_F0);
        att = (1.0f - eo) * (1.0f - ei);
        float a = tr_principled_alpha(m->roughness), ed, em;
        tr_coat_broad_albedos(m, c, ac, &ed, &em);
        /* The single-scattering lobe's N at both ends. */
        float nsq = (1.0f - c * tr_ggx_ms_coat_e(m->ms, co, a, ac)) *
                    (1.0f - c * tr_ggx_ms_coat_e(m->ms, ci, a, ac));
        tr_vec3 r = v3_add(v3_scale(spec, nsq > 0.0f ? att / tr_sqrtf(nsq) : 0.0f),
                           v3_scale(diff, att / (1.0f - ed)));
        return v3_add(v3_add(r, v3_scale(ms, att / (1.0f - em))), v3_scale(fc, c));
    }
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
    int spec = tr_principled_has_spec(m);
    tr_vec3 f = spec
                    ? tr_principled_spec_f90(m, f0, nf, wo, wi, co, ci)
                    : tr_principled_spec(tr_principled_alpha(m->roughness), f0, nf, wo, wi, co, ci);
    tr_vec3 fms = v3s(0.0f);
    if ((m->flags & TR_MATERIAL_MULTISCATTER) != 0u && m->ms && k > 0.0f) {
        /* The conductor's share of the layer (the dielectric one couples to the base). */
        fms = v3_scale(tr_ggx_ms_lobe(m->ms, tr_principled_alpha(m->roughness), f0, co, ci), k);
        if (!(m->clearcoat > 0.0f)) {
            f = v3_add(f, fms);
        }
    }
    float kd = 0.0f;
    if (spec) {
        /* Per channel: the layer's F0 may be tinted (set below). */
    } else if (tr_principled_comp(m)) {
        float a = tr_principled_alpha(m->roughness), f0d = tr_principled_f0d(m);
        kd = (1.0f - k) * TR_INV_PI * (1.0f - tr_ggx_ms_layer_e(m->ms, co, a, f0d)) *
             (1.0f - tr_ggx_ms_layer_e(m->ms, ci, a, f0d)) /
             (1.0f - tr_ggx_ms_layer_eavg(m->ms, a, f0d));
    } else {
        kd = (1.0f - k) * (28.0f / 23.0f) * TR_INV_PI * (1.0f - tr_principled_f0d(m)) *
             tr_as_factor(ci) * tr_as_factor(co);
    }
    tr_vec3 diff = v3_scale(m->color, kd);
    if (spec) {
        tr_vec3 fd = tr_principled_f0d_spec(m);
        diff = v3_mul(m->color, v3(tr_spec_kd(m, fd.x, co, ci), tr_spec_kd(m, fd.y, co, ci),
                                   tr_spec_kd(m, fd.z, co, ci)));
    }
    if (tr_sheen_weight(m) > 0.0f) {
        /* The sheen over the base, which it scales by glTF's albedo scaling. */
        float sc = tr_fminf(1.0f - tr_sheen_albedo(m, co), 1.0f - tr_sheen_albedo(m, ci));
        f = v3_scale(f, sc);
        fms = v3_scale(fms, sc);
        diff = v3_add(v3_scale(diff, sc), tr_sheen_eval(m, nf, wo, wi, co, ci));
    }
    if (m->clearcoat > 0.0f) {
        return tr_coat_layer(m, f, fms, diff, nf, wo, wi, co, ci);
    }
    return v3_add(f, diff);
}

/* Probability of sampling the sheen's lobe for outgoing cosine co (0 without a sheen). */
TR_FN float tr_sheen_prob(const tr_bsdf_params *m, float co) {
    if (!(tr_sheen_weight(m) > 0.0f)) {
        return 0.0f;
    }
    return tr_fminf(tr_fmaxf(tr_sheen_albedo(m, co), 0.1f), 0.9f);
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
TR_FN float tr_coat_prob_at(const tr_bsdf_params *m, float co, float xo) {
    float k = tr_fminf(tr_fmaxf(m->metallic, 0.0f), 1.0f);
    tr_vec3 fs = tr_fresnel_schlick(tr_principled_f0(m), co);
    float wb = (fs.x + fs.y + fs.z) * (1.0f / 3.0f) +
               (1.0f - k) * (m->color.x + m->color.y + m->color.z) * (1.0f / 3.0f) *
                   (1.0f - tr_principled_f0d(m)) * tr_as_factor(co);
    float wc = tr_coat_weight(m) * tr_coat_fresnel(xo);
    wb *= 1.0f - wc;
    if (!(wb > 0.0f)) {
        return 1.0f;
    }
    if (!(wc > 0.0f)) {
        return 0.0f;
    }
    return tr_fminf(tr_fmaxf(wc / (wc + wb), 0.1f), 0.9f);
}

TR_FN float tr_coat_prob(const tr_bsdf_params *m, float co) {
    return tr_coat_prob_at(m, co, co);
}

/* With the coat's own normal nc: its cosine xo of wo picks the coat (never below its
 * horizon, where its visible normals cannot be drawn). */
TR_FN float tr_coat_prob_tilted(const tr_bsdf_params *m, float co, float xo) {
    return xo > 0.0f ? tr_coat_prob_at(m, co, xo) : 0.0f;
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
    if (tr_sheen_weight(m) > 0.0f) {
        float psh = tr_sheen_prob(m, co);
        p = psh * ci * TR_INV_PI + (1.0f - psh) * p;
    }
    if (m->clearcoat > 0.0f && m->coat_n != 0u) {
        /* The coat's visible normals around its own normal. */
        tr_vec3 nc = tr_coat_normal(m, nf);
        float xo = v3_dot(wo, nc);
        float pc = tr_coat_prob_tilted(m, co, xo);
        float pcoat = 0.0f;
        if (pc > 0.0f) {
            float ac = tr_principled_alpha(m->clearcoat_roughness);
            float g1c = 1.0f / (1.0f + tr_ggx_lambda(ac, xo));
            pcoat = g1c * tr_ggx_d(ac, v3_dot(h, nc)) / (4.0f * xo);
        }
        p = pc * pcoat + (1.0f - pc) * p;
    } else if (m->clearcoat > 0.0f) {
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
        float pc = m->coat_n != 0u ? tr_coat_prob_tilted(m, co, v3_dot(wo, tr_coat_normal(m, nf)))
                                   : tr_coat_prob(m, co);
        if (ulobe < pc) {
            coat = 1;
        } else {
            ulobe = tr_fminf((ulobe - pc) / (1.0f - pc), 0.99999994f);
        }
    }
    int sheen = 0;
    if (!coat && tr_sheen_weight(m) > 0.0f) {
        /* The sheen next, its cosine lobe; else ulobe, stretched again, picks the base's. */
        float psh = tr_sheen_prob(m, co);
        if (ulobe < psh) {
            sheen = 1;
        } else {
            ulobe = tr_fminf((ulobe - psh) / (1.0f - psh), 0.99999994f);
        }
    }
    if (coat && m->coat_n != 0u) {
        /* The coat's visible normals in its own normal's frame. */
        tr_vec3 nc = tr_coat_normal(m, nf), tc, bc;
        v3_basis(nc, &tc, &bc);
        tr_vec3 vl = v3(v3_dot(wo, tc), v3_dot(wo, bc), v3_dot(wo, nc));
        tr_vec3 hl = tr_ggx_sample_vndf(tr_principled_alpha(m->clearcoat_roughness), vl, u1, u2);
        tr_vec3 h = v3_add(v3_add(v3_scale(tc, hl.x), v3_scale(bc, hl.y)), v3_scale(nc, hl.z));
        s->wi = v3_normalize(v3_reflect(v3_neg(wo), h));
    } else if (!sheen && (coat || ulobe < tr_principled_spec_prob(m, co))) {
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
