/* scene_view.h - the arrays a kernel traces against, and the closest-hit query.
 *
 * A tr_scene_view only points at arrays owned by the host's tr_scene (or, on a
 * device, at buffers holding the same bytes). */
#ifndef TR_KERNEL_SCENE_VIEW_H
#define TR_KERNEL_SCENE_VIEW_H

#include "attrib.h"
#include "compat.h"
#include "cwbvh.h"
#include "intersect.h"
#include "types.h"

/* Embree (TR_ACCEL_EMBREE) is a host library: only host builds configured with it
 * (CMake defines TRAC0R_HAVE_EMBREE for libtrac0r and everything linking it) see the
 * Embree member and dispatch below; OpenCL C never does. */
#if !defined(__OPENCL_C_VERSION__) && !defined(__OPENCL_VERSION__) && defined(TRAC0R_HAVE_EMBREE)
#define TR_SCENE_VIEW_EMBREE 1
/* Closest hit / any hit in (ray->tmin, ray->tmax) through an RTCScene built by
 * tr_embree_build (src/accel/embree.c), with the flat structure's conventions; `first`
 * turns a hit through an instance into its id (tr_embree.first, NULL without instances). */
int tr_embree_intersect(const void *scene, const uint32_t *first, const tr_ray *ray, tr_hit *hit);
int tr_embree_occluded(const void *scene, const tr_ray *ray);
#endif

/* The wide BVH (src/accel/wbvh.c) is host code too: host builds trace TR_ACCEL_BVH views
 * through it when the view holds one, OpenCL C walks the binary BVH. */
#if !defined(__OPENCL_C_VERSION__) && !defined(__OPENCL_VERSION__)
#define TR_SCENE_VIEW_WBVH 1
struct tr_wbvh;
int tr_wbvh_intersect(const struct tr_wbvh *w, const tr_ray *ray, tr_hit *hit);
int tr_wbvh_occluded(const struct tr_wbvh *w, const tr_ray *ray);
/* Kept instances (src/scene/instance.c): triangle ids from the view's triangle_count on
 * name a triangle of an instance whose prototype's triangles are stored once, in its own
 * space. These place it as flattening does (the same functions, so the same floats):
 * its triangle into *tmp, its material, whether it has vertex attributes, and its three
 * vertices (normals through the inverse transpose). */
struct tr_scene;
const tr_triangle *tr_inst_triangle(const struct tr_scene *s, uint32_t id, tr_triangle *tmp);
uint32_t tr_inst_material(const struct tr_scene *s, uint32_t id);
int tr_inst_has_verts(const struct tr_scene *s, uint32_t id);
int tr_inst_vertices(const struct tr_scene *s, uint32_t id, tr_vertex x[3]);
#endif

/* Every array a kernel reads, declared once: X(element type, member, count member).
 * This one list generates the scene view's members below, the OpenCL kernel's buffer
 * arguments and its view set-up (entry.cl), and the host's upload table
 * (src/device/opencl.c); adding an array is one line here. */
#define TR_SCENE_ARRAYS(X)                                                                         \
    X(tr_triangle, triangles, triangle_count)                                                      \
    X(tr_material, materials, material_count)                                                      \
    X(tr_flat_node, flat_nodes, flat_node_count)    /* the thesis's flat structure */              \
    X(tr_bvh_node, bvh_nodes, bvh_node_count)       /* 0 nodes for an empty scene */               \
    X(tr_bvh_tri, bvh_tris, bvh_tri_count)          /* leaf triangles, in tr_bvh.indices order */  \
    X(uint32_t, lights, light_count)                /* emissive triangle indices */                \
    X(float, light_cdf, light_cdf_count)            /* their selection CDF (last entry 1) */       \
    X(tr_light_node, light_nodes, light_node_count) /* light tree (light_tree.h), or none */       \
    X(uint32_t, light_leaf, light_leaf_count)       /* each emitter's leaf in it */                \
    X(tr_vertex, vertices, vertex_count)            /* attrib.h: shading normals, UVs */           \
    X(tr_tri_verts, tri_verts, tri_verts_count)     /* triangles 0..count-1: their vertices */     \
    X(tr_texture, textures, texture_count)                                                         \
    X(uint32_t, texels, texel_count)                      /* every texture's RGBA8 texels */       \
    X(tr_material_ext, material_exts, material_ext_count) /* 0 or one per material */              \
    X(tr_env, env, env_count)             /* 0 or 1: the environment light (envmap.h) */           \
    X(float, env_texels, env_texel_count) /* its map, RGB */                                       \
    X(float, env_cdf, env_cdf_count) /* marginal CDF (height + 1), then each row's (width + 1) */  \
    X(tr_sun, sun, sun_count)        /* 0 or 1: the sun (sun.h) */                                 \
    X(tr_punctual, punctual, punctual_count) /* point, spot and directional lights */              \
    X(float, ggx_ms, ggx_ms_count)           /* GGX multiple scattering (ggx_ms.h), or none */     \
    X(tr_cwbvh_node, cwbvh_nodes, cwbvh_node_count) /* a device's compressed wide BVH, or none */  \
    X(tr_bvh_tri, cwbvh_tris, cwbvh_tri_count)      /* its leaf triangles (cwbvh.h) */

/* The scalars a view carries besides its arrays, X(type, member), uploaded to a device as
 * 32-bit words after the counts. */
#define TR_SCENE_SCALARS(X)                                                                        \
    X(uint32_t, accel)           /* TR_ACCEL_*: which structure tr_intersect_scene walks */        \
    X(float, light_weight_total) /* sum of the emitters' weights (tr_light_weight) */              \
    X(float, sky_cx)             /* the scene's bounding sphere, which light subpaths from */      \
    X(float, sky_cy)             /* the environment and the sun cross (integrator_bdpt.h); */      \
    X(float, sky_cz)             /* radius 0: none (no triangles) */                               \
    X(float, sky_radius)

#define TR_SCENE_VIEW_ARRAY_MEMBER(type, name, count) TR_CONST_GLOBAL type *name;
#define TR_SCENE_VIEW_COUNT_MEMBER(type, name, count) uint32_t count;
#define TR_SCENE_VIEW_SCALAR_MEMBER(type, name) type name;

/* The emitter table (src/scene/lights.c, built by tr_scene_commit) serves next-event
 * estimation: light_count emissive triangle indices and the CDF of their selection
 * weights; light_cdf_count equals light_count. With a light tree (light_node_count > 0,
 * light_leaf_count == light_count) next-event estimation picks emitters through it
 * instead of the CDF. */
typedef struct tr_scene_view {
    TR_SCENE_ARRAYS(TR_SCENE_VIEW_ARRAY_MEMBER)
    TR_SCENE_ARRAYS(TR_SCENE_VIEW_COUNT_MEMBER)
    TR_SCENE_SCALARS(TR_SCENE_VIEW_SCALAR_MEMBER)
#ifdef TR_SCENE_VIEW_EMBREE
    const void *embree_scene;     /* RTCScene, for TR_ACCEL_EMBREE */
    const uint32_t *embree_first; /* its instances' first ids (tr_embree.first), or NULL */
#endif
#ifdef TR_SCENE_VIEW_WBVH
    const struct tr_wbvh *wbvh;  /* TR_ACCEL_BVH: the wide BVH, or NULL for the binary one */
    const struct tr_scene *kept; /* the scene, when it holds kept instances; else NULL */
#endif
} tr_scene_view;

/* Every read of a triangle by id goes through these, so that ids of kept instances
 * (host only; past triangle_count) read their placed triangle: the triangle (written to
 * *tmp when placed, else a pointer into the array), its material, whether it has vertex
 * attributes (the `triangle < tri_verts_count` test), and its vertices (0: none). */
#ifdef TR_SCENE_VIEW_WBVH
TR_FN const tr_triangle *tr_view_triangle(const tr_scene_view *s, uint32_t t, tr_triangle *tmp) {
    return t < s->triangle_count ? &s->triangles[t] : tr_inst_triangle(s->kept, t, tmp);
}
TR_FN uint32_t tr_view_material(const tr_scene_view *s, uint32_t t) {
    return t < s->triangle_count ? s->triangles[t].material : tr_inst_material(s->kept, t);
}
TR_FN int tr_view_has_verts(const tr_scene_view *s, uint32_t t) {
    return t < s->tri_verts_count || (t >= s->triangle_count && tr_inst_has_verts(s->kept, t));
}
#else
TR_FN TR_CONST_GLOBAL tr_triangle *tr_view_triangle(const tr_scene_view *s, uint32_t t,
                                                    tr_triangle *tmp) {
    (void)tmp;
    return &s->triangles[t];
}
TR_FN uint32_t tr_view_material(const tr_scene_view *s, uint32_t t) {
    return s->triangles[t].material;
}
TR_FN int tr_view_has_verts(const tr_scene_view *s, uint32_t t) {
    return t < s->tri_verts_count;
}
#endif
TR_FN int tr_view_vertices(const tr_scene_view *s, uint32_t t, tr_vertex *x0, tr_vertex *x1,
                           tr_vertex *x2) {
#ifdef TR_SCENE_VIEW_WBVH
    if (t >= s->triangle_count) {
        tr_vertex x[3];
        if (!tr_inst_vertices(s->kept, t, x)) {
            return 0;
        }
        *x0 = x[0];
        *x1 = x[1];
        *x2 = x[2];
        return 1;
    }
#endif
    if (t >= s->tri_verts_count) {
        return 0;
    }
    tr_tri_verts tv = s->tri_verts[t];
    if (tv.v[0] == TR_NO_INDEX) {
        return 0;
    }
    *x0 = s->vertices[tv.v[0]];
    *x1 = s->vertices[tv.v[1]];
    *x2 = s->vertices[tv.v[2]];
    return 1;
}

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
            /* Zero-area triangles are skipped as the BVH leaves them out: Moller-Trumbore's
             * determinant of a degenerate triangle is rounding noise, not zero. */
            if (tri->area > 0.0f &&
                tr_intersect_triangle(&r, tri->v0, tri->v1, tri->v2, &t, &u, &v)) {
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

/* Tests the leaf triangles bvh_tris[first .. first+count) and keeps the closest hit. */
TR_FN int tr_intersect_bvh_leaf(const tr_scene_view *s, tr_ray *r, uint32_t first, uint32_t count,
                                tr_hit *hit) {
    int found = 0;
    for (uint32_t k = first; k < first + count; ++k) {
        TR_CONST_GLOBAL tr_bvh_tri *tri = &s->bvh_tris[k];
        float t, u, v;
        if (tr_intersect_triangle_edges(r, tri->v0, tri->e1, tri->e2, &t, &u, &v)) {
            r->tmax = t;
            hit->t = t;
            hit->triangle = tri->index;
            hit->u = u;
            hit->v = v;
            found = 1;
        }
    }
    return found;
}

/* Closest hit through the binary BVH: children visited near-first, the far one pushed
 * on a fixed-size stack, subtrees skipped once they start beyond the closest hit. With
 * any_hit set it returns at the first hit in (tmin, tmax), for shadow rays. */
TR_FN_TRAVERSE int tr_traverse_bvh(const tr_scene_view *s, const tr_ray *ray, tr_hit *hit,
                                   int any_hit) {
    tr_ray r = *ray;
    int found = 0;
    float tn;
    if (s->bvh_node_count == 0 || !tr_intersect_aabb(&r, s->bvh_nodes[0].box, &tn)) {
        return 0;
    }
    uint32_t stack[TR_BVH_STACK_SIZE];
    float stack_t[TR_BVH_STACK_SIZE]; /* entry distance of each pushed subtree */
    int top = 0;
    uint32_t node = 0;
    for (;;) {
        TR_CONST_GLOBAL tr_bvh_node *n = &s->bvh_nodes[node];
        if (n->count > 0) {
            if (tr_intersect_bvh_leaf(s, &r, n->left_first, n->count, hit)) {
                found = 1;
                if (any_hit) {
                    return 1;
                }
            }
        } else {
            uint32_t a = n->left_first, b = a + 1;
            float ta, tb;
            int ha = tr_intersect_aabb(&r, s->bvh_nodes[a].box, &ta);
            int hb = tr_intersect_aabb(&r, s->bvh_nodes[b].box, &tb);
            if (ha && hb) {
                if (tb < ta) {
                    uint32_t x = a;
                    a = b;
                    b = x;
                    tb = ta;
                }
                stack[top] = b;
                stack_t[top] = tb;
                ++top;
                node = a;
                continue;
            }
            if (ha || hb) {
                node = ha ? a : b;
                continue;
            }
        }
        /* Pop the next subtree that starts before the closest hit found since. */
        do {
            if (top == 0) {
                return found;
            }
            --top;
        } while (stack_t[top] > r.tmax);
        node = stack[top];
    }
}

/* The compressed wide BVH (cwbvh.h) in place of the binary one: an OpenCL device walks it
 * when its upload chose it (src/device/opencl.c). Host views never hold one, so host builds
 * leave the branch out and the CPU's query paths compile as they did before it. Out of line
 * on a device for the binary walk's reason (compat.h): one copy of its stack per work item. */
#if defined(__OPENCL_C_VERSION__) || defined(__OPENCL_VERSION__)
#define TR_SCENE_VIEW_CWBVH 1
TR_FN_TRAVERSE int tr_traverse_cwbvh(const tr_scene_view *s, const tr_ray *ray, tr_hit *hit,
                                     int any_hit) {
    return tr_cwbvh_traverse(s->cwbvh_nodes, s->cwbvh_node_count, s->cwbvh_tris, ray, hit, any_hit);
}
#endif

/* Closest hit against whichever structure the view holds. */
TR_FN int tr_intersect_scene(const tr_scene_view *s, const tr_ray *ray, tr_hit *hit) {
#ifdef TR_SCENE_VIEW_EMBREE
    if (s->accel == TR_ACCEL_EMBREE) {
        return tr_embree_intersect(s->embree_scene, s->embree_first, ray, hit);
    }
#endif
#ifdef TR_SCENE_VIEW_WBVH
    if (s->accel == TR_ACCEL_BVH && s->wbvh) {
        return tr_wbvh_intersect(s->wbvh, ray, hit);
    }
#endif
#ifdef TR_SCENE_VIEW_CWBVH
    if (s->accel == TR_ACCEL_BVH && s->cwbvh_node_count > 0u) {
        return tr_traverse_cwbvh(s, ray, hit, 0);
    }
#endif
    if (s->accel == TR_ACCEL_BVH) {
        return tr_traverse_bvh(s, ray, hit, 0);
    }
    return tr_intersect_flat(s, ray, hit);
}

/* Whether anything lies on the ray's segment (tmin, tmax): the shadow-ray query. */
TR_FN int tr_occluded_scene(const tr_scene_view *s, const tr_ray *ray) {
    tr_hit hit;
#ifdef TR_SCENE_VIEW_EMBREE
    if (s->accel == TR_ACCEL_EMBREE) {
        return tr_embree_occluded(s->embree_scene, ray);
    }
#endif
#ifdef TR_SCENE_VIEW_WBVH
    if (s->accel == TR_ACCEL_BVH && s->wbvh) {
        return tr_wbvh_occluded(s->wbvh, ray);
    }
#endif
#ifdef TR_SCENE_VIEW_CWBVH
    if (s->accel == TR_ACCEL_BVH && s->cwbvh_node_count > 0u) {
        return tr_traverse_cwbvh(s, ray, &hit, 1);
    }
#endif
    if (s->accel == TR_ACCEL_BVH) {
        return tr_traverse_bvh(s, ray, &hit, 1);
    }
    return tr_intersect_flat(s, ray, &hit);
}

#endif
