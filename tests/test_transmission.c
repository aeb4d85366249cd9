/* test_transmission.c - the principled material's transmission (KHR_materials_transmission
 * with KHR_materials_ior: the rough dielectric boundary of src/kernel/bsdf_dielectric.h)
 * and the volume's absorption (KHR_materials_volume), from the BSDF to scene files and
 * glTF import.
 *
 *  (a) Chi-square goodness of fit over the whole sphere: directions drawn by
 *      tr_bsdf_sample for a transmissive principled material, binned on (cos theta, phi),
 *      against the counts tr_bsdf_pdf predicts, from outside and from inside, at several
 *      roughnesses and angles; every sample's pdf and weight agree with tr_bsdf_pdf and
 *      tr_bsdf_eval.
 *  (b) Reciprocity: reflection is reciprocal, f(wo, wi) = f(wi, wo); refraction is not,
 *      and obeys f(wi, wo) eta^2 = f(wo, wi) with eta = n_i / n_o, the ratio of the indices
 *      on wi's and wo's sides (the boundary carries radiance / n^2, as smooth glass does).
 *  (c) White furnace: with a white tint every sample's weight is G2 / G1(wo), so it lies in
 *      [G1(wi), 1] (G2 >= G1(wo) G1(wi)): checked sample by sample, which bounds the albedo
 *      by 1 from above; the sampled albedo equals an independent estimate (uniform over the
 *      sphere) of the integral of f |cos|, within 5 standard errors.
 *  (d) Beer-Lambert: a slab of thickness d of an absorbing transmissive material (index
 *      1.01: no Fresnel, no bending) in front of a white environment: the centre pixels
 *      divided by those of the same slab without absorption are exp(-sigma d), with sigma
 *      = -ln(attenuation_color) / attenuation_distance, per channel. No absorption, or
 *      "transmission": 0, renders bit for bit as the file without the keys.
 *  (e) The keys: "transmission", "ior", "attenuation_color", "attenuation_distance" and
 *      "emission_strength" reach the material; out of range they are refused
 *      (TR_STATUS_PARSE), and a diffuse material refuses the principled-only ones.
 *  (f) glTF import: a glTF written here with KHR_materials_transmission, _ior, _volume
 *      becomes a principled material with that transmission, index and absorption, and no
 *      warning names those extensions.
 *  (g) glTF's transmissionTexture: imported as the transmission map (no warning, the
 *      thickness map beside it neither), whose red channel multiplies the factor in the
 *      kernel's material extras; the scene-file key "transmission_texture" reads one too. */
#define _POSIX_C_SOURCE 200809L
#include "check.h"
#include "model_util.h"
#include "kernel/kernel.h"
#include "scene/scene_internal.h"
#include "kernel/bsdf.h"
#include "render_film.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#define PI_D 3.14159265358979323846
#define NSIGMA 5.0

static tr_bsdf_params transmissive(float roughness, float ior, float transmission, float metallic) {
    tr_material m;
    memset(&m, 0, sizeof m);
    m.type = TR_MATERIAL_PRINCIPLED;
    m.color = v3s(1.0f);
    m.roughness = roughness;
    m.ior = ior;
    tr_bsdf_params b = tr_material_params(&m, v3(0.0f, 0.0f, 1.0f));
    b.transmission = transmission;
    b.metallic = metallic;
    return b;
}

static tr_vec3 dir_of(double cos_t, double phi) {
    double s = sqrt(fmax(0.0, 1.0 - cos_t * cos_t));
    return v3((float)(s * cos(phi)), (float)(s * sin(phi)), (float)cos_t);
}

/* wo at angle theta from +z (theta > 90: from inside). */
static tr_vec3 wo_at(double theta_deg) {
    const double t = theta_deg * PI_D / 180.0;
    return v3((float)sin(t), 0.0f, (float)cos(t));
}

enum { NC = 32, NP = 16, SUB = 24 };

/* (a) */
static void chi2_case(const tr_bsdf_params *m, double theta_deg, uint64_t seed) {
    const tr_vec3 wo = wo_at(theta_deg);
    static double expect[NC * NP + 1];
    double total = 0.0;
    for (int i = 0; i < NC; ++i) {
        /* cos theta in [-1 + 2i/NC, -1 + 2(i+1)/NC], integrated over theta (narrow lobes
         * near the poles stay resolved). */
        double th1 = acos(-1.0 + 2.0 * i / NC), th0 = acos(-1.0 + 2.0 * (i + 1) / NC);
        double dth = (th1 - th0) / SUB;
        for (int j = 0; j < NP; ++j) {
            double sum = 0.0;
            for (int a = 0; a < SUB; ++a) {
                double th = th0 + ((double)a + 0.5) * dth;
                for (int b = 0; b < SUB; ++b) {
                    double phi = 2.0 * PI_D * ((double)j + ((double)b + 0.5) / SUB) / NP;
                    sum += tr_bsdf_pdf(m, wo, dir_of(cos(th), phi)) * sin(th) * dth;
                }
            }
            expect[i * NP + j] = sum * (2.0 * PI_D / NP) / SUB;
            total += expect[i * NP + j];
        }
    }
    expect[NC * NP] = fmax(0.0, 1.0 - total);
    CHECK(total <= 1.0 + 2e-3, "r=%.2f theta %.0f: pdf integrates to %.5f > 1",
          (double)m->roughness, theta_deg, total);
    const int N = 200000;
    static double count[NC * NP + 1];
    memset(count, 0, sizeof count);
    tr_rng rng;
    tr_rng_init(&rng, seed, 5, 6);
    int inconsistent = 0, through = 0;
    for (int k = 0; k < N; ++k) {
        tr_scatter s;
        if (!tr_bsdf_sample(m, wo, tr_rng_float(&rng), tr_rng_float(&rng), tr_rng_float(&rng),
                            &s)) {
            count[NC * NP] += 1;
            continue;
        }
        through += s.wi.z * wo.z < 0.0f;
        double phi = atan2(s.wi.y, s.wi.x);
        phi += phi < 0.0 ? 2.0 * PI_D : 0.0;
        int i = (int)((s.wi.z + 1.0) * 0.5 * NC), j = (int)(phi / (2.0 * PI_D) * NP);
        i = i < 0 ? 0 : i >= NC ? NC - 1 : i;
        j = j < 0 ? 0 : j >= NP ? NP - 1 : j;
        count[i * NP + j] += 1;
        float pdf = tr_bsdf_pdf(m, wo, s.wi);
        tr_vec3 w = v3_scale(tr_bsdf_eval(m, wo, s.wi), fabsf(s.wi.z) / pdf);
        if (s.delta || !(fabsf(pdf - s.pdf) <= 1e-4f * pdf) ||
            !(fabsf(w.y - s.weight.y) <= 1e-4f * fmaxf(1.0f, w.y))) {
            ++inconsistent;
        }
    }
    CHECK(inconsistent == 0, "r=%.2f theta %.0f: %d samples disagree with eval/pdf",
          (double)m->roughness, theta_deg, inconsistent);
    CHECK(!(theta_deg < 90.0) || through > N / 4,
          "r=%.2f theta %.0f: only %d of %d samples refracted", (double)m->roughness, theta_deg,
          through, N);
    double chi2 = 0.0, pool_e = 0.0, pool_o = 0.0;
    int bins = 0;
    for (int b = 0; b <= NC * NP; ++b) {
        double e = expect[b] * N;
        if (e < 5.0) {
            pool_e += e;
            pool_o += count[b];
            continue;
        }
        chi2 += (count[b] - e) * (count[b] - e) / e;
        if (getenv("TR_DEBUG_CHI2") && (count[b] - e) * (count[b] - e) / e > 5.0) {
            printf("bin %d (cos %d phi %d): %g expected %g\n", b, b / NP, b % NP, count[b], e);
        }
        ++bins;
    }
    if (pool_e >= 5.0) {
        chi2 += (pool_o - pool_e) * (pool_o - pool_e) / pool_e;
        ++bins;
    } else {
        CHECK(pool_o <= pool_e + NSIGMA * sqrt(pool_e) + 5.0,
              "r=%.2f theta %.0f: %.0f samples where %.2f are expected", (double)m->roughness,
              theta_deg, pool_o, pool_e);
    }
    CHECK(bins > 10 && chi2 < chi2_critical(bins - 1),
          "r=%.2f t=%.2f theta %.0f: chi2 %.1f with %d bins (critical %.1f)", (double)m->roughness,
          (double)m->transmission, theta_deg, chi2, bins, chi2_critical(bins - 1));
}

/* (b) */
static void reciprocity(float roughness, float ior) {
    tr_rng rng;
    tr_rng_init(&rng, 91, 3, 4);
    int bad_r = 0, bad_t = 0, n_r = 0, n_t = 0, asym = 0;
    const tr_vec3 n = v3(0.0f, 0.0f, 1.0f);
    const float alpha = tr_principled_alpha(roughness);
    for (int k = 0; k < 40000; ++k) {
        tr_vec3 a = dir_of(2.0 * tr_rng_float(&rng) - 1.0, 2.0 * PI_D * tr_rng_float(&rng));
        tr_vec3 b = dir_of(2.0 * tr_rng_float(&rng) - 1.0, 2.0 * PI_D * tr_rng_float(&rng));
        double fab = tr_rd_eval(alpha, ior, v3s(1.0f), n, a, b).x;
        double fba = tr_rd_eval(alpha, ior, v3s(1.0f), n, b, a).x;
        if (!(fab > 1e-4 || fba > 1e-4)) {
            continue;
        }
        if (a.z * b.z > 0.0f) {
            ++n_r;
            bad_r += !(fabs(fab - fba) <= 1e-3 * fmax(fab, fba));
        } else {
            /* eta = n_i / n_o for (wo = a, wi = b). */
            const double eta = a.z > 0.0f ? ior : 1.0 / ior;
            ++n_t;
            /* float rounding: relative, and absolute where f is tiny (grazing). */
            bad_t += !(fabs(fba * eta * eta - fab) <= 2e-3 * fmax(fab, fba * eta * eta) + 1e-5);
            asym += fabs(fab - fba) > 0.05 * fmax(fab, fba);
        }
    }
    CHECK(n_r > 1000 && bad_r == 0, "r=%.2f ior %.2f: %d of %d reflections not reciprocal",
          (double)roughness, (double)ior, bad_r, n_r);
    CHECK(n_t > 1000 && bad_t == 0,
          "r=%.2f ior %.2f: %d of %d refractions break f(wi, wo) eta^2 = f(wo, wi)",
          (double)roughness, (double)ior, bad_t, n_t);
    CHECK(asym > n_t / 2, "r=%.2f ior %.2f: refraction looks reciprocal (%d of %d differ)",
          (double)roughness, (double)ior, asym, n_t);
}

/* (c) */
static void furnace(float roughness, float ior, float transmission, double theta_deg) {
    const tr_bsdf_params m = transmissive(roughness, ior, transmission, 0.0f);
    const tr_vec3 wo = wo_at(theta_deg);
    const float alpha = tr_principled_alpha(roughness);
    const int N = 300000;
    tr_rng rng;
    tr_rng_init(&rng, 4321, (uint64_t)theta_deg, (uint64_t)(roughness * 100.0f));
    double s1 = 0.0, s2 = 0.0, u1 = 0.0, u2 = 0.0;
    int outside = 0;
    for (int k = 0; k < N; ++k) {
        tr_scatter s;
        double w = 0.0;
        if (tr_bsdf_sample(&m, wo, tr_rng_float(&rng), tr_rng_float(&rng), tr_rng_float(&rng),
                           &s)) {
            w = s.weight.y;
            const double g1i = 1.0 / (1.0 + tr_ggx_lambda(alpha, s.wi.z));
            /* A boundary sample (transmission 1): G1(wi) <= G2 / G1(wo) <= 1. */
            if (transmission == 1.0f && !(w <= 1.0 + 1e-5 && w >= g1i * (1.0 - 1e-4))) {
                ++outside;
            }
        }
        s1 += w;
        s2 += w * w;
        tr_vec3 d = dir_of(2.0 * tr_rng_float(&rng) - 1.0, 2.0 * PI_D * tr_rng_float(&rng));
        double v = tr_bsdf_eval(&m, wo, d).y * fabs(d.z) * 4.0 * PI_D;
        u1 += v;
        u2 += v * v;
    }
    const double a = s1 / N, sa = sqrt(fmax(0.0, s2 / N - a * a) / N);
    const double u = u1 / N, su = sqrt(fmax(0.0, u2 / N - u * u) / N);
    printf("r=%.2f ior %.2f t=%.2f theta %5.1f: albedo %.4f +- %.4f, uniform %.4f +- %.4f\n",
           (double)roughness, (double)ior, (double)transmission, theta_deg, a, sa, u, su);
    CHECK(outside == 0, "r=%.2f theta %.0f: %d sample weights outside [G1(wi), 1]",
          (double)roughness, theta_deg, outside);
    CHECK(a <= 1.0 + NSIGMA * sa, "r=%.2f theta %.0f: albedo %.4f > 1", (double)roughness,
          theta_deg, a);
    CHECK(fabs(a - u) <= NSIGMA * sqrt(sa * sa + su * su),
          "r=%.2f t=%.2f theta %.0f: sampled albedo %.4f, uniform %.4f", (double)roughness,
          (double)transmission, theta_deg, a, u);
}

/* ---- Scene files ---------------------------------------------------------------------- */

enum { W = 16, H = 16, SPP = 16 };

static int parse_slab(tr_scene *s, const char *mat, tr_error *err) {
    char text[2048];
    snprintf(text, sizeof text,
             "{\"camera\": {\"position\": [0, 0, 5], \"direction\": [0, 0, -1], \"fov\": 4},\n"
             " \"render\": {\"width\": %d, \"height\": %d},\n"
             " \"materials\": {\"m\": %s},\n"
             " \"shapes\": [{\"type\": \"box\", \"material\": \"m\", \"scale\": [2, 2, 0.5]}],\n"
             " \"environment\": {\"color\": [1, 1, 1]}}",
             W, H, mat);
    tr_scene_init(s);
    return tr_scene_file_parse(s, "slab.json", text, strlen(text), NULL, NULL, err);
}

static void render_slab(const char *mat, tr_film *f) {
    tr_scene s;
    tr_error err;
    CHECK(parse_slab(&s, mat, &err) == TR_OK, "%s: %s", mat, err.msg);
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
    tr_render_config cfg = tr_render_config_default();
    CHECK(tr_film_init(f, W, H, &err) == TR_OK, "%s", err.msg);
    cfg.integrator = TR_INTEGRATOR_PT;
    cfg.seed = 17;
    cfg.threads = 2;
    /* No roulette: the two slabs' paths then take the same random decisions. */
    cfg.roulette_start = 64;
    cfg.max_depth = 64;
    for (uint32_t k = 0; k < SPP; ++k) {
        CHECK(tr_render_frame(&s, tr_scene_camera(&s), &cfg, f, k, NULL, &err) == TR_OK, "%s",
              err.msg);
    }
    tr_scene_clear(&s);
}

static int same_film(const tr_film *a, const tr_film *b) {
    return memcmp(a->sum, b->sum, 3 * sizeof *a->sum * W * H) == 0 &&
           memcmp(a->count, b->count, sizeof *a->count * W * H) == 0;
}

/* (d) */
static void beer_lambert(void) {
    const char *clear = "{\"type\": \"principled\", \"color\": [1, 1, 1], \"roughness\": 0, "
                        "\"transmission\": 1, \"ior\": 1.01}";
    /* The slab's box is the unit cube scaled 0.5 along z: thickness 0.5. */
    const double d = 0.5, color[3] = {0.5, 0.25, 0.9}, dist = 1.5;
    char absorbing[512];
    snprintf(absorbing, sizeof absorbing,
             "{\"type\": \"principled\", \"color\": [1, 1, 1], \"roughness\": 0, "
             "\"transmission\": 1, \"ior\": 1.01, \"attenuation_color\": [%g, %g, %g], "
             "\"attenuation_distance\": %g}",
             color[0], color[1], color[2], dist);
    tr_film a, b;
    render_slab(clear, &a);
    render_slab(absorbing, &b);
    double sa[3] = {0, 0, 0}, sb[3] = {0, 0, 0};
    for (uint32_t y = H / 2 - 2; y < H / 2 + 2; ++y) {
        for (uint32_t x = W / 2 - 2; x < W / 2 + 2; ++x) {
            tr_vec3 pa = tr_film_pixel(&a, x, y), pb = tr_film_pixel(&b, x, y);
            sa[0] += pa.x, sa[1] += pa.y, sa[2] += pa.z;
            sb[0] += pb.x, sb[1] += pb.y, sb[2] += pb.z;
        }
    }
    for (int c = 0; c < 3; ++c) {
        const double want = exp(log(color[c]) / dist * d);
        const double got = sb[c] / sa[c];
        printf("channel %d: through the slab %.5f of the light, exp(-sigma d) = %.5f\n", c, got,
               want);
        CHECK(sa[c] > 0.5 * 16 && fabs(got - want) <= 0.01 * want,
              "channel %d: %.5f of the light passes, Beer-Lambert says %.5f", c, got, want);
    }
    tr_film_free(&b);
    /* Keys that change nothing: bit for bit. */
    const char *neutral[] = {
        "{\"type\": \"principled\", \"color\": [1, 1, 1], \"roughness\": 0, \"transmission\": 1, "
        "\"ior\": 1.01, \"attenuation_color\": [1, 1, 1], \"attenuation_distance\": 2}"};
    render_slab(neutral[0], &b);
    CHECK(same_film(&a, &b), "a white attenuation colour changes the image");
    tr_film_free(&b);
    tr_film_free(&a);
    render_slab("{\"type\": \"principled\", \"color\": [0.8, 0.6, 0.4], \"roughness\": 0.5}", &a);
    render_slab("{\"type\": \"principled\", \"color\": [0.8, 0.6, 0.4], \"roughness\": 0.5, "
                "\"transmission\": 0, \"ior\": 1.5, \"emission_strength\": 3}",
                &b);
    CHECK(same_film(&a, &b), "transmission 0, ior 1.5 and a strength without emission change "
                             "the image");
    tr_film_free(&b);
    tr_film_free(&a);
}

/* (e) */
static void keys(void) {
    tr_scene s;
    tr_error err;
    CHECK(parse_slab(&s,
                     "{\"type\": \"principled\", \"color\": [1, 1, 1], \"transmission\": 0.75, "
                     "\"ior\": 1.33, \"attenuation_color\": [0.5, 1, 0.25], "
                     "\"attenuation_distance\": 2, \"emission\": [1, 0.5, 0], "
                     "\"emission_strength\": 4}",
                     &err) == TR_OK,
          "%s", err.msg);
    if (s.material_ext_count == s.material_count && s.material_count >= 1) {
        const tr_material_ext *e = &s.material_exts[0];
        CHECK(e->transmission == 0.75f && s.materials[0].ior == 1.33f, "transmission %g, ior %g",
              (double)e->transmission, (double)s.materials[0].ior);
        CHECK(fabs(e->absorption.x - log(2.0) / 2.0) < 1e-6 && e->absorption.y == 0.0f &&
                  fabs(e->absorption.z - log(4.0) / 2.0) < 1e-6,
              "absorption (%g, %g, %g)", (double)e->absorption.x, (double)e->absorption.y,
              (double)e->absorption.z);
        CHECK(e->emission.x == 4.0f && e->emission.y == 2.0f && e->emission.z == 0.0f,
              "emission x strength (%g, %g, %g)", (double)e->emission.x, (double)e->emission.y,
              (double)e->emission.z);
    } else {
        CHECK(0, "the keys made no material extras");
    }
    tr_scene_clear(&s);
    const char *bad[] = {
        "{\"type\": \"principled\", \"color\": [1, 1, 1], \"transmission\": 1.5}",
        "{\"type\": \"principled\", \"color\": [1, 1, 1], \"transmission\": -0.5}",
        "{\"type\": \"principled\", \"color\": [1, 1, 1], \"ior\": 0.5}",
        "{\"type\": \"principled\", \"color\": [1, 1, 1], \"attenuation_color\": [1.5, 1, 1], "
        "\"attenuation_distance\": 1}",
        "{\"type\": \"principled\", \"color\": [1, 1, 1], \"attenuation_color\": [0, 1, 1], "
        "\"attenuation_distance\": 1}",
        "{\"type\": \"principled\", \"color\": [1, 1, 1], \"attenuation_distance\": 0}",
        "{\"type\": \"principled\", \"color\": [1, 1, 1], \"emission\": [1, 1, 1], "
        "\"emission_strength\": -1}",
        "{\"type\": \"diffuse\", \"color\": [1, 1, 1], \"transmission\": 0.5}",
        "{\"type\": \"diffuse\", \"color\": [1, 1, 1], \"attenuation_distance\": 1}"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        int rc = parse_slab(&s, bad[i], &err);
        CHECK(rc != TR_OK && err.code == TR_STATUS_PARSE && strstr(err.msg, "materials.m"),
              "refused (%s): %s", rc != TR_OK ? err.msg : "accepted", bad[i]);
        tr_scene_clear(&s);
    }
}

/* (f) */
static void gltf_import(const char *dir) {
    /* One triangle, its positions and texture coordinates in a data URI. */
    static const char *gltf =
        "{\"asset\": {\"version\": \"2.0\"},\n"
        " \"extensionsUsed\": [\"KHR_materials_transmission\", \"KHR_materials_ior\", "
        "\"KHR_materials_volume\"],\n"
        " \"buffers\": [{\"byteLength\": 60, \"uri\": \"data:application/octet-stream;base64,"
        "AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAAAAAAAAAAAAAIA/AAAAAAAAAAAAAIA/\"}],\n"
        " \"bufferViews\": [{\"buffer\": 0, \"byteOffset\": 0, \"byteLength\": 36},\n"
        "                 {\"buffer\": 0, \"byteOffset\": 36, \"byteLength\": 24}],\n"
        " \"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, \"count\": 3, \"type\": "
        "\"VEC3\", \"min\": [0, 0, 0], \"max\": [1, 1, 0]},\n"
        "               {\"bufferView\": 1, \"componentType\": 5126, \"count\": 3, \"type\": "
        "\"VEC2\"}],\n"
        " \"materials\": [{\"name\": \"water\", \"pbrMetallicRoughness\": {\"baseColorFactor\": "
        "[0.9, 0.95, 1, 1], \"roughnessFactor\": 0.2, \"metallicFactor\": 0},\n"
        "   \"extensions\": {\"KHR_materials_transmission\": {\"transmissionFactor\": 0.75},\n"
        "                  \"KHR_materials_ior\": {\"ior\": 1.33},\n"
        "                  \"KHR_materials_volume\": {\"thicknessFactor\": 0.1, "
        "\"attenuationDistance\": 2, \"attenuationColor\": [0.5, 0.25, 1]}}}],\n"
        " \"meshes\": [{\"primitives\": [{\"attributes\": {\"POSITION\": 0, \"TEXCOORD_0\": 1}, "
        "\"material\": 0}]}],\n"
        " \"nodes\": [{\"mesh\": 0}], \"scenes\": [{\"nodes\": [0]}], \"scene\": 0}\n";
    char path[700];
    snprintf(path, sizeof path, "%s/water.gltf", dir);
    FILE *f = fopen(path, "w");
    CHECK(f && fputs(gltf, f) >= 0 && fclose(f) == 0, "cannot write %s", path);
    tr_scene s;
    tr_scene_file info;
    load_model_file(&s, path, &info);
    int found = 0;
    for (uint32_t i = 0; i < s.material_count && s.material_ext_count == s.material_count; ++i) {
        const tr_material_ext *e = &s.material_exts[i];
        if (e->transmission <= 0.0f) {
            continue;
        }
        found = 1;
        CHECK(s.materials[i].type == TR_MATERIAL_PRINCIPLED && e->transmission == 0.75f &&
                  fabsf(s.materials[i].ior - 1.33f) < 1e-6f &&
                  fabsf(s.materials[i].roughness - 0.2f) < 1e-6f,
              "glTF water: type %u, transmission %g, ior %g", s.materials[i].type,
              (double)e->transmission, (double)s.materials[i].ior);
        CHECK(fabs(e->absorption.x - log(2.0) / 2.0) < 1e-6 &&
                  fabs(e->absorption.y - log(4.0) / 2.0) < 1e-6 && e->absorption.z == 0.0f,
              "glTF water: absorption (%g, %g, %g)", (double)e->absorption.x,
              (double)e->absorption.y, (double)e->absorption.z);
    }
    CHECK(found, "no transmissive material imported from %s", path);
    CHECK(info.warning_count == 0, "%u warnings for extensions that are rendered",
          info.warning_count);
    tr_scene_clear(&s);
    unlink(path);
}

/* (g) */
static void gltf_transmission_map(const char *dir) {
    /* The triangle of (f), its material's transmission 0.8 times a map, and the volume's
     * thickness map (not needed: no warning either); the map a 2x2 PNG of RGBA (64, 200,
     * 10, 255) in a data URI, so that red (0.251) and not green or alpha must be read. */
    static const char *gltf =
        "{\"asset\": {\"version\": \"2.0\"},\n"
        " \"extensionsUsed\": [\"KHR_materials_transmission\", \"KHR_materials_volume\"],\n"
        " \"buffers\": [{\"byteLength\": 60, \"uri\": \"data:application/octet-stream;base64,"
        "AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAAAAAAAAAAAAAIA/AAAAAAAAAAAAAIA/\"}],\n"
        " \"bufferViews\": [{\"buffer\": 0, \"byteOffset\": 0, \"byteLength\": 36},\n"
        "                 {\"buffer\": 0, \"byteOffset\": 36, \"byteLength\": 24}],\n"
        " \"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, \"count\": 3, \"type\": "
        "\"VEC3\", \"min\": [0, 0, 0], \"max\": [1, 1, 0]},\n"
        "               {\"bufferView\": 1, \"componentType\": 5126, \"count\": 3, \"type\": "
        "\"VEC2\"}],\n"
        " \"images\": [{\"uri\": \"data:image/png;base64,"
        "iVBORw0KGgoAAAANSUhEUgAAAAIAAAACCAYAAABytg0kAAAAEUlEQVR4nGNwOMH1H4QZYAwAR3gIRdn56ZMAAAAASU"
        "VORK5CYII="
        "\"}],\n"
        " \"textures\": [{\"source\": 0}],\n"
        " \"materials\": [{\"name\": \"frosted\", \"pbrMetallicRoughness\": {\"baseColorFactor\": "
        "[1, 1, 1, 1], \"roughnessFactor\": 0.3, \"metallicFactor\": 0},\n"
        "   \"extensions\": {\"KHR_materials_transmission\": {\"transmissionFactor\": 0.8, "
        "\"transmissionTexture\": {\"index\": 0}},\n"
        "                  \"KHR_materials_volume\": {\"thicknessFactor\": 0.1, "
        "\"thicknessTexture\": {\"index\": 0}}}}],\n"
        " \"meshes\": [{\"primitives\": [{\"attributes\": {\"POSITION\": 0, \"TEXCOORD_0\": 1}, "
        "\"material\": 0}]}],\n"
        " \"nodes\": [{\"mesh\": 0}], \"scenes\": [{\"nodes\": [0]}], \"scene\": 0}\n";
    char path[700];
    snprintf(path, sizeof path, "%s/frosted.gltf", dir);
    FILE *f = fopen(path, "w");
    CHECK(f && fputs(gltf, f) >= 0 && fclose(f) == 0, "cannot write %s", path);
    tr_scene s;
    tr_scene_file info;
    tr_error err;
    load_model_file(&s, path, &info);
    CHECK(info.warning_count == 0, "%u warnings for a transmission map (first: %s)",
          info.warning_count, info.warning_count ? info.warnings[0] : "");
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
    tr_scene_view v = tr_scene_view_of(&s);
    int found = 0;
    for (uint32_t i = 0; i < s.material_count && v.material_ext_count == s.material_count; ++i) {
        const tr_material_ext *e = &s.material_exts[i];
        if (e->transmission <= 0.0f) {
            continue;
        }
        found = 1;
        CHECK(e->transmission == 0.8f && e->transmission_tex != TR_NO_INDEX &&
                  (tr_scene_material_maps(&s, i) & TR_MAP_TRANSMISSION) != 0u,
              "glTF frosted: transmission %g, map %u", (double)e->transmission,
              e->transmission_tex);
        /* The kernel's material extras: the factor times the map's red, at any point. */
        tr_bsdf_params b;
        memset(&b, 0, sizeof b);
        b.type = TR_MATERIAL_PRINCIPLED;
        b.color = v3s(1.0f);
        b.roughness = 0.3f;
        tr_surface_attr a;
        memset(&a, 0, sizeof a);
        a.ns = v3(0.0f, 0.0f, 1.0f);
        a.tu = 0.3f;
        a.tv = 0.6f;
        tr_material_apply_ext(&v, i, &a, &b);
        CHECK(fabsf(b.transmission - 0.8f * 64.0f / 255.0f) < 1e-3f,
              "transmission with its map %g, expected %g", (double)b.transmission,
              0.8 * 64.0 / 255.0);
    }
    CHECK(found, "no transmissive material imported from %s", path);
    tr_scene_clear(&s);
    unlink(path);

    /* The scene file's key, with the same image as a file. */
    static const unsigned char png[74] = {
        0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a, 0x00, 0x00, 0x00, 0x0d, 0x49, 0x48, 0x44,
        0x52, 0x00, 0x00, 0x00, 0x02, 0x00, 0x00, 0x00, 0x02, 0x08, 0x06, 0x00, 0x00, 0x00, 0x72,
        0xb6, 0x0d, 0x24, 0x00, 0x00, 0x00, 0x11, 0x49, 0x44, 0x41, 0x54, 0x78, 0x9c, 0x63, 0x70,
        0x38, 0xc1, 0xf5, 0x1f, 0x84, 0x19, 0x60, 0x0c, 0x00, 0x47, 0x78, 0x08, 0x45, 0xd9, 0xf9,
        0xe9, 0x93, 0x00, 0x00, 0x00, 0x00, 0x49, 0x45, 0x4e, 0x44, 0xae, 0x42, 0x60, 0x82};
    char png_path[700], json_path[700];
    snprintf(png_path, sizeof png_path, "%s/red.png", dir);
    snprintf(json_path, sizeof json_path, "%s/slab.json", dir);
    f = fopen(png_path, "wb");
    CHECK(f && fwrite(png, 1, sizeof png, f) == sizeof png && fclose(f) == 0, "cannot write %s",
          png_path);
    static const char text[] =
        "{\"camera\": {\"position\": [0, 0, 5], \"direction\": [0, 0, -1], \"fov\": 4},\n"
        " \"materials\": {\"m\": {\"type\": \"principled\", \"color\": [1, 1, 1],"
        " \"transmission\": 0.5, \"transmission_texture\": \"red.png\"}},\n"
        " \"shapes\": [{\"type\": \"box\", \"material\": \"m\"}],\n"
        " \"environment\": {\"color\": [1, 1, 1]}}";
    tr_scene_init(&s);
    CHECK(tr_scene_file_parse(&s, json_path, text, strlen(text), NULL, NULL, &err) == TR_OK,
          "transmission_texture: %s", err.msg);
    CHECK(s.material_ext_count == s.material_count && s.material_count >= 1 &&
              s.material_exts[0].transmission == 0.5f &&
              s.material_exts[0].transmission_tex != TR_NO_INDEX,
          "the key transmission_texture made no transmission map");
    tr_scene_clear(&s);
    unlink(png_path);
}

int main(void) {
    const float rough[] = {0.4f, 0.7f, 1.0f};
    const double thetas[] = {10.0, 50.0, 70.0, 120.0, 175.0};
    for (int r = 0; r < 3; ++r) {
        tr_bsdf_params m = transmissive(rough[r], 1.5f, 1.0f, 0.0f);
        for (int t = 0; t < 5; ++t) {
            chi2_case(&m, thetas[t], 100u + (uint64_t)(r * 10 + t));
        }
    }
    /* A mix with the opaque part and a metallic share. */
    tr_bsdf_params mix = transmissive(0.5f, 1.33f, 0.6f, 0.3f);
    chi2_case(&mix, 40.0, 7);
    chi2_case(&mix, 140.0, 8);
    reciprocity(0.5f, 1.5f);
    reciprocity(0.9f, 1.33f);
    for (int r = 0; r < 3; ++r) {
        furnace(rough[r], 1.5f, 1.0f, 30.0);
        furnace(rough[r], 1.5f, 1.0f, 150.0);
    }
    furnace(0.5f, 1.33f, 0.5f, 60.0);
    beer_lambert();
    keys();
    char dir[600];
    const char *tmp = getenv("TMPDIR");
    snprintf(dir, sizeof dir, "%s/trac0r-test-transmission-XXXXXX", tmp && *tmp ? tmp : "/tmp");
    if (!mkdtemp(dir)) {
        CHECK(0, "mkdtemp");
    } else {
        gltf_import(dir);
        gltf_transmission_map(dir);
        rmdir(dir);
    }
    return check_finish("test_transmission");
}
