/* test_emission.c - the emission pass (TR_PASS_EMISSION), its resolution over the pixels'
 * area (tr_resolve_emission) and the reconstruction's use of both.
 *
 * 1. The pass is the first hit's emission: with max depth 1 pt adds nothing else, so the
 *    radiance of a max-depth-1 render is the emission pass of a max-depth-8 one on the
 *    same seed, bit for bit (the camera ray reads the same sampler dimensions). Asking
 *    for the pass changes no other pass and no radiance; bdpt with it is refused.
 * 2. Resolving: every pixel the resolver traces lies next to an edge between emitting and
 *    non-emitting samples, the others keep their own emission exactly, and a traced
 *    pixel's value agrees with an independent estimate of the same integral, the mean
 *    emission of 256 randomly jittered samples, within bounds from that estimate's
 *    variance (the lamp's partly covered pixels: coverage times radiance).
 *    A lamp's straight edge along or across the rows, placed at every 64th of a pixel
 *    (a flat lamp facing the camera, its edge's place exact from the camera's own
 *    numbers): the resolved coverage of the edge's pixels is within 1/32 of the exact
 *    one at 4 x 4 rays, what a (0, 4, 2)-net of 16 points guarantees for such an edge
 *    (an n x n grid guarantees only 1/8, and misses a sliver thinner than that); a sliver
 *    that one ray of the 16 finds (coverage 3/64 .. 5/64) is traced again at 64 rays and
 *    resolved to 1/128. The same edge in front of an environment of half its radiance
 *    (a step between two emitters) is resolved to 1/32 of the step too; a smooth ramp of
 *    emission is no edge, a step of 30 % is, and the host's mask traces the pixels the
 *    per-pixel test names.
 * 3. The reconstruction: a frame whose colour is a constant plus an emission pass comes
 *    out as the constant (filtered) plus the emission added back, for every method, and
 *    with has_resolved set the resolved emission is what is added. Without the pass SVGF
 *    spreads the same bright pixels onto their neighbours.
 * 4. An upscaled output's missed emitters (tr_emission_missed): in the previous output a
 *    lamp of 3 x 3 pixels and a strip one pixel high count as missed where the samples
 *    (4 output pixels apart) saw none, inside and on their edges; the sky above a
 *    horizon, at its edge, its corners and the image's border, does not (it reaches 4
 *    pixels in both axes: had it still been there a sample would have seen it); a pixel
 *    that saw no emission never counts. */
#include "check.h"
#include "classic_box.h"
#include "kernel/emission.h"
#include "render_film.h"
#include "synth_frame.h"
#include "trac0r/post.h"
#include "trac0r/trac0r.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define W 64
#define H 48

static void render(const tr_scene *s, int integrator, int max_depth, uint32_t passes,
                   uint32_t first, uint32_t spp, tr_film *f) {
    render_film(s, W, H, integrator, max_depth, passes, 5, first, spp, f);
}

static void test_pass(const tr_scene *s) {
    const size_t n3 = 3u * W * H;
    tr_film d1, d8, plain, all;
    render(s, TR_INTEGRATOR_PT, 1, 0u, 0, 2, &d1);
    render(s, TR_INTEGRATOR_PT, 8, TR_PASS_ALL | TR_PASS_EMISSION, 0, 2, &d8);
    CHECK(memcmp(d8.emission, d1.sum, n3 * sizeof(float)) == 0,
          "the emission pass is not the max-depth-1 radiance");
    double e = 0.0, r = 0.0;
    for (size_t i = 0; i < n3; ++i) {
        e += d8.emission[i];
        r += d8.sum[i];
    }
    CHECK(e > 0.0 && r > 1.5 * e, "emission %g of radiance %g: the lamp or the room is lost", e, r);
    render(s, TR_INTEGRATOR_PT, 8, 0u, 0, 2, &plain);
    render(s, TR_INTEGRATOR_PT, 8, TR_PASS_ALL, 0, 2, &all);
    CHECK(memcmp(plain.sum, d8.sum, n3 * sizeof(float)) == 0,
          "the emission pass changed the radiance");
    CHECK(memcmp(all.albedo, d8.albedo, n3 * sizeof(float)) == 0 &&
              memcmp(all.normal, d8.normal, n3 * sizeof(float)) == 0 &&
              memcmp(all.depth, d8.depth, (n3 / 3) * sizeof(float)) == 0 &&
              memcmp(all.prim, d8.prim, (n3 / 3) * sizeof(uint32_t)) == 0,
          "the emission pass changed another pass");
    tr_film_free(&d1);
    tr_film_free(&d8);
    tr_film_free(&plain);
    tr_film_free(&all);

    tr_film f;
    tr_error err;
    CHECK(tr_film_init_passes(&f, W, H, TR_PASS_EMISSION, &err) == TR_OK, "%s", err.msg);
    tr_render_config cfg = tr_render_config_default();
    cfg.integrator = TR_INTEGRATOR_BDPT;
    cfg.passes = TR_PASS_EMISSION;
    CHECK(tr_render_frame(s, tr_scene_camera(s), &cfg, &f, 0, NULL, &err) == TR_ERR &&
              err.code == TR_STATUS_INVALID_ARGUMENT,
          "bdpt with the emission pass was not refused");
    tr_film_free(&f);
}

static float max3(const float *v) {
    return fmaxf(v[0], fmaxf(v[1], v[2]));
}

static void test_resolve(const tr_scene *s) {
    tr_error err;
    tr_film one, many;
    render(s, TR_INTEGRATOR_PT, 8, TR_PASS_ALL | TR_PASS_EMISSION, 0, 1, &one);
    /* The independent estimate: 256 jittered camera rays per pixel, first hit only. */
    render(s, TR_INTEGRATOR_PT, 1, TR_PASS_EMISSION, 100, 256, &many);
    tr_gbuffer g;
    CHECK(tr_gbuffer_init(&g, W, H, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_gbuffer_from_film(&g, &one, &err) == TR_OK && g.has_emission && !g.has_resolved,
          "gbuffer from a film with the emission pass");
    uint32_t traced = 0;
    CHECK(tr_resolve_emission(s, tr_scene_camera(s), 16, 2, &g, &traced, &err) == TR_OK, "%s",
          err.msg);
    CHECK(g.has_resolved, "has_resolved not set");
    /* The lamp's radiance: the brightest channel any sample saw. */
    float le = 0.0f;
    for (size_t i = 0; i < (size_t)W * H; ++i) {
        le = fmaxf(le, max3(g.emission + 3 * i));
    }
    CHECK(le > 1.0f, "no lamp in view (%g)", (double)le);
    uint32_t edge = 0, partial = 0, bad = 0;
    for (int y = 0; y < H; ++y) {
        for (int x = 0; x < W; ++x) {
            const size_t i = (size_t)y * W + x;
            int on_edge = 0;
            const int c = max3(g.emission + 3 * i) > 0.0f;
            for (int dy = -1; dy <= 1; ++dy) {
                for (int dx = -1; dx <= 1; ++dx) {
                    const int xx = x + dx, yy = y + dy;
                    if (xx >= 0 && yy >= 0 && xx < W && yy < H &&
                        (max3(g.emission + 3 * ((size_t)yy * W + xx)) > 0.0f) != c) {
                        on_edge = 1;
                    }
                }
            }
            edge += (uint32_t)on_edge;
            if (!on_edge) {
                bad +=
                    memcmp(g.emission + 3 * i, g.emission_resolved + 3 * i, 3 * sizeof(float)) != 0;
                continue;
            }
            /* Coverage c of the pixel by the lamp, estimated twice: from the 16 x 16 grid
             * (error at most a row of cells, 1/16, along a straight edge) and from 256
             * random samples (standard deviation sqrt(c (1 - c) / 256) <= 1/32). */
            for (int k = 0; k < 3; ++k) {
                const float mean = many.emission[3 * i + k] / (float)many.count[i];
                const float got = g.emission_resolved[3 * i + k];
                const float cov = fminf(fmaxf(mean / le, 0.0f), 1.0f);
                const float sd = sqrtf(fmaxf(cov * (1.0f - cov), 1.0f / 256.0f) / 256.0f);
                if (fabsf(got - mean) > le * (5.0f * sd + 1.0f / 16.0f)) {
                    ++bad;
                }
            }
            const float cov = max3(g.emission_resolved + 3 * i) / le;
            partial += cov > 0.05f && cov < 0.95f;
        }
    }
    CHECK(traced == edge, "traced %u pixels, %u are on an edge", traced, edge);
    CHECK(edge > 8 && edge < (uint32_t)(W * H) / 10, "%u edge pixels", edge);
    CHECK(partial > 4, "only %u partly covered pixels: nothing resolved", partial);
    CHECK(bad == 0, "%u resolved values disagree with the jittered estimate", bad);

    /* Bad input: no pass, a wrong n, a camera of another size. */
    g.has_emission = 0;
    CHECK(tr_resolve_emission(s, tr_scene_camera(s), 4, 2, &g, NULL, &err) == TR_ERR,
          "resolved without the pass");
    g.has_emission = 1;
    CHECK(tr_resolve_emission(s, tr_scene_camera(s), 0, 2, &g, NULL, &err) == TR_ERR &&
              tr_resolve_emission(s, tr_scene_camera(s), TR_RESOLVE_EMISSION_MAX + 1, 2, &g, NULL,
                                  &err) == TR_ERR,
          "n out of range accepted");
    tr_camera small = *tr_scene_camera(s);
    CHECK(tr_camera_resize(&small, W / 2, H / 2, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_resolve_emission(s, &small, 4, 2, &g, NULL, &err) == TR_ERR &&
              err.code == TR_STATUS_INVALID_ARGUMENT,
          "a camera of another size accepted");
    tr_gbuffer_free(&g);
    tr_film_free(&one);
    tr_film_free(&many);
}

/* A lamp of radiance 1 filling the half plane y < 0 (rows = 1) or x < 0 (rows = 0) of z = 0,
 * seen head-on from z = 5 by a W x H camera, in front of a constant environment of
 * radiance bg (none at 0); returns the committed scene or NULL. */
static tr_scene *edge_scene(int rows, float bg, tr_error *err) {
    char text[900], env[100] = "";
    if (bg > 0.0f) {
        snprintf(env, sizeof env, " \"environment\": {\"color\": [%g, %g, %g]},\n", (double)bg,
                 (double)bg, (double)bg);
    }
    const double lo = -50.0, hi = 50.0, ex = rows ? hi : 0.0, ey = rows ? 0.0 : hi;
    snprintf(text, sizeof text,
             "{\"render\": {\"width\": %d, \"height\": %d},\n%s"
             " \"camera\": {\"position\": [0, 0, 5], \"direction\": [0, 0, -1], \"fov\": 30},\n"
             " \"materials\": {\"lamp\": {\"type\": \"emitter\", \"color\": [1, 1, 1], "
             "\"emittance\": 1}},\n"
             " \"shapes\": [{\"type\": \"quad\", \"vertices\": [[%g, %g, 0], [%g, %g, 0], "
             "[%g, %g, 0], [%g, %g, 0]], \"material\": \"lamp\"}]}",
             W, H, env, lo, lo, ex, lo, ex, ey, lo, ey);
    tr_scene *s = tr_scene_create(err);
    if (!s) {
        return NULL;
    }
    if (tr_scene_file_parse(s, "edge.json", text, strlen(text), NULL, NULL, err) != TR_OK ||
        tr_scene_commit(s, TR_ACCEL_TYPE_BVH, err) != TR_OK) {
        tr_scene_destroy(s);
        return NULL;
    }
    return s;
}

/* The lamp's edge at 1/64 steps across pixel row (or column) 20: the camera is moved so
 * that the edge's screen coordinate is 20 + f, the frame's emission pass marks the edge,
 * and the resolved coverage of row 20's pixels must be 1 - f (the lamp lies beyond the
 * edge, at larger screen coordinates) within 1/32. In front of an environment of radiance
 * bg the edge is a step between two emitters (tr_emission_step), resolved the same way:
 * the pixels must hold bg + (1 - bg)(1 - f). */
static void test_resolve_edge(int rows, float bg) {
    tr_error err;
    tr_scene *s = edge_scene(rows, bg, &err);
    CHECK(s != NULL, "the edge scene: %s", err.msg);
    if (!s) {
        return;
    }
    const tr_camera base = *tr_scene_camera(s);
    /* Screen coordinate c (pixels) of a point of z = 0 at offset d from the camera's axis:
     * c = side * (0.5 - d / (5 canvas)), side the screen size, the sign by the camera's
     * up (rows) or right (columns) vector; so d = 5 canvas (0.5 - c / side) * sign. */
    const float canvas = rows ? base.canvas_height : base.canvas_width;
    const float side = rows ? (float)H : (float)W;
    const float sign =
        rows ? (base.up.y > 0.0f ? 1.0f : -1.0f) : (base.right.x > 0.0f ? -1.0f : 1.0f);
    float worst = 0.0f;
    int bad = 0, lit = 0, fine_bad = 0;
    for (int step = 1; step < 64; ++step) {
        const float f = (float)step / 64.0f;
        const float d = 5.0f * canvas * (0.5f - (20.0f + f) / side) * sign;
        tr_camera cam = base;
        /* The edge is at 0: the camera sits at -d from it. */
        if (rows) {
            cam.pos.y = -d;
        } else {
            cam.pos.x = -d;
        }
        tr_film film;
        CHECK(tr_film_init_passes(&film, W, H, TR_PASS_ALL | TR_PASS_EMISSION, &err) == TR_OK, "%s",
              err.msg);
        tr_render_config cfg = tr_render_config_default();
        cfg.max_depth = 1;
        cfg.passes = TR_PASS_ALL | TR_PASS_EMISSION;
        cfg.threads = 2;
        CHECK(tr_render_frame(s, &cam, &cfg, &film, (uint32_t)step, NULL, &err) == TR_OK, "%s",
              err.msg);
        tr_gbuffer g;
        CHECK(tr_gbuffer_init(&g, W, H, &err) == TR_OK &&
                  tr_gbuffer_from_film(&g, &film, &err) == TR_OK,
              "%s", err.msg);
        CHECK(tr_resolve_emission(s, &cam, 4, 2, &g, NULL, &err) == TR_OK, "%s", err.msg);
        const int across = rows ? W : H;
        for (int k = 2; k < across - 2; ++k) {
            const int x = rows ? k : 20, y = rows ? 20 : k;
            const float got = g.emission_resolved[3 * ((size_t)y * W + x)];
            const float e = fabsf(got - (bg + (1.0f - bg) * (1.0f - f))) / (1.0f - bg);
            worst = fmaxf(worst, e);
            bad += e > 1.0f / 32.0f + 1e-3f;
            /* Coverage 3/64 .. 5/64: one of the 16 rays sees the lamp, and the pixel is
             * traced again with 64, whose strata resolve it to 1/128. (Before an
             * environment every ray sees emission, so no pixel is one ray's.) */
            fine_bad += bg == 0.0f && step >= 59 && step <= 61 && e > 1.0f / 128.0f + 1e-3f;
            /* One pixel further on lies wholly on the lamp. */
            const int x2 = rows ? x : x + 1, y2 = rows ? y + 1 : y;
            lit += g.emission_resolved[3 * ((size_t)y2 * W + x2)] == 1.0f;
        }
        tr_gbuffer_free(&g);
        tr_film_free(&film);
    }
    CHECK(lit == 63 * ((rows ? W : H) - 4), "%d pixels past the edge wholly lit", lit);
    CHECK(bad == 0, "%s edge before %g: %d pixels' coverage off by more than 1/32 (worst %.4f)",
          rows ? "a row's" : "a column's", (double)bg, bad, (double)worst);
    CHECK(fine_bad == 0, "%s edge: %d thin slivers' coverage off by more than 1/128",
          rows ? "a row's" : "a column's", fine_bad);
    tr_scene_destroy(s);
}

/* Which pixels an emission pass puts on an edge: a ramp whose luminance changes by 2 % a
 * column has none; a step of 30 % between columns 9 and 10 puts those two columns there
 * and no other; tr_resolve_emission's own mask traces exactly the pixels that
 * tr_emission_on_edge names. */
static void test_steps(void) {
    tr_error err;
    tr_scene *s = edge_scene(1, 0.0f, &err);
    CHECK(s != NULL, "the edge scene: %s", err.msg);
    if (!s) {
        return;
    }
    tr_gbuffer g;
    CHECK(tr_gbuffer_init(&g, W, H, &err) == TR_OK, "%s", err.msg);
    for (int step = 0; step < 2; ++step) {
        for (int y = 0; y < H; ++y) {
            for (int x = 0; x < W; ++x) {
                const float v = step ? (x < 10 ? 1.0f : 0.7f) : powf(1.02f, (float)x);
                for (int k = 0; k < 3; ++k) {
                    g.emission[3 * ((size_t)y * W + x) + k] = v * (k == 2 ? 0.5f : 1.0f);
                }
            }
        }
        g.has_emission = 1;
        uint32_t traced = 0, want = 0, wrong = 0;
        for (int y = 0; y < H; ++y) {
            for (int x = 0; x < W; ++x) {
                const int on = tr_emission_on_edge(g.emission, W, H, x, y);
                want += (uint32_t)on;
                wrong += on != (step && (x == 9 || x == 10));
            }
        }
        CHECK(wrong == 0, "%s: %u pixels wrongly on an edge or off one", step ? "step" : "ramp",
              wrong);
        CHECK(tr_resolve_emission(s, tr_scene_camera(s), 2, 2, &g, &traced, &err) == TR_OK, "%s",
              err.msg);
        CHECK(traced == want, "%s: traced %u pixels, %u on an edge", step ? "step" : "ramp", traced,
              want);
    }
    tr_gbuffer_free(&g);
    tr_scene_destroy(s);
}

/* A synthetic frame (synth_frame.h, no noise, colour `base`) plus a 3 x 3 block of
 * emission 20 on the left wall, with or without the emission pass. */
static void lamp_frame(tr_gbuffer *g, float base, int with_pass) {
    synth_frame(g, W, H, base, base, 0.0f, -1.0f, 1u);
    memset(g->emission, 0, 3u * W * H * sizeof(float));
    for (int y = 20; y < 23; ++y) {
        for (int x = 10; x < 13; ++x) {
            for (int k = 0; k < 3; ++k) {
                g->emission[3 * ((size_t)y * W + x) + k] = 20.0f;
                g->color[3 * ((size_t)y * W + x) + k] += 20.0f;
            }
        }
    }
    g->has_emission = with_pass;
    g->has_resolved = 0;
}

static void test_recon(void) {
    tr_error err;
    tr_gbuffer g;
    tr_recon r;
    CHECK(tr_gbuffer_init(&g, W, H, &err) == TR_OK && tr_recon_init(&r, W, H, &err) == TR_OK, "%s",
          err.msg);
    tr_camera cam;
    CHECK(tr_camera_make(&cam, tr_vec3_make(0, 0, -1), tr_vec3_make(0, 0, 1), tr_vec3_make(0, 1, 0),
                         60.0f, 1e-3f, 1e4f, W, H, &err) == TR_OK,
          "%s", err.msg);
    const tr_recon_params p = tr_recon_params_default();
    float *out = malloc(3u * W * H * sizeof *out);
    CHECK(out != NULL, "out of memory");
    for (int m = TR_RECON_ACCUMULATE; out && m < TR_RECON_COUNT; ++m) {
        tr_recon_clear(&r);
        lamp_frame(&g, 0.3f, 1);
        CHECK(tr_recon_frame(&r, &g, &cam, m, &p, 2, out, &err) == TR_OK, "%s", err.msg);
        double worst = 0.0;
        for (size_t i = 0; i < 3u * W * H; ++i) {
            worst = fmax(worst, fabs(out[i] - (0.3 + g.emission[i])));
        }
        CHECK(worst < 1e-4, "%s: constant plus emission off by %g", tr_recon_name(m), worst);

        /* The resolved emission is the one added. */
        tr_recon_clear(&r);
        for (size_t i = 0; i < 3u * W * H; ++i) {
            g.emission_resolved[i] = 0.25f * g.emission[i];
        }
        g.has_resolved = 1;
        CHECK(tr_recon_frame(&r, &g, &cam, m, &p, 2, out, &err) == TR_OK, "%s", err.msg);
        worst = 0.0;
        for (size_t i = 0; i < 3u * W * H; ++i) {
            worst = fmax(worst, fabs(out[i] - (0.3 + g.emission_resolved[i])));
        }
        CHECK(worst < 1e-4, "%s: resolved emission not the one added (off by %g)", tr_recon_name(m),
              worst);

        /* Without the pass SVGF spreads the lamp's light onto its neighbours (the
         * bilateral and a-trous filters' colour weights stop a value this bright). */
        if (m == TR_RECON_SVGF) {
            tr_recon_clear(&r);
            lamp_frame(&g, 0.3f, 0);
            CHECK(tr_recon_frame(&r, &g, &cam, m, &p, 2, out, &err) == TR_OK, "%s", err.msg);
            const size_t nb = 3 * ((size_t)21 * W + 14);
            CHECK(out[nb] > 0.31f, "%s: without the pass the lamp did not spread (%g)",
                  tr_recon_name(m), (double)out[nb]);
        }
    }
    free(out);
    tr_recon_free(&r);
    tr_gbuffer_free(&g);
}

static void test_missed(void) {
    enum { MW = 32, MH = 24, D = 4 };
    float *prev = calloc(3u * MW * MH, sizeof *prev);
    CHECK(prev != NULL, "out of memory");
    if (!prev) {
        return;
    }
    /* The sky: rows 0..7, every column; a lamp at (20..22, 14..16); a strip along row 19
     * from column 4 to 27. */
    for (int y = 0; y < MH; ++y) {
        for (int x = 0; x < MW; ++x) {
            const int sky = y < 8;
            const int lamp = x >= 20 && x <= 22 && y >= 14 && y <= 16;
            const int strip = y == 19 && x >= 4 && x <= 27;
            if (sky || lamp || strip) {
                prev[3 * (y * MW + x)] = 1.0f;
                prev[3 * (y * MW + x) + 1] = 0.5f;
            }
        }
    }
    const int small[][2] = {{21, 15}, {20, 14}, {22, 16}, {4, 19}, {15, 19}, {27, 19}};
    for (size_t k = 0; k < sizeof small / sizeof small[0]; ++k) {
        CHECK(tr_emission_missed(prev, MW, MH, small[k][0], small[k][1], D, D),
              "a small emitter at (%d, %d) does not count as missed", small[k][0], small[k][1]);
    }
    const int large[][2] = {{10, 3}, {10, 7}, {0, 7}, {31, 7}, {0, 0}, {31, 0}, {16, 0}};
    for (size_t k = 0; k < sizeof large / sizeof large[0]; ++k) {
        CHECK(!tr_emission_missed(prev, MW, MH, large[k][0], large[k][1], D, D),
              "the sky at (%d, %d) counts as missed", large[k][0], large[k][1]);
    }
    const int none[][2] = {{10, 8}, {19, 15}, {3, 19}, {10, 12}};
    for (size_t k = 0; k < sizeof none / sizeof none[0]; ++k) {
        CHECK(!tr_emission_missed(prev, MW, MH, none[k][0], none[k][1], D, D),
              "(%d, %d), which saw no emission, counts as missed", none[k][0], none[k][1]);
    }
    free(prev);
}

int main(void) {
    tr_error err;
    tr_scene *s = classic_box(W, H, &err);
    if (s) {
        test_pass(s);
        test_resolve(s);
        tr_scene_destroy(s);
    }
    test_resolve_edge(1, 0.0f);
    test_resolve_edge(0, 0.0f);
    test_resolve_edge(1, 0.5f);
    test_resolve_edge(0, 0.5f);
    test_steps();
    test_recon();
    test_missed();
    return check_finish("test_emission");
}
