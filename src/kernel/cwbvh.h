/* cwbvh.h - a compressed 8-wide BVH and its traversal, single-source (host and OpenCL C),
 * after Ylitie, Karras and Laine, "Efficient Incoherent Ray Traversal on GPUs Through
 * Compressed Wide BVHs", HPG 2017. src/accel/cwbvh.c converts the binary BVH
 * (tr_bvh_node, the same binned-SAH build) into it.
 *
 * A node is 80 bytes: the origin p of its frame, three power-of-two scales 2^e (one
 * exponent byte per axis), and its up-to-8 children's boxes quantized to 8 bits per plane
 * in that frame: child box = p + q * 2^e per axis, q in 0..255. The quantization is
 * conservative (every child box contains the exact one: the converter checks the float
 * values the traversal will compute), so the traversal visits every node the binary BVH
 * would and finds the same closest hit. Internal children are stored consecutively from
 * child_base; leaf children's triangles consecutively from tri_base (a reordered copy of
 * the binary BVH's leaf triangles), each leaf's range following the previous leaf's.
 *
 * What this keeps from the paper: the node format's quantized frame and 8-bit planes (80
 * bytes for 8 children against 256 for the binary BVH's 8 nodes) and the collapse by
 * largest surface area. What it does not (yet): the octant-ordered child slots and the
 * hit-mask stack entries; the traversal here pushes each hit internal child with its entry
 * distance, nearest popped first, as the binary walk does. */
#ifndef TR_KERNEL_CWBVH_H
#define TR_KERNEL_CWBVH_H

#include "compat.h"
#include "intersect.h"
#include "types.h"
#include "vec.h"

/* meta byte of a child: 0 empty; TR_CWBVH_INTERNAL | k: the k-th internal child
 * (child_base + k); otherwise a leaf of `meta` triangles (1..127). */
#define TR_CWBVH_INTERNAL 0x80u
/* Entries of the traversal stack: at most 7 per level of the wide tree. */
#define TR_CWBVH_STACK_SIZE 128

typedef struct tr_cwbvh_node {
    float px, py, pz;    /* the frame's origin */
    uint32_t exps;       /* exponent bytes ex | ey << 8 | ez << 16 (biased by 127) */
    uint32_t child_base; /* first internal child node */
    uint32_t tri_base;   /* first triangle of the first leaf child */
    uint32_t meta[2];    /* 8 meta bytes, child i in byte i % 4 of word i / 4 */
    uint32_t q[12];      /* lo x, lo y, lo z, hi x, hi y, hi z: 8 bytes each, 2 words */
} tr_cwbvh_node;
TR_STATIC_ASSERT(sizeof(tr_cwbvh_node) == 80, "tr_cwbvh_node layout");

/* Byte i (0..7) of an 8-byte field stored as two words. */
TR_FN uint32_t tr_cwbvh_byte(TR_CONST_GLOBAL uint32_t *w, uint32_t i) {
    return (w[i >> 2] >> ((i & 3u) * 8u)) & 0xffu;
}

/* 2^(e - 127) for a biased exponent byte, exactly (a normal float's bits). */
TR_FN float tr_cwbvh_scale(uint32_t e) {
    union {
        uint32_t u;
        float f;
    } b;
    b.u = e << 23;
    return b.f;
}

/* Child i's box as the traversal sees it: origin + q * scale, per axis and plane. */
TR_FN tr_aabb tr_cwbvh_child_box(TR_CONST_GLOBAL tr_cwbvh_node *n, uint32_t i) {
    const float sx = tr_cwbvh_scale(n->exps & 0xffu);
    const float sy = tr_cwbvh_scale((n->exps >> 8) & 0xffu);
    const float sz = tr_cwbvh_scale((n->exps >> 16) & 0xffu);
    tr_aabb b;
    b.min.x = n->px + (float)tr_cwbvh_byte(&n->q[0], i) * sx;
    b.min.y = n->py + (float)tr_cwbvh_byte(&n->q[2], i) * sy;
    b.min.z = n->pz + (float)tr_cwbvh_byte(&n->q[4], i) * sz;
    b.max.x = n->px + (float)tr_cwbvh_byte(&n->q[6], i) * sx;
    b.max.y = n->py + (float)tr_cwbvh_byte(&n->q[8], i) * sy;
    b.max.z = n->pz + (float)tr_cwbvh_byte(&n->q[10], i) * sz;
    return b;
}

/* Closest hit (or with any_hit the first hit) of the ray in (tmin, tmax) through the
 * compressed wide BVH over `tris`; root: node 0. Returns 0 without a hit or nodes. */
TR_FN int tr_cwbvh_traverse(TR_CONST_GLOBAL tr_cwbvh_node *nodes, uint32_t node_count,
                            TR_CONST_GLOBAL tr_bvh_tri *tris, const tr_ray *ray, tr_hit *hit,
                            int any_hit) {
    if (node_count == 0u) {
        return 0;
    }
    tr_ray r = *ray;
    int found = 0;
    uint32_t stack[TR_CWBVH_STACK_SIZE];
    float stack_t[TR_CWBVH_STACK_SIZE];
    int top = 0;
    stack[0] = 0u;
    stack_t[0] = r.tmin;
    top = 1;
    while (top > 0) {
        --top;
        if (stack_t[top] > r.tmax) {
            continue; /* starts beyond the closest hit found since it was pushed */
        }
        TR_CONST_GLOBAL tr_cwbvh_node *n = &nodes[stack[top]];
        uint32_t tri = n->tri_base;
        /* The hit internal children, nearest last so that it is popped first. */
        uint32_t child[8];
        float child_t[8];
        int hits = 0;
        for (uint32_t i = 0; i < 8u; ++i) {
            const uint32_t meta = tr_cwbvh_byte(n->meta, i);
            if (meta == 0u) {
                continue;
            }
            const int internal = (meta & TR_CWBVH_INTERNAL) != 0u;
            const uint32_t first = tri;
            if (!internal) {
                tri += meta;
            }
            float tn;
            if (!tr_intersect_aabb(&r, tr_cwbvh_child_box(n, i), &tn)) {
                continue;
            }
            if (!internal) {
                for (uint32_t k = first; k < first + meta; ++k) {
                    float t, u, v;
                    if (tr_intersect_triangle_edges(&r, tris[k].v0, tris[k].e1, tris[k].e2, &t, &u,
                                                    &v)) {
                        r.tmax = t;
                        hit->t = t;
                        hit->triangle = tris[k].index;
                        hit->u = u;
                        hit->v = v;
                        found = 1;
                        if (any_hit) {
                            return 1;
                        }
                    }
                }
                continue;
            }
            /* Insert by decreasing distance. */
            int j = hits++;
            while (j > 0 && child_t[j - 1] < tn) {
                child[j] = child[j - 1];
                child_t[j] = child_t[j - 1];
                --j;
            }
            child[j] = n->child_base + (meta & ~TR_CWBVH_INTERNAL);
            child_t[j] = tn;
        }
        for (int j = 0; j < hits && top < TR_CWBVH_STACK_SIZE; ++j) {
            stack[top] = child[j];
            stack_t[top] = child_t[j];
            ++top;
        }
    }
    return found;
}

#endif
