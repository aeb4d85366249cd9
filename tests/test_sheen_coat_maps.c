/* test_sheen_coat_maps.c - glTF's sheen maps (KHR_materials_sheen's sheenColorTexture and
 * sheenRoughnessTexture) and the clear coat's own normal map (KHR_materials_clearcoat's
 * clearcoatNormalTexture), from the import to the principled BSDF.
 *
 *  (a) glTF import: a triangle whose material has both sheen maps and a coat normal map
 *      (three different images) imports with no warning; at a hit the material stage
 *      gives the sheen colour = factor x the colour map's texel (sRGB-decoded), the sheen
 *      roughness = factor x the roughness map's alpha / 255, and the coat's normal = the
 *      map's texel in the triangle's tangent frame (glTF's +Y up in the image), scaled by
 *      the map's scale; the base's shading normal and every other parameter are those of
 *      the same material without the coat's map, bit for bit.
 *  (b) the scene-file keys sheen_color_texture, sheen_roughness_texture,
 *      clearcoat_normal_texture and clearcoat_normal_scale on a principled material give
 *      the same values; on a diffuse material each is refused (a parse error naming the
 *      file and the key).
 *  (c) the BSDF with a tilted coat normal: reciprocal; its white furnace reflects no more
 *      than arrives, the sampler's albedo equals a uniform estimate of the integral of
 *      f cos (so the pdf is the sampler's density), with and without the energy
 *      compensation; the coat's highlight follows the coat's normal while the base's
 *      does not move; a coat of weight 0 with a normal, and sheen maps of value 1, are
 *      bit for bit none; a black sheen map turns the sheen off, bit for bit.
 *
 * Fixed seeds; statistical bounds are 5 standard errors. */
#define _POSIX_C_SOURCE 200809L
#include "bsdf_util.h"
#include "check.h"
#include "model_util.h"
#include "kernel/kernel.h"
#include "scene/scene_internal.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#define PI_D 3.14159265358979323846
#define NSIGMA 5.0

/* 2x2 PNGs of one RGBA colour each: S (200, 120, 40, 255) the sheen's colour, R (10, 20,
 * 30, 100) its roughness (alpha), N (200, 90, 230, 255) the coat's normal. A value read
 * from the wrong channel or the wrong image gives another number. */
#define PNG_S                                                                                      \
    "iVBORw0KGgoAAAANSUhEUgAAAAIAAAACCAYAAABytg0kAAAAEUlEQVR42mM4UaHxH4QZYAwAVeQJnVgR5VEAAAAASU"   \
    "VORK5CYII="
#define PNG_R                                                                                      \
    "iVBORw0KGgoAAAANSUhEUgAAAAIAAAACCAYAAABytg0kAAAAEUlEQVR42mPgEpFLAWEGGAMAFGICgZUTlXEAAAAASU"   \
    "VORK5CYII="
#define PNG_N                                                                                      \
    "iVBORw0KGgoAAAANSUhEUgAAAAIAAAACCAYAAABytg0kAAAAEUlEQVR42mM4EfXsPwgzwBgAaqwMHYHrwlkAAAAASU"   \
    "VORK5CYII="

static double srgb(double c) {
    return c <= 0.04045 ? c / 12.92 : pow((c + 0.055) / 1.055, 2.4);
}

/* The coat normal map N's normal with x and y scaled by `scale`, on a triangle whose
 * texture u runs along +x and v along +y (image downwards) with normal +z: tangent +x,
 * and glTF's +Y (up in the image) is -y. */
static tr_vec3 expected_coat_normal(double scale) {
    const double kx = 2.0 * 200.0 / 255.0 - 1.0, ky = 2.0 * 90.0 / 255.0 - 1.0;
    const double kz = 2.0 * 230.0 / 255.0 - 1.0;
    const double x = kx * scale, y = -ky * scale, l = sqrt(x * x + y * y + kz * kz);
    return v3((float)(x / l), (float)(y / l), (float)(kz / l));
}

/* The triangle (0, 0, 0), (1, 0, 0), (0, 1, 0) with texture coordinates (0, 0), (1, 0),
 * (0, 1); its material has a sheen (colour factor 0.8, 0.6, 0.4, roughness 0.5) with
 * colour map S and roughness map R, and a coat (weight 1, roughness 0.2) with normal map N
 * of scale 0.5. */
static int write_gltf(const char *path) {
    FILE *f = fopen(path, "w");
    if (!f) {
        return 0;
    }
    fprintf(
        f, "{\"asset\": {\"version\": \"2.0\"},\n"
           " \"extensionsUsed\": [\"KHR_materials_clearcoat\", "
           "\"KHR_materials_sheen\"],\n" GLTF_TRIANGLE_GEOMETRY
           " \"images\": [{\"uri\": \"data:image/png;base64," PNG_S "\"},\n"
           "            {\"uri\": \"data:image/png;base64," PNG_R "\"},\n"
           "            {\"uri\": \"data:image/png;base64," PNG_N "\"}],\n"
           " \"textures\": [{\"source\": 0}, {\"source\": 1}, {\"source\": 2}],\n"
           " \"materials\": [{\"name\": \"velvet\", \"pbrMetallicRoughness\": "
           "{\"baseColorFactor\": [0.2, 0.3, 0.8, 1], \"roughnessFactor\": 0.5, "
           "\"metallicFactor\": 0},\n"
           "   \"extensions\": {\"KHR_materials_sheen\": {\"sheenColorFactor\": [0.8, 0.6, 0.4], "
           "\"sheenRoughnessFactor\": 0.5, \"sheenColorTexture\": {\"index\": 0}, "
           "\"sheenRoughnessTexture\": {\"index\": 1}},\n"
           "     \"KHR_materials_clearcoat\": {\"clearcoatFactor\": 1, "
           "\"clearcoatRoughnessFactor\": 0.2, "
           "\"clearcoatNormalTexture\": {\"index\": 2, \"scale\": 0.5}}}}],\n" GLTF_TRIANGLE_SCENE);
    return fclose(f) == 0;
}

/* The material stage on triangle 0 at barycentrics (0.3, 0.6). */
static tr_bsdf_params stage(const tr_scene *s) {
    tr_scene_view v = tr_scene_view_of(s);
    const tr_triangle *t = &s->triangles[0];
    tr_vec3 p = v3_add(v3_add(v3_scale(t->v0, 0.1f), v3_scale(t->v1, 0.3f)), v3_scale(t->v2, 0.6f));
    return tr_material_eval(&v, 0, 0.3f, 0.6f, p, t->normal, v3(0.0f, 0.0f, -1.0f));
}

/* The values (a) and (b) check, for the scene's first material with coat normal scale
 * `scale` and sheen factors (0.8, 0.6, 0.4) and 0.5. */
static void check_stage(tr_scene *s, double scale, const char *what) {
    tr_error err;
    CHECK(tr_scene_commit(s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
    CHECK(s->triangle_count >= 1 && s->material_ext_count == s->material_count, "%s: no extras",
          what);
    if (s->triangle_count < 1 || s->material_ext_count != s->material_count) {
        return;
    }
    const uint32_t mi = s->triangles[0].material;
    tr_material_ext *e = &s->material_exts[mi];
    const uint32_t maps = tr_scene_material_maps(s, mi);
    CHECK(e->sheen_color_tex != TR_NO_INDEX && e->sheen_rough_tex != TR_NO_INDEX &&
              e->clearcoat_normal_tex != TR_NO_INDEX && e->sheen_color_tex != e->sheen_rough_tex &&
              (maps & TR_MAP_SHEEN_COLOR) && (maps & TR_MAP_SHEEN_ROUGHNESS) &&
              (maps & TR_MAP_CLEARCOAT_NORMAL),
          "%s: maps %u, %u, %u (flags %u)", what, e->sheen_color_tex, e->sheen_rough_tex,
          e->clearcoat_normal_tex, maps);
    CHECK_NEAR(e->clearcoat_normal_scale, scale, 1e-6, "the coat normal map's scale");
    tr_bsdf_params b = stage(s);
    tr_vec3 sc = tr_sheen_color(&b);
    CHECK_NEAR(sc.x, 0.8 * srgb(200.0 / 255.0), 1e-4, "sheen red: factor x the map's (sRGB)");
    CHECK_NEAR(sc.y, 0.6 * srgb(120.0 / 255.0), 1e-4, "sheen green: factor x the map's");
    CHECK_NEAR(sc.z, 0.4 * srgb(40.0 / 255.0), 1e-4, "sheen blue: factor x the map's");
    CHECK_NEAR(tr_sheen_roughness(&b), 0.5 * 100.0 / 255.0, 1e-4,
               "sheen roughness: factor x the roughness map's alpha");
    CHECK(b.coat_n != 0u, "%s: no coat normal at the hit", what);
    tr_vec3 nc = tr_unpack_oct(b.coat_n), want = expected_coat_normal(scale);
    CHECK(fabs(nc.x - want.x) < 1e-4 && fabs(nc.y - want.y) < 1e-4 && fabs(nc.z - want.z) < 1e-4,
          "%s: coat normal (%.5f, %.5f, %.5f), expected (%.5f, %.5f, %.5f)", what, (double)nc.x,
          (double)nc.y, (double)nc.z, (double)want.x, (double)want.y, (double)want.z);
    /* Only the coat tilts: without its map every other parameter is the same. */
    const uint32_t keep = e->clearcoat_normal_tex;
    e->clearcoat_normal_tex = TR_NO_INDEX;
    tr_bsdf_params b0 = stage(s);
    e->clearcoat_normal_tex = keep;
    CHECK(b0.coat_n == 0u, "%s: a coat normal without the map", what);
    b0.coat_n = b.coat_n;
    CHECK(memcmp(&b0, &b, sizeof b) == 0, "%s: the coat's map changed more than the coat", what);
    CHECK(b.ns.x == 0.0f && b.ns.y == 0.0f && b.ns.z == 1.0f, "%s: base normal (%g, %g, %g)", what,
          (double)b.ns.x, (double)b.ns.y, (double)b.ns.z);
    /* The same map as the base's normal map and none of the coat's own: the base tilts,
     * the coat keeps the interpolated normal (glTF: a coat without its map is not
     * normal-mapped). */
    const uint32_t base_keep = e->normal_tex;
    const float scale_keep = e->normal_scale;
    e->normal_tex = keep;
    e->normal_scale = 1.0f;
    e->clearcoat_normal_tex = TR_NO_INDEX;
    tr_bsdf_params b1 = stage(s);
    e->normal_tex = base_keep;
    e->normal_scale = scale_keep;
    e->clearcoat_normal_tex = keep;
    const tr_vec3 n1 = tr_unpack_oct(b1.coat_n);
    CHECK(b1.ns.z < 0.999f && b1.coat_n != 0u && fabs(n1.x) < 1e-4 && fabs(n1.y) < 1e-4 &&
              fabs(n1.z - 1.0) < 1e-4,
          "%s: base normal map only: base (%g, %g, %g), coat (%g, %g, %g)", what, (double)b1.ns.x,
          (double)b1.ns.y, (double)b1.ns.z, (double)n1.x, (double)n1.y, (double)n1.z);
}

/* (a) */
static void gltf_maps(const char *dir) {
    char path[700];
    snprintf(path, sizeof path, "%s/velvet.gltf", dir);
    CHECK(write_gltf(path), "cannot write %s", path);
    tr_scene s;
    tr_scene_file info;
    load_model_file(&s, path, &info);
    CHECK(info.warning_count == 0, "%u warnings", info.warning_count);
    for (uint32_t k = 0; k < info.warning_count; ++k) {
        printf("warning: %s\n", info.warnings[k]);
    }
    check_stage(&s, 0.5, "glTF");
    tr_scene_clear(&s);
    unlink(path);
}

/* Parses a one-material scene file at dir/maps.json: the unit quad [0, 1]^2, its corners at
 * the texture coordinates of the same numbers. */
static int parse(tr_scene *s, const char *dir, const char *material, tr_error *err) {
    char path[700];
    snprintf(path, sizeof path, "%s/maps.json", dir);
    return parse_material_quad(s, path, material, 0.0, 1.0, err);
}

/* (b) */
static void scene_file_keys(const char *dir) {
    static const char *const names[3] = {"s.png", "r.png", "n.png"};
    static const char *const b64[3] = {PNG_S, PNG_R, PNG_N};
    write_base64_files(dir, names, b64, 3, 0);
    tr_scene s;
    tr_error err;
    CHECK(parse(&s, dir,
                "{\"type\": \"principled\", \"color\": [0.2, 0.3, 0.8], \"roughness\": 0.5, "
                "\"sheen_color\": [0.8, 0.6, 0.4], \"sheen_roughness\": 0.5, "
                "\"sheen_color_texture\": \"s.png\", \"sheen_roughness_texture\": \"r.png\", "
                "\"clearcoat\": 1, \"clearcoat_roughness\": 0.2, "
                "\"clearcoat_normal_texture\": \"n.png\", \"clearcoat_normal_scale\": 0.75}",
                &err) == TR_OK,
          "sheen and coat normal maps in a scene file: %s", err.msg);
    check_stage(&s, 0.75, "scene file");
    tr_scene_clear(&s);

    /* The principled material's keys alone. */
    static const char *const keys[4] = {"sheen_color_texture", "sheen_roughness_texture",
                                        "clearcoat_normal_texture", "clearcoat_normal_scale"};
    char path[700];
    snprintf(path, sizeof path, "%s/maps.json", dir);
    for (int k = 0; k < 4; ++k) {
        check_key_refused(path, "maps.json", keys[k], k == 3 ? "0.5" : "\"s.png\"");
    }
    write_base64_files(dir, names, b64, 3, 1);
}

/* ---- (c) the BSDF ------------------------------------------------------------------- */

/* A principled material on the plane z = 0 (normal +z) under a coat of weight c and
 * roughness rc whose normal is tilted by `tilt` degrees towards +x (0: none). */
static tr_bsdf_params coated(tr_vec3 color, float roughness, float metallic, float c, float rc,
                             double tilt) {
    tr_material m;
    memset(&m, 0, sizeof m);
    m.type = TR_MATERIAL_PRINCIPLED;
    m.color = color;
    m.roughness = roughness;
    m.ior = 1.5f;
    tr_bsdf_params b = tr_material_params(&m, v3(0.0f, 0.0f, 1.0f));
    b.metallic = metallic;
    b.clearcoat = c;
    b.clearcoat_roughness = rc;
    if (tilt != 0.0) {
        const double t = tilt * PI_D / 180.0;
        b.coat_n = tr_pack_oct(v3((float)sin(t), 0.0f, (float)cos(t)));
    }
    return b;
}

/* Reciprocal within 1e-3 on 20000 random pairs, with f > 0 on most of them. */
static int reciprocal(const tr_bsdf_params *m, uint64_t seed) {
    int nonzero;
    return bsdf_not_reciprocal(m, seed, &nonzero) == 0 && nonzero > 10000;
}

/* Albedo towards wo by the sampler (mean weight) and by uniform hemisphere sampling of
 * f cos; counts samples whose weight is not eval cos / pdf. */
static void albedo(const tr_bsdf_params *m, tr_vec3 wo, uint64_t seed, double *sampled,
                   double *se_sampled, double *uniform, double *se_uniform, int *inconsistent) {
    tr_rng rng;
    tr_rng_init(&rng, 4321, seed, 7);
    bsdf_albedo(m, wo, 200000, &rng, sampled, se_sampled, uniform, se_uniform, inconsistent);
}

static void bsdf_tests(void) {
    const float *tab = tr_ggx_ms_table();
    /* Reciprocity and the furnace over white dielectric and metallic bases, coats of two
     * roughnesses tilted by 25 degrees, outgoing directions on both sides of the tilt. */
    const float coat_r[] = {0.3f, 0.6f};
    const double theta[] = {0.0, 40.0, 75.0}, phi[] = {0.0, PI_D};
    for (int c = 0; c < 2; ++c) {
        for (int k = 0; k < 2; ++k) {
            for (int comp = 0; comp < 2; ++comp) {
                tr_bsdf_params p = coated(v3s(1.0f), 0.5f, (float)k, 1.0f, coat_r[c], 25.0);
                p.ms = tab;
                p.flags = comp ? TR_MATERIAL_MULTISCATTER : 0u;
                tr_bsdf_params q = p;
                q.color = v3(0.9f, 0.6f, 0.3f);
                CHECK(reciprocal(&q, 77 + (uint64_t)(4 * c + 2 * k + comp)),
                      "tilted coat r=%.2f m=%d comp %d: not reciprocal", (double)coat_r[c], k,
                      comp);
                for (int t = 0; t < 3; ++t) {
                    for (int f = 0; f < 2 && (t > 0 || f == 0); ++f) {
                        const double to = theta[t] * PI_D / 180.0;
                        tr_vec3 wo = v3((float)(sin(to) * cos(phi[f])), 0.0f, (float)cos(to));
                        double a, sa, u, su;
                        int bad;
                        albedo(&p, wo, (uint64_t)(100 * c + 10 * k + 3 * t + f), &a, &sa, &u, &su,
                               &bad);
                        printf("tilted coat r=%.2f over white m=%d comp %d at %+.0f deg: albedo "
                               "%.5f (uniform %.5f)\n",
                               (double)coat_r[c], k, comp, f ? -theta[t] : theta[t], a, u);
                        CHECK(a <= 1.0 + NSIGMA * sa, "tilted coat: albedo %.5f > 1", a);
                        CHECK(fabs(a - u) <= NSIGMA * sqrt(sa * sa + su * su),
                              "tilted coat r=%.2f m=%d comp %d theta %.0f: sampled %.5f vs "
                              "uniform %.5f",
                              (double)coat_r[c], k, comp, f ? -theta[t] : theta[t], a, u);
                        CHECK(bad == 0, "tilted coat: %d samples disagree with eval and pdf", bad);
                    }
                }
            }
        }
    }
    /* The highlight: a smooth coat over a black conductor (only the coat reflects) seen
     * from 30 degrees peaks at the mirror direction about the coat's normal (tilted 10
     * degrees towards the viewer: the reflection leaves at 10 degrees on the far side,
     * where the untilted coat's leaves at 30), and the coat's samples go there. A base
     * without a coat is the same whatever coat_n says. */
    {
        const double to = 30.0 * PI_D / 180.0, tc = 10.0;
        const tr_vec3 wo = v3((float)sin(to), 0.0f, (float)cos(to));
        const tr_vec3 at_coat =
            v3((float)-sin(10.0 * PI_D / 180.0), 0.0f, (float)cos(10.0 * PI_D / 180.0));
        const tr_vec3 at_base = v3((float)-sin(to), 0.0f, (float)cos(to));
        tr_bsdf_params tilted = coated(v3s(0.0f), 0.5f, 1.0f, 1.0f, 0.1f, tc);
        tr_bsdf_params flat = coated(v3s(0.0f), 0.5f, 1.0f, 1.0f, 0.1f, 0.0);
        const double ft_c = tr_bsdf_eval(&tilted, wo, at_coat).x;
        const double ft_b = tr_bsdf_eval(&tilted, wo, at_base).x;
        const double ff_c = tr_bsdf_eval(&flat, wo, at_coat).x;
        const double ff_b = tr_bsdf_eval(&flat, wo, at_base).x;
        CHECK(ft_c > 20.0 * ft_b && ff_b > 20.0 * ff_c,
              "the coat's highlight: tilted %.4g at its mirror direction vs %.4g at the base's; "
              "untilted %.4g vs %.4g",
              ft_c, ft_b, ff_c, ff_b);
        /* Every sample of the coat's lobe lands near the tilted mirror direction. */
        tr_rng rng;
        tr_rng_init(&rng, 9, 9, 9);
        int near = 0, drawn = 0;
        for (int k = 0; k < 2000; ++k) {
            tr_scatter s;
            if (tr_bsdf_sample(&tilted, wo, 0.0f, tr_rng_float(&rng), tr_rng_float(&rng), &s)) {
                ++drawn;
                near += v3_dot(s.wi, at_coat) > cosf(0.2f);
            }
        }
        CHECK(drawn > 1500 && near > (drawn * 9) / 10, "coat samples: %d of %d near its mirror",
              near, drawn);
        tr_bsdf_params g0 = coated(v3s(0.9f), 0.2f, 1.0f, 0.0f, 0.0f, 0.0);
        tr_bsdf_params g1 = coated(v3s(0.9f), 0.2f, 1.0f, 0.0f, 0.0f, tc);
        CHECK(bsdf_differences(&g0, &g1, 3) == 0, "without a coat its normal changed the base");
    }
    /* Weight 0 with a tilted normal: none, bit for bit. */
    tr_bsdf_params p0 = coated(v3(0.9f, 0.6f, 0.3f), 0.5f, 0.3f, 0.0f, 0.3f, 0.0);
    tr_bsdf_params p1 = coated(v3(0.9f, 0.6f, 0.3f), 0.5f, 0.3f, 0.0f, 0.3f, 20.0);
    CHECK(bsdf_differences(&p0, &p1, 5) == 0, "a coat of weight 0 with a normal differs from none");

    /* Sheen maps: all 1 is the factors bit for bit; black turns the sheen off bit for bit;
     * in between, the factors times the packed values. */
    tr_material_ext e;
    memset(&e, 0, sizeof e);
    e.sheen_color = v3(0.8f, 0.6f, 0.9f);
    e.sheen_roughness = 0.5f;
    tr_bsdf_params s0 = coated(v3(0.9f, 0.6f, 0.3f), 0.5f, 0.0f, 0.0f, 0.0f, 0.0);
    s0.ext = &e;
    s0.ms = tab;
    tr_bsdf_params s1 = s0;
    s1.sheen_rg = tr_pack_map16(1.0f) | (tr_pack_map16(1.0f) << 16);
    s1.sheen_ba = tr_pack_map16(1.0f) | (tr_pack_map16(1.0f) << 16);
    CHECK(s1.sheen_rg == 0u && s1.sheen_ba == 0u && bsdf_differences(&s0, &s1, 6) == 0,
          "sheen maps of value 1 differ from none");
    tr_bsdf_params none = s0;
    none.ext = NULL;
    tr_bsdf_params black = s0;
    black.sheen_rg = tr_pack_map16(0.0f) | (tr_pack_map16(0.0f) << 16);
    black.sheen_ba = tr_pack_map16(0.0f) | (tr_pack_map16(0.7f) << 16);
    CHECK(tr_sheen_weight(&black) == 0.0f && bsdf_differences(&none, &black, 7) == 0,
          "a black sheen map leaves a sheen");
    tr_bsdf_params half = s0;
    half.sheen_rg = tr_pack_map16(0.25f) | (tr_pack_map16(0.5f) << 16);
    half.sheen_ba = tr_pack_map16(0.75f) | (tr_pack_map16(0.4f) << 16);
    tr_vec3 hc = tr_sheen_color(&half);
    CHECK(fabs(hc.x - 0.2) < 1e-4 && fabs(hc.y - 0.3) < 1e-4 && fabs(hc.z - 0.675) < 1e-4 &&
              fabs(tr_sheen_roughness(&half) - 0.2) < 1e-4,
          "packed sheen maps: (%g, %g, %g), roughness %g", (double)hc.x, (double)hc.y, (double)hc.z,
          (double)tr_sheen_roughness(&half));
    CHECK(reciprocal(&half, 11), "sheen with maps: not reciprocal");
    /* Octahedral normals: round trips within 2e-4 (summed over x, y, z) all over the sphere,
     * never 0. */
    tr_rng rng;
    tr_rng_init(&rng, 5, 6, 7);
    double worst = 0.0;
    int zero = 0;
    for (int k = 0; k < 100000; ++k) {
        tr_vec3 n = dir_of(2.0 * tr_rng_float(&rng) - 1.0, 2.0 * PI_D * tr_rng_float(&rng));
        if (k < 6) {
            n = v3(k == 0   ? 1.0f
                   : k == 1 ? -1.0f
                            : 0.0f,
                   k == 2   ? 1.0f
                   : k == 3 ? -1.0f
                            : 0.0f,
                   k == 4   ? 1.0f
                   : k == 5 ? -1.0f
                            : 0.0f);
        }
        uint32_t w = tr_pack_oct(n);
        zero += w == 0u;
        tr_vec3 r = tr_unpack_oct(w);
        worst = fmax(worst, fabs(r.x - n.x) + fabs(r.y - n.y) + fabs(r.z - n.z));
    }
    CHECK(zero == 0 && worst < 2e-4, "octahedral normals: %d zero, worst error %g", zero, worst);
    tr_vec3 dn = tr_unpack_oct(tr_pack_oct(v3(-1e-6f, -1e-6f, -1.0f)));
    CHECK(dn.z < -0.9999f, "-z round trips to (%g, %g, %g)", (double)dn.x, (double)dn.y,
          (double)dn.z);
}

int main(void) {
    char dir[] = "/tmp/trac0r-maps-XXXXXX";
    if (!mkdtemp(dir)) {
        CHECK(0, "mkdtemp");
        return check_finish("test_sheen_coat_maps");
    }
    gltf_maps(dir);
    scene_file_keys(dir);
    rmdir(dir);
    bsdf_tests();
    return check_finish("test_sheen_coat_maps");
}
