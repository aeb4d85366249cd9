/* test_defaults.c - a zero-initialised public config or desc means its _default(): the
 * builtin box rendered with a zeroed tr_render_config and with tr_render_config_default()
 * gives the same bits, on tr_render_frame and through the CPU device; a zeroed
 * tr_recon_params (the fields whose zero is a setting copied) filters a frame as the
 * defaults do. The integrator is the one field whose zero is a choice of its own
 * (TR_INTEGRATOR_NAIVE), as are some of tr_recon_params' (post.h lists them); a zeroed
 * tr_shape_desc is refused. */
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "trac0r/trac0r.h"

enum { W = 24, H = 18, SPP = 2 };

static int same_floats(const float *a, const float *b, size_t n) {
    return memcmp(a, b, n * sizeof *a) == 0;
}

static int same_films(const tr_film *a, const tr_film *b) {
    const size_t n = (size_t)a->width * a->height;
    return a->width == b->width && a->height == b->height && same_floats(a->sum, b->sum, 3 * n) &&
           memcmp(a->count, b->count, n * sizeof *a->count) == 0;
}

/* Samples 0..SPP-1 of the scene's camera with cfg, by tr_render_frame. */
static void render(const tr_scene *s, const tr_render_config *cfg, tr_film *f) {
    tr_error err;
    CHECK(tr_film_init(f, W, H, &err) == TR_OK, "%s", err.msg);
    for (uint32_t k = 0; k < SPP; ++k) {
        CHECK(tr_render_frame(s, tr_scene_camera(s), cfg, f, k, NULL, &err) == TR_OK, "%s",
              err.msg);
    }
}

/* The same frames through the "cpu" device. */
static void render_device(const tr_scene *s, const tr_render_config *cfg, tr_film *f) {
    tr_error err;
    CHECK(tr_film_init(f, W, H, &err) == TR_OK, "%s", err.msg);
    tr_device *dev = tr_device_create("cpu", &err);
    CHECK(dev != NULL, "%s", err.msg);
    if (!dev) {
        return;
    }
    CHECK(tr_device_upload(dev, s, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_device_render(dev, tr_scene_camera(s), cfg, 0, SPP, NULL, NULL, &err) == TR_OK, "%s",
          err.msg);
    CHECK(tr_device_read_film(dev, f, &err) == TR_OK, "%s", err.msg);
    tr_device_destroy(dev);
}

static void test_render_config(const tr_scene *s) {
    tr_render_config zero;
    memset(&zero, 0, sizeof zero);
    tr_error err;
    CHECK(tr_render_config_check(&zero, &err) == TR_OK, "a zeroed config is refused: %s", err.msg);

    /* Zero's integrator is naive; with pt set (the one field zero does not default), the
     * zeroed config is the default. */
    tr_render_config zero_pt = zero;
    zero_pt.integrator = TR_INTEGRATOR_PT;
    tr_render_config def = tr_render_config_default();
    tr_film a, b;
    render(s, &zero_pt, &a);
    render(s, &def, &b);
    CHECK(same_films(&a, &b), "pt: a zeroed config and the default render different bits");
    tr_film_free(&a);
    tr_film_free(&b);
    render_device(s, &zero_pt, &a);
    render_device(s, &def, &b);
    CHECK(same_films(&a, &b), "pt on the device: zeroed and default configs differ");
    tr_film_free(&a);
    tr_film_free(&b);

    /* The zeroed config as it is: the default with naive. */
    tr_render_config def_naive = tr_render_config_default();
    def_naive.integrator = TR_INTEGRATOR_NAIVE;
    render(s, &zero, &a);
    render(s, &def_naive, &b);
    CHECK(same_films(&a, &b), "naive: a zeroed config and the default render different bits");
    tr_film_free(&a);
    tr_film_free(&b);

    /* Stride 0 is stride 1, not a preview: a stride of 2 renders something else. */
    tr_render_config stride2 = zero_pt;
    stride2.stride = 2;
    render(s, &zero_pt, &a);
    render(s, &stride2, &b);
    CHECK(!same_films(&a, &b), "stride 2 renders what stride 0 does");
    tr_film_free(&a);
    tr_film_free(&b);

    /* Out of range is still refused. */
    tr_render_config bad = zero;
    bad.stride = -1;
    CHECK_STATUS(tr_render_config_check(&bad, &err), err, TR_STATUS_INVALID_ARGUMENT, "stride -1");
    bad.stride = 65;
    CHECK_STATUS(tr_render_config_check(&bad, &err), err, TR_STATUS_INVALID_ARGUMENT, "stride 65");
}

/* tr_shape_desc has no zero default: its type has none (tr_shape_desc_default takes it),
 * and a zero scale is refused rather than taken for the unit scale, so that a scene file's
 * "radius": 0 is an error and not a unit sphere. A zeroed desc, type set or not, fails. */
static void test_shape_desc(void) {
    tr_error err;
    tr_scene *s = tr_scene_create(&err);
    CHECK(s != NULL, "%s", err.msg);
    if (!s) {
        return;
    }
    uint32_t m = 0;
    CHECK(tr_scene_add_material(s, tr_material_diffuse(tr_vec3_make(0.5f, 0.5f, 0.5f)), &m, &err) ==
              TR_OK,
          "%s", err.msg);
    tr_shape_desc zero;
    memset(&zero, 0, sizeof zero);
    CHECK_STATUS(tr_scene_add_shape(s, &zero, &err), err, TR_STATUS_INVALID_ARGUMENT,
                 "a zeroed shape desc");
    zero.type = TR_SHAPE_BOX;
    CHECK_STATUS(tr_scene_add_shape(s, &zero, &err), err, TR_STATUS_INVALID_ARGUMENT,
                 "a zeroed box desc");
    const tr_shape_desc def = tr_shape_desc_default(TR_SHAPE_BOX);
    CHECK(tr_scene_add_shape(s, &def, &err) == TR_OK, "the default box: %s", err.msg);
    tr_scene_destroy(s);
}

static void test_recon_params(const tr_scene *s) {
    tr_error err;
    tr_film f;
    CHECK(tr_film_init_passes(&f, W, H, TR_PASS_ALBEDO | TR_PASS_NORMAL | TR_PASS_DEPTH, &err) ==
              TR_OK,
          "%s", err.msg);
    tr_render_config cfg = tr_render_config_default();
    cfg.passes = f.passes;
    CHECK(tr_render_frame(s, tr_scene_camera(s), &cfg, &f, 0, NULL, &err) == TR_OK, "%s", err.msg);
    tr_gbuffer g;
    CHECK(tr_gbuffer_init(&g, W, H, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_gbuffer_from_film(&g, &f, &err) == TR_OK, "%s", err.msg);

    const tr_recon_params def = tr_recon_params_default();
    tr_recon_params zero;
    memset(&zero, 0, sizeof zero);
    /* The fields whose zero is a setting of its own (post.h). */
    zero.alpha_min = def.alpha_min;
    zero.bilateral_radius = def.bilateral_radius;
    zero.atrous_iterations = def.atrous_iterations;
    zero.svgf_iterations = def.svgf_iterations;
    zero.svgf_sigma_l = def.svgf_sigma_l;
    zero.svgf_sigma_n = def.svgf_sigma_n;
    zero.svgf_sigma_z = def.svgf_sigma_z;
    zero.svgf_feedback = def.svgf_feedback;
    zero.svgf_alpha_min = def.svgf_alpha_min;
    zero.albedo_alpha = def.albedo_alpha;
    zero.upscale_albedo = def.upscale_albedo;
    zero.emission_samples = def.emission_samples;
    zero.svgf_taa_alpha = def.svgf_taa_alpha;
    zero.svgf_split = def.svgf_split;

    const size_t n = 3u * W * H;
    float *out_a = calloc(n, sizeof *out_a), *out_b = calloc(n, sizeof *out_b);
    CHECK(out_a && out_b, "out of memory");
    for (int method = TR_RECON_ACCUMULATE; out_a && out_b && method < TR_RECON_COUNT; ++method) {
        tr_recon ra, rb;
        CHECK(tr_recon_init(&ra, W, H, &err) == TR_OK, "%s", err.msg);
        CHECK(tr_recon_init(&rb, W, H, &err) == TR_OK, "%s", err.msg);
        /* Two frames: the second reads the history, where max_len matters. */
        for (int frame = 0; frame < 2; ++frame) {
            CHECK(tr_recon_frame(&ra, &g, tr_scene_camera(s), method, &zero, 1, out_a, &err) ==
                      TR_OK,
                  "%s: %s", tr_recon_name(method), err.msg);
            CHECK(tr_recon_frame(&rb, &g, tr_scene_camera(s), method, &def, 1, out_b, &err) ==
                      TR_OK,
                  "%s: %s", tr_recon_name(method), err.msg);
        }
        CHECK(same_floats(out_a, out_b, n), "%s: zeroed params filter otherwise than the defaults",
              tr_recon_name(method));
        tr_recon_free(&ra);
        tr_recon_free(&rb);
    }
    CHECK(out_a && tr_filter_bilateral(&g, g.color, out_a, &zero, 1, &err) == TR_OK, "%s", err.msg);
    CHECK(out_b && tr_filter_bilateral(&g, g.color, out_b, &def, 1, &err) == TR_OK, "%s", err.msg);
    CHECK(out_a && out_b && same_floats(out_a, out_b, n), "bilateral: zeroed params differ");
    CHECK(out_a && tr_filter_atrous(&g, g.color, out_a, &zero, 1, &err) == TR_OK, "%s", err.msg);
    CHECK(out_b && tr_filter_atrous(&g, g.color, out_b, &def, 1, &err) == TR_OK, "%s", err.msg);
    CHECK(out_a && out_b && same_floats(out_a, out_b, n), "a-trous: zeroed params differ");
    free(out_a);
    free(out_b);
    tr_gbuffer_free(&g);
    tr_film_free(&f);
}

int main(void) {
    tr_error err;
    tr_scene *s = tr_scene_create(&err);
    CHECK(s != NULL, "%s", err.msg);
    if (!s) {
        return check_finish("test_defaults");
    }
    CHECK(tr_scene_builtin(s, "cornell", W, H, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_scene_commit(s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
    test_render_config(s);
    test_shape_desc();
    test_recon_params(s);
    tr_scene_destroy(s);
    return check_finish("test_defaults");
}
