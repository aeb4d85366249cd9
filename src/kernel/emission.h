/* emission.h - the first hit's emission resolved over a pixel's area, per pixel: what
 * tr_resolve_emission (src/post/emission.c) runs on the host and tr_cl_resolve_emission
 * (entry.cl) on an OpenCL device.
 *
 * `e` is a frame's emission pass (TR_PASS_EMISSION: sums or means, 3 floats per pixel,
 * row-major); a pixel "saw emission" where any of its channels is above zero. */
#ifndef TR_KERNEL_EMISSION_H
#define TR_KERNEL_EMISSION_H

#include "camera.h"
#include "compat.h"
#include "integrator_pt.h"
#include "scene_view.h"
#include "vec.h"

/* Whether pixel i's samples saw any emission. */
TR_FN int tr_emission_seen(TR_GLOBAL const float *e, uint32_t i) {
    return e[3u * i] > 0.0f || e[3u * i + 1u] > 0.0f || e[3u * i + 2u] > 0.0f;
}

/* Whether the emission an upscaled frame's previous output `prev` (w x h) saw at (x, y)
 * belongs to an emitter this frame's samples can miss, where none of them saw it: one
 * that does not also reach dx output pixels away along x (either way) and dy along y.
 * The samples lie at most two traced pixels apart (dx, dy: two traced pixels in output
 * pixels), so an emitter that reaches that far in both axes from (x, y) and were still
 * there would hold one of them: where none saw it, it moved away (the sky behind a
 * silhouette, as the camera turns). A small lamp or a thin strip does not reach that far
 * in both axes: where it lay between the samples, its emission is traced instead of lost.
 * Outside the image counts as reached (the sky goes on past the frame's edge). */
TR_FN int tr_emission_missed(TR_GLOBAL const float *prev, int w, int h, int x, int y, int dx,
                             int dy) {
    if (!tr_emission_seen(prev, (uint32_t)(y * w + x))) {
        return 0;
    }
    const int l = x - dx < 0 || tr_emission_seen(prev, (uint32_t)(y * w + x - dx));
    const int r = x + dx >= w || tr_emission_seen(prev, (uint32_t)(y * w + x + dx));
    const int u = y - dy < 0 || tr_emission_seen(prev, (uint32_t)((y - dy) * w + x));
    const int d = y + dy >= h || tr_emission_seen(prev, (uint32_t)((y + dy) * w + x));
    return !((l || r) && (u || d));
}

/* Two emitting pixels whose luminances differ by more than this share of the larger are
 * on a step in the emission too: an environment's horizon, the sun's disc against the
 * sky, one lamp in front of a brighter one. At one sample a pixel across such a step shows
 * one side or the other, and its light is not filtered (emission is kept out of the
 * filters), so without the resolve it stays one sample's worth of noise in every frame.
 * A quarter: a smooth sky's neighbouring pixels differ by a few percent. */
#define TR_EMISSION_STEP 0.25f

/* Whether pixels i and j, both of which saw emission, lie across a step
 * (TR_EMISSION_STEP). */
TR_FN int tr_emission_step(TR_GLOBAL const float *e, uint32_t i, uint32_t j) {
    const float li = tr_env_luminance(v3(e[3u * i], e[3u * i + 1u], e[3u * i + 2u]));
    const float lj = tr_env_luminance(v3(e[3u * j], e[3u * j + 1u], e[3u * j + 2u]));
    return tr_fabsf(li - lj) > TR_EMISSION_STEP * tr_fmaxf(li, lj);
}

/* Whether a pixel of the 3 x 3 block around (x, y), clipped to the w x h image, differs
 * from (x, y) in tr_emission_seen, or both saw emission across a step
 * (tr_emission_step): the pixels next to an emitter's edge, on both sides. */
TR_FN int tr_emission_on_edge(TR_GLOBAL const float *e, int w, int h, int x, int y) {
    const uint32_t i = (uint32_t)(y * w + x);
    const int c = tr_emission_seen(e, i);
    for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
            const int xx = x + dx, yy = y + dy;
            if (xx < 0 || yy < 0 || xx >= w || yy >= h) {
                continue;
            }
            const uint32_t j = (uint32_t)(yy * w + xx);
            const int cj = tr_emission_seen(e, j);
            if (cj != c || (c && tr_emission_step(e, i, j))) {
                return 1;
            }
        }
    }
    return 0;
}

/* The sum of the emission seen at the first hit (tr_pt_first_emission) by the `count` camera
 * rays through the points of a Hammersley set over pixel (x, y) (tr_hammersley_point), and
 * in *hits how many of them saw any. With a thin lens each ray also gets its own lens
 * point, the points the R2 sequence over the lens's square (Roberts 2018: k times the
 * inverse powers of the plastic number, modulo 1), evenly spread and unrelated to the
 * pixel's points. */
TR_FN tr_vec3 tr_emission_rays(const tr_scene_view *s, const tr_camera *cam, int x, int y,
                               uint32_t count, uint32_t *hits) {
    tr_vec3 sum = v3s(0.0f);
    *hits = 0u;
    for (uint32_t k = 0; k < count; ++k) {
        float u, v;
        tr_hammersley_point(k, count, &u, &v);
        tr_ray ray = tr_camera_ray(cam, (float)x, (float)y, u, v);
        if (cam->lens_radius > 0.0f) {
            const float kk = (float)k;
            const float lu = 0.5f + kk * 0.75487767f, lv = 0.5f + kk * 0.56984029f;
            ray = tr_camera_ray_lens(cam, (float)x, (float)y, u, v, lu - tr_floorf(lu),
                                     lv - tr_floorf(lv));
        }
        const tr_vec3 e = tr_pt_first_emission(s, ray);
        *hits += (e.x > 0.0f || e.y > 0.0f || e.z > 0.0f) ? 1u : 0u;
        sum = v3_add(sum, e);
    }
    return sum;
}

/* The mean emission seen at the first hit by n x n camera rays over pixel (x, y): the
 * pixel's coverage by each emitter times its radiance. The rays pass through the n^2
 * points of a Hammersley set, not an n x n grid: a bright lamp's rim is mostly near-straight
 * edges, and a pixel a lamp covers by a sliver thinner than a grid row (1/n) but thicker
 * than the lamp's 1/radiance shows the lamp's colour at full brightness in a converged
 * image, where the grid's rays all miss it. Where exactly one ray of the n^2 sees emission
 * the coverage lies between 1/(2 n^2) and 3/(2 n^2) along a straight edge, and that one
 * ray shows it as 1/n^2: for a lamp brighter than n^2 times the display's white, full
 * white instead of a fraction of it (a lamp seen almost edge-on covers whole rows of
 * pixels so). There (n above 1) the pixel is traced again with 4 n^2 rays, whose mean it
 * takes. */
TR_FN tr_vec3 tr_emission_resolve_pixel(const tr_scene_view *s, const tr_camera *cam, int x, int y,
                                        int n) {
    const uint32_t count = (uint32_t)(n * n);
    uint32_t hits;
    const tr_vec3 sum = tr_emission_rays(s, cam, x, y, count, &hits);
    if (hits == 1u && count > 1u) {
        const tr_vec3 more = tr_emission_rays(s, cam, x, y, 4u * count, &hits);
        return v3_scale(more, 1.0f / (float)(4u * count));
    }
    return v3_scale(sum, 1.0f / (float)count);
}

#endif
