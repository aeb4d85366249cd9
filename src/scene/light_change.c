/* light_change.c - lights that change at run time: an emitter's emittance set (switched
 * off, on or scaled), the sun turned, and the demonstration animation of both. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "scene/scene_internal.h"
#include "trac0r/scene.h"

int tr_scene_set_emittance(tr_scene *s, uint32_t material, float emittance, tr_error *err) {
    if (material >= s->material_count) {
        return tr_error_set(err, TR_STATUS_NOT_FOUND,
                            "material %u does not exist (the scene has %u)", material,
                            s->material_count);
    }
    tr_material *m = &s->materials[material];
    if (m->type != TR_MATERIAL_EMITTER) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT, "material %u is not an emitter",
                            material);
    }
    if (!isfinite(emittance) || emittance < 0.0f) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "emittance %g must be finite and non-negative", (double)emittance);
    }
    if (m->emittance == emittance) {
        return TR_OK; /* nothing changes: the committed scene stays current */
    }
    m->emittance = emittance;
    s->lights_dirty = 1;
    s->generation++;
    return TR_OK;
}

int tr_scene_set_sun_direction(tr_scene *s, tr_vec3 dir, tr_error *err) {
    float angle;
    tr_vec3 irradiance;
    if (!tr_scene_sun(s, NULL, &angle, &irradiance)) {
        return tr_error_set(err, TR_STATUS_NOT_FOUND, "the scene has no sun");
    }
    if (tr_scene_set_sun(s, dir, angle, irradiance, err) != TR_OK) {
        return TR_ERR;
    }
    s->generation++;
    return TR_OK;
}

int tr_scene_rebuild_lights(tr_scene *s, tr_error *err) {
    if (tr_scene_build_lights(s, err) != TR_OK) {
        return TR_ERR;
    }
    tr_scene_free_light_tree(s);
    if (tr_scene_light_tree_wanted(s) && tr_scene_build_light_tree(s, err) != TR_OK) {
        return TR_ERR;
    }
    s->lights_dirty = 0;
    return TR_OK;
}

const char *tr_light_animation_name(int mode) {
    switch (mode) {
    case TR_LIGHT_ANIMATION_NONE:
        return "none";
    case TR_LIGHT_ANIMATION_SWITCH:
        return "switch";
    case TR_LIGHT_ANIMATION_MOVE:
        return "move";
    default:
        return NULL;
    }
}

int tr_light_animation_from_name(const char *name) {
    for (int m = TR_LIGHT_ANIMATION_NONE; m <= TR_LIGHT_ANIMATION_MOVE; ++m) {
        if (name && strcmp(name, tr_light_animation_name(m)) == 0) {
            return m;
        }
    }
    return -1;
}

int tr_light_animation_on(uint32_t frame) {
    return frame % TR_LIGHT_SWITCH_PERIOD < TR_LIGHT_SWITCH_PERIOD / 2u;
}

/* The emitters' emittances as first seen, so that a switched-off light comes back. */
static int save_base(tr_scene *s, tr_error *err) {
    if (s->light_base_count == s->material_count) {
        return TR_OK;
    }
    float *b =
        realloc(s->light_base, (size_t)(s->material_count ? s->material_count : 1) * sizeof *b);
    if (!b) {
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory for the lights' state");
    }
    /* Materials added since keep their own emittance as their base. */
    for (uint32_t i = s->light_base_count; i < s->material_count; ++i) {
        b[i] = s->materials[i].emittance;
    }
    s->light_base = b;
    s->light_base_count = s->material_count;
    return TR_OK;
}

static double sway(double amplitude, uint32_t frame) {
    const double two_pi = 6.283185307179586;
    return amplitude * sin(two_pi * (double)(frame % 60u) / 60.0);
}

/* Whether shape i is an emitter's: its first triangle's material emits (as first seen). */
static int emitter_shape(const tr_scene *s, uint32_t shape) {
    const tr_flat_node *node = &s->shapes[shape];
    if (node->count == 0) {
        return 0;
    }
    const uint32_t m = tr_scene_triangle(s, node->first).material; /* a kept instance too */
    return m < s->material_count && s->materials[m].type == TR_MATERIAL_EMITTER &&
           (m < s->light_base_count ? s->light_base[m] : s->materials[m].emittance) > 0.0f;
}

int tr_scene_animate_light(tr_scene *s, uint32_t frame, int mode, tr_error *err) {
    if (!tr_light_animation_name(mode)) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT, "unknown light animation %d", mode);
    }
    if (mode == TR_LIGHT_ANIMATION_NONE) {
        return TR_OK;
    }
    if (save_base(s, err) != TR_OK) {
        return TR_ERR;
    }
    if (mode == TR_LIGHT_ANIMATION_SWITCH) {
        const float on = tr_light_animation_on(frame) ? 1.0f : 0.0f;
        for (uint32_t i = 0; i < s->material_count; ++i) {
            if (s->materials[i].type == TR_MATERIAL_EMITTER && s->light_base[i] > 0.0f &&
                tr_scene_set_emittance(s, i, on * s->light_base[i], err) != TR_OK) {
                return TR_ERR;
            }
        }
        return TR_OK;
    }
    if (frame == 0) {
        return TR_OK; /* where it was built */
    }
    /* Moving: every emitter's shape sways along x, a quarter of its width either way, and
     * the sun turns about y, 0.3 radians either way; one period per 60 frames. */
    for (uint32_t i = 0; i < s->shape_count; ++i) {
        if (!emitter_shape(s, i)) {
            continue;
        }
        const double width = (double)s->shapes[i].box.max.x - (double)s->shapes[i].box.min.x;
        const double dx = sway(0.25 * width, frame) - sway(0.25 * width, frame - 1);
        if (tr_scene_move_shape(s, i, tr_vec3_make((float)dx, 0.0f, 0.0f), err) != TR_OK) {
            return TR_ERR;
        }
    }
    tr_vec3 d;
    if (tr_scene_sun(s, &d, NULL, NULL)) {
        const double a = sway(0.3, frame) - sway(0.3, frame - 1);
        const double c = cos(a), sn = sin(a);
        const tr_vec3 r =
            tr_vec3_make((float)(c * d.x + sn * d.z), d.y, (float)(c * d.z - sn * d.x));
        if (tr_scene_set_sun_direction(s, r, err) != TR_OK) {
            return TR_ERR;
        }
    }
    return TR_OK;
}
