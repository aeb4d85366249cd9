/* tlas.c - the top level of a two-level structure: a BVH over instances, each a bottom
 * level (a wide BVH in its object space) and a transform. The binary tree is built over
 * the instances' world boxes with the same binned SAH as triangles, then collapsed into
 * the same wide BVH; its leaf lanes name instances, which the wide traversal
 * (src/accel/wbvh_traverse.h) follows into their bottom levels. */
#include <stdlib.h>
#include <string.h>

#include "accel/accel_internal.h"
#include "trac0r/render.h"

void tr_tlas_free(tr_tlas *t) {
    tr_bvh_free(&t->bvh);
    tr_wbvh_free(&t->wbvh);
    free(t->inst);
    free(t->boxes);
    free(t->parent);
    free(t->leaf_of);
    free(t->wide_slot);
    memset(t, 0, sizeof *t);
}

static tr_aabb box_union(tr_aabb a, tr_aabb b) {
    tr_aabb r = {v3_min(a.min, b.min), v3_max(a.max, b.max)};
    return r;
}

static void set_wide_bounds(tr_wbvh *w, uint32_t slot, tr_aabb b) {
    tr_wbvh_node *node = &w->nodes[slot / TR_WBVH_WIDTH];
    const uint32_t i = slot % TR_WBVH_WIDTH;
    node->bounds[0][i] = b.min.x;
    node->bounds[1][i] = b.max.x;
    node->bounds[2][i] = b.min.y;
    node->bounds[3][i] = b.max.y;
    node->bounds[4][i] = b.min.z;
    node->bounds[5][i] = b.max.z;
}

int tr_tlas_build(tr_tlas *t, const tr_wbvh_instance *inst, const tr_aabb *boxes, uint32_t n,
                  tr_error *err) {
    const double t0 = tr_time_now();
    memset(t, 0, sizeof *t);
    const size_t nn = n ? n : 1;
    t->inst = malloc(nn * sizeof *t->inst);
    t->boxes = malloc(nn * sizeof *t->boxes);
    t->leaf_of = malloc(nn * sizeof *t->leaf_of);
    if (!t->inst || !t->boxes || !t->leaf_of) {
        tr_tlas_free(t);
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY,
                            "out of memory building the top level over %u instances", n);
    }
    memcpy(t->inst, inst, (size_t)n * sizeof *inst);
    memcpy(t->boxes, boxes, (size_t)n * sizeof *boxes);
    t->count = n;
    if (tr_bvh_build_boxes(&t->bvh, boxes, n, err) != TR_OK ||
        tr_wbvh_build(&t->wbvh, &t->bvh, err) != TR_OK) {
        tr_tlas_free(t);
        return TR_ERR;
    }
    t->wbvh.instances = t->inst;
    /* Lanes past a leaf's last instance name none (the collapse leaves them zero, which
     * would name instance 0). */
    for (uint32_t l = 0; l < t->wbvh.leaf_count; ++l) {
        const tr_wbvh_leaf *leaf = &t->wbvh.leaves[l];
        const uint32_t packets = (leaf->count + 3) / 4;
        for (uint32_t k = leaf->count; k < 4 * packets; ++k) {
            t->wbvh.packets[leaf->packet + k / 4].index[k % 4] = UINT32_MAX;
        }
    }
    const uint32_t nodes = t->bvh.node_count;
    t->parent = malloc((size_t)(nodes ? nodes : 1) * sizeof *t->parent);
    t->wide_slot = malloc((size_t)(nodes ? nodes : 1) * sizeof *t->wide_slot);
    if (!t->parent || !t->wide_slot) {
        tr_tlas_free(t);
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY,
                            "out of memory building the top level over %u instances", n);
    }
    for (uint32_t i = 0; i < n; ++i) {
        t->leaf_of[i] = UINT32_MAX;
    }
    for (uint32_t i = 0; i < nodes; ++i) {
        t->wide_slot[i] = UINT32_MAX;
    }
    if (nodes > 0) {
        t->parent[0] = UINT32_MAX;
    }
    for (uint32_t i = 0; i < nodes; ++i) {
        const tr_bvh_node *nd = &t->bvh.nodes[i];
        if (nd->count > 0) {
            for (uint32_t k = nd->left_first; k < nd->left_first + nd->count; ++k) {
                t->leaf_of[t->bvh.indices[k]] = i;
            }
        } else {
            t->parent[nd->left_first] = i;
            t->parent[nd->left_first + 1] = i;
        }
    }
    for (uint32_t w = 0; w < t->wbvh.node_count; ++w) {
        for (uint32_t i = 0; i < TR_WBVH_WIDTH; ++i) {
            const uint32_t src = t->wbvh.slot_src[(size_t)TR_WBVH_WIDTH * w + i];
            if (src != UINT32_MAX) {
                t->wide_slot[src] = TR_WBVH_WIDTH * w + i;
            }
        }
    }
    t->build_seconds = tr_time_now() - t0;
    return TR_OK;
}

int tr_tlas_move(tr_tlas *t, uint32_t i, const float inv[12], tr_aabb box) {
    if (i >= t->count || t->leaf_of[i] == UINT32_MAX) {
        return 0;
    }
    memcpy(t->inst[i].inv, inv, sizeof t->inst[i].inv);
    t->boxes[i] = box;
    for (uint32_t node = t->leaf_of[i]; node != UINT32_MAX; node = t->parent[node]) {
        tr_bvh_node *nd = &t->bvh.nodes[node];
        tr_aabb b;
        if (nd->count > 0) {
            b = t->boxes[t->bvh.indices[nd->left_first]];
            for (uint32_t k = nd->left_first + 1; k < nd->left_first + nd->count; ++k) {
                b = box_union(b, t->boxes[t->bvh.indices[k]]);
            }
        } else {
            b = box_union(t->bvh.nodes[nd->left_first].box, t->bvh.nodes[nd->left_first + 1].box);
        }
        nd->box = b;
        if (t->wide_slot[node] != UINT32_MAX) {
            set_wide_bounds(&t->wbvh, t->wide_slot[node], b);
        }
    }
    t->moves++;
    return 1;
}
