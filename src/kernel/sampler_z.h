/* sampler_z.h - `--sampler zsobol`: the Sobol sampler of sampler.h with the pixels'
 * errors spread as blue noise in screen space. Included by sampler.h, whose scrambles
 * and Sobol dimensions it uses.
 *
 * The independently hashed pixels of the plain Sobol sampler make the error of
 * neighbouring pixels independent (white noise). Interpolating neighbours, as a
 * reprojected history in `bench realtime` does, then averages independent errors. Here
 * the point of dimension pair d, sample i, pixel p is
 *
 *     P_d(i, p) = T_d(i) xor B_d(p)        (coordinate-wise, on the 32-bit fractions)
 *
 *   - T_d(i): the sample index's point, shared by every pixel: the Owen-scrambled Sobol
 *     (0,2)-sequence of sampler.h, shuffled and scrambled by seeds hashed from (seed, d)
 *     alone.
 *   - B_d(p): the pixel's point in a screen-wide (0,2)-net: Sobol's first two
 *     dimensions at index g = pi_d(z(p)), z(p) the Morton (Z-order) code of the pixel's
 *     coordinates and pi_d a random permutation of its base-4 digits that is nested (the
 *     digit of level k is permuted by a choice that depends on the digits above it).
 *     This is the hierarchical pixel ordering of A. G. M. Ahmed and P. Wonka,
 *     "Screen-Space Blue-Noise Diffusion of Monte Carlo Sampling Error via Hierarchical
 *     Ordering of Pixels", ACM TOG 39(6), 2020 (pbrt-v4's ZSobolSampler), with one sample
 *     per pixel: the pixels of each aligned 2^k x 2^k block of the screen get the
 *     4^k indices of one aligned block of the Sobol sequence, a (0,2k,2)-net.
 *
 * A digital shift (xor with a constant) maps every elementary interval of base 2 onto
 * another, so it keeps nets nets. Hence both at once:
 *   - in time, each pixel's points over the sample index are T's scrambled
 *     (0,2)-sequence shifted by B_d(p): every aligned block of 2^m samples is a
 *     (0,m,2)-net, as with the plain sampler (the same error per pixel);
 *   - in space, at each sample index (one frame of `bench realtime` at 1 spp) the
 *     points of each aligned 2^k x 2^k block of pixels form a (0,2k,2)-net shifted by
 *     T_d(i): neighbours' errors are anti-correlated, so the error of a block mean, of a
 *     blur or of an interpolation is smaller (blue noise). Where Ahmed and Wonka put the
 *     sample index below the Morton code (the screen-space net forms only over a whole
 *     pixel's sample count, which must be a known power of two), the shift keeps a net
 *     at every single sample index and lets the sample count be anything.
 * Per-pixel shifts of one shared sequence are Georgiev and Fajardo's dithered sampling
 * (I. Georgiev and M. Fajardo, "Blue-Noise Dithered Sampling", SIGGRAPH Talks 2016,
 * there a toroidal shift read from a blue-noise mask); here the shift is digital and the
 * mask is the Z-ordered net, which needs no table and has no period.
 *
 * Unbiased: T_d(i) is uniform (Owen scrambling makes each point uniform) and independent
 * of the fixed B_d(p), and u xor c of a uniform u is uniform.
 *
 * The permutation pi_d: Burley's hashed Owen scramble of the code (sampler.h) flips
 * each bit by a choice depending on the bits above it, which over a base-4 digit gives
 * the 8 permutations that keep the digit's halves {0,1}, {2,3} together; before it a
 * second scramble's choice, also depending only on the digits above, swaps the digit's
 * two bits (x and y), so that a block's Sobol pairs fall on rows as often as on columns
 * (16 of the 24 permutations of a digit; pbrt-v4 draws from all 24 with a table).
 *
 * Pixels are addressed by their coordinates (16 bits each; beyond 65536 the tile's
 * position enters the key), not by the image's width: a pixel's numbers do not depend on
 * the resolution, tiles, strides or rectangles. */
#ifndef TR_KERNEL_SAMPLER_Z_H
#define TR_KERNEL_SAMPLER_Z_H

/* Spreads the low 16 bits of v to the even bit positions. */
TR_FN uint32_t tr_spread_bits16(uint32_t v) {
    v &= 0xffffu;
    v = (v | (v << 8)) & 0x00ff00ffu;
    v = (v | (v << 4)) & 0x0f0f0f0fu;
    v = (v | (v << 2)) & 0x33333333u;
    v = (v | (v << 1)) & 0x55555555u;
    return v;
}

/* The Morton code of (x, y) in a 65536 x 65536 tile: x in the even bits, y in the odd. */
TR_FN uint32_t tr_morton2(uint32_t x, uint32_t y) {
    return tr_spread_bits16(x) | (tr_spread_bits16(y) << 1);
}

TR_FN tr_sampler tr_sampler_make_z(uint64_t seed, uint32_t x, uint32_t y, uint32_t index) {
    tr_sampler s;
    const uint64_t tile = ((uint64_t)(y >> 16) << 16) | (uint64_t)(x >> 16);
    s.key = (uint32_t)tr_mix64(seed ^ tr_mix64(tile + (uint64_t)0x3c6ef372fe94f82bUL));
    s.index = index;
    s.kind = 2u;
    s.morton = tr_morton2(x, y);
    return s;
}

/* pi: the nested permutation of the base-4 digits of Morton code z. */
TR_FN uint32_t tr_zorder_permute(uint32_t z, uint32_t seed_swap, uint32_t seed_flip) {
    /* Bit 2k+1 of `swap` set: swap the bits of digit k. The flip an Owen scramble makes
     * to bit 2k+1 depends only on the bits above it, i.e. on the higher digits. */
    const uint32_t swap = (tr_owen_scramble(z, seed_swap) ^ z) & 0xaaaaaaaau;
    const uint32_t diff = ((z >> 1) ^ z) & (swap >> 1); /* digits whose two bits differ */
    z ^= diff | (diff << 1);
    return tr_owen_scramble(z, seed_flip);
}

/* The point of dimension pair `dim`, in the bit-reversed domain of sampler.h: *rx, *ry
 * hold the fractions' bits with the first binary digit in bit 0. */
TR_FN void tr_sampler_z_bits(const tr_sampler *s, uint32_t dim, uint32_t *rx, uint32_t *ry) {
    const uint32_t k = tr_hash32(s->key ^ tr_hash32(dim + 0x68e31da4u));
    /* T: as sampler.h's point, with a key that does not name the pixel. */
    const uint32_t i = tr_owen_scramble(s->index, k);
    const uint32_t tx = tr_lk_permute(i, tr_hash32(k + 0x1b56c4e9u));
    const uint32_t ty = tr_lk_permute(tr_sobol1_reversed(i), tr_hash32(k + 0x2f3a8d17u));
    /* B: Sobol's dimensions 0 and 1 at the permuted Morton code; dimension 0 reversed is
     * the index itself. */
    const uint32_t g =
        tr_zorder_permute(s->morton, tr_hash32(k + 0x5d1f0a63u), tr_hash32(k + 0x7a4c91e5u));
    *rx = tx ^ g;
    *ry = ty ^ tr_sobol1_reversed(g);
}

/* Out of line: it is called from tr_sampler_2d's rarely taken branch, and pt's default
 * (Sobol) path should not carry its code. */
TR_FN_NOINLINE void tr_sampler_z_2d(const tr_sampler *s, uint32_t dim, float *u1, float *u2) {
    uint32_t rx, ry;
    tr_sampler_z_bits(s, dim, &rx, &ry);
    *u1 = tr_u32_to_unit(tr_reverse_bits32(rx));
    *u2 = tr_u32_to_unit(tr_reverse_bits32(ry));
}

#endif
