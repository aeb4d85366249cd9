/* material_eval.h - the material stage: what a surface is at one hit, evaluated once,
 * before any BSDF code runs.
 *
 * tr_material_eval turns a hit (triangle, barycentrics, position, geometric normal, ray
 * direction) into tr_bsdf_params; the BSDFs (bsdf.h), the naive integrator's scatter
 * (material.h) and emission read only that struct. Today every parameter is the
 * material's constant and the shading normal is the geometric one; textures and
 * interpolated or mapped normals change this step alone (as yocto-gl's eval_material
 * comes before eval_bsdf, and pbrt-v4's Material::GetBSDF before the BSDF). */
#ifndef TR_KERNEL_MATERIAL_EVAL_H
#define TR_KERNEL_MATERIAL_EVAL_H

#include "compat.h"
#include "scene_view.h"
#include "types.h"
#include "vec.h"

/* The BSDF's inputs at one surface point. */
typedef struct tr_bsdf_params {
    uint32_t type;   /* TR_MATERIAL_* */
    uint32_t flags;  /* TR_MATERIAL_TWO_SIDED */
    tr_vec3 color;   /* base colour (linear RGB): albedo, F0, glass filter, emitted colour */
    float roughness; /* glossy, in [0, 1] */
    float ior;       /* glass: index of refraction */
    float emittance; /* emitted radiance is color * emittance */
    tr_vec3 ng;      /* the triangle's geometric normal: emitters' sides */
    tr_vec3 ns;      /* shading normal the BSDFs use (glass: pointing outside) */
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
    return b;
}

/* The material stage: the BSDF parameters at point p of triangle `triangle` (barycentrics
 * u, v of its second and third vertex; geometric normal ng), reached along direction dir.
 * p, u, v and dir are unused until textures and shading normals need them. */
TR_FN tr_bsdf_params tr_material_eval(const tr_scene_view *s, uint32_t triangle, float u, float v,
                                      tr_vec3 p, tr_vec3 ng, tr_vec3 dir) {
    (void)u;
    (void)v;
    (void)p;
    (void)dir;
    tr_material m = s->materials[s->triangles[triangle].material];
    return tr_material_params(&m, ng);
}

#endif
