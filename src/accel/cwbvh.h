/* cwbvh.h - the compressed 8-wide BVH (src/kernel/cwbvh.h) converted from the binary BVH,
 * for OpenCL devices. */
#ifndef TR_ACCEL_CWBVH_H
#define TR_ACCEL_CWBVH_H

#include "accel/accel_internal.h"
#include "kernel/cwbvh.h"

typedef struct tr_cwbvh {
    tr_cwbvh_node *nodes;
    uint32_t node_count;
    tr_bvh_tri *tris; /* the binary BVH's leaf triangles, in the wide leaves' order */
    uint32_t tri_count;
    uint32_t depth; /* wide levels below the root */
} tr_cwbvh;

/* Collapses the binary BVH (nodes, leaf triangles `tris`) into 8-wide nodes, each wide
 * node's children taken by repeatedly opening the internal child of largest surface area,
 * and quantizes the children's boxes conservatively. TR_STATUS_LIMIT where the tree is too
 * deep for the traversal's stack (TR_CWBVH_STACK_SIZE). */
int tr_cwbvh_build(tr_cwbvh *cw, const tr_bvh_node *nodes, uint32_t node_count,
                   const tr_bvh_tri *tris, tr_error *err);
void tr_cwbvh_free(tr_cwbvh *cw);

#endif
