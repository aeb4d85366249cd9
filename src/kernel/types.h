/* types.h - every struct the kernel reads, declared once for the host and the device.
 *
 * Fields are fixed-width and laid out without implicit padding; the sizes are checked
 * with static asserts on the host so that arrays upload to a device unchanged. */
#ifndef TR_KERNEL_TYPES_H
#define TR_KERNEL_TYPES_H

#include "compat.h"
#include "material_types.h" /* TR_MATERIAL_EMITTER ..., numbered as in the thesis (listing 2) */
#include "vec.h"

/* tr_material.flags bits. Emitters emit towards the side their triangle's geometric
 * normal points to, unless TWO_SIDED is set (the pt integrator; naive ignores it). */
#define TR_MATERIAL_TWO_SIDED 1u

/* 32 bytes. */
typedef struct tr_material {
    uint32_t type;   /* TR_MATERIAL_* */
    tr_vec3 color;   /* base colour (linear RGB) */
    float roughness; /* glossy: the reflection cone's half-angle is roughness * pi/2 */
    float ior;       /* glass: index of refraction */
    float emittance; /* radiance scale; emitted radiance is color * emittance */
    uint32_t flags;  /* TR_MATERIAL_TWO_SIDED */
} tr_material;
TR_STATIC_ASSERT(sizeof(tr_material) == 32, "tr_material layout");

/* A triangle with its precomputed geometric normal, centroid and area (listing 5).
 * The material is an index into the scene's material array. 68 bytes. */
typedef struct tr_triangle {
    tr_vec3 v0, v1, v2;
    tr_vec3 normal;   /* unit, (v1 - v0) x (v2 - v0); zero for a degenerate triangle */
    tr_vec3 centroid; /* (v0 + v1 + v2) / 3 */
    float area;
    uint32_t material;
} tr_triangle;
TR_STATIC_ASSERT(sizeof(tr_triangle) == 68, "tr_triangle layout");

typedef struct tr_aabb {
    tr_vec3 min;
    tr_vec3 max;
} tr_aabb;
TR_STATIC_ASSERT(sizeof(tr_aabb) == 24, "tr_aabb layout");

/* One entry of the thesis's flat structure: a shape's box and its run of triangles.
 * 32 bytes. */
typedef struct tr_flat_node {
    tr_aabb box;
    uint32_t first; /* index of the shape's first triangle */
    uint32_t count; /* number of triangles */
} tr_flat_node;
TR_STATIC_ASSERT(sizeof(tr_flat_node) == 32, "tr_flat_node layout");

/* Acceleration structures a scene view can hold. */
#define TR_ACCEL_FLAT 0u   /* the thesis's list of shape boxes */
#define TR_ACCEL_BVH 1u    /* binary SAH BVH (src/accel/bvh.c) */
#define TR_ACCEL_EMBREE 2u /* Intel Embree 3, host only (src/accel/embree.c) */

/* A node of the binary BVH, 32 bytes. Interior nodes (count == 0) have their two
 * children at left_first and left_first + 1; leaves hold `count` entries of the BVH's
 * triangle index array starting at left_first. Node 0 is the root. */
typedef struct tr_bvh_node {
    tr_aabb box;
    uint32_t left_first;
    uint32_t count;
} tr_bvh_node;
TR_STATIC_ASSERT(sizeof(tr_bvh_node) == 32, "tr_bvh_node layout");

/* A triangle as the BVH's leaves store it, in leaf order: the first vertex and the two
 * edges Moller-Trumbore needs, and the index of the scene triangle. 40 bytes, against
 * 68 for tr_triangle, and no indirection. */
typedef struct tr_bvh_tri {
    tr_vec3 v0, e1, e2;
    uint32_t index;
} tr_bvh_tri;
TR_STATIC_ASSERT(sizeof(tr_bvh_tri) == 40, "tr_bvh_tri layout");

/* The BVH's depth never exceeds this (the builder switches to median splits well before),
 * so a traversal stack of this size cannot overflow. */
#define TR_BVH_STACK_SIZE 64

/* The camera as the kernel sees it (listing 6); built by tr_camera_make() on the host. */
typedef struct tr_camera {
    tr_vec3 pos;
    tr_vec3 dir;          /* unit view direction */
    tr_vec3 world_up;     /* the up vector the user gave */
    tr_vec3 right;        /* unit, dir x world_up */
    tr_vec3 up;           /* unit, right x dir */
    float vertical_fov;   /* degrees */
    float horizontal_fov; /* degrees, derived from the aspect ratio */
    float near_dist;
    float far_dist;
    float canvas_width; /* extent of the image plane at distance 1 */
    float canvas_height;
    uint32_t screen_width;
    uint32_t screen_height;
} tr_camera;
TR_STATIC_ASSERT(sizeof(tr_camera) == 92, "tr_camera layout");

/* Passes a film can keep beside radiance (tr_frame.passes, tr_film.passes): what a
 * denoiser needs, taken at the first non-specular hit of each camera path (after mirror
 * and smooth-glass bounces, as denoisers expect). */
#define TR_PASS_ALBEDO 1u /* base colour of the surface, linear RGB */
#define TR_PASS_NORMAL 2u /* unit shading normal, world space, facing the arriving ray */
#define TR_PASS_DEPTH 4u  /* distance travelled from the camera to the surface */
#define TR_PASS_PRIM 8u   /* index of the triangle hit, plus one (0: none) */
#define TR_PASS_ALL 15u

/* Everything one frame of the kernel needs besides the scene: one struct, declared once,
 * uploaded as one buffer to a device. The 64-bit seed travels as two words so that the
 * layout has no padding on any device. A frame adds samples sample .. sample+sample_count-1
 * to every pixel of the rectangle (rect_x, rect_y, rect_w, rect_h); with stride k > 1 only
 * pixels whose coordinates are multiples of k are traced and each stands for its k x k
 * block (the thesis's preview). 140 bytes. */
typedef struct tr_frame {
    tr_camera camera;
    uint32_t seed_lo, seed_hi;
    uint32_t sample, sample_count;
    int32_t max_depth;
    uint32_t integrator; /* TR_INTEGRATOR_* */
    uint32_t stride;
    uint32_t passes; /* TR_PASS_* the film keeps */
    uint32_t rect_x, rect_y, rect_w, rect_h;
} tr_frame;
TR_STATIC_ASSERT(sizeof(tr_frame) == 140, "tr_frame layout");

/* What one sample of one pixel gives: radiance, the intersection queries it made, and
 * the surface the passes describe (zero where the path found no non-specular surface). */
typedef struct tr_sample {
    tr_vec3 radiance;
    tr_vec3 albedo;
    tr_vec3 normal;
    float depth;
    uint32_t prim; /* triangle index + 1, 0 for none */
    uint32_t rays;
} tr_sample;

typedef struct tr_ray {
    tr_vec3 origin;
    tr_vec3 dir;
    tr_vec3 inv_dir; /* 1/dir per component, precomputed for the slab test (listing 7) */
    float tmin;
    float tmax;
} tr_ray;

/* What a closest-hit query returns. */
typedef struct tr_hit {
    float t;
    uint32_t triangle; /* index of the hit triangle; meaningless when t is infinite */
    float u, v;        /* barycentrics of v1 and v2 */
} tr_hit;

#endif
