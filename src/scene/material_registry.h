/* material_registry.h - what each material type of TR_MATERIAL_TYPES
 * (trac0r/material_types.h) takes: its scene-file keys with their ranges, its neutral
 * values, and the check every material passes before it enters a scene. Internal to
 * libtrac0r: json.c and scene.c use it instead of switches of their own. */
#ifndef TR_SCENE_MATERIAL_REGISTRY_H
#define TR_SCENE_MATERIAL_REGISTRY_H

#include <stddef.h>
#include <stdint.h>

#include "kernel/types.h"
#include "trac0r/error.h"

enum { TR_KEY_COLOR, TR_KEY_NUMBER, TR_KEY_FLAG };

/* One scene-file key of a material. */
typedef struct tr_material_key_info {
    uint32_t key;     /* TR_MATERIAL_KEY_* */
    const char *name; /* the key in the file */
    int kind;         /* TR_KEY_COLOR (an RGB triple), TR_KEY_NUMBER or TR_KEY_FLAG (bool) */
    double lo, hi;    /* range of the number, or of each colour component */
    int positive;     /* the number must also be > lo */
    size_t offset;    /* COLOR, NUMBER: offset of the tr_material field (tr_vec3, float) */
    uint32_t flag;    /* FLAG: the tr_material.flags bit that true sets */
} tr_material_key_info;

/* Every key, in the order files are checked and messages list them. */
const tr_material_key_info *tr_material_keys(size_t *count);
/* The TR_MATERIAL_KEY_* masks a type requires and accepts besides; 0 for an unknown type. */
int tr_material_type_keys(uint32_t type, uint32_t *required, uint32_t *optional);
/* A material of the given type with every parameter at its neutral value: black, ior 1,
 * roughness 0, no emission, no flags. */
tr_material tr_material_default(uint32_t type);
/* Whether m may enter a scene: a known type, finite non-negative colour and emittance,
 * roughness in [0, 1], ior in [1, 10], no unknown flag bits. */
int tr_material_check(const tr_material *m, tr_error *err);

#endif
