/* film.h - what one sample leaves behind: the surface record the passes are made of,
 * and the one function that adds a sample to a film, which the CPU backend and the
 * OpenCL entry point both call (so both fill radiance and passes the same way).
 *
 * A film is a set of per-pixel sums, row-major, top row first: radiance (3 floats), a
 * sample count, and, for the passes kept (TR_PASS_*), albedo and normal (3 floats each),
 * depth (1 float), the primitive id of the pixel's first sample (1 word) and squared
 * radiance (3 floats, for the variance), direct radiance and the first hit's emission
 * (3 floats each). The mean of a pixel is its
 * sum over its count; sums and counts of two films add (src/film/film.c). */
#ifndef TR_KERNEL_FILM_H
#define TR_KERNEL_FILM_H

#include "bsdf.h"
#include "compat.h"
#include "material_eval.h"
#include "types.h"
#include "vec.h"

/* Called at every hit of a path until it has recorded the surface the passes describe:
 * the first one that is not a perfect mirror or smooth glass. Adds the segment's length
 * `t` to the distance travelled from the camera (kept in out->depth meanwhile), and at
 * that surface records its albedo (tr_bsdf_guide_albedo) and shading normal, turned to face the
 * arriving direction `dir`. Only films that keep passes pay for it: the integrators are
 * handed a null `out` otherwise. */
TR_FN void tr_sample_surface(tr_sample *out, const tr_bsdf_params *m, tr_vec3 dir, float t,
                             uint32_t triangle) {
    if (out->prim != 0u) {
        return;
    }
    out->depth += t;
    if (tr_bsdf_is_delta(m)) {
        return;
    }
    out->albedo = tr_bsdf_guide_albedo(m, dir);
    out->normal = v3_dot(m->ns, dir) > 0.0f ? v3_neg(m->ns) : m->ns;
    out->prim = triangle + 1u;
}

/* A sample with nothing recorded yet. */
TR_FN void tr_sample_clear(tr_sample *out) {
    out->radiance = v3s(0.0f);
    out->direct = v3s(0.0f);
    out->emission = v3s(0.0f);
    out->specular = v3s(0.0f);
    out->spec_f0 = v3s(0.0f);
    out->spec_alpha = 0.0f;
    out->spec_dist = 0.0f;
    out->albedo = v3s(0.0f);
    out->normal = v3s(0.0f);
    out->depth = 0.0f;
    out->prim = 0u;
    out->rays = 0u;
}

/* Ends a traced sample: where the path met no surface for the passes, its depth means
 * nothing and is zero. */
TR_FN void tr_sample_finish(tr_sample *out) {
    if (out->prim == 0u) {
        out->depth = 0.0f;
    }
}

/* The film's buffers as one kernel sees them (device or host memory). Pass buffers that
 * the film does not keep may be null; `passes` says which are written. */
typedef struct tr_film_view {
    TR_GLOBAL float *sum;
    TR_GLOBAL uint32_t *count;
    TR_GLOBAL float *albedo;
    TR_GLOBAL float *normal;
    TR_GLOBAL float *depth;
    TR_GLOBAL uint32_t *prim;
    TR_GLOBAL float *sq;       /* TR_PASS_VARIANCE: squared radiance; set after tr_film_view_make */
    TR_GLOBAL float *direct;   /* TR_PASS_DIRECT: direct radiance; set after tr_film_view_make */
    TR_GLOBAL float *emission; /* TR_PASS_EMISSION: the same */
    TR_GLOBAL float *specular; /* TR_PASS_SPECULAR (8 per pixel, the CPU's): the same */
    uint32_t width;
    uint32_t passes;
} tr_film_view;

/* A film view over the given buffers (pass buffers the film does not keep may be null). */
TR_FN tr_film_view tr_film_view_make(TR_GLOBAL float *sum, TR_GLOBAL uint32_t *count,
                                     TR_GLOBAL float *albedo, TR_GLOBAL float *normal,
                                     TR_GLOBAL float *depth, TR_GLOBAL uint32_t *prim,
                                     uint32_t width, uint32_t passes) {
    tr_film_view v;
    v.sum = sum;
    v.count = count;
    v.albedo = albedo;
    v.normal = normal;
    v.depth = depth;
    v.prim = prim;
    v.sq = 0;
    v.direct = 0;
    v.emission = 0;
    v.specular = 0;
    v.width = width;
    v.passes = passes;
    return v;
}

/* Adds sample `smp` to every pixel of the block [x0, x1) x [y0, y1) (one pixel, or a
 * preview block with stride > 1). The primitive id is kept from the first sample a pixel
 * receives. */
TR_FN void tr_film_add_block(const tr_film_view *f, const tr_sample *smp, uint32_t x0, uint32_t y0,
                             uint32_t x1, uint32_t y1) {
    const tr_vec3 c = smp->radiance;
    if (f->passes == 0u) {
        /* Radiance only, the common case: nothing else to look at per pixel. */
        for (uint32_t y = y0; y < y1; ++y) {
            for (uint32_t x = x0; x < x1; ++x) {
                const size_t i = (size_t)y * f->width + x;
                f->sum[3 * i] += c.x;
                f->sum[3 * i + 1] += c.y;
                f->sum[3 * i + 2] += c.z;
                f->count[i] += 1u;
            }
        }
        return;
    }
    for (uint32_t y = y0; y < y1; ++y) {
        for (uint32_t x = x0; x < x1; ++x) {
            const size_t i = (size_t)y * f->width + x;
            f->sum[3 * i] += smp->radiance.x;
            f->sum[3 * i + 1] += smp->radiance.y;
            f->sum[3 * i + 2] += smp->radiance.z;
            if ((f->passes & TR_PASS_ALBEDO) != 0u) {
                f->albedo[3 * i] += smp->albedo.x;
                f->albedo[3 * i + 1] += smp->albedo.y;
                f->albedo[3 * i + 2] += smp->albedo.z;
            }
            if ((f->passes & TR_PASS_NORMAL) != 0u) {
                f->normal[3 * i] += smp->normal.x;
                f->normal[3 * i + 1] += smp->normal.y;
                f->normal[3 * i + 2] += smp->normal.z;
            }
            if ((f->passes & TR_PASS_DEPTH) != 0u) {
                f->depth[i] += smp->depth;
            }
            if ((f->passes & TR_PASS_PRIM) != 0u && f->count[i] == 0u) {
                f->prim[i] = smp->prim;
            }
            if ((f->passes & TR_PASS_VARIANCE) != 0u) {
                f->sq[3 * i] += smp->radiance.x * smp->radiance.x;
                f->sq[3 * i + 1] += smp->radiance.y * smp->radiance.y;
                f->sq[3 * i + 2] += smp->radiance.z * smp->radiance.z;
            }
            if ((f->passes & TR_PASS_DIRECT) != 0u) {
                f->direct[3 * i] += smp->direct.x;
                f->direct[3 * i + 1] += smp->direct.y;
                f->direct[3 * i + 2] += smp->direct.z;
            }
            if ((f->passes & TR_PASS_EMISSION) != 0u) {
                f->emission[3 * i] += smp->emission.x;
                f->emission[3 * i + 1] += smp->emission.y;
                f->emission[3 * i + 2] += smp->emission.z;
            }
            if ((f->passes & TR_PASS_SPECULAR) != 0u) {
                TR_GLOBAL float *sp = f->specular + 8 * i;
                sp[0] += smp->specular.x;
                sp[1] += smp->specular.y;
                sp[2] += smp->specular.z;
                sp[3] += smp->spec_f0.x;
                sp[4] += smp->spec_f0.y;
                sp[5] += smp->spec_f0.z;
                sp[6] += smp->spec_alpha;
                sp[7] += smp->spec_dist;
            }
            f->count[i] += 1u;
        }
    }
}

#endif
