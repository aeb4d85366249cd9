/* test_bsdf.c - the pt integrator's BSDFs (src/kernel/bsdf.h).
 *
 *  (a) Chi-square goodness of fit: directions drawn by tr_bsdf_sample, binned on
 *      (cos theta, phi), against the counts tr_bsdf_pdf predicts (numerically
 *      integrated over each bin), plus one bin for samples the sampler rejects
 *      (GGX's visible-normal sampler sends some reflections below the surface). For
 *      Lambertian and GGX at several roughnesses and incident angles.
 *  (b) eval/pdf/sample agree: a sample's weight is eval * cos / pdf at its direction
 *      and its pdf is tr_bsdf_pdf's.
 *  (c) Reciprocity: f(wo, wi) = f(wi, wo) for Lambertian and GGX.
 *  (d) White furnace: the albedo (mean sample weight) of a white Lambertian is 1, of a
 *      white GGX conductor <= 1 and equal to an independent uniform-hemisphere estimate
 *      of the integral of f cos; single-scattering GGX loses energy as roughness and
 *      incidence grow. The smooth dielectric is lossless (weight 1 for every sample),
 *      reflects with the Fresnel probability and refracts by Snell's law; the smooth
 *      mirror reflects exactly with Schlick's weight.
 *
 *  (e) The principled material: (a)-(c) at several roughness x metallic, and
 *      a white furnace over a grid of roughness x metallic x incidence: albedo <= 1,
 *      equal to the uniform estimate, and above the single-scattering floor.
 *  (f) The principled material's clear coat: (a)-(c) with a coat over dielectric and
 *      metallic bases; a white furnace (albedo <= 1, equal to the uniform estimate; a coat
 *      over a white dielectric keeps within 0.03 of the uncoated albedo at normal
 *      incidence, over a white conductor at least 90 % of it, and a smooth coat over black reflects
 * its Fresnel's F0, 0.04); weight 0 evaluates, weighs and samples bit for bit as no coat.
 *  (g) The principled material's sheen (Charlie, KHR_materials_sheen): (a)-(c) over
 *      dielectric and metallic bases, with and without a coat and energy compensation; a
 *      white furnace (a white sheen over a white base: albedo <= 1, equal to the uniform
 *      estimate); the sheen albedo table (ggx_ms.h) against a uniform estimate of the
 *      lobe's integral. A black sheen evaluates, weighs and samples bit for bit as none.
 *  (h) KHR_materials_specular (specular, specular_color): (a)-(c) with a tinted, weakened
 *      dielectric layer, with and without compensation; a white furnace (albedo <= 1,
 *      equal to the uniform estimate); specular 1 and white evaluate as none, bit for bit.
 *  (i) The albedo the passes record (tr_bsdf_guide_albedo) against the BSDF's directional
 *      albedo, principled dielectric and metal, with and without the table.
 *
 * Fixed seeds; statistical bounds are 5 standard errors or chi2_critical (p = 1e-4). */
#include "check.h"
#include "kernel/kernel.h"
#include "scene/scene_internal.h"
#include "kernel/bsdf.h"
#include "kernel/kernel.h"
#include "bsdf_util.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define PI_D 3.14159265358979323846
#define NSIGMA 5.0

/* A material's BSDF parameters on the plane z = 0 with normal +z, the normal every case
 * below uses. */
static tr_bsdf_params mat(uint32_t type, tr_vec3 color, float roughness, float ior) {
    tr_material m;
    memset(&m, 0, sizeof m);
    m.type = type;
    m.color = color;
    m.roughness = roughness;
    m.ior = ior;
    return tr_material_params(&m, v3(0.0f, 0.0f, 1.0f));
}

enum { NC = 16, NP = 24, SUB = 24 };

/* (a) + (b) for one material and incident angle. */
static void chi2_case(const tr_bsdf_params *m, double theta_o_deg, uint64_t seed) {
    const double to = theta_o_deg * PI_D / 180.0;
    const tr_vec3 wo = v3((float)sin(to), 0.0f, (float)cos(to));
    /* Expected fraction per bin: midpoint rule on SUB x SUB cells in (theta, phi), with
     * the solid angle element sin(theta) d(theta) d(phi): cells in theta stay narrow
     * near the pole, where the glossy lobes at normal incidence are. */
    static double expect[NC * NP + 1];
    double total = 0.0;
    for (int i = 0; i < NC; ++i) {
        for (int j = 0; j < NP; ++j) {
            double sum = 0.0;
            double th1 = acos((double)i / NC), th0 = acos((double)(i + 1) / NC);
            double dth = (th1 - th0) / SUB;
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
    expect[NC * NP] = fmax(0.0, 1.0 - total); /* rejected samples */
    CHECK(total <= 1.0 + 1e-3, "type %u r=%.2f theta %.0f: pdf integrates to %.5f > 1", m->type,
          (double)m->roughness, theta_o_deg, total);

    const int N = 200000;
    static double count[NC * NP + 1];
    memset(count, 0, sizeof count);
    tr_rng rng;
    tr_rng_init(&rng, seed, 1, 2);
    int inconsistent = 0;
    for (int k = 0; k < N; ++k) {
        tr_scatter s;
        if (!tr_bsdf_sample(m, wo, tr_rng_float(&rng), tr_rng_float(&rng), tr_rng_float(&rng),
                            &s)) {
            count[NC * NP] += 1;
            continue;
        }
        double c = s.wi.z;
        double phi = atan2(s.wi.y, s.wi.x);
        if (phi < 0.0) {
            phi += 2.0 * PI_D;
        }
        int i = (int)(c * NC), j = (int)(phi / (2.0 * PI_D) * NP);
        i = i < 0 ? 0 : i >= NC ? NC - 1 : i;
        j = j < 0 ? 0 : j >= NP ? NP - 1 : j;
        count[i * NP + j] += 1;
        /* (b) */
        float pdf = tr_bsdf_pdf(m, wo, s.wi);
        tr_vec3 f = tr_bsdf_eval(m, wo, s.wi);
        float ci = s.wi.z;
        tr_vec3 w = v3_scale(f, ci / pdf);
        if (s.delta || !(fabsf(pdf - s.pdf) <= 1e-4f * pdf) ||
            !(fabsf(w.x - s.weight.x) <= 1e-4f * fmaxf(1.0f, w.x)) ||
            !(fabsf(w.y - s.weight.y) <= 1e-4f * fmaxf(1.0f, w.y)) ||
            !(fabsf(w.z - s.weight.z) <= 1e-4f * fmaxf(1.0f, w.z))) {
            ++inconsistent;
        }
    }
    CHECK(inconsistent == 0, "type %u r=%.2f theta %.0f: %d samples disagree with eval/pdf",
          m->type, (double)m->roughness, theta_o_deg, inconsistent);

    /* Pool bins expected to hold fewer than 5 samples, as the chi-square test needs. */
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
        ++bins;
    }
    if (pool_e >= 5.0) {
        chi2 += (pool_o - pool_e) * (pool_o - pool_e) / pool_e;
        ++bins;
    } else {
        /* Samples where the pdf says almost none can land are a failure too. */
        CHECK(pool_o <= pool_e + NSIGMA * sqrt(pool_e) + 5.0,
              "type %u r=%.2f theta %.0f: %.0f samples where %.2f are expected", m->type,
              (double)m->roughness, theta_o_deg, pool_o, pool_e);
    }
    CHECK(bins > 10 && chi2 < chi2_critical(bins - 1),
          "type %u r=%.2f theta %.0f: chi2 %.1f with %d bins (critical %.1f)", m->type,
          (double)m->roughness, theta_o_deg, chi2, bins, chi2_critical(bins - 1));
}

/* (c) */
static void reciprocity(const tr_bsdf_params *m) {
    int nonzero;
    const int bad = bsdf_not_reciprocal(m, 77, &nonzero);
    CHECK(bad == 0 && nonzero > 10000, "type %u r=%.2f: %d of 20000 pairs not reciprocal (%d > 0)",
          m->type, (double)m->roughness, bad, nonzero);
}

/* (d) Albedo by the sampler (mean weight) and by uniform hemisphere sampling of f cos. */
static void albedo(const tr_bsdf_params *m, double theta_o_deg, double *sampled, double *se_sampled,
                   double *uniform, double *se_uniform) {
    const double to = theta_o_deg * PI_D / 180.0;
    const tr_vec3 wo = v3((float)sin(to), 0.0f, (float)cos(to));
    tr_rng rng;
    tr_rng_init(&rng, 1234, (uint64_t)theta_o_deg, (uint64_t)(m->roughness * 100.0f));
    bsdf_albedo(m, wo, 400000, &rng, sampled, se_sampled, uniform, se_uniform, NULL);
}

static void furnace(void) {
    tr_bsdf_params diffuse = mat(TR_MATERIAL_DIFFUSE, v3s(1.0f), 0.0f, 1.0f);
    double a, sa, u, su;
    albedo(&diffuse, 40.0, &a, &sa, &u, &su);
    CHECK_NEAR(a, 1.0, 1e-6, "white Lambertian albedo (every weight is 1)");
    CHECK(fabs(u - 1.0) <= NSIGMA * su, "white Lambertian, uniform estimate %.5f +- %.5f", u, su);

    const float rough[] = {0.1f, 0.3f, 0.6f, 1.0f};
    const double theta[] = {0.0, 45.0, 80.0};
    double loss_smooth_normal = 0.0, loss_rough_grazing = 0.0;
    for (int r = 0; r < 4; ++r) {
        tr_bsdf_params g = mat(TR_MATERIAL_GLOSSY, v3s(1.0f), rough[r], 1.0f);
        for (int t = 0; t < 3; ++t) {
            albedo(&g, theta[t], &a, &sa, &u, &su);
            CHECK(a <= 1.0 + NSIGMA * sa, "GGX r=%.1f theta %.0f: albedo %.5f > 1",
                  (double)rough[r], theta[t], a);
            CHECK(fabs(a - u) <= NSIGMA * sqrt(sa * sa + su * su),
                  "GGX r=%.1f theta %.0f: sampled albedo %.5f vs uniform %.5f +- %.5f",
                  (double)rough[r], theta[t], a, u, sqrt(sa * sa + su * su));
            if (r == 0 && t == 0) {
                loss_smooth_normal = 1.0 - a;
                /* Nearly smooth at normal incidence: hardly any energy is lost. */
                CHECK(a > 0.98, "GGX r=0.1 at normal incidence: albedo %.5f", a);
            }
            if (r == 3 && t == 2) {
                loss_rough_grazing = 1.0 - a;
            }
        }
    }
    /* Single scattering loses the light that would scatter again between microfacets:
     * measurably at high roughness and grazing incidence. */
    CHECK(loss_rough_grazing > 0.02 && loss_rough_grazing > 5.0 * loss_smooth_normal,
          "GGX energy loss: %.4f at r=1, 80 deg vs %.4f at r=0.1, 0 deg", loss_rough_grazing,
          loss_smooth_normal);
}

static void delta_lobes(void) {
    /* Smooth glass from outside at 50 degrees and from inside at 30 (below TIR) and 60
     * (beyond the critical angle 41.8 degrees for ior 1.5). */
    tr_bsdf_params glass = mat(TR_MATERIAL_GLASS, v3s(1.0f), 0.0f, 1.5f);
    const double angles[] = {50.0, -30.0, -60.0};
    for (int c = 0; c < 3; ++c) {
        double th = fabs(angles[c]) * PI_D / 180.0;
        int outside = angles[c] > 0.0;
        tr_vec3 wo = v3((float)sin(th), 0.0f, (float)(outside ? cos(th) : -cos(th)));
        float cos_t;
        double r = tr_fresnel_dielectric((float)cos(th), outside ? 1.0f : 1.5f,
                                         outside ? 1.5f : 1.0f, &cos_t);
        tr_rng rng;
        tr_rng_init(&rng, 99, (uint64_t)c, 0);
        const int N = 100000;
        int refl = 0, bad = 0;
        for (int k = 0; k < N; ++k) {
            tr_scatter s;
            if (!tr_bsdf_sample(&glass, wo, tr_rng_float(&rng), tr_rng_float(&rng),
                                tr_rng_float(&rng), &s) ||
                !s.delta || s.weight.x != 1.0f || s.weight.y != 1.0f || s.weight.z != 1.0f) {
                ++bad;
                continue;
            }
            int is_refl = (s.wi.z > 0.0f) == outside;
            refl += is_refl;
            double sin_i = sin(th), sin_o = sqrt(s.wi.x * s.wi.x + s.wi.y * s.wi.y);
            double eta = outside ? 1.0 / 1.5 : 1.5;
            double expect_sin = is_refl ? sin_i : eta * sin_i;
            /* Reflection mirrors the tangential part; refraction scales it (Snell). */
            /* Both keep the tangential direction of -wo (negative x). */
            if (fabs(sin_o - expect_sin) > 1e-5 || s.wi.x > 0.0f ||
                fabsf(s.pdf - (float)(is_refl ? r : 1.0 - r)) > 1e-6f) {
                ++bad;
            }
        }
        CHECK(bad == 0, "glass case %d: %d bad samples (weight 1 = lossless, Snell, pdf)", c, bad);
        double se = sqrt(fmax(r * (1.0 - r), 1e-12) / N);
        CHECK(fabs((double)refl / N - r) <= NSIGMA * se + 1e-9,
              "glass case %d: reflected fraction %.5f vs Fresnel %.5f", c, (double)refl / N, r);
        if (angles[c] == -60.0) {
            CHECK(refl == N, "total internal reflection: %d of %d reflected", refl, N);
        }
        CHECK(tr_bsdf_pdf(&glass, wo, v3(0, 0, 1)) == 0.0f &&
                  tr_bsdf_eval(&glass, wo, v3(0, 0, 1)).x == 0.0f,
              "glass: eval and pdf of a delta lobe are 0");
    }
    /* Roughness 0: a mirror with Schlick's Fresnel, on either side of the normal. */
    tr_bsdf_params mirror = mat(TR_MATERIAL_GLOSSY, v3(0.9f, 0.5f, 0.2f), 0.0f, 1.0f);
    tr_vec3 wo = v3_normalize(v3(0.3f, -0.4f, -0.8f));
    tr_rng rng;
    tr_rng_init(&rng, 5, 5, 5);
    tr_scatter s;
    int ok =
        tr_bsdf_sample(&mirror, wo, tr_rng_float(&rng), tr_rng_float(&rng), tr_rng_float(&rng), &s);
    tr_vec3 fr = tr_fresnel_schlick(mirror.color, fabsf(wo.z));
    CHECK(ok && s.delta && fabsf(s.wi.x + wo.x) < 1e-6f && fabsf(s.wi.y + wo.y) < 1e-6f &&
              fabsf(s.wi.z - wo.z) < 1e-6f && fabsf(s.weight.x - fr.x) < 1e-6f &&
              fabsf(s.weight.z - fr.z) < 1e-6f,
          "mirror: wi (%g %g %g) weight %g", (double)s.wi.x, (double)s.wi.y, (double)s.wi.z,
          (double)s.weight.x);
    CHECK(tr_bsdf_is_delta(&mirror) && tr_bsdf_is_delta(&glass), "delta materials");
    /* An emitter's BSDF is black. */
    tr_bsdf_params em = mat(TR_MATERIAL_EMITTER, v3s(1.0f), 0.0f, 1.0f);
    em.emittance = 5.0f;
    CHECK(
        !tr_bsdf_sample(&em, wo, tr_rng_float(&rng), tr_rng_float(&rng), tr_rng_float(&rng), &s) &&
            tr_bsdf_eval(&em, wo, v3(0, 0, 1)).x == 0.0f,
        "emitters do not scatter");
    /* One-sided emission, towards the normal's side only, unless two-sided. */
    CHECK(tr_emitted(&em, v3(0, 0, 1)).x == 5.0f && tr_emitted(&em, v3(0, 0, -1)).x == 0.0f,
          "one-sided emitter");
    em.flags = TR_MATERIAL_TWO_SIDED;
    CHECK(tr_emitted(&em, v3(0, 0, -1)).x == 5.0f, "two-sided emitter");
}

static void alpha_mapping(void) {
    /* Documented in docs/integrators.md: monotonic, tan(pi/8) at r = 1. */
    CHECK_NEAR(tr_ggx_alpha(1.0f), tan(PI_D / 8.0), 1e-6, "alpha(1)");
    CHECK(tr_ggx_alpha(0.0f) == TR_GGX_MIN_ALPHA, "alpha(0) clamps");
    float prev = 0.0f;
    int mono = 1;
    for (int i = 1; i <= 100; ++i) {
        float a = tr_ggx_alpha((float)i / 100.0f);
        mono &= a >= prev;
        prev = a;
    }
    CHECK(mono, "alpha(r) is non-decreasing");
}

/* (e) */
static tr_bsdf_params principled(tr_vec3 color, float roughness, float metallic) {
    tr_bsdf_params b = mat(TR_MATERIAL_PRINCIPLED, color, roughness, 1.5f);
    b.metallic = metallic;
    return b;
}

static void principled_tests(void) {
    const float rough[] = {0.05f, 0.3f, 0.6f, 1.0f};
    const float metal[] = {0.0f, 0.5f, 1.0f};
    const double theta[] = {0.0, 45.0, 80.0};
    for (int r = 1; r < 4; r += 2) {
        for (int k = 0; k < 3; ++k) {
            tr_bsdf_params p = principled(v3(0.9f, 0.6f, 0.3f), rough[r], metal[k]);
            for (int t = 0; t < 3; ++t) {
                chi2_case(&p, theta[t], 500 + (uint64_t)(100 * r + 10 * k + t));
            }
            reciprocity(&p);
        }
    }
    for (int r = 0; r < 4; ++r) {
        for (int k = 0; k < 3; ++k) {
            tr_bsdf_params p = principled(v3s(1.0f), rough[r], metal[k]);
            for (int t = 0; t < 3; ++t) {
                double a, sa, u, su;
                albedo(&p, theta[t], &a, &sa, &u, &su);
                CHECK(a <= 1.0 + NSIGMA * sa,
                      "principled r=%.2f m=%.1f theta %.0f: albedo %.5f > 1", (double)rough[r],
                      (double)metal[k], theta[t], a);
                /* (Uniform sampling cannot resolve the peak of alpha = 0.05^2.) */
                CHECK(r == 0 || fabs(a - u) <= NSIGMA * sqrt(sa * sa + su * su),
                      "principled r=%.2f m=%.1f theta %.0f: sampled %.5f vs uniform %.5f",
                      (double)rough[r], (double)metal[k], theta[t], a, u);
                /* A white dielectric at normal incidence keeps nearly everything: the base
                 * takes 28/23 (1 - 0.04) (1 - 1/32) x 23/28 = 0.93, the layer 0.04. */
                CHECK(k != 0 || t != 0 || a > 0.9,
                      "principled r=%.2f dielectric at normal incidence: albedo %.5f",
                      (double)rough[r], a);
                /* Closed form: a white conductor of alpha 1 at normal incidence has
                 * D = 1/pi, G2 = 2 c / (1 + c), albedo = int_0^1 c / (1 + c) dc = 1 - ln 2
                 * (single scattering loses the rest). */
                if (r == 3 && k == 2 && t == 0) {
                    CHECK(fabs(a - (1.0 - log(2.0))) <= NSIGMA * sa + 1e-4,
                          "principled alpha 1 metal: albedo %.5f vs 1 - ln 2", a);
                }
            }
        }
    }
}

/* (f) */
static void clearcoat_tests(void) {
    const float base_rough[] = {0.44f, 0.8f};
    const float coat_rough[] = {0.3f, 0.7f};
    const float metal[] = {0.0f, 1.0f};
    const double theta[] = {0.0, 45.0, 80.0};
    for (int r = 0; r < 2; ++r) {
        for (int k = 0; k < 2; ++k) {
            tr_bsdf_params p = principled(v3(0.9f, 0.6f, 0.3f), base_rough[r], metal[k]);
            p.clearcoat = r == 0 ? 1.0f : 0.6f;
            p.clearcoat_roughness = coat_rough[r];
            for (int t = 0; t < 3; ++t) {
                chi2_case(&p, theta[t], 900 + (uint64_t)(100 * r + 10 * k + t));
            }
            reciprocity(&p);
        }
    }
    const float coat_r[] = {0.03f, 0.3f, 0.7f, 1.0f};
    for (int c = 0; c < 4; ++c) {
        for (int k = 0; k < 2; ++k) {
            for (int t = 0; t < 3; ++t) {
                tr_bsdf_params p = principled(v3s(1.0f), 0.44f, metal[k]);
                double a0, sa0, u0, su0;
                albedo(&p, theta[t], &a0, &sa0, &u0, &su0);
                p.clearcoat = 1.0f;
                p.clearcoat_roughness = coat_r[c];
                double a, sa, u, su;
                albedo(&p, theta[t], &a, &sa, &u, &su);
                printf("coat r=%.2f over white m=%.0f at %.0f deg: albedo %.5f (uncoated %.5f)\n",
                       (double)coat_r[c], (double)metal[k], theta[t], a, a0);
                CHECK(a <= 1.0 + NSIGMA * sa, "coat r=%.2f m=%.0f theta %.0f: albedo %.5f > 1",
                      (double)coat_r[c], (double)metal[k], theta[t], a);
                /* (Uniform sampling cannot resolve the peak of alpha = 0.03^2.) */
                CHECK(c == 0 || fabs(a - u) <= NSIGMA * sqrt(sa * sa + su * su),
                      "coat r=%.2f m=%.0f theta %.0f: sampled %.5f vs uniform %.5f",
                      (double)coat_r[c], (double)metal[k], theta[t], a, u);
                /* At normal incidence a coat over the white dielectric keeps its albedo
                 * (the diffuse part's internal reflections are given back), over the white
                 * conductor about (1 - 0.04)^2 of it (light passes the coat twice). */
                CHECK(t != 0 || (k == 0 ? fabs(a - a0) <= 0.03 : a >= 0.9 * a0 && a <= a0),
                      "coat r=%.2f m=%.0f at normal incidence: albedo %.5f, uncoated %.5f",
                      (double)coat_r[c], (double)metal[k], a, a0);
            }
        }
    }
    /* A smooth coat over a black conductor (F0 0) at normal incidence reflects its own
     * F0, 0.04, and nearly nothing else. */
    tr_bsdf_params black = principled(v3s(0.0f), 0.44f, 1.0f);
    black.clearcoat = 1.0f;
    black.clearcoat_roughness = 0.03f;
    double a, sa, u, su;
    albedo(&black, 0.0, &a, &sa, &u, &su);
    double a_half;
    black.clearcoat = 0.5f;
    albedo(&black, 0.0, &a_half, &sa, &u, &su);
    printf("smooth coat over black: albedo %.5f (weight 1), %.5f (weight 0.5)\n", a, a_half);
    CHECK(fabs(a - 0.04) <= 0.003, "smooth coat over black at normal incidence: %.5f vs 0.04", a);
    CHECK(fabs(a_half - 0.02) <= 0.002, "half a smooth coat over black: %.5f vs 0.02", a_half);

    /* Weight 0: the coat's roughness is ignored bit for bit. */
    tr_bsdf_params p0 = principled(v3(0.9f, 0.6f, 0.3f), 0.5f, 0.3f);
    tr_bsdf_params p1 = p0;
    p1.clearcoat_roughness = 0.2f;
    const int differ = bsdf_differences(&p0, &p1, 5);
    CHECK(differ == 0, "clear coat weight 0: %d of 2000 cases differ from no coat", differ);
}

/* (g) */
/* The sheen lives in the material's extras, which *e holds for as long as the result is
 * used. */
static tr_bsdf_params sheened(tr_vec3 color, float roughness, float metallic, tr_vec3 sheen,
                              float sheen_roughness, tr_material_ext *e) {
    tr_bsdf_params p = principled(color, roughness, metallic);
    memset(e, 0, sizeof *e);
    e->sheen_color = sheen;
    e->sheen_roughness = sheen_roughness;
    p.ext = e;
    p.ms = tr_ggx_ms_table();
    return p;
}

static void sheen_tests(void) {
    const float sr[] = {0.3f, 0.8f};
    const double theta[] = {0.0, 45.0, 80.0};
    for (int r = 0; r < 2; ++r) {
        for (int k = 0; k < 2; ++k) {
            tr_material_ext e;
            tr_bsdf_params p =
                sheened(v3(0.9f, 0.6f, 0.3f), 0.5f, (float)k, v3(0.8f, 0.6f, 0.9f), sr[r], &e);
            if (r == 1) {
                /* Under a coat, with the energy compensation. */
                p.clearcoat = 0.7f;
                p.clearcoat_roughness = 0.2f;
                p.flags |= TR_MATERIAL_MULTISCATTER;
            }
            for (int t = 0; t < 3; ++t) {
                chi2_case(&p, theta[t], 1300 + (uint64_t)(100 * r + 10 * k + t));
            }
            reciprocity(&p);
        }
    }
    for (int r = 0; r < 2; ++r) {
        for (int k = 0; k < 2; ++k) {
            for (int comp = 0; comp < 2; ++comp) {
                tr_material_ext e;
                tr_bsdf_params p = sheened(v3s(1.0f), 0.6f, (float)k, v3s(1.0f), sr[r], &e);
                p.flags = comp ? TR_MATERIAL_MULTISCATTER : 0u;
                for (int t = 0; t < 3; ++t) {
                    double a, sa, u, su;
                    albedo(&p, theta[t], &a, &sa, &u, &su);
                    printf("white sheen r=%.1f over white m=%d (compensation %d) at %.0f deg: "
                           "albedo %.5f\n",
                           (double)sr[r], k, comp, theta[t], a);
                    CHECK(a <= 1.0 + NSIGMA * sa,
                          "sheen r=%.1f m=%d comp %d theta %.0f: albedo %.5f > 1", (double)sr[r], k,
                          comp, theta[t], a);
                    CHECK(fabs(a - u) <= NSIGMA * sqrt(sa * sa + su * su),
                          "sheen r=%.1f m=%d comp %d theta %.0f: sampled %.5f vs uniform %.5f",
                          (double)sr[r], k, comp, theta[t], a, u);
                }
            }
        }
    }
    /* The table: E_sh(mu, r) against a uniform-hemisphere estimate of the lobe's albedo
     * (within 1 % of it, 0.001 and the estimate's 5 standard errors: the table is bilinear
     * between nodes 1/31 apart, and at low roughness the albedo is a few thousandths that
     * change fast with r). */
    const float rr[] = {0.1f, 0.3f, 0.6f, 1.0f};
    const float mus[] = {0.15f, 0.5f, 0.9f};
    const float *tab = tr_ggx_ms_table();
    for (int r = 0; r < 4; ++r) {
        for (int i = 0; i < 3; ++i) {
            const float mu = mus[i];
            const tr_vec3 wo = v3(sqrtf(1.0f - mu * mu), 0.0f, mu);
            tr_rng rng;
            tr_rng_init(&rng, 31, (uint64_t)r, (uint64_t)i);
            const int N = 400000;
            double s1 = 0.0, s2 = 0.0;
            for (int k = 0; k < N; ++k) {
                const tr_vec3 d = dir_of(tr_rng_float(&rng), 2.0 * PI_D * tr_rng_float(&rng));
                const double v =
                    d.z > 0.0f ? tr_sheen_lobe(rr[r], wo, d, mu, d.z) * d.z * 2.0 * PI_D : 0.0;
                s1 += v;
                s2 += v * v;
            }
            const double e = s1 / N, se = sqrt(fmax(0.0, s2 / N - e * e) / N);
            const double t = tr_ggx_ms_e(tab + TR_GGX_MS_SHEEN, mu, rr[r]);
            CHECK(fabs(t - e) <= 0.01 * e + 0.001 + NSIGMA * se,
                  "sheen albedo table r=%.1f mu=%.2f: %.5f vs estimate %.5f +- %.5f", (double)rr[r],
                  (double)mu, t, e, se);
        }
    }
    /* A black sheen: bit for bit none, whatever its roughness. */
    tr_bsdf_params p0 = principled(v3(0.9f, 0.6f, 0.3f), 0.5f, 0.3f);
    tr_bsdf_params p1 = p0;
    tr_material_ext e1;
    memset(&e1, 0, sizeof e1);
    e1.sheen_roughness = 0.4f;
    p1.ext = &e1;
    p1.ms = tab;
    const int differ = bsdf_differences(&p0, &p1, 8);
    CHECK(differ == 0, "black sheen: %d of 2000 cases differ from none", differ);
}

/* (h) */
static void specular_tests(void) {
    const double theta[] = {0.0, 45.0, 80.0};
    for (int comp = 0; comp < 2; ++comp) {
        for (int k = 0; k < 2; ++k) {
            tr_material_ext e;
            memset(&e, 0, sizeof e);
            e.flags = TR_MATEXT_SPECULAR;
            e.specular = 0.6f;
            e.specular_color = v3(2.0f, 1.0f, 0.3f);
            tr_bsdf_params p = principled(v3(0.9f, 0.6f, 0.3f), 0.4f, 0.5f * (float)k);
            p.ext = &e;
            p.ms = tr_ggx_ms_table();
            p.flags = comp ? TR_MATERIAL_MULTISCATTER : 0u;
            for (int t = 0; t < 3; ++t) {
                chi2_case(&p, theta[t], 1700 + (uint64_t)(10 * comp + 5 * k + t));
            }
            reciprocity(&p);
            tr_bsdf_params w = principled(v3s(1.0f), 0.4f, 0.5f * (float)k);
            w.ext = &e;
            w.ms = tr_ggx_ms_table();
            w.flags = p.flags;
            for (int t = 0; t < 3; ++t) {
                double a, sa, u, su;
                albedo(&w, theta[t], &a, &sa, &u, &su);
                CHECK(a <= 1.0 + NSIGMA * sa, "specular comp %d m=%d theta %.0f: albedo %.5f > 1",
                      comp, k, theta[t], a);
                CHECK(fabs(a - u) <= NSIGMA * sqrt(sa * sa + su * su),
                      "specular comp %d m=%d theta %.0f: sampled %.5f vs uniform %.5f", comp, k,
                      theta[t], a, u);
            }
        }
    }
    /* Specular 1 and white: bit for bit none (the parameters' defaults). */
    tr_bsdf_params p0 = principled(v3(0.9f, 0.6f, 0.3f), 0.5f, 0.3f);
    tr_bsdf_params p1 = p0;
    tr_material_ext e1;
    memset(&e1, 0, sizeof e1);
    e1.flags = TR_MATEXT_SPECULAR;
    e1.specular = 1.0f;
    e1.specular_color = v3s(1.0f);
    p1.ext = &e1;
    CHECK(p0.ext == NULL && tr_principled_specular(&p0) == 1.0f &&
              tr_principled_specular_color(&p0).x == 1.0f &&
              tr_principled_specular_color(&p0).z == 1.0f,
          "specular defaults to 1 and white");
    const int differ = bsdf_differences(&p0, &p1, 12);
    CHECK(differ == 0, "specular 1, white: %d of 2000 cases differ", differ);
}

/* (i) The passes' albedo (tr_bsdf_guide_albedo) against the BSDF's own directional albedo,
 * the sampler's mean weight over 400000 draws (standard error about 0.001). With the
 * multiple-scattering table, as every scene's principled material has it, the two agree
 * to 0.01; without it (Karis's fit for the layer) a dielectric's to 0.05. A diffuse
 * surface's is its colour. */
static void guide_albedo_tests(void) {
    const float rough[] = {0.15f, 0.35f, 0.55f, 0.8f};
    const float base[] = {0.1f, 0.5f, 0.9f};
    const double theta[] = {0.0, 45.0, 75.0};
    for (int r = 0; r < 4; ++r) {
        for (int c = 0; c < 3; ++c) {
            for (int k = 0; k < 3; ++k) {
                /* k: 0 dielectric without the table, 1 dielectric, 2 metal with it */
                tr_bsdf_params p = principled(v3s(base[c]), rough[r], k == 2 ? 1.0f : 0.0f);
                if (k >= 1) {
                    p.ms = tr_ggx_ms_table();
                    p.flags |= TR_MATERIAL_MULTISCATTER;
                }
                const double tol = k == 0 ? 0.05 : 0.01;
                for (int t = 0; t < 3; ++t) {
                    double a, sa, u, su;
                    albedo(&p, theta[t], &a, &sa, &u, &su);
                    const double to = theta[t] * PI_D / 180.0;
                    const tr_vec3 wo = v3((float)sin(to), 0.0f, (float)cos(to));
                    const double g = tr_bsdf_guide_albedo(&p, wo).x;
                    CHECK(
                        fabs(g - a) <= tol + NSIGMA * sa,
                        "guide albedo r=%.2f colour %.1f kind %d theta %.0f: %.4f, the BSDF's %.4f",
                        (double)rough[r], (double)base[c], k, theta[t], g, a);
                }
            }
        }
    }
    const tr_bsdf_params d = mat(TR_MATERIAL_DIFFUSE, v3(0.8f, 0.5f, 0.3f), 0.0f, 1.0f);
    const tr_vec3 gd = tr_bsdf_guide_albedo(&d, v3(0.6f, 0.0f, 0.8f));
    CHECK(gd.x == 0.8f && gd.y == 0.5f && gd.z == 0.3f, "diffuse guide albedo %g %g %g",
          (double)gd.x, (double)gd.y, (double)gd.z);
}

int main(void) {
    guide_albedo_tests();
    specular_tests();
    sheen_tests();
    principled_tests();
    clearcoat_tests();
    tr_bsdf_params diffuse = mat(TR_MATERIAL_DIFFUSE, v3(0.8f, 0.5f, 0.3f), 0.0f, 1.0f);
    const double theta[] = {0.0, 30.0, 60.0, 80.0};
    for (int t = 0; t < 4; ++t) {
        chi2_case(&diffuse, theta[t], 11 + (uint64_t)t);
    }
    const float rough[] = {0.15f, 0.4f, 0.7f, 1.0f};
    for (int r = 0; r < 4; ++r) {
        tr_bsdf_params g = mat(TR_MATERIAL_GLOSSY, v3(0.9f, 0.7f, 0.4f), rough[r], 1.0f);
        for (int t = 0; t < 4; ++t) {
            chi2_case(&g, theta[t], 100 + (uint64_t)(10 * r + t));
        }
        reciprocity(&g);
    }
    reciprocity(&diffuse);
    furnace();
    delta_lobes();
    alpha_mapping();
    return check_finish("test_bsdf");
}
