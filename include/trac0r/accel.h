/* accel.h - acceleration structures built over a scene's triangles.
 *
 * A BVH is built once per scene change (tr_scene_commit) into flat arrays with no
 * pointers: the node array (tr_bvh_node, 32 bytes each) and a triangle index array,
 * which upload to a device unchanged. */
#ifndef TRAC0R_ACCEL_H
#define TRAC0R_ACCEL_H

#include <stdint.h>

#include "kernel/types.h"
#include "trac0r/error.h"

typedef enum tr_accel_type {
    TR_ACCEL_TYPE_FLAT = TR_ACCEL_FLAT, /* the thesis's flat list of shape boxes */
    TR_ACCEL_TYPE_BVH = TR_ACCEL_BVH,   /* binned-SAH binary BVH */
} tr_accel_type;

typedef struct tr_bvh {
    tr_bvh_node *nodes;
    uint32_t node_count;
    uint32_t *indices; /* triangle indices, leaf by leaf */
    uint32_t index_count;
    uint32_t leaf_count;
    uint32_t depth;   /* deepest leaf, root = 0 */
    uint32_t skipped; /* degenerate triangles (zero area, NaN/Inf) left out */
    double build_seconds;
} tr_bvh;

/* Builds a BVH over n triangles with the binned surface-area heuristic (Wald, "On fast
 * Construction of SAH-based Bounding Volume Hierarchies", IEEE RT 2007). Triangles that
 * can never be hit (zero area, non-finite vertices) are left out. */
int tr_bvh_build(tr_bvh *bvh, const tr_triangle *tris, uint32_t n, tr_error *err);
/* Recomputes every node's box from the triangles' current positions, keeping the tree:
 * for scenes whose triangles moved but did not change in number. */
void tr_bvh_refit(tr_bvh *bvh, const tr_triangle *tris);
void tr_bvh_free(tr_bvh *bvh);

/* "flat" / "bvh" <-> tr_accel_type; returns -1 for an unknown name. */
int tr_accel_from_name(const char *name);
const char *tr_accel_name(tr_accel_type type);

#endif
