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

typedef enum tr_accel_type {
    TR_ACCEL_TYPE_FLAT = 0,   /* the thesis's flat list of shape boxes */
    TR_ACCEL_TYPE_BVH = 1,    /* binned-SAH binary BVH, traced as the wide BVH on the CPU */
    TR_ACCEL_TYPE_EMBREE = 2, /* Intel Embree 3 (CPU only; see tr_accel_available) */
    /* The binary BVH alone, without the wide BVH the CPU traverses for TR_ACCEL_TYPE_BVH:
     * for comparisons (--accel bvh2). */
    TR_ACCEL_TYPE_BVH2 = 3,
} tr_accel_type;

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

/* "flat" / "bvh" / "embree" / "bvh2" <-> tr_accel_type; returns -1 for an unknown name.
 * tr_accel_from_name knows "embree" even where it is not available. */
int tr_accel_from_name(const char *name);
const char *tr_accel_name(tr_accel_type type);
/* 1 when tr_scene_commit can build this structure: flat, bvh and bvh2 always, embree only
 * in builds configured with Embree 3 (TRAC0R_HAVE_EMBREE). */
int tr_accel_available(tr_accel_type type);

#endif
