/* test_furnace_principled.c - the white furnace table of the principled material
 * (bsdf_principled.h) with energy compensation ("multiscatter": true).
 *
 * A sphere of white principled material (base colour 1) under a uniform white environment
 * of radiance 1, seen from far away: every pixel's first bounce sends a path along the
 * BSDF's sample and the environment returns 1, so the image's mean is the BSDF's albedo
 * averaged over the visible disc. A point of the disc at radius rho sees the view at
 * cos theta_o = sqrt(1 - rho^2), and a uniform point of the disc has rho^2 uniform: the
 * estimator below draws cos theta_o = sqrt(1 - u) and averages the sampler's weight
 * (tr_bsdf_sample: f cos / pdf, what pt's BSDF sample carries), the render's own estimator
 * without the camera. A material that neither creates nor loses energy gives 1.
 *
 * Every combination of metallic 0 and 1, roughness 0, 0.1, ..., 1 and clear coat off and
 * on (weight 1, roughness 0.1) is checked against 1 within 1 %, conductors at roughness
 * >= 0.5 within 0.5 %; each estimate's standard error (from the weights' spread, fixed
 * seeds) must be under a third of its tolerance, so that a pass means the value is there.
 * Without compensation no combination reflects more than arrives (within 5 standard
 * errors). With KHR_materials_specular (specular 0.5, specular_color (2, 1, 0.25)) the
 * dielectric keeps 1 within 1 % too, in each channel.
 *
 * The test prints the table (docs/integrators.md records it):
 *   build/release/tests/test_furnace_principled */
#include "check.h"
#include "kernel/kernel.h"
#include "scene/scene_internal.h"
#include "kernel/bsdf.h"

#include <math.h>
#include <stdint.h>
#include <string.h>

static tr_bsdf_params white(float roughness, float metallic, int coat, int comp) {
    tr_material m;
    memset(&m, 0, sizeof m);
    m.type = TR_MATERIAL_PRINCIPLED;
    m.color = v3s(1.0f);
    m.roughness = roughness;
    m.ior = 1.5f;
    m.flags = comp ? TR_MATERIAL_MULTISCATTER : 0u;
    tr_bsdf_params b = tr_material_params(&m, v3(0.0f, 0.0f, 1.0f));
    b.metallic = metallic;
    b.ms = tr_ggx_ms_table();
    if (coat) {
        b.clearcoat = 1.0f;
        b.clearcoat_roughness = 0.1f;
    }
    return b;
}

/* The sphere's mean radiance and its standard error, n samples from seed. */
static double sphere(const tr_bsdf_params *b, int n, uint64_t seed, double *se) {
    tr_rng rng;
    tr_rng_init(&rng, 4242, seed, 7);
    double s1 = 0.0, s2 = 0.0;
    for (int k = 0; k < n; ++k) {
        const float co = sqrtf(1.0f - tr_rng_float(&rng));
        const tr_vec3 wo = v3(sqrtf(fmaxf(0.0f, 1.0f - co * co)), 0.0f, co);
        const float ul = tr_rng_float(&rng), u1 = tr_rng_float(&rng), u2 = tr_rng_float(&rng);
        tr_scatter s;
        const double w = tr_bsdf_sample(b, wo, ul, u1, u2, &s) ? (double)s.weight.y : 0.0;
        s1 += w;
        s2 += w * w;
    }
    const double mean = s1 / n;
    *se = sqrt(fmax(0.0, s2 / n - mean * mean) / n);
    return mean;
}

int main(void) {
    printf("| metallic | roughness | no coat | coat (weight 1, roughness 0.1) |\n");
    printf("|---|---|---|---|\n");
    for (int k = 0; k < 2; ++k) {
        for (int r = 0; r <= 10; ++r) {
            double v[2], e[2];
            for (int coat = 0; coat < 2; ++coat) {
                const tr_bsdf_params b = white((float)r / 10.0f, (float)k, coat, 1);
                /* The conductor's rough rows have the tight bound and the most spread
                 * (its multiple-scattering lobe is not sampled on its own). */
                const int n = k == 1 && r >= 5 ? 1200000 : 200000;
                v[coat] = sphere(&b, n, (uint64_t)(100 * k + 10 * r + coat), &e[coat]);
                const double tol = k == 1 && r >= 5 ? 0.005 : 0.01;
                CHECK(e[coat] <= tol / 3.0,
                      "metallic %d roughness %.1f coat %d: standard error %.5f", k, r / 10.0, coat,
                      e[coat]);
                CHECK(fabs(v[coat] - 1.0) <= tol,
                      "metallic %d roughness %.1f coat %d: %.5f +- %.5f (furnace 1, tolerance %g)",
                      k, r / 10.0, coat, v[coat], e[coat], tol);
                /* Without compensation: never above 1. */
                const tr_bsdf_params b0 = white((float)r / 10.0f, (float)k, coat, 0);
                double e0;
                const double v0 =
                    sphere(&b0, 100000, (uint64_t)(1000 + 100 * k + 10 * r + coat), &e0);
                CHECK(v0 <= 1.0 + 5.0 * e0,
                      "uncompensated metallic %d roughness %.1f coat %d: %.5f", k, r / 10.0, coat,
                      v0);
            }
            printf("| %d | %.1f | %.4f ± %.4f | %.4f ± %.4f |\n", k, r / 10.0, v[0], e[0], v[1],
                   e[1]);
        }
    }
    for (int r = 0; r <= 10; r += 5) {
        tr_bsdf_params b = white((float)r / 10.0f, 0.0f, 0, 1);
        tr_material_ext e;
        memset(&e, 0, sizeof e);
        e.flags = TR_MATEXT_SPECULAR;
        e.specular = 0.5f;
        e.specular_color = v3(2.0f, 1.0f, 0.25f);
        b.ext = &e;
        double se;
        const double v = sphere(&b, 200000, (uint64_t)(5000 + r), &se);
        printf("specular 0.5, colour (2, 1, 0.25), roughness %.1f: %.4f +- %.4f\n", r / 10.0, v,
               se);
        CHECK(fabs(v - 1.0) <= 0.01 && se <= 0.01 / 3.0,
              "specular, roughness %.1f: %.5f +- %.5f (furnace 1)", r / 10.0, v, se);
    }
    return check_finish("test_furnace_principled");
}
