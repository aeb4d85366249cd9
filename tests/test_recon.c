/* test_recon.c - real-time reconstruction (src/post/filter.h, filter.c).
 *
 * 1. Every filter keeps a constant image constant and the mean of a noisy one (within
 *    1 %), and the guided ones do not blur across a depth and normal step nor brighten a
 *    dark texture's near-black channel with its neighbours' light; the host's
 *    vectorised filters compute what filter.h's per-pixel operators do.
 * 2. Reprojection of a rendered static scene under a known camera move: surviving taps
 *    lie on the pixel's own primitive, most pixels survive a small move, pixels whose
 *    point the previous camera saw behind another surface (disocclusions) are rejected,
 *    and the same buffers reprojected through a wrong (mirrored) camera mostly fail.
 *    The host's temporal stage gives tr_post_temporal_pixel's results bit for bit.
 * 3. After a camera cut the error returns within 8 frames to that of a history started
 *    fresh on the new view: no ghost of the old one survives.
 * 4. The result does not depend on the thread count.
 * 5. The albedo history converges to a pixel's mean albedo where each frame's sample
 *    alternates; without it the output flips with each frame's own albedo.
 * 6. The filmic display curve rises strictly below white, and its display film gives the
 *    direct tonemap's bytes.
 * 7. SSIM is 1 for an image with itself, falls with noise and is symmetric.
 * 8. A cancel (tr_recon.cancel) stops the spatial filter after its first iteration with
 *    TR_STATUS_CANCELLED, and keeps the history: the next frame equals, bit for bit, that
 *    of a reconstruction whose frame was not cancelled; a cancel that never fires changes
 *    nothing. */
#include "check.h"
#include "synth_frame.h"
#include "classic_box.h"
#include "post/filter.h"
#include "post/tonemap.h"
#include "trac0r/post.h"
#include "trac0r/scene_file.h"
#include "trac0r/trac0r.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define W 40
#define H 30

/* A synthetic frame: left half a wall facing the camera at depth 1 (colour left_c), right
 * half a wall at depth 2 turned away (colour right_c), each with uniform noise of
 * amplitude `noise` (seeded). Albedo 0.5 everywhere. */
static void synth(tr_gbuffer *g, float left_c, float right_c, float noise, uint32_t seed) {
    synth_frame(g, W, H, left_c, right_c, noise, -1.0f, seed);
}

static double mean(const float *img, size_t pixels) {
    double s = 0.0;
    for (size_t i = 0; i < 3 * pixels; ++i) {
        s += img[i];
    }
    return s / (3.0 * (double)pixels);
}

/* The mean of channel 0 over columns [x0, x1). */
static double column_mean(const float *img, int x0, int x1) {
    double s = 0.0;
    for (int y = 0; y < H; ++y) {
        for (int x = x0; x < x1; ++x) {
            s += img[3 * (y * W + x)];
        }
    }
    return s / (double)(H * (x1 - x0));
}

static tr_camera front_camera(void) {
    tr_camera cam;
    tr_error err;
    CHECK(tr_camera_make(&cam, tr_vec3_make(0, 0, -1), tr_vec3_make(0, 0, 1), tr_vec3_make(0, 1, 0),
                         60.0f, 1e-3f, 1e4f, W, H, &err) == TR_OK,
          "%s", err.msg);
    return cam;
}

/* One spatial method's output on g (fresh history). */
static void run_method(const tr_gbuffer *g, int method, float *out, int threads) {
    tr_recon r;
    tr_error err;
    const tr_camera cam = front_camera();
    const tr_recon_params p = tr_recon_params_default();
    CHECK(tr_recon_init(&r, W, H, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_recon_frame(&r, g, &cam, method, &p, threads, out, &err) == TR_OK, "%s", err.msg);
    tr_recon_free(&r);
}

/* The largest difference between a and b relative to max(1, |b|). */
static double worst_rel(const float *a, const float *b, size_t n) {
    double worst = 0.0;
    for (size_t i = 0; i < n; ++i) {
        worst = fmax(worst, fabs((double)a[i] - b[i]) / fmax(1.0, fabs((double)b[i])));
    }
    return worst;
}

/* The host's vectorised filters (filter.c turns the tap loops round and works on planar
 * copies) against filter.h's per-pixel operators, which a device runs one work item per
 * pixel: the same sums in the same order, so they agree to rounding. A frame 300 wide
 * crosses the host's 256-pixel chunks; noise, random albedo, a normal and depth step and
 * a depth ramp give every weight term work to do. */
static void test_operators(void) {
    enum { OW = 300, OH = 9 };
    const size_t n = (size_t)OW * OH;
    tr_gbuffer g;
    tr_error err;
    CHECK(tr_gbuffer_init(&g, OW, OH, &err) == TR_OK, "%s", err.msg);
    uint32_t s = 7;
    for (int y = 0; y < OH; ++y) {
        for (int x = 0; x < OW; ++x) {
            const size_t i = (size_t)y * OW + x;
            const int left = x < 150;
            for (int k = 0; k < 3; ++k) {
                g.color[3 * i + k] = unit(&s);
                g.albedo[3 * i + k] = 0.2f + 0.7f * unit(&s);
            }
            g.normal[3 * i] = left ? 0.0f : 0.6f;
            g.normal[3 * i + 1] = 0.0f;
            g.normal[3 * i + 2] = left ? -1.0f : -0.8f;
            g.depth[i] = (left ? 1.0f : 2.0f) + 0.002f * (float)x;
            g.prim[i] = left ? 1u : 2u;
        }
    }
    const tr_recon_params p = tr_recon_params_default();
    float *out = malloc(3 * n * sizeof *out), *ref = malloc(3 * n * sizeof *ref);
    float *a = malloc(3 * n * sizeof *a), *b = malloc(3 * n * sizeof *b);
    float *va = malloc(n * sizeof *va), *vb = malloc(n * sizeof *vb);
    float *mom = malloc(2 * n * sizeof *mom), *len = malloc(n * sizeof *len);
    CHECK(out && ref && a && b && va && vb && mom && len, "out of memory");

    CHECK(tr_filter_bilateral(&g, g.color, out, &p, 2, &err) == TR_OK, "%s", err.msg);
    for (int y = 0; y < OH; ++y) {
        for (int x = 0; x < OW; ++x) {
            tr_post_bilateral_pixel(g.color, OW, OH, x, y, p.bilateral_radius, p.bilateral_sigma_s,
                                    p.bilateral_sigma_r, ref + 3 * ((size_t)y * OW + x));
        }
    }
    double d = worst_rel(out, ref, 3 * n);
    CHECK(d < 1e-5, "bilateral: host and operator differ by %g", d);

    CHECK(tr_filter_atrous(&g, g.color, out, &p, 2, &err) == TR_OK, "%s", err.msg);
    for (size_t i = 0; i < 3 * n; ++i) {
        a[i] = g.color[i] / tr_post_demod_factor(g.albedo[i]);
    }
    for (int it = 0; it < p.atrous_iterations; ++it) {
        for (int y = 0; y < OH; ++y) {
            for (int x = 0; x < OW; ++x) {
                tr_post_atrous_pixel(a, g.normal, g.depth, g.albedo, OW, OH, x, y, 1 << it,
                                     p.atrous_sigma_c / (float)(1 << it), p.atrous_sigma_n,
                                     p.atrous_sigma_z, p.atrous_sigma_a,
                                     b + 3 * ((size_t)y * OW + x));
            }
        }
        memcpy(a, b, 3 * n * sizeof *a);
    }
    for (size_t i = 0; i < 3 * n; ++i) {
        ref[i] = a[i] * tr_post_demod_factor(g.albedo[i]);
    }
    d = worst_rel(out, ref, 3 * n);
    CHECK(d < 1e-5, "atrous: host and operator differ by %g", d);

    /* SVGF on a first frame: no history, so the variance is the spatial estimate. */
    tr_camera cam;
    CHECK(tr_camera_make(&cam, tr_vec3_make(0, 0, -1), tr_vec3_make(0, 0, 1), tr_vec3_make(0, 1, 0),
                         60.0f, 1e-3f, 1e4f, OW, OH, &err) == TR_OK,
          "%s", err.msg);
    tr_recon r;
    CHECK(tr_recon_init(&r, OW, OH, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_recon_frame(&r, &g, &cam, TR_RECON_SVGF, &p, 2, out, &err) == TR_OK, "%s", err.msg);
    tr_recon_free(&r);
    for (size_t i = 0; i < n; ++i) {
        for (int k = 0; k < 3; ++k) {
            a[3 * i + k] = g.color[3 * i + k] / tr_post_demod_factor(g.albedo[3 * i + k]);
        }
        const float l = tr_post_luminance(a[3 * i], a[3 * i + 1], a[3 * i + 2]);
        mom[2 * i] = l;
        mom[2 * i + 1] = l * l;
        len[i] = 1.0f;
    }
    for (int y = 0; y < OH; ++y) {
        for (int x = 0; x < OW; ++x) {
            va[y * OW + x] = tr_post_svgf_variance_pixel(a, mom, len, g.normal, OW, OH, x, y);
        }
    }
    for (int it = 0; it < p.svgf_iterations; ++it) {
        for (int y = 0; y < OH; ++y) {
            for (int x = 0; x < OW; ++x) {
                const size_t i = (size_t)y * OW + x;
                tr_post_svgf_pixel(a, va, g.normal, g.depth, OW, OH, x, y, 1 << it, p.svgf_sigma_l,
                                   p.svgf_sigma_n, p.svgf_sigma_z, tr_post_var3x3(va, OW, OH, x, y),
                                   b + 3 * i, vb + i);
            }
        }
        memcpy(a, b, 3 * n * sizeof *a);
        memcpy(va, vb, n * sizeof *va);
    }
    for (size_t i = 0; i < 3 * n; ++i) {
        ref[i] = a[i] * tr_post_demod_factor(g.albedo[i]);
    }
    d = worst_rel(out, ref, 3 * n);
    CHECK(d < 1e-5, "svgf: host and operator differ by %g", d);
    free(out);
    free(ref);
    free(a);
    free(b);
    free(va);
    free(vb);
    free(mom);
    free(len);
    tr_gbuffer_free(&g);
}

static void test_filters(void) {
    tr_gbuffer g;
    tr_error err;
    CHECK(tr_gbuffer_init(&g, W, H, &err) == TR_OK, "%s", err.msg);
    float *out = malloc(3 * W * H * sizeof *out), *out1 = malloc(3 * W * H * sizeof *out);
    for (int m = TR_RECON_ACCUMULATE; m < TR_RECON_COUNT; ++m) {
        const char *name = tr_recon_name(m);
        /* Constant: the normalised weights give the constant back. */
        synth(&g, 0.4f, 0.4f, 0.0f, 1);
        run_method(&g, m, out, 2);
        double worst = 0.0;
        for (size_t i = 0; i < 3 * W * H; ++i) {
            worst = fmax(worst, fabs(out[i] - 0.4));
        }
        CHECK(worst < 1e-5, "%s: constant image changed by %g", name, worst);
        /* Noisy: the mean stays within 1 %. */
        synth(&g, 0.4f, 0.4f, 0.3f, 2);
        const double m0 = mean(g.color, W * H);
        run_method(&g, m, out, 2);
        const double m1 = mean(out, W * H);
        CHECK(fabs(m1 - m0) <= 0.01 * m0, "%s: mean %g -> %g", name, m0, m1);
        /* The thread count changes nothing, bit for bit. */
        run_method(&g, m, out1, 1);
        CHECK(memcmp(out, out1, 3 * W * H * sizeof *out) == 0, "%s: 1 and 2 threads differ", name);
        if (m == TR_RECON_ACCUMULATE) {
            continue;
        }
        /* A step in depth, normal and colour: the two columns next to the edge keep their
         * side's colour (a blur across would pull each towards 0.5). The noise is small
         * enough for the bilateral filter's colour weight to see the step too. */
        synth(&g, 0.2f, 0.8f, 0.05f, 3);
        run_method(&g, m, out, 2);
        const double l = column_mean(out, W / 2 - 2, W / 2), r = column_mean(out, W / 2, W / 2 + 2);
        CHECK(fabs(l - 0.2) < 0.03 && fabs(r - 0.8) < 0.03, "%s: edge blurred: %g | %g", name, l,
              r);
    }
    /* A dark texture under even light with a specular part: the blue channel's base colour
     * alternates between 0.02 and 10^-4 in a checker, the light is a + 0.01 (the 0.01
     * reflected whatever the base colour). Noise-free, so every filter should give it
     * back nearly as it is. Demodulated by the albedo itself, a 10^-4 pixel took its
     * neighbours' illumination, 1.5 (0.03 / 0.02), back undivided: 0.75, not 0.0101. */
    for (int m = TR_RECON_ATROUS; m <= TR_RECON_SVGF; ++m) {
        synth(&g, 0.4f, 0.4f, 0.0f, 5);
        for (int y = 0; y < H; ++y) {
            for (int x = 0; x < W; ++x) {
                const size_t i = (size_t)y * W + x;
                g.albedo[3 * i + 2] = (x + y) % 2 ? 0.02f : 1e-4f;
                g.color[3 * i + 2] = g.albedo[3 * i + 2] + 0.01f;
            }
        }
        run_method(&g, m, out, 2);
        double worst = 0.0;
        for (size_t i = 0; i < W * H; ++i) {
            worst = fmax(worst, out[3 * i + 2] / g.color[3 * i + 2]);
        }
        CHECK(worst < 2.0, "%s: a dark texture's blue channel brightened %gx", tr_recon_name(m),
              worst);
    }
    /* Noisier and guided by geometry only: à-trous and SVGF still keep the edge where
     * the colour difference alone is within the noise. */
    for (int m = TR_RECON_ATROUS; m <= TR_RECON_SVGF; ++m) {
        synth(&g, 0.3f, 0.5f, 0.3f, 4);
        run_method(&g, m, out, 2);
        const double l = column_mean(out, W / 2 - 2, W / 2), r = column_mean(out, W / 2, W / 2 + 2);
        CHECK(fabs(l - 0.3) < 0.05 && fabs(r - 0.5) < 0.05, "%s: noisy edge blurred: %g | %g",
              tr_recon_name(m), l, r);
    }
    free(out);
    free(out1);
    tr_gbuffer_free(&g);
}

/* Renders `spp` samples (first sample `first`) of scene through cam into g. */
static void render_g(const tr_scene *s, const tr_camera *cam, uint32_t first, uint32_t spp,
                     tr_gbuffer *g) {
    tr_film f;
    tr_error err;
    CHECK(tr_film_init_passes(&f, cam->screen_width, cam->screen_height, TR_PASS_ALL, &err) ==
              TR_OK,
          "%s", err.msg);
    tr_render_config cfg = tr_render_config_default();
    cfg.passes = TR_PASS_ALL;
    cfg.threads = 2;
    for (uint32_t k = 0; k < spp; ++k) {
        CHECK(tr_render_frame(s, cam, &cfg, &f, first + k, NULL, &err) == TR_OK, "%s", err.msg);
    }
    CHECK(tr_gbuffer_from_film(g, &f, &err) == TR_OK, "%s", err.msg);
    tr_film_free(&f);
}

static tr_scene *cornell(tr_error *err) {
    return classic_box(W, H, err);
}

/* A camera at pos looking along dir with a's field of view and a's handedness. */
static tr_camera like(const tr_camera *a, tr_vec3 pos, tr_vec3 dir) {
    tr_camera b;
    tr_error err;
    CHECK(tr_camera_make(&b, pos, dir, a->world_up, a->vertical_fov, a->near_dist, a->far_dist, W,
                         H, &err) == TR_OK,
          "%s", err.msg);
    b.right = a->right.x < 0.0f ? tr_vec3_make(-b.right.x, -b.right.y, -b.right.z) : b.right;
    return b;
}

static void test_reprojection(void) {
    tr_error err;
    tr_scene *s = cornell(&err);
    const tr_camera a = *tr_scene_camera(s);
    /* B: a step sideways and up, so that the boxes' edges move against the walls. */
    const tr_camera b = like(&a, tr_vec3_make(a.pos.x + 20.0f, a.pos.y + 12.0f, a.pos.z), a.dir);
    tr_gbuffer ga, gb;
    CHECK(tr_gbuffer_init(&ga, W, H, &err) == TR_OK && tr_gbuffer_init(&gb, W, H, &err) == TR_OK,
          "%s", err.msg);
    /* One sample: depth and primitive belong to the same ray, as in a real-time frame. */
    render_g(s, &a, 0, 1, &ga);
    render_g(s, &b, 0, 1, &gb);
    int hits = 0, survived = 0, occluded = 0, occluded_rejected = 0, mirrored_survived = 0;
    tr_camera am = a; /* a wrong previous camera: a's image mirrored */
    am.right = tr_vec3_make(-a.right.x, -a.right.y, -a.right.z);
    for (uint32_t y = 0; y < H; ++y) {
        for (uint32_t x = 0; x < W; ++x) {
            const size_t i = (size_t)y * W + x;
            if (!(gb.depth[i] > 0.0f)) {
                continue;
            }
            ++hits;
            const tr_vec3 n =
                tr_vec3_make(gb.normal[3 * i], gb.normal[3 * i + 1], gb.normal[3 * i + 2]);
            float wt[4];
            int x0, y0;
            const float total = tr_post_reproject(&b, &a, x, y, gb.depth[i], n, gb.prim[i],
                                                  ga.depth, ga.normal, ga.prim, &x0, &y0, wt);
            for (int k = 0; k < 4; ++k) {
                if (wt[k] > 0.0f) {
                    const size_t j = (size_t)(y0 + (k >> 1)) * W + (size_t)(x0 + (k & 1));
                    CHECK(ga.prim[j] == gb.prim[i], "(%u, %u): tap on primitive %u, not %u", x, y,
                          ga.prim[j] - 1, gb.prim[i] - 1);
                }
            }
            survived += total > 0.0f;
            /* Independently of the taps: where does the point land in A, and is A's
             * surface there nearer than the point (it hid the point)? */
            const tr_vec3 p = tr_camera_point_at(&b, (float)x, (float)y, gb.depth[i]);
            float px, py, dist;
            if (tr_camera_project(&a, p, &px, &py, &dist) && px >= 0 && py >= 0 && px < W &&
                py < H) {
                const size_t j = (size_t)py * W + (size_t)px;
                if (ga.depth[j] > 0.0f && ga.depth[j] < 0.9f * dist) {
                    ++occluded;
                    /* Every tap within a pixel of it must see the nearer surface too,
                     * or the tap test rejects it: nothing survives. */
                    occluded_rejected += total == 0.0f || wt[0] + wt[1] + wt[2] + wt[3] < 1.0f;
                }
            }
            mirrored_survived +=
                tr_post_reproject(&b, &am, x, y, gb.depth[i], n, gb.prim[i], ga.depth, ga.normal,
                                  ga.prim, &x0, &y0, wt) > 0.0f;
        }
    }
    CHECK(hits > W * H / 2, "only %d pixels hit something", hits);
    CHECK(survived > hits * 8 / 10, "only %d of %d pixels survived a small move", survived, hits);
    CHECK(occluded > 0, "the move disoccluded nothing: no test of rejection");
    CHECK(occluded_rejected == occluded, "%d of %d disoccluded pixels kept history",
          occluded - occluded_rejected, occluded);
    CHECK(mirrored_survived < survived / 2, "a mirrored previous camera kept %d of %d",
          mirrored_survived, survived);
    tr_gbuffer_free(&ga);
    tr_gbuffer_free(&gb);
    tr_scene_destroy(s);
}

/* The host's temporal stage (filter.c: points computed once per frame and kept,
 * projection vectorised) against tr_post_temporal_pixel run on every pixel: the same
 * colour, moments and length, bit for bit, over a camera path with a move that
 * disoccludes, a turn, and a frame from the side where much history fails. */
static void test_temporal_host(void) {
    tr_error err;
    tr_scene *s = cornell(&err);
    const tr_camera a = *tr_scene_camera(s);
    const tr_camera path[4] = {
        a, like(&a, tr_vec3_make(a.pos.x + 20.0f, a.pos.y + 12.0f, a.pos.z), a.dir),
        like(&a, tr_vec3_make(a.pos.x + 25.0f, a.pos.y + 10.0f, a.pos.z + 30.0f),
             tr_vec3_make(a.dir.x + 0.08f, a.dir.y - 0.03f, a.dir.z)),
        like(&a, tr_vec3_make(120.0f, 420.0f, -300.0f), tr_vec3_make(0.35f, -0.35f, 1.0f))};
    tr_gbuffer g[2];
    CHECK(tr_gbuffer_init(&g[0], W, H, &err) == TR_OK &&
              tr_gbuffer_init(&g[1], W, H, &err) == TR_OK,
          "%s", err.msg);
    const tr_recon_params p = tr_recon_params_default();
    tr_recon r;
    CHECK(tr_recon_init(&r, W, H, &err) == TR_OK, "%s", err.msg);
    float *out = malloc(3 * W * H * sizeof *out);
    float *pc = malloc(3 * W * H * sizeof *pc), *pm = malloc(2 * W * H * sizeof *pm);
    float *pl = malloc(W * H * sizeof *pl);
    int kept = 0, fresh = 0;
    for (int f = 0; f < 4; ++f) {
        tr_gbuffer *cur = &g[f & 1];
        const tr_gbuffer *old = &g[(f + 1) & 1];
        render_g(s, &path[f], 7 * (uint32_t)f, 1, cur);
        if (f > 0) { /* the history the frame will read */
            memcpy(pc, r.hist_color[r.cur], 3 * W * H * sizeof *pc);
            memcpy(pm, r.hist_moments[r.cur], 2 * W * H * sizeof *pm);
            memcpy(pl, r.hist_len[r.cur], W * H * sizeof *pl);
        }
        CHECK(tr_recon_frame(&r, cur, &path[f], TR_RECON_ACCUMULATE, &p, 2, out, &err) == TR_OK,
              "%s", err.msg);
        if (f == 0) {
            continue;
        }
        int bad = 0;
        for (uint32_t y = 0; y < H; ++y) {
            for (uint32_t x = 0; x < W; ++x) {
                const size_t i = (size_t)y * W + x;
                float c[3], m[2], l;
                /* r.illum still holds this frame's demodulated illumination. */
                tr_post_temporal_pixel(&path[f], &path[f - 1], x, y, r.illum, cur->normal,
                                       cur->depth, cur->prim, pc, pm, pl, old->depth, old->normal,
                                       old->prim, p.alpha_min, p.max_len, c, m, &l);
                const float *hc = r.hist_color[r.cur] + 3 * i, *hm = r.hist_moments[r.cur] + 2 * i;
                bad += c[0] != hc[0] || c[1] != hc[1] || c[2] != hc[2] || m[0] != hm[0] ||
                       m[1] != hm[1] || l != r.hist_len[r.cur][i];
                kept += l > 1.0f;
                fresh += l == 1.0f;
            }
        }
        CHECK(bad == 0, "frame %d: %d pixels differ from tr_post_temporal_pixel", f, bad);
    }
    /* Both branches were exercised: history kept and history rejected. */
    CHECK(kept > W * H && fresh > W * H / 4, "kept %d, fresh %d", kept, fresh);
    free(out);
    free(pc);
    free(pm);
    free(pl);
    tr_recon_free(&r);
    tr_gbuffer_free(&g[0]);
    tr_gbuffer_free(&g[1]);
    tr_scene_destroy(s);
}

/* Mean squared error of img against ref. */
static double mse(const float *img, const float *ref) {
    double s = 0.0;
    for (size_t i = 0; i < 3 * W * H; ++i) {
        const double d = fmin(fmax(img[i], 0.0), 1.0) - fmin(fmax(ref[i], 0.0), 1.0);
        s += d * d;
    }
    return s / (3.0 * W * H);
}

static void test_cut(void) {
    tr_error err;
    tr_scene *s = cornell(&err);
    const tr_camera a = *tr_scene_camera(s);
    /* B looks at the box from high up on its side: another view of the same scene. */
    const tr_camera b =
        like(&a, tr_vec3_make(120.0f, 420.0f, -300.0f), tr_vec3_make(0.35f, -0.35f, 1.0f));
    tr_gbuffer ref, g;
    CHECK(tr_gbuffer_init(&ref, W, H, &err) == TR_OK && tr_gbuffer_init(&g, W, H, &err) == TR_OK,
          "%s", err.msg);
    render_g(s, &b, 100000, 128, &ref);
    float *out = malloc(3 * W * H * sizeof *out);
    /* Every method, and last (m == TR_RECON_COUNT) SVGF with its temporal antialiasing,
     * whose own history must not carry the old view either. */
    for (int m = TR_RECON_ACCUMULATE; m <= TR_RECON_COUNT; ++m) {
        tr_recon_params p = tr_recon_params_default();
        if (m == TR_RECON_COUNT) {
            p.svgf_taa_alpha = 0.1f;
            p.svgf_feedback = 0;
        }
        const int method = m < TR_RECON_COUNT ? m : TR_RECON_SVGF;
        /* Fresh: 8 frames of B; cut: 12 frames of A, then the same 8 frames of B. */
        double fresh = 0.0, cut = 0.0;
        for (int run = 0; run < 2; ++run) {
            tr_recon r;
            CHECK(tr_recon_init(&r, W, H, &err) == TR_OK, "%s", err.msg);
            for (uint32_t f = 0; run == 1 && f < 12; ++f) {
                render_g(s, &a, 1000 + f, 1, &g);
                CHECK(tr_recon_frame(&r, &g, &a, method, &p, 2, out, &err) == TR_OK, "%s", err.msg);
            }
            for (uint32_t f = 0; f < 8; ++f) {
                render_g(s, &b, f, 1, &g);
                CHECK(tr_recon_frame(&r, &g, &b, method, &p, 2, out, &err) == TR_OK, "%s", err.msg);
            }
            *(run ? &cut : &fresh) = mse(out, ref.color);
            tr_recon_free(&r);
        }
        /* Feeding SVGF's filtered level back compounds its blur over a long history, and
         * pixels of B that A saw too (the same walls) keep theirs across the cut: a few
         * per cent more error than 8 fresh frames (5.3 % measured), hence 10 % there. */
        const double slack = method == TR_RECON_SVGF && p.svgf_feedback ? 1.10 : 1.05;
        CHECK(cut <= slack * fresh, "%s%s: 8 frames after a cut, MSE %g vs %g fresh",
              tr_recon_name(method), m == TR_RECON_COUNT ? " with TAA" : "", cut, fresh);
    }
    free(out);
    tr_gbuffer_free(&ref);
    tr_gbuffer_free(&g);
    tr_scene_destroy(s);
}

/* The albedo history (albedo_alpha): a static view whose albedo alternates between 0.2
 * and 0.8 from frame to frame, as a pixel on a texture's edge does under jitter, under
 * unit illumination (colour = albedo). Off, SVGF multiplies by each frame's sample, so
 * its output flips between 0.2 and 0.8; with the history at weight a = 0.35 the
 * output settles between the two-frame fixed points (0.8 + 0.2 (1 - a)) / (2 - a) =
 * 0.5636 and 0.4364, within 0.07 of the pixel's mean 0.5. */
static void test_albedo_history(void) {
    tr_error err;
    tr_scene *s = cornell(&err);
    const tr_camera cam = *tr_scene_camera(s);
    tr_gbuffer g;
    CHECK(tr_gbuffer_init(&g, W, H, &err) == TR_OK, "%s", err.msg);
    render_g(s, &cam, 0, 1, &g);
    g.has_emission = g.has_direct = g.has_specular = 0;
    float *out = malloc(3 * W * H * sizeof *out);
    for (int on = 0; on < 2; ++on) {
        tr_recon_params p = tr_recon_params_default();
        p.albedo_alpha = on ? 0.35f : 0.0f;
        tr_recon r;
        CHECK(tr_recon_init(&r, W, H, &err) == TR_OK, "%s", err.msg);
        int far = 0, kept = 0, total = 0;
        for (int f = 0; f < 24; ++f) {
            const float a = (f & 1) ? 0.8f : 0.2f;
            for (int i = 0; i < 3 * W * H; ++i) {
                g.albedo[i] = a;
                g.color[i] = a;
            }
            CHECK(tr_recon_frame(&r, &g, &cam, TR_RECON_SVGF, &p, 2, out, &err) == TR_OK, "%s",
                  err.msg);
            for (int i = 0; f >= 20 && i < W * H; ++i) {
                if (!(g.depth[i] > 0.0f)) {
                    continue; /* no surface: nothing to reproject */
                }
                total += 1;
                far += fabsf(out[3 * i] - 0.5f) > 0.07f;
                kept += fabsf(out[3 * i] - a) < 0.01f * a;
            }
        }
        if (on) {
            CHECK(total > W * H && far == 0,
                  "albedo history: %d of %d pixels more than 0.07 from the mean", far, total);
        } else {
            CHECK(total > W * H && kept == total,
                  "no albedo history: %d of %d pixels at the frame's own albedo", kept, total);
        }
        tr_recon_free(&r);
    }
    free(out);
    tr_gbuffer_free(&g);
    tr_scene_destroy(s);
}

/* The filmic curve: 0 stays black, it rises strictly until it reaches white, and a
 * display film written at exposure 0 holds exactly the bytes of the direct tonemap. */
static void test_filmic(void) {
    float prev = 0.0f;
    CHECK(tr_tonemap_curve(0.0f, 1.0f, TR_CURVE_FILMIC) == 0.0f, "filmic(0)");
    for (int k = 1; k <= 400; ++k) {
        const float x = 0.01f * (float)k * (float)k;
        const float y = tr_tonemap_curve(x, 1.0f, TR_CURVE_FILMIC);
        CHECK(y <= 1.0f && (y > prev || y == 1.0f), "filmic(%g) = %g after %g", x, y, prev);
        prev = y;
    }
    CHECK(tr_tonemap_curve(1e38f, 1.0f, TR_CURVE_FILMIC) == 1.0f &&
              tr_tonemap_curve(NAN, 1.0f, TR_CURVE_FILMIC) == 0.0f,
          "filmic at the ends");
    tr_film f, d;
    tr_error err;
    CHECK(tr_film_init(&f, W, H, &err) == TR_OK, "%s", err.msg);
    uint32_t s = 5;
    for (size_t i = 0; i < (size_t)W * H; ++i) {
        f.count[i] = i % 7;
        for (int k = 0; k < 3; ++k) {
            f.sum[3 * i + k] = 4.0f * unit(&s) * (float)f.count[i];
        }
    }
    static uint32_t direct[W * H], via[W * H];
    for (int curve = TR_TONEMAP_CLAMP; curve <= TR_TONEMAP_FILMIC; ++curve) {
        CHECK(tr_tonemap_film_curve(&f, 0, 0, W, H, 0.5f, curve, TR_PIXEL_ARGB8888, direct, W * 4,
                                    &err) == TR_OK &&
                  tr_tonemap_display_film(&f, 0.5f, curve, &d, &err) == TR_OK &&
                  tr_tonemap_film(&d, 0, 0, W, H, 0.0f, TR_PIXEL_ARGB8888, via, W * 4, &err) ==
                      TR_OK,
              "%s", err.msg);
        CHECK(memcmp(direct, via, sizeof direct) == 0, "curve %s: display film differs",
              tr_tonemap_curve_name(curve));
        tr_film_free(&d);
    }
    CHECK(tr_tonemap_curve_parse("filmic") == TR_TONEMAP_FILMIC &&
              tr_tonemap_curve_parse("aces") == -1,
          "tr_tonemap_curve_parse");
    tr_film_free(&f);
}

/* SSIM: 1 for identical images, lower with more noise, symmetric. */
static void test_ssim(void) {
    tr_gbuffer g;
    tr_error err;
    CHECK(tr_gbuffer_init(&g, W, H, &err) == TR_OK, "%s", err.msg);
    synth(&g, 0.3f, 0.7f, 0.0f, 1);
    float *clean = malloc(3 * W * H * sizeof *clean);
    memcpy(clean, g.color, 3 * W * H * sizeof *clean);
    CHECK_NEAR(tr_ssim(clean, clean, W, H), 1.0, 1e-9, "ssim of an image with itself");
    double last = 1.0;
    for (int k = 1; k <= 3; ++k) {
        synth(&g, 0.3f, 0.7f, 0.1f * (float)k, 7);
        const double v = tr_ssim(g.color, clean, W, H);
        CHECK(v < last && v > 0.0, "ssim at noise %g: %g after %g", 0.1 * k, v, last);
        CHECK_NEAR(tr_ssim(clean, g.color, W, H), v, 1e-9, "ssim symmetric");
        last = v;
    }
    free(clean);
    tr_gbuffer_free(&g);
}

static void test_errors(void) {
    tr_recon r;
    tr_gbuffer g;
    tr_error err;
    CHECK(tr_recon_init(&r, W, H, &err) == TR_OK && tr_gbuffer_init(&g, W + 1, H, &err) == TR_OK,
          "%s", err.msg);
    const tr_camera cam = front_camera();
    const tr_recon_params p = tr_recon_params_default();
    float *out = malloc(3 * (W + 1) * H * sizeof *out);
    CHECK_STATUS(tr_recon_frame(&r, &g, &cam, TR_RECON_SVGF, &p, 1, out, &err), err,
                 TR_STATUS_INVALID_ARGUMENT, "size mismatch");
    tr_gbuffer_free(&g);
    CHECK(tr_gbuffer_init(&g, W, H, &err) == TR_OK, "%s", err.msg);
    CHECK_STATUS(tr_recon_frame(&r, &g, &cam, 9, &p, 1, out, &err), err, TR_STATUS_INVALID_ARGUMENT,
                 "unknown method");
    CHECK(tr_recon_parse("svgf") == TR_RECON_SVGF && tr_recon_parse("bogus") == -1,
          "tr_recon_parse");
    free(out);
    tr_gbuffer_free(&g);
    tr_recon_free(&r);
}

/* tr_recon.cancel's callback: counts its calls, fires from call number *user on (0: never). */
static int cancel_calls;
static int cancel_at(void *user) {
    cancel_calls += 1;
    const int at = *(const int *)user;
    return at > 0 && cancel_calls >= at;
}

static void test_cancel(void) {
    tr_error err;
    tr_scene *s = cornell(&err);
    const tr_camera a = *tr_scene_camera(s);
    const tr_camera path[3] = {
        a, like(&a, tr_vec3_make(a.pos.x + 20.0f, a.pos.y + 12.0f, a.pos.z), a.dir),
        like(&a, tr_vec3_make(a.pos.x + 30.0f, a.pos.y + 10.0f, a.pos.z + 20.0f), a.dir)};
    tr_gbuffer g[3];
    for (int f = 0; f < 3; ++f) {
        CHECK(tr_gbuffer_init(&g[f], W, H, &err) == TR_OK, "%s", err.msg);
        render_g(s, &path[f], 5 * (uint32_t)f, 1, &g[f]);
    }
    const int methods[2] = {TR_RECON_SVGF, TR_RECON_ATROUS};
    float *ref = malloc(3 * W * H * sizeof *ref), *out = malloc(3 * W * H * sizeof *out);
    for (int m = 0; m < 2; ++m) {
        tr_recon_params p = tr_recon_params_default();
        p.svgf_taa_alpha = 0.0f; /* TAA's history is the one a cancel drops */
        const int iterations =
            methods[m] == TR_RECON_SVGF ? p.svgf_iterations : p.atrous_iterations;
        CHECK(iterations >= 2, "method %d: %d iterations", methods[m], iterations);
        /* The reference: three frames, none cancelled. */
        tr_recon r;
        CHECK(tr_recon_init(&r, W, H, &err) == TR_OK, "%s", err.msg);
        for (int f = 0; f < 3; ++f) {
            CHECK(tr_recon_frame(&r, &g[f], &path[f], methods[m], &p, 2, ref, &err) == TR_OK, "%s",
                  err.msg);
        }
        tr_recon_free(&r);
        /* The middle frame cancelled at the first question; a hook that never fires on the
         * others. */
        CHECK(tr_recon_init(&r, W, H, &err) == TR_OK, "%s", err.msg);
        int never = 0, first = 1;
        r.cancel = cancel_at;
        r.cancel_user = &never;
        cancel_calls = 0;
        CHECK(tr_recon_frame(&r, &g[0], &path[0], methods[m], &p, 2, out, &err) == TR_OK, "%s",
              err.msg);
        CHECK(cancel_calls >= iterations - 1, "method %d: asked %d times over %d iterations",
              methods[m], cancel_calls, iterations);
        cancel_calls = 0;
        r.cancel_user = &first;
        err.code = TR_STATUS_OK;
        const int rc = tr_recon_frame(&r, &g[1], &path[1], methods[m], &p, 2, out, &err);
        CHECK(rc == TR_ERR && err.code == TR_STATUS_CANCELLED, "method %d: cancel gave %d (%d)",
              methods[m], rc, (int)err.code);
        CHECK(cancel_calls >= 1, "method %d: the cancel was never asked", methods[m]);
        r.cancel_user = &never;
        CHECK(tr_recon_frame(&r, &g[2], &path[2], methods[m], &p, 2, out, &err) == TR_OK, "%s",
              err.msg);
        /* The history (SVGF's first iteration fed back into it) is the same either way. */
        CHECK(memcmp(out, ref, 3 * W * H * sizeof *out) == 0,
              "method %d: the frame after a cancelled one differs from the uncancelled run's",
              methods[m]);
        tr_recon_free(&r);
    }
    free(ref);
    free(out);
    for (int f = 0; f < 3; ++f) {
        tr_gbuffer_free(&g[f]);
    }
    tr_scene_destroy(s);
}

int main(void) {
    test_cancel();
    test_filters();
    test_operators();
    test_reprojection();
    test_temporal_host();
    test_cut();
    test_albedo_history();
    test_filmic();
    test_ssim();
    test_errors();
    return check_finish("test_recon");
}
