/* wbvh.c - the wide BVH: collapsed from the binary BVH (host only), and the run-time
 * choice of the instruction set its traversal runs with (src/accel/wbvh_*.c). */
#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "accel/wbvh.h"
#include "kernel/scene_view.h"
#include "accel/accel_internal.h"
#include "trac0r/accel.h"
#include "trac0r/render.h"
#include "util/bigmem.h"

_Static_assert(TR_BVH_STACK_SIZE < 1 << 8, "recursion depth of the collapse");

typedef struct collapser {
    const tr_bvh *bvh;
    uint32_t *sub_first; /* per binary node: its subtree's run of leaf triangles */
    uint32_t *sub_count;
    tr_wbvh *w;
    uint32_t node_cap, packet_cap, leaf_cap;
    int failed;
} collapser;

static float box_area(tr_aabb b) {
    tr_vec3 d = v3_sub(b.max, b.min);
    return d.x * d.y + d.y * d.z + d.z * d.x;
}

/* Whether binary node i becomes a leaf of the wide tree: a binary leaf, or a subtree
 * small enough for one packet. */
static int is_wide_leaf(const collapser *c, uint32_t i) {
    return c->bvh->nodes[i].count > 0 || c->sub_count[i] <= TR_WBVH_LEAF_MERGE;
}

/* Node i's subtree's run of leaf triangles from its children's runs (sub_runs). */
static void sub_join(collapser *c, uint32_t i) {
    const tr_bvh_node *n = &c->bvh->nodes[i];
    if (n->count > 0) {
        c->sub_first[i] = n->left_first;
        c->sub_count[i] = n->count;
        return;
    }
    const uint32_t l = n->left_first, r = l + 1;
    c->sub_first[i] = c->sub_first[l] < c->sub_first[r] ? c->sub_first[l] : c->sub_first[r];
    c->sub_count[i] = c->sub_count[l] + c->sub_count[r];
    /* A subtree whose run were not contiguous could not be merged into one leaf; mark it
     * too big to merge. */
    if (c->sub_first[l] + c->sub_count[l] != c->sub_first[r] &&
        c->sub_first[r] + c->sub_count[r] != c->sub_first[l]) {
        c->sub_count[i] = UINT32_MAX / 2;
    }
}

/* The runs of node i's subtree, children before parents. */
static void sub_walk(collapser *c, uint32_t i) {
    const tr_bvh_node *n = &c->bvh->nodes[i];
    if (n->count == 0) {
        sub_walk(c, n->left_first);
        sub_walk(c, n->left_first + 1);
    }
    sub_join(c, i);
}

enum {
    SUB_PARALLEL_MIN = 1u << 17, /* binary nodes: fewer take one thread */
    SUB_CUT_DEPTH = 4,           /* a big tree's subtrees below this depth, shared out */
};

/* Lists the nodes at depth SUB_CUT_DEPTH below node i, and the leaves above it. */
static void sub_cut(const collapser *c, uint32_t i, uint32_t depth, uint32_t *cut, uint32_t *cuts) {
    const tr_bvh_node *n = &c->bvh->nodes[i];
    if (depth == SUB_CUT_DEPTH || n->count > 0) {
        cut[(*cuts)++] = i;
        return;
    }
    sub_cut(c, n->left_first, depth + 1, cut, cuts);
    sub_cut(c, n->left_first + 1, depth + 1, cut, cuts);
}

/* Joins the nodes above the cut (sub_cut), whose subtrees are done, bottom up. */
static void sub_top(collapser *c, uint32_t i, uint32_t depth) {
    const tr_bvh_node *n = &c->bvh->nodes[i];
    if (depth == SUB_CUT_DEPTH || n->count > 0) {
        return;
    }
    sub_top(c, n->left_first, depth + 1);
    sub_top(c, n->left_first + 1, depth + 1);
    sub_join(c, i);
}

/* Every binary node's run of leaf triangles (sub_first, sub_count), which is contiguous
 * (the builder partitions its parent's run). A big tree's subtrees below SUB_CUT_DEPTH are
 * walked by all threads; the nodes above them after, on one. The runs do not depend on
 * who computes them. */
static void sub_runs(collapser *c) {
    const tr_bvh *bvh = c->bvh;
    if (bvh->node_count < SUB_PARALLEL_MIN) {
        /* Children come after their parents: one backward pass. */
        for (uint32_t i = bvh->node_count; i-- > 0;) {
            sub_join(c, i);
        }
        return;
    }
    uint32_t cut[1u << SUB_CUT_DEPTH], cuts = 0;
    sub_cut(c, 0, 0, cut, &cuts);
#pragma omp parallel for num_threads(tr_default_threads()) schedule(dynamic, 1)
    for (int k = 0; k < (int)cuts; ++k) {
        sub_walk(c, cut[k]);
    }
    sub_top(c, 0, 0);
}

static uint32_t emit_leaf(collapser *c, uint32_t first, uint32_t count) {
    tr_wbvh *w = c->w;
    uint32_t packets = (count + 3) / 4;
    /* The arrays are sized for the worst case (see tr_wbvh_build); the checks only guard
     * that bound. */
    if (packets > TR_WBVH_LEAF_MAX_PACKETS || w->packet_count + packets > c->packet_cap ||
        w->leaf_count == c->leaf_cap || c->packet_cap > (1u << TR_WBVH_LEAF_SHIFT)) {
        c->failed = 1;
        return TR_WBVH_EMPTY;
    }
    tr_wbvh_leaf *l = &w->leaves[w->leaf_count++];
    l->packet = w->packet_count;
    l->first = first;
    l->count = count;
    w->packet_count += packets;
    return TR_WBVH_LEAF_BIT | packets << TR_WBVH_LEAF_SHIFT | l->packet;
}

/* Writes a leaf's triangles into its packets, lane by lane. */
static void fill_leaf(const tr_bvh *bvh, tr_wbvh_tri4 *packets, const tr_wbvh_leaf *l) {
    for (uint32_t p = 0; 4 * p < l->count; ++p) {
        tr_wbvh_tri4 *q = &packets[l->packet + p];
        memset(q, 0, sizeof *q);
        for (uint32_t k = 0; k < 4 && 4 * p + k < l->count; ++k) {
            const tr_bvh_tri *t = &bvh->tris[l->first + 4 * p + k];
            q->v0[0][k] = t->v0.x;
            q->v0[1][k] = t->v0.y;
            q->v0[2][k] = t->v0.z;
            q->e1[0][k] = t->e1.x;
            q->e1[1][k] = t->e1.y;
            q->e1[2][k] = t->e1.z;
            q->e2[0][k] = t->e2.x;
            q->e2[1][k] = t->e2.y;
            q->e2[2][k] = t->e2.z;
            q->index[k] = t->index;
        }
    }
}

/* Emits the wide node for the binary nodes slots[0, count) (the children it starts
 * from) and everything below it; returns its index. */
static uint32_t emit_node(collapser *c, uint32_t *slots, int count, uint32_t depth) {
    const tr_bvh_node *bn = c->bvh->nodes;
    /* Open the largest interior slot until the node is full (areas and kinds computed
     * once per slot). */
    float area[TR_WBVH_WIDTH];
    int leaf[TR_WBVH_WIDTH];
    for (int i = 0; i < count; ++i) {
        area[i] = box_area(bn[slots[i]].box);
        leaf[i] = is_wide_leaf(c, slots[i]);
    }
    while (count < TR_WBVH_WIDTH) {
        int best = -1;
        float best_area = -1.0f;
        for (int i = 0; i < count; ++i) {
            if (!leaf[i] && area[i] > best_area) {
                best = i;
                best_area = area[i];
            }
        }
        if (best < 0) {
            break;
        }
        uint32_t l = bn[slots[best]].left_first;
        slots[best] = l;
        slots[count] = l + 1;
        area[best] = box_area(bn[l].box);
        leaf[best] = is_wide_leaf(c, l);
        area[count] = box_area(bn[l + 1].box);
        leaf[count] = is_wide_leaf(c, l + 1);
        ++count;
    }
    /* The slots' children are read when the recursion opens them: ask for them now (the
     * binary nodes of a big tree are far apart; their loads were most of the time here). */
    for (int i = 0; i < count; ++i) {
        if (!leaf[i]) {
            const uint32_t l = bn[slots[i]].left_first;
            __builtin_prefetch(&bn[l]);
            __builtin_prefetch(&bn[l + 1]);
            __builtin_prefetch(&c->sub_count[l]);
        }
    }
    tr_wbvh *w = c->w;
    if (w->node_count == c->node_cap) {
        c->failed = 1;
        return 0;
    }
    uint32_t index = w->node_count++;
    w->depth = depth > w->depth ? depth : w->depth;
    tr_wbvh_node node;
    for (int i = 0; i < TR_WBVH_WIDTH; ++i) {
        for (int a = 0; a < 3; ++a) {
            node.bounds[2 * a][i] = INFINITY;
            node.bounds[2 * a + 1][i] = -INFINITY;
        }
        node.child[i] = TR_WBVH_EMPTY;
    }
    for (int i = 0; i < count && !c->failed; ++i) {
        uint32_t s = slots[i];
        const tr_aabb b = bn[s].box;
        node.bounds[0][i] = b.min.x;
        node.bounds[1][i] = b.max.x;
        node.bounds[2][i] = b.min.y;
        node.bounds[3][i] = b.max.y;
        node.bounds[4][i] = b.min.z;
        node.bounds[5][i] = b.max.z;
        if (leaf[i]) {
            node.child[i] = emit_leaf(c, c->sub_first[s], c->sub_count[s]);
        } else {
            uint32_t kids[TR_WBVH_WIDTH] = {bn[s].left_first, bn[s].left_first + 1};
            node.child[i] = emit_node(c, kids, 2, depth + 1);
        }
    }
    if (!c->failed) {
        w->nodes[index] = node; /* after the recursion: it may have moved the array */
        for (int i = 0; i < TR_WBVH_WIDTH; ++i) {
            w->slot_src[(size_t)TR_WBVH_WIDTH * index + i] = i < count ? slots[i] : UINT32_MAX;
        }
    }
    return index;
}

/* aligned_alloc wants a multiple of the alignment. */
static size_t round64(size_t bytes) {
    return (bytes + 63) & ~(size_t)63;
}

void tr_wbvh_free(tr_wbvh *w) {
    tr_bigmem_free(w->nodes);
    tr_bigmem_free(w->packets);
    tr_bigmem_free(w->slot_src);
    tr_bigmem_free(w->leaves);
    memset(w, 0, sizeof *w);
}

int tr_wbvh_build(tr_wbvh *w, const tr_bvh *bvh, tr_error *err) {
    double t0 = tr_time_now();
    memset(w, 0, sizeof *w);
    w->bvh_refits = bvh->refits;
    if (bvh->node_count == 0) {
        w->build_seconds = tr_time_now() - t0;
        return TR_OK;
    }
    collapser c;
    memset(&c, 0, sizeof c);
    c.bvh = bvh;
    c.w = w;
    c.sub_first = tr_bigmem_malloc((size_t)bvh->node_count * sizeof *c.sub_first);
    c.sub_count = tr_bigmem_malloc((size_t)bvh->node_count * sizeof *c.sub_count);
    /* Worst cases, allocated once (pages never written are never backed by memory): every
     * wide node opens at least one binary interior node (the root may be a lone leaf),
     * and every wide leaf is a binary leaf of at most 8 triangles (two packets) or a
     * merged subtree of two or more binary leaves (one packet). */
    c.node_cap = bvh->leaf_count;
    c.leaf_cap = bvh->leaf_count;
    c.packet_cap = 2 * bvh->leaf_count;
    w->nodes = tr_bigmem_aligned(64, round64((size_t)c.node_cap * sizeof *w->nodes));
    w->packets = tr_bigmem_aligned(64, round64((size_t)c.packet_cap * sizeof *w->packets));
    w->leaves = tr_bigmem_malloc((size_t)c.leaf_cap * sizeof *w->leaves);
    w->slot_src = tr_bigmem_malloc((size_t)c.node_cap * TR_WBVH_WIDTH * sizeof *w->slot_src);
    if (!c.sub_first || !c.sub_count || !w->nodes || !w->packets || !w->leaves || !w->slot_src) {
        c.failed = 1;
    }
    if (!c.failed) {
        sub_runs(&c);
    }
    if (!c.failed) {
        uint32_t slots[TR_WBVH_WIDTH] = {0};
        if (bvh->nodes[0].count > 0 || c.sub_count[0] <= TR_WBVH_LEAF_MERGE) {
            emit_node(&c, slots, 1, 0); /* the root is one leaf: a node holding it */
        } else {
            slots[0] = bvh->nodes[0].left_first;
            slots[1] = slots[0] + 1;
            emit_node(&c, slots, 2, 0);
        }
    }
    if (!c.failed) {
        const int leaves = (int)w->leaf_count;
#pragma omp parallel for num_threads(tr_default_threads())                                         \
    schedule(static, 4096) if (leaves > 65536)
        for (int i = 0; i < leaves; ++i) {
            fill_leaf(bvh, w->packets, &w->leaves[i]);
        }
    }
    tr_bigmem_free(c.sub_first);
    tr_bigmem_free(c.sub_count);
    if (c.failed) {
        tr_wbvh_free(w);
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY,
                            "out of memory collapsing a BVH of %u nodes into a wide BVH",
                            bvh->node_count);
    }
    w->build_seconds = tr_time_now() - t0;
    return TR_OK;
}

void tr_wbvh_refit(tr_wbvh *w, const tr_bvh *bvh) {
    const int nodes = (int)w->node_count, leaves = (int)w->leaf_count;
#pragma omp parallel num_threads(tr_default_threads())
    {
#pragma omp for schedule(static, 1024) nowait
        for (int n = 0; n < nodes; ++n) {
            tr_wbvh_node *node = &w->nodes[n];
            for (int i = 0; i < TR_WBVH_WIDTH; ++i) {
                const uint32_t s = w->slot_src[(size_t)TR_WBVH_WIDTH * n + i];
                if (s == UINT32_MAX) {
                    continue;
                }
                const tr_aabb b = bvh->nodes[s].box;
                node->bounds[0][i] = b.min.x;
                node->bounds[1][i] = b.max.x;
                node->bounds[2][i] = b.min.y;
                node->bounds[3][i] = b.max.y;
                node->bounds[4][i] = b.min.z;
                node->bounds[5][i] = b.max.z;
            }
        }
#pragma omp for schedule(static, 4096)
        for (int i = 0; i < leaves; ++i) {
            fill_leaf(bvh, w->packets, &w->leaves[i]);
        }
    }
    w->bvh_refits = bvh->refits;
}

/* ---- Run-time ISA choice ---------------------------------------------------------- */

typedef struct isa_entry {
    int (*intersect)(const tr_wbvh *w, const tr_ray *ray, tr_hit *hit);
    int (*occluded)(const tr_wbvh *w, const tr_ray *ray);
} isa_entry;

/* Entries this build lacks stay NULL (tr_wbvh_isa_mask never offers them). */
static const isa_entry isa_table[TR_WBVH_ISA_COUNT] = {
    [TR_WBVH_ISA_SCALAR] = {tr_wbvh_intersect_scalar, tr_wbvh_occluded_scalar},
#if defined(TR_WBVH_HAVE_X86) || defined(TR_WBVH_HAVE_SSE_ONLY)
    [TR_WBVH_ISA_SSE2] = {tr_wbvh_intersect_sse2, tr_wbvh_occluded_sse2},
#endif
#ifdef TR_WBVH_HAVE_X86
    [TR_WBVH_ISA_AVX2] = {tr_wbvh_intersect_avx2, tr_wbvh_occluded_avx2},
    [TR_WBVH_ISA_AVX512] = {tr_wbvh_intersect_avx512, tr_wbvh_occluded_avx512},
#endif
};

static const char *const isa_names[TR_WBVH_ISA_COUNT] = {
    [TR_WBVH_ISA_SCALAR] = "scalar",
    [TR_WBVH_ISA_SSE2] = "sse2",
    [TR_WBVH_ISA_AVX2] = "avx2",
    [TR_WBVH_ISA_AVX512] = "avx512",
};

/* The ISA every ray takes, -1 until the first ray (or tr_wbvh_isa) chooses it. Choosing
 * twice gives the same answer, so a race between first rays only repeats the work; the
 * compare-exchange keeps whichever choice, or tr_wbvh_set_isa, came first. */
static atomic_int isa_current = -1;

const char *tr_wbvh_isa_name(int isa) {
    return isa >= 0 && isa < TR_WBVH_ISA_COUNT ? isa_names[isa] : NULL;
}

int tr_wbvh_isa_from_name(const char *name) {
    for (int i = 0; name && i < TR_WBVH_ISA_COUNT; ++i) {
        if (strcmp(name, isa_names[i]) == 0) {
            return i;
        }
    }
    return -1;
}

unsigned tr_wbvh_isa_mask(void) {
    unsigned mask = 1u << TR_WBVH_ISA_SCALAR;
#ifdef TR_WBVH_HAVE_SSE_ONLY
    /* A target whose 128-bit vectors are always there: WebAssembly with SIMD, where
     * Emscripten maps the SSE2 intrinsics onto them (the web build, web/CMakeLists.txt). */
    mask |= 1u << TR_WBVH_ISA_SSE2;
#endif
#ifdef TR_WBVH_HAVE_X86
    /* __builtin_cpu_supports reads the CPUID bits libgcc (or compiler-rt) gathered at
     * start-up; for the AVX features it also checks that the OS saves the wide
     * registers (XGETBV). */
    if (__builtin_cpu_supports("sse2")) {
        mask |= 1u << TR_WBVH_ISA_SSE2;
    }
    if (__builtin_cpu_supports("avx2")) {
        mask |= 1u << TR_WBVH_ISA_AVX2;
        if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl")) {
            mask |= 1u << TR_WBVH_ISA_AVX512;
        }
    }
#endif
    return mask;
}

int tr_wbvh_isa_choose(const char *request, unsigned mask) {
    int want = tr_wbvh_isa_from_name(request);
    if (want >= 0 && (mask >> want & 1u)) {
        return want;
    }
    for (int i = TR_WBVH_ISA_COUNT - 1; i > 0; --i) {
        if (mask >> i & 1u) {
            return i;
        }
    }
    return TR_WBVH_ISA_SCALAR;
}

static int isa_choose_once(void) {
    int isa = tr_wbvh_isa_choose(getenv("TRAC0R_ISA"), tr_wbvh_isa_mask());
    int expected = -1;
    if (!atomic_compare_exchange_strong(&isa_current, &expected, isa)) {
        isa = expected;
    }
    return isa;
}

static inline int isa_now(void) {
    int isa = atomic_load_explicit(&isa_current, memory_order_relaxed);
    return isa >= 0 ? isa : isa_choose_once();
}

const char *tr_wbvh_isa(void) {
    return isa_names[isa_now()];
}

int tr_wbvh_set_isa(int isa, tr_error *err) {
    if (isa < 0 || isa >= TR_WBVH_ISA_COUNT) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT, "unknown wide-BVH ISA %d", isa);
    }
    if (!(tr_wbvh_isa_mask() >> isa & 1u)) {
        return tr_error_set(err, TR_STATUS_UNSUPPORTED,
                            "wide-BVH ISA %s: not supported by this CPU or build", isa_names[isa]);
    }
    atomic_store(&isa_current, isa);
    return TR_OK;
}

int tr_wbvh_trace_isa(int isa, const tr_wbvh *w, const tr_ray *ray, tr_hit *hit, int any_hit) {
    if (isa < 0 || isa >= TR_WBVH_ISA_COUNT || !(tr_wbvh_isa_mask() >> isa & 1u)) {
        return -1;
    }
    return any_hit ? isa_table[isa].occluded(w, ray) : isa_table[isa].intersect(w, ray, hit);
}

int tr_wbvh_intersect(const struct tr_wbvh *w, const tr_ray *ray, tr_hit *hit) {
    return isa_table[isa_now()].intersect(w, ray, hit);
}

int tr_wbvh_occluded(const struct tr_wbvh *w, const tr_ray *ray) {
    return isa_table[isa_now()].occluded(w, ray);
}
