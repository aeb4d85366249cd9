/* accel.h - the acceleration structures rays are traced through.
 *
 * tr_scene_commit (scene.h) builds one over a scene's triangles: the thesis's flat list
 * of shape boxes, a binned-SAH BVH (traced on the CPU as a wide SIMD BVH), or, in
 * builds configured with it, an Intel Embree 3 scene, the speed reference the BVH is
 * measured against. The structures themselves are private to the library
 * (src/accel/accel_internal.h); tr_scene_accel_info describes the committed one. */
#ifndef TRAC0R_ACCEL_H
#define TRAC0R_ACCEL_H

#include <stdint.h>

/* The one list of acceleration structures: X(NAME, value, "name", "description")
 * generates tr_accel_type's TR_ACCEL_TYPE_NAME and, in src/util/registry.c, the names
 * tr_accel_from_name / tr_accel_name know and the descriptions --help prints. Rows are in
 * the order messages list them, the default first. BVH2 is the binary BVH alone, without
 * the wide BVH the CPU traverses for TR_ACCEL_TYPE_BVH: its scene view is a TR_ACCEL_BVH
 * view. Embree runs on the CPU only (see tr_accel_available). */
/* clang-format off */
#define TR_ACCEL_TYPES(X)                                                                    \
    X(BVH,    1,               "bvh",    "binned-SAH BVH (a SIMD wide BVH on the CPU)")                      \
    X(FLAT,   0,               "flat",   "the thesis's list of per-shape boxes")             \
    X(EMBREE, 2,               "embree", "Intel Embree 3, in builds that found it")          \
    X(BVH2,   3,               "bvh2",   "the binary BVH alone, for comparisons")
/* clang-format on */

#define TR_ACCEL_ENUM_ROW(id, value, name, description) TR_ACCEL_TYPE_##id = value,
typedef enum tr_accel_type { TR_ACCEL_TYPES(TR_ACCEL_ENUM_ROW) } tr_accel_type;
#undef TR_ACCEL_ENUM_ROW

/* What tr_scene_commit built (tr_scene_accel_info): counts are 0 for the parts the
 * committed structure does not have. */
typedef struct tr_accel_info {
    tr_accel_type type; /* the committed structure (flat before any commit) */
    uint32_t bvh_nodes; /* binary BVH (bvh, bvh2) */
    uint32_t bvh_leaves;
    uint32_t bvh_depth;  /* deepest leaf, root = 0 */
    uint32_t wide_width; /* wide BVH (bvh only): children per node */
    uint32_t wide_nodes;
    uint32_t wide_leaves;
    uint32_t wide_depth;
    double bvh_seconds;    /* the binary build */
    double wide_seconds;   /* the collapse into the wide BVH */
    double embree_seconds; /* the Embree scene's build */
    const char *wide_isa;  /* the wide traversal's instruction set: "avx2", "sse2", ... */
} tr_accel_info;

/* Names <-> tr_accel_type, from TR_ACCEL_TYPES (src/util/registry.c; trac0r/registry.h
 * has the name lists and descriptions): tr_accel_from_name returns -1 for an unknown name
 * and knows "embree" even where it is not available; tr_accel_name returns "unknown" for
 * a value not in the list. */
int tr_accel_from_name(const char *name);
const char *tr_accel_name(tr_accel_type type);
/* 1 when tr_scene_commit can build this structure: flat, bvh and bvh2 always, embree only
 * in builds configured with Embree 3 (TRAC0R_HAVE_EMBREE). */
int tr_accel_available(tr_accel_type type);

#endif
