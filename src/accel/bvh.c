/* bvh.c - binned-SAH binary BVH build and refit. */
#include <stdlib.h>
#include <string.h>

#include "accel/accel_internal.h"
#include "trac0r/accel.h"
#include "trac0r/render.h"

enum {
    BINS = 16,       /* SAH bins per axis (nodes of fewer triangles use one per triangle) */
    MAX_LEAF = 8,    /* a node this small may become a leaf when the SAH says so */
    FORCED_LEAF = 2, /* a node this small always becomes a leaf */
    SAH_DEPTH = 32,  /* below this depth, split at the object median to bound depth */
};
/* Relative cost of visiting an interior node versus testing one triangle. */
#define TRAVERSAL_COST 1.0f

/* Past SAH_DEPTH every split halves its node, so a tree over at most 2^31 triangles is
 * no deeper than SAH_DEPTH + 31 and the kernel's traversal stack cannot overflow. */
_Static_assert(SAH_DEPTH + 31 < TR_BVH_STACK_SIZE, "BVH depth must fit the traversal stack");

static tr_aabb box_empty(void) {
    tr_aabb b = {v3s(INFINITY), v3s(-INFINITY)};
    return b;
}

static tr_aabb box_union(tr_aabb a, tr_aabb b) {
    tr_aabb r = {v3_min(a.min, b.min), v3_max(a.max, b.max)};
    return r;
}

static float box_area(tr_aabb b) {
    tr_vec3 d = v3_sub(b.max, b.min);
    if (!(d.x >= 0.0f && d.y >= 0.0f && d.z >= 0.0f)) {
        return 0.0f; /* empty */
    }
    return 2.0f * (d.x * d.y + d.y * d.z + d.z * d.x);
}

static float axis_of(tr_vec3 v, int axis) {
    return axis == 0 ? v.x : axis == 1 ? v.y : v.z;
}

static tr_aabb tri_box(const tr_triangle *t) {
    tr_aabb b = {v3_min(t->v0, v3_min(t->v1, t->v2)), v3_max(t->v0, v3_max(t->v1, t->v2))};
    return b;
}

/* A triangle (or box) as the builder moves it: its box and its index in 32 bytes. The
 * partitions move these records themselves rather than indices to them, so every pass over
 * a node's entries reads one contiguous run of memory instead of gathering from arrays
 * indexed by triangle. */
typedef struct ref {
    tr_vec3 min;
    uint32_t index;
    tr_vec3 max;
    uint32_t pad;
} ref;

static tr_aabb ref_box(const ref *r) {
    tr_aabb b = {r->min, r->max};
    return b;
}

static tr_vec3 ref_centroid(const ref *r) {
    return v3_scale(v3_add(r->min, r->max), 0.5f);
}

typedef struct builder {
    ref *refs; /* in the order the partitions leave them: leaf order at the end */
    tr_bvh_node *nodes;
    uint32_t node_count;
} builder;

typedef struct bin {
    tr_aabb box;
    uint32_t count;
} bin;

enum {
    /* Nodes with at least this many triangles are bounded and binned by all threads (the
     * top levels of a big build, before there are subtrees to share out). */
    PARALLEL_NODE_MIN = 1u << 16,
};

static int bin_index(float c, float lo, float scale, int nb) {
    int i = (int)((c - lo) * scale);
    return i < 0 ? 0 : i >= nb ? nb - 1 : i;
}

/* Bins indices[first, end) on all three axes into bins[axis][]; an axis that is not
 * active has lo = scale = 0 here (every triangle lands in bin 0, which is ignored), so
 * the loop has no branches on the axis. */
static void bin_range(const builder *b, uint32_t first, uint32_t end, const float lo[3],
                      const float scale[3], int nb, bin bins[3][BINS]) {
    for (uint32_t k = first; k < end; ++k) {
        const ref *r = &b->refs[k];
        const tr_vec3 c = ref_centroid(r);
        const tr_aabb box = ref_box(r);
        const int ix = bin_index(c.x, lo[0], scale[0], nb);
        const int iy = bin_index(c.y, lo[1], scale[1], nb);
        const int iz = bin_index(c.z, lo[2], scale[2], nb);
        bins[0][ix].box = box_union(bins[0][ix].box, box);
        bins[0][ix].count++;
        bins[1][iy].box = box_union(bins[1][iy].box, box);
        bins[1][iy].count++;
        bins[2][iz].box = box_union(bins[2][iz].box, box);
        bins[2][iz].count++;
    }
}

static void bins_clear(bin bins[3][BINS], int nb) {
    for (int axis = 0; axis < 3; ++axis) {
        for (int i = 0; i < nb; ++i) {
            bins[axis][i].box = box_empty();
            bins[axis][i].count = 0;
        }
    }
}

/* The best SAH split of indices[first, first+count): returns its cost (relative to
 * testing all triangles in one leaf, in units of triangle tests) and sets the axis and
 * the bin boundary; INFINITY when no axis has any extent. Big nodes are binned by all
 * threads, each into bins of its own, merged after: box unions and counts do not depend
 * on the order, so neither does the tree. */
static float find_split(const builder *b, uint32_t first, uint32_t count, tr_aabb cbox,
                        float node_area, int nb, int *best_axis, int *best_bin, tr_aabb child[2]) {
    float best = INFINITY;
    float lo[3], scale[3];
    int active[3], any = 0;
    for (int axis = 0; axis < 3; ++axis) {
        float hi = axis_of(cbox.max, axis);
        lo[axis] = axis_of(cbox.min, axis);
        scale[axis] = (float)nb / (hi - lo[axis]);
        /* No extent, or one so small (or large) that binning would overflow. */
        active[axis] = hi > lo[axis] && scale[axis] > 0.0f && scale[axis] < INFINITY;
        any |= active[axis];
        if (!active[axis]) {
            lo[axis] = scale[axis] = 0.0f;
        }
    }
    if (!any) {
        return INFINITY;
    }
    bin bins[3][BINS];
    bins_clear(bins, nb);
    if (count >= PARALLEL_NODE_MIN) {
#pragma omp parallel num_threads(tr_default_threads())
        {
            bin local[3][BINS];
            bins_clear(local, nb);
            const int64_t end = (int64_t)first + count;
#pragma omp for schedule(static) nowait
            for (int64_t k = first; k < end; k += 4096) {
                uint32_t stop = (uint32_t)(k + 4096 < end ? k + 4096 : end);
                bin_range(b, (uint32_t)k, stop, lo, scale, nb, local);
            }
#pragma omp critical
            for (int axis = 0; axis < 3; ++axis) {
                for (int i = 0; i < nb; ++i) {
                    bins[axis][i].box = box_union(bins[axis][i].box, local[axis][i].box);
                    bins[axis][i].count += local[axis][i].count;
                }
            }
        }
    } else {
        bin_range(b, first, first + count, lo, scale, nb, bins);
    }
    for (int axis = 0; axis < 3; ++axis) {
        if (!active[axis]) {
            continue;
        }
        /* Sweep from the right, then from the left, evaluating each of the nb-1 planes. */
        float right_cost[BINS];
        tr_aabb acc = box_empty();
        uint32_t n = 0;
        for (int i = nb - 1; i > 0; --i) {
            acc = box_union(acc, bins[axis][i].box);
            n += bins[axis][i].count;
            right_cost[i] = box_area(acc) * (float)n;
        }
        acc = box_empty();
        n = 0;
        for (int i = 0; i < nb - 1; ++i) {
            acc = box_union(acc, bins[axis][i].box);
            n += bins[axis][i].count;
            if (n == 0 || n == count) {
                continue;
            }
            float cost =
                TRAVERSAL_COST + (box_area(acc) * (float)n + right_cost[i + 1]) / node_area;
            if (cost < best) {
                best = cost;
                *best_axis = axis;
                *best_bin = i;
            }
        }
    }
    if (best < INFINITY) {
        /* The children's boxes are the unions of their bins' boxes: the same minima and
         * maxima as a pass over their triangles would find, without that pass. */
        child[0] = child[1] = box_empty();
        for (int i = 0; i < nb; ++i) {
            const int side = i > *best_bin;
            child[side] = box_union(child[side], bins[*best_axis][i].box);
        }
    }
    return best;
}

/* Moves the indices whose key on `axis` is below the k-th smallest to the front
 * (quickselect; keys are centroids). */
static void select_median(builder *b, uint32_t first, uint32_t count, int axis, uint32_t k) {
    uint32_t lo = first, hi = first + count - 1, target = first + k;
    ref *refs = b->refs;
    while (lo < hi) {
        float pivot = axis_of(ref_centroid(&refs[(lo + hi) / 2]), axis);
        uint32_t i = lo, j = hi;
        while (i <= j) {
            while (axis_of(ref_centroid(&refs[i]), axis) < pivot) {
                ++i;
            }
            while (axis_of(ref_centroid(&refs[j]), axis) > pivot) {
                --j;
            }
            if (i <= j) {
                ref t = refs[i];
                refs[i] = refs[j];
                refs[j] = t;
                ++i;
                if (j == 0) {
                    break;
                }
                --j;
            }
        }
        if (target <= j) {
            hi = j;
        } else if (target >= i) {
            lo = i;
        } else {
            break;
        }
    }
}

/* A node to build: its entries refs[first, first + count), their bounds (box) and their
 * centroids' bounds (cbox), both found by its parent's split. */
typedef struct task {
    uint32_t node, first, count, depth;
    tr_aabb box, cbox;
} task;

/* The bounds of refs[first, first + count) and of their centroids: by all threads, merged,
 * for a big run (min and max do not depend on the order). */
static void range_bounds(const builder *b, uint32_t first, uint32_t count, tr_aabb *box_out,
                         tr_aabb *cbox_out) {
    tr_aabb box = box_empty(), cbox = box_empty();
    if (count >= PARALLEL_NODE_MIN) {
#pragma omp parallel num_threads(tr_default_threads())
        {
            tr_aabb lbox = box_empty(), lcbox = box_empty();
            const int64_t end = (int64_t)first + count;
#pragma omp for schedule(static) nowait
            for (int64_t k = first; k < end; ++k) {
                const tr_vec3 c = ref_centroid(&b->refs[k]);
                lbox = box_union(lbox, ref_box(&b->refs[k]));
                lcbox.min = v3_min(lcbox.min, c);
                lcbox.max = v3_max(lcbox.max, c);
            }
#pragma omp critical
            {
                box = box_union(box, lbox);
                cbox = box_union(cbox, lcbox);
            }
        }
    } else {
        for (uint32_t k = first; k < first + count; ++k) {
            const tr_vec3 c = ref_centroid(&b->refs[k]);
            box = box_union(box, ref_box(&b->refs[k]));
            cbox.min = v3_min(cbox.min, c);
            cbox.max = v3_max(cbox.max, c);
        }
    }
    *box_out = box;
    *cbox_out = cbox;
}

/* Sets the node's box and decides its split: returns how many of its triangles go to
 * the left child (the refs are partitioned accordingly, and the children's tasks get
 * their bounds), or 0 for a leaf. */
static uint32_t split_node(builder *b, const task *t, tr_bvh_node *node, task child[2]) {
    const tr_aabb box = t->box, cbox = t->cbox;
    node->box = box;
    node->left_first = t->first;
    node->count = t->count;
    if (t->count <= FORCED_LEAF) {
        return 0;
    }
    int axis = 0, split_bin = 0;
    float cost = INFINITY;
    tr_aabb child_box[2];
    /* Fewer bins than triangles only cost time: small nodes get one per triangle (at
     * least 4); most nodes are small, and the bins' set-up and sweeps dominate there. */
    const int nbins = t->count >= BINS ? BINS : t->count < 4 ? 4 : (int)t->count;
    if (t->depth < SAH_DEPTH) {
        cost = find_split(b, t->first, t->count, cbox, box_area(box), nbins, &axis, &split_bin,
                          child_box);
    }
    if (cost < INFINITY && (cost < (float)t->count || t->count > MAX_LEAF)) {
        /* Partition by the chosen bin plane, binning exactly as find_split did; the
         * centroids' bounds of each side are gathered on the way. */
        float lo = axis_of(cbox.min, axis);
        float scale = (float)nbins / (axis_of(cbox.max, axis) - lo);
        tr_aabb cl = box_empty(), cr = box_empty();
        ref *refs = b->refs;
        uint32_t i = t->first, j = t->first + t->count;
        while (i < j) {
            const tr_vec3 c = ref_centroid(&refs[i]);
            int bi = (int)((axis_of(c, axis) - lo) * scale);
            bi = bi < 0 ? 0 : bi >= nbins ? nbins - 1 : bi;
            if (bi <= split_bin) {
                cl.min = v3_min(cl.min, c);
                cl.max = v3_max(cl.max, c);
                ++i;
            } else {
                cr.min = v3_min(cr.min, c);
                cr.max = v3_max(cr.max, c);
                ref x = refs[i];
                refs[i] = refs[--j];
                refs[j] = x;
            }
        }
        child[0].box = child_box[0];
        child[0].cbox = cl;
        child[1].box = child_box[1];
        child[1].cbox = cr;
        return i - t->first;
    }
    if (t->count > MAX_LEAF) {
        /* No useful SAH split (coincident centroids, or too deep): halve the node at
         * the median of its widest centroid axis, which bounds the depth. */
        tr_vec3 d = v3_sub(cbox.max, cbox.min);
        axis = d.x >= d.y && d.x >= d.z ? 0 : d.y >= d.z ? 1 : 2;
        const uint32_t half = t->count / 2;
        select_median(b, t->first, t->count, axis, half);
        range_bounds(b, t->first, half, &child[0].box, &child[0].cbox);
        range_bounds(b, t->first + half, t->count - half, &child[1].box, &child[1].cbox);
        return half;
    }
    return 0;
}

/* Builds the subtree of `root` into nodes[], root first, children always after their
 * parent; sets *node_count, raises *deepest to the deepest leaf's depth and returns the
 * number of leaves. With `cut` non-NULL, nodes
 * at depth cut_depth are not built but recorded in cut[] (their slot is reserved), to
 * be built separately. */
static uint32_t build_nodes(builder *b, task root, tr_bvh_node *nodes, uint32_t *node_count,
                            uint32_t cut_depth, task *cut, uint32_t *cut_count, uint32_t *deepest) {
    /* Depth-first with the left child popped first: at most one pending sibling per
     * level, and the depth is below TR_BVH_STACK_SIZE. */
    task stack[2 * TR_BVH_STACK_SIZE + 2];
    uint32_t top = 0, leaves = 0;
    *node_count = 1;
    root.node = 0;
    stack[top++] = root;
    while (top > 0) {
        task t = stack[--top];
        if (cut && t.depth == cut_depth) {
            cut[(*cut_count)++] = t;
            continue;
        }
        tr_bvh_node *node = &nodes[t.node];
        task child[2];
        uint32_t left = split_node(b, &t, node, child);
        if (left == 0) {
            leaves++;
            *deepest = t.depth > *deepest ? t.depth : *deepest;
            continue;
        }
        uint32_t l = *node_count;
        *node_count += 2;
        node->left_first = l;
        node->count = 0;
        child[1].node = l + 1;
        child[1].first = t.first + left;
        child[1].count = t.count - left;
        child[1].depth = t.depth + 1;
        child[0].node = l;
        child[0].first = t.first;
        child[0].count = left;
        child[0].depth = t.depth + 1;
        stack[top++] = child[1];
        stack[top++] = child[0];
    }
    return leaves;
}

enum {
    PARALLEL_MIN = PARALLEL_NODE_MIN, /* fewer triangles than this build on one thread */
    CUT_DEPTH = 4, /* the top levels are built serially, up to 16 subtrees after */
};

/* Builds the tree over indices[0, n) into b->nodes. Large trees are built in two
 * phases: the top CUT_DEPTH levels serially, then the subtrees below them in parallel,
 * each into its own array, appended in a fixed order. The result does not depend on the
 * thread count, so neither does any image rendered through it. */
static int build_tree(builder *b, uint32_t n, uint32_t *leaves_out, uint32_t *depth_out) {
    task root = {.node = 0, .first = 0, .count = n, .depth = 0};
    range_bounds(b, 0, n, &root.box, &root.cbox);
    task cut[1u << CUT_DEPTH];
    uint32_t cuts = 0, count = 0, deepest = 0;
    int parallel = n >= PARALLEL_MIN;
    uint32_t leaves =
        build_nodes(b, root, b->nodes, &count, CUT_DEPTH, parallel ? cut : NULL, &cuts, &deepest);
    tr_bvh_node *sub[1u << CUT_DEPTH] = {0};
    uint32_t sub_count[1u << CUT_DEPTH] = {0}, sub_leaves[1u << CUT_DEPTH] = {0};
    uint32_t sub_depth[1u << CUT_DEPTH] = {0};
    int failed = 0;
#pragma omp parallel for num_threads(tr_default_threads()) schedule(dynamic, 1)                    \
    reduction(|                                                                                    \
              : failed) if (cuts > 1)
    for (int k = 0; k < (int)cuts; ++k) {
        sub[k] = malloc((size_t)(2 * (uint64_t)cut[k].count) * sizeof *sub[k]);
        if (!sub[k]) {
            failed = 1;
            continue;
        }
        sub_leaves[k] = build_nodes(b, cut[k], sub[k], &sub_count[k], 0, NULL, NULL, &sub_depth[k]);
    }
    for (uint32_t k = 0; k < cuts && !failed; ++k) {
        /* The subtree's root takes the reserved slot; the rest goes to the end, with
         * child links moved from local index c >= 1 to count + c - 1. */
        uint32_t offset = count - 1;
        for (uint32_t i = 0; i < sub_count[k]; ++i) {
            tr_bvh_node nd = sub[k][i];
            if (nd.count == 0) {
                nd.left_first += offset;
            }
            b->nodes[i == 0 ? cut[k].node : offset + i] = nd;
        }
        count += sub_count[k] - 1;
        leaves += sub_leaves[k];
        deepest = sub_depth[k] > deepest ? sub_depth[k] : deepest;
    }
    for (uint32_t k = 0; k < cuts; ++k) {
        free(sub[k]);
    }
    b->node_count = count;
    *leaves_out = leaves;
    *depth_out = deepest;
    return failed ? TR_ERR : TR_OK;
}

/* The leaf-order triangle copy the traversal reads. */
static void bvh_fill_tris(tr_bvh *bvh, const tr_triangle *tris) {
    for (uint32_t k = 0; k < bvh->index_count; ++k) {
        const tr_triangle *t = &tris[bvh->indices[k]];
        bvh->tris[k].v0 = t->v0;
        bvh->tris[k].e1 = v3_sub(t->v1, t->v0);
        bvh->tris[k].e2 = v3_sub(t->v2, t->v0);
        bvh->tris[k].index = bvh->indices[k];
    }
}

/* The build over triangles (tris) or over boxes (boxes, tris NULL: the top level of a
 * two-level structure, whose leaf entries are instances). */
static int bvh_build(tr_bvh *bvh, const tr_triangle *tris, const tr_aabb *boxes, uint32_t n,
                     const uint8_t *skip, tr_error *err) {
    double t0 = tr_time_now();
    memset(bvh, 0, sizeof *bvh);
    builder b;
    memset(&b, 0, sizeof b);
    b.refs = malloc((size_t)(n ? n : 1) * sizeof *b.refs);
    uint32_t *indices = malloc((size_t)(n ? n : 1) * sizeof *indices);
    /* A binary tree over m leaves of >= 1 triangle has at most 2m - 1 nodes. */
    b.nodes = malloc((size_t)(2 * (uint64_t)(n ? n : 1)) * sizeof *b.nodes);
    if (!b.refs || !indices || !b.nodes) {
        free(b.refs);
        free(indices);
        free(b.nodes);
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY,
                            "out of memory building a BVH over %u triangles", n);
    }
    uint32_t m = 0;
    for (uint32_t i = 0; i < n; ++i) {
        tr_aabb box;
        if (boxes) {
            /* An empty or non-finite box (an instance of nothing) can never be hit. */
            if (!(boxes[i].min.x <= boxes[i].max.x && boxes[i].min.y <= boxes[i].max.y &&
                  boxes[i].min.z <= boxes[i].max.z) ||
                !v3_is_finite(boxes[i].min) || !v3_is_finite(boxes[i].max)) {
                continue;
            }
            box = boxes[i];
        } else {
            const tr_triangle *t = &tris[i];
            if ((skip && skip[i]) || !(t->area > 0.0f) || !v3_is_finite(t->v0) ||
                !v3_is_finite(t->v1) || !v3_is_finite(t->v2)) {
                continue; /* can never be hit */
            }
            box = tri_box(t);
        }
        b.refs[m++] = (ref){box.min, i, box.max, 0};
    }
    uint32_t leaves = 0, depth = 0;
    int rc = m > 0 ? build_tree(&b, m, &leaves, &depth) : TR_OK;
    for (uint32_t k = 0; k < m && rc == TR_OK; ++k) {
        indices[k] = b.refs[k].index;
    }
    free(b.refs);
    if (rc != TR_OK) {
        free(b.nodes);
        free(indices);
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY,
                            "out of memory building a BVH over %u triangles", n);
    }
    bvh->nodes = b.nodes;
    bvh->node_count = m > 0 ? b.node_count : 0;
    bvh->indices = indices;
    bvh->index_count = m;
    bvh->leaf_count = leaves;
    bvh->depth = depth;
    bvh->skipped = n - m;
    /* Give back what the worst-case allocation did not use. */
    tr_bvh_node *shrunk =
        realloc(bvh->nodes, (size_t)(bvh->node_count ? bvh->node_count : 1) * sizeof *bvh->nodes);
    if (shrunk) {
        bvh->nodes = shrunk;
    }
    bvh->tris = malloc((size_t)(m ? m : 1) * sizeof *bvh->tris);
    if (!bvh->tris) {
        tr_bvh_free(bvh);
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY,
                            "out of memory building a BVH over %u triangles", n);
    }
    if (tris) {
        bvh_fill_tris(bvh, tris);
    } else {
        memset(bvh->tris, 0, (size_t)m * sizeof *bvh->tris);
        for (uint32_t k = 0; k < m; ++k) {
            bvh->tris[k].index = bvh->indices[k];
        }
    }
    bvh->build_seconds = tr_time_now() - t0;
    return TR_OK;
}

int tr_bvh_build(tr_bvh *bvh, const tr_triangle *tris, uint32_t n, tr_error *err) {
    return bvh_build(bvh, tris, NULL, n, NULL, err);
}

int tr_bvh_build_skip(tr_bvh *bvh, const tr_triangle *tris, uint32_t n, const uint8_t *skip,
                      tr_error *err) {
    return bvh_build(bvh, tris, NULL, n, skip, err);
}

int tr_bvh_build_boxes(tr_bvh *bvh, const tr_aabb *boxes, uint32_t n, tr_error *err) {
    return bvh_build(bvh, NULL, boxes, n, NULL, err);
}

void tr_bvh_refit(tr_bvh *bvh, const tr_triangle *tris) {
    bvh->refits++;
    /* The leaves' triangles and boxes are independent of each other: all threads share
     * them out. The inner nodes (children after their parent in the array) follow on one
     * thread, bottom up: a union per node. Same operations in the same order per box as
     * a sequential refit, so the boxes do not depend on the thread count. */
    const int64_t nk = bvh->index_count, nn = bvh->node_count;
#pragma omp parallel num_threads(tr_default_threads())
    {
#pragma omp for schedule(static)
        for (int64_t k = 0; k < nk; ++k) {
            const tr_triangle *t = &tris[bvh->indices[k]];
            bvh->tris[k].v0 = t->v0;
            bvh->tris[k].e1 = v3_sub(t->v1, t->v0);
            bvh->tris[k].e2 = v3_sub(t->v2, t->v0);
            bvh->tris[k].index = bvh->indices[k];
        }
#pragma omp for schedule(dynamic, 4096)
        for (int64_t i = 0; i < nn; ++i) {
            tr_bvh_node *n = &bvh->nodes[i];
            if (n->count > 0) {
                tr_aabb box = box_empty();
                for (uint32_t k = n->left_first; k < n->left_first + n->count; ++k) {
                    box = box_union(box, tri_box(&tris[bvh->indices[k]]));
                }
                n->box = box;
            }
        }
    }
    for (int64_t i = nn; i-- > 0;) {
        tr_bvh_node *n = &bvh->nodes[i];
        if (n->count == 0) {
            n->box = box_union(bvh->nodes[n->left_first].box, bvh->nodes[n->left_first + 1].box);
        }
    }
}

void tr_bvh_free(tr_bvh *bvh) {
    free(bvh->nodes);
    free(bvh->indices);
    free(bvh->tris);
    memset(bvh, 0, sizeof *bvh);
}
