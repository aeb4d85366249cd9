/* attrib.h - what a surface carries besides its triangle: vertex attributes (shading
 * normals, texture coordinates), textures and the material parameters that the public
 * tr_material (32 bytes, part of the ABI) has no room for.
 *
 * Every array here is optional: a scene without any of them has zero counts, and the
 * material stage (material_eval.h) then does exactly what it did before they existed.
 *
 * Vertex attributes are indexed: tri_verts[t] names three entries of `vertices` for
 * triangle t. An imported mesh shares a vertex among ~6 triangles, so the index buffer
 * costs 12 bytes a triangle plus 20 bytes for every ~2 triangles (~22 bytes), against
 * 60 for three independent vertices per triangle; the positions stay in tr_triangle
 * and the BVH's leaves, whose layout the traversal is tuned for. */
#ifndef TR_KERNEL_ATTRIB_H
#define TR_KERNEL_ATTRIB_H

#include "compat.h"
#include "types.h"

/* tr_tri_verts.v[0] of a triangle without vertex attributes; tr_material_ext's texture
 * index of no texture. */
#define TR_NO_INDEX 0xffffffffu

/* One vertex's attributes, 20 bytes. A zero normal means none (the geometric one). */
typedef struct tr_vertex {
    tr_vec3 normal; /* unit, world space, on the side the triangle's geometric normal faces */
    float u, v;     /* texture coordinates, glTF's convention: v grows downwards in the image */
} tr_vertex;
TR_STATIC_ASSERT(sizeof(tr_vertex) == 20, "tr_vertex layout");

/* The vertices of one triangle, in the order of tr_triangle's v0, v1, v2. 12 bytes. */
typedef struct tr_tri_verts {
    uint32_t v[3];
} tr_tri_verts;
TR_STATIC_ASSERT(sizeof(tr_tri_verts) == 12, "tr_tri_verts layout");

/* tr_texture.flags */
#define TR_TEXTURE_CLAMP 1u     /* clamp coordinates to the edge (else repeat) */
#define TR_TEXTURE_TRANSFORM 2u /* transform the coordinates by xf first */

/* An image in the scene's texel array: width x height RGBA8 texels (R in the low byte),
 * row-major from the top row, starting at texels[offset]. With TR_TEXTURE_TRANSFORM the
 * texture coordinates (u, v) are first replaced by (xf[0] u + xf[1] v + xf[2],
 * xf[3] u + xf[4] v + xf[5]): glTF's KHR_texture_transform, which belongs to a material's
 * use of an image, so such a use gets an entry of its own over the same texels. 40 bytes. */
typedef struct tr_texture {
    uint32_t offset;
    uint32_t width, height;
    uint32_t flags; /* TR_TEXTURE_* */
    float xf[6];
} tr_texture;
TR_STATIC_ASSERT(sizeof(tr_texture) == 40, "tr_texture layout");

/* tr_material_ext.flags */
#define TR_MATEXT_ALPHA_MASK 1u /* texels with alpha below alpha_cutoff are holes */
#define TR_MATEXT_SPECULAR 2u   /* specular and specular_color are set (else 1 and white) */

/* Per-material extras, one per material when the scene has any (material_ext_count is 0
 * or material_count). Texture indices are TR_NO_INDEX for none. 128 bytes. */
typedef struct tr_material_ext {
    uint32_t base_tex;     /* sRGB colour (x the material's colour), alpha in a */
    uint32_t emission_tex; /* sRGB colour (x emission) */
    uint32_t mr_tex;       /* glTF: roughness in g, metallic in b (x the factors) */
    uint32_t normal_tex;   /* tangent-space normal map, linear */
    tr_vec3 emission;      /* emitted radiance of a non-emitter material (principled) */
    float metallic;        /* principled: 0 dielectric, 1 conductor */
    float alpha_cutoff;    /* TR_MATEXT_ALPHA_MASK: alpha below this is a hole */
    float normal_scale;    /* glTF normalTexture.scale */
    uint32_t flags;        /* TR_MATEXT_* */
    /* principled: glTF's clear coat, a second GGX layer (bsdf_principled.h); 0 for none. */
    float clearcoat;           /* the layer's weight in [0, 1] */
    float clearcoat_roughness; /* its roughness in [0, 1] (alpha = roughness^2) */
    /* principled: glTF's KHR_materials_transmission, the weight of the rough dielectric
     * transmission lobe (bsdf_dielectric.h) in [0, 1]; 0 for none. */
    float transmission;
    /* KHR_materials_volume's attenuation as an absorption coefficient per unit length,
     * -ln(attenuationColor) / attenuationDistance: light inside the object keeps
     * exp(-absorption d) after a distance d (tr_volume_attenuation, material_eval.h).
     * Zero for none. */
    tr_vec3 absorption;
    /* principled: glTF's KHR_materials_sheen, a Charlie sheen layer over the base
     * (bsdf_principled.h); black for none. */
    tr_vec3 sheen_color;
    float sheen_roughness;
    /* principled, with TR_MATEXT_SPECULAR: glTF's KHR_materials_specular, the dielectric
     * layer's F0 min(F0(ior) specular_color, 1) specular and its F90 specular. */
    float specular;
    tr_vec3 specular_color;
    /* principled: glTF's transmissionTexture, linear, its red channel multiplying
     * `transmission`; TR_NO_INDEX for none. */
    uint32_t transmission_tex;
    /* principled: glTF's clearcoatTexture (linear, its red channel multiplying
     * `clearcoat`) and clearcoatRoughnessTexture (linear, its green channel multiplying
     * `clearcoat_roughness`); TR_NO_INDEX for none. */
    uint32_t clearcoat_tex;
    uint32_t clearcoat_rough_tex;
    /* principled: glTF's sheenColorTexture (sRGB, its colour multiplying `sheen_color`) and
     * sheenRoughnessTexture (linear, its alpha multiplying `sheen_roughness`), and the
     * clear coat's own normal map, clearcoatNormalTexture (tangent space, linear, its x
     * and y scaled by clearcoat_normal_scale as normalTexture's by normal_scale);
     * TR_NO_INDEX for none. */
    uint32_t sheen_color_tex;
    uint32_t sheen_rough_tex;
    uint32_t clearcoat_normal_tex;
    float clearcoat_normal_scale;
} tr_material_ext;
TR_STATIC_ASSERT(sizeof(tr_material_ext) == 128, "tr_material_ext layout");

/* The environment: radiance arriving from infinitely far along directions no surface
 * blocks, a constant colour or an equirectangular map (width x height RGB floats in
 * env_texels, row 0 at +y, column 0 at -z turning towards +x... see envmap.h), times
 * color * strength, turned by `rotation` about +y. The scene holds 0 or 1. 40 bytes. */
typedef struct tr_env {
    tr_vec3 color;
    float strength;
    float rot_cos, rot_sin; /* the rotation about +y */
    uint32_t width, height; /* 0 x 0: constant */
    float weight_sum;       /* sum of the sampling weights (envmap.h) over all texels */
    uint32_t pad;
} tr_env;
TR_STATIC_ASSERT(sizeof(tr_env) == 40, "tr_env layout");

/* The sun (sun.h): radiance from a cone of directions around `dir` (unit, towards the
 * sun) of half-angle t, one_minus_cos = 1 - cos t kept apart so that small discs keep
 * their precision; radiance = irradiance / (pi sin^2 t), so that a surface facing the
 * sun receives the given irradiance. The scene holds 0 or 1. 32 bytes. */
typedef struct tr_sun {
    tr_vec3 dir;
    float one_minus_cos;
    tr_vec3 radiance;
    float pdf; /* 1 / (2 pi one_minus_cos): uniform over the cone's solid angle */
} tr_sun;
TR_STATIC_ASSERT(sizeof(tr_sun) == 32, "tr_sun layout");

/* Punctual lights (punctual.h): delta lights, found only by next-event estimation. */
#define TR_PUNCTUAL_POINT 0u       /* intensity in every direction from pos */
#define TR_PUNCTUAL_SPOT 1u        /* a point light limited to a cone around dir */
#define TR_PUNCTUAL_DIRECTIONAL 2u /* parallel light travelling along dir */

/* One punctual light. Point and spot: `intensity` is the radiant intensity I (W/sr, on the
 * axis for a spot), so a surface at distance r whose normal makes the angle t with the
 * light receives E = I cos t / r^2; a spot's intensity falls from I inside cos_inner to 0
 * outside cos_outer (the cosines of the angles from its axis) by a smoothstep.
 * Directional: `intensity` is the irradiance E (W/m^2) on a surface facing the light,
 * whose light travels along dir. cdf: the lights' selection CDF (by power; the last 1).
 * 64 bytes. */
typedef struct tr_punctual {
    tr_vec3 pos;
    uint32_t type; /* TR_PUNCTUAL_* */
    tr_vec3 dir;   /* spot: the unit axis it shines along; directional: the unit direction
                      the light travels */
    float cdf;
    tr_vec3 intensity;
    float cos_outer;
    float cos_inner;
    float power; /* the selection weight (punctual.c), for the tests */
    float pad[2];
} tr_punctual;
TR_STATIC_ASSERT(sizeof(tr_punctual) == 64, "tr_punctual layout");

#endif
