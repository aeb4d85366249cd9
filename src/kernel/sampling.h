/* sampling.h - direction sampling (thesis section 3.1.6) and pixel jitter.
 *
 * The *_u samplers take their uniform numbers as arguments (pt draws them from its
 * low-discrepancy sampler, sampler.h); the tr_rng versions draw them from the caller's
 * stream in the same order (naive's thesis streams). Each returns a unit vector; the
 * pdfs are with respect to solid angle. */
#ifndef TR_KERNEL_SAMPLING_H
#define TR_KERNEL_SAMPLING_H

#include "compat.h"
#include "rng.h"
#include "vec.h"

/* Uniform on the unit sphere, pdf 1/(4 pi). The thesis normalised a point of the cube
 * [-1,1]^3, which is not uniform; we invert the area CDF instead (z uniform in [-1,1]). */
TR_FN tr_vec3 tr_sample_uniform_sphere(tr_rng *r) {
    float z = 1.0f - 2.0f * tr_rng_float(r);
    float phi = TR_TWO_PI * tr_rng_float(r);
    float s = tr_sqrtf(tr_fmaxf(0.0f, 1.0f - z * z));
    return v3(s * tr_cosf(phi), s * tr_sinf(phi), z);
}

TR_FN float tr_pdf_uniform_sphere(void) {
    return 1.0f / (4.0f * TR_PI);
}

/* 1 - cos(angle)^(power+1), the lobe's normalisation, without the cancellation that
 * makes narrow cones collapse onto their axis in float. */
TR_FN float tr_cone_one_minus_cmin(float power, float angle) {
    if (angle >= TR_HALF_PI) {
        return 1.0f;
    }
    /* log(cos a) from sin a: cos a rounds to 1 in float long before sin a loses digits. */
    float sa = tr_sinf(angle);
    float log_c = 0.5f * tr_log1pf(-sa * sa);
    return -tr_expm1f((power + 1.0f) * log_c);
}

/* Local-frame sample of the power-cosine lobe cos^power(theta), restricted to the cone
 * theta <= angle (0 < angle <= pi/2), around +z.
 *
 * Invert the CDF of z = cos(theta): p(z) ~ z^power on [cos(angle), 1], so
 * z^(power+1) = 1 - (1 - u) (1 - cos(angle)^(power+1)).
 * The thesis's listing 12 drew u from [cos(angle), 1] instead of [cos(angle)^(power+1), 1],
 * which for power = 1 narrows the cone to acos(sqrt(cos(angle))); we sample the cone the
 * documentation describes. power = 0: uniform, power = 1: cosine-weighted. z and
 * sin(theta) both come from log1p/expm1 so that narrow cones keep their spread. */
TR_FN tr_vec3 tr_sample_cone_local_u(float u, float uphi, float power, float angle) {
    float e = power + 1.0f;
    float omc = tr_cone_one_minus_cmin(power, angle);
    float phi = TR_TWO_PI * uphi;
    float z, s;
    if (power == 1.0f && omc == 1.0f) {
        /* The cosine-weighted hemisphere, every diffuse bounce: z^2 = u exactly. */
        z = tr_sqrtf(u);
        s = tr_sqrtf(1.0f - u);
    } else {
        float lz = tr_log1pf(-(1.0f - u) * omc) / e; /* log(z), <= 0 */
        z = tr_expf(lz);
        s = tr_sqrtf(tr_fmaxf(0.0f, -tr_expm1f(2.0f * lz)));
    }
    return v3(s * tr_cosf(phi), s * tr_sinf(phi), z);
}

TR_FN tr_vec3 tr_sample_cone_local(tr_rng *r, float power, float angle) {
    float u = tr_rng_float(r);
    float uphi = tr_rng_float(r);
    return tr_sample_cone_local_u(u, uphi, power, angle);
}

/* Pdf (solid angle) of tr_sample_cone_local for a direction with cos(theta) = z. */
TR_FN float tr_pdf_cone(float power, float angle, float z) {
    if (z < tr_cosf(angle) || z > 1.0f) {
        return 0.0f;
    }
    float e = power + 1.0f;
    return e * tr_powf(tr_fmaxf(z, 0.0f), power) /
           (TR_TWO_PI * tr_cone_one_minus_cmin(power, angle));
}

/* The thesis's sample_hemisphere(dir, power, angle): the lobe above around dir. */
TR_FN tr_vec3 tr_sample_hemisphere_u(float u1, float u2, tr_vec3 dir, float power, float angle) {
    tr_vec3 t, b;
    v3_basis(dir, &t, &b);
    tr_vec3 l = tr_sample_cone_local_u(u1, u2, power, angle);
    return v3_normalize(v3_add(v3_add(v3_scale(t, l.x), v3_scale(b, l.y)), v3_scale(dir, l.z)));
}

TR_FN tr_vec3 tr_sample_hemisphere(tr_rng *r, tr_vec3 dir, float power, float angle) {
    float u1 = tr_rng_float(r);
    float u2 = tr_rng_float(r);
    return tr_sample_hemisphere_u(u1, u2, dir, power, angle);
}

/* Cosine-weighted on the hemisphere around dir from the uniforms (u1, u2). */
TR_FN tr_vec3 tr_sample_cosine_hemisphere_u(float u1, float u2, tr_vec3 dir) {
    return tr_sample_hemisphere_u(u1, u2, dir, 1.0f, TR_HALF_PI);
}

/* Uniform on the hemisphere around dir, pdf 1/(2 pi). */
TR_FN tr_vec3 tr_sample_uniform_hemisphere(tr_rng *r, tr_vec3 dir) {
    return tr_sample_hemisphere(r, dir, 0.0f, TR_HALF_PI);
}

/* Cosine-weighted on the hemisphere around dir, pdf cos(theta)/pi. */
TR_FN tr_vec3 tr_sample_cosine_hemisphere(tr_rng *r, tr_vec3 dir) {
    return tr_sample_hemisphere(r, dir, 1.0f, TR_HALF_PI);
}

/* Cosine-weighted inside the cone of half-angle `angle` around dir. */
TR_FN tr_vec3 tr_sample_cosine_cone(tr_rng *r, tr_vec3 dir, float angle) {
    return tr_sample_hemisphere(r, dir, 1.0f, angle);
}

/* Sub-pixel jitter for anti-aliasing: a uniform offset in [0,1)^2. */
TR_FN void tr_sample_pixel_jitter(tr_rng *r, float *dx, float *dy) {
    *dx = tr_rng_float(r);
    *dy = tr_rng_float(r);
}

#endif
