/* cwbvh.c - the binary BVH collapsed into the compressed 8-wide BVH of src/kernel/cwbvh.h
 * (Ylitie, Karras and Laine, HPG 2017), with conservatively quantized child boxes. */
#include "accel/cwbvh.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static float box_area(tr_aabb b) {
    const float dx = b.max.x - b.min.x, dy = b.max.y - b.min.y, dz = b.max.z - b.min.z;
    return dx * dy + dy * dz + dz * dx;
}

/* The binary children (up to 8) that wide node `root` gets: start from its two children,
 * open the internal one of largest area while there is room. Returns the count. */
static int collect_children(const tr_bvh_node *nodes, uint32_t root, uint32_t out[8]) {
    int n = 0;
    out[n++] = nodes[root].left_first;
    out[n++] = nodes[root].left_first + 1u;
    while (n < 8) {
        int best = -1;
        float area = -1.0f;
        for (int i = 0; i < n; ++i) {
            const tr_bvh_node *c = &nodes[out[i]];
            if (c->count == 0u && box_area(c->box) > area) {
                area = box_area(c->box);
                best = i;
            }
        }
        if (best < 0) {
            break;
        }
        const uint32_t open = out[best];
        out[best] = nodes[open].left_first;
        out[n++] = nodes[open].left_first + 1u;
    }
    return n;
}

/* The exponent (biased by 127) of the smallest power of two s with origin + 255 s >= hi,
 * in the float arithmetic the traversal uses. */
static uint32_t axis_exponent(float lo, float hi) {
    const float extent = hi - lo;
    int e = extent > 0.0f ? (int)ceilf(log2f(extent / 255.0f)) : -126;
    if (e < -126) {
        e = -126;
    }
    while (e < 127 && lo + 255.0f * ldexpf(1.0f, e) < hi) {
        ++e;
    }
    return (uint32_t)(e + 127);
}

/* Conservative quantization of one plane: the largest q with p + q s <= v (lower planes)
 * or the smallest with p + q s >= v (upper planes). */
static uint32_t quantize(float p, float s, float v, int upper) {
    float q = upper ? ceilf((v - p) / s) : floorf((v - p) / s);
    q = q < 0.0f ? 0.0f : q > 255.0f ? 255.0f : q;
    if (upper) {
        while (q < 255.0f && p + q * s < v) {
            q += 1.0f;
        }
    } else {
        while (q > 0.0f && p + q * s > v) {
            q -= 1.0f;
        }
    }
    return (uint32_t)q;
}

static void set_byte(uint32_t *w, uint32_t i, uint32_t v) {
    w[i >> 2] |= (v & 0xffu) << ((i & 3u) * 8u);
}

typedef struct task {
    uint32_t binary; /* the binary node this wide node stands for */
    uint32_t wide;   /* its index among the wide nodes */
    uint32_t depth;
} task;

int tr_cwbvh_build(tr_cwbvh *cw, const tr_bvh_node *nodes, uint32_t node_count,
                   const tr_bvh_tri *tris, tr_error *err) {
    memset(cw, 0, sizeof *cw);
    if (node_count == 0u) {
        return TR_OK;
    }
    /* At most one wide node per binary internal node, and every leaf triangle once (a
     * binary root that is a leaf becomes one wide node with one leaf child). */
    uint32_t leaf_tris = 0;
    for (uint32_t i = 0; i < node_count; ++i) {
        leaf_tris += nodes[i].count;
    }
    cw->nodes = calloc(node_count, sizeof *cw->nodes);
    cw->tris = malloc((size_t)(leaf_tris ? leaf_tris : 1u) * sizeof *cw->tris);
    task *queue = malloc((size_t)node_count * sizeof *queue);
    if (!cw->nodes || !cw->tris || !queue) {
        free(queue);
        tr_cwbvh_free(cw);
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory for a wide BVH");
    }
    uint32_t head = 0, tail = 0;
    queue[tail++] = (task){0u, 0u, 0u};
    cw->node_count = 1;
    while (head < tail) {
        const task t = queue[head++];
        tr_cwbvh_node *w = &cw->nodes[t.wide];
        uint32_t child[8];
        int n;
        if (nodes[t.binary].count > 0u) {
            child[0] = t.binary; /* a root that is a leaf */
            n = 1;
        } else {
            n = collect_children(nodes, t.binary, child);
        }
        tr_aabb box = nodes[child[0]].box;
        for (int i = 1; i < n; ++i) {
            const tr_aabb b = nodes[child[i]].box;
            box.min =
                v3(fminf(box.min.x, b.min.x), fminf(box.min.y, b.min.y), fminf(box.min.z, b.min.z));
            box.max =
                v3(fmaxf(box.max.x, b.max.x), fmaxf(box.max.y, b.max.y), fmaxf(box.max.z, b.max.z));
        }
        w->px = box.min.x;
        w->py = box.min.y;
        w->pz = box.min.z;
        const uint32_t ex = axis_exponent(box.min.x, box.max.x);
        const uint32_t ey = axis_exponent(box.min.y, box.max.y);
        const uint32_t ez = axis_exponent(box.min.z, box.max.z);
        w->exps = ex | ey << 8 | ez << 16;
        const float sx = tr_cwbvh_scale(ex), sy = tr_cwbvh_scale(ey), sz = tr_cwbvh_scale(ez);
        w->child_base = cw->node_count;
        w->tri_base = cw->tri_count;
        uint32_t internal = 0;
        for (int i = 0; i < n; ++i) {
            const tr_bvh_node *c = &nodes[child[i]];
            const uint32_t slot = (uint32_t)i;
            set_byte(&w->q[0], slot, quantize(w->px, sx, c->box.min.x, 0));
            set_byte(&w->q[2], slot, quantize(w->py, sy, c->box.min.y, 0));
            set_byte(&w->q[4], slot, quantize(w->pz, sz, c->box.min.z, 0));
            set_byte(&w->q[6], slot, quantize(w->px, sx, c->box.max.x, 1));
            set_byte(&w->q[8], slot, quantize(w->py, sy, c->box.max.y, 1));
            set_byte(&w->q[10], slot, quantize(w->pz, sz, c->box.max.z, 1));
            if (c->count > 0u) {
                if (c->count > 127u) {
                    tr_cwbvh_free(cw);
                    free(queue);
                    return tr_error_set(err, TR_STATUS_LIMIT,
                                        "wide BVH: a leaf of %u triangles (at most 127)", c->count);
                }
                memcpy(&cw->tris[cw->tri_count], &tris[c->left_first], c->count * sizeof *cw->tris);
                cw->tri_count += c->count;
                set_byte(w->meta, slot, c->count);
            } else {
                set_byte(w->meta, slot, TR_CWBVH_INTERNAL | internal);
                queue[tail++] = (task){child[i], cw->node_count++, t.depth + 1u};
                ++internal;
            }
        }
        cw->depth = t.depth > cw->depth ? t.depth : cw->depth;
    }
    free(queue);
    /* The stack holds at most 7 entries per level below the root, and the root's. */
    if (7u * cw->depth + 1u > TR_CWBVH_STACK_SIZE) {
        const uint32_t depth = cw->depth;
        tr_cwbvh_free(cw);
        return tr_error_set(err, TR_STATUS_LIMIT,
                            "wide BVH: %u levels need more than the traversal's %d stack entries",
                            depth, TR_CWBVH_STACK_SIZE);
    }
    return TR_OK;
}

void tr_cwbvh_free(tr_cwbvh *cw) {
    free(cw->nodes);
    free(cw->tris);
    memset(cw, 0, sizeof *cw);
}
