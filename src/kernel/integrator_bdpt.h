/* integrator_bdpt.h - bidirectional path tracing with multiple importance sampling of all
 * strategies (E. Veach, "Robust Monte Carlo Methods for Light Transport Simulation", PhD
 * thesis, Stanford 1997, chapter 10; Veach and Guibas, "Bidirectional Estimators for Light
 * Transport", EGWR 1994, and "Optimally Combining Sampling Techniques", SIGGRAPH 1995).
 *
 * One sample of one pixel traces a camera subpath z_0 (the pinhole) .. z_{t-1} and a light
 * subpath y_0 (a point on an emitter) .. y_{s-1}, and joins every prefix pair (s, t):
 *   s = 0      the camera subpath hits an emitter;
 *   s = 1      next-event estimation: a fresh light point drawn by tr_light_sample (the
 *              solid-angle sampler pt uses) is joined to z_{t-1} with a shadow ray;
 *   t = 1      light tracing: y_{s-1} is joined to the pinhole and its contribution lands in
 *              the pixel it projects to (a splat, see below), weighted by the camera's
 *              importance We = 1 / (A cos^4 theta) times the cosine at the sensor (A: the
 *              image plane's area at distance 1; the pixel sample's jitter draws camera rays
 *              with density 1 / (A cos^3 theta));
 *   otherwise  y_{s-1} and z_{t-1} are joined by a shadow ray.
 * (s, t) = (1, 1) is left out (the camera path's s = 0 sees the emitter itself), as are
 * t = 0 strategies (a pinhole cannot be hit). Connections at delta vertices (mirror, smooth
 * glass) carry nothing and are not tried.
 *
 * MIS: the power heuristic (beta = 2) over every strategy able to make the path. With p_k
 * the density of the path made with k light vertices, p_k / p_{k+1} is the ratio of the
 * densities with which vertex k is drawn from the camera side and from the light side,
 * so all p_k / p_s follow from the vertices' forward and reverse area densities in one
 * pass along the path: the recursive formulation of pbrt-v3's MISWeight (Pharr, Jakob and
 * Humphreys, Physically Based Rendering, 3rd ed., section 16.3.4) and of van Antwerpen's
 * "Improving SIMD Efficiency for Parallel Monte Carlo Light Transport on the GPU" (HPG
 * 2011). Light subpaths start on a point drawn by area (the emitter table's CDF), but the
 * s = 1 strategy draws y_0 by solid angle from y_1; the weight accounts for that by
 * rescaling p_1 by P_nee(y_0 | y_1) / P_area(y_0) (tr_bdpt_mis_weight).
 *
 * Transport mode: light subpaths carry importance. Every BSDF here is symmetric (glass too:
 * neither integrator scales radiance by eta^2), so the adjoint BSDF is the BSDF; shading
 * normals are not, and light-side scattering is multiplied by Veach's correction
 * |wo.ns| |wi.ng| / (|wo.ng| |wi.ns|) (thesis, section 5.3, eq. 5.17).
 *
 * Splatting: light-tracing contributions go to a frame-sized buffer of 64-bit fixed-point
 * sums (2^-24 units), added with atomic integer additions: integer addition is associative,
 * so the sums, and the image, do not depend on the thread count or the tile order. The
 * host folds the buffer into the film after the frame (src/device/cpu.c).
 *
 * Lights at infinity: in a scene with an environment or a sun, light subpaths start from
 * them too, chosen by power beside the emitter table (tr_bdpt_light_probs_of): a direction
 * by the light's own sampler and an origin on a disc that covers the scene's bounding
 * sphere (tr_bdpt_sky_subpath; pbrt-v3's InfiniteAreaLight::Sample_Le). The path's first
 * vertex is then a direction (TR_BDPT_INFINITE), whose densities are solid-angle ones, and
 * the camera side's strategies for these lights, pt's light sample at each vertex (s = 1)
 * and the escape into the sky (s = 0), are weighed with the others by the same MIS
 * (tr_bdpt_sky_camera). Punctual lights join the same choice by power
 * (tr_bdpt_punctual_subpath): a point or spot light's subpath starts at its position
 * (TR_BDPT_PUNCTUAL, delta in position), a directional light's on the disc as the sun's
 * (TR_BDPT_DIRECTIONAL, delta in direction); no strategy hits them, so strategy s = 0 is
 * left out of their paths' MIS sums, and pt's light sample of them is strategy s = 1
 * (tr_bdpt_punctual_camera). A scene without an environment, a sun and punctual lights
 * draws the random numbers it drew before and renders the same bits.
 *
 * Limits: a subpath holds at most TR_BDPT_MAX_VERTS vertices, so the max depth is
 * TR_BDPT_MAX_DEPTH (also the default). On an OpenCL device the 64-bit
 * addition is atom_add (cl_khr_int64_base_atomics), or two 32-bit atomic additions where
 * the device lacks it (tr_bdpt_atomic_add64), and the fold runs there in double precision
 * (cl_khr_fp64, entry.cl), or on the host where the device has no doubles. */
#ifndef TR_KERNEL_INTEGRATOR_BDPT_H
#define TR_KERNEL_INTEGRATOR_BDPT_H

#include "bsdf.h"
#include "camera.h"
#include "compat.h"
#include "film.h"
#include "integrator_pt.h"
#include "kernel.h"
#include "light.h"
#include "material.h"
#include "material_eval.h"
#include "punctual.h"
#include "sampler.h"
#include "sampling.h"
#include "scene_view.h"
#include "types.h"
#include "vec.h"

/* Vertices of one subpath: the camera subpath has the pinhole and up to max_depth hits. */
#define TR_BDPT_MAX_VERTS 16
#define TR_BDPT_MAX_DEPTH (TR_BDPT_MAX_VERTS - 1)

/* Russian roulette (Arvo and Kirk, "Particle Transport and Image Synthesis", SIGGRAPH
 * 1990) decides a subpath's segment seg + 1 from this segment seg on, with pt's rule (the
 * survival probability the square root of the throughput relative to the subpath's first).
 * Camera subpaths start where pt does. Light subpaths start after their second hit: each
 * light vertex costs a light-tracing join and a join with every camera vertex, while the
 * deep ones carry paths that the camera side's strategies (next-event estimation, short
 * light prefixes) sample with nearly all the MIS weight. Measured (docs/integrators.md):
 * from segment 2 instead of 5, 11-13 % fewer instructions per sample for 1-3 % more
 * MSE at equal samples on cornell-mirror and cornell-glass. */
#define TR_BDPT_RR_START_CAMERA TR_PT_RR_START
#define TR_BDPT_RR_START_LIGHT 2

/* Light-tracing splats are sums of value * 2^24, rounded. */
#define TR_BDPT_SPLAT_ONE 16777216.0f
/* A splat beyond this (in radiance units) is dropped rather than allowed to overflow. */
#define TR_BDPT_SPLAT_MAX 1e9f

/* Light subpaths read their own sampler dimensions, after those a camera subpath of
 * TR_BDPT_MAX_DEPTH segments can use: the origin's pair, the emission direction's pair,
 * then TR_SAMPLER_PER_BOUNCE pairs per segment as the camera side. */
#define TR_BDPT_DIM_LIGHT0 (1u + (uint32_t)(TR_BDPT_MAX_DEPTH + 1) * TR_SAMPLER_PER_BOUNCE)
#define TR_BDPT_DIM_LIGHT_ORIGIN TR_BDPT_DIM_LIGHT0
#define TR_BDPT_DIM_LIGHT_DIR (TR_BDPT_DIM_LIGHT0 + 1u)

TR_FN uint32_t tr_bdpt_light_dim(int seg, uint32_t what) {
    return TR_BDPT_DIM_LIGHT0 + 2u + (uint32_t)(seg - 1) * TR_SAMPLER_PER_BOUNCE + what;
}

#define TR_BDPT_CAMERA 0u
#define TR_BDPT_LIGHT 1u /* the origin of a light subpath, or the s = 1 light sample */
#define TR_BDPT_SURFACE 2u
/* A light at infinity (the environment or the sun): a direction, not a point. wo is the
 * unit direction from the scene towards it, tri which of them it is (TR_BDPT_SKY_*), and
 * its "area" densities are solid-angle densities of that direction (pbrt-v3's infinite
 * light vertices). */
#define TR_BDPT_INFINITE 3u
#define TR_BDPT_SKY_ENV 0u
#define TR_BDPT_SKY_SUN 1u
/* A point or spot light (delta in position): p its position, tri its index among the
 * punctual lights, m.ng its axis, cone the cosine that bounds the directions its
 * subpaths take (-1 for a point light) and pdf_pos their solid-angle density inside. */
#define TR_BDPT_PUNCTUAL 4u
/* A directional light (delta in direction): wo the unit direction towards it, tri its
 * index, pdf_pos the density of the disc its subpaths start on (as TR_BDPT_INFINITE). */
#define TR_BDPT_DIRECTIONAL 5u

typedef struct tr_bdpt_vertex {
    tr_bsdf_params m; /* surfaces and light points: the material stage's output */
    tr_vec3 p;
    tr_vec3 beta;  /* the subpath's throughput up to (not including) this vertex's scattering */
    tr_vec3 wo;    /* unit direction to the previous vertex (surfaces) */
    float pdf_fwd; /* area density of this vertex, drawn from its subpath's side */
    float pdf_rev; /* area density of this vertex, drawn from the other side */
    float pdf_nee; /* light vertices: area density of next-event estimation choosing this
                    * point from the next vertex of the path (tr_bdpt_nee_pdf) */
    float pdf_pos; /* TR_BDPT_INFINITE, TR_BDPT_DIRECTIONAL: the density 1 / (pi R^2) of a
                    * subpath's origin on the disc that covers the scene; TR_BDPT_PUNCTUAL:
                    * its directions' density (read for no other kind) */
    float cone;    /* TR_BDPT_PUNCTUAL: the cosine bounding its directions */
    uint32_t tri;
    uint32_t kind; /* TR_BDPT_* */
    int delta;     /* its scattering was a delta lobe */
} tr_bdpt_vertex;

/* Where a camera subpath left the scene: the direction of the ray that found nothing, the
 * throughput it carries, and the solid-angle density with which the last vertex drew that
 * direction (delta: a delta lobe or the pinhole drew it, which no light sample can). */
typedef struct tr_bdpt_escape {
    tr_vec3 dir, beta;
    float pdf;
    int delta, left;
} tr_bdpt_escape;

/* The splats' 64-bit atomic addition: the host's builtin, or OpenCL's atom_add from
 * cl_khr_int64_base_atomics, or on a device without that extension (entry.cl defines
 * TR_BDPT_ATOM64_EMULATED) two of OpenCL's core 32-bit atomic_add on the sum's halves. */
#if (defined(__OPENCL_C_VERSION__) || defined(__OPENCL_VERSION__)) &&                              \
    defined(TR_BDPT_ATOM64_EMULATED)
/* The sum as two 32-bit words, the low one first (the device's own 64-bit integer on a
 * little-endian device, which the host asks for before it uses this: src/device/opencl.c).
 * The low word takes the low half and returns what it held; where that addition wrapped,
 * the high word takes the carry with the high half. Each addition wraps the low word at
 * most once and each wrap is seen by the one work item that made it, so after the kernel
 * the pair holds the exact 64-bit sum, whatever the order, as atom_add leaves it. */
TR_FN void tr_bdpt_atomic_add64(TR_GLOBAL int64_t *p, int64_t v) {
    TR_GLOBAL uint32_t *w = (TR_GLOBAL uint32_t *)p;
    const uint32_t lo = (uint32_t)((uint64_t)v & 0xffffffffu);
    const uint32_t hi = (uint32_t)((uint64_t)v >> 32);
    const uint32_t old = atomic_add(&w[0], lo);
    const uint32_t carry = (uint32_t)(old + lo < old) + hi;
    if (carry != 0u) {
        atomic_add(&w[1], carry);
    }
}
#define TR_BDPT_ATOMIC_ADD(p, v) tr_bdpt_atomic_add64((p), (v))
#elif defined(__OPENCL_C_VERSION__) || defined(__OPENCL_VERSION__)
#define TR_BDPT_ATOMIC_ADD(p, v) atom_add((p), (v))
#else
#define TR_BDPT_ATOMIC_ADD(p, v) __atomic_fetch_add((p), (v), __ATOMIC_RELAXED)
#endif

/* Where light tracing's splats go: 3 fixed-point sums per pixel of the rectangle
 * (x0, y0, w, h); splats outside it are dropped (the host scales what it keeps). */
typedef struct tr_bdpt_splat {
    TR_GLOBAL int64_t *sum;
    uint32_t x0, y0, w, h;
} tr_bdpt_splat;

/* Camera importance towards unit direction w (from the pinhole) times the cosine at the
 * sensor, We cos = 1 / (A cos^3) with We = 1 / (A cos^4) (normalised so that its integral
 * times cos over the image's solid angle is 1), the solid-angle density of the camera's
 * rays *pdf_dir = 1 / (A cos^3) and the raster point (*rx, *ry) w goes through; 0 where w
 * leaves the image. */
TR_FN float tr_bdpt_camera_we(const tr_camera *c, tr_vec3 w, float *rx, float *ry, float *pdf_dir) {
    *pdf_dir = 0.0f;
    float cs = v3_dot(w, c->dir);
    if (!(cs > 0.0f)) {
        return 0.0f;
    }
    float fx = v3_dot(w, c->right) / cs / c->canvas_width + 0.5f;
    float fy = 0.5f - v3_dot(w, c->up) / cs / c->canvas_height;
    if (!(fx >= 0.0f && fx < 1.0f && fy >= 0.0f && fy < 1.0f)) {
        return 0.0f;
    }
    *rx = fx * (float)c->screen_width;
    *ry = fy * (float)c->screen_height;
    float a = c->canvas_width * c->canvas_height;
    float c3 = cs * cs * cs;
    *pdf_dir = 1.0f / (a * c3);
    return *pdf_dir;
}

/* Light subpaths from the environment and the sun (pbrt-v3's InfiniteAreaLight::Sample_Le,
 * Pharr, Jakob and Humphreys, 3rd ed., 16.1.2 and 16.3): a direction by the light's own
 * sampler (the sun's cone, the environment map's CDF, the constant environment uniformly),
 * then an origin uniform on the disc of radius R perpendicular to it whose centre lies R
 * from the centre of the scene's bounding sphere towards the light (area density
 * 1 / (pi R^2)); the ray runs parallel to the direction, through the sphere. A subpath's
 * light is chosen by power among the emitter table (its total weight, power / pi) and
 * these lights, whose weight is the power they send through the disc over pi: R^2 times
 * their radiance integrated over directions (RGB means). */
typedef struct tr_bdpt_light_probs {
    float emitters, env, sun, punct;
} tr_bdpt_light_probs;

/* The radiance of the environment or the sun integrated over directions (RGB mean). */
TR_FN float tr_bdpt_sky_integral(const tr_scene_view *s, uint32_t which) {
    if (which == TR_BDPT_SKY_SUN) {
        TR_CONST_GLOBAL tr_sun *sun = &s->sun[0];
        const float l = (sun->radiance.x + sun->radiance.y + sun->radiance.z) * (1.0f / 3.0f);
        return l * TR_TWO_PI * sun->one_minus_cos;
    }
    TR_CONST_GLOBAL tr_env *e = &s->env[0];
    const float c = (e->color.x + e->color.y + e->color.z) * (1.0f / 3.0f) * e->strength;
    if (e->width == 0u) {
        return c * 4.0f * TR_PI;
    }
    /* The map's texels are weighted by luminance x sin t (envmap.h): their sum times the
     * texels' extent in (t, p) approximates the integral. */
    return c * e->weight_sum * (2.0f * TR_PI * TR_PI) / ((float)e->width * (float)e->height);
}

/* The probabilities of a light subpath's origin; returns whether the environment, the
 * sun or the punctual lights can start one (else the emitters' probability is 1 and the
 * others are added along the camera subpath only, tr_bdpt_infinite). The punctual lights
 * weigh their power over pi (src/scene/punctual.c: 4 pi I for a point, the cone's for a
 * spot, pi R^2 E for a directional light) and are picked among by its CDF. */
TR_FN int tr_bdpt_light_probs_of(const tr_scene_view *s, tr_bdpt_light_probs *lp) {
    lp->emitters = 1.0f;
    lp->env = 0.0f;
    lp->sun = 0.0f;
    lp->punct = 0.0f;
    if (s->env_count + s->sun_count + s->punctual_count == 0u || !(s->sky_radius > 0.0f)) {
        return 0;
    }
    float wp = 0.0f;
    for (uint32_t i = 0; i < s->punctual_count; ++i) {
        wp += tr_fmaxf(s->punctual[i].power, 0.0f) * TR_INV_PI;
    }
    const float r2 = s->sky_radius * s->sky_radius;
    const float we =
        s->env_count > 0u ? tr_fmaxf(r2 * tr_bdpt_sky_integral(s, TR_BDPT_SKY_ENV), 0.0f) : 0.0f;
    const float ws =
        s->sun_count > 0u ? tr_fmaxf(r2 * tr_bdpt_sky_integral(s, TR_BDPT_SKY_SUN), 0.0f) : 0.0f;
    const float wl = s->light_count > 0u ? tr_fmaxf(s->light_weight_total, 0.0f) : 0.0f;
    const float total = we + ws + wl + wp;
    if (!(we + ws + wp > 0.0f) || !(total < TR_INFINITY)) {
        return 0;
    }
    lp->emitters = wl / total;
    lp->env = we / total;
    lp->sun = ws / total;
    lp->punct = wp / total;
    return 1;
}

/* Whether light subpaths start from the environment and the sun. */
TR_FN int tr_bdpt_sky_on(const tr_scene_view *s) {
    tr_bdpt_light_probs lp;
    return tr_bdpt_light_probs_of(s, &lp) && lp.env + lp.sun > 0.0f;
}

/* Whether light subpaths start from the punctual lights. */
TR_FN int tr_bdpt_punctual_on(const tr_scene_view *s) {
    tr_bdpt_light_probs lp;
    return tr_bdpt_light_probs_of(s, &lp) && lp.punct > 0.0f;
}

/* Whether a light subpath may start outside the scene (the environment, the sun or a
 * directional light): vcm then merges only on surfaces that face alike (tr_vcm_facing). */
TR_FN int tr_bdpt_outside_on(const tr_scene_view *s) {
    if (tr_bdpt_sky_on(s)) {
        return 1;
    }
    if (!tr_bdpt_punctual_on(s)) {
        return 0;
    }
    for (uint32_t i = 0; i < s->punctual_count; ++i) {
        if (s->punctual[i].type == TR_PUNCTUAL_DIRECTIONAL) {
            return 1;
        }
    }
    return 0;
}

/* Whether vertex v is a light at infinity: a direction, not a point. */
TR_FN int tr_bdpt_far(const tr_bdpt_vertex *v) {
    return v->kind == TR_BDPT_INFINITE || v->kind == TR_BDPT_DIRECTIONAL;
}

/* Whether vertex v is a delta light (no strategy can hit it). */
TR_FN int tr_bdpt_delta_light(const tr_bdpt_vertex *v) {
    return v->kind == TR_BDPT_PUNCTUAL || v->kind == TR_BDPT_DIRECTIONAL;
}

/* The probability of the punctual lights' CDF picking light k. */
TR_FN float tr_bdpt_punctual_prob(const tr_scene_view *s, uint32_t k) {
    return s->punctual[k].cdf - (k > 0u ? s->punctual[k - 1u].cdf : 0.0f);
}

/* The probability with which pt's light sample (tr_punctual_nee) takes light k: 1 where
 * it takes every light, else the CDF's. */
TR_FN float tr_bdpt_punctual_sel(const tr_scene_view *s, uint32_t k) {
    return s->punctual_count <= TR_PUNCTUAL_ALL ? 1.0f : tr_bdpt_punctual_prob(s, k);
}

/* The solid-angle density of light `which` (TR_BDPT_SKY_*) drawing the unit direction w
 * towards it, and its radiance from there. */
TR_FN float tr_bdpt_sky_pdf(const tr_scene_view *s, uint32_t which, tr_vec3 w) {
    return which == TR_BDPT_SKY_SUN ? tr_sun_pdf(s, w) : tr_env_pdf(s, w);
}
TR_FN tr_vec3 tr_bdpt_sky_radiance(const tr_scene_view *s, uint32_t which, tr_vec3 w) {
    return which == TR_BDPT_SKY_SUN ? tr_sun_radiance(s, w) : tr_env_radiance(s, w);
}

/* The density 1 / (pi R^2) of a point on the disc light subpaths from infinity start on. */
TR_FN float tr_bdpt_disc_pdf(const tr_scene_view *s) {
    return 1.0f / (TR_PI * s->sky_radius * s->sky_radius);
}

/* Solid-angle density of an emitter at y (cosine-weighted about its normal on the side
 * chosen, each side with probability 1/2 when two-sided) emitting towards unit w. */
TR_FN float tr_bdpt_emit_pdf(const tr_bdpt_vertex *y, tr_vec3 w) {
    float c = v3_dot(w, y->m.ng);
    if ((y->m.flags & TR_MATERIAL_TWO_SIDED) != 0u) {
        return tr_fabsf(c) * (0.5f * TR_INV_PI);
    }
    return c > 0.0f ? c * TR_INV_PI : 0.0f;
}

/* Area density of choosing y as a light subpath's origin: 0 for surfaces that emit but are
 * not in the emitter table (glTF emission). */
TR_FN float tr_bdpt_origin_pdf(const tr_scene_view *s, const tr_bdpt_vertex *y) {
    tr_bdpt_light_probs lp;
    const int sky = tr_bdpt_light_probs_of(s, &lp);
    if (tr_bdpt_delta_light(y)) {
        return lp.punct * tr_bdpt_punctual_prob(s, y->tri); /* times a delta */
    }
    if (y->kind == TR_BDPT_INFINITE) {
        return y->tri == TR_BDPT_SKY_SUN ? lp.sun * tr_sun_pdf(s, y->wo)
                                         : lp.env * tr_env_pdf(s, y->wo);
    }
    tr_triangle tri_tmp;
    TR_CONST_GLOBAL tr_triangle *tri = tr_view_triangle(s, y->tri, &tri_tmp);
    tr_material m = s->materials[tri->material];
    const float pdf = tr_light_pdf_area(s, &m, tri->area);
    return sky ? pdf * lp.emitters : pdf;
}

/* Solid-angle density at `next` converted to area density there. */
TR_FN float tr_bdpt_to_area(float pdf_dir, tr_vec3 from, const tr_bdpt_vertex *next) {
    tr_vec3 d = v3_sub(next->p, from);
    float d2 = v3_dot(d, d);
    if (!(d2 > 0.0f)) {
        return 0.0f;
    }
    if (next->kind == TR_BDPT_CAMERA) {
        return pdf_dir / d2;
    }
    return pdf_dir * tr_fabsf(v3_dot(d, next->m.ng)) / (d2 * tr_sqrtf(d2));
}

/* Area density with which vertex `cur` draws `next`, given the unit direction w from cur
 * to next, their squared distance d2 and, for a surface reached from a previous vertex
 * (has_prev), the unit direction wp from cur to it. The connections know these
 * directions already: tr_bdpt_mis_weight passes them instead of normalising again. */
TR_FN float tr_bdpt_pdf_dir(const tr_camera *cam, const tr_bdpt_vertex *cur, int has_prev,
                            tr_vec3 wp, tr_vec3 w, float d2, const tr_bdpt_vertex *next) {
    if (!(d2 > 0.0f)) {
        return 0.0f;
    }
    if (tr_bdpt_delta_light(next)) {
        return 0.0f; /* no strategy hits a delta light */
    }
    if (tr_bdpt_far(cur)) {
        /* Parallel rays from the disc: the area density at next is the disc's times the
         * cosine there (w is -cur->wo, d2 is 1); the pinhole is never hit. */
        return next->kind == TR_BDPT_CAMERA ? 0.0f : cur->pdf_pos * tr_fabsf(v3_dot(w, next->m.ng));
    }
    float pdf;
    if (cur->kind == TR_BDPT_CAMERA) {
        float rx, ry;
        tr_bdpt_camera_we(cam, w, &rx, &ry, &pdf);
    } else if (cur->kind == TR_BDPT_PUNCTUAL) {
        pdf = v3_dot(w, cur->m.ng) >= cur->cone ? cur->pdf_pos : 0.0f;
    } else if (cur->kind == TR_BDPT_LIGHT || !has_prev) {
        pdf = tr_bdpt_emit_pdf(cur, w);
    } else {
        pdf = tr_bsdf_pdf(&cur->m, wp, w);
    }
    if (next->kind == TR_BDPT_INFINITE) {
        return pdf; /* a direction: its density is the solid-angle one */
    }
    if (next->kind == TR_BDPT_CAMERA) {
        return pdf / d2;
    }
    return pdf * tr_fabsf(v3_dot(w, next->m.ng)) / d2;
}

/* The unit direction from a to b and the squared distance (0 and a zero vector where the
 * points coincide). */
TR_FN tr_vec3 tr_bdpt_dir(tr_vec3 a, tr_vec3 b, float *d2) {
    tr_vec3 d = v3_sub(b, a);
    *d2 = v3_dot(d, d);
    return *d2 > 0.0f ? v3_scale(d, 1.0f / tr_sqrtf(*d2)) : v3s(0.0f);
}

/* tr_bdpt_dir between vertices: towards a light at infinity (or away from one) its
 * direction, with a squared distance of 1 (the densities tr_bdpt_pdf_dir gives there are
 * not converted by distance). */
TR_FN tr_vec3 tr_bdpt_vdir(const tr_bdpt_vertex *a, const tr_bdpt_vertex *b, float *d2) {
    if (tr_bdpt_far(b)) {
        *d2 = 1.0f;
        return b->wo;
    }
    if (tr_bdpt_far(a)) {
        *d2 = 1.0f;
        return v3_neg(a->wo);
    }
    return tr_bdpt_dir(a->p, b->p, d2);
}

/* Area density with which vertex `cur`, reached from `prev` (null for the pinhole and
 * light origins), draws `next`. */
TR_FN float tr_bdpt_pdf(const tr_camera *cam, const tr_bdpt_vertex *cur, const tr_bdpt_vertex *prev,
                        const tr_bdpt_vertex *next) {
    float d2, dp2 = 0.0f;
    tr_vec3 w = tr_bdpt_vdir(cur, next, &d2);
    tr_vec3 wp = prev ? tr_bdpt_vdir(cur, prev, &dp2) : v3s(0.0f);
    return tr_bdpt_pdf_dir(cam, cur, prev != 0, wp, w, d2, next);
}

/* Veach's shading-normal correction for importance carried from wo to wi (thesis eq. 5.17);
 * 0 where a geometric cosine vanishes. */
TR_FN float tr_bdpt_shading_fix(const tr_bsdf_params *m, tr_vec3 wo, tr_vec3 wi) {
    float num = tr_fabsf(v3_dot(wo, m->ns)) * tr_fabsf(v3_dot(wi, m->ng));
    float den = tr_fabsf(v3_dot(wo, m->ng)) * tr_fabsf(v3_dot(wi, m->ns));
    return den > 0.0f ? num / den : 0.0f;
}

/* Area density with which next-event estimation (tr_light_sample) at vertex x picks the
 * point of light vertex y. */
TR_FN float tr_bdpt_nee_pdf(const tr_scene_view *s, const tr_bdpt_vertex *y,
                            const tr_bdpt_vertex *x) {
    if (tr_bdpt_delta_light(y)) {
        return tr_bdpt_punctual_sel(s, y->tri); /* times the delta light subpaths share */
    }
    if (y->kind == TR_BDPT_INFINITE) {
        return tr_bdpt_sky_pdf(s, y->tri, y->wo); /* pt's light sample of it, from anywhere */
    }
    tr_vec3 d = v3_sub(y->p, x->p);
    float d2 = v3_dot(d, d);
    if (!(d2 > 0.0f)) {
        return 0.0f;
    }
    float sa = tr_light_pdf(s, x->p, y->tri, y->p);
    return sa * tr_fabsf(v3_dot(d, y->m.ng)) / (d2 * tr_sqrtf(d2));
}

TR_FN float tr_bdpt_remap0(float x) {
    return x != 0.0f ? x : 1.0f;
}

/* The power-heuristic weight of strategy (s, t) for the path made of lv[0..s-1] and
 * cv[t-1..0] (with `nee` standing for lv[0] when s = 1). The path's vertices are indexed
 * from the light end, 0 .. n-1 with n = s + t; for each, pl and pc are its area densities
 * drawn from the light side and from the camera side. Most are stored by the random walks;
 * the ones next to the connection change with it and are computed here. */
/*
 * Vertex merging (integrator_vcm.h) adds a strategy at the camera subpath's first
 * non-delta vertex v (1 <= v <= n - 2): the light subpath's vertex v is drawn from the
 * light side, the camera subpath's from the camera side, and the two are merged when they
 * lie within the radius r of each other, out of the light subpaths of all N pixels. Its density is
 * p_{v+1} * pc[v] * eta with eta = N pi r^2 (Georgiev, Krivanek, Davidovic and Slusallek,
 * "Light Transport Simulation with Vertex Connection and Merging", SIGGRAPH Asia 2012,
 * section 4.2: n_VM pi r^2 / n_VC with one connection per camera subpath). With eta > 0
 * those strategies join every sum. merge: the strategy weighed is the merge at vertex ns,
 * with cv[nt-1] standing for the merged vertex and lv[ns-1] the light vertex before it
 * (which may be a delta vertex: the merge does not connect there); eta 0 gives BDPT's
 * weights exactly. */
TR_FN float tr_bdpt_mis_weight_vm(const tr_scene_view *s, const tr_camera *cam,
                                  const tr_bdpt_vertex *lv, int ns, const tr_bdpt_vertex *nee,
                                  const tr_bdpt_vertex *cv, int nt, float eta, int merge) {
    const int n = ns + nt;
    if (n == 2) {
        return 1.0f; /* only (0, 2): (1, 1) is not used; no vertex to merge at */
    }
    if (merge && (ns < 1 || nt < 2 || !(eta > 0.0f))) {
        return 0.0f;
    }
    float pl[2 * TR_BDPT_MAX_VERTS], pc[2 * TR_BDPT_MAX_VERTS], r[2 * TR_BDPT_MAX_VERTS];
    int dl[2 * TR_BDPT_MAX_VERTS];
    if (nt < 1 || ns < 0 || n > 2 * TR_BDPT_MAX_VERTS) {
        return 0.0f;
    }
    /* The path's vertices are read where they lie (no array of pointers to fill). */
    const tr_bdpt_vertex *y0 = ns == 1 && nee ? nee : (ns >= 1 ? &lv[0] : &cv[n - 1]);
    for (int i = 0; i < ns; ++i) {
        const tr_bdpt_vertex *vi = i == 0 ? y0 : &lv[i];
        pl[i] = vi->pdf_fwd;
        pc[i] = vi->pdf_rev;
        dl[i] = vi->delta;
    }
    for (int i = ns; i < n; ++i) {
        const tr_bdpt_vertex *vi = &cv[n - 1 - i];
        pc[i] = vi->pdf_fwd;
        pl[i] = vi->pdf_rev;
        dl[i] = vi->delta;
    }
    /* The densities the connection changes. */
    const tr_bdpt_vertex *pt = &cv[nt - 1];
    const tr_bdpt_vertex *pt_prev = nt >= 2 ? &cv[nt - 2] : 0;
    dl[ns] = 0;
    if (ns > 0) {
        const tr_bdpt_vertex *qs = ns == 1 ? y0 : &lv[ns - 1];
        const tr_bdpt_vertex *qs_prev = ns >= 2 ? (ns == 2 ? y0 : &lv[ns - 2]) : 0;
        /* A merge reaches pt from qs by qs's own scattering, delta or not. */
        const int qs_delta = merge && qs->delta;
        dl[ns - 1] = qs_delta;
        /* Three directions serve the four densities: the connection's (qs to pt) and
         * those from each end to its own subpath's previous vertex. */
        float de2, da2 = 0.0f, db2 = 0.0f;
        const tr_vec3 w = tr_bdpt_vdir(qs, pt, &de2);
        const tr_vec3 wa = qs_prev ? tr_bdpt_vdir(qs, qs_prev, &da2) : v3s(0.0f);
        const tr_vec3 wb = pt_prev ? tr_bdpt_vdir(pt, pt_prev, &db2) : v3s(0.0f);
        pc[ns - 1] = tr_bdpt_pdf_dir(cam, pt, pt_prev != 0, wb, v3_neg(w), de2, qs);
        if (qs_prev) {
            pc[ns - 2] = qs_delta ? 0.0f : tr_bdpt_pdf_dir(cam, qs, 1, w, wa, da2, qs_prev);
        }
        pl[ns] = qs_delta ? 0.0f : tr_bdpt_pdf_dir(cam, qs, qs_prev != 0, wa, w, de2, pt);
        if (pt_prev) {
            pl[ns + 1] = tr_bdpt_pdf_dir(cam, pt, 1, v3_neg(w), wb, db2, pt_prev);
        }
    } else {
        pl[0] = tr_bdpt_origin_pdf(s, pt);
        if (pt_prev && pt->kind == TR_BDPT_INFINITE) {
            pl[1] = tr_bdpt_pdf(cam, pt, 0, pt_prev); /* the disc's density, projected */
        } else if (pt_prev) {
            pl[1] = tr_bdpt_to_area(tr_bdpt_emit_pdf(pt, v3_normalize(v3_sub(pt_prev->p, pt->p))),
                                    pt->p, pt_prev);
        }
    }
    /* r[k] = p_k / p_s. */
    r[ns] = 1.0f;
    for (int k = ns - 1; k >= 0; --k) {
        float q = tr_bdpt_remap0(pc[k]) / tr_bdpt_remap0(pl[k]);
        r[k] = r[k + 1] * q;
    }
    for (int k = ns + 1; k < n; ++k) {
        float q = tr_bdpt_remap0(pl[k - 1]) / tr_bdpt_remap0(pc[k - 1]);
        r[k] = r[k - 1] * q;
    }
    /* Strategy 1 draws y_0 by solid angle from y_1, not by area: p_1 scales by c. The
     * density is the light vertex's own (computed once per subpath or sample) except for
     * s = 0, where y_0 is a camera vertex. */
    const int light_ok = pl[0] > 0.0f; /* y_0 is a point light subpaths can start on */
    /* A delta light: strategy 0 (the camera subpath hitting it) cannot make the path. */
    const int delta_light = ns >= 1 && tr_bdpt_delta_light(y0);
    float c = 0.0f;
    if (light_ok && !dl[1]) {
        /* Vertex 1 of the path: a light vertex, or for s = 0 and s = 1 a camera one. */
        const tr_bdpt_vertex *y1 = ns >= 2 ? &lv[1] : &cv[n - 2];
        /* A merge at vertex 1 puts y_1 where the camera vertex is, not the light's. */
        float nee_area = ns >= 1 && !(merge && ns == 1) ? y0->pdf_nee : tr_bdpt_nee_pdf(s, y0, y1);
        c = nee_area / pl[0];
    }
    if (ns == 1 && !merge) {
        if (!(c > 0.0f)) {
            return 0.0f;
        }
        for (int k = 0; k < n; ++k) {
            r[k] = k == 1 ? 1.0f : r[k] / c;
        }
    } else {
        r[1] *= c;
    }
    float sum = 0.0f;
    for (int k = 0; k < n; ++k) {
        int ok = (k == 0 || !dl[k - 1]) && !dl[k];
        ok = ok && (k == 0 || light_ok) && !(k == 1 && n == 2) && !(k == 0 && delta_light);
        if (ok || (k == ns && !merge)) {
            sum += r[k] * r[k];
        }
    }
    float own = merge ? 0.0f : 1.0f;
    if (eta > 0.0f && light_ok) {
        /* Merges happen only at the camera subpath's first non-delta vertex
         * (integrator_vcm.h): going back from the camera, the vertices n-2 .. v+1 are
         * delta and v is not. */
        int v = n - 2;
        while (v >= 1 && dl[v]) {
            --v;
        }
        if (v >= 1) {
            const float m = r[v + 1] * tr_bdpt_remap0(pc[v]) * eta;
            sum += m * m;
            own = merge && v == ns ? m * m : own;
        }
    }
    return sum > 0.0f ? own / sum : 0.0f;
}

/* The power-heuristic weight of connection strategy (s, t) among BDPT's strategies. */
TR_FN float tr_bdpt_mis_weight(const tr_scene_view *s, const tr_camera *cam,
                               const tr_bdpt_vertex *lv, int ns, const tr_bdpt_vertex *nee,
                               const tr_bdpt_vertex *cv, int nt) {
    return tr_bdpt_mis_weight_vm(s, cam, lv, ns, nee, cv, nt, 0.0f, 0);
}

/* Extends a subpath whose last vertex is v[0 .. *count-1] along `ray` with throughput
 * beta and the last vertex's solid-angle density pdf_dir for ray's direction, up to
 * max_verts vertices. importance: a light subpath (shading-normal correction, its own
 * sampler dimensions). `surface` (camera subpaths, may be null) gets the passes' surface. */
TR_FN void tr_bdpt_walk(const tr_scene_view *s, tr_ray ray, tr_vec3 beta, float pdf_dir,
                        tr_bdpt_vertex *v, int *count, int max_verts, int importance,
                        const tr_sampler *smp, uint32_t *rays, tr_sample *surface,
                        tr_bdpt_escape *esc) {
    int n = *count;
    int holes = 0;
    float rr_ref = v3_max_component(beta); /* roulette is played on beta relative to this */
    float last_pdf = pdf_dir;
    int last_delta = 1; /* the first ray: the pinhole's, or the light's emission */
    for (int seg = 1; n < max_verts; ++seg) {
        tr_hit hit;
        *rays += 1;
        if (!tr_intersect_scene(s, &ray, &hit)) {
            if (esc) {
                esc->dir = ray.dir;
                esc->beta = beta;
                esc->pdf = last_pdf;
                esc->delta = last_delta;
                esc->left = 1;
            }
            break;
        }
        tr_triangle tri_tmp;
        TR_CONST_GLOBAL tr_triangle *tri = tr_view_triangle(s, hit.triangle, &tri_tmp);
        tr_vec3 p = v3_madd(ray.origin, ray.dir, hit.t);
        tr_bsdf_params m = tr_material_eval(s, hit.triangle, hit.u, hit.v, p, tri->normal, ray.dir);
        if (m.hole && holes < TR_MAX_HOLES) {
            ++holes;
            --seg;
            ray.tmin = hit.t + 1e-5f * tr_fmaxf(1.0f, hit.t);
            continue;
        }
        if (surface) {
            tr_sample_surface(surface, &m, ray.dir, hit.t, hit.triangle);
        }
        tr_bdpt_vertex *cur = &v[n];
        tr_bdpt_vertex *prev = &v[n - 1];
        cur->m = m;
        cur->p = p;
        cur->beta = beta;
        cur->wo = v3_neg(ray.dir);
        cur->tri = hit.triangle;
        cur->kind = TR_BDPT_SURFACE;
        cur->delta = 0;
        cur->pdf_rev = 0.0f;
        cur->pdf_nee = 0.0f;
        if (prev->kind == TR_BDPT_SURFACE && n >= 2) {
            /* Both densities through prev from the vertices' positions, as the connections
             * evaluate them (not from the offset ray origin), so that every strategy of a
             * path computes the same densities. */
            tr_bdpt_vertex *pp = &v[n - 2];
            cur->pdf_fwd = prev->delta ? 0.0f : tr_bdpt_pdf(0, prev, pp, cur);
            pp->pdf_rev = prev->delta ? 0.0f : tr_bdpt_pdf(0, prev, cur, pp);
        } else if (prev->kind != TR_BDPT_CAMERA) {
            cur->pdf_fwd = tr_bdpt_pdf(0, prev, 0, cur);
        } else {
            cur->pdf_fwd = tr_bdpt_to_area(pdf_dir, prev->p, cur);
        }
        ++n;
        if (n >= max_verts) {
            break;
        }
        tr_scatter bs;
        float b1, b2, blobe = 0.0f;
        uint32_t dd = importance ? tr_bdpt_light_dim(seg, TR_DIM_BSDF_DIR)
                                 : tr_sampler_dim(seg, TR_DIM_BSDF_DIR);
        /* As in pt: only glass and the principled material choose a lobe, so the others
         * leave the dimension unread instead of hashing it at every vertex. */
        if (m.type == TR_MATERIAL_GLASS || m.type == TR_MATERIAL_PRINCIPLED) {
            blobe = tr_sampler_1d(smp, importance ? tr_bdpt_light_dim(seg, TR_DIM_BSDF_LOBE)
                                                  : tr_sampler_dim(seg, TR_DIM_BSDF_LOBE));
        }
        tr_sampler_2d(smp, dd, &b1, &b2);
        if (!tr_bsdf_sample(&m, cur->wo, blobe, b1, b2, &bs)) {
            break;
        }
        tr_vec3 weight = bs.weight;
        if (importance) {
            weight = v3_scale(weight, tr_bdpt_shading_fix(&m, cur->wo, bs.wi));
        }
        cur->delta = bs.delta;
        last_pdf = bs.pdf;
        last_delta = bs.delta;
        beta = v3_mul(beta, weight);
        if (tr_v3_is_zero(beta)) {
            break;
        }
        if (seg >= (importance ? TR_BDPT_RR_START_LIGHT : TR_BDPT_RR_START_CAMERA) &&
            rr_ref > 0.0f) {
            float q = tr_sqrtf(v3_max_component(beta) / rr_ref);
            if (q < 1.0f) {
                uint32_t dr = importance ? tr_bdpt_light_dim(seg, TR_DIM_ROULETTE)
                                         : tr_sampler_dim(seg, TR_DIM_ROULETTE);
                if (!(tr_sampler_1d(smp, dr) < q)) {
                    break;
                }
                beta = v3_scale(beta, 1.0f / q);
            }
        }
        ray = tr_ray_make(tr_surface_origin(&m, p, bs.wi), bs.wi, 0.0f, TR_INFINITY);
    }
    *count = n;
}

/* Adds c (a light-tracing contribution) to the splat buffer at raster point (rx, ry). */
TR_FN void tr_bdpt_splat_add(const tr_bdpt_splat *sp, float rx, float ry, tr_vec3 c) {
    uint32_t x = (uint32_t)rx, y = (uint32_t)ry;
    if (x < sp->x0 || y < sp->y0 || x >= sp->x0 + sp->w || y >= sp->y0 + sp->h) {
        return;
    }
    float m = v3_max_component(c);
    if (!(m > 0.0f) || !(m < TR_BDPT_SPLAT_MAX) || !(c.x >= 0.0f && c.y >= 0.0f && c.z >= 0.0f)) {
        return; /* nothing, or NaN, or beyond the fixed-point range */
    }
    size_t i = 3u * ((size_t)(y - sp->y0) * sp->w + (x - sp->x0));
    int64_t q0 = (int64_t)(c.x * TR_BDPT_SPLAT_ONE + 0.5f);
    int64_t q1 = (int64_t)(c.y * TR_BDPT_SPLAT_ONE + 0.5f);
    int64_t q2 = (int64_t)(c.z * TR_BDPT_SPLAT_ONE + 0.5f);
    TR_BDPT_ATOMIC_ADD(&sp->sum[i], q0);
    TR_BDPT_ATOMIC_ADD(&sp->sum[i + 1], q1);
    TR_BDPT_ATOMIC_ADD(&sp->sum[i + 2], q2);
}

/* Selects strategies for tests: with only_t > 0 only (only_s, only_t) contributes, with
 * weight 1 (the unweighted estimator of that strategy); otherwise every strategy, with
 * its MIS weight. */
typedef struct tr_bdpt_select {
    int only_s, only_t;
} tr_bdpt_select;

/* The camera subpath of the ray through raster point (x + jx, y + jy), (jx, jy) from the
 * sampler: cv[0] the pinhole, then up to max_depth hits. Returns the vertex count; *esc
 * says whether and how it left the scene. */
TR_FN int tr_bdpt_camera_subpath(const tr_scene_view *s, const tr_camera *cam, float x, float y,
                                 int max_depth, const tr_sampler *smp, tr_bdpt_vertex *cv,
                                 uint32_t *rays, tr_sample *surface, tr_bdpt_escape *esc) {
    esc->left = 0;
    float jx, jy;
    tr_sampler_2d(smp, TR_DIM_CAMERA, &jx, &jy);
    tr_ray ray = tr_camera_ray(cam, x, y, jx, jy);
    cv[0].p = cam->pos;
    cv[0].beta = v3s(1.0f);
    cv[0].wo = v3s(0.0f);
    cv[0].kind = TR_BDPT_CAMERA;
    cv[0].delta = 0;
    cv[0].tri = 0u;
    cv[0].pdf_fwd = 1.0f;
    cv[0].pdf_rev = 0.0f;
    cv[0].pdf_nee = 0.0f;
    /* cv[0].m is never read: the pinhole has no surface. */
    float rx, ry, cam_pdf;
    tr_bdpt_camera_we(cam, ray.dir, &rx, &ry, &cam_pdf);
    int nc = 1;
    tr_bdpt_walk(s, ray, v3s(1.0f), cam_pdf, cv, &nc, max_depth + 1, 0, smp, rays, surface, esc);
    return nc;
}

/* A light subpath from the environment or the sun (light chosen by u1 of the origin pair,
 * below lp->env + lp->sun): a direction by the light's sampler, an origin on the disc
 * that covers the scene (see tr_bdpt_light_probs), then up to max_depth - 1 hits. lv[0]
 * is the light's TR_BDPT_INFINITE vertex; returns the vertex count (0 where the light
 * draws no direction). */
TR_FN int tr_bdpt_sky_subpath(const tr_scene_view *s, int max_depth, const tr_sampler *smp,
                              const tr_bdpt_light_probs *lp, tr_bdpt_vertex *lv, uint32_t *rays) {
    float u1, u2, d1, d2;
    tr_sampler_2d(smp, TR_BDPT_DIM_LIGHT_ORIGIN, &u1, &u2);
    tr_sampler_2d(smp, TR_BDPT_DIM_LIGHT_DIR, &d1, &d2);
    const uint32_t which = u1 < lp->sun ? TR_BDPT_SKY_SUN : TR_BDPT_SKY_ENV;
    const float lo = which == TR_BDPT_SKY_SUN ? 0.0f : lp->sun;
    const float share = which == TR_BDPT_SKY_SUN ? lp->sun : lp->env;
    if (!(share > 0.0f)) {
        return 0;
    }
    u1 = tr_fminf(tr_fmaxf((u1 - lo) / share, 0.0f), 0.99999994f);
    tr_vec3 wl;
    float pdf_dir;
    const tr_vec3 le = which == TR_BDPT_SKY_SUN ? tr_sun_sample(s, d1, d2, &wl, &pdf_dir)
                                                : tr_env_sample(s, d1, d2, &wl, &pdf_dir);
    if (!(pdf_dir > 0.0f) || tr_v3_is_zero(le)) {
        return 0;
    }
    /* The origin: uniform on the disc (pbrt 3rd ed. 13.6.2's polar mapping). */
    const float R = s->sky_radius;
    tr_vec3 ta, tb;
    v3_basis(wl, &ta, &tb);
    const float rr = R * tr_sqrtf(u1), phi = TR_TWO_PI * u2;
    const tr_vec3 centre = v3(s->sky_cx, s->sky_cy, s->sky_cz);
    const tr_vec3 o = v3_add(v3_madd(centre, wl, R), v3_add(v3_scale(ta, rr * tr_cosf(phi)),
                                                            v3_scale(tb, rr * tr_sinf(phi))));
    tr_bdpt_vertex *y0 = &lv[0];
    y0->p = o;
    y0->wo = wl;
    y0->tri = which;
    y0->kind = TR_BDPT_INFINITE;
    y0->delta = 0;
    y0->pdf_pos = tr_bdpt_disc_pdf(s);
    y0->pdf_fwd = share * pdf_dir;
    y0->pdf_rev = 0.0f;
    y0->pdf_nee = pdf_dir;
    y0->beta = v3_scale(le, 1.0f / y0->pdf_fwd);
    y0->m.ng = wl; /* no surface: read by nothing, set for tidiness */
    y0->m.ns = wl;
    int nl = 1;
    /* Le cos / (p_light p_dir p_disc), with cos = 1 on the disc. */
    const tr_vec3 beta = v3_scale(le, 1.0f / (y0->pdf_fwd * y0->pdf_pos));
    tr_ray lr = tr_ray_make(o, v3_neg(wl), 0.0f, TR_INFINITY);
    tr_bdpt_walk(s, lr, beta, pdf_dir, lv, &nl, max_depth, 1, smp, rays, 0, 0);
    return nl;
}

/* The punctual light subpath's vertex y_0 for light k, picked with probability
 * lp->punct * prob (see tr_bdpt_vertex's kinds); p: a subpath's origin on the scene's disc
 * (directional lights; the light's position otherwise). */
TR_FN void tr_bdpt_punctual_vertex(const tr_scene_view *s, uint32_t k, float pick, tr_vec3 p,
                                   tr_bdpt_vertex *y) {
    TR_CONST_GLOBAL tr_punctual *l = &s->punctual[k];
    const int dir = l->type == TR_PUNCTUAL_DIRECTIONAL;
    y->kind = dir ? TR_BDPT_DIRECTIONAL : TR_BDPT_PUNCTUAL;
    y->tri = k;
    y->p = dir ? p : l->pos;
    y->wo = dir ? v3_neg(l->dir) : v3s(0.0f);
    y->m.ng = l->dir;
    y->m.ns = l->dir;
    y->cone = l->type == TR_PUNCTUAL_SPOT ? l->cos_outer : -1.0f;
    y->pdf_pos = dir ? tr_bdpt_disc_pdf(s) : 1.0f / (TR_TWO_PI * (1.0f - y->cone));
    y->delta = 0;
    y->pdf_fwd = pick;
    y->pdf_rev = 0.0f;
    y->pdf_nee = tr_bdpt_punctual_sel(s, k);
    y->beta = v3s(0.0f);
}

/* A light subpath from a punctual light (u1 of the origin pair in the lights' share
 * [lp->env + lp->sun, + lp->punct)), picked by the lights' power CDF: from a point light's
 * position a direction uniform on the sphere, from a spot's uniform in its outer cone
 * (its falloff a weight), from a directional light its direction from an origin on the
 * disc that covers the scene (as tr_bdpt_sky_subpath's); then up to max_depth - 1 hits. */
TR_FN int tr_bdpt_punctual_subpath(const tr_scene_view *s, int max_depth, const tr_sampler *smp,
                                   const tr_bdpt_light_probs *lp, tr_bdpt_vertex *lv,
                                   uint32_t *rays) {
    float u1, u2, d1, d2, prob;
    tr_sampler_2d(smp, TR_BDPT_DIM_LIGHT_ORIGIN, &u1, &u2);
    tr_sampler_2d(smp, TR_BDPT_DIM_LIGHT_DIR, &d1, &d2);
    u1 = tr_fminf(tr_fmaxf((u1 - (lp->env + lp->sun)) / lp->punct, 0.0f), 0.99999994f);
    const uint32_t k = tr_punctual_pick(s, u1, &prob);
    TR_CONST_GLOBAL tr_punctual *l = &s->punctual[k];
    if (!(prob > 0.0f) || tr_punctual_black(l->intensity)) {
        return 0;
    }
    tr_bdpt_vertex *y0 = &lv[0];
    tr_vec3 beta, o, w;
    float pdf_dir;
    if (l->type == TR_PUNCTUAL_DIRECTIONAL) {
        const float R = s->sky_radius;
        tr_vec3 ta, tb;
        const tr_vec3 wl = v3_neg(l->dir);
        v3_basis(wl, &ta, &tb);
        const float rr = R * tr_sqrtf(d1), phi = TR_TWO_PI * d2;
        const tr_vec3 centre = v3(s->sky_cx, s->sky_cy, s->sky_cz);
        o = v3_add(v3_madd(centre, wl, R),
                   v3_add(v3_scale(ta, rr * tr_cosf(phi)), v3_scale(tb, rr * tr_sinf(phi))));
        w = l->dir;
        tr_bdpt_punctual_vertex(s, k, lp->punct * prob, o, y0);
        pdf_dir = 1.0f; /* read by nothing: the first hit's density comes from y_0 */
        beta = v3_scale(l->intensity, 1.0f / (y0->pdf_fwd * y0->pdf_pos)); /* E / p */
    } else {
        o = l->pos;
        tr_bdpt_punctual_vertex(s, k, lp->punct * prob, o, y0);
        /* Uniform in the cone about the axis down to cos = y0->cone (the sphere for -1). */
        const float ct = 1.0f - d1 * (1.0f - y0->cone);
        const float st = tr_sqrtf(tr_fmaxf(0.0f, 1.0f - ct * ct));
        tr_vec3 ta, tb;
        v3_basis(l->dir, &ta, &tb);
        const float phi = TR_TWO_PI * d2;
        w = v3_add(v3_scale(l->dir, ct),
                   v3_add(v3_scale(ta, st * tr_cosf(phi)), v3_scale(tb, st * tr_sinf(phi))));
        w = v3_normalize(w);
        pdf_dir = y0->pdf_pos;
        const float fall =
            l->type == TR_PUNCTUAL_SPOT ? tr_punctual_spot_falloff(l, v3_dot(w, l->dir)) : 1.0f;
        beta = v3_scale(l->intensity, fall / (y0->pdf_fwd * pdf_dir)); /* I / p */
    }
    y0->beta = v3_scale(l->intensity, 1.0f / y0->pdf_fwd);
    if (tr_v3_is_zero(beta)) {
        return 1;
    }
    int nl = 1;
    tr_ray lr = tr_ray_make(o, w, 0.0f, TR_INFINITY);
    tr_bdpt_walk(s, lr, beta, pdf_dir, lv, &nl, max_depth, 1, smp, rays, 0, 0);
    return nl;
}

/* The light subpath: a point by area from the emitter table, a cosine-weighted direction
 * on its emitting side (either, for two-sided emitters), then up to max_depth - 1 hits
 * (a light subpath of s vertices serves paths of at least s segments); or, with the
 * probability of their power, one from the environment or the sun (tr_bdpt_sky_subpath)
 * or a punctual light (tr_bdpt_punctual_subpath). Returns the vertex count (0 without lights). */
TR_FN int tr_bdpt_light_subpath(const tr_scene_view *s, int max_depth, const tr_sampler *smp,
                                tr_bdpt_vertex *lv, uint32_t *rays) {
    int nl = 0;
    tr_bdpt_light_probs lp;
    const int sky = tr_bdpt_light_probs_of(s, &lp);
    if (sky && max_depth >= 2) {
        float u1, u2;
        tr_sampler_2d(smp, TR_BDPT_DIM_LIGHT_ORIGIN, &u1, &u2);
        if (u1 < lp.env + lp.sun) {
            return tr_bdpt_sky_subpath(s, max_depth, smp, &lp, lv, rays);
        }
        if (lp.punct > 0.0f && (u1 < lp.env + lp.sun + lp.punct || !(lp.emitters > 0.0f))) {
            return tr_bdpt_punctual_subpath(s, max_depth, smp, &lp, lv, rays);
        }
        if (!(lp.emitters > 0.0f)) {
            return tr_bdpt_sky_subpath(s, max_depth, smp, &lp, lv, rays);
        }
    }
    if (s->light_count > 0u && max_depth >= 2) {
        float u1, u2, d1, d2;
        tr_sampler_2d(smp, TR_BDPT_DIM_LIGHT_ORIGIN, &u1, &u2);
        tr_sampler_2d(smp, TR_BDPT_DIM_LIGHT_DIR, &d1, &d2);
        if (sky) { /* the emitters' share of u1, back to [0, 1) */
            u1 = tr_fminf(tr_fmaxf((u1 - (lp.env + lp.sun + lp.punct)) / lp.emitters, 0.0f),
                          0.99999994f);
        }
        float interval;
        uint32_t t = s->lights[tr_light_pick_rescale(s, &u1, &interval)];
        tr_triangle tri_tmp;
        TR_CONST_GLOBAL tr_triangle *tri = tr_view_triangle(s, t, &tri_tmp);
        float b1, b2;
        const tr_vec3 yp = tr_light_area_point(tri, u1, u2, &b1, &b2);
        tr_bdpt_vertex *y0 = &lv[0];
        y0->m = tr_material_eval(s, t, b1, b2, yp, tri->normal, tri->normal);
        y0->p = yp;
        y0->tri = t;
        y0->kind = TR_BDPT_LIGHT;
        y0->delta = 0;
        y0->wo = v3s(0.0f);
        y0->pdf_rev = 0.0f;
        y0->pdf_nee = 0.0f;
        y0->pdf_fwd = tr_bdpt_origin_pdf(s, y0);
        y0->beta = v3s(0.0f);
        nl = 1;
        tr_vec3 n0 = tri->normal;
        int two = (y0->m.flags & TR_MATERIAL_TWO_SIDED) != 0u;
        if (two) {
            if (d1 < 0.5f) {
                d1 *= 2.0f;
            } else {
                d1 = (d1 - 0.5f) * 2.0f;
                n0 = v3_neg(n0);
            }
        }
        tr_vec3 w = tr_sample_cosine_hemisphere_u(d1, d2, n0);
        float pdf_dir = tr_bdpt_emit_pdf(y0, w);
        tr_vec3 le = tr_emitted(&y0->m, w);
        if (y0->pdf_fwd > 0.0f && pdf_dir > 0.0f && !tr_v3_is_zero(le)) {
            float cs = tr_fabsf(v3_dot(w, tri->normal));
            y0->beta = v3_scale(le, 1.0f / y0->pdf_fwd); /* Le / p(y_0) */
            tr_vec3 beta = v3_scale(le, cs / (y0->pdf_fwd * pdf_dir));
            tr_ray lr = tr_ray_make(tr_offset_origin(yp, n0), w, 0.0f, TR_INFINITY);
            tr_bdpt_walk(s, lr, beta, pdf_dir, lv, &nl, max_depth, 1, smp, rays, 0, 0);
            if (nl >= 2) {
                y0->pdf_nee = tr_bdpt_nee_pdf(s, y0, &lv[1]);
            }
        }
    }

    return nl;
}

/* Every connection strategy (s, t) of camera subpath cv[0 .. nc-1] and light subpath
 * lv[0 .. nl-1]: returns what the camera-side strategies (t >= 2) bring to the pixel and
 * splats the light-tracing ones (t = 1). eta: vertex merging's eta for the MIS weights
 * (0 for BDPT). */
TR_FN tr_vec3 tr_bdpt_connect(const tr_scene_view *s, const tr_camera *cam,
                              const tr_bdpt_vertex *cv, int nc, const tr_bdpt_vertex *lv, int nl,
                              int max_depth, const tr_sampler *smp, const tr_bdpt_splat *sp,
                              tr_bdpt_select sel, float eta, uint32_t *rays) {
    tr_vec3 radiance = v3s(0.0f);
    for (int t = 1; t <= nc; ++t) {
        for (int ns = 0; ns <= nl && ns + t - 1 <= max_depth; ++ns) {
            const int n = ns + t;
            if (n < 2 || n - 1 > max_depth || (ns == 1 && t == 1)) {
                continue;
            }
            if (sel.only_t > 0 && (ns != sel.only_s || t != sel.only_t)) {
                continue;
            }
            const tr_bdpt_vertex *pt = &cv[t - 1];
            tr_vec3 c = v3s(0.0f);
            tr_bdpt_vertex nee;
            const tr_bdpt_vertex *neep = 0;
            int splat = 0;
            float sx = 0.0f, sy = 0.0f;
            if (ns == 0) {
                if (t < 2) {
                    continue;
                }
                c = v3_mul(pt->beta, tr_emitted(&pt->m, pt->wo));
            } else if (t == 1) {
                const tr_bdpt_vertex *qs = &lv[ns - 1];
                if (ns < 2 || tr_bsdf_is_delta(&qs->m)) {
                    continue;
                }
                tr_vec3 d = v3_sub(cam->pos, qs->p);
                float dist = v3_length(d);
                if (!(dist > cam->near_dist && dist < cam->far_dist)) {
                    continue;
                }
                tr_vec3 w = v3_scale(d, 1.0f / dist);
                float pdf;
                float we = tr_bdpt_camera_we(cam, v3_neg(w), &sx, &sy, &pdf); /* We cos */
                if (!(we > 0.0f)) {
                    continue;
                }
                tr_vec3 f = v3_scale(tr_bsdf_eval(&qs->m, qs->wo, w),
                                     tr_bdpt_shading_fix(&qs->m, qs->wo, w));
                c = v3_scale(v3_mul(qs->beta, f),
                             tr_fabsf(v3_dot(w, qs->m.ns)) * we / (dist * dist));
                if (tr_v3_is_zero(c)) {
                    continue;
                }
                tr_vec3 o = tr_surface_origin(&qs->m, qs->p, w);
                tr_vec3 od = v3_sub(o, cam->pos);
                float len = v3_length(od);
                tr_ray sh = tr_ray_make(cam->pos, v3_scale(od, 1.0f / len), cam->near_dist,
                                        len * (1.0f - 1e-4f));
                *rays += 1;
                if (tr_occluded_masked(s, &sh)) {
                    continue;
                }
                splat = 1;
            } else if (ns == 1) {
                if (tr_bsdf_is_delta(&pt->m) || pt->m.type == TR_MATERIAL_EMITTER) {
                    continue;
                }
                uint32_t lt;
                tr_vec3 yl;
                float lu, lvv, l1, l2;
                tr_sampler_2d(smp, tr_sampler_dim(t - 1, TR_DIM_LIGHT), &l1, &l2);
                float pl = tr_light_sample(s, pt->p, l1, l2, &lt, &yl, &lu, &lvv);
                tr_triangle ltri_tmp;
                TR_CONST_GLOBAL tr_triangle *ltri = tr_view_triangle(s, lt, &ltri_tmp);
                tr_vec3 d = v3_sub(yl, pt->p);
                float dist = v3_length(d);
                if (!(pl > 0.0f) || !(dist > 0.0f)) {
                    continue;
                }
                tr_vec3 wi = v3_scale(d, 1.0f / dist);
                nee.m = tr_material_eval(s, lt, lu, lvv, yl, ltri->normal, wi);
                tr_vec3 le = tr_emitted(&nee.m, v3_neg(wi));
                tr_vec3 f = tr_bsdf_eval(&pt->m, pt->wo, wi);
                if (tr_v3_is_zero(le) || tr_v3_is_zero(f)) {
                    continue;
                }
                tr_vec3 o = tr_surface_origin(&pt->m, pt->p, wi);
                tr_vec3 od = v3_sub(yl, o);
                float len = v3_length(od);
                tr_ray sh = tr_ray_make(o, v3_scale(od, 1.0f / len), 0.0f, len * (1.0f - 1e-4f));
                *rays += 1;
                if (tr_occluded_masked(s, &sh)) {
                    continue;
                }
                c = v3_scale(v3_mul(v3_mul(pt->beta, f), le), tr_fabsf(v3_dot(wi, pt->m.ns)) / pl);
                nee.p = yl;
                nee.tri = lt;
                nee.kind = TR_BDPT_LIGHT;
                nee.delta = 0;
                nee.wo = v3s(0.0f);
                nee.beta = v3s(0.0f);
                nee.pdf_rev = 0.0f;
                nee.pdf_fwd = tr_bdpt_origin_pdf(s, &nee);
                nee.pdf_nee = pl * tr_fabsf(v3_dot(wi, ltri->normal)) / (dist * dist);
                neep = &nee;
            } else {
                const tr_bdpt_vertex *qs = &lv[ns - 1];
                if (tr_bsdf_is_delta(&qs->m) || tr_bsdf_is_delta(&pt->m)) {
                    continue;
                }
                tr_vec3 d = v3_sub(pt->p, qs->p);
                float d2 = v3_dot(d, d);
                if (!(d2 > 0.0f)) {
                    continue;
                }
                tr_vec3 w = v3_scale(d, 1.0f / tr_sqrtf(d2));
                tr_vec3 fq = v3_scale(tr_bsdf_eval(&qs->m, qs->wo, w),
                                      tr_bdpt_shading_fix(&qs->m, qs->wo, w));
                tr_vec3 fp = tr_bsdf_eval(&pt->m, pt->wo, v3_neg(w));
                float g = tr_fabsf(v3_dot(w, qs->m.ns)) * tr_fabsf(v3_dot(w, pt->m.ns)) / d2;
                c = v3_scale(v3_mul(v3_mul(qs->beta, fq), v3_mul(fp, pt->beta)), g);
                if (tr_v3_is_zero(c)) {
                    continue;
                }
                tr_vec3 o1 = tr_surface_origin(&qs->m, qs->p, w);
                tr_vec3 o2 = tr_surface_origin(&pt->m, pt->p, v3_neg(w));
                tr_vec3 od = v3_sub(o2, o1);
                float len = v3_length(od);
                if (!(len > 0.0f)) {
                    continue;
                }
                tr_ray sh = tr_ray_make(o1, v3_scale(od, 1.0f / len), 0.0f, len * (1.0f - 1e-4f));
                *rays += 1;
                if (tr_occluded_masked(s, &sh)) {
                    continue;
                }
            }
            if (tr_v3_is_zero(c)) {
                continue;
            }
            float w =
                sel.only_t > 0 ? 1.0f : tr_bdpt_mis_weight_vm(s, cam, lv, ns, neep, cv, t, eta, 0);
            c = v3_scale(c, w);
            if (splat) {
                tr_bdpt_splat_add(sp, sx, sy, c);
            } else {
                radiance = v3_add(radiance, c);
            }
        }
    }
    return radiance;
}

/* The punctual lights', the environment's and the sun's part of camera subpath
 * cv[0 .. nc-1] that left the scene as *esc says, where no light subpath starts from them
 * (a scene without triangles, tr_bdpt_sky_on, tr_bdpt_punctual_on): at each vertex
 * that is not specular and can still add a segment, pt's light samples of them (the
 * sampler dimensions pt reads at that segment, which BDPT's camera side leaves unread);
 * where the subpath left the scene, the environment and the sun it sees, each weighted
 * against the light sample by the power heuristic. */
TR_FN tr_vec3 tr_bdpt_infinite(const tr_scene_view *s, const tr_bdpt_vertex *cv, int nc,
                               const tr_bdpt_escape *esc, int max_depth, const tr_sampler *smp,
                               uint32_t *rays) {
    tr_vec3 radiance = v3s(0.0f);
    /* With light subpaths from the environment and the sun, tr_bdpt_sky_camera has their
     * camera-side strategies, weighed with the rest; the punctual lights stay here. */
    const uint32_t env_count = tr_bdpt_sky_on(s) ? 0u : s->env_count;
    const uint32_t sun_count = tr_bdpt_sky_on(s) ? 0u : s->sun_count;
    /* Likewise tr_bdpt_punctual_camera for the punctual lights. */
    const uint32_t punctual_count = tr_bdpt_punctual_on(s) ? 0u : s->punctual_count;
    if (env_count == 0u && sun_count == 0u && punctual_count == 0u) {
        return radiance;
    }
    for (int i = 1; i < nc && i < max_depth; ++i) {
        const tr_bdpt_vertex *v = &cv[i];
        if (tr_bsdf_is_delta(&v->m) || v->m.type == TR_MATERIAL_EMITTER) {
            continue;
        }
        if (env_count > 0u) {
            radiance =
                v3_add(radiance, tr_pt_env_light(s, smp, i, &v->m, v->p, v->wo, v->beta, rays));
        }
        if (sun_count > 0u) {
            float su1, su2;
            tr_sampler_2d(smp, tr_sun_dim(i), &su1, &su2);
            radiance = v3_add(radiance,
                              v3_mul(v->beta, tr_sun_nee(s, &v->m, v->wo, v->p, su1, su2, rays)));
        }
        if (punctual_count > 0u) {
            const float pu = tr_sampler_1d(smp, tr_punctual_dim(i));
            radiance =
                v3_add(radiance, v3_mul(v->beta, tr_punctual_nee(s, &v->m, v->wo, v->p, pu, rays)));
        }
    }
    if (esc->left) {
        if (env_count > 0u) {
            const float w = esc->delta ? 1.0f : tr_mis_power(esc->pdf, tr_env_pdf(s, esc->dir));
            radiance =
                v3_add(radiance, v3_scale(v3_mul(esc->beta, tr_env_radiance(s, esc->dir)), w));
        }
        if (sun_count > 0u) {
            const float w = esc->delta ? 1.0f : tr_mis_power(esc->pdf, tr_sun_pdf(s, esc->dir));
            radiance =
                v3_add(radiance, v3_scale(v3_mul(esc->beta, tr_sun_radiance(s, esc->dir)), w));
        }
    }
    return radiance;
}

/* The camera-side strategies of paths from the environment and the sun, where light
 * subpaths start from them too (tr_bdpt_sky_on): at each camera vertex z_{t-1} that is
 * not specular, pt's light sample of each (strategy s = 1, the sampler dimensions pt
 * reads at that segment), and where the camera subpath left the scene, what it sees of
 * each (s = 0, cv[nc] then holds the light's vertex). Every one is weighed by
 * tr_bdpt_mis_weight_vm against all the strategies of its path: with eta > 0 the merges
 * among them. */
TR_FN tr_vec3 tr_bdpt_sky_camera(const tr_scene_view *s, const tr_camera *cam, tr_bdpt_vertex *cv,
                                 int nc, const tr_bdpt_escape *esc, int max_depth,
                                 const tr_sampler *smp, float eta, uint32_t *rays) {
    tr_vec3 radiance = v3s(0.0f);
    tr_bdpt_light_probs lp;
    if (!tr_bdpt_light_probs_of(s, &lp)) {
        return radiance;
    }
    const float disc = tr_bdpt_disc_pdf(s);
    for (int t = 2; t <= nc && t <= max_depth; ++t) {
        const tr_bdpt_vertex *pt = &cv[t - 1];
        if (tr_bsdf_is_delta(&pt->m) || pt->m.type == TR_MATERIAL_EMITTER) {
            continue;
        }
        for (uint32_t which = TR_BDPT_SKY_ENV; which <= TR_BDPT_SKY_SUN; ++which) {
            if ((which == TR_BDPT_SKY_SUN ? s->sun_count : s->env_count) == 0u) {
                continue;
            }
            float u1, u2, pdf_dir;
            tr_vec3 wi;
            tr_sampler_2d(smp,
                          which == TR_BDPT_SKY_SUN ? tr_sun_dim(t - 1)
                                                   : tr_sampler_dim(t - 1, TR_DIM_ENV),
                          &u1, &u2);
            const tr_vec3 le = which == TR_BDPT_SKY_SUN ? tr_sun_sample(s, u1, u2, &wi, &pdf_dir)
                                                        : tr_env_sample(s, u1, u2, &wi, &pdf_dir);
            const tr_vec3 f = pdf_dir > 0.0f ? tr_bsdf_eval(&pt->m, pt->wo, wi) : v3s(0.0f);
            if (tr_v3_is_zero(le) || tr_v3_is_zero(f)) {
                continue;
            }
            tr_ray sh = tr_ray_make(tr_surface_origin(&pt->m, pt->p, wi), wi, 0.0f, TR_INFINITY);
            *rays += 1;
            if (tr_occluded_masked(s, &sh)) {
                continue;
            }
            tr_bdpt_vertex nee;
            nee.p = pt->p;
            nee.wo = wi;
            nee.tri = which;
            nee.kind = TR_BDPT_INFINITE;
            nee.delta = 0;
            nee.beta = v3s(0.0f);
            nee.pdf_pos = disc;
            nee.pdf_fwd = (which == TR_BDPT_SKY_SUN ? lp.sun : lp.env) * pdf_dir;
            nee.pdf_rev = 0.0f;
            nee.pdf_nee = pdf_dir;
            nee.m.ng = wi;
            nee.m.ns = wi;
            const float w = tr_bdpt_mis_weight_vm(s, cam, &nee, 1, &nee, cv, t, eta, 0);
            const tr_vec3 c = v3_mul(v3_mul(pt->beta, f), le);
            radiance = v3_add(radiance, v3_scale(c, tr_fabsf(v3_dot(wi, pt->m.ns)) * w / pdf_dir));
        }
    }
    if (esc->left) {
        if (nc < 2) { /* the pinhole sees the sky: no other strategy makes this path */
            const tr_vec3 le = v3_add(s->env_count > 0u ? tr_env_radiance(s, esc->dir) : v3s(0.0f),
                                      s->sun_count > 0u ? tr_sun_radiance(s, esc->dir) : v3s(0.0f));
            return v3_add(radiance, v3_mul(esc->beta, le));
        }
        tr_bdpt_vertex *z = &cv[nc]; /* free: the walk stops short of the last vertex to escape */
        z->p = cv[nc - 1].p;
        z->wo = esc->dir;
        z->beta = esc->beta;
        z->kind = TR_BDPT_INFINITE;
        z->delta = 0;
        z->pdf_pos = disc;
        z->pdf_rev = 0.0f;
        z->pdf_nee = 0.0f;
        z->m.ng = esc->dir;
        z->m.ns = esc->dir;
        z->pdf_fwd = cv[nc - 1].delta ? 0.0f : tr_bdpt_pdf(cam, &cv[nc - 1], &cv[nc - 2], z);
        for (uint32_t which = TR_BDPT_SKY_ENV; which <= TR_BDPT_SKY_SUN; ++which) {
            if ((which == TR_BDPT_SKY_SUN ? s->sun_count : s->env_count) == 0u) {
                continue;
            }
            const tr_vec3 le = tr_bdpt_sky_radiance(s, which, esc->dir);
            if (tr_v3_is_zero(le)) {
                continue;
            }
            z->tri = which;
            const float w = tr_bdpt_mis_weight_vm(s, cam, cv, 0, 0, cv, nc + 1, eta, 0);
            radiance = v3_add(radiance, v3_scale(v3_mul(esc->beta, le), w));
        }
    }
    return radiance;
}

/* The camera-side strategy of paths from the punctual lights, where light subpaths start
 * from them too (tr_bdpt_punctual_on): at each camera vertex z_{t-1} that is not specular,
 * pt's light sample of them (tr_punctual_nee's choice: every light, or one by the CDF with
 * the sampler dimension pt reads at that segment), strategy s = 1 of tr_bdpt_mis_weight_vm,
 * weighed against the light subpaths' connections (and with eta > 0 merges). */
TR_FN tr_vec3 tr_bdpt_punctual_camera(const tr_scene_view *s, const tr_camera *cam,
                                      const tr_bdpt_vertex *cv, int nc, int max_depth,
                                      const tr_sampler *smp, float eta, uint32_t *rays) {
    tr_vec3 radiance = v3s(0.0f);
    tr_bdpt_light_probs lp;
    if (!tr_bdpt_light_probs_of(s, &lp) || !(lp.punct > 0.0f)) {
        return radiance;
    }
    for (int t = 2; t <= nc && t <= max_depth; ++t) {
        const tr_bdpt_vertex *pt = &cv[t - 1];
        if (tr_bsdf_is_delta(&pt->m) || pt->m.type == TR_MATERIAL_EMITTER) {
            continue;
        }
        uint32_t k0 = 0u, k1 = s->punctual_count;
        if (s->punctual_count > TR_PUNCTUAL_ALL) {
            float prob;
            k0 = tr_punctual_pick(s, tr_sampler_1d(smp, tr_punctual_dim(t - 1)), &prob);
            k1 = k0 + 1u;
        }
        for (uint32_t k = k0; k < k1; ++k) {
            const float sel = tr_bdpt_punctual_sel(s, k);
            const tr_vec3 c = tr_punctual_one(s, &s->punctual[k], sel, &pt->m, pt->wo, pt->p, rays);
            if (tr_v3_is_zero(c)) {
                continue;
            }
            tr_bdpt_vertex nee;
            tr_bdpt_punctual_vertex(s, k, lp.punct * tr_bdpt_punctual_prob(s, k), pt->p, &nee);
            const float w = tr_bdpt_mis_weight_vm(s, cam, &nee, 1, &nee, cv, t, eta, 0);
            radiance = v3_add(radiance, v3_scale(v3_mul(pt->beta, c), w));
        }
    }
    return radiance;
}

/* One BDPT sample for the camera ray through raster point (x + jx, y + jy): returns what
 * the camera-side strategies (t >= 2) bring to this pixel and splats the light-tracing
 * ones (t = 1). Paths have at most max_depth segments (<= TR_BDPT_MAX_DEPTH). */
TR_FN tr_vec3 tr_trace_bdpt(const tr_scene_view *s, const tr_camera *cam, float x, float y,
                            int max_depth, const tr_sampler *smp, const tr_bdpt_splat *sp,
                            tr_bdpt_select sel, uint32_t *rays, tr_sample *surface) {
    if (max_depth > TR_BDPT_MAX_DEPTH) {
        max_depth = TR_BDPT_MAX_DEPTH;
    }
    tr_bdpt_vertex cv[TR_BDPT_MAX_VERTS], lv[TR_BDPT_MAX_VERTS];
    tr_bdpt_escape esc;
    int nc = tr_bdpt_camera_subpath(s, cam, x, y, max_depth, smp, cv, rays, surface, &esc);
    int nl = tr_bdpt_light_subpath(s, max_depth, smp, lv, rays);
    tr_vec3 c = tr_bdpt_connect(s, cam, cv, nc, lv, nl, max_depth, smp, sp, sel, 0.0f, rays);
    /* A test that selects one strategy (sel.only_t) wants the emitters' part alone. */
    if (sel.only_t > 0) {
        return c;
    }
    if (tr_bdpt_sky_on(s)) {
        c = v3_add(c, tr_bdpt_sky_camera(s, cam, cv, nc, &esc, max_depth, smp, 0.0f, rays));
    }
    if (tr_bdpt_punctual_on(s)) {
        c = v3_add(c, tr_bdpt_punctual_camera(s, cam, cv, nc, max_depth, smp, 0.0f, rays));
    }
    return v3_add(c, tr_bdpt_infinite(s, cv, nc, &esc, max_depth, smp, rays));
}

/* tr_render_grid_rows (kernel.h) for bdpt: grid points [gx0, gx1) x [gy0, gy1) of frame f,
 * camera-side contributions into the film, light tracing into sp. Returns the rays. */
TR_FN uint32_t tr_bdpt_render_grid_rows(const tr_scene_view *s, const tr_frame *f,
                                        const tr_film_view *film, const tr_bdpt_splat *sp,
                                        uint32_t gx0, uint32_t gy0, uint32_t gx1, uint32_t gy1) {
    const tr_camera cam = f->camera;
    const uint64_t seed = ((uint64_t)f->seed_hi << 32) | (uint64_t)f->seed_lo;
    const tr_bdpt_select all = {0, 0};
    uint32_t rays = 0;
    for (uint32_t gy = gy0; gy < gy1; ++gy) {
        for (uint32_t gx = gx0; gx < gx1; ++gx) {
            uint32_t x, y, bx0, by0, bx1, by1;
            const uint64_t pixel = tr_frame_point(f, gx, gy, &x, &y, &bx0, &by0, &bx1, &by1);
            for (uint32_t n = 0; n < f->sample_count; ++n) {
                tr_sample out;
                tr_sample_clear(&out);
                tr_sampler smp = tr_sampler_make(seed, pixel, f->sample + n);
                out.radiance = tr_trace_bdpt(s, &cam, (float)x, (float)y, f->max_depth, &smp, sp,
                                             all, &out.rays, f->passes != 0u ? &out : 0);
                tr_sample_finish(&out);
                rays += out.rays;
                tr_film_add_block(film, &out, bx0, by0, bx1, by1);
            }
        }
    }
    return rays;
}

#endif
