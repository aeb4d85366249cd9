/* wbvh.h - the wide BVH (src/accel/wbvh.c), host only and private to the library.
 *
 * The binary BVH collapsed into nodes of TR_WBVH_WIDTH children whose boxes are stored
 * axis by axis (structure of arrays), so that one ray meets all of a node's boxes in a few
 * SIMD instructions, and leaves whose triangles come in packets of four, also stored lane
 * by lane, tested four at a time. The binary BVH stays as it is: devices trace that one.
 *
 * The layout is the same whatever the compiler flags: the width is fixed at 8 and the
 * traversal is compiled once per instruction set (src/accel/wbvh_{scalar,sse2,avx2,
 * avx512}.c, each with its own flags) and chosen at run time from what the CPU has
 * (tr_wbvh_isa). SSE2 tests a node's eight boxes as two halves of four, AVX2 and AVX-512
 * in one 256-bit operation. */
#ifndef TR_ACCEL_WBVH_H
#define TR_ACCEL_WBVH_H

#include <stdint.h>

#include "accel/accel_internal.h"
#include "kernel/types.h"
#include "trac0r/accel.h"
#include "trac0r/error.h"

#define TR_WBVH_WIDTH 8
#define TR_WBVH_LEAF_BIT 0x80000000u /* child entry: leaf, with packet count and start */
#define TR_WBVH_LEAF_SHIFT 27        /* packet count in bits 27..30 */
#define TR_WBVH_LEAF_MAX_PACKETS 15u
/* Binary subtrees of at most this many triangles become one leaf packet. */
#define TR_WBVH_LEAF_MERGE 4u
#define TR_WBVH_EMPTY TR_WBVH_LEAF_BIT /* an unused child slot: a leaf of no packets */

/* One node: the boxes of its children as bounds[2 * axis + side][child] (side 0 the
 * minimum, 1 the maximum); unused slots have the empty box (+inf, -inf), which no ray
 * meets. child[i] is a node index, or TR_WBVH_LEAF_BIT | packets << 27 | first packet.
 * Each bounds row is one 32-byte aligned 256-bit load (or two 128-bit ones). */
typedef struct tr_wbvh_node {
    _Alignas(32) float bounds[6][TR_WBVH_WIDTH];
    uint32_t child[TR_WBVH_WIDTH];
} tr_wbvh_node;

/* Four leaf triangles, lane by lane: v0 and the edges e1 = v1 - v0, e2 = v2 - v0 as in
 * tr_bvh_tri, and the scene triangle index. Unused lanes are all zero (a degenerate
 * triangle, which never hits). */
typedef struct tr_wbvh_tri4 {
    _Alignas(16) float v0[3][4];
    float e1[3][4];
    float e2[3][4];
    uint32_t index[4];
} tr_wbvh_tri4;

/* Nothing in the layout may depend on the flags a file is compiled with: every ISA's
 * traversal reads the same arrays. */
_Static_assert(sizeof(tr_wbvh_node) == 224, "tr_wbvh_node layout");
_Static_assert(sizeof(tr_wbvh_tri4) == 160, "tr_wbvh_tri4 layout");

/* A leaf of the wide tree: its first packet, and the run of leaf-ordered binary BVH
 * triangles (tr_bvh.tris) it holds. */
typedef struct tr_wbvh_leaf {
    uint32_t packet, first, count;
} tr_wbvh_leaf;

struct tr_wbvh;

/* One instance as the top level of a two-level structure traces it: the ray is carried
 * into the instance's object space by inv (world to object, a 3x4 row-major affine
 * matrix: x' = inv[0] x + inv[1] y + inv[2] z + inv[3], ...) and traced through the
 * bottom level `blas`, whose triangle indices tri_base shifts to the scene's. The
 * direction is not normalised, so a hit's t is the same in both spaces. identity: inv is
 * the identity and the world ray is used unchanged (the scene's own triangles). */
typedef struct tr_wbvh_instance {
    float inv[12];
    const struct tr_wbvh *blas;
    uint32_t tri_base;
    uint32_t identity;
} tr_wbvh_instance;

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
    uint32_t depth;      /* deepest node, root = 0 */
    uint32_t bvh_refits; /* tr_bvh.refits of the tree it was collapsed from */
    /* A top level (src/accel/tlas.c): the leaf packets' index lanes name entries of this
     * array (UINT32_MAX: an unused lane) instead of triangles; NULL for a bottom level or
     * a one-level tree. */
    const tr_wbvh_instance *instances;
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

/* ---- Run-time choice of the traversal's instruction set ------------------------------
 *
 * tr_wbvh_intersect and tr_wbvh_occluded (declared in src/kernel/scene_view.h) go
 * through the traversal chosen on first use: the one named by the environment variable
 * TRAC0R_ISA when this build has it and the CPU supports it, else the best the CPU
 * supports. Every ISA computes exactly what the scalar code computes (same hits, same
 * t, u, v), so the choice changes speed only. The numbers are preprocessor constants
 * because src/accel/wbvh_traverse.h selects its code with them. */
#define TR_WBVH_ISA_SCALAR 0 /* portable C, every CPU */
#define TR_WBVH_ISA_SSE2 1   /* x86: 8 boxes as two 128-bit halves */
#define TR_WBVH_ISA_AVX2 2   /* x86: 8 boxes in 256-bit registers */
#define TR_WBVH_ISA_AVX512 3 /* x86 with AVX-512F and VL: AVX2 plus mask compares */
#define TR_WBVH_ISA_COUNT 4

/* "scalar", "sse2", "avx2", "avx512"; NULL for a number out of range. */
const char *tr_wbvh_isa_name(int isa);
/* The number of an ISA's name, or -1 for an unknown name. */
int tr_wbvh_isa_from_name(const char *name);
/* Bit i set when this build has ISA i's traversal and the CPU can run it (scalar always). */
unsigned tr_wbvh_isa_mask(void);
/* The ISA taken for a TRAC0R_ISA value (NULL when unset) given the usable ISAs `mask`:
 * the requested one when it is in the mask, else (unknown name, or an ISA the CPU or
 * the build lacks) the highest in the mask. */
int tr_wbvh_isa_choose(const char *request, unsigned mask);
/* The ISA the traversal uses (chosen on first call; thread-safe), as its name. */
const char *tr_wbvh_isa(void);
/* Forces the traversal to ISA `isa` for every later ray (for tests and measurements):
 * fails, keeping the current choice, when it is not in tr_wbvh_isa_mask(). */
int tr_wbvh_set_isa(int isa, tr_error *err);
/* Closest hit (any_hit 0, into *hit) or any hit (any_hit 1; hit may be NULL) through ISA
 * `isa`'s traversal whatever the current choice; `isa` must be in tr_wbvh_isa_mask(). */
int tr_wbvh_trace_isa(int isa, const tr_wbvh *w, const tr_ray *ray, tr_hit *hit, int any_hit);

/* The traversal of each ISA, one file each (src/accel/wbvh_traverse.h), for the
 * dispatcher in wbvh.c. The x86 ones exist only in builds that define TR_WBVH_HAVE_X86
 * (CMakeLists.txt compiles their files with -msse2, -mavx2, -mavx512vl). */
int tr_wbvh_intersect_scalar(const tr_wbvh *w, const tr_ray *ray, tr_hit *hit);
int tr_wbvh_occluded_scalar(const tr_wbvh *w, const tr_ray *ray);
int tr_wbvh_intersect_sse2(const tr_wbvh *w, const tr_ray *ray, tr_hit *hit);
int tr_wbvh_occluded_sse2(const tr_wbvh *w, const tr_ray *ray);
int tr_wbvh_intersect_avx2(const tr_wbvh *w, const tr_ray *ray, tr_hit *hit);
int tr_wbvh_occluded_avx2(const tr_wbvh *w, const tr_ray *ray);
int tr_wbvh_intersect_avx512(const tr_wbvh *w, const tr_ray *ray, tr_hit *hit);
int tr_wbvh_occluded_avx512(const tr_wbvh *w, const tr_ray *ray);

/* The top level of a two-level structure (src/accel/tlas.c): a binary SAH BVH over the
 * instances' world boxes, collapsed into a wide BVH whose leaves name instances
 * (tr_wbvh.instances), each traced through its own bottom-level wide BVH. Keeps what
 * moving one instance needs to refit only the path from its leaf to the root. */
typedef struct tr_tlas {
    tr_bvh bvh;             /* entries are instance numbers */
    tr_wbvh wbvh;           /* wbvh.instances == inst */
    tr_wbvh_instance *inst; /* count entries, owned */
    tr_aabb *boxes;         /* each instance's world box */
    uint32_t count;
    uint32_t *parent;    /* per binary node, UINT32_MAX for the root */
    uint32_t *leaf_of;   /* per instance: its binary leaf, UINT32_MAX when left out */
    uint32_t *wide_slot; /* per binary node: TR_WBVH_WIDTH * wide node + slot, or UINT32_MAX */
    uint32_t moves;      /* path refits since the build */
    double build_seconds;
} tr_tlas;

/* Builds the top level over n instances (copied) with world boxes boxes[i]; overwrites *t
 * (free a previous one first). */
int tr_tlas_build(tr_tlas *t, const tr_wbvh_instance *inst, const tr_aabb *boxes, uint32_t n,
                  tr_error *err);
/* Instance i moved: takes its new inverse transform and world box and refits the binary
 * and wide boxes on the path from its leaf to the root (O(depth)). Returns 0 when that
 * cannot be done (the instance was left out of the tree, its box having been empty):
 * build the top level anew then. */
int tr_tlas_move(tr_tlas *t, uint32_t i, const float inv[12], tr_aabb box);
void tr_tlas_free(tr_tlas *t);

#endif
