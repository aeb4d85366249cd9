/* accel.h - acceleration structures built over a scene's triangles.
 *
 * A BVH is built once per scene change (tr_scene_commit) into flat arrays with no
 * pointers: the node array (tr_bvh_node, 32 bytes each) and a triangle index array,
 * which upload to a device unchanged. Builds configured with Embree 3 also offer an
 * Embree scene (host only), the speed reference the BVH is measured against. */
#ifndef TRAC0R_ACCEL_H
#define TRAC0R_ACCEL_H

#include <stdint.h>

#include "kernel/types.h"
#include "trac0r/error.h"

/* The one list of acceleration structures: X(NAME, value, "name", "description")
 * generates tr_accel_type's TR_ACCEL_TYPE_NAME and, in src/util/registry.c, the names
 * tr_accel_from_name / tr_accel_name know and the descriptions --help prints. Rows are in
 * the order messages list them, the default first. BVH2 is the binary BVH alone, without
 * the wide BVH the CPU traverses for TR_ACCEL_TYPE_BVH: its scene view is a TR_ACCEL_BVH
 * view. Embree runs on the CPU only (see tr_accel_available). */
/* clang-format off */
#define TR_ACCEL_TYPES(X)                                                                    \
    X(BVH,    TR_ACCEL_BVH,    "bvh",    "binned-SAH BVH (a SIMD wide BVH on the CPU)")                      \
    X(FLAT,   TR_ACCEL_FLAT,   "flat",   "the thesis's list of per-shape boxes")             \
    X(EMBREE, TR_ACCEL_EMBREE, "embree", "Intel Embree 3, in builds that found it")          \
    X(BVH2,   3,               "bvh2",   "the binary BVH alone, for comparisons")
/* clang-format on */

#define TR_ACCEL_ENUM_ROW(id, value, name, description) TR_ACCEL_TYPE_##id = value,
typedef enum tr_accel_type { TR_ACCEL_TYPES(TR_ACCEL_ENUM_ROW) } tr_accel_type;
#undef TR_ACCEL_ENUM_ROW

typedef struct tr_bvh {
    tr_bvh_node *nodes;
    uint32_t node_count;
    uint32_t *indices; /* triangle indices, leaf by leaf */
    tr_bvh_tri *tris;  /* the same triangles, as the traversal reads them */
    uint32_t index_count;
    uint32_t leaf_count;
    uint32_t depth;   /* deepest leaf, root = 0 */
    uint32_t skipped; /* degenerate triangles (zero area, NaN/Inf) left out */
    double build_seconds;
    uint32_t refits; /* times tr_bvh_refit ran: a wide BVH collapsed before is stale */
} tr_bvh;

/* Builds a BVH over n triangles with the binned surface-area heuristic (Wald, "On fast
 * Construction of SAH-based Bounding Volume Hierarchies", IEEE RT 2007). Triangles that
 * can never be hit (zero area, non-finite vertices) are left out. */
int tr_bvh_build(tr_bvh *bvh, const tr_triangle *tris, uint32_t n, tr_error *err);
/* Recomputes every node's box from the triangles' current positions, keeping the tree:
 * for scenes whose triangles moved but did not change in number. */
void tr_bvh_refit(tr_bvh *bvh, const tr_triangle *tris);
void tr_bvh_free(tr_bvh *bvh);

/* An Embree 3 scene over a scene's triangles (src/accel/embree.c): one triangle
 * geometry holding every triangle in the scene's order, so that Embree's primID is the
 * index into the scene's triangle array. The handles are opaque so that this header
 * does not need Embree's. Each tr_embree owns its own RTCDevice (creating one costs
 * well under a millisecond next to the build). */
struct tr_embree_state; /* device, scene and the device's error message */
typedef struct tr_embree {
    struct tr_embree_state *state; /* NULL when nothing is built */
    const void *scene;             /* the RTCScene rays are traced through, or NULL */
    uint32_t triangle_count;       /* triangles handed to Embree */
    double build_seconds;          /* device creation, vertex copy and rtcCommitScene; the
                                      first build in a process also starts Embree's threads
                                      (a few ms) */
} tr_embree;

/* Builds an Embree scene over n triangles into *e, which it overwrites (free a previous
 * one first). Fails with a message, leaving *e zeroed, when this build of trac0r has no
 * Embree (tr_accel_available(TR_ACCEL_TYPE_EMBREE) == 0) or when Embree reports an
 * error. Degenerate triangles are handed over too (Embree never hits them). The Embree
 * scene holds a copy of the vertices: moving triangles needs a new build. */
int tr_embree_build(tr_embree *e, const tr_triangle *tris, uint32_t n, tr_error *err);
/* Releases the Embree scene and device; safe on a zeroed or already freed tr_embree. */
void tr_embree_free(tr_embree *e);

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
