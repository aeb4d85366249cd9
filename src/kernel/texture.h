/* texture.h - texture lookups (bilinear, repeat or clamp, sRGB decode) and the surface
 * attributes of a hit: interpolated shading normal, texture coordinates, the shadow-
 * terminator offset, normal maps. Only scenes that have vertex attributes or material
 * extras (attrib.h) reach any of this; for the others the material stage skips it. */
#ifndef TR_KERNEL_TEXTURE_H
#define TR_KERNEL_TEXTURE_H

#include "attrib.h"
#include "compat.h"
#include "scene_view.h"
#include "types.h"
#include "vec.h"

/* sRGB transfer function, decoded (IEC 61966-2-1). */
TR_FN float tr_tex_srgb_decode(float c) {
    return c <= 0.04045f ? c * (1.0f / 12.92f) : tr_powf((c + 0.055f) * (1.0f / 1.055f), 2.4f);
}

/* floor for |x| < 2^23 (larger values are integers already). */
TR_FN float tr_floor_small(float x) {
    if (!(tr_fabsf(x) < 8388608.0f)) {
        return x == x ? x : 0.0f;
    }
    float f = (float)(int32_t)x;
    return f > x ? f - 1.0f : f;
}

/* Texel column/row i of a texture n texels wide, wrapped or clamped. */
TR_FN uint32_t tr_texel_index(int32_t i, uint32_t n, int clamp) {
    int32_t m = (int32_t)n;
    if (clamp) {
        return (uint32_t)(i < 0 ? 0 : (i >= m ? m - 1 : i));
    }
    int32_t r = i % m;
    return (uint32_t)(r < 0 ? r + m : r);
}

/* One texel as linear RGB (sRGB-decoded when srgb is set) and alpha (always linear). */
TR_FN tr_vec3 tr_texel(const tr_scene_view *s, TR_CONST_GLOBAL tr_texture *t, uint32_t x,
                       uint32_t y, int srgb, float *alpha) {
    uint32_t p = s->texels[t->offset + y * t->width + x];
    const float k = 1.0f / 255.0f;
    tr_vec3 c =
        v3((float)(p & 255u) * k, (float)((p >> 8) & 255u) * k, (float)((p >> 16) & 255u) * k);
    *alpha = (float)(p >> 24) * k;
    if (srgb) {
        c = v3(tr_tex_srgb_decode(c.x), tr_tex_srgb_decode(c.y), tr_tex_srgb_decode(c.z));
    }
    return c;
}

/* Texture `tex` at (u, v) (0..1 across the image, v downwards from the top row; after the
 * texture's own transform, if it has one), filtered
 * bilinearly between texel centres; colour channels sRGB-decoded before filtering when
 * srgb is set. *alpha receives the filtered alpha. */
TR_FN tr_vec3 tr_texture_sample(const tr_scene_view *s, uint32_t tex, float u, float v, int srgb,
                                float *alpha) {
    TR_CONST_GLOBAL tr_texture *t = &s->textures[tex];
    if ((t->flags & TR_TEXTURE_TRANSFORM) != 0u) {
        float tu = t->xf[0] * u + t->xf[1] * v + t->xf[2];
        v = t->xf[3] * u + t->xf[4] * v + t->xf[5];
        u = tu;
    }
    int clamp = (t->flags & TR_TEXTURE_CLAMP) != 0u;
    /* Repeat: only the fraction matters, and keeping it small keeps the integer
     * conversion below exact. */
    if (!clamp) {
        u -= tr_floor_small(u);
        v -= tr_floor_small(v);
    } else {
        u = tr_fminf(tr_fmaxf(u, 0.0f), 1.0f);
        v = tr_fminf(tr_fmaxf(v, 0.0f), 1.0f);
    }
    float x = u * (float)t->width - 0.5f, y = v * (float)t->height - 0.5f;
    float x0 = tr_floor_small(x), y0 = tr_floor_small(y);
    float fx = x - x0, fy = y - y0;
    int32_t ix = (int32_t)x0, iy = (int32_t)y0;
    uint32_t xa = tr_texel_index(ix, t->width, clamp), xb = tr_texel_index(ix + 1, t->width, clamp);
    uint32_t ya = tr_texel_index(iy, t->height, clamp);
    uint32_t yb = tr_texel_index(iy + 1, t->height, clamp);
    float a00, a10, a01, a11;
    tr_vec3 c00 = tr_texel(s, t, xa, ya, srgb, &a00), c10 = tr_texel(s, t, xb, ya, srgb, &a10);
    tr_vec3 c01 = tr_texel(s, t, xa, yb, srgb, &a01), c11 = tr_texel(s, t, xb, yb, srgb, &a11);
    float w00 = (1.0f - fx) * (1.0f - fy), w10 = fx * (1.0f - fy);
    float w01 = (1.0f - fx) * fy, w11 = fx * fy;
    *alpha = a00 * w00 + a10 * w10 + a01 * w01 + a11 * w11;
    return v3_add(v3_add(v3_scale(c00, w00), v3_scale(c10, w10)),
                  v3_add(v3_scale(c01, w01), v3_scale(c11, w11)));
}

/* What the vertex attributes give a hit on triangle tri at barycentrics (u, v) of its
 * second and third vertex, geometric normal ng. */
typedef struct tr_surface_attr {
    tr_vec3 ns;   /* interpolated shading normal, on ng's side (ng when there is none) */
    tr_vec3 ps;   /* the point rays leave from on ns's side (the terminator fix below) */
    float tu, tv; /* texture coordinates (the barycentrics when there are none) */
    tr_vec3 dpdu; /* position derivatives along the texture coordinates (zero: none) */
    tr_vec3 dpdv;
} tr_surface_attr;

TR_FN tr_surface_attr tr_surface_attributes(const tr_scene_view *s, uint32_t triangle, float u,
                                            float v, tr_vec3 p, tr_vec3 ng) {
    tr_surface_attr a;
    a.ns = ng;
    a.ps = p;
    a.tu = u;
    a.tv = v;
    a.dpdu = v3s(0.0f);
    a.dpdv = v3s(0.0f);
    tr_vertex x0, x1, x2;
    if (!tr_view_vertices(s, triangle, &x0, &x1, &x2)) {
        return a;
    }
    tr_triangle tri_tmp;
    TR_CONST_GLOBAL tr_triangle *tri = tr_view_triangle(s, triangle, &tri_tmp);
    float w = 1.0f - u - v;
    a.tu = x0.u * w + x1.u * u + x2.u * v;
    a.tv = x0.v * w + x1.v * u + x2.v * v;
    /* Tangents from the triangle's edges and their UV differences (as for normal maps
     * everywhere, e.g. Lengyel, "Computing Tangent Space Basis Vectors", 2001). */
    float du1 = x1.u - x0.u, dv1 = x1.v - x0.v, du2 = x2.u - x0.u, dv2 = x2.v - x0.v;
    float det = du1 * dv2 - du2 * dv1;
    if (tr_fabsf(det) > 1e-12f) {
        tr_vec3 e1 = v3_sub(tri->v1, tri->v0), e2 = v3_sub(tri->v2, tri->v0);
        float r = 1.0f / det;
        a.dpdu = v3_scale(v3_sub(v3_scale(e1, dv2), v3_scale(e2, dv1)), r);
        a.dpdv = v3_scale(v3_sub(v3_scale(e2, du1), v3_scale(e1, du2)), r);
    }
    /* Vertex normals oriented to ng's side, so that the geometry's winding keeps saying
     * which side is outside. */
    tr_vec3 n0 = v3_dot(x0.normal, ng) < 0.0f ? v3_neg(x0.normal) : x0.normal;
    tr_vec3 n1 = v3_dot(x1.normal, ng) < 0.0f ? v3_neg(x1.normal) : x1.normal;
    tr_vec3 n2 = v3_dot(x2.normal, ng) < 0.0f ? v3_neg(x2.normal) : x2.normal;
    tr_vec3 n = v3_add(v3_add(v3_scale(n0, w), v3_scale(n1, u)), v3_scale(n2, v));
    float l2 = v3_dot(n, n);
    if (!(l2 > 1e-12f) || !(l2 < TR_INFINITY) || v3_dot(n0, n0) == 0.0f || v3_dot(n1, n1) == 0.0f ||
        v3_dot(n2, n2) == 0.0f) {
        return a;
    }
    a.ns = v3_scale(n, 1.0f / tr_sqrtf(l2));
    /* The shadow terminator: a low-polygon mesh shaded with interpolated normals is lit
     * where its flat triangles are still in their own shadow. Hanika, "Hacking the
     * Shadow Terminator" (Ray Tracing Gems II, 2021, chapter 4): move the point rays
     * leave from onto the curved surface the vertex normals describe - for each vertex,
     * project p onto that vertex's tangent plane when p lies below it, and interpolate
     * the projections with the barycentrics. */
    tr_vec3 d0 = v3_sub(p, tri->v0), d1 = v3_sub(p, tri->v1), d2 = v3_sub(p, tri->v2);
    float h0 = tr_fminf(0.0f, v3_dot(d0, n0)), h1 = tr_fminf(0.0f, v3_dot(d1, n1));
    float h2 = tr_fminf(0.0f, v3_dot(d2, n2));
    a.ps =
        v3_sub(p, v3_add(v3_add(v3_scale(n0, w * h0), v3_scale(n1, u * h1)), v3_scale(n2, v * h2)));
    return a;
}

#endif
