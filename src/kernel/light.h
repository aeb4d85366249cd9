/* light.h - sampling emissive triangles for next-event estimation.
 *
 * An emitter is chosen from the scene's table with probability proportional to its
 * weight (emitted power: mean radiance x area x number of emitting sides), by binary
 * search in the table's CDF, then a point uniformly on its area. */
#ifndef TR_KERNEL_LIGHT_H
#define TR_KERNEL_LIGHT_H

#include "compat.h"
#include "scene_view.h"
#include "types.h"
#include "vec.h"

/* Selection weight of triangle t of material m: the power it emits up to the common
 * factor pi, with the RGB mean as the scalar radiance. 0 for non-emitters. */
TR_FN float tr_light_weight(const tr_material *m, float area) {
    if (!(m->emittance > 0.0f) || !(area > 0.0f)) {
        return 0.0f;
    }
    float l = m->emittance * (m->color.x + m->color.y + m->color.z) * (1.0f / 3.0f);
    float sides = (m->flags & TR_MATERIAL_TWO_SIDED) ? 2.0f : 1.0f;
    return l * area * sides;
}

/* Index into s->lights of the entry u in [0,1) selects: the first with cdf > u. */
TR_FN uint32_t tr_light_pick(const tr_scene_view *s, float u) {
    uint32_t lo = 0, hi = s->light_count - 1;
    while (lo < hi) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (s->light_cdf[mid] > u) {
            hi = mid;
        } else {
            lo = mid + 1;
        }
    }
    return lo;
}

/* Area density (per unit area) of sampling a point on triangle `tri` (material m)
 * through tr_light_sample. */
TR_FN float tr_light_pdf_area(const tr_scene_view *s, const tr_material *m, float area) {
    if (s->light_count == 0 || !(s->light_weight_total > 0.0f) || !(area > 0.0f)) {
        return 0.0f;
    }
    return tr_light_weight(m, area) / (s->light_weight_total * area);
}

/* A point on an emitter, from the uniform numbers usel (which emitter) and (u1, u2)
 * (where on it): *tri_index the triangle, *p the point, *u and *v its
 * barycentrics of the triangle's second and third vertex (as tr_hit's, for the material
 * stage); returns the area density of the choice (0 when the scene has no emitters). */
TR_FN float tr_light_sample(const tr_scene_view *s, float usel, float u1, float u2,
                            uint32_t *tri_index, tr_vec3 *p, float *u, float *v) {
    *tri_index = 0u;
    *p = v3s(0.0f);
    *u = 0.0f;
    *v = 0.0f;
    if (s->light_count == 0) {
        return 0.0f;
    }
    uint32_t k = tr_light_pick(s, usel);
    uint32_t t = s->lights[k];
    TR_CONST_GLOBAL tr_triangle *tri = &s->triangles[t];
    /* Uniform on the triangle: b0 = 1 - sqrt(u1), b1 = u2 sqrt(u1) (Pharr et al.,
     * Physically Based Rendering, 3rd ed., section 13.6.5). */
    float su = tr_sqrtf(u1);
    float b0 = 1.0f - su, b1 = u2 * su;
    *p = v3_add(v3_add(v3_scale(tri->v0, b0), v3_scale(tri->v1, b1)),
                v3_scale(tri->v2, 1.0f - b0 - b1));
    *tri_index = t;
    *u = b1;
    *v = 1.0f - b0 - b1;
    /* The density from the weight, not from CDF differences, so that it equals what
     * tr_light_pdf_area returns when a BSDF-sampled ray hits the same emitter. */
    tr_material m = s->materials[tri->material];
    return tr_light_pdf_area(s, &m, tri->area);
}

#endif
