/* test_surface.c - vertex attributes and textures.
 *
 * 1. Smooth icosphere: the normal pass of a smooth-shaded icosphere matches the analytic
 *    sphere's normal within a fraction of a degree, and its change between neighbouring
 *    pixels stays within the analytic sphere's own change plus a small margin (no facet
 *    edges); the same checks fail for the faceted icosphere, so they measure something.
 *    (The analytic normal is taken only where it is within ~32 degrees of the view
 *    direction: near the silhouette the mesh and the sphere are hit at different points.)
 * 2. Texture lookups: texel centres return the texel (sRGB-decoded for colour maps,
 *    linear otherwise), bilinear midpoints the mean, repeat wraps by whole periods and
 *    clamp holds the edge texel.
 * 3. A textured quad filling the image: its emission texture is what the camera sees, so
 *    the image's mean is the texture's (decoded) mean and the pixel over a texel's centre
 *    is that texel; its base-colour texture is the albedo pass.
 * 3b. tr_emitted_at (next-event estimation's read of a light's emission) equals tr_emitted
 *    of the whole material stage, on a textured emissive quad and on a plain emitter.
 * 4. Image files: a PNG decodes to the texels it was written with (top row first, R in
 *    the low byte); a missing file, a truncated PNG, a 0x0 one, one declaring 10^5 x 10^5
 *    texels, one whose chunk runs past the end of the file and a text file fail with a
 *    status code and add nothing.
 * 4b. Normal maps: a constant map tilting the normal towards +X (+Y) of tangent space
 *    turns the quad's shading normal towards the direction u (the image's up) grows in,
 *    glTF's convention (+Y up in the image while v grows downwards).
 * 4c. Metallic-roughness maps: blue is metallic and green roughness (glTF), read by the
 *    material stage at known UVs; a rough white metal half renders darker than a white
 *    dielectric half under a constant environment.
 * 5. Environment light: directions drawn from an HDR map fall into its texels as the
 *    sampling weights say (chi-square, p = 1e-4), with the density tr_env_pdf gives, and
 *    that density integrates to 1 over the sphere (also turned about +y); a white furnace:
 *    a diffuse sphere under a constant environment of radiance L renders L * albedo. */
#include "check.h"
#include "scene_util.h"
#include "kernel/envmap.h"
#include "kernel/rng.h"
#include "scene/texture.h"
#include "trac0r/device.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define SW 64
#define SH 64

static double angle_deg(const float *a, const double *b) {
    double la = sqrt((double)a[0] * a[0] + (double)a[1] * a[1] + (double)a[2] * a[2]);
    double lb = sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
    double c = (a[0] * b[0] + a[1] * b[1] + a[2] * b[2]) / (la * lb);
    return acos(c > 1.0 ? 1.0 : c < -1.0 ? -1.0 : c) * 180.0 / 3.14159265358979;
}

/* Renders a unit icosphere (subdivisions 3) at the origin seen from (0, 0, 3) and
 * compares its normal pass with the analytic sphere's normal through each pixel centre:
 * the largest error and the largest excess of a neighbour-to-neighbour change over the
 * analytic change, in degrees, over pixels whose analytic normal faces the camera. */
static void sphere_normal_errors(tr_shape_type type, double *max_err, double *max_step) {
    tr_scene s = {0};
    tr_scene_init(&s);
    tr_error err;
    uint32_t white = add_mat(&s, tr_material_diffuse(v3s(0.5f)));
    tr_shape_desc d = tr_shape_desc_default(type);
    d.material = white;
    d.subdivisions = 3;
    CHECK(tr_scene_add_shape(&s, &d, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
    tr_camera cam;
    CHECK(tr_camera_make(&cam, v3(0.0f, 0.0f, 3.0f), v3(0.0f, 0.0f, -1.0f), v3(0.0f, 1.0f, 0.0f),
                         45.0f, 1e-3f, 1e3f, SW, SH, &err) == TR_OK,
          "%s", err.msg);
    tr_film film;
    CHECK(tr_film_init_passes(&film, SW, SH, TR_PASS_NORMAL, &err) == TR_OK, "%s", err.msg);
    tr_render_config cfg = tr_render_config_default();
    cfg.passes = TR_PASS_NORMAL;
    cfg.max_depth = 2;
    for (uint32_t smp = 0; smp < 4; ++smp) {
        CHECK(tr_render_frame(&s, &cam, &cfg, &film, smp, NULL, &err) == TR_OK, "%s", err.msg);
    }
    static double ana[SH][SW][3];
    static float got[SH][SW][3];
    static int ok[SH][SW];
    for (uint32_t y = 0; y < SH; ++y) {
        for (uint32_t x = 0; x < SW; ++x) {
            tr_ray r = tr_camera_ray(&cam, (float)x, (float)y, 0.5f, 0.5f);
            /* |o + t d| = 1 */
            double b = 0, c = -1, a = 0;
            const double o[3] = {r.origin.x, r.origin.y, r.origin.z};
            const double dd[3] = {r.dir.x, r.dir.y, r.dir.z};
            for (int k = 0; k < 3; ++k) {
                a += dd[k] * dd[k];
                b += 2 * o[k] * dd[k];
                c += o[k] * o[k];
            }
            double disc = b * b - 4 * a * c;
            ok[y][x] = 0;
            if (disc <= 0) {
                continue;
            }
            double t = (-b - sqrt(disc)) / (2 * a);
            for (int k = 0; k < 3; ++k) {
                ana[y][x][k] = o[k] + t * dd[k];
            }
            ok[y][x] =
                ana[y][x][2] >
                0.85; /* away from the silhouette, where the inscribed mesh and the sphere part */
            CHECK(tr_film_pass_pixel(&film, TR_PASS_NORMAL, x, y, got[y][x], &err) == TR_OK, "%s",
                  err.msg);
        }
    }
    *max_err = 0.0;
    *max_step = 0.0;
    for (uint32_t y = 0; y + 1 < SH; ++y) {
        for (uint32_t x = 0; x + 1 < SW; ++x) {
            if (!ok[y][x]) {
                continue;
            }
            double e = angle_deg(got[y][x], ana[y][x]);
            *max_err = e > *max_err ? e : *max_err;
            for (int k = 0; k < 2; ++k) {
                uint32_t nx = x + (k == 0), ny = y + (k == 1);
                if (!ok[ny][nx]) {
                    continue;
                }
                double gf[3] = {got[ny][nx][0], got[ny][nx][1], got[ny][nx][2]};
                double step = angle_deg(got[y][x], gf) -
                              angle_deg((float[3]){(float)ana[y][x][0], (float)ana[y][x][1],
                                                   (float)ana[y][x][2]},
                                        ana[ny][nx]);
                *max_step = step > *max_step ? step : *max_step;
            }
        }
    }
    tr_film_free(&film);
    tr_scene_clear(&s);
}

static void test_smooth_icosphere(void) {
    double err_s, step_s, err_f, step_f;
    sphere_normal_errors(TR_SHAPE_ICOSPHERE_SMOOTH, &err_s, &step_s);
    sphere_normal_errors(TR_SHAPE_ICOSPHERE, &err_f, &step_f);
    printf("smooth: max error %.3f deg, max step excess %.3f deg; faceted: %.3f, %.3f\n", err_s,
           step_s, err_f, step_f);
    /* Subdivision 3 leaves edges of ~7.9 degrees: a facet's normal is up to ~4 degrees off
     * the sphere's and jumps by the edge angle. An interpolated normal differs from the
     * sphere's only through parallax - the inscribed mesh lies up to 1 - cos(3.9 deg) =
     * 0.2 % inside the sphere, so a pixel's ray meets it at a slightly different point
     * (about a degree at 30 degrees from the silhouette, less towards the centre). */
    CHECK(err_s < 1.5, "smooth normal error %.3f degrees", err_s);
    CHECK(step_s < 2.0, "smooth normal jumps %.3f degrees more than the sphere's", step_s);
    CHECK(err_f > 3.0 && step_f > 4.0, "faceted: %.3f, %.3f (the checks must see facets)", err_f,
          step_f);
}

#define TW 4
#define TH 2
/* A 4x2 texture of distinct colours (R in the low byte), alpha 255 except texel 3. */
static const uint32_t tex_rgba[TW * TH] = {0xff0000ffu, 0xff00ff00u, 0xffff0000u, 0x80808080u,
                                           0xff204060u, 0xffffffffu, 0xff000000u, 0xff10c0a0u};

static double srgb_decode(double c) {
    return c <= 0.04045 ? c / 12.92 : pow((c + 0.055) / 1.055, 2.4);
}

/* Channel k of texel i, decoded when srgb. */
static double texel_channel(int i, int k, int srgb) {
    double c = (double)((tex_rgba[i] >> (8 * k)) & 255u) / 255.0;
    return srgb ? srgb_decode(c) : c;
}

static void test_texture_lookup(void) {
    tr_scene s = {0};
    tr_scene_init(&s);
    tr_error err;
    uint32_t rep, clp;
    CHECK(tr_scene_add_texture(&s, tex_rgba, TW, TH, 0u, &rep, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_scene_add_texture(&s, tex_rgba, TW, TH, TR_TEXTURE_CLAMP, &clp, &err) == TR_OK, "%s",
          err.msg);
    CHECK_STATUS(tr_scene_add_texture(&s, tex_rgba, 0, TH, 0u, NULL, &err), err,
                 TR_STATUS_INVALID_ARGUMENT, "a 0-wide texture");
    tr_scene_view v = tr_scene_view_of(&s);
    float a;
    for (int srgb = 0; srgb < 2; ++srgb) {
        for (int i = 0; i < TW * TH; ++i) {
            float u = ((float)(i % TW) + 0.5f) / TW, w = ((float)(i / TW) + 0.5f) / TH;
            tr_vec3 c = tr_texture_sample(&v, rep, u, w, srgb, &a);
            CHECK_NEAR(c.x, texel_channel(i, 0, srgb), 1e-5, "texel centre r");
            CHECK_NEAR(c.y, texel_channel(i, 1, srgb), 1e-5, "texel centre g");
            CHECK_NEAR(c.z, texel_channel(i, 2, srgb), 1e-5, "texel centre b");
            CHECK_NEAR(a, texel_channel(i, 3, 0), 1e-5, "texel centre alpha");
            /* Repeat: whole periods away, either sign. */
            tr_vec3 r = tr_texture_sample(&v, rep, u + 3.0f, w - 2.0f, srgb, &a);
            CHECK_NEAR(r.x, c.x, 1e-5, "repeat");
            CHECK_NEAR(r.z, c.z, 1e-5, "repeat");
        }
    }
    /* Bilinear: halfway between texels 0 and 1 (same row), linear channels. */
    tr_vec3 mid = tr_texture_sample(&v, rep, 1.0f / TW, 0.25f, 0, &a);
    CHECK_NEAR(mid.x, 0.5 * (texel_channel(0, 0, 0) + texel_channel(1, 0, 0)), 1e-5, "bilinear");
    CHECK_NEAR(mid.y, 0.5 * (texel_channel(0, 1, 0) + texel_channel(1, 1, 0)), 1e-5, "bilinear");
    /* At u = 0 the repeating texture blends the first and the last column; the clamped
     * one holds the first. */
    tr_vec3 e_rep = tr_texture_sample(&v, rep, 0.0f, 0.25f, 0, &a);
    tr_vec3 e_clp = tr_texture_sample(&v, clp, 0.0f, 0.25f, 0, &a);
    CHECK_NEAR(e_rep.x, 0.5 * (texel_channel(0, 0, 0) + texel_channel(3, 0, 0)), 1e-5,
               "repeat wraps at the edge");
    CHECK_NEAR(e_clp.x, texel_channel(0, 0, 0), 1e-5, "clamp holds the edge");
    tr_vec3 far_clp = tr_texture_sample(&v, clp, 7.5f, -3.0f, 0, &a);
    CHECK_NEAR(far_clp.x, texel_channel(3, 0, 0), 1e-5, "clamp beyond: the corner texel");
    tr_scene_clear(&s);
}

#define QW 60
#define QH 30
static void test_textured_quad(void) {
    tr_scene s = {0};
    tr_scene_init(&s);
    tr_error err;
    uint32_t tex;
    CHECK(tr_scene_add_texture(&s, tex_rgba, TW, TH, 0u, &tex, &err) == TR_OK, "%s", err.msg);
    tr_material black = tr_material_diffuse(v3s(1.0f));
    uint32_t mat = add_mat(&s, black);
    tr_material_ext ext = tr_material_ext_default();
    ext.emission = v3s(1.0f);
    ext.emission_tex = tex;
    ext.base_tex = tex;
    CHECK(tr_scene_set_material_ext(&s, mat, &ext, &err) == TR_OK, "%s", err.msg);
    /* The quad x in [-2, 2], y in [-1, 1] at z = 0 facing +z, seen from z = 1 with a 90
     * degree vertical field of view: it fills the 2:1 image exactly. UV (0, 0) at the
     * top-left corner as the image shows it. */
    tr_camera cam;
    CHECK(tr_camera_make(&cam, v3(0.0f, 0.0f, 1.0f), v3(0.0f, 0.0f, -1.0f), v3(0.0f, 1.0f, 0.0f),
                         90.0f, 1e-3f, 1e3f, QW, QH, &err) == TR_OK,
          "%s", err.msg);
    tr_ray tl = tr_camera_ray(&cam, 0.0f, 0.0f, 0.0f, 0.0f);
    const float left = tl.dir.x < 0.0f ? -2.0f : 2.0f; /* the image's left edge in x */
    const float pos[12] = {left, 1, 0, -left, 1, 0, -left, -1, 0, left, -1, 0};
    const float uv[8] = {0, 0, 1, 0, 1, 1, 0, 1};
    const uint32_t idx[6] = {0, 1, 2, 0, 2, 3};
    CHECK(tr_scene_add_mesh_uv(&s, pos, 4, idx, 2, NULL, uv, mat, NULL, NULL, &err) == TR_OK, "%s",
          err.msg);
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
    tr_film film;
    CHECK(tr_film_init_passes(&film, QW, QH, TR_PASS_ALBEDO, &err) == TR_OK, "%s", err.msg);
    tr_render_config cfg = tr_render_config_default();
    cfg.passes = TR_PASS_ALBEDO;
    cfg.max_depth = 1; /* what the camera sees: the emission */
    for (uint32_t smp = 0; smp < 16; ++smp) {
        CHECK(tr_render_frame(&s, &cam, &cfg, &film, smp, NULL, &err) == TR_OK, "%s", err.msg);
    }
    double mean[3] = {0, 0, 0}, want[3] = {0, 0, 0};
    for (uint32_t y = 0; y < QH; ++y) {
        for (uint32_t x = 0; x < QW; ++x) {
            tr_vec3 px = tr_film_pixel(&film, x, y);
            mean[0] += px.x / (QW * QH);
            mean[1] += px.y / (QW * QH);
            mean[2] += px.z / (QW * QH);
        }
    }
    for (int i = 0; i < TW * TH; ++i) {
        for (int k = 0; k < 3; ++k) {
            want[k] += texel_channel(i, k, 1) / (TW * TH);
        }
    }
    /* Bilinear filtering with repeat keeps the mean; 16 jittered samples per pixel over 8
     * texels of 15x15 pixels leave a sampling error far below 0.01. */
    for (int k = 0; k < 3; ++k) {
        CHECK_NEAR(mean[k], want[k], 0.01, "image mean = texture mean");
    }
    /* The pixel whose centre is texel i's centre (15 pixels a texel): over its footprint
     * the bilinear weights move symmetrically by at most 1/30, so the pixel's expected
     * value is the texel's and a sample's within 1/30 of the neighbours' difference. */
    for (int i = 0; i < TW * TH; ++i) {
        uint32_t x = (uint32_t)(i % TW) * (QW / TW) + QW / TW / 2;
        uint32_t y = (uint32_t)(i / TW) * (QH / TH) + QH / TH / 2;
        float alb[3];
        tr_vec3 pv = tr_film_pixel(&film, x, y);
        const float px[3] = {pv.x, pv.y, pv.z};
        CHECK(tr_film_pass_pixel(&film, TR_PASS_ALBEDO, x, y, alb, &err) == TR_OK, "%s", err.msg);
        for (int k = 0; k < 3; ++k) {
            CHECK_NEAR(px[k], texel_channel(i, k, 1), 0.04, "emission at a texel's centre");
            CHECK_NEAR(alb[k], texel_channel(i, k, 1), 0.04, "albedo at a texel's centre");
        }
    }
    /* Alpha cut-out at 0.6: texel 3 (alpha 0.5) becomes a hole showing the black behind,
     * the others (alpha 1) stay. */
    ext.flags |= TR_MATEXT_ALPHA_MASK;
    ext.alpha_cutoff = 0.6f;
    CHECK(tr_scene_set_material_ext(&s, mat, &ext, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
    tr_film_clear(&film);
    for (uint32_t smp = 0; smp < 4; ++smp) {
        CHECK(tr_render_frame(&s, &cam, &cfg, &film, smp, NULL, &err) == TR_OK, "%s", err.msg);
    }
    for (int i = 0; i < TW * TH; ++i) {
        uint32_t x = (uint32_t)(i % TW) * (QW / TW) + QW / TW / 2;
        uint32_t y = (uint32_t)(i / TW) * (QH / TH) + QH / TH / 2;
        tr_vec3 pv = tr_film_pixel(&film, x, y);
        if (i == 3) {
            CHECK(pv.x == 0.0f && pv.y == 0.0f && pv.z == 0.0f, "the cut-out shows black");
        } else {
            CHECK_NEAR(pv.x, texel_channel(i, 0, 1), 0.04, "opaque texels stay");
        }
    }
    tr_film_free(&film);
    tr_scene_clear(&s);
}

/* The normal pass over a quad filling the image whose material has a constant normal
 * map texel `texel` (RGBA8, R low); *n receives the centre pixel's normal. */
static void normal_mapped(uint32_t texel, float n[3]) {
    tr_scene s = {0};
    tr_scene_init(&s);
    tr_error err;
    const uint32_t map[4] = {texel, texel, texel, texel};
    uint32_t tex;
    CHECK(tr_scene_add_texture(&s, map, 2, 2, 0u, &tex, &err) == TR_OK, "%s", err.msg);
    uint32_t mat = add_mat(&s, tr_material_diffuse(v3s(0.5f)));
    tr_material_ext ext = tr_material_ext_default();
    ext.normal_tex = tex;
    CHECK(tr_scene_set_material_ext(&s, mat, &ext, &err) == TR_OK, "%s", err.msg);
    tr_camera cam;
    CHECK(tr_camera_make(&cam, v3(0.0f, 0.0f, 1.0f), v3(0.0f, 0.0f, -1.0f), v3(0.0f, 1.0f, 0.0f),
                         90.0f, 1e-3f, 1e3f, 8, 8, &err) == TR_OK,
          "%s", err.msg);
    /* UV (0, 0) at world (-1, 1): u grows towards +x, v towards -y; wound to face +z,
     * the camera. */
    const float pos[12] = {-1, 1, 0, 1, 1, 0, 1, -1, 0, -1, -1, 0};
    const float uv[8] = {0, 0, 1, 0, 1, 1, 0, 1};
    const uint32_t idx[6] = {0, 2, 1, 0, 3, 2};
    CHECK(tr_scene_add_mesh_uv(&s, pos, 4, idx, 2, NULL, uv, mat, NULL, NULL, &err) == TR_OK, "%s",
          err.msg);
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
    tr_film film;
    CHECK(tr_film_init_passes(&film, 8, 8, TR_PASS_NORMAL, &err) == TR_OK, "%s", err.msg);
    tr_render_config cfg = tr_render_config_default();
    cfg.passes = TR_PASS_NORMAL;
    cfg.max_depth = 1;
    CHECK(tr_render_frame(&s, &cam, &cfg, &film, 0, NULL, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_film_pass_pixel(&film, TR_PASS_NORMAL, 4, 4, n, &err) == TR_OK, "%s", err.msg);
    tr_film_free(&film);
    tr_scene_clear(&s);
}

static void test_normal_map(void) {
    float n[3];
    /* (0.6, 0, 0.8) encoded as (204, 128, 230): decodes to (0.6, 0.004, 0.804). */
    normal_mapped(0xffe680ccu, n);
    CHECK(fabs(n[0] - 0.6) < 0.02 && fabs(n[1]) < 0.02 && fabs(n[2] - 0.8) < 0.02,
          "+X tilt: (%.3f, %.3f, %.3f), expected (0.6, 0, 0.8)", n[0], n[1], n[2]);
    normal_mapped(0xffe6cc80u, n);
    CHECK(fabs(n[0]) < 0.02 && fabs(n[1] - 0.6) < 0.02 && fabs(n[2] - 0.8) < 0.02,
          "+Y tilt: (%.3f, %.3f, %.3f), expected (0, 0.6, 0.8) (+Y up in the image)", n[0], n[1],
          n[2]);
}

/* 4c. glTF's metallicRoughnessTexture: blue is metallic, green roughness (both linear,
 * times the factors). A quad whose left half is white metal (blue 255) and right half a
 * white dielectric (blue 0), both of roughness 1 (green 255): the material stage returns
 * metallic 1 and 0 at the two texel centres, and a texel of green 0 gives roughness 0;
 * under a constant environment of radiance 1 the rough metal half renders darker than
 * the dielectric half (single-scattering GGX at alpha 1 loses about half the light, the
 * dielectric's base keeps most of it: 0.46 and 0.85 here), by more than 5 standard
 * errors. */
static void test_metallic_roughness_map(void) {
    tr_scene s = {0};
    tr_scene_init(&s);
    tr_error err;
    /* R in the low byte: (0, 255, 255) metal, (0, 255, 0) dielectric, (0, 0, 255) smooth. */
    const uint32_t map[3] = {0xffffff00u, 0xff00ff00u, 0xffff0000u};
    uint32_t tex;
    CHECK(tr_scene_add_texture(&s, map, 3, 1, 0u, &tex, &err) == TR_OK, "%s", err.msg);
    tr_material pm = tr_material_diffuse(v3s(1.0f));
    pm.type = TR_MATERIAL_PRINCIPLED;
    pm.roughness = 1.0f;
    pm.ior = 1.5f;
    uint32_t mat = add_mat(&s, pm);
    tr_material_ext ext = tr_material_ext_default();
    ext.metallic = 1.0f;
    ext.mr_tex = tex;
    CHECK(tr_scene_set_material_ext(&s, mat, &ext, &err) == TR_OK, "%s", err.msg);
    /* As normal_mapped's quad: u grows towards +x over [-1.5, 1.5], the camera sees the
     * left two thirds, x in [-1.5, 0.5]: the metal and dielectric texels. */
    const float pos[12] = {-1.5f, 1, 0, 1.5f, 1, 0, 1.5f, -1, 0, -1.5f, -1, 0};
    const float uv[8] = {0, 0, 1, 0, 1, 1, 0, 1};
    const uint32_t idx[6] = {0, 2, 1, 0, 3, 2};
    CHECK(tr_scene_add_mesh_uv(&s, pos, 4, idx, 2, NULL, uv, mat, NULL, NULL, &err) == TR_OK, "%s",
          err.msg);
    CHECK(tr_scene_set_environment(&s, v3s(1.0f), 1.0f, 0.0f, NULL, 0, 0, &err) == TR_OK, "%s",
          err.msg);
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
    /* Triangle 0 is (v0, v2, v1): uv = (b1 + b2, b1) for barycentrics b1 (of v2), b2 (of v1). */
    tr_scene_view v = tr_scene_view_of(&s);
    const float centre_u[3] = {1.0f / 6.0f, 0.5f, 5.0f / 6.0f};
    for (int k = 0; k < 3; ++k) {
        const float b1 = 0.1f, b2 = centre_u[k] - b1;
        tr_vec3 p = v3_add(v3_add(v3_scale(v3(pos[0], pos[1], 0.0f), 1.0f - b1 - b2),
                                  v3_scale(v3(pos[6], pos[7], 0.0f), b1)),
                           v3_scale(v3(pos[3], pos[4], 0.0f), b2));
        tr_bsdf_params m =
            tr_material_eval(&v, 0, b1, b2, p, s.triangles[0].normal, v3(0.0f, 0.0f, -1.0f));
        const float want_m = k == 1 ? 0.0f : 1.0f, want_r = k == 2 ? 0.0f : 1.0f;
        CHECK(m.type == TR_MATERIAL_PRINCIPLED && fabsf(m.metallic - want_m) < 1e-3f &&
                  fabsf(m.roughness - want_r) < 1e-3f,
              "texel %d: metallic %g (want %g), roughness %g (want %g)", k, (double)m.metallic,
              (double)want_m, (double)m.roughness, (double)want_r);
    }
    /* Rendered: the camera at (-0.5, 0, 1) sees x in [-1.5, 0.5] (the metal texel is
     * x < -0.5, the dielectric -0.5 < x < 0.5); columns 1-2 and 5-6 of 8 lie inside each. */
    tr_camera cam;
    CHECK(tr_camera_make(&cam, v3(-0.5f, 0.0f, 1.0f), v3(0.0f, 0.0f, -1.0f), v3(0.0f, 1.0f, 0.0f),
                         90.0f, 1e-3f, 1e3f, 8, 8, &err) == TR_OK,
          "%s", err.msg);
    cam.right = v3_neg(cam.right); /* right-handed: +x on the image's right */
    tr_film film;
    CHECK(tr_film_init(&film, 8, 8, &err) == TR_OK, "%s", err.msg);
    tr_render_config cfg = tr_render_config_default();
    cfg.max_depth = 8;
    for (uint32_t k = 0; k < 64; ++k) {
        CHECK(tr_render_frame(&s, &cam, &cfg, &film, k, NULL, &err) == TR_OK, "%s", err.msg);
    }
    double m[2] = {0, 0}, m2[2] = {0, 0};
    for (uint32_t y = 0; y < 8; ++y) {
        for (uint32_t x = 0; x < 8; ++x) {
            int half = x == 1 || x == 2 ? 0 : x == 5 || x == 6 ? 1 : -1;
            if (half >= 0) {
                double g = tr_film_pixel(&film, x, y).y;
                m[half] += g / 16.0;
                m2[half] += g * g / 16.0;
            }
        }
    }
    const double se =
        sqrt((fmax(0.0, m2[0] - m[0] * m[0]) + fmax(0.0, m2[1] - m[1] * m[1])) / 15.0);
    CHECK(m[1] - m[0] > 5.0 * se && m[0] < 0.7 && m[1] > 0.75,
          "metal half %.4f vs dielectric half %.4f (se %.2g)", m[0], m[1], se);
    printf("metallic-roughness map: metal half %.4f, dielectric half %.4f (se %.2g)\n", m[0], m[1],
           se);
    tr_film_free(&film);
    tr_scene_clear(&s);
}

#define TEXDATA TR_SOURCE_DIR "/tests/data/texture"

/* 3b. Next-event estimation reads a light's emission through tr_emitted_at (a faster path
 * than evaluating the whole material): it must equal tr_emitted of the whole material stage, on a
 * textured emissive quad (the attribute path: the emission texture varies over it) and on the same
 * quad with a plain emitter (the path that reads the material alone), from both sides. */
static void emitted_at_matches(int textured) {
    tr_scene s = {0};
    tr_scene_init(&s);
    tr_error err;
    uint32_t mat;
    if (textured) {
        uint32_t tex;
        CHECK(tr_scene_add_texture(&s, tex_rgba, TW, TH, 0u, &tex, &err) == TR_OK, "%s", err.msg);
        mat = add_mat(&s, tr_material_diffuse(v3s(0.5f)));
        tr_material_ext ext = tr_material_ext_default();
        ext.emission = v3(2.0f, 1.0f, 0.5f);
        ext.emission_tex = tex;
        CHECK(tr_scene_set_material_ext(&s, mat, &ext, &err) == TR_OK, "%s", err.msg);
    } else {
        mat = add_mat(&s, tr_material_emitter(v3(1.0f, 0.5f, 0.25f), 3.0f));
    }
    const float pos[12] = {-1, 1, 0, 1, 1, 0, 1, -1, 0, -1, -1, 0};
    const float uv[8] = {0, 0, 1, 0, 1, 1, 0, 1};
    const uint32_t idx[6] = {0, 1, 2, 0, 2, 3};
    CHECK(tr_scene_add_mesh_uv(&s, pos, 4, idx, 2, NULL, textured ? uv : NULL, mat, NULL, NULL,
                               &err) == TR_OK,
          "%s", err.msg);
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
    const tr_scene_view view = tr_scene_view_of(&s);
    CHECK((view.tri_verts_count == 0u && view.material_ext_count == 0u) == !textured,
          "the scene takes the path meant");
    int checked = 0, lit = 0;
    for (uint32_t t = 0; t < view.triangle_count; ++t) {
        tr_vec3 ng = view.triangles[t].normal;
        for (int k = 0; k < 16; ++k) {
            float u = 0.05f + 0.06f * (float)k, v = 0.9f - u; /* inside: u + v < 1 */
            if (v < 0.0f) {
                v = 0.02f;
            }
            tr_vec3 p = v3_add(v3_add(v3_scale(view.triangles[t].v0, 1.0f - u - v),
                                      v3_scale(view.triangles[t].v1, u)),
                               v3_scale(view.triangles[t].v2, v));
            for (int side = 0; side < 2; ++side) {
                tr_vec3 w = side ? v3_neg(ng) : ng;
                tr_bsdf_params b = tr_material_eval(&view, t, u, v, p, ng, v3_neg(w));
                tr_vec3 want = tr_emitted(&b, w);
                tr_vec3 got = tr_emitted_at(&view, t, u, v, p, ng, w);
                CHECK(got.x == want.x && got.y == want.y && got.z == want.z,
                      "triangle %u (%g, %g) side %d: (%g %g %g) against (%g %g %g)", t, u, v, side,
                      got.x, got.y, got.z, want.x, want.y, want.z);
                lit += want.x + want.y + want.z > 0.0f;
                ++checked;
            }
        }
    }
    CHECK(checked == 64 && lit == 32, "%d points, %d lit (only the front emits)", checked, lit);
    tr_scene_clear(&s);
}

static void test_emitted_at(void) {
    emitted_at_matches(1);
    emitted_at_matches(0);
}

static void test_texture_files(void) {
    tr_scene s = {0};
    tr_scene_init(&s);
    tr_error err;
    uint32_t index = 99;
    CHECK(tr_scene_load_texture(&s, TEXDATA "/checker.png", 0u, &index, &err) == TR_OK, "%s",
          err.msg);
    CHECK(index == 0 && s.texture_count == 1 && s.textures[0].width == TW &&
              s.textures[0].height == TH,
          "checker.png: %u textures", s.texture_count);
    for (int i = 0; s.texture_count == 1 && i < TW * TH; ++i) {
        CHECK(s.texels[i] == tex_rgba[i], "texel %d: %08x vs %08x", i, s.texels[i], tex_rgba[i]);
    }
    static const struct {
        const char *file;
        tr_status code;
    } bad[] = {{TEXDATA "/no-such-texture.png", TR_STATUS_NOT_FOUND},
               {TEXDATA "/truncated.png", TR_STATUS_PARSE},
               {TEXDATA "/zero.png", TR_STATUS_PARSE},
               {TEXDATA "/not_image.png", TR_STATUS_PARSE},
               {TEXDATA "/chunk_past_end.png", TR_STATUS_PARSE},
               {TEXDATA "/rle_past_end.tga", TR_STATUS_PARSE},
               {TEXDATA, TR_STATUS_IO}};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        CHECK_STATUS(tr_scene_load_texture(&s, bad[i].file, 0u, &index, &err), err, bad[i].code,
                     bad[i].file);
    }
    /* The declared size is refused before anything is decoded: stb_image's own limit
     * (parse error) or ours (limit), whichever looks first. */
    int rc = tr_scene_load_texture(&s, TEXDATA "/huge.png", 0u, &index, &err);
    CHECK(rc == TR_ERR && (err.code == TR_STATUS_PARSE || err.code == TR_STATUS_LIMIT),
          "huge.png: rc %d", rc);
    CHECK(s.texture_count == 1 && s.texel_count == TW * TH, "failures add nothing");
    tr_scene_clear(&s);

    /* The PNG chunk walk that runs before stb_image: a whole PNG fits, so does one with
     * bytes after IEND; one cut inside its IDAT or its IEND does not, nor does the file
     * fuzz_texture found; other formats pass through. */
    unsigned char *png = NULL;
    size_t len = 0;
    CHECK(tr_read_image_file(TEXDATA "/checker.png", &png, &len, &err) == TR_OK, "%s", err.msg);
    if (png) {
        CHECK(tr_png_chunks_fit(png, len), "checker.png does not fit");
        CHECK(len > 8 + 25 + 13 && memcmp(png + 8 + 25 + 4, "IDAT", 4) == 0,
              "checker.png: no IDAT after IHDR");
        CHECK(!tr_png_chunks_fit(png, 8 + 25 + 13), "a cut inside IDAT fits");
        CHECK(!tr_png_chunks_fit(png, len - 1), "a cut inside IEND fits");
        unsigned char *more = malloc(len + 5);
        if (more) {
            memcpy(more, png, len);
            memcpy(more + len, "extra", 5);
            CHECK(tr_png_chunks_fit(more, len + 5), "bytes after IEND refused");
            free(more);
        }
        free(png);
    }
    CHECK(tr_read_image_file(TEXDATA "/chunk_past_end.png", &png, &len, &err) == TR_OK, "%s",
          err.msg);
    if (png) {
        CHECK(!tr_png_chunks_fit(png, len), "chunk_past_end.png fits");
        free(png);
    }
    static const unsigned char hdr[] = "#?RADIANCE\n\n-Y 1 +X 1\n\1\2\3\4";
    CHECK(tr_png_chunks_fit(hdr, sizeof hdr - 1), "an HDR refused by the PNG walk");

    /* The declared size against the file's length: the 17-byte TGA fuzz_texture found
     * declares 9799x4096 texels; a TGA of 2x1 texels that holds them decodes, the same
     * header declaring 2000x1 in 24 bytes does not (64 texels a byte at most). */
    unsigned char tga[18 + 6] = {
        0, 0, 2, 0, 0,  0,    0, 0, 0, 0, 0, 0,
        2, 0, 1, 0, 24, 0x20, 3, 2, 1, 6, 5, 4}; /* uncompressed, top row first, BGR */
    CHECK(tr_image_max_texels_per_byte(tga, sizeof tga) == 64, "TGA: %u",
          tr_image_max_texels_per_byte(tga, sizeof tga));
    CHECK(tr_read_image_file(TEXDATA "/checker.png", &png, &len, &err) == TR_OK, "%s", err.msg);
    if (png) {
        CHECK(tr_image_max_texels_per_byte(png, len) == 8256, "PNG: %u",
              tr_image_max_texels_per_byte(png, len));
        free(png);
    }
    uint32_t *rgba = NULL, w = 0, h = 0;
    CHECK(tr_image_decode_rgba8(tga, sizeof tga, "tga", &rgba, &w, &h, &err) == TR_OK && w == 2 &&
              h == 1 && rgba[0] == 0xff030201u && rgba[1] == 0xff060504u,
          "%s", err.msg);
    free(rgba);
    rgba = NULL;
    unsigned char wide[sizeof tga];
    memcpy(wide, tga, sizeof tga);
    wide[12] = 2000 & 0xff;
    wide[13] = 2000 >> 8;
    CHECK_STATUS(tr_image_decode_rgba8(wide, sizeof wide, "wide", &rgba, &w, &h, &err), err,
                 TR_STATUS_PARSE, "2000x1 texels in 24 bytes");
    CHECK(rgba == NULL, "a refused image left texels");

    /* 8-bit images as linear floats: a gamma of 2.2 on each channel, in order. */
    float *rgb = NULL;
    CHECK(tr_image_decode_rgbf(tga, sizeof tga, "tga", &rgb, &w, &h, &err) == TR_OK && w == 2 &&
              h == 1,
          "%s", err.msg);
    for (int i = 0; rgb && i < 6; ++i) {
        const float want = (float)pow((float)(i + 1) / 255.0f, 2.2f);
        CHECK(rgb[i] == want, "channel %d: %g, want %g", i, (double)rgb[i], (double)want);
    }
    free(rgb);
}

static void test_env_sampling(void) {
    tr_scene s = {0};
    tr_scene_init(&s);
    tr_error err;
    CHECK(tr_scene_load_environment(&s, TEXDATA "/sky.hdr", v3s(1.0f), 2.0f, 0.7f, &err) == TR_OK,
          "%s", err.msg);
    tr_scene_view v = tr_scene_view_of(&s);
    const uint32_t w = s.env.width, h = s.env.height, n = w * h;
    CHECK(w == 32 && h == 16, "sky.hdr: %ux%u", w, h);
    if (w != 32 || h != 16) {
        tr_scene_clear(&s);
        return;
    }
    /* The density integrates to 1: midpoint rule over 512 x 256 cells in (t, p). */
    double integral = 0.0;
    for (int a = 0; a < 256; ++a) {
        double t = (a + 0.5) * 3.14159265358979 / 256;
        for (int b = 0; b < 512; ++b) {
            double p = (b + 0.5) * 2 * 3.14159265358979 / 512;
            tr_vec3 d = v3((float)(sin(t) * cos(p)), (float)cos(t), (float)(sin(t) * sin(p)));
            integral += tr_env_pdf(&v, d) * sin(t) * (3.14159265358979 / 256) *
                        (2 * 3.14159265358979 / 512);
        }
    }
    CHECK_NEAR(integral, 1.0, 0.01, "the environment's pdf integrates to 1");
    /* Chi-square over the texels: expected fraction weight / sum. */
    static double count[32 * 16];
    memset(count, 0, sizeof count);
    const int N = 400000;
    tr_rng rng;
    tr_rng_init(&rng, 2024, 5, 6);
    int bad_pdf = 0;
    for (int k = 0; k < N; ++k) {
        float u1 = tr_rng_float(&rng), u2 = tr_rng_float(&rng);
        tr_vec3 d;
        float pdf;
        tr_vec3 le = tr_env_sample(&v, u1, u2, &d, &pdf);
        float st;
        uint32_t t = tr_env_texel_of(&s.env, tr_env_to_local(&s.env, d), &st);
        count[t] += 1;
        tr_vec3 want = tr_env_radiance(&v, d);
        if (!(fabsf(pdf - tr_env_pdf(&v, d)) <= 1e-4f * pdf) || le.x != want.x) {
            ++bad_pdf;
        }
    }
    CHECK(bad_pdf == 0, "%d samples disagree with tr_env_pdf / tr_env_radiance", bad_pdf);
    double chi2 = 0.0, pool_e = 0.0, pool_o = 0.0;
    int bins = 0;
    for (uint32_t k = 0; k < n; ++k) {
        double e = tr_env_weight(&v, k, k / w) / s.env.weight_sum * N;
        if (e < 5.0) {
            pool_e += e;
            pool_o += count[k];
            continue;
        }
        chi2 += (count[k] - e) * (count[k] - e) / e;
        ++bins;
    }
    if (pool_e >= 5.0) {
        chi2 += (pool_o - pool_e) * (pool_o - pool_e) / pool_e;
        ++bins;
    }
    double crit = chi2_critical(bins - 1);
    CHECK(bins > 100 && chi2 < crit, "environment sampling: chi2 %.1f, %d bins (critical %.1f)",
          chi2, bins, crit);
    tr_scene_clear(&s);
}

#define NSIGMA_ENV 5.0

static void test_env_furnace(void) {
    tr_scene s = {0};
    tr_scene_init(&s);
    tr_error err;
    const float albedo = 0.6f;
    const tr_vec3 L = v3(0.5f, 1.0f, 2.0f);
    uint32_t mat = add_mat(&s, tr_material_diffuse(v3s(albedo)));
    tr_shape_desc d = tr_shape_desc_default(TR_SHAPE_ICOSPHERE_SMOOTH);
    d.material = mat;
    d.subdivisions = 3;
    CHECK(tr_scene_add_shape(&s, &d, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_scene_set_environment(&s, L, 1.0f, 0.0f, NULL, 0, 0, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
    tr_camera cam;
    CHECK(tr_camera_make(&cam, v3(0.0f, 0.0f, 3.0f), v3(0.0f, 0.0f, -1.0f), v3(0.0f, 1.0f, 0.0f),
                         45.0f, 1e-3f, 1e3f, 32, 32, &err) == TR_OK,
          "%s", err.msg);
    tr_film film;
    CHECK(tr_film_init(&film, 32, 32, &err) == TR_OK, "%s", err.msg);
    tr_render_config cfg = tr_render_config_default();
    cfg.max_depth = 64; /* a convex sphere: every path leaves after one bounce anyway */
    for (uint32_t smp = 0; smp < 16; ++smp) {
        CHECK(tr_render_frame(&s, &cam, &cfg, &film, smp, NULL, &err) == TR_OK, "%s", err.msg);
    }
    /* The centre 8x8 pixels see only the sphere, the corners only the environment. The
     * bound: 5 standard errors of the mean, from the spread of the 64 pixels' means. */
    double m[3] = {0, 0, 0}, m2[3] = {0, 0, 0};
    for (uint32_t y = 12; y < 20; ++y) {
        for (uint32_t x = 12; x < 20; ++x) {
            tr_vec3 px = tr_film_pixel(&film, x, y);
            const double c[3] = {px.x, px.y, px.z};
            for (int k = 0; k < 3; ++k) {
                m[k] += c[k] / 64;
                m2[k] += c[k] * c[k] / 64;
            }
        }
    }
    const double want[3] = {albedo * L.x, albedo * L.y, albedo * L.z};
    for (int k = 0; k < 3; ++k) {
        double se = sqrt(fmax(0.0, m2[k] - m[k] * m[k]) / 63.0);
        CHECK(fabs(m[k] - want[k]) <= NSIGMA_ENV * se + 1e-6,
              "furnace channel %d: %.4f vs %.4f (se %.4f)", k, m[k], want[k], se);
        CHECK(se < 0.05 * want[k], "furnace channel %d: se %.4f (the test must be tight)", k, se);
    }
    tr_vec3 corner = tr_film_pixel(&film, 0, 0);
    CHECK(corner.x == L.x && corner.y == L.y && corner.z == L.z, "background is L");
    printf("env furnace: %.4f %.4f %.4f vs %.4f %.4f %.4f\n", m[0], m[1], m[2], want[0], want[1],
           want[2]);
    tr_film_free(&film);
    tr_scene_clear(&s);
}

int main(void) {
    test_smooth_icosphere();
    test_texture_lookup();
    test_textured_quad();
    test_emitted_at();
    test_texture_files();
    test_normal_map();
    test_metallic_roughness_map();
    test_env_sampling();
    test_env_furnace();
    return check_finish("test_surface");
}
