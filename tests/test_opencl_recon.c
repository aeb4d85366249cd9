/* test_opencl_recon.c - the reconstruction on an OpenCL device (src/post/recon.cl,
 * recon_opencl.c) on PoCL (or whatever device 0 is) against the host's (filter.c).
 *
 * 1. The same frames (the classic Cornell box at 1 spp, passes included, under a moving
 *    camera) through every method on the host and on the device agree to float
 *    rounding, frame after frame: the temporal stage, the history kept on the device,
 *    SVGF's feedback and TAA included. The host's filters are filter.h's per-pixel
 *    operators with their loops turned round (test_recon: within 1e-5); the device runs
 *    those operators, compiled with the same FP_CONTRACT off and correctly rounded
 *    division and square root, so what remains is the rounding of a few operations
 *    done in another order (the host's vectorised sums, its reciprocals), ~1e-7
 *    relative per operation, grown through up to 5 filter iterations and 4 frames of
 *    history: a bound of 1e-4 relative to max(1, |value|) (the images are radiance in
 *    [0, ~10]) leaves that two orders of magnitude, while a filter that differed in any
 *    weight or tap differs by 1e-2 and more (checked: every method changes the frame by
 *    far more than the bound).
 * 2. The device's own film, reconstructed where it lies, gives what the host gives on
 *    the same film read back; also with the emission pass, which the device resolves on
 *    emitters' edges (tr_cl_resolve_emission) and the host by tr_resolve_emission.
 * 3. On the CPU device tr_recon_device is tr_recon_frame, bit for bit (with the emission
 *    pass: tr_resolve_emission, then tr_recon_frame).
 * 4. A frame or camera of another size and an unknown method fail with a message.
 * 5. Per-primitive motion (a sphere moving in front of a wall, tests/motion_scene.h):
 *    host and device agree with the motion table as in 1.
 * 6. SVGF's albedo history (albedo_alpha) agrees as in 1 on frames whose albedo
 *    alternates from frame to frame.
 * 7. SVGF with direct and indirect light apart (svgf_split) agrees as in 1 (with TAA too)
 *    and as in 2 on the device's film with its direct and emission passes; the split
 *    changes the host's output by far more than the bound, so both sides do split.
 * 8. The same for diffuse and specular light apart (svgf_specular) on the box with glossy
 *    walls (roughness 0.3), the specular pass written by the device's own kernel in 2.
 *
 * Needs an OpenCL platform; it fails (not skips) when no device can be opened. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "classic_box.h"
#include "motion_scene.h"
#include "trac0r/scene_file.h"
#include "trac0r/trac0r.h"

#define W MOTION_W
#define H MOTION_H
#define FRAMES 4

static const double bound = 1e-4;

static tr_scene *cornell(tr_error *err) {
    return classic_box(W, H, err);
}

/* Frame k's camera: the scene's, moved sideways and turned a little more each frame. */
static tr_camera camera_at(const tr_camera *a, int k) {
    tr_camera b;
    tr_error err;
    const tr_vec3 pos =
        tr_vec3_make(a->pos.x + 6.0f * (float)k, a->pos.y + 2.0f * (float)k, a->pos.z);
    const tr_vec3 dir = tr_vec3_make(a->dir.x + 0.01f * (float)k, a->dir.y, a->dir.z);
    CHECK(tr_camera_make(&b, pos, dir, a->world_up, a->vertical_fov, a->near_dist, a->far_dist, W,
                         H, &err) == TR_OK,
          "%s", err.msg);
    b.right = a->right.x < 0.0f ? tr_vec3_make(-b.right.x, -b.right.y, -b.right.z) : b.right;
    return b;
}

/* The classic box with its diffuse walls glossy (GGX, roughness 0.3): light for the
 * specular split. */
static tr_scene *glossy_box(tr_error *err) {
    const char *path = TR_SOURCE_DIR "/scenes/cornell-classic.json";
    FILE *f = fopen(path, "rb");
    char *text = calloc(1, 1u << 16), *out = calloc(1, 1u << 17);
    CHECK(f && text && out, "reading %s", path);
    const size_t len = f && text ? fread(text, 1, (1u << 16) - 1, f) : 0;
    if (f) {
        fclose(f);
    }
    static const char from[] = "\"type\": \"diffuse\"",
                      to[] = "\"type\": \"glossy\", \"roughness\": 0.3";
    size_t n = 0, swapped = 0;
    for (const char *p = text; text && out && *p;) {
        if (strncmp(p, from, sizeof from - 1) == 0) {
            memcpy(out + n, to, sizeof to - 1);
            n += sizeof to - 1;
            p += sizeof from - 1;
            ++swapped;
        } else {
            out[n++] = *p++;
        }
    }
    CHECK(len > 0 && swapped >= 3, "%zu diffuse materials made glossy", swapped);
    tr_scene *s = tr_scene_create(err);
    CHECK(s && tr_scene_file_parse(s, path, out, n, NULL, NULL, err) == TR_OK, "glossy box: %s",
          err->msg);
    free(text);
    free(out);
    tr_camera cam = *tr_scene_camera(s);
    CHECK(tr_camera_resize(&cam, W, H, err) == TR_OK, "%s", err->msg);
    tr_scene_set_camera(s, &cam);
    CHECK(tr_scene_commit(s, TR_ACCEL_TYPE_BVH, err) == TR_OK, "commit: %s", err->msg);
    return s;
}

static void render_g(const tr_scene *s, const tr_camera *cam, uint32_t sample, tr_gbuffer *g) {
    tr_film f;
    tr_error err;
    const uint32_t passes = TR_PASS_ALL | TR_PASS_DIRECT | TR_PASS_SPECULAR;
    CHECK(tr_film_init_passes(&f, W, H, passes, &err) == TR_OK, "%s", err.msg);
    tr_render_config cfg = tr_render_config_default();
    cfg.passes = passes;
    cfg.threads = 2;
    CHECK(tr_render_frame(s, cam, &cfg, &f, sample, NULL, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_gbuffer_init(g, W, H, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_gbuffer_from_film(g, &f, &err) == TR_OK, "%s", err.msg);
    tr_film_free(&f);
}

/* The largest difference of a from b relative to max(1, |b|). */
static double worst_rel(const float *a, const float *b, size_t n) {
    double worst = 0.0;
    for (size_t i = 0; i < n; ++i) {
        const double d = fabs((double)a[i] - b[i]) / fmax(1.0, fabs((double)b[i]));
        worst = d > worst || d != d ? (d != d ? INFINITY : d) : worst;
    }
    return worst;
}

/* Section 1: one method over FRAMES frames on both sides. */
static void agree(tr_device *cl, const tr_gbuffer *g, const tr_camera *cams, int method,
                  const tr_recon_params *p, const char *label) {
    tr_error err;
    tr_recon host;
    CHECK(tr_recon_init(&host, W, H, &err) == TR_OK, "%s", err.msg);
    tr_recon_device *dev = tr_recon_device_create(cl, W, H, &err);
    CHECK(dev, "tr_recon_device_create: %s", err.msg);
    CHECK(tr_recon_device_on_device(dev), "%s: the OpenCL state runs on the host", label);
    float *a = malloc(3 * W * H * sizeof *a), *b = malloc(3 * W * H * sizeof *b);
    CHECK(a && b, "out of memory");
    double worst = 0.0, change = 0.0;
    for (int k = 0; k < FRAMES; ++k) {
        CHECK(tr_recon_frame(&host, &g[k], &cams[k], method, p, 2, a, &err) == TR_OK, "%s",
              err.msg);
        CHECK(tr_recon_device_frame_gbuffer(dev, &g[k], &cams[k], NULL, 0, method, p, b, &err) ==
                  TR_OK,
              "%s: %s", label, err.msg);
        const double d = worst_rel(b, a, 3 * W * H);
        CHECK(d <= bound, "%s, frame %d: device and host differ by %.3g (relative) > %.1g", label,
              k, d, bound);
        worst = fmax(worst, d);
        change = fmax(change, worst_rel(a, g[k].color, 3 * W * H));
    }
    /* The bound is not vacuous: the method changed the frames by far more. */
    if (method != TR_RECON_OFF) {
        CHECK(change > 100.0 * bound, "%s changed the frames by only %.3g", label, change);
    } else {
        CHECK(worst == 0.0, "off: the device's frame differs from the input by %.3g", worst);
    }
    printf("  %-12s worst relative difference %.3g (the method changes the frame by %.3g)\n", label,
           worst, change);
    free(a);
    free(b);
    tr_recon_device_destroy(dev);
    tr_recon_free(&host);
}

/* Sections 7 and 8: on the host, SVGF with a split (p) and without differ by far more
 * than the bound, by the last frame: the split is not a no-op. */
static void split_changes(const tr_gbuffer *g, const tr_camera *cams, const tr_recon_params *p) {
    tr_error err;
    tr_recon split, sum;
    CHECK(tr_recon_init(&split, W, H, &err) == TR_OK && tr_recon_init(&sum, W, H, &err) == TR_OK,
          "%s", err.msg);
    const tr_recon_params q = tr_recon_params_default();
    float *a = malloc(3 * W * H * sizeof *a), *b = malloc(3 * W * H * sizeof *b);
    CHECK(a && b, "out of memory");
    for (int k = 0; k < FRAMES; ++k) {
        CHECK(g[k].has_direct && g[k].has_specular, "frame %d lacks a pass", k);
        CHECK(tr_recon_frame(&split, &g[k], &cams[k], TR_RECON_SVGF, p, 2, a, &err) == TR_OK &&
                  tr_recon_frame(&sum, &g[k], &cams[k], TR_RECON_SVGF, &q, 2, b, &err) == TR_OK,
              "%s", err.msg);
    }
    const double d = worst_rel(a, b, 3 * W * H);
    CHECK(d > 100.0 * bound, "the split changed SVGF's output by only %.3g", d);
    printf("  the split changes SVGF's output by %.3g\n", d);
    free(a);
    free(b);
    tr_recon_free(&split);
    tr_recon_free(&sum);
}

/* Frames 0..frames-1 rendered on device d (spp samples each, from sample spp*k) and
 * reconstructed by SVGF through `dev` on the device's own film, and, read back, through
 * the host's tr_recon_frame with `threads`: every frame's output must agree within
 * `tol` relative (0: bit for bit). */
static void film_frames(tr_device *d, tr_recon_device *dev, const tr_camera *cams, int frames,
                        uint32_t spp, int threads, double tol, const tr_scene *emission, int apart,
                        const char *label) {
    tr_error err;
    tr_recon host;
    tr_gbuffer g;
    tr_film f;
    /* With `emission` (the scene) the film keeps the emission pass and both sides resolve
     * it (the device in tr_recon_device_frame, the host by tr_resolve_emission). */
    /* apart 1: the film keeps the direct pass and SVGF filters direct and indirect light
     * apart; 2: the specular pass, diffuse and specular light apart. */
    const uint32_t passes = TR_PASS_ALL | (emission ? TR_PASS_EMISSION : 0u) |
                            (apart == 1 ? TR_PASS_DIRECT : 0u) |
                            (apart == 2 ? TR_PASS_SPECULAR : 0u);
    CHECK(tr_recon_init(&host, W, H, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_gbuffer_init(&g, W, H, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_film_init_passes(&f, W, H, passes, &err) == TR_OK, "%s", err.msg);
    tr_render_config cfg = tr_render_config_default();
    cfg.passes = passes;
    tr_recon_params p = tr_recon_params_default();
    p.svgf_split = apart == 1;
    p.svgf_specular = apart == 2;
    float *a = malloc(3 * W * H * sizeof *a), *b = malloc(3 * W * H * sizeof *b);
    CHECK(a && b, "out of memory");
    for (int k = 0; k < frames; ++k) {
        /* The OpenCL device has no film to clear before its first render. */
        CHECK(tr_device_clear(d, &err) == TR_OK || (k == 0 && tol > 0.0), "%s", err.msg);
        CHECK(tr_device_render(d, &cams[k], &cfg, spp * (uint32_t)k, spp, NULL, NULL, &err) ==
                  TR_OK,
              "%s", err.msg);
        CHECK(tr_recon_device_frame(dev, &cams[k], NULL, 0, TR_RECON_SVGF, &p, b, &err) == TR_OK,
              "%s", err.msg);
        CHECK(tr_device_read_film(d, &f, &err) == TR_OK, "%s", err.msg);
        CHECK(tr_gbuffer_from_film(&g, &f, &err) == TR_OK, "%s", err.msg);
        CHECK(!emission || tr_resolve_emission(emission, &cams[k], p.emission_samples, threads, &g,
                                               NULL, &err) == TR_OK,
              "%s", err.msg);
        CHECK(tr_recon_frame(&host, &g, &cams[k], TR_RECON_SVGF, &p, threads, a, &err) == TR_OK,
              "%s", err.msg);
        if (tol > 0.0) {
            const double diff = worst_rel(b, a, 3 * W * H);
            CHECK(diff <= tol, "%s, frame %d: differs by %.3g > %.1g", label, k, diff, tol);
        } else {
            CHECK(memcmp(a, b, 3 * W * H * sizeof *a) == 0, "%s, frame %d: not bit-identical",
                  label, k);
        }
    }
    free(a);
    free(b);
    tr_film_free(&f);
    tr_gbuffer_free(&g);
    tr_recon_free(&host);
}

/* Section 2: the device's film, where it lies, against the same film on the host. */
static void film_on_device(tr_device *cl, const tr_scene *s, const tr_camera *cams) {
    tr_error err;
    CHECK(tr_device_upload(cl, s, &err) == TR_OK, "%s", err.msg);
    tr_recon_device *dev = tr_recon_device_create(cl, W, H, &err);
    CHECK(dev, "%s", err.msg);
    /* Two samples, so that the film's means divide by a count above 1. */
    film_frames(cl, dev, cams, FRAMES, 2, 2, bound, NULL, 0, "film on the device");
    /* The emission pass, resolved on the device as on the host (tr_cl_resolve_emission
     * against tr_resolve_emission: the same per-pixel code, src/kernel/emission.h). */
    tr_recon_device_clear(dev);
    film_frames(cl, dev, cams, FRAMES, 1, 2, bound, s, 0, "emission resolved on the device");
    /* Section 7: direct and indirect apart on the device's film, the emission taken out of
     * both (a history kept without the split starts over). */
    film_frames(cl, dev, cams, FRAMES, 1, 2, bound, s, 1, "split on the device's film");
    /* Section 8: diffuse and specular apart, the specular pass the device's, on the glossy
     * box. */
    tr_scene *glossy = glossy_box(&err);
    CHECK(tr_device_upload(cl, glossy, &err) == TR_OK, "%s", err.msg);
    tr_recon_device_clear(dev);
    film_frames(cl, dev, cams, FRAMES, 1, 2, bound, glossy, 2,
                "specular apart on the device's film");
    tr_scene_destroy(glossy);
    CHECK(tr_device_upload(cl, s, &err) == TR_OK, "%s", err.msg);
    double ms_t, ms_s;
    tr_recon_device_times(dev, &ms_t, &ms_s);
    CHECK(ms_t >= 0.0 && ms_s >= 0.0, "negative stage times %g %g", ms_t, ms_s);
    /* Section 4: bad input. */
    const tr_recon_params p = tr_recon_params_default();
    float *b = malloc(3 * W * H * sizeof *b);
    CHECK(b, "out of memory");
    tr_camera small = cams[0];
    small.screen_width = W / 2;
    CHECK(tr_recon_device_frame(dev, &small, NULL, 0, TR_RECON_SVGF, &p, b, &err) == TR_ERR &&
              err.code == TR_STATUS_INVALID_ARGUMENT,
          "a camera of another size was accepted");
    CHECK(tr_recon_device_frame(dev, &cams[0], NULL, 0, 99, &p, b, &err) == TR_ERR &&
              err.code == TR_STATUS_INVALID_ARGUMENT,
          "method 99 was accepted");
    tr_recon_device *wrong = tr_recon_device_create(cl, W + 1, H, &err);
    CHECK(wrong, "%s", err.msg);
    CHECK(tr_recon_device_frame(wrong, &cams[0], NULL, 0, TR_RECON_SVGF, &p, b, &err) == TR_ERR,
          "a film of another size was accepted");
    tr_recon_device_destroy(wrong);
    free(b);
    tr_recon_device_destroy(dev);
}

/* Section 3: the CPU device's state is the host's, bit for bit. */
static void cpu_device(const tr_scene *s, const tr_camera *cams) {
    tr_error err;
    tr_device *cpu = tr_device_create("cpu", &err);
    CHECK(cpu && tr_device_upload(cpu, s, &err) == TR_OK, "%s", err.msg);
    tr_recon_device *dev = tr_recon_device_create(cpu, W, H, &err);
    CHECK(dev && !tr_recon_device_on_device(dev), "%s", err.msg);
    film_frames(cpu, dev, cams, 2, 1, 0, 0.0, NULL, 0, "cpu device");
    tr_recon_device_clear(dev);
    film_frames(cpu, dev, cams, 2, 1, 0, 0.0, s, 0, "cpu device, emission resolved");
    tr_recon_device_destroy(dev);
    tr_device_destroy(cpu);
}

/* Section 5: the moving sphere with its motion, host against device. */
static void moving(tr_device *cl) {
    tr_camera cam;
    uint32_t first, count;
    tr_scene *s = motion_scene(&cam, &first, &count);
    tr_vec3 *table = motion_table(first, count);
    const uint32_t ids = first + count + 1;
    tr_error err;
    /* A moving surface's history capped below FRAMES, so that both sides apply the cap. */
    tr_recon_params p = tr_recon_params_default();
    p.max_len_moving = 2.0f;
    const int methods[2] = {TR_RECON_ACCUMULATE, TR_RECON_SVGF};
    tr_recon host[2];
    tr_recon_device *dev[2];
    for (int m = 0; m < 2; ++m) {
        CHECK(tr_recon_init(&host[m], W, H, &err) == TR_OK, "%s", err.msg);
        dev[m] = tr_recon_device_create(cl, W, H, &err);
        CHECK(dev[m], "%s", err.msg);
    }
    float *a = malloc(3 * W * H * sizeof *a), *b = malloc(3 * W * H * sizeof *b);
    CHECK(a && b, "out of memory");
    double worst = 0.0;
    for (int k = 0; k < FRAMES; ++k) {
        tr_gbuffer g;
        motion_frame(s, &cam, k, &g);
        for (int m = 0; m < 2; ++m) {
            CHECK(tr_recon_frame_moving(&host[m], &g, &cam, k ? table : NULL, ids, methods[m], &p,
                                        2, a, &err) == TR_OK,
                  "%s", err.msg);
            CHECK(tr_recon_device_frame_gbuffer(dev[m], &g, &cam, k ? table : NULL, ids, methods[m],
                                                &p, b, &err) == TR_OK,
                  "%s", err.msg);
            const double d = worst_rel(b, a, 3 * W * H);
            CHECK(d <= bound, "moving sphere, %s, frame %d: differs by %.3g > %.1g",
                  tr_recon_name(methods[m]), k, d, bound);
            worst = fmax(worst, d);
        }
        tr_gbuffer_free(&g);
    }
    printf("  moving sphere with its motion: worst relative difference %.3g\n", worst);
    for (int m = 0; m < 2; ++m) {
        tr_recon_free(&host[m]);
        tr_recon_device_destroy(dev[m]);
    }
    free(a);
    free(b);
    free(table);
    tr_scene_destroy(s);
}

int main(void) {
    tr_error err;
    tr_scene *s = cornell(&err);
    tr_camera cams[FRAMES];
    tr_gbuffer g[FRAMES];
    for (int k = 0; k < FRAMES; ++k) {
        cams[k] = camera_at(tr_scene_camera(s), k);
        render_g(s, &cams[k], (uint32_t)k, &g[k]);
    }
    tr_device *cl = tr_device_create("opencl:0", &err);
    CHECK(cl, "no OpenCL device: %s", err.msg);
    printf("OpenCL device: %s\n", tr_device_get_info(cl)->model);

    tr_recon_params p = tr_recon_params_default();
    agree(cl, g, cams, TR_RECON_OFF, &p, "off");
    agree(cl, g, cams, TR_RECON_ACCUMULATE, &p, "accumulate");
    agree(cl, g, cams, TR_RECON_BILATERAL, &p, "bilateral");
    agree(cl, g, cams, TR_RECON_ATROUS, &p, "atrous");
    agree(cl, g, cams, TR_RECON_SVGF, &p, "svgf");
    p.svgf_taa_alpha = 0.3f;
    agree(cl, g, cams, TR_RECON_SVGF, &p, "svgf+taa");
    p = tr_recon_params_default();
    p.svgf_feedback = 0;
    agree(cl, g, cams, TR_RECON_SVGF, &p, "svgf-nofb");

    /* Section 7: direct and indirect apart. */
    p = tr_recon_params_default();
    p.svgf_split = 1;
    split_changes(g, cams, &p);
    agree(cl, g, cams, TR_RECON_SVGF, &p, "svgf-split");
    p.svgf_taa_alpha = 0.3f;
    agree(cl, g, cams, TR_RECON_SVGF, &p, "svgf-split+taa");
    /* Section 8: diffuse and specular apart, on the glossy box. */
    {
        tr_scene *glossy = glossy_box(&err);
        tr_gbuffer gg[FRAMES];
        for (int k = 0; k < FRAMES; ++k) {
            render_g(glossy, &cams[k], (uint32_t)k, &gg[k]);
        }
        p = tr_recon_params_default();
        p.svgf_specular = 1;
        split_changes(gg, cams, &p);
        agree(cl, gg, cams, TR_RECON_SVGF, &p, "svgf-specular");
        p.svgf_taa_alpha = 0.3f;
        agree(cl, gg, cams, TR_RECON_SVGF, &p, "svgf-specular+taa");
        for (int k = 0; k < FRAMES; ++k) {
            tr_gbuffer_free(&gg[k]);
        }
        tr_scene_destroy(glossy);
    }

    film_on_device(cl, s, cams);
    moving(cl);
    cpu_device(s, cams);

    /* The albedo history: the same views with each frame's albedo alternating between 0.2
     * and 0.8 under unit light (colour = albedo), as on a texture's edge under jitter. A
     * device that multiplied by the frame's own albedo would differ from the host's
     * history by 0.2 and more. */
    for (int k = 0; k < FRAMES; ++k) {
        for (int i = 0; i < 3 * W * H; ++i) {
            g[k].albedo[i] = g[k].color[i] = (k & 1) ? 0.8f : 0.2f;
        }
        g[k].has_emission = g[k].has_direct = g[k].has_specular = 0;
    }
    p = tr_recon_params_default();
    p.albedo_alpha = 0.35f;
    agree(cl, g, cams, TR_RECON_SVGF, &p, "svgf+albedo");
    p.svgf_taa_alpha = 0.3f;
    agree(cl, g, cams, TR_RECON_SVGF, &p, "svgf+albedo+taa");

    for (int k = 0; k < FRAMES; ++k) {
        tr_gbuffer_free(&g[k]);
    }
    tr_device_destroy(cl);
    tr_scene_destroy(s);
    return check_finish("test_opencl_recon");
}
