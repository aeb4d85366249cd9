/* types.h - every struct the kernel reads, declared once for the host and the device.
 *
 * Fields are fixed-width and laid out without implicit padding; the sizes are checked
 * with static asserts on the host so that arrays upload to a device unchanged. */
#ifndef TR_KERNEL_TYPES_H
#define TR_KERNEL_TYPES_H

#include "compat.h"
#include "trac0r/types.h"
#include "vec.h"

/* tr_vec3, tr_material, tr_triangle, tr_aabb and tr_camera are public value types,
 * declared once in include/trac0r/types.h (included through vec.h); their layouts are
 * checked here, where the host and the device compile them. */
TR_STATIC_ASSERT(sizeof(tr_material) == 32, "tr_material layout");
TR_STATIC_ASSERT(sizeof(tr_triangle) == 68, "tr_triangle layout");
TR_STATIC_ASSERT(sizeof(tr_aabb) == 24, "tr_aabb layout");
TR_STATIC_ASSERT(sizeof(tr_camera) == 100, "tr_camera layout");

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

/* A node of the light tree (src/scene/light_tree.c, kernel/light_tree.h) over the emissive
 * triangles, after Conty Estevez and Kulla 2018: the sphere around the box of the emitters
 * below (its centre, radius and squared radius: what the importance reads of the box, so that a
 * pick does not work them out again at every node it weighs), their total power, and a
 * cone bounding their normals (axis, cos_o and sin_o) beyond which they emit at most
 * theta_e further (cos_e: 0 for one-sided triangles). Interior nodes have their two
 * children at child and child + 1; a leaf (child has TR_LIGHT_LEAF set) holds one emitter,
 * child & ~TR_LIGHT_LEAF indexing the scene's light table. parent is the parent node's
 * index (the root's is 0). 56 bytes. */
typedef struct tr_light_node {
    tr_vec3 centre; /* (box.min + box.max) / 2 */
    float r, r2;    /* the half-diagonal of the box, and its square */
    tr_vec3 axis;
    float cos_o, sin_o, cos_e;
    float power;
    uint32_t child;
    uint32_t parent;
} tr_light_node;
TR_STATIC_ASSERT(sizeof(tr_light_node) == 56, "tr_light_node layout");
#define TR_LIGHT_LEAF 0x80000000u

/* The BVH's depth never exceeds this (the builder switches to median splits well before),
 * so a traversal stack of this size cannot overflow. */
#define TR_BVH_STACK_SIZE 64

/* Everything one frame of the kernel needs besides the scene: one struct, declared once,
 * uploaded as one buffer to a device. The 64-bit seed travels as two words so that the
 * layout has no padding on any device. A frame adds samples sample .. sample+sample_count-1
 * to every pixel of the rectangle (rect_x, rect_y, rect_w, rect_h); with stride k > 1 only
 * pixels whose coordinates are multiples of k are traced and each stands for its k x k
 * block (the thesis's preview). 164 bytes. */
typedef struct tr_frame {
    tr_camera camera;
    uint32_t seed_lo, seed_hi;
    uint32_t sample, sample_count;
    int32_t max_depth;
    uint32_t integrator; /* TR_INTEGRATOR_* */
    uint32_t stride;
    uint32_t passes; /* TR_PASS_* the film keeps */
    uint32_t rect_x, rect_y, rect_w, rect_h;
    uint32_t sampler; /* TR_SAMPLER_*: pt's uniform numbers */
    int32_t rr_start; /* pt: Russian roulette after this many segments */
    /* pt's firefly control (integrator_pt.h): the largest luminance of a contribution
     * arriving over an indirect vertex (0: no clamp), and TR_FRAME_* bits. */
    float clamp_indirect;
    uint32_t flags;
} tr_frame;
TR_STATIC_ASSERT(sizeof(tr_frame) == 164, "tr_frame layout");

/* tr_frame.flags: pt roughens glossy and specular lobes after the first non-specular
 * vertex (path regularization, integrator_pt.h). */
#define TR_FRAME_REGULARIZE 1u
/* tr_frame.flags: pt leaves out the direct light at the camera ray's first surface where that
 * is not specular (its light samples and the emission its BSDF sample finds next), which a
 * later stage adds
 * (ReSTIR DI, src/kernel/restir.h). */
#define TR_FRAME_NO_PRIMARY_DIRECT 2u
/* tr_frame.flags: pt ends the path at the camera ray's first surface where that is not
 * specular, leaving its indirect light to a later stage (ReSTIR GI, restir_gi.h). */
#define TR_FRAME_NO_PRIMARY_INDIRECT 4u
/* pt leaves out the emission of the first surface its ray finds that light sampling
 * reaches (emitters of the light table, the environment, the sun): set by ReSTIR GI's
 * rays from the first surface, whose direct light ReSTIR DI estimates. */
#define TR_FRAME_NO_FIRST_LIGHT 8u
/* tr_frame.flags: primary surface replacement (psr.h): where the camera ray first meets a
 * mirror or smooth glass, the passes describe the first surface behind the delta chain,
 * traced apart with the more probable lobe at glass. The radiance is unchanged. */
#define TR_FRAME_PSR 16u
/* The top bit of a primitive id in the passes (TR_PASS_PRIM) under TR_FRAME_PSR: the surface
 * was found through a curved delta surface (smooth-shaded, its shading normal off the
 * triangle's) or through a refraction, where the virtual position is an approximation, so
 * that the reconstruction's consistency test is wider there (tr_reproject_consistent). */
#define TR_PRIM_PSR_CURVED 0x80000000u
/* tr_frame.flags: pt splits the light reflected at the passes' surface into its diffuse and
 * specular parts (TR_PASS_SPECULAR, tr_trace_pt_ff). The radiance is unchanged. */
#define TR_FRAME_SPLIT_SPECULAR 32u

/* What one sample of one pixel gives: radiance, the intersection queries it made, and
 * the surface the passes describe (zero where the path found no non-specular surface). */
typedef struct tr_sample {
    tr_vec3 radiance;
    tr_vec3 direct;   /* the part of radiance that is direct light (TR_PASS_DIRECT) */
    tr_vec3 emission; /* the emission the camera ray saw at its first hit (TR_PASS_EMISSION) */
    /* TR_PASS_SPECULAR: the specular part of radiance, the surface's specular F0 and GGX
     * alpha, and the distance from it to the next vertex along a specular sample (0: none) */
    tr_vec3 specular;
    tr_vec3 spec_f0;
    float spec_alpha;
    float spec_dist;
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
