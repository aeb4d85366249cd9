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
/* The same build over n boxes (the top level of a two-level structure): its entries
 * (indices, and tris[].index with zero geometry) are box numbers; empty or non-finite
 * boxes are left out. tr_bvh_refit does not apply to it (src/accel/tlas.c refits it). */
int tr_bvh_build_boxes(tr_bvh *bvh, const tr_aabb *boxes, uint32_t n, tr_error *err);
/* tr_bvh_build for a tree that tr_wbvh_build collapses, leaving out the triangles whose
 * skip[i] is non-zero (skip may be NULL); a node of at most
 * TR_WBVH_LEAF_MERGE triangles becomes a leaf at once instead of being split further. The
 * collapse merges such a subtree into one wide leaf anyway, so the wide BVH is the same
 * (its nodes bit for bit; the order of the triangles inside a leaf of three or four may
 * differ), and the build skips the SAH of 46 % of its nodes (1.3 M triangles). The binary
 * tree itself then has leaves of up to four triangles. */
int tr_bvh_build_wide(tr_bvh *bvh, const tr_triangle *tris, uint32_t n, const uint8_t *skip,
                      tr_error *err);
void tr_bvh_free(tr_bvh *bvh);

/* An Embree 3 scene over a scene's triangles (src/accel/embree.c): one triangle
 * geometry holding every stored triangle in the scene's order, so that Embree's primID is
 * the index into the scene's triangle array, and, for kept instances, one instance
 * geometry each (Embree's own instancing) of a scene per prototype. The handles are
 * opaque so that this header does not need Embree's. Each tr_embree owns its own
 * RTCDevice (creating one costs well under a millisecond next to the build). */
struct tr_embree_state; /* device, scenes and the device's error message */
typedef struct tr_embree {
    struct tr_embree_state *state; /* NULL when nothing is built */
    const void *scene;             /* the RTCScene rays are traced through, or NULL */
    const uint32_t *first;         /* per geometry of `scene` (1 + instance index), the id a
                                      hit on its primitive 0 reports; NULL: no instances */
    uint32_t triangle_count;       /* stored triangles handed to Embree */
    uint32_t instance_count;       /* instances handed to Embree (traced or not) */
    double build_seconds;          /* device creation, vertex copy and rtcCommitScene; the
                                      first build in a process also starts Embree's threads
                                      (a few ms) */
} tr_embree;

/* A prototype's triangles in its own space, and one placement of a prototype: m is its
 * 3x4 row-major matrix (object to world), first the id its primitive 0 reports. An
 * instance whose proto is past the prototypes is not traced (its triangles are stored). */
typedef struct tr_embree_proto {
    const tr_triangle *tris;
    uint32_t count;
} tr_embree_proto;
typedef struct tr_embree_instance {
    const float *m;
    uint32_t proto;
    uint32_t first;
} tr_embree_instance;

/* Builds an Embree scene over n triangles into *e, which it overwrites (free a previous
 * one first). Fails with a message, leaving *e zeroed, when this build of trac0r has no
 * Embree (tr_accel_available(TR_ACCEL_TYPE_EMBREE) == 0) or when Embree reports an
 * error. Degenerate triangles are handed over too (Embree never hits them). The Embree
 * scene holds a copy of the vertices. */
int tr_embree_build(tr_embree *e, const tr_triangle *tris, uint32_t n, tr_error *err);
/* The same with inst_count instances of the prototypes: instance k is the top scene's
 * geometry k + 1, and a prototype's scene is built once, for its first instance. */
int tr_embree_build_instanced(tr_embree *e, const tr_triangle *tris, uint32_t n,
                              const tr_embree_proto *protos, uint32_t proto_count,
                              const tr_embree_instance *inst, uint32_t inst_count, tr_error *err);
/* Moves traced instance k to matrix m, or rewrites the stored triangles' positions (n as
 * built); either takes effect at tr_embree_commit, which rebuilds the top scene only (a
 * prototype's scene stays as it is). */
int tr_embree_set_transform(tr_embree *e, uint32_t k, const float m[12], tr_error *err);
int tr_embree_set_triangles(tr_embree *e, const tr_triangle *tris, uint32_t n, tr_error *err);
int tr_embree_commit(tr_embree *e, tr_error *err);
/* Releases the Embree scenes and device; safe on a zeroed or already freed tr_embree. */
void tr_embree_free(tr_embree *e);

/* The wide BVH the CPU traces (src/accel/wbvh.h, with its run-time ISA choice). */
#include "accel/wbvh.h"

/* The two-level structure's top level (tr_tlas) is declared there too. */

#endif
