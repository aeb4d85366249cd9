/* scene_view.h - the arrays a kernel traces against, and the closest-hit query.
 *
 * A tr_scene_view only points at arrays owned by the host's tr_scene (or, on a
 * device, at buffers holding the same bytes). */
#ifndef TR_KERNEL_SCENE_VIEW_H
#define TR_KERNEL_SCENE_VIEW_H

#include "compat.h"
#include "intersect.h"
#include "types.h"

typedef struct tr_scene_view {
    TR_CONST_GLOBAL tr_triangle *triangles;
    TR_CONST_GLOBAL tr_material *materials;
    TR_CONST_GLOBAL tr_flat_node *flat_nodes;
    uint32_t triangle_count;
    uint32_t material_count;
    uint32_t flat_node_count;
} tr_scene_view;

/* The thesis's flat structure (listing 18): test every shape's box, and the triangles
 * of each box the ray meets. Returns 1 and fills *hit for the closest hit in
 * (ray->tmin, ray->tmax). */
TR_FN int tr_intersect_flat(const tr_scene_view *s, const tr_ray *ray, tr_hit *hit) {
    tr_ray r = *ray;
    int found = 0;
    for (uint32_t n = 0; n < s->flat_node_count; ++n) {
        float tnear;
        if (!tr_intersect_aabb(&r, s->flat_nodes[n].box, &tnear)) {
            continue;
        }
        uint32_t end = s->flat_nodes[n].first + s->flat_nodes[n].count;
        for (uint32_t i = s->flat_nodes[n].first; i < end; ++i) {
            TR_CONST_GLOBAL tr_triangle *tri = &s->triangles[i];
            float t, u, v;
            if (tr_intersect_triangle(&r, tri->v0, tri->v1, tri->v2, &t, &u, &v)) {
                r.tmax = t; /* only closer hits from here on */
                hit->t = t;
                hit->triangle = i;
                hit->u = u;
                hit->v = v;
                found = 1;
            }
        }
    }
    return found;
}

/* Closest hit against whichever structure the view holds. */
TR_FN int tr_intersect_scene(const tr_scene_view *s, const tr_ray *ray, tr_hit *hit) {
    return tr_intersect_flat(s, ray, hit);
}

#endif
