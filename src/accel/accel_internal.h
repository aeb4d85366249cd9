/* accel_internal.h - the acceleration structures as the library builds and traces them.
 *
 * A BVH is built once per scene change (tr_scene_commit) into flat arrays with no
 * pointers: the node array (tr_bvh_node, 32 bytes each) and a triangle index array,
 * which upload to a device unchanged. Builds configured with Embree 3 also offer an
 * Embree scene (host only). Private: the public API names the structures by
 * tr_accel_type (include/trac0r/accel.h) and describes them with tr_accel_info. */
#ifndef TR_ACCEL_INTERNAL_H
#define TR_ACCEL_INTERNAL_H

#include <stdint.h>

#include "kernel/types.h"
#include "trac0r/accel.h"
#include "trac0r/error.h"

/* tr_accel_type names the kernel's view types where they coincide. */
_Static_assert(TR_ACCEL_TYPE_FLAT == TR_ACCEL_FLAT && TR_ACCEL_TYPE_BVH == TR_ACCEL_BVH &&
                   TR_ACCEL_TYPE_EMBREE == TR_ACCEL_EMBREE,
               "tr_accel_type and the kernel's TR_ACCEL_* differ");

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

/* The wide BVH (src/accel/wbvh.c), host only: the binary BVH collapsed into nodes of
 * TR_WBVH_WIDTH children whose boxes are stored axis by axis (structure of arrays), so
 * that one ray meets all of a node's boxes in a few SIMD instructions, and leaves whose
 * triangles come in packets of four, also stored lane by lane, tested four at a time.
 * The width follows the compiler's target: 8 with AVX2 (one 256-bit register per
 * plane), 4 otherwise (SSE2, or the portable scalar code on other CPUs). The binary BVH
 * stays as it is: devices trace that one. */
#if defined(__AVX2__)
#define TR_WBVH_WIDTH 8
#else
#define TR_WBVH_WIDTH 4
#endif
#define TR_WBVH_LEAF_BIT 0x80000000u /* child entry: leaf, with packet count and start */
#define TR_WBVH_LEAF_SHIFT 27        /* packet count in bits 27..30 */
#define TR_WBVH_LEAF_MAX_PACKETS 15u
#define TR_WBVH_EMPTY TR_WBVH_LEAF_BIT /* an unused child slot: a leaf of no packets */

/* One node: the boxes of its children as bounds[2 * axis + side][child] (side 0 the
 * minimum, 1 the maximum); unused slots have the empty box (+inf, -inf), which no ray
 * meets. child[i] is a node index, or TR_WBVH_LEAF_BIT | packets << 27 | first packet. */
typedef struct tr_wbvh_node {
    _Alignas(32) float bounds[6][TR_WBVH_WIDTH];
    uint32_t child[TR_WBVH_WIDTH];
} tr_wbvh_node;

/* Four leaf triangles, lane by lane: v0 and the edges e1 = v1 - v0, e2 = v2 - v0 as in
 * tr_bvh_tri, and the scene triangle index. Unused lanes are all zero (a degenerate
 * triangle, which never hits). 160 bytes. */
typedef struct tr_wbvh_tri4 {
    _Alignas(16) float v0[3][4];
    float e1[3][4];
    float e2[3][4];
    uint32_t index[4];
} tr_wbvh_tri4;

/* A leaf of the wide tree: its first packet, and the run of leaf-ordered binary BVH
 * triangles (tr_bvh.tris) it holds. */
typedef struct tr_wbvh_leaf {
    uint32_t packet, first, count;
} tr_wbvh_leaf;

typedef struct tr_wbvh {
    tr_wbvh_node *nodes; /* node 0 is the root; 0 nodes for an empty scene */
    uint32_t node_count;
    tr_wbvh_tri4 *packets;
    uint32_t packet_count;
    uint32_t leaf_count;
    /* For tr_wbvh_refit: the binary node each child slot was collapsed from (node i's
     * slots at [TR_WBVH_WIDTH * i, ...), UINT32_MAX for an empty slot), and the leaves. */
    uint32_t *slot_src;
    tr_wbvh_leaf *leaves;
    uint32_t depth;       /* deepest node, root = 0 */
    uint32_t bvh_refits;  /* tr_bvh.refits of the tree it was collapsed from */
    double build_seconds; /* the collapse alone (the binary build comes before) */
} tr_wbvh;

/* Collapses a built binary BVH into *w, which it overwrites: each wide node takes the
 * children of a binary node and keeps opening the largest-area interior one among them
 * until it has TR_WBVH_WIDTH (as in Wald et al., "Getting Rid of Packets", RT 2008, and
 * Embree); binary subtrees of at most four triangles become one leaf packet. */
int tr_wbvh_build(tr_wbvh *w, const tr_bvh *bvh, tr_error *err);
/* After tr_bvh_refit of the binary BVH it was collapsed from (same tree, moved boxes and
 * triangles): copies the new boxes into the wide nodes and the triangles into the leaf
 * packets, keeping the wide tree's shape. */
void tr_wbvh_refit(tr_wbvh *w, const tr_bvh *bvh);
void tr_wbvh_free(tr_wbvh *w);
/* Which traversal this build uses: "avx512", "avx2", "sse2" or "scalar". */
const char *tr_wbvh_isa(void);

#endif
