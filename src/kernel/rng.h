/* rng.h - the thesis's random numbers (section 3.1.5): xorshift64* seeds a
 * xorshift1024* generator (S. Vigna, "An experimental exploration of Marsaglia's
 * xorshift generators, scrambled", ACM TOMS 2016).
 *
 * Streams are keyed by (seed, pixel, sample), never by thread, so an image is
 * bit-identical whatever the thread count or tile order. The key is first passed
 * through a 64-bit finaliser (the MurmurHash3 fmix64 constants) so that adjacent
 * pixels and samples start from unrelated xorshift64* states. */
#ifndef TR_KERNEL_RNG_H
#define TR_KERNEL_RNG_H

#include "compat.h"

typedef struct tr_rng {
    uint64_t s[16];
    uint32_t p;
} tr_rng;

/* One step of xorshift64*: advances *x and returns the scrambled output. */
TR_FN uint64_t tr_xorshift64star(uint64_t *x) {
    uint64_t v = *x;
    v ^= v >> 12;
    v ^= v << 25;
    v ^= v >> 27;
    *x = v;
    return v * (uint64_t)2685821657736338717UL;
}

TR_FN uint64_t tr_mix64(uint64_t k) {
    k ^= k >> 33;
    k *= (uint64_t)0xff51afd7ed558ccdUL;
    k ^= k >> 33;
    k *= (uint64_t)0xc4ceb9fe1a85ec53UL;
    k ^= k >> 33;
    return k;
}

/* Seeds the stream for one (seed, pixel, sample) triple. */
TR_FN void tr_rng_init(tr_rng *r, uint64_t seed, uint64_t pixel, uint64_t sample) {
    uint64_t x =
        tr_mix64(seed ^ tr_mix64(pixel ^ tr_mix64(sample + (uint64_t)0x9e3779b97f4a7c15UL)));
    if (x == 0) {
        x = (uint64_t)0x9e3779b97f4a7c15UL; /* xorshift has the all-zero fixed point */
    }
    for (int i = 0; i < 16; ++i) {
        r->s[i] = tr_xorshift64star(&x);
    }
    r->p = 0;
}

/* xorshift1024*: period 2^1024 - 1. */
TR_FN uint64_t tr_rng_next(tr_rng *r) {
    uint64_t s0 = r->s[r->p];
    r->p = (r->p + 1) & 15u;
    uint64_t s1 = r->s[r->p];
    s1 ^= s1 << 31;
    s1 ^= s1 >> 11;
    s0 ^= s0 >> 30;
    r->s[r->p] = s0 ^ s1;
    return r->s[r->p] * (uint64_t)1181783497276652981UL;
}

/* Uniform float in [0, 1): the top 24 bits, so every value is exactly representable. */
TR_FN float tr_rng_float(tr_rng *r) {
    return (float)(tr_rng_next(r) >> 40) * (1.0f / 16777216.0f);
}

/* Uniform float in [lo, hi). */
TR_FN float tr_rng_range(tr_rng *r, float lo, float hi) {
    return lo + (hi - lo) * tr_rng_float(r);
}

#endif
