/* material_types.h - the one list of material types.
 *
 * Each row is X(NAME, value, "scene-file name", keys required in a scene file, keys
 * optional there) and generates the TR_MATERIAL_NAME enum constant (numbered as in the
 * thesis, listing 2) here, and on the host the name tables (src/util/registry.c), the keys
 * json.c accepts and the validation of src/scene/material_registry.c. Rows are listed in
 * the order messages and documentation name them. A new material type is one row here
 * plus its BSDF (bsdf.h for pt, material.h for naive); parameters that vary over the
 * surface also go through tr_material_eval (material_eval.h). The key bits are TR_MATERIAL_KEY_*
 * below; "type" is always allowed. Valid C99 and OpenCL C: the kernel uses the enum only. */
#ifndef TRAC0R_MATERIAL_TYPES_H
#define TRAC0R_MATERIAL_TYPES_H

/* Scene-file keys of a material (src/scene/material_registry.c names them and holds their
 * ranges). COLOR is a reflectance in [0, 1]; LIGHT_COLOR the same "color" key where it
 * scales emitted radiance and may exceed 1. */
#define TR_MATERIAL_KEY_COLOR 1u
#define TR_MATERIAL_KEY_LIGHT_COLOR 2u
#define TR_MATERIAL_KEY_EMITTANCE 4u
#define TR_MATERIAL_KEY_TWO_SIDED 8u
#define TR_MATERIAL_KEY_IOR 16u
#define TR_MATERIAL_KEY_ROUGHNESS 32u
#define TR_MATERIAL_KEY_MULTISCATTER 64u

/* clang-format off */
#define TR_MATERIAL_TYPES(X)                                                                 \
    X(EMITTER, 1, "emitter", TR_MATERIAL_KEY_LIGHT_COLOR | TR_MATERIAL_KEY_EMITTANCE,        \
      TR_MATERIAL_KEY_TWO_SIDED)                                                             \
    X(DIFFUSE, 2, "diffuse", TR_MATERIAL_KEY_COLOR, 0u)                                      \
    X(GLASS,   3, "glass",   TR_MATERIAL_KEY_COLOR | TR_MATERIAL_KEY_IOR, 0u)                \
    X(GLOSSY,  4, "glossy",  TR_MATERIAL_KEY_COLOR | TR_MATERIAL_KEY_ROUGHNESS,              \
      TR_MATERIAL_KEY_MULTISCATTER)                                                          \
    X(PRINCIPLED, 5, "principled", TR_MATERIAL_KEY_COLOR,                                    \
      TR_MATERIAL_KEY_ROUGHNESS | TR_MATERIAL_KEY_MULTISCATTER | TR_MATERIAL_KEY_IOR)
/* clang-format on */

#define TR_MATERIAL_ENUM_ROW(id, value, name, required, optional) TR_MATERIAL_##id = value,
enum tr_material_type { TR_MATERIAL_TYPES(TR_MATERIAL_ENUM_ROW) };
#undef TR_MATERIAL_ENUM_ROW

#endif
