/* scene_internal.h - the scene as the library holds it (tr_scene is opaque to clients:
 * include/trac0r/scene.h), and what the scene, accel and backend sources share. Tests
 * include it to build scenes on the stack and to read the arrays directly. */
#ifndef TR_SCENE_INTERNAL_H
#define TR_SCENE_INTERNAL_H

#include "accel/accel_internal.h"
#include "kernel/scene_view.h"
#include "kernel/types.h"
#include "trac0r/scene.h"

struct tr_scene {
    tr_material *materials;
    uint32_t material_count, material_capacity;
    tr_triangle *triangles;
    uint32_t triangle_count, triangle_capacity;
    tr_flat_node *shapes; /* one box + triangle run per shape: the thesis's flat structure */
    uint32_t shape_count, shape_capacity;
    tr_camera camera;
    /* Set by tr_scene_commit: the structure rays are traced through. */
    tr_accel_type accel;
    tr_bvh bvh;
    tr_wbvh wbvh;                 /* collapsed from bvh for TR_ACCEL_TYPE_BVH (host traversal) */
    tr_embree embree;             /* built for TR_ACCEL_TYPE_EMBREE only */
    uint32_t committed_triangles; /* triangle count at the last successful commit */
    /* Bumped by every edit of what rays hit (tr_scene_generation); committed_generation is
     * the generation the last tr_scene_commit or tr_scene_update built for, valid when
     * `committed` is set. */
    uint64_t generation;
    uint64_t committed_generation;
    int committed;
    /* Emitter table for next-event estimation, rebuilt by tr_scene_commit
     * (src/scene/lights.c): emissive triangle indices and their selection CDF. */
    uint32_t *lights;
    float *light_cdf;
    uint32_t light_count;
    float light_weight_total;
    uint32_t light_triangles; /* triangle count when the table was built */
    /* Vertex normals of imported meshes, kept for smooth shading (the kernels do not read
     * them yet): three per triangle for triangles 0..vertex_normal_count-1, zero where a
     * triangle has none; triangles beyond that have none. */
    tr_vec3 *vertex_normals;
    uint32_t vertex_normal_count, vertex_normal_capacity;
};

/* An empty scene (no allocation), for a tr_scene the caller owns (tr_scene_create does
 * this on the heap). Callers may also zero-initialise one: tr_scene s = {0}. */
void tr_scene_init(tr_scene *s);

/* Appends n triangles as one shape (one box of the flat structure), growing the scene's
 * arrays; `normals` (3 per triangle) may be NULL. The caller keeps its arrays. */
int tr_scene_append_shape(tr_scene *s, const tr_triangle *tris, uint32_t n, const tr_vec3 *normals,
                          tr_error *err);

/* After moving triangles (same count) of a scene committed to a BVH: refits the binary
 * BVH's boxes (tr_bvh_refit), then the wide BVH in place (tr_wbvh_refit: same shape, new
 * boxes and leaf packets; collapsed anew if it was older than the binary tree). A view
 * taken after a bare tr_bvh_refit uses the binary BVH until this runs. */
int tr_scene_refit(tr_scene *s, tr_error *err);

/* Rebuilds the emitter table (tr_scene_commit calls it): every triangle of positive
 * area whose material has emittance > 0, weighted by tr_light_weight. */
int tr_scene_build_lights(tr_scene *s, tr_error *err);

/* Fills a triangle's normal, centroid and area from its vertices (normal and area are
 * zero for degenerate ones). */
void tr_triangle_finish(tr_triangle *t);
/* The bounding box of n triangles. */
tr_aabb tr_triangles_bounds(const tr_triangle *t, uint32_t n);

/* TR_OK when the scene is committed at its current generation (tr_scene_is_committed),
 * otherwise TR_ERR with a message saying which call is missing: every backend checks
 * this before it traces or uploads a scene. */
int tr_scene_check_committed(const tr_scene *s, tr_error *err);

/* The view the kernels trace against; valid while the scene is not modified. */
tr_scene_view tr_scene_view_of(const tr_scene *s);

#endif
