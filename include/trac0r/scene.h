/* scene.h - a scene: materials, triangles grouped into shapes, and a camera.
 *
 * The scene owns flat arrays indexed by integers, exactly as the kernels read them
 * (src/kernel/types.h). Shapes are generators of triangles (the thesis's
 * Shape::make_*): each call appends its triangles and the shape's bounding box.
 *
 *     tr_scene s;
 *     tr_scene_init(&s);
 *     uint32_t white;
 *     tr_scene_add_material(&s, tr_material_diffuse(v3(0.7f, 0.7f, 0.7f)), &white, &err);
 *     tr_shape_desc box = tr_shape_desc_default(TR_SHAPE_BOX);
 *     box.material = white;
 *     tr_scene_add_shape(&s, &box, &err);
 *     ...
 *     tr_scene_free(&s);
 */
#ifndef TRAC0R_SCENE_H
#define TRAC0R_SCENE_H

#include <stdint.h>

#include "accel/wbvh.h" /* tr_wbvh, embedded below (private to the library) */
#include "kernel/scene_view.h"
#include "kernel/types.h"
#include "trac0r/accel.h"
#include "trac0r/error.h"

/* Icospheres are limited to this many subdivisions: 20 * 4^9 = 5 242 880 triangles. */
#define TR_ICOSPHERE_MAX_SUBDIVISIONS 9

typedef enum tr_shape_type {
    TR_SHAPE_PLANE = 1,     /* unit square in the xz plane, normal +y */
    TR_SHAPE_BOX = 2,       /* unit cube centred on the origin, normals outward */
    TR_SHAPE_ICOSPHERE = 3, /* unit sphere from a subdivided icosahedron */
} tr_shape_type;

/* Where a shape's unit geometry goes: scaled, then rotated about x, then y, then z
 * (R = Rz * Ry * Rx, angles in radians, right-handed), then translated. */
typedef struct tr_transform {
    tr_vec3 position;
    tr_vec3 orientation; /* Euler angles, radians */
    tr_vec3 scale;       /* plane: (size x, 1, size z); box: size; icosphere: radius */
} tr_transform;

typedef struct tr_shape_desc {
    tr_shape_type type;
    tr_transform transform;
    uint32_t subdivisions; /* icosphere only: 20 * 4^n triangles */
    uint32_t material;     /* index returned by tr_scene_add_material */
} tr_shape_desc;

typedef struct tr_scene {
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
    uint32_t committed_triangles; /* triangle count when the BVH or Embree scene was built */
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
} tr_scene;

/* A shape of the given type at the origin, unrotated, unit scale, material 0. */
tr_shape_desc tr_shape_desc_default(tr_shape_type type);

tr_material tr_material_emitter(tr_vec3 color, float emittance);
tr_material tr_material_diffuse(tr_vec3 color);
tr_material tr_material_glass(tr_vec3 color, float ior);
tr_material tr_material_glossy(tr_vec3 color, float roughness);

/* An empty scene (no allocation). */
void tr_scene_init(tr_scene *s);
/* Releases everything the scene owns and leaves it empty. */
void tr_scene_free(tr_scene *s);
/* Appends a material and returns its index in *index. Rejects non-finite or negative
 * values and unknown types. */
int tr_scene_add_material(tr_scene *s, tr_material m, uint32_t *index, tr_error *err);
/* Appends a shape's triangles and its bounding box. */
int tr_scene_add_shape(tr_scene *s, const tr_shape_desc *desc, tr_error *err);
/* Appends an indexed triangle mesh as one shape: positions holds 3 floats per vertex,
 * indices 3 per triangle, normals (NULL for none) 3 floats per vertex; tf (NULL for
 * none) places it like a shape. Triangles of zero area after the transform are dropped
 * and counted in *dropped (may be NULL). Fails, adding nothing, on an index out of range,
 * a non-finite position, an unknown material or when nothing but degenerate triangles
 * is left. */
int tr_scene_add_mesh(tr_scene *s, const float *positions, uint32_t vertex_count,
                      const uint32_t *indices, uint32_t triangle_count, const float *normals,
                      uint32_t material, const tr_transform *tf, uint32_t *dropped, tr_error *err);
/* A shape transform applied to a point, and to a normal (inverse transpose, unit). */
tr_vec3 tr_transform_point(const tr_transform *tf, tr_vec3 p);
tr_vec3 tr_transform_normal(const tr_transform *tf, tr_vec3 n);

/* Number of triangles a shape description generates (0 for an invalid one). */
uint64_t tr_shape_triangle_count(const tr_shape_desc *desc);

/* Fills a triangle's normal, centroid and area from its vertices (normal and area are
 * zero for degenerate ones). */
void tr_triangle_finish(tr_triangle *t);
/* The bounding box of n triangles. */
tr_aabb tr_triangles_bounds(const tr_triangle *t, uint32_t n);

/* Builds a built-in scene by name with its camera set up for a width x height image:
 * "cornell" is the thesis's listing 16; "cornell-mirror" the same with the glossy
 * objects' roughness 0 (perfect mirrors, on which the naive and pt integrators agree);
 * "cornell-diffuse" the same room with every object white diffuse; "cornell-ico-N" is
 * the scene of the thesis's complexity benchmark (figure 3.5): the same room with only
 * the glass icosphere, at N = 0..TR_ICOSPHERE_MAX_SUBDIVISIONS subdivisions (20 * 4^N
 * triangles). */
int tr_scene_builtin(tr_scene *s, const char *name, uint32_t width, uint32_t height, tr_error *err);

/* Builds the acceleration structure rays will be traced through (the thesis's flat
 * structure needs no build), releasing the one built before. Call again after adding
 * shapes; rendering a scene whose BVH or Embree scene is older than its triangles
 * fails. TR_ACCEL_TYPE_EMBREE fails with "this build of trac0r has no Embree support"
 * where tr_accel_available says so. On failure the scene is left on the flat structure. */
int tr_scene_commit(tr_scene *s, tr_accel_type accel, tr_error *err);
/* Whether the committed structure covers the scene's current triangles. */
int tr_scene_is_committed(const tr_scene *s);
/* After moving triangles (same count) of a scene committed to a BVH: refits the binary
 * BVH's boxes (tr_bvh_refit), then the wide BVH in place (tr_wbvh_refit: same shape, new
 * boxes and leaf packets; collapsed anew if it was older than the binary tree). A view
 * taken after a bare tr_bvh_refit uses the binary BVH until this runs. */
int tr_scene_refit(tr_scene *s, tr_error *err);
/* Dynamic scenes, as the thesis assumes (geometry may change every frame): moves shape
 * `shape` (its triangles and its box in the flat structure) by `delta`. Areas, normals and
 * the emitter table stay valid; the committed structure is stale until tr_scene_update. */
int tr_scene_move_shape(tr_scene *s, uint32_t shape, tr_vec3 delta, tr_error *err);
/* Brings the committed structure up to date after triangles moved (same count): a BVH is
 * refitted (tr_scene_refit: boxes of the same trees, binary and wide), Embree's scene
 * rebuilt, the flat structure needs nothing. *seconds (may be NULL) gets the time taken. */
int tr_scene_update(tr_scene *s, double *seconds, tr_error *err);
/* What tr_scene_update does for the scene's structure: "refit", "rebuild" or "none". */
const char *tr_scene_update_kind(const tr_scene *s);
/* Seconds tr_scene_commit took to build the BVH: the binary build plus, for
 * TR_ACCEL_TYPE_BVH, the wide collapse (0 for other structures). */
double tr_scene_bvh_build_seconds(const tr_scene *s);
/* Seconds tr_scene_commit took to build the Embree scene (0 unless the scene is
 * committed to TR_ACCEL_TYPE_EMBREE). */
double tr_scene_embree_build_seconds(const tr_scene *s);

/* Rebuilds the emitter table (tr_scene_commit calls it): every triangle of positive
 * area whose material has emittance > 0, weighted by tr_light_weight. */
int tr_scene_build_lights(tr_scene *s, tr_error *err);

/* The view the kernels trace against; valid while the scene is not modified. */
tr_scene_view tr_scene_view_of(const tr_scene *s);

#endif
