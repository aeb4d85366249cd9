/* material_registry.c - material types' keys, neutral values and checks, generated from
 * TR_MATERIAL_TYPES (trac0r/material_types.h). */
#include "material_registry.h"

#include <math.h>
#include <stddef.h>
#include <string.h>

#include "trac0r/registry.h"
#include "trac0r/scene_file.h"

/* Ranges are the scene format's (docs/scene-format.md); an emitter's colour scales its
 * radiance and may exceed 1 up to the format's coordinate limit. */
static const tr_material_key_info keys[] = {
    {TR_MATERIAL_KEY_COLOR, "color", TR_KEY_COLOR, 0.0, 1.0, 0, offsetof(tr_material, color), 0u},
    {TR_MATERIAL_KEY_LIGHT_COLOR, "color", TR_KEY_COLOR, 0.0, TR_SCENE_FILE_MAX_COORD, 0,
     offsetof(tr_material, color), 0u},
    {TR_MATERIAL_KEY_EMITTANCE, "emittance", TR_KEY_NUMBER, 0.0, 1e7, 1,
     offsetof(tr_material, emittance), 0u},
    {TR_MATERIAL_KEY_TWO_SIDED, "two_sided", TR_KEY_FLAG, 0.0, 0.0, 0, 0, TR_MATERIAL_TWO_SIDED},
    {TR_MATERIAL_KEY_MULTISCATTER, "multiscatter", TR_KEY_FLAG, 0.0, 0.0, 0, 0,
     TR_MATERIAL_MULTISCATTER},
    {TR_MATERIAL_KEY_IOR, "ior", TR_KEY_NUMBER, 1.0, 10.0, 0, offsetof(tr_material, ior), 0u},
    {TR_MATERIAL_KEY_ROUGHNESS, "roughness", TR_KEY_NUMBER, 0.0, 1.0, 0,
     offsetof(tr_material, roughness), 0u},
};

const tr_material_key_info *tr_material_keys(size_t *count) {
    *count = sizeof keys / sizeof keys[0];
    return keys;
}

int tr_material_type_keys(uint32_t type, uint32_t *required, uint32_t *optional) {
#define TYPE_KEYS(id, value, name, req, opt)                                                       \
    if (type == (uint32_t)(value)) {                                                               \
        *required = (req);                                                                         \
        *optional = (opt);                                                                         \
        return 1;                                                                                  \
    }
    TR_MATERIAL_TYPES(TYPE_KEYS)
#undef TYPE_KEYS
    *required = *optional = 0u;
    return 0;
}

tr_material tr_material_default(uint32_t type) {
    tr_material m;
    memset(&m, 0, sizeof m);
    m.type = type;
    m.ior = 1.0f;
    if (type == TR_MATERIAL_PRINCIPLED) {
        /* A dielectric layer of index 1.5 (F0 = 0.04, glTF's) and glTF's default roughness,
         * with multiple-scattering compensation (energy-conserving: a white sphere keeps a
         * white furnace's radiance at every roughness; docs/integrators.md). */
        m.ior = 1.5f;
        m.roughness = 1.0f;
        m.flags = TR_MATERIAL_MULTISCATTER;
    }
    return m;
}

int tr_material_check(const tr_material *m, tr_error *err) {
    if (!tr_material_type_name(m->type)) {
#define TYPE_VALUE(id, value, name, req, opt) value,
        static const uint32_t values[] = {TR_MATERIAL_TYPES(TYPE_VALUE)};
#undef TYPE_VALUE
        uint32_t lo = values[0], hi = values[0];
        for (size_t i = 1; i < sizeof values / sizeof values[0]; ++i) {
            lo = values[i] < lo ? values[i] : lo;
            hi = values[i] > hi ? values[i] : hi;
        }
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "unknown material type %u (expected %u..%u)", m->type, lo, hi);
    }
    if (!v3_is_finite(m->color) || m->color.x < 0.0f || m->color.y < 0.0f || m->color.z < 0.0f) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "material colour (%g, %g, %g) must be finite and non-negative",
                            (double)m->color.x, (double)m->color.y, (double)m->color.z);
    }
    if (!isfinite(m->emittance) || m->emittance < 0.0f) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "material emittance %g must be finite and non-negative",
                            (double)m->emittance);
    }
    if (!(m->roughness >= 0.0f && m->roughness <= 1.0f)) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "material roughness %g must be in [0, 1]", (double)m->roughness);
    }
    if (!(m->ior >= 1.0f && m->ior <= 10.0f)) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT, "material ior %g must be in [1, 10]",
                            (double)m->ior);
    }
    if ((m->flags & ~(TR_MATERIAL_TWO_SIDED | TR_MATERIAL_MULTISCATTER)) != 0u) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "material flags 0x%x have unknown bits", m->flags);
    }
    return TR_OK;
}
