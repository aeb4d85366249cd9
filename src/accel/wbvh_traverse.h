/* wbvh_traverse.h - closest-hit and any-hit traversal of the wide BVH (host only).
 *
 * A template: each of src/accel/wbvh_{scalar,sse2,avx2,avx512}.c defines
 * TR_WBVH_TEMPLATE_ISA (a TR_WBVH_ISA_* number) and TR_WBVH_TEMPLATE_SUFFIX, includes
 * this file once under its own compiler flags (CMakeLists.txt) and so exports
 * tr_wbvh_intersect_SUFFIX and tr_wbvh_occluded_SUFFIX, between which src/accel/wbvh.c
 * chooses at run time. The node test takes a node's 8 boxes in one 256-bit operation per
 * plane with AVX2 (with AVX-512VL the hit mask comes straight from the compare), as two
 * 128-bit halves with SSE2, or lane by lane in the portable scalar code; the triangle
 * test takes a packet of four in one 128-bit operation per step (SSE2 and up). For
 * measuring what each part buys, defining TR_WBVH_SCALAR_NODES or TR_WBVH_SCALAR_TRIS
 * when building the library keeps only the box tests or only the triangle tests scalar
 * (docs/benchmarks.md).
 *
 * Every path computes exactly what the binary BVH and the flat structure compute: the
 * slab test as (plane - origin) * inv_dir and Moller-Trumbore in the same operation
 * order (src/kernel/intersect.h; no fused multiply-add, the library is built with
 * -ffp-contract=off and none of the files is given -mfma), so the wide BVH hits the same
 * triangle at the same distance whichever ISA runs it. The boxes' near and far planes
 * are picked per ray from the sign of inv_dir (as in Embree): then an empty box (+inf,
 * -inf) is never entered, and a plane through which an axis-parallel ray runs (0 * inf =
 * NaN) puts no limit on the segment, as in tr_slab: max and min below return their
 * second operand, the running bound, when the first is NaN (the semantics of the
 * SSE/AVX instructions). */
#ifndef TR_ACCEL_WBVH_TRAVERSE_H
#define TR_ACCEL_WBVH_TRAVERSE_H

#include <stddef.h>
#include <stdint.h>

#include "accel/wbvh.h"
#include "kernel/types.h"
#include "accel/accel_internal.h"

#if !defined(TR_WBVH_TEMPLATE_ISA) || !defined(TR_WBVH_TEMPLATE_SUFFIX)
#error "define TR_WBVH_TEMPLATE_ISA and TR_WBVH_TEMPLATE_SUFFIX before including wbvh_traverse.h"
#endif

/* Each file must be compiled with the flags its ISA needs (and the dispatcher must only
 * call it on a CPU that has them); a file built without them would not compile anyway,
 * this says why. */
#if TR_WBVH_TEMPLATE_ISA == TR_WBVH_ISA_AVX512
#if !defined(__AVX2__) || !defined(__AVX512F__) || !defined(__AVX512VL__)
#error "wbvh_avx512.c needs -mavx2 -mavx512f -mavx512vl"
#endif
#define TR_WBVH_NODES_256 1
#define TR_WBVH_TRIS_128 1
#include <immintrin.h>
#elif TR_WBVH_TEMPLATE_ISA == TR_WBVH_ISA_AVX2
#if !defined(__AVX2__)
#error "wbvh_avx2.c needs -mavx2"
#endif
#define TR_WBVH_NODES_256 1
#define TR_WBVH_TRIS_128 1
#include <immintrin.h>
#elif TR_WBVH_TEMPLATE_ISA == TR_WBVH_ISA_SSE2
#if !defined(__SSE2__)
#error "wbvh_sse2.c needs -msse2"
#endif
#define TR_WBVH_NODES_128 1
#define TR_WBVH_TRIS_128 1
#include <emmintrin.h>
#elif TR_WBVH_TEMPLATE_ISA != TR_WBVH_ISA_SCALAR
#error "unknown TR_WBVH_TEMPLATE_ISA"
#endif
#ifdef TR_WBVH_SCALAR_NODES
#undef TR_WBVH_NODES_256
#undef TR_WBVH_NODES_128
#endif
#ifdef TR_WBVH_SCALAR_TRIS
#undef TR_WBVH_TRIS_128
#endif

/* Each node level pushes at most TR_WBVH_WIDTH - 1 entries, and the wide tree is no
 * deeper than the binary one. */
#define TR_WBVH_STACK_SIZE ((TR_WBVH_WIDTH - 1) * TR_BVH_STACK_SIZE + 1)

static inline float tr_wbvh_max(float a, float b) {
    return a > b ? a : b; /* b when a is NaN, as maxps */
}
static inline float tr_wbvh_min(float a, float b) {
    return a < b ? a : b;
}

/* The ray as the traversal uses it: which row of a node's bounds holds each axis's
 * near plane (the far one is the other row of the pair). */
typedef struct tr_wbvh_ray {
    float o[3], d[3], inv[3];
    int near_row[3], far_row[3];
} tr_wbvh_ray;

static inline void tr_wbvh_ray_init(tr_wbvh_ray *r, const tr_ray *ray) {
    const float o[3] = {ray->origin.x, ray->origin.y, ray->origin.z};
    const float d[3] = {ray->dir.x, ray->dir.y, ray->dir.z};
    const float inv[3] = {ray->inv_dir.x, ray->inv_dir.y, ray->inv_dir.z};
    for (int a = 0; a < 3; ++a) {
        r->o[a] = o[a];
        r->d[a] = d[a];
        r->inv[a] = inv[a];
        int neg = inv[a] < 0.0f; /* -0 gives inv = -inf: negative */
        r->near_row[a] = 2 * a + neg;
        r->far_row[a] = 2 * a + 1 - neg;
    }
}

/* Which children of the node the segment (tmin, tmax) meets; their entry distances go
 * to tnear[]. */
static inline uint32_t tr_wbvh_node_hits(const tr_wbvh_node *n, const tr_wbvh_ray *r, float tmin,
                                         float tmax, float *tnear) {
#if defined(TR_WBVH_NODES_256)
    __m256 t0 = _mm256_set1_ps(tmin), t1 = _mm256_set1_ps(tmax);
    for (int a = 0; a < 3; ++a) {
        __m256 o = _mm256_set1_ps(r->o[a]), inv = _mm256_set1_ps(r->inv[a]);
        __m256 tn = _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(n->bounds[r->near_row[a]]), o), inv);
        __m256 tf = _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(n->bounds[r->far_row[a]]), o), inv);
        t0 = _mm256_max_ps(tn, t0);
        t1 = _mm256_min_ps(tf, t1);
    }
    _mm256_storeu_ps(tnear, t0);
#if TR_WBVH_TEMPLATE_ISA == TR_WBVH_ISA_AVX512
    return (uint32_t)_mm256_cmp_ps_mask(t0, t1, _CMP_LE_OQ);
#else
    return (uint32_t)_mm256_movemask_ps(_mm256_cmp_ps(t0, t1, _CMP_LE_OQ));
#endif
#elif defined(TR_WBVH_NODES_128)
    /* Boxes 0-3 and 4-7 side by side: the two halves are independent chains. */
    __m128 t0a = _mm_set1_ps(tmin), t1a = _mm_set1_ps(tmax);
    __m128 t0b = t0a, t1b = t1a;
    for (int a = 0; a < 3; ++a) {
        __m128 o = _mm_set1_ps(r->o[a]), inv = _mm_set1_ps(r->inv[a]);
        const float *np = n->bounds[r->near_row[a]], *fp = n->bounds[r->far_row[a]];
        t0a = _mm_max_ps(_mm_mul_ps(_mm_sub_ps(_mm_load_ps(np), o), inv), t0a);
        t0b = _mm_max_ps(_mm_mul_ps(_mm_sub_ps(_mm_load_ps(np + 4), o), inv), t0b);
        t1a = _mm_min_ps(_mm_mul_ps(_mm_sub_ps(_mm_load_ps(fp), o), inv), t1a);
        t1b = _mm_min_ps(_mm_mul_ps(_mm_sub_ps(_mm_load_ps(fp + 4), o), inv), t1b);
    }
    _mm_storeu_ps(tnear, t0a);
    _mm_storeu_ps(tnear + 4, t0b);
    return (uint32_t)_mm_movemask_ps(_mm_cmple_ps(t0a, t1a)) |
           (uint32_t)_mm_movemask_ps(_mm_cmple_ps(t0b, t1b)) << 4;
#else
    uint32_t mask = 0;
    for (int i = 0; i < TR_WBVH_WIDTH; ++i) {
        float t0 = tmin, t1 = tmax;
        for (int a = 0; a < 3; ++a) {
            t0 = tr_wbvh_max((n->bounds[r->near_row[a]][i] - r->o[a]) * r->inv[a], t0);
            t1 = tr_wbvh_min((n->bounds[r->far_row[a]][i] - r->o[a]) * r->inv[a], t1);
        }
        tnear[i] = t0;
        mask |= (uint32_t)(t0 <= t1) << i;
    }
    return mask;
#endif
}

/* Moller-Trumbore on four triangles (src/kernel/intersect.h, operation for operation):
 * returns the mask of lanes hit in (tmin, tmax) and their t, u, v. */
static inline uint32_t tr_wbvh_tri4_hits(const tr_wbvh_tri4 *p, const tr_wbvh_ray *r, float tmin,
                                         float tmax, float *t_out, float *u_out, float *v_out) {
#if defined(TR_WBVH_TRIS_128)
    const __m128 dx = _mm_set1_ps(r->d[0]), dy = _mm_set1_ps(r->d[1]), dz = _mm_set1_ps(r->d[2]);
    const __m128 e1x = _mm_load_ps(p->e1[0]), e1y = _mm_load_ps(p->e1[1]),
                 e1z = _mm_load_ps(p->e1[2]);
    const __m128 e2x = _mm_load_ps(p->e2[0]), e2y = _mm_load_ps(p->e2[1]),
                 e2z = _mm_load_ps(p->e2[2]);
    /* p = dir x e2 */
    __m128 px = _mm_sub_ps(_mm_mul_ps(dy, e2z), _mm_mul_ps(dz, e2y));
    __m128 py = _mm_sub_ps(_mm_mul_ps(dz, e2x), _mm_mul_ps(dx, e2z));
    __m128 pz = _mm_sub_ps(_mm_mul_ps(dx, e2y), _mm_mul_ps(dy, e2x));
    __m128 det =
        _mm_add_ps(_mm_add_ps(_mm_mul_ps(e1x, px), _mm_mul_ps(e1y, py)), _mm_mul_ps(e1z, pz));
    const __m128 abs_mask = _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff));
    __m128 ok = _mm_cmpgt_ps(_mm_and_ps(det, abs_mask), _mm_set1_ps(1e-12f));
    if (!_mm_movemask_ps(ok)) {
        return 0;
    }
    __m128 inv_det = _mm_div_ps(_mm_set1_ps(1.0f), det);
    __m128 sx = _mm_sub_ps(_mm_set1_ps(r->o[0]), _mm_load_ps(p->v0[0]));
    __m128 sy = _mm_sub_ps(_mm_set1_ps(r->o[1]), _mm_load_ps(p->v0[1]));
    __m128 sz = _mm_sub_ps(_mm_set1_ps(r->o[2]), _mm_load_ps(p->v0[2]));
    __m128 u = _mm_mul_ps(
        _mm_add_ps(_mm_add_ps(_mm_mul_ps(sx, px), _mm_mul_ps(sy, py)), _mm_mul_ps(sz, pz)),
        inv_det);
    const __m128 zero = _mm_setzero_ps(), one = _mm_set1_ps(1.0f);
    ok = _mm_and_ps(ok, _mm_and_ps(_mm_cmpge_ps(u, zero), _mm_cmple_ps(u, one)));
    if (!_mm_movemask_ps(ok)) {
        return 0;
    }
    /* q = s x e1 */
    __m128 qx = _mm_sub_ps(_mm_mul_ps(sy, e1z), _mm_mul_ps(sz, e1y));
    __m128 qy = _mm_sub_ps(_mm_mul_ps(sz, e1x), _mm_mul_ps(sx, e1z));
    __m128 qz = _mm_sub_ps(_mm_mul_ps(sx, e1y), _mm_mul_ps(sy, e1x));
    __m128 v = _mm_mul_ps(
        _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, qx), _mm_mul_ps(dy, qy)), _mm_mul_ps(dz, qz)),
        inv_det);
    ok = _mm_and_ps(ok, _mm_and_ps(_mm_cmpge_ps(v, zero), _mm_cmple_ps(_mm_add_ps(u, v), one)));
    __m128 t = _mm_mul_ps(
        _mm_add_ps(_mm_add_ps(_mm_mul_ps(e2x, qx), _mm_mul_ps(e2y, qy)), _mm_mul_ps(e2z, qz)),
        inv_det);
    ok = _mm_and_ps(
        ok, _mm_and_ps(_mm_cmpgt_ps(t, _mm_set1_ps(tmin)), _mm_cmplt_ps(t, _mm_set1_ps(tmax))));
    uint32_t mask = (uint32_t)_mm_movemask_ps(ok);
    if (mask) {
        _mm_storeu_ps(t_out, t);
        _mm_storeu_ps(u_out, u);
        _mm_storeu_ps(v_out, v);
    }
    return mask;
#else
    uint32_t mask = 0;
    for (int i = 0; i < 4; ++i) {
        const float e1x = p->e1[0][i], e1y = p->e1[1][i], e1z = p->e1[2][i];
        const float e2x = p->e2[0][i], e2y = p->e2[1][i], e2z = p->e2[2][i];
        const float dx = r->d[0], dy = r->d[1], dz = r->d[2];
        float px = dy * e2z - dz * e2y, py = dz * e2x - dx * e2z, pz = dx * e2y - dy * e2x;
        float det = e1x * px + e1y * py + e1z * pz;
        if (!((det < 0.0f ? -det : det) > 1e-12f)) {
            continue;
        }
        float inv_det = 1.0f / det;
        float sx = r->o[0] - p->v0[0][i], sy = r->o[1] - p->v0[1][i], sz = r->o[2] - p->v0[2][i];
        float u = (sx * px + sy * py + sz * pz) * inv_det;
        if (!(u >= 0.0f && u <= 1.0f)) {
            continue;
        }
        float qx = sy * e1z - sz * e1y, qy = sz * e1x - sx * e1z, qz = sx * e1y - sy * e1x;
        float v = (dx * qx + dy * qy + dz * qz) * inv_det;
        if (!(v >= 0.0f && u + v <= 1.0f)) {
            continue;
        }
        float t = (e2x * qx + e2y * qy + e2z * qz) * inv_det;
        if (!(t > tmin && t < tmax)) {
            continue;
        }
        t_out[i] = t;
        u_out[i] = u;
        v_out[i] = v;
        mask |= 1u << i;
    }
    return mask;
#endif
}

static inline int tr_wbvh_ctz(uint32_t x) {
    return __builtin_ctz(x);
}

static inline int tr_wbvh_traverse(const tr_wbvh *w, const tr_ray *ray, tr_hit *hit, int any_hit);

/* A top-level leaf: each instance's bottom level with the ray in its object space, t
 * limited to the closest hit so far (*tmax). Out of line, so that the bottom levels'
 * traversal below is inlined once here and the one-level loop stays as it was. */
static __attribute__((noinline)) int tr_wbvh_leaf_instances(const tr_wbvh *w, uint32_t first,
                                                            uint32_t packets, const tr_ray *ray,
                                                            float *tmax, tr_hit *hit, int any_hit) {
    int found = 0;
    for (uint32_t k = first; k < first + packets; ++k) {
        const tr_wbvh_tri4 *p = &w->packets[k];
        for (int lane = 0; lane < 4; ++lane) {
            const uint32_t id = p->index[lane];
            if (id == UINT32_MAX) {
                continue;
            }
            const tr_wbvh_instance *in = &w->instances[id];
            tr_ray lr = *ray;
            if (!in->identity) {
                const float *m = in->inv;
                const tr_vec3 o = ray->origin, d = ray->dir;
                lr.origin.x = m[0] * o.x + m[1] * o.y + m[2] * o.z + m[3];
                lr.origin.y = m[4] * o.x + m[5] * o.y + m[6] * o.z + m[7];
                lr.origin.z = m[8] * o.x + m[9] * o.y + m[10] * o.z + m[11];
                lr.dir.x = m[0] * d.x + m[1] * d.y + m[2] * d.z;
                lr.dir.y = m[4] * d.x + m[5] * d.y + m[6] * d.z;
                lr.dir.z = m[8] * d.x + m[9] * d.y + m[10] * d.z;
                lr.inv_dir.x = 1.0f / lr.dir.x;
                lr.inv_dir.y = 1.0f / lr.dir.y;
                lr.inv_dir.z = 1.0f / lr.dir.z;
            }
            lr.tmax = *tmax;
            tr_hit h;
            if (!tr_wbvh_traverse(in->blas, &lr, &h, any_hit)) {
                continue;
            }
            if (any_hit) {
                return 1;
            }
            *tmax = h.t;
            *hit = h;
            hit->triangle = in->tri_base + h.triangle;
            found = 1;
        }
    }
    return found;
}

/* Closest hit in (ray->tmin, ray->tmax), or with any_hit set the first hit found (hit
 * is then not written).
 * Children are visited nearest entry first; the others wait on a fixed-size stack with
 * their entry distance and are dropped once they start beyond the closest hit. */
static inline int tr_wbvh_traverse(const tr_wbvh *w, const tr_ray *ray, tr_hit *hit, int any_hit) {
    if (w->node_count == 0) {
        return 0;
    }
    tr_wbvh_ray r;
    tr_wbvh_ray_init(&r, ray);
    const float tmin = ray->tmin;
    float tmax = ray->tmax;
    uint32_t stack[TR_WBVH_STACK_SIZE];
    float stack_t[TR_WBVH_STACK_SIZE];
    int top = 0, found = 0;
    uint32_t cur = 0;
    for (;;) {
        if (cur & TR_WBVH_LEAF_BIT) {
            uint32_t first = cur & ((1u << TR_WBVH_LEAF_SHIFT) - 1u);
            uint32_t packets = (cur & ~TR_WBVH_LEAF_BIT) >> TR_WBVH_LEAF_SHIFT;
            if (w->instances) {
                if (tr_wbvh_leaf_instances(w, first, packets, ray, &tmax, hit, any_hit)) {
                    if (any_hit) {
                        return 1;
                    }
                    found = 1;
                }
                packets = 0;
            }
            for (uint32_t k = first; k < first + packets; ++k) {
                float t[4], u[4], v[4];
                const tr_wbvh_tri4 *p = &w->packets[k];
                uint32_t m = tr_wbvh_tri4_hits(p, &r, tmin, tmax, t, u, v);
                if (!m) {
                    continue;
                }
                if (any_hit) {
                    return 1;
                }
                /* The nearest lane; on equal distances the first, as one by one. */
                int best = tr_wbvh_ctz(m);
                for (m &= m - 1; m; m &= m - 1) {
                    int i = tr_wbvh_ctz(m);
                    best = t[i] < t[best] ? i : best;
                }
                tmax = t[best];
                hit->t = t[best];
                hit->triangle = p->index[best];
                hit->u = u[best];
                hit->v = v[best];
                found = 1;
            }
        } else {
            const tr_wbvh_node *n = &w->nodes[cur];
            float tn[TR_WBVH_WIDTH];
            uint32_t m = tr_wbvh_node_hits(n, &r, tmin, tmax, tn);
            if (m) {
                int i = tr_wbvh_ctz(m);
                m &= m - 1;
                if (!m) {
                    cur = n->child[i];
                    continue;
                }
                /* Two or more: sort them by entry distance (insertion, stable), push all
                 * but the nearest, farthest first, and go on with the nearest. */
                uint32_t ids[TR_WBVH_WIDTH];
                float ds[TR_WBVH_WIDTH];
                ids[0] = n->child[i];
                ds[0] = tn[i];
                /* Start loading every child hit (its first three cache lines) while the
                 * nearest is sorted out: +5% Mrays/s on 1.3 M triangles, neutral on
                 * small scenes (docs/benchmarks.md). */
                for (uint32_t pm = m | (1u << i); pm; pm &= pm - 1) {
                    uint32_t ch = n->child[tr_wbvh_ctz(pm)];
                    const char *addr =
                        (ch & TR_WBVH_LEAF_BIT)
                            ? (const char *)&w->packets[ch & ((1u << TR_WBVH_LEAF_SHIFT) - 1u)]
                            : (const char *)&w->nodes[ch];
                    __builtin_prefetch(addr);
                    __builtin_prefetch(addr + 64);
                    __builtin_prefetch(addr + 128);
                }
                int k = 1;
                for (; m; m &= m - 1) {
                    i = tr_wbvh_ctz(m);
                    float d = tn[i];
                    int j = k++;
                    while (j > 0 && ds[j - 1] > d) {
                        ids[j] = ids[j - 1];
                        ds[j] = ds[j - 1];
                        --j;
                    }
                    ids[j] = n->child[i];
                    ds[j] = d;
                }
                for (int j = k - 1; j > 0; --j) {
                    stack[top] = ids[j];
                    stack_t[top] = ds[j];
                    ++top;
                }
                cur = ids[0];
                continue;
            }
        }
        /* Pop the next subtree that starts before the closest hit found since. */
        do {
            if (top == 0) {
                return found;
            }
            --top;
        } while (stack_t[top] > tmax);
        cur = stack[top];
    }
}

#define TR_WBVH_NAME_(f, isa) f##_##isa
#define TR_WBVH_NAME(f, isa) TR_WBVH_NAME_(f, isa)

/* The two entry points of this file's ISA, any_hit folded into each. */
int TR_WBVH_NAME(tr_wbvh_intersect, TR_WBVH_TEMPLATE_SUFFIX)(const tr_wbvh *w, const tr_ray *ray,
                                                             tr_hit *hit) {
    return tr_wbvh_traverse(w, ray, hit, 0);
}

int TR_WBVH_NAME(tr_wbvh_occluded, TR_WBVH_TEMPLATE_SUFFIX)(const tr_wbvh *w, const tr_ray *ray) {
    return tr_wbvh_traverse(w, ray, NULL, 1);
}

#endif
