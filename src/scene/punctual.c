/* punctual.c - point, spot and directional lights on the host: checks, and the power CDF
 * next-event estimation picks them by (src/kernel/punctual.h). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "scene/scene_internal.h"

#define PI_D 3.14159265358979323846

int tr_scene_add_punctual(tr_scene *s, const tr_punctual *light, tr_error *err) {
    tr_punctual l = *light;
    if (l.type != TR_PUNCTUAL_POINT && l.type != TR_PUNCTUAL_SPOT &&
        l.type != TR_PUNCTUAL_DIRECTIONAL) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT, "unknown punctual light type %u",
                            l.type);
    }
    if (s->punctual_count >= TR_MAX_PUNCTUAL) {
        return tr_error_set(err, TR_STATUS_LIMIT, "more than %u punctual lights",
                            (unsigned)TR_MAX_PUNCTUAL);
    }
    if (!v3_is_finite(l.intensity) || l.intensity.x < 0.0f || l.intensity.y < 0.0f ||
        l.intensity.z < 0.0f) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "light intensity must be finite and non-negative");
    }
    if (l.type != TR_PUNCTUAL_DIRECTIONAL && !v3_is_finite(l.pos)) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT, "light position must be finite");
    }
    if (l.type != TR_PUNCTUAL_POINT) {
        const float len = v3_length(l.dir);
        if (!v3_is_finite(l.dir) || !(len > 0.0f) || !isfinite(len)) {
            return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                                "light direction must be a finite non-zero vector");
        }
        l.dir = v3_scale(l.dir, 1.0f / len);
    } else {
        l.dir = v3(0.0f, -1.0f, 0.0f);
    }
    if (l.type == TR_PUNCTUAL_SPOT) {
        if (!(l.cos_outer >= -1.0f && l.cos_outer < 1.0f) ||
            !(l.cos_inner >= l.cos_outer && l.cos_inner <= 1.0f)) {
            return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                                "spot cone cosines outer %g, inner %g must satisfy -1 <= outer "
                                "< 1 and outer <= inner <= 1",
                                (double)l.cos_outer, (double)l.cos_inner);
        }
    } else {
        l.cos_outer = -1.0f;
        l.cos_inner = -1.0f;
    }
    if (s->punctual_count == s->punctual_capacity) {
        const uint32_t cap = s->punctual_capacity ? 2u * s->punctual_capacity : 4u;
        tr_punctual *p = realloc(s->punctual, (size_t)cap * sizeof *p);
        if (!p) {
            return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory for lights");
        }
        s->punctual = p;
        s->punctual_capacity = cap;
    }
    l.cdf = 0.0f;
    l.power = 0.0f;
    memset(l.pad, 0, sizeof l.pad);
    s->punctual[s->punctual_count++] = l;
    s->generation++;
    return TR_OK;
}

/* A light's selection weight: its power (mean over the channels). A spot's is the cone's
 * solid angle up to the middle of its blend times I; a directional light's is its
 * irradiance over the disc of the scene's bounding sphere (radius `radius`). */
static double punctual_power(const tr_punctual *l, double radius) {
    const double m = ((double)l->intensity.x + l->intensity.y + l->intensity.z) / 3.0;
    switch (l->type) {
    case TR_PUNCTUAL_SPOT:
        return 2.0 * PI_D * (1.0 - 0.5 * ((double)l->cos_inner + l->cos_outer)) * m;
    case TR_PUNCTUAL_DIRECTIONAL:
        return PI_D * radius * radius * m;
    default:
        return 4.0 * PI_D * m;
    }
}

void tr_scene_build_punctual(tr_scene *s) {
    s->punctual_built = s->punctual_count;
    if (s->punctual_count == 0u) {
        return;
    }
    const tr_aabb b = tr_triangles_bounds(s->triangles, s->triangle_count);
    double radius = 0.5 * (double)v3_length(v3_sub(b.max, b.min));
    if (!(radius > 0.0) || !isfinite(radius)) {
        radius = 1.0;
    }
    double total = 0.0;
    for (uint32_t i = 0; i < s->punctual_count; ++i) {
        s->punctual[i].power = (float)punctual_power(&s->punctual[i], radius);
        total += s->punctual[i].power;
    }
    double acc = 0.0;
    for (uint32_t i = 0; i < s->punctual_count; ++i) {
        /* All black: every light alike (they give nothing either way). */
        acc += total > 0.0 ? s->punctual[i].power / total : 1.0 / s->punctual_count;
        s->punctual[i].cdf = (float)acc;
    }
    s->punctual[s->punctual_count - 1u].cdf = 1.0f;
}
