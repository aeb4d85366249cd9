/* sampler.h - the `pt` integrator's stateless low-discrepancy sampler: Owen-scrambled
 * Sobol points, padded by dimension pairs and shuffled, after B. Burley, "Practical
 * Hash-based Owen Scrambling", JCGT 9(4), 2020.
 *
 * A sample's uniform number is a pure function of (seed, pixel, sample index,
 * dimension): no stream is advanced, so the value does not depend on the thread, the
 * tile order or the backend, and a work item keeps only eight bytes of state.
 *
 * Construction, for one dimension pair d of one pixel:
 *   1. k = hash(pixel key, d) gives three 32-bit seeds.
 *   2. The sample index i is shuffled: i' = owen(i, seed0). An Owen scramble of the
 *      index permutes the top bits first, so the first 2^m indices map onto one aligned
 *      block of 2^m Sobol indices: every power-of-two prefix stays a (0,m,2)-net.
 *   3. The point (sobol_0(i'), sobol_1(i')) of Sobol's first two dimensions, a
 *      (0,2)-sequence in base 2, each coordinate Owen-scrambled with its own seed.
 * Pairs are padded, not taken from higher Sobol dimensions: each pair is stratified on
 * its own and, because every pair has its own shuffle, decorrelated from the others
 * (Burley 2020, section 4; Kollig and Keller 2002 for padding). One-dimensional uses take
 * the first coordinate of their own pair, a scrambled van der Corput sequence.
 *
 * Pixels are decorrelated by hashing the pixel index into the key (a per-pixel
 * shuffle and scramble), not by pbrt-v4's Z-order Sobol: the error between pixels is
 * white rather than blue, but every pixel keeps the full (0,2) stratification for any
 * power-of-two count, the image size and sample count need not be powers of two, and a
 * pixel's sequence does not change when the resolution does (tiles, strides and
 * distributed rectangles address pixels by index). `--sampler zsobol` (sampler_z.h) is the
 * screen-space alternative: the same points per pixel, digitally shifted by the pixel's
 * point in a Z-ordered net, so that neighbours' errors are blue noise.
 *
 * Sobol's generator matrices for dimensions 0 and 1 are derived here, not tabulated:
 * dimension 0 is the identity (the bit-reversed index), dimension 1 comes from the
 * primitive polynomial x + 1 with initial direction number m_1 = 1, whose recurrence
 * v_{k+1} = v_k ^ (v_k >> 1) gives the columns (Bratley and Fox, ACM TOMS 14(1), 1988;
 * the same as the first entry of Joe and Kuo's published table): the Pascal matrix mod
 * 2, applied in five shift-and-xor steps (tr_sobol1_reversed). */
#ifndef TR_KERNEL_SAMPLER_H
#define TR_KERNEL_SAMPLER_H

#include "compat.h"
#include "rng.h"

/* Dimension pairs of one pt path: the camera's pair, then TR_SAMPLER_PER_BOUNCE per
 * segment. */
#define TR_DIM_CAMERA 0u
#define TR_DIM_LIGHT 0u /* offsets inside a bounce's block; light selection and point */
#define TR_DIM_BSDF_LOBE 1u
#define TR_DIM_BSDF_DIR 2u
#define TR_DIM_ROULETTE 3u
#define TR_DIM_ENV 4u /* environment light direction */
#define TR_SAMPLER_PER_BOUNCE 5u
/* The thin lens's point (camera.h): a pair of its own, far past any path's pairs, so that
 * a pinhole camera's paths keep every number they had. */
#define TR_DIM_LENS 0x7fff0000u

typedef struct tr_sampler {
    uint32_t key;    /* hash of (seed, pixel); zsobol: of the seed and the pixel's tile */
    uint32_t index;  /* sample index inside the pixel */
    uint32_t kind;   /* TR_SAMPLER_SOBOL 0, TR_SAMPLER_RANDOM 1, TR_SAMPLER_ZSOBOL 2 */
    uint32_t morton; /* zsobol: the pixel's Z-order code inside its 65536 x 65536 tile */
} tr_sampler;

/* A 32-bit integer hash (the "lowbias32" finaliser of C. Wellons' hash prospector):
 * seeds for the scrambles must differ in every bit for nearby inputs. */
TR_FN uint32_t tr_hash32(uint32_t x) {
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846ca68bu;
    x ^= x >> 16;
    return x;
}

/* The bits of x in reverse order: swap neighbouring bits, pairs and nibbles, then the
 * bytes (one instruction where the compiler has a byte swap; OpenCL C has none). */
TR_FN uint32_t tr_reverse_bits32(uint32_t x) {
    x = ((x >> 1) & 0x55555555u) | ((x & 0x55555555u) << 1);
    x = ((x >> 2) & 0x33333333u) | ((x & 0x33333333u) << 2);
    x = ((x >> 4) & 0x0f0f0f0fu) | ((x & 0x0f0f0f0fu) << 4);
#if defined(__GNUC__) && !defined(__OPENCL_VERSION__) && !defined(__OPENCL_C_VERSION__)
    return __builtin_bswap32(x);
#else
    x = ((x >> 8) & 0x00ff00ffu) | ((x & 0x00ff00ffu) << 8);
    return (x >> 16) | (x << 16);
#endif
}

/* Laine and Karras' hash-based permutation with the constants of Burley 2020
 * (listing 2): each output bit depends only on itself and the bits below it. On
 * bit-reversed input it is an Owen scramble: after reversing back, each bit of the
 * result depends on itself and the bits above it (nested uniform scrambling). */
TR_FN uint32_t tr_lk_permute(uint32_t x, uint32_t seed) {
    x += seed;
    x ^= x * 0x6c50b47cu;
    x ^= x * 0xb82f1e52u;
    x ^= x * 0xc7afe638u;
    x ^= x * 0x8d22f6e6u;
    return x;
}

TR_FN uint32_t tr_owen_scramble(uint32_t x, uint32_t seed) {
    return tr_reverse_bits32(tr_lk_permute(tr_reverse_bits32(x), seed));
}

/* Sobol's dimension 1 for index i, bit-reversed (the fraction's first binary digit in
 * bit 0). Its generator column k is (1 + z)^k, z one digit further down: the value is
 * I(1 + z) for the index polynomial I(z) = sum_k i_k z^k, a Taylor shift by one over
 * GF(2). Since (1 + z)^(2^j) = 1 + z^(2^j) there, the shift takes five steps, each adding
 * the upper half of every block of 2h coefficients onto its lower half (divide and
 * conquer: f_lo(z+1) + (1 + z^h) f_hi(z+1)). */
TR_FN uint32_t tr_sobol1_reversed(uint32_t i) {
    i ^= (i & 0xaaaaaaaau) >> 1;
    i ^= (i & 0xccccccccu) >> 2;
    i ^= (i & 0xf0f0f0f0u) >> 4;
    i ^= (i & 0xff00ff00u) >> 8;
    i ^= (i & 0xffff0000u) >> 16;
    return i;
}

/* Sobol's dimension 1 for index i, as a 32-bit fraction. */
TR_FN uint32_t tr_sobol1(uint32_t i) {
    return tr_reverse_bits32(tr_sobol1_reversed(i));
}

/* [0,1) from the top 24 bits: every value exactly representable, never 1. */
TR_FN float tr_u32_to_unit(uint32_t x) {
    return (float)(x >> 8) * (1.0f / 16777216.0f);
}

/* Point k of a Hammersley set of `count` points over the unit square, each in its stratum's
 * centre: u = (k + 1/2) / count, v = the radical inverse of k in base 2 plus half of 1/count.
 * Where count is a power of two the set is a (0, m, 2)-net (Niederreiter 1992): every
 * elementary interval of area 1/count holds exactly one point, so a straight edge that
 * crosses a pixel along or across its rows is found to 1/count of its coverage, where an
 * n x n grid of the same count finds it only to 1/n. The points do not depend on any seed. */
TR_FN void tr_hammersley_point(uint32_t k, uint32_t count, float *u, float *v) {
    const float inv = 1.0f / (float)count;
    *u = ((float)k + 0.5f) * inv;
    *v = tr_u32_to_unit(tr_reverse_bits32(k)) + 0.5f * inv;
}

TR_FN tr_sampler tr_sampler_make(uint64_t seed, uint64_t pixel, uint32_t index) {
    tr_sampler s;
    s.key = (uint32_t)tr_mix64(seed ^ tr_mix64(pixel + (uint64_t)0x9e3779b97f4a7c15UL));
    s.index = index;
    s.kind = 0u;
    s.morton = 0u;
    return s;
}

/* The sampler of kind `kind` (TR_SAMPLER_SOBOL 0, TR_SAMPLER_RANDOM 1): the same key and
 * index; random replaces the points by independent uniform numbers, as a baseline. */
TR_FN tr_sampler tr_sampler_make_kind(uint64_t seed, uint64_t pixel, uint32_t index,
                                      uint32_t kind) {
    tr_sampler s = tr_sampler_make(seed, pixel, index);
    s.kind = kind == 1u ? 1u : 0u;
    return s;
}

#include "sampler_z.h"

/* The sampler of any kind for pixel (x, y), the pixel_index-th of the image: zsobol
 * addresses the pixel by its coordinates, the others by its index. */
TR_FN tr_sampler tr_sampler_make_pixel(uint64_t seed, uint64_t pixel_index, uint32_t x, uint32_t y,
                                       uint32_t index, uint32_t kind) {
    if (kind == 2u) {
        return tr_sampler_make_z(seed, x, y, index);
    }
    return tr_sampler_make_kind(seed, pixel_index, index, kind);
}

/* Independent uniform numbers for (key, index, dim): 64 bits of a hash of all three, no
 * stratification across samples or pixels (the baseline the Sobol points are measured
 * against; bench realtime --sampler random). */
TR_FN uint64_t tr_sampler_random_bits(const tr_sampler *s, uint32_t dim) {
    uint64_t k = ((uint64_t)s->key << 32) | (uint64_t)s->index;
    return tr_mix64(k ^ tr_mix64((uint64_t)dim + (uint64_t)0x632be59bd9b4e019UL));
}

/* The point of dimension pair `dim`: both coordinates in [0,1). The Owen scramble of a
 * Sobol coordinate reverses it, permutes and reverses back; dimension 0 is the reversed
 * index and dimension 1 is computed reversed, so the first reversal cancels. */
TR_FN void tr_sampler_2d(const tr_sampler *s, uint32_t dim, float *u1, float *u2) {
    if (s->kind != 0u) {
        if (s->kind == 2u) {
            tr_sampler_z_2d(s, dim, u1, u2);
        } else {
            uint64_t r = tr_sampler_random_bits(s, dim);
            *u1 = tr_u32_to_unit((uint32_t)r);
            *u2 = tr_u32_to_unit((uint32_t)(r >> 32));
        }
        return;
    }
    uint32_t k = tr_hash32(s->key ^ tr_hash32(dim + 0x68e31da4u));
    uint32_t i = tr_owen_scramble(s->index, k);
    uint32_t x = tr_reverse_bits32(tr_lk_permute(i, tr_hash32(k + 0x1b56c4e9u)));
    uint32_t y =
        tr_reverse_bits32(tr_lk_permute(tr_sobol1_reversed(i), tr_hash32(k + 0x2f3a8d17u)));
    *u1 = tr_u32_to_unit(x);
    *u2 = tr_u32_to_unit(y);
}

/* The first coordinate of dimension pair `dim`. */
TR_FN float tr_sampler_1d(const tr_sampler *s, uint32_t dim) {
    if (s->kind != 0u) {
        if (s->kind == 2u) {
            float u1, u2;
            tr_sampler_z_2d(s, dim, &u1, &u2);
            return u1;
        }
        return tr_u32_to_unit((uint32_t)tr_sampler_random_bits(s, dim));
    }
    uint32_t k = tr_hash32(s->key ^ tr_hash32(dim + 0x68e31da4u));
    uint32_t i = tr_owen_scramble(s->index, k);
    return tr_u32_to_unit(tr_reverse_bits32(tr_lk_permute(i, tr_hash32(k + 0x1b56c4e9u))));
}

/* The dimension pair of use `what` (TR_DIM_*) at path segment seg (1 = camera ray). */
TR_FN uint32_t tr_sampler_dim(int seg, uint32_t what) {
    return 1u + (uint32_t)(seg - 1) * TR_SAMPLER_PER_BOUNCE + what;
}

#endif
