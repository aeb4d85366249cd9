/* test_material.c - the material stage and the shared glass code change no sample.
 *
 * (a) tr_material_scatter_naive and tr_bsdf_sample's glass case now share
 *     tr_glass_sample and read tr_bsdf_params from tr_material_eval. Copies of the two
 *     glass branches as they were before (oracles, below) run beside them on random
 *     directions, normals, iors and random-number states: the new ray, weight, pdf and
 *     the random state afterwards must be bit-identical, including grazing directions
 *     and total internal reflection.
 * (b) tr_material_eval gives every material of a scene its constant parameters and the
 *     geometric normal, whatever the barycentrics, point and direction. */
#include "check.h"
#include "kernel/kernel.h"
#include "scene/scene_internal.h"
#include "kernel/bsdf.h"
#include "kernel/kernel.h"
#include "trac0r/trac0r.h"

#include <stdint.h>
#include <string.h>

/* The naive integrator's glass branch before the material stage (tr_material_scatter_naive
 * with m->type == TR_MATERIAL_GLASS), kept verbatim as the oracle. */
static void oracle_naive_glass(const tr_material *m, tr_vec3 dir, tr_vec3 p, tr_vec3 n, tr_rng *rng,
                               tr_vec3 *next_origin, tr_vec3 *next_dir, tr_vec3 *weight) {
    float cos_dn = v3_dot(dir, n);
    tr_vec3 nf = cos_dn > 0.0f ? v3_neg(n) : n;
    *weight = m->color;
    int entering = cos_dn < 0.0f;
    float n1 = entering ? 1.0f : m->ior;
    float n2 = entering ? m->ior : 1.0f;
    float cos_i = tr_fabsf(cos_dn);
    float cos_t;
    float r = tr_fresnel_dielectric(cos_i, n1, n2, &cos_t);
    if (tr_rng_float(rng) < r) {
        *next_dir = v3_reflect(dir, nf);
        *next_origin = tr_offset_origin(p, nf);
    } else {
        float eta = n1 / n2;
        *next_dir = v3_normalize(v3_add(v3_scale(dir, eta), v3_scale(nf, eta * cos_i - cos_t)));
        *next_origin = tr_offset_origin(p, v3_neg(nf));
    }
}

/* The pt integrator's glass case of tr_bsdf_sample before the material stage. */
static void oracle_pt_glass(const tr_material *m, tr_vec3 n, tr_vec3 wo, tr_rng *rng,
                            tr_scatter *s) {
    tr_vec3 nf = tr_bsdf_facing(n, wo);
    s->delta = 0;
    float cos_dn = v3_dot(wo, n);
    int entering = cos_dn > 0.0f;
    float n1 = entering ? 1.0f : m->ior;
    float n2 = entering ? m->ior : 1.0f;
    float cos_i = tr_fabsf(cos_dn);
    float cos_t;
    float r = tr_fresnel_dielectric(cos_i, n1, n2, &cos_t);
    s->delta = 1;
    s->weight = m->color;
    tr_vec3 d = v3_neg(wo);
    if (tr_rng_float(rng) < r) {
        s->wi = v3_reflect(d, nf);
        s->pdf = r;
    } else {
        float eta = n1 / n2;
        s->wi = v3_normalize(v3_add(v3_scale(d, eta), v3_scale(nf, eta * cos_i - cos_t)));
        s->pdf = 1.0f - r;
    }
}

static int same_v3(tr_vec3 a, tr_vec3 b) {
    return memcmp(&a, &b, sizeof a) == 0;
}

/* (a) */
static void glass_bit_identity(void) {
    tr_rng gen;
    tr_rng_init(&gen, 0x5eedULL, 1, 2);
    const int N = 200000;
    int bad_naive = 0, bad_pt = 0, reflected = 0, tir = 0;
    for (int k = 0; k < N; ++k) {
        tr_vec3 n = tr_sample_uniform_sphere(&gen);
        if (k % 7 == 0) {
            n = v3(0.0f, k % 14 == 0 ? 1.0f : -1.0f, 0.0f); /* axis-aligned, as in scenes */
        }
        tr_vec3 dir = tr_sample_uniform_sphere(&gen);
        if (k % 16 == 0) {
            /* Exactly tangent (cos = 0), where the entering/leaving and facing decisions
             * meet. */
            n = v3(0.0f, k % 32 == 0 ? 1.0f : -1.0f, 0.0f);
            dir = k % 64 < 32 ? v3(1.0f, 0.0f, 0.0f) : v3(0.0f, 0.0f, -1.0f);
        }
        /* iors from 1 (no boundary) to 10 (the format's limit) and the thesis's glass. */
        float ior = k % 5 == 0 ? 1.51714f : 1.0f + 9.0f * tr_rng_float(&gen);
        if (k % 11 == 0) {
            ior = 1.0f;
        }
        tr_material m = tr_material_glass(v3(tr_rng_float(&gen), 0.5f, 0.9f), ior);
        tr_vec3 p = v3_scale(tr_sample_uniform_sphere(&gen), 100.0f * tr_rng_float(&gen));
        tr_rng a, b;
        tr_rng_init(&a, (uint64_t)k * 2654435761ULL, (uint64_t)k, 3);
        /* Random states at every step of the stream's 16-word cycle. */
        for (int j = k % 17; j > 0; --j) {
            tr_rng_float(&a);
        }
        b = a;

        /* naive */
        tr_vec3 oo, od, ow, no, nd, nw;
        oracle_naive_glass(&m, dir, p, n, &a, &oo, &od, &ow);
        tr_bsdf_params bp = tr_material_params(&m, n);
        int rc = tr_material_scatter_naive(&bp, dir, p, &b, &no, &nd, &nw);
        if (rc != TR_SCATTER_CONTINUE || !same_v3(oo, no) || !same_v3(od, nd) || !same_v3(ow, nw) ||
            memcmp(&a, &b, sizeof a) != 0) {
            if (++bad_naive <= 3) {
                fprintf(stderr, "naive case %d: dir (%a %a %a) n (%a %a %a) ior %a\n", k,
                        (double)dir.x, (double)dir.y, (double)dir.z, (double)n.x, (double)n.y,
                        (double)n.z, (double)ior);
            }
        }
        float cos_dn = v3_dot(dir, n);
        reflected += v3_dot(od, n) * cos_dn < 0.0f;
        tir += cos_dn > 0.0f && ior * ior * (1.0f - cos_dn * cos_dn) >= 1.0f;

        /* pt: wo is minus the ray direction */
        tr_vec3 wo = v3_neg(dir);
        tr_scatter os, ns;
        memset(&os, 0, sizeof os);
        memset(&ns, 0, sizeof ns);
        oracle_pt_glass(&m, n, wo, &a, &os);
        rc = tr_bsdf_sample(&bp, wo, tr_rng_float(&b), 0.5f, 0.5f, &ns);
        if (!rc || !same_v3(os.wi, ns.wi) || !same_v3(os.weight, ns.weight) ||
            memcmp(&os.pdf, &ns.pdf, sizeof os.pdf) != 0 || os.delta != ns.delta ||
            memcmp(&a, &b, sizeof a) != 0) {
            if (++bad_pt <= 3) {
                fprintf(stderr, "pt case %d: wo (%a %a %a) n (%a %a %a) ior %a\n", k, (double)wo.x,
                        (double)wo.y, (double)wo.z, (double)n.x, (double)n.y, (double)n.z,
                        (double)ior);
            }
        }
    }
    CHECK(bad_naive == 0, "naive glass: %d of %d samples differ from the oracle", bad_naive, N);
    CHECK(bad_pt == 0, "pt glass: %d of %d samples differ from the oracle", bad_pt, N);
    /* The cases cover both lobes and total internal reflection. */
    CHECK(reflected > N / 50 && reflected < N - N / 50, "reflected %d of %d", reflected, N);
    CHECK(tir > N / 50, "total internal reflection in %d of %d cases", tir, N);
}

/* (b) */
static void eval_constant(void) {
    tr_scene s = {0};
    tr_error err;
    CHECK(tr_scene_builtin(&s, "cornell", 64, 48, &err) == TR_OK, "builtin: %s", err.msg);
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "commit: %s", err.msg);
    tr_scene_view v = tr_scene_view_of(&s);
    tr_rng rng;
    tr_rng_init(&rng, 9, 9, 9);
    int bad = 0;
    for (uint32_t t = 0; t < s.triangle_count; ++t) {
        const tr_material *m = &s.materials[s.triangles[t].material];
        tr_vec3 ng = s.triangles[t].normal;
        float u = tr_rng_float(&rng), w = tr_rng_float(&rng);
        tr_bsdf_params b =
            tr_material_eval(&v, t, u, w * (1.0f - u), tr_sample_uniform_sphere(&rng), ng,
                             tr_sample_uniform_sphere(&rng));
        bad += !(b.type == m->type && b.flags == m->flags && same_v3(b.color, m->color) &&
                 b.roughness == m->roughness && b.ior == m->ior && b.emittance == m->emittance &&
                 same_v3(b.ng, ng) && same_v3(b.ns, ng));
    }
    CHECK(bad == 0, "%d of %u triangles: parameters other than their material's", bad,
          s.triangle_count);
    tr_scene_clear(&s);
}

int main(void) {
    glass_bit_identity();
    eval_constant();
    return check_finish("test_material");
}
