/* synth_frame.h - a synthetic G-buffer for the reconstruction tests (test_recon,
 * test_direct): left half a wall facing the camera at depth 1, right half one at depth 2
 * turned away, each of one colour with uniform noise from a seeded LCG. */
#ifndef TRAC0R_TESTS_SYNTH_FRAME_H
#define TRAC0R_TESTS_SYNTH_FRAME_H

#include <stddef.h>
#include <stdint.h>

#include "trac0r/post.h"

static uint32_t lcg(uint32_t *s) {
    *s = *s * 1664525u + 1013904223u;
    return *s >> 8;
}
static float unit(uint32_t *s) {
    return (float)lcg(s) / 16777216.0f;
}

/* Fills the w x h frame g: colour c_left / c_right plus noise of amplitude `noise` per
 * channel, albedo 0.5. With dfrac >= 0 the fraction dfrac of the colour is the direct
 * pass, and direct and indirect parts get noise of their own (g->has_direct set); with
 * dfrac < 0 the direct pass is left alone. */
static void synth_frame(tr_gbuffer *g, uint32_t w, uint32_t h, float c_left, float c_right,
                        float noise, float dfrac, uint32_t seed) {
    uint32_t s = seed;
    for (uint32_t y = 0; y < h; ++y) {
        for (uint32_t x = 0; x < w; ++x) {
            const size_t i = (size_t)y * w + x;
            const int left = x < w / 2;
            const float c = left ? c_left : c_right;
            for (int k = 0; k < 3; ++k) {
                if (dfrac < 0.0f) {
                    g->color[3 * i + k] = c + noise * (2.0f * unit(&s) - 1.0f);
                } else {
                    const float d = dfrac * c + noise * (2.0f * unit(&s) - 1.0f);
                    const float ind = (1.0f - dfrac) * c + noise * (2.0f * unit(&s) - 1.0f);
                    g->direct[3 * i + k] = d;
                    g->color[3 * i + k] = d + ind;
                }
                g->albedo[3 * i + k] = 0.5f;
            }
            g->normal[3 * i] = left ? 0.0f : 0.6f;
            g->normal[3 * i + 1] = 0.0f;
            g->normal[3 * i + 2] = left ? -1.0f : -0.8f;
            g->depth[i] = left ? 1.0f : 2.0f;
            g->prim[i] = left ? 1u : 2u;
        }
    }
    if (dfrac >= 0.0f) {
        g->has_direct = 1;
    }
}

#endif
