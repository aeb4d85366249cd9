/* material_eval.h - the material stage: what a surface is at one hit, evaluated once,
 * before any BSDF code runs.
 *
 * tr_material_eval turns a hit (triangle, barycentrics, position, geometric normal, ray
 * direction) into tr_bsdf_params; the BSDFs (bsdf.h), the naive integrator's scatter
 * (material.h) and emission read only that struct. Without vertex attributes and
 * material extras (attrib.h) every parameter is the material's constant and the shading
 * normal is the geometric one; interpolated normals, textures and normal maps (texture.h)
 * change this step alone (as yocto-gl's eval_material comes before eval_bsdf, and
 * pbrt-v4's Material::GetBSDF before the BSDF). */
#ifndef TR_KERNEL_MATERIAL_EVAL_H
#define TR_KERNEL_MATERIAL_EVAL_H

#include "compat.h"
#include "scene_view.h"
#include "texture.h"
#include "types.h"
#include "vec.h"

/* Per-hit values of principled's sheen and clear coat normal maps travel in
 * tr_bsdf_params packed into 32-bit words, 0 meaning none (below). A map's value v in
 * [0, 1] is kept as 65535 (1 - v) in 16 bits, so that 0 is the factor 1: a word of zeros is
 * the material's constants unchanged. */
TR_FN uint32_t tr_pack_map16(float v) {
    float q = (1.0f - tr_fminf(tr_fmaxf(v, 0.0f), 1.0f)) * 65535.0f + 0.5f;
    return (uint32_t)q;
}

TR_FN float tr_unpack_map16(uint32_t q) {
    return (float)(65535u - (q & 65535u)) / 65535.0f;
}

/* A unit normal in 32 bits: its octahedral map (Meyer et al., "On Floating-Point Normal
 * Vectors", 2010), 16 bits a coordinate; never 0, which means none. */
TR_FN uint32_t tr_pack_oct(tr_vec3 n) {
    float l = tr_fabsf(n.x) + tr_fabsf(n.y) + tr_fabsf(n.z);
    float px = n.x / l, py = n.y / l;
    if (n.z < 0.0f) {
        float qx = (1.0f - tr_fabsf(py)) * (px >= 0.0f ? 1.0f : -1.0f);
        float qy = (1.0f - tr_fabsf(px)) * (py >= 0.0f ? 1.0f : -1.0f);
        px = qx;
        py = qy;
    }
    uint32_t ux = (uint32_t)((tr_fminf(tr_fmaxf(px, -1.0f), 1.0f) * 0.5f + 0.5f) * 65535.0f + 0.5f);
    uint32_t uy = (uint32_t)((tr_fminf(tr_fmaxf(py, -1.0f), 1.0f) * 0.5f + 0.5f) * 65535.0f + 0.5f);
    uint32_t w = ux | (uy << 16);
    /* (0, 0) and (65535, 65535) both are -z. */
    return w != 0u ? w : 0xffffffffu;
}

TR_FN tr_vec3 tr_unpack_oct(uint32_t w) {
    float px = (float)(w & 65535u) / 65535.0f * 2.0f - 1.0f;
    float py = (float)(w >> 16) / 65535.0f * 2.0f - 1.0f;
    tr_vec3 n = v3(px, py, 1.0f - tr_fabsf(px) - tr_fabsf(py));
    if (n.z < 0.0f) {
        n.x = (1.0f - tr_fabsf(py)) * (px >= 0.0f ? 1.0f : -1.0f);
        n.y = (1.0f - tr_fabsf(px)) * (py >= 0.0f ? 1.0f : -1.0f);
    }
    /* (Not v3_normalize: one more caller made the compiler keep that out of line on the
     * camera's path.) */
    return v3_scale(n, 1.0f / tr_sqrtf(v3_dot(n, n)));
}

/* The BSDF's inputs at one surface point. */
typedef struct tr_bsdf_params {
    uint32_t type;    /* TR_MATERIAL_* */
    uint32_t flags;   /* TR_MATERIAL_TWO_SIDED */
    tr_vec3 color;    /* base colour (linear RGB): albedo, F0, glass filter, emitted colour */
    float roughness;  /* glossy, in [0, 1] */
    float ior;        /* glass: index of refraction */
    float emittance;  /* emitted radiance is color * emittance */
    tr_vec3 ng;       /* the triangle's geometric normal: emitters' sides */
    tr_vec3 ns;       /* shading normal the BSDFs use (glass: pointing outside) */
    tr_vec3 ps;       /* where rays leaving on ng's side start (tr_surface_origin) */
    tr_vec3 emission; /* emitted radiance of a non-emitter (principled materials) */
    float metallic;   /* principled: 0 dielectric .. 1 conductor */
    float clearcoat;  /* principled: the clear coat's weight, 0 for none (bsdf_principled.h) */
    float clearcoat_roughness; /* principled: the clear coat's roughness */
    float transmission;        /* principled: the rough dielectric boundary's weight (0: none) */
    int hole;                  /* an alpha cut-out: the ray passes through (tr_material_ext) */
    /* principled's maps at this hit, packed (tr_pack_map16, tr_pack_oct), 0 for none: three
     * words where seven floats would be (see ext below; the first fills what was padding
     * before the pointers). The sheen colour map's red and green, its blue and the sheen
     * roughness map's alpha, each multiplying the extras' factor; the clear coat's shading
     * normal from its own normal map, or the interpolated normal where only the base is
     * normal-mapped (with neither map the coat shares ns). */
    uint32_t sheen_rg, sheen_ba, coat_n;
    /* The scene's multiple-scattering table (ggx_ms.h), or NULL: read where flags has
     * TR_MATERIAL_MULTISCATTER. */
    TR_CONST_GLOBAL float *ms;
    /* The material's extras (attrib.h), or NULL for none: principled reads its sheen and
     * KHR_materials_specular there (bsdf_principled.h). They stay out of this struct as
     * values because the integrators keep it in registers for every material: eight more
     * floats here made the classic box's frame (diffuse materials only) 12 % slower. */
    TR_CONST_GLOBAL tr_material_ext *ext;
} tr_bsdf_params;

/* The parameters of a material whose values do not vary over the surface, with
 * geometric normal ng. The whole of tr_material_eval today; tests use it alone. */
TR_FN tr_bsdf_params tr_material_params(const tr_material *m, tr_vec3 ng) {
    tr_bsdf_params b;
    b.type = m->type;
    b.flags = m->flags;
    b.color = m->color;
    b.roughness = m->roughness;
    b.ior = m->ior;
    b.emittance = m->emittance;
    b.ng = ng;
    b.ns = ng;
    b.ps = v3s(0.0f);
    b.emission = v3s(0.0f);
    b.metallic = 0.0f;
    b.clearcoat = 0.0f;
    b.clearcoat_roughness = 0.0f;
    b.transmission = 0.0f;
    b.hole = 0;
    b.sheen_rg = 0u;
    b.sheen_ba = 0u;
    b.coat_n = 0u;
    b.ms = 0;
    b.ext = 0;
    return b;
}

/* The normal that tangent-space normal map `tex` (linear; x and y scaled by `scale`) gives
 * at a's texture coordinates around the unit normal n, in the frame of a->dpdu, a->dpdv;
 * returns 0 (*out untouched) where that frame or the result is degenerate. */
TR_FN int tr_normal_map(const tr_scene_view *s, uint32_t tex, float scale, const tr_surface_attr *a,
                        tr_vec3 n, tr_vec3 *out) {
    float unused;
    tr_vec3 t = tr_texture_sample(s, tex, a->tu, a->tv, 0, &unused);
    tr_vec3 k = v3(2.0f * t.x - 1.0f, 2.0f * t.y - 1.0f, 2.0f * t.z - 1.0f);
    /* Gram-Schmidt: a tangent frame around the interpolated normal. glTF's +Y is up in
     * the image, against our v (downwards): the bitangent is -dp/dv. */
    tr_vec3 tu = v3_sub(a->dpdu, v3_scale(n, v3_dot(n, a->dpdu)));
    float lt = v3_dot(tu, tu);
    if (!(lt > 0.0f)) {
        return 0;
    }
    tu = v3_scale(tu, 1.0f / tr_sqrtf(lt));
    tr_vec3 bt = v3_cross(n, tu);
    if (v3_dot(bt, a->dpdv) > 0.0f) {
        bt = v3_neg(bt);
    }
    tr_vec3 m =
        v3_add(v3_add(v3_scale(tu, k.x * scale), v3_scale(bt, k.y * scale)), v3_scale(n, k.z));
    float lm = v3_dot(m, m);
    if (!(lm > 0.0f && lm < TR_INFINITY)) {
        return 0;
    }
    *out = v3_scale(m, 1.0f / tr_sqrtf(lm));
    return 1;
}

/* The extras of material `mat` at texture coordinates (tu, tv) (texture.h): textures
 * multiply the material's factors, a normal map tilts b->ns in the frame of dpdu, dpdv
 * (the clear coat's own map, a->ns into b->coat_n). */
TR_FN void tr_material_apply_ext(const tr_scene_view *s, uint32_t mat, const tr_surface_attr *a,
                                 tr_bsdf_params *b) {
    tr_material_ext e = s->material_exts[mat];
    b->metallic = e.metallic;
    b->clearcoat = e.clearcoat;
    b->clearcoat_roughness = e.clearcoat_roughness;
    b->transmission = e.transmission;
    b->ext = s->material_exts + mat;
    b->emission = e.emission;
    float alpha = 1.0f;
    if (e.base_tex != TR_NO_INDEX) {
        b->color = v3_mul(b->color, tr_texture_sample(s, e.base_tex, a->tu, a->tv, 1, &alpha));
    }
    if ((e.flags & TR_MATEXT_ALPHA_MASK) != 0u && alpha < e.alpha_cutoff) {
        b->hole = 1;
    }
    float unused;
    if (e.emission_tex != TR_NO_INDEX) {
        b->emission =
            v3_mul(b->emission, tr_texture_sample(s, e.emission_tex, a->tu, a->tv, 1, &unused));
    }
    if (e.mr_tex != TR_NO_INDEX) {
        /* glTF: roughness in green, metallic in blue, both linear. */
        tr_vec3 mr = tr_texture_sample(s, e.mr_tex, a->tu, a->tv, 0, &unused);
        b->roughness *= mr.y;
        b->metallic *= mr.z;
    }
    if (e.transmission_tex != TR_NO_INDEX && b->transmission > 0.0f) {
        /* glTF: the transmission in red, linear, times the factor. */
        b->transmission *= tr_texture_sample(s, e.transmission_tex, a->tu, a->tv, 0, &unused).x;
    }
    if (b->clearcoat > 0.0f) {
        /* glTF: the coat's weight in its map's red, its roughness in its own map's green,
         * both linear, times the factors. */
        if (e.clearcoat_tex != TR_NO_INDEX) {
            b->clearcoat *= tr_texture_sample(s, e.clearcoat_tex, a->tu, a->tv, 0, &unused).x;
        }
        if (e.clearcoat_rough_tex != TR_NO_INDEX) {
            b->clearcoat_roughness *=
                tr_texture_sample(s, e.clearcoat_rough_tex, a->tu, a->tv, 0, &unused).y;
        }
    }
    if (b->clearcoat > 0.0f && e.clearcoat_normal_tex != TR_NO_INDEX &&
        v3_dot(a->dpdu, a->dpdu) > 0.0f) {
        /* glTF: the coat's normal map tilts the interpolated normal, not the base's map. */
        tr_vec3 nc;
        if (tr_normal_map(s, e.clearcoat_normal_tex, e.clearcoat_normal_scale, a, a->ns, &nc)) {
            b->coat_n = tr_pack_oct(nc);
        }
    }
    if (e.normal_tex != TR_NO_INDEX && v3_dot(a->dpdu, a->dpdu) > 0.0f) {
        tr_normal_map(s, e.normal_tex, e.normal_scale, a, b->ns, &b->ns);
        if (b->clearcoat > 0.0f && b->coat_n == 0u) {
            /* glTF: without its own map the coat is not normal-mapped, even where the
             * base is: it keeps the interpolated normal. */
            b->coat_n = tr_pack_oct(a->ns);
        }
    }
    if (e.sheen_color_tex != TR_NO_INDEX || e.sheen_rough_tex != TR_NO_INDEX) {
        /* glTF: the sheen colour map's RGB (sRGB) and the roughness map's alpha (linear),
         * times the factors (bsdf_principled.h's tr_sheen_color, tr_sheen_roughness). */
        tr_vec3 sc = v3s(1.0f);
        float sa = 1.0f;
        if (e.sheen_color_tex != TR_NO_INDEX) {
            sc = tr_texture_sample(s, e.sheen_color_tex, a->tu, a->tv, 1, &unused);
        }
        if (e.sheen_rough_tex != TR_NO_INDEX) {
            tr_texture_sample(s, e.sheen_rough_tex, a->tu, a->tv, 0, &sa);
        }
        b->sheen_rg = tr_pack_map16(sc.x) | (tr_pack_map16(sc.y) << 16);
        b->sheen_ba = tr_pack_map16(sc.z) | (tr_pack_map16(sa) << 16);
    }
}

/* tr_material_eval for a triangle with vertex attributes or a scene with material
 * extras (material mi), into *out. Out of line: inlined, its size kept the integrators
 * from inlining the material stage at all, and scenes without any of it paid for the
 * call. */
TR_FN_NOINLINE void tr_material_eval_attributes(const tr_scene_view *s, uint32_t triangle,
                                                uint32_t mi, float u, float v, tr_vec3 p,
                                                tr_vec3 ng, tr_bsdf_params *out) {
    tr_material m = s->materials[mi];
    tr_bsdf_params b = tr_material_params(&m, ng);
    tr_surface_attr a = tr_surface_attributes(s, triangle, u, v, p, ng);
    b.ns = a.ns;
    b.ps = a.ps;
    b.ms = s->ggx_ms_count > 0u ? s->ggx_ms : 0;
    if (s->material_ext_count > 0u) {
        tr_material_apply_ext(s, mi, &a, &b);
    }
    *out = b;
}

/* The material stage: the BSDF parameters at point p of triangle `triangle` (barycentrics
 * u, v of its second and third vertex; geometric normal ng), reached along direction dir
 * (unused so far). */
TR_FN tr_bsdf_params tr_material_eval(const tr_scene_view *s, uint32_t triangle, float u, float v,
                                      tr_vec3 p, tr_vec3 ng, tr_vec3 dir) {
    (void)dir;
    uint32_t mi = tr_view_material(s, triangle);
    if (tr_view_has_verts(s, triangle) || s->material_ext_count > 0u) {
        /* Through a temporary: a result written straight into the caller's struct would
         * take its address, and keep it in memory on the path without attributes too. */
        tr_bsdf_params t;
        tr_material_eval_attributes(s, triangle, mi, u, v, p, ng, &t);
        return t;
    }
    tr_material m = s->materials[mi];
    tr_bsdf_params b = tr_material_params(&m, ng);
    b.ps = p;
    b.ms = s->ggx_ms_count > 0u ? s->ggx_ms : 0;
    return b;
}

/* Beer-Lambert absorption inside a transmissive object (glTF's KHR_materials_volume): a
 * ray along dir that travelled distance t before it hit triangle `triangle` from behind
 * (dir . ng > 0: from inside, for outward normals) crossed the inside of that triangle's
 * material and keeps exp(-absorption t) of its light; *att receives that factor. Returns 0
 * (att untouched) where nothing was absorbed: a hit from outside, or no absorption. Each
 * object is taken as its own medium in air: an object inside another is not modelled. */
TR_FN int tr_volume_attenuation(const tr_scene_view *s, uint32_t triangle, tr_vec3 dir, tr_vec3 ng,
                                float t, tr_vec3 *att) {
    if (s->material_ext_count == 0u || !(v3_dot(dir, ng) > 0.0f)) {
        return 0;
    }
    tr_vec3 a = s->material_exts[tr_view_material(s, triangle)].absorption;
    if (!(a.x > 0.0f || a.y > 0.0f || a.z > 0.0f)) {
        return 0;
    }
    *att = v3(tr_expf(-a.x * t), tr_expf(-a.y * t), tr_expf(-a.z * t));
    return 1;
}

/* Alpha cut-outs stop nothing: at most this many are passed through along one ray. */
#define TR_MAX_HOLES 64

/* Whether hit is a hole: an alpha-masked material whose base map is transparent there. */
TR_FN int tr_hit_is_hole(const tr_scene_view *s, const tr_ray *ray, const tr_hit *hit) {
    if (s->material_ext_count == 0u) {
        return 0;
    }
    uint32_t mi = tr_view_material(s, hit->triangle);
    if ((s->material_exts[mi].flags & TR_MATEXT_ALPHA_MASK) == 0u) {
        return 0;
    }
    tr_triangle tri_tmp;
    TR_CONST_GLOBAL tr_triangle *tri = tr_view_triangle(s, hit->triangle, &tri_tmp);
    tr_vec3 p = v3_madd(ray->origin, ray->dir, hit->t);
    tr_bsdf_params b = tr_material_eval(s, hit->triangle, hit->u, hit->v, p, tri->normal, ray->dir);
    return b.hole;
}

/* tr_occluded_masked in a scene with material extras: out of line, as the material stage's
 * attribute path is (tr_material_eval_attributes). */
TR_FN_NOINLINE int tr_occluded_through_holes(const tr_scene_view *s, const tr_ray *ray) {
    tr_ray r = *ray;
    for (int k = 0; k < TR_MAX_HOLES; ++k) {
        tr_hit hit;
        if (!tr_intersect_scene(s, &r, &hit)) {
            return 0;
        }
        if (!tr_hit_is_hole(s, &r, &hit)) {
            return 1;
        }
        r.tmin = hit.t + 1e-5f * tr_fmaxf(1.0f, hit.t);
    }
    return 1;
}

/* The shadow-ray query with alpha cut-outs: occluded unless every surface on the segment
 * is a hole. Without material extras, tr_occluded_scene itself. */
TR_FN int tr_occluded_masked(const tr_scene_view *s, const tr_ray *ray) {
    if (s->material_ext_count == 0u) {
        return tr_occluded_scene(s, ray);
    }
    return tr_occluded_through_holes(s, ray);
}

#endif
