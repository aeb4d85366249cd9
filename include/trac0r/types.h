/* types.h - the plain value types of libtrac0r's API.
 *
 * Fixed-width fields, no padding, nothing that depends on compile flags: a struct has
 * the same size and layout in the library, in a C99, C11 or C++ client, and on an
 * OpenCL device. The kernel (src/kernel/types.h) takes these declarations from here
 * rather than declaring them again, so this header is also valid OpenCL C 1.2, where
 * the fixed-width integer types come from src/kernel/compat.h instead of <stdint.h>.
 * tr_abi_sizeof (abi.h) reports the sizes as compiled into the library. */
#ifndef TRAC0R_TYPES_H
#define TRAC0R_TYPES_H

#if !defined(__OPENCL_C_VERSION__) && !defined(__OPENCL_VERSION__)
#include <stdint.h>
#endif

/* Three floats, 12 bytes (OpenCL's float3 takes 16: arrays of it would not match). */
typedef struct tr_vec3 {
    float x, y, z;
} tr_vec3;

/* (x, y, z): for C++ and C99 alike (a compound literal is not C++). */
static inline tr_vec3 tr_vec3_make(float x, float y, float z) {
    tr_vec3 v;
    v.x = x;
    v.y = y;
    v.z = z;
    return v;
}

/* Material types, numbered as in the thesis (listing 2): TR_MATERIAL_EMITTER ..., from the
 * one list of them. */
#include "trac0r/material_types.h"

/* tr_material.flags bits. Emitters emit towards the side their triangle's geometric
 * normal points to, unless TWO_SIDED is set (the pt integrator; naive ignores it). */
#define TR_MATERIAL_TWO_SIDED 1u
/* glossy and principled: Kulla and Conty's multiple-scattering compensation of the GGX
 * conductor lobe (src/kernel/ggx_ms.h); scene files' "multiscatter": true. */
#define TR_MATERIAL_MULTISCATTER 2u

/* 32 bytes. */
typedef struct tr_material {
    uint32_t type;   /* TR_MATERIAL_* */
    tr_vec3 color;   /* base colour (linear RGB) */
    float roughness; /* glossy: the reflection cone's half-angle is roughness * pi/2 */
    float ior;       /* glass: index of refraction */
    float emittance; /* radiance scale; emitted radiance is color * emittance */
    uint32_t flags;  /* TR_MATERIAL_TWO_SIDED */
} tr_material;

/* A triangle with its precomputed geometric normal, centroid and area (listing 5).
 * The material is an index into the scene's material array. 68 bytes. */
typedef struct tr_triangle {
    tr_vec3 v0, v1, v2;
    tr_vec3 normal;   /* unit, (v1 - v0) x (v2 - v0); zero for a degenerate triangle */
    tr_vec3 centroid; /* (v0 + v1 + v2) / 3 */
    float area;
    uint32_t material;
} tr_triangle;

/* An axis-aligned box, 24 bytes. */
typedef struct tr_aabb {
    tr_vec3 min;
    tr_vec3 max;
} tr_aabb;

/* A pinhole camera (listing 6), built by tr_camera_make (camera.h), or a thin lens with an
 * aperture (tr_camera_set_lens). 100 bytes. */
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
    /* Thin lens: the lens's radius (0: a pinhole, the default) and the distance along dir
     * of the plane in focus, in scene units. */
    float lens_radius;
    float focus_dist;
} tr_camera;

/* Integrators (tr_render_config.integrator): TR_INTEGRATOR_PT, TR_INTEGRATOR_NAIVE, from the
 * one list of them. */
#include "trac0r/integrator_types.h"

/* Passes a film can keep beside radiance (tr_render_config.passes, tr_film.passes): what a
 * denoiser needs, taken at the first surface of each camera path that is not a mirror or
 * smooth glass (their bounces are followed, as denoisers expect). */
#define TR_PASS_ALBEDO 1u /* the surface's albedo towards the camera, linear RGB */
#define TR_PASS_NORMAL 2u /* unit shading normal, world space, facing the arriving ray */
#define TR_PASS_DEPTH 4u  /* distance travelled from the camera to the surface */
#define TR_PASS_PRIM 8u   /* index of the triangle hit, plus one (0: none) */
#define TR_PASS_ALL 15u   /* the surface passes above: a denoiser's guides */
/* Not a surface but the noise of the radiance estimate: the film keeps per-pixel sums of
 * squared radiance (per channel), from which the variance of the pixel's mean follows
 * (tr_film_pass_pixel). Taken from every sample, so it costs a few multiplications and
 * 12 bytes a pixel, and changes no other pass or the radiance. */
#define TR_PASS_VARIANCE 16u
/* Not a surface either: the part of the radiance that is direct illumination of the passes'
 * surface (the first one that is not a mirror or smooth glass), summed like radiance, for
 * filters that treat direct and indirect light apart (SVGF, Schied et al. 2017, section 4).
 * pt and naive write it (tr_trace_pt: what goes where); bdpt does not. Radiance minus direct
 * is the indirect part. */
#define TR_PASS_DIRECT 32u
/* Not a surface either: the emission the camera ray sees at its first hit (an emitter's, or
 * the environment's and the sun's where it leaves the scene), summed like radiance; radiance
 * minus it is the light the scene reflects. The real-time reconstruction keeps it out of its
 * filters and adds back an estimate resolved over the pixel's area (tr_resolve_emission), so
 * that a lamp's edge is antialiased at 1 spp. pt and naive write it (naive's with its
 * roulette weight and without the environment, which naive does not see); bdpt does not. */
#define TR_PASS_EMISSION 64u
/* Not a surface either: the light the passes' surface reflects split by lobe, 8 floats per
 * pixel summed like radiance: the specular part (3: what its GGX layer reflects; radiance
 * minus emission minus it is the diffuse part), the surface's specular F0 (3), its GGX alpha
 * (1) and the distance to what a specular sample from it hit (1, 0 where none), from which
 * the real-time reconstruction demodulates the specular part and follows reflections
 * (docs/realtime.md). pt writes it, on the CPU and on OpenCL devices; the others do not. */
#define TR_PASS_SPECULAR 128u
#define TR_PASS_MASK 255u /* every pass bit a film knows */

#endif
