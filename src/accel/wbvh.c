/* wbvh.c - the wide BVH: collapsed from the binary BVH, traversed with SIMD (host only). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "accel/wbvh_traverse.h"
#include "kernel/scene_view.h"
#include "trac0r/accel.h"
#include "trac0r/render.h"

enum {
    LEAF_MERGE = 4, /* binary subtrees of at most this many triangles become one packet */
};

_Static_assert(TR_BVH_STACK_SIZE < 1 << 8, "recursion depth of the collapse");

typedef struct collapser {
    const tr_bvh *bvh;
    uint32_t *sub_first; /* per binary node: its subtree's run of leaf triangles */
    uint32_t *sub_count;
    tr_wbvh *w;
    uint32_t node_cap, packet_cap;
    int failed;
} collapser;

static float box_area(tr_aabb b) {
    tr_vec3 d = v3_sub(b.max, b.min);
    return d.x * d.y + d.y * d.z + d.z * d.x;
}

/* Whether binary node i becomes a leaf of the wide tree: a binary leaf, or a subtree
 * small enough for one packet. */
static int is_wide_leaf(const collapser *c, uint32_t i) {
    return c->bvh->nodes[i].count > 0 || c->sub_count[i] <= LEAF_MERGE;
}

static uint32_t emit_leaf(collapser *c, uint32_t first, uint32_t count) {
    uint32_t packets = (count + 3) / 4;
    if (packets > TR_WBVH_LEAF_MAX_PACKETS || c->w->packet_count + packets > (1u << 27)) {
        c->failed = 1; /* the binary builder makes leaves of at most 8 triangles */
        return TR_WBVH_EMPTY;
    }
    tr_wbvh *w = c->w;
    if (w->packet_count + packets > c->packet_cap) {
        uint32_t cap = c->packet_cap ? 2 * c->packet_cap : 64;
        while (cap < w->packet_count + packets) {
            cap *= 2;
        }
        tr_wbvh_tri4 *grown = realloc(w->packets, (size_t)cap * sizeof *grown);
        if (!grown) {
            c->failed = 1;
            return TR_WBVH_EMPTY;
        }
        w->packets = grown;
        c->packet_cap = cap;
    }
    uint32_t start = w->packet_count;
    for (uint32_t p = 0; p < packets; ++p) {
        tr_wbvh_tri4 *q = &w->packets[start + p];
        memset(q, 0, sizeof *q);
        for (uint32_t l = 0; l < 4 && 4 * p + l < count; ++l) {
            const tr_bvh_tri *t = &c->bvh->tris[first + 4 * p + l];
            q->v0[0][l] = t->v0.x;
            q->v0[1][l] = t->v0.y;
            q->v0[2][l] = t->v0.z;
            q->e1[0][l] = t->e1.x;
            q->e1[1][l] = t->e1.y;
            q->e1[2][l] = t->e1.z;
            q->e2[0][l] = t->e2.x;
            q->e2[1][l] = t->e2.y;
            q->e2[2][l] = t->e2.z;
            q->index[l] = t->index;
        }
    }
    w->packet_count += packets;
    w->leaf_count++;
    return TR_WBVH_LEAF_BIT | packets << TR_WBVH_LEAF_SHIFT | start;
}

/* Emits the wide node for the binary nodes slots[0, count) (the children it starts
 * from) and everything below it; returns its index. */
static uint32_t emit_node(collapser *c, uint32_t *slots, int count, uint32_t depth) {
    const tr_bvh_node *bn = c->bvh->nodes;
    /* Open the largest interior slot until the node is full. */
    while (count < TR_WBVH_WIDTH) {
        int best = -1;
        float best_area = -1.0f;
        for (int i = 0; i < count; ++i) {
            float a = box_area(bn[slots[i]].box);
            if (!is_wide_leaf(c, slots[i]) && a > best_area) {
                best = i;
                best_area = a;
            }
        }
        if (best < 0) {
            break;
        }
        uint32_t l = bn[slots[best]].left_first;
        slots[best] = l;
        slots[count++] = l + 1;
    }
    tr_wbvh *w = c->w;
    if (w->node_count == c->node_cap) {
        uint32_t cap = c->node_cap ? 2 * c->node_cap : 64;
        tr_wbvh_node *grown = aligned_alloc(64, (size_t)cap * sizeof *grown);
        if (!grown) {
            c->failed = 1;
            return 0;
        }
        if (w->node_count) {
            memcpy(grown, w->nodes, (size_t)w->node_count * sizeof *grown);
        }
        free(w->nodes);
        w->nodes = grown;
        c->node_cap = cap;
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
        if (is_wide_leaf(c, s)) {
            node.child[i] = emit_leaf(c, c->sub_first[s], c->sub_count[s]);
        } else {
            uint32_t kids[TR_WBVH_WIDTH] = {bn[s].left_first, bn[s].left_first + 1};
            node.child[i] = emit_node(c, kids, 2, depth + 1);
        }
    }
    if (!c->failed) {
        w->nodes[index] = node; /* after the recursion: it may have moved the array */
    }
    return index;
}

void tr_wbvh_free(tr_wbvh *w) {
    free(w->nodes);
    free(w->packets);
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
    c.sub_first = malloc((size_t)bvh->node_count * sizeof *c.sub_first);
    c.sub_count = malloc((size_t)bvh->node_count * sizeof *c.sub_count);
    if (!c.sub_first || !c.sub_count) {
        c.failed = 1;
    }
    /* Children come after their parents: one backward pass gives every subtree's run of
     * triangles, which is contiguous (the builder partitions its parent's run). */
    for (uint32_t i = bvh->node_count; i-- > 0 && !c.failed;) {
        const tr_bvh_node *n = &bvh->nodes[i];
        if (n->count > 0) {
            c.sub_first[i] = n->left_first;
            c.sub_count[i] = n->count;
        } else {
            uint32_t l = n->left_first, r = l + 1;
            c.sub_first[i] = c.sub_first[l] < c.sub_first[r] ? c.sub_first[l] : c.sub_first[r];
            c.sub_count[i] = c.sub_count[l] + c.sub_count[r];
            /* A subtree whose run were not contiguous could not be merged into one leaf;
             * mark it too big to merge. */
            if (c.sub_first[l] + c.sub_count[l] != c.sub_first[r] &&
                c.sub_first[r] + c.sub_count[r] != c.sub_first[l]) {
                c.sub_count[i] = UINT32_MAX / 2;
            }
        }
    }
    if (!c.failed) {
        uint32_t slots[TR_WBVH_WIDTH] = {0};
        if (bvh->nodes[0].count > 0 || c.sub_count[0] <= LEAF_MERGE) {
            emit_node(&c, slots, 1, 0); /* the root is one leaf: a node holding it */
        } else {
            slots[0] = bvh->nodes[0].left_first;
            slots[1] = slots[0] + 1;
            emit_node(&c, slots, 2, 0);
        }
    }
    free(c.sub_first);
    free(c.sub_count);
    if (c.failed) {
        tr_wbvh_free(w);
        return tr_error_set(err, "out of memory collapsing a BVH of %u nodes into a wide BVH",
                            bvh->node_count);
    }
    w->build_seconds = tr_time_now() - t0;
    return TR_OK;
}

const char *tr_wbvh_isa(void) {
#if defined(TR_WBVH_AVX2) && defined(__AVX512VL__)
    return "avx512";
#elif defined(TR_WBVH_AVX2)
    return "avx2";
#elif defined(TR_WBVH_SSE2)
    return "sse2";
#else
    return "scalar";
#endif
}

int tr_wbvh_intersect(const struct tr_wbvh *w, const tr_ray *ray, tr_hit *hit) {
    return tr_wbvh_traverse(w, ray, hit, 0);
}

int tr_wbvh_occluded(const struct tr_wbvh *w, const tr_ray *ray) {
    tr_hit hit;
    return tr_wbvh_traverse(w, ray, &hit, 1);
}
