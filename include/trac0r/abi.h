/* abi.h - the sizes of the public structs as compiled into the library.
 *
 * A client compiled with other flags or another compiler than libtrac0r can check
 * that it agrees with the library on every struct the API passes by value or pointer:
 *
 *     #define CHECK_ONE(name, type) \
 *         if (tr_abi_sizeof(TR_ABI_##name) != sizeof(type)) return 1;
 *     TR_ABI_TYPES(CHECK_ONE)
 *
 * (tests/test_abi.c does exactly this from a file compiled with nothing but -Iinclude.) */
#ifndef TRAC0R_ABI_H
#define TRAC0R_ABI_H

#include <stddef.h>

#include "trac0r/accel.h"
#include "trac0r/camera.h"
#include "trac0r/error.h"
#include "trac0r/film.h"
#include "trac0r/image.h"
#include "trac0r/realtime.h"
#include "trac0r/scene.h"
#include "trac0r/scene_file.h"
#include "trac0r/session.h"
#include "trac0r/types.h"

/* Every public struct: X(NAME, type). A struct added to a public header is added here. */
#define TR_ABI_TYPES(X)                                                                            \
    X(VEC3, tr_vec3)                                                                               \
    X(MATERIAL, tr_material)                                                                       \
    X(TRIANGLE, tr_triangle)                                                                       \
    X(AABB, tr_aabb)                                                                               \
    X(CAMERA, tr_camera)                                                                           \
    X(ERROR, tr_error)                                                                             \
    X(FILM, tr_film)                                                                               \
    X(IMAGE, tr_image)                                                                             \
    X(TRANSFORM, tr_transform)                                                                     \
    X(SHAPE_DESC, tr_shape_desc)                                                                   \
    X(ACCEL_INFO, tr_accel_info)                                                                   \
    X(SCENE_FILE_OPTIONS, tr_scene_file_options)                                                   \
    X(SCENE_FILE, tr_scene_file)                                                                   \
    X(MESH_IMPORT_STATS, tr_mesh_import_stats)                                                     \
    X(REALTIME_DESC, tr_realtime_desc)                                                             \
    X(REALTIME_FRAME_DESC, tr_realtime_frame_desc)                                                 \
    X(REALTIME_RESULT, tr_realtime_result)                                                         \
    X(RENDER_REQUEST, tr_render_request)                                                           \
    X(RENDER_SETTINGS, tr_render_settings)                                                         \
    X(SESSION_DESC, tr_session_desc)                                                               \
    X(SESSION_PROGRESS, tr_session_progress)                                                       \
    X(FLY_CAMERA, tr_fly_camera)                                                                   \
    X(MODEL_OPTIONS, tr_model_options)                                                             \
    X(SCENE_EXTRAS, tr_scene_extras)                                                               \
    X(SCENE_OPEN_DESC, tr_scene_open_desc)

#define TR_ABI_ENUM_ENTRY(name, type) TR_ABI_##name,
typedef enum tr_abi_type { TR_ABI_TYPES(TR_ABI_ENUM_ENTRY) TR_ABI_TYPE_COUNT } tr_abi_type;
#undef TR_ABI_ENUM_ENTRY

/* sizeof the struct as the library was compiled; 0 for a value out of range. */
size_t tr_abi_sizeof(tr_abi_type type);

#endif
