/* bvh.c - binned-SAH binary BVH build and refit. */
#include <stdlib.h>
#include <string.h>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "accel/accel_internal.h"
#include "trac0r/accel.h"
#include "trac0r/render.h"
#include "util/bigmem.h"

enum {
    BINS = 16,       /* SAH bins per axis (nodes of fewer triangles use one per triangle) */
    MAX_LEAF = 8,    /* a node this small may become a leaf when the SAH says so */
    FORCED_LEAF = 2, /* a node this small always becomes a leaf (for the wide BVH: below) */
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
    uint32_t forced_leaf; /* a node of at most this many entries becomes a leaf */
    int nodes_exact;      /* nodes is no larger than the tree (else the worst case's size) */
} builder;

/* The bins of one node on all three axes: each bin's box as two rows of four floats (the
 * fourth unused), so that the SSE2 binning loads and stores them whole, and its count. */
typedef struct bin_set {
    _Alignas(16) float min[3][BINS][4];
    _Alignas(16) float max[3][BINS][4];
    uint32_t count[3][BINS];
} bin_set;

static tr_aabb bin_box(const bin_set *s, int axis, int i) {
    const float *lo = s->min[axis][i], *hi = s->max[axis][i];
    tr_aabb b = {v3(lo[0], lo[1], lo[2]), v3(hi[0], hi[1], hi[2])};
    return b;
}

static void bin_set_box(bin_set *s, int axis, int i, tr_aabb b) {
    float *lo = s->min[axis][i], *hi = s->max[axis][i];
    lo[0] = b.min.x;
    lo[1] = b.min.y;
    lo[2] = b.min.z;
    hi[0] = b.max.x;
    hi[1] = b.max.y;
    hi[2] = b.max.z;
}

enum {
    /* Nodes with at least this many triangles are bounded and binned by all threads (the
     * top levels of a big build, before there are subtrees to share out). */
    PARALLEL_NODE_MIN = 1u << 16,
};

#if !defined(__SSE2__)
static int bin_index(float c, float lo, float scale, int nb) {
    int i = (int)((c - lo) * scale);
    return i < 0 ? 0 : i >= nb ? nb - 1 : i;
}
#endif

/* Bins refs[first, end) on all three axes into bins[axis][]; an axis that is not active
 * has lo = scale = 0 here (every triangle lands in bin 0, which is ignored), so the loop
 * has no branches on the axis. */
#if defined(__SSE2__)
/* With SSE2 (every x86-64 CPU) a record's box is two 128-bit loads, its centroid and its
 * three bin indices one operation each, and a bin's box two: the same operations as the
 * scalar code below, lane by lane (minps and maxps pick as tr_fminf and tr_fmaxf do for
 * operands that are not NaN; boxes never are), so the bins and the tree are the same. The
 * fourth lane (the record's index) is cleared on loading: read as a float, an index is a
 * denormal number, which would slow every operation on it by a microcode assist. */
static void bin_range(const builder *b, uint32_t first, uint32_t end, const float lo[3],
                      const float scale[3], int nb, bin_set *bins) {
    const __m128 vlo = _mm_setr_ps(lo[0], lo[1], lo[2], 0.0f);
    const __m128 vscale = _mm_setr_ps(scale[0], scale[1], scale[2], 0.0f);
    const __m128 half = _mm_set1_ps(0.5f);
    const __m128i zero = _mm_setzero_si128(), last = _mm_set1_epi32(nb - 1);
    const __m128 xyz = _mm_castsi128_ps(_mm_setr_epi32(-1, -1, -1, 0));
    for (uint32_t k = first; k < end; ++k) {
        const __m128 mn = _mm_and_ps(_mm_loadu_ps(&b->refs[k].min.x), xyz);
        const __m128 mx = _mm_and_ps(_mm_loadu_ps(&b->refs[k].max.x), xyz);
        const __m128 c = _mm_mul_ps(_mm_add_ps(mn, mx), half);
        __m128i bi = _mm_cvttps_epi32(_mm_mul_ps(_mm_sub_ps(c, vlo), vscale));
        bi = _mm_andnot_si128(_mm_cmplt_epi32(bi, zero), bi);
        const __m128i over = _mm_cmpgt_epi32(bi, last);
        bi = _mm_or_si128(_mm_and_si128(over, last), _mm_andnot_si128(over, bi));
        const int at[3] = {_mm_cvtsi128_si32(bi), _mm_cvtsi128_si32(_mm_shuffle_epi32(bi, 1)),
                           _mm_cvtsi128_si32(_mm_shuffle_epi32(bi, 2))};
        for (int axis = 0; axis < 3; ++axis) {
            float *lo4 = bins->min[axis][at[axis]], *hi4 = bins->max[axis][at[axis]];
            _mm_store_ps(lo4, _mm_min_ps(_mm_load_ps(lo4), mn));
            _mm_store_ps(hi4, _mm_max_ps(_mm_load_ps(hi4), mx));
            bins->count[axis][at[axis]]++;
        }
    }
}
#else
static void bin_range(const builder *b, uint32_t first, uint32_t end, const float lo[3],
                      const float scale[3], int nb, bin_set *bins) {
    for (uint32_t k = first; k < end; ++k) {
        const ref *r = &b->refs[k];
        const tr_vec3 c = ref_centroid(r);
        const tr_aabb box = ref_box(r);
        const int at[3] = {bin_index(c.x, lo[0], scale[0], nb), bin_index(c.y, lo[1], scale[1], nb),
                           bin_index(c.z, lo[2], scale[2], nb)};
        for (int axis = 0; axis < 3; ++axis) {
            bin_set_box(bins, axis, at[axis], box_union(bin_box(bins, axis, at[axis]), box));
            bins->count[axis][at[axis]]++;
        }
    }
}
#endif

/* The best of the nb - 1 planes between bins on each active axis (SAH cost relative to
 * one leaf of all `count` entries, in units of triangle tests, INFINITY if none splits
 * them); sets its axis and the last bin on its left. Each axis is swept from the right,
 * keeping each plane's right-hand area times count, then from the left, each plane's
 * cost TRAVERSAL_COST + (left area * left count + right area * right count) / node_area.
 * A tie goes to the lower axis, then to the plane further left. */
#if defined(__SSE2__)
/* The three axes' sweeps at once, one lane each: the boxes grown (one register per axis,
 * as bins store them) turned into one register per dimension, so that the three areas,
 * costs and comparisons are one operation each. Lane by lane these are the scalar code's
 * operations in its order (no contraction into fused multiply-adds: -ffp-contract=off), so
 * the costs are the same bits and the same plane wins. */
static __m128 sweep_areas(const __m128 mn[3], const __m128 mx[3]) {
    __m128 d0 = _mm_sub_ps(mx[0], mn[0]), d1 = _mm_sub_ps(mx[1], mn[1]);
    __m128 d2 = _mm_sub_ps(mx[2], mn[2]), d3 = _mm_setzero_ps();
    _MM_TRANSPOSE4_PS(d0, d1, d2, d3); /* now d0: every axis's box's x extent, d1: y, d2: z */
    const __m128 zero = _mm_setzero_ps();
    const __m128 full = _mm_and_ps(_mm_and_ps(_mm_cmpge_ps(d0, zero), _mm_cmpge_ps(d1, zero)),
                                   _mm_cmpge_ps(d2, zero));
    const __m128 sum =
        _mm_add_ps(_mm_add_ps(_mm_mul_ps(d0, d1), _mm_mul_ps(d1, d2)), _mm_mul_ps(d2, d0));
    /* An empty box (a negative or NaN extent) has area 0, as box_area gives it. */
    return _mm_and_ps(full, _mm_mul_ps(_mm_set1_ps(2.0f), sum));
}

static __m128i bin_counts(const bin_set *bins, int i) {
    return _mm_setr_epi32((int)bins->count[0][i], (int)bins->count[1][i], (int)bins->count[2][i],
                          0);
}

static float sweep_planes(const bin_set *bins, int nb, uint32_t count, float node_area,
                          const int active[3], int *best_axis, int *best_bin) {
    __m128 right_cost[BINS];
    __m128 mn[3], mx[3];
    for (int a = 0; a < 3; ++a) {
        mn[a] = _mm_set1_ps(INFINITY);
        mx[a] = _mm_set1_ps(-INFINITY);
    }
    __m128i n = _mm_setzero_si128();
    for (int i = nb - 1; i > 0; --i) {
        for (int a = 0; a < 3; ++a) {
            mn[a] = _mm_min_ps(mn[a], _mm_load_ps(bins->min[a][i]));
            mx[a] = _mm_max_ps(mx[a], _mm_load_ps(bins->max[a][i]));
        }
        n = _mm_add_epi32(n, bin_counts(bins, i));
        right_cost[i] = _mm_mul_ps(sweep_areas(mn, mx), _mm_cvtepi32_ps(n));
    }
    for (int a = 0; a < 3; ++a) {
        mn[a] = _mm_set1_ps(INFINITY);
        mx[a] = _mm_set1_ps(-INFINITY);
    }
    n = _mm_setzero_si128();
    const __m128i all = _mm_set1_epi32((int)count), none = _mm_setzero_si128();
    const __m128i on = _mm_setr_epi32(-active[0], -active[1], -active[2], 0);
    const __m128 trav = _mm_set1_ps(TRAVERSAL_COST), area = _mm_set1_ps(node_area);
    __m128 best = _mm_set1_ps(INFINITY);
    __m128i best_at = _mm_set1_epi32(-1);
    for (int i = 0; i < nb - 1; ++i) {
        for (int a = 0; a < 3; ++a) {
            mn[a] = _mm_min_ps(mn[a], _mm_load_ps(bins->min[a][i]));
            mx[a] = _mm_max_ps(mx[a], _mm_load_ps(bins->max[a][i]));
        }
        n = _mm_add_epi32(n, bin_counts(bins, i));
        const __m128 cost = _mm_add_ps(
            trav, _mm_div_ps(_mm_add_ps(_mm_mul_ps(sweep_areas(mn, mx), _mm_cvtepi32_ps(n)),
                                        right_cost[i + 1]),
                             area));
        /* A plane with every entry on one side splits nothing. */
        const __m128i splits =
            _mm_andnot_si128(_mm_or_si128(_mm_cmpeq_epi32(n, none), _mm_cmpeq_epi32(n, all)), on);
        const __m128i better = _mm_and_si128(splits, _mm_castps_si128(_mm_cmplt_ps(cost, best)));
        best = _mm_or_ps(_mm_and_ps(_mm_castsi128_ps(better), cost),
                         _mm_andnot_ps(_mm_castsi128_ps(better), best));
        best_at = _mm_or_si128(_mm_and_si128(better, _mm_set1_epi32(i)),
                               _mm_andnot_si128(better, best_at));
    }
    float lane[4];
    int at[4];
    _mm_storeu_ps(lane, best);
    _mm_storeu_si128((__m128i *)(void *)at, best_at);
    float result = INFINITY;
    for (int a = 0; a < 3; ++a) {
        if (lane[a] < result) {
            result = lane[a];
            *best_axis = a;
            *best_bin = at[a];
        }
    }
    return result;
}
#else
static float sweep_planes(const bin_set *bins, int nb, uint32_t count, float node_area,
                          const int active[3], int *best_axis, int *best_bin) {
    float best = INFINITY;
    for (int axis = 0; axis < 3; ++axis) {
        if (!active[axis]) {
            continue;
        }
        float right_cost[BINS];
        tr_aabb acc = box_empty();
        uint32_t n = 0;
        for (int i = nb - 1; i > 0; --i) {
            acc = box_union(acc, bin_box(bins, axis, i));
            n += bins->count[axis][i];
            right_cost[i] = box_area(acc) * (float)n;
        }
        acc = box_empty();
        n = 0;
        for (int i = 0; i < nb - 1; ++i) {
            acc = box_union(acc, bin_box(bins, axis, i));
            n += bins->count[axis][i];
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
    return best;
}
#endif

static void bins_clear(bin_set *bins, int nb) {
    for (int axis = 0; axis < 3; ++axis) {
        for (int i = 0; i < nb; ++i) {
            for (int l = 0; l < 4; ++l) {
                bins->min[axis][i][l] = INFINITY;
                bins->max[axis][i][l] = -INFINITY;
            }
            bins->count[axis][i] = 0;
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
    bin_set bins;
    bins_clear(&bins, nb);
    if (count >= PARALLEL_NODE_MIN) {
#pragma omp parallel num_threads(tr_default_threads())
        {
            bin_set local;
            bins_clear(&local, nb);
            const int64_t end = (int64_t)first + count;
#pragma omp for schedule(static) nowait
            for (int64_t k = first; k < end; k += 4096) {
                uint32_t stop = (uint32_t)(k + 4096 < end ? k + 4096 : end);
                bin_range(b, (uint32_t)k, stop, lo, scale, nb, &local);
            }
#pragma omp critical
            for (int axis = 0; axis < 3; ++axis) {
                for (int i = 0; i < nb; ++i) {
                    bin_set_box(&bins, axis, i,
                                box_union(bin_box(&bins, axis, i), bin_box(&local, axis, i)));
                    bins.count[axis][i] += local.count[axis][i];
                }
            }
        }
    } else {
        bin_range(b, first, first + count, lo, scale, nb, &bins);
    }
    best = sweep_planes(&bins, nb, count, node_area, active, best_axis, best_bin);
    if (best < INFINITY) {
        /* The children's boxes are the unions of their bins' boxes: the same minima and
         * maxima as a pass over their triangles would find, without that pass. */
        child[0] = child[1] = box_empty();
        for (int i = 0; i < nb; ++i) {
            const int side = i > *best_bin;
            child[side] = box_union(child[side], bin_box(&bins, *best_axis, i));
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

/* Partitions refs[i, j) by the chosen bin plane on `axis`, binning exactly as find_split
 * did: the entries of bins up to split_bin first. Returns where the right side starts and
 * sets both sides' centroid bounds, gathered on the way. */
#if defined(__SSE2__)
/* The same moves as the scalar code below, without its branch on the side, which a
 * processor cannot predict: every step swaps the entry at i with the one at i (left) or at
 * j - 1 (right), and both sides' bounds take the centroid or an infinity that leaves them
 * as they are (minps and maxps keep their first operand there, as tr_fminf does). */
static uint32_t partition(ref *refs, uint32_t i, uint32_t j, int axis, float lo, float scale,
                          int nb, int split_bin, tr_aabb *cl_out, tr_aabb *cr_out) {
    const __m128 xyz = _mm_castsi128_ps(_mm_setr_epi32(-1, -1, -1, 0));
    const __m128 half = _mm_set1_ps(0.5f), inf = _mm_set1_ps(INFINITY);
    const __m128 ninf = _mm_set1_ps(-INFINITY);
    __m128 lmin = inf, lmax = ninf, rmin = inf, rmax = ninf;
    while (i < j) {
        const float *mn = &refs[i].min.x, *mx = &refs[i].max.x;
        int bi = (int)(((mn[axis] + mx[axis]) * 0.5f - lo) * scale);
        bi = bi < 0 ? 0 : bi >= nb ? nb - 1 : bi;
        const uint32_t right = bi > split_bin;
        const __m128 a0 = _mm_loadu_ps(mn), a1 = _mm_loadu_ps(mx);
        const __m128 c = _mm_mul_ps(_mm_add_ps(_mm_and_ps(a0, xyz), _mm_and_ps(a1, xyz)), half);
        const __m128 r = _mm_castsi128_ps(_mm_set1_epi32(-(int)right));
        lmin = _mm_min_ps(lmin, _mm_or_ps(_mm_and_ps(r, inf), _mm_andnot_ps(r, c)));
        lmax = _mm_max_ps(lmax, _mm_or_ps(_mm_and_ps(r, ninf), _mm_andnot_ps(r, c)));
        rmin = _mm_min_ps(rmin, _mm_or_ps(_mm_andnot_ps(r, inf), _mm_and_ps(r, c)));
        rmax = _mm_max_ps(rmax, _mm_or_ps(_mm_andnot_ps(r, ninf), _mm_and_ps(r, c)));
        const uint32_t other = right ? j - 1 : i;
        float *omn = &refs[other].min.x, *omx = &refs[other].max.x;
        const __m128 b0 = _mm_loadu_ps(omn), b1 = _mm_loadu_ps(omx);
        _mm_storeu_ps(omn, a0);
        _mm_storeu_ps(omx, a1);
        _mm_storeu_ps(&refs[i].min.x, b0);
        _mm_storeu_ps(&refs[i].max.x, b1);
        j -= right;
        i += 1 - right;
    }
    float v[4][4];
    _mm_storeu_ps(v[0], lmin);
    _mm_storeu_ps(v[1], lmax);
    _mm_storeu_ps(v[2], rmin);
    _mm_storeu_ps(v[3], rmax);
    *cl_out = (tr_aabb){v3(v[0][0], v[0][1], v[0][2]), v3(v[1][0], v[1][1], v[1][2])};
    *cr_out = (tr_aabb){v3(v[2][0], v[2][1], v[2][2]), v3(v[3][0], v[3][1], v[3][2])};
    return i;
}
#else
static uint32_t partition(ref *refs, uint32_t i, uint32_t j, int axis, float lo, float scale,
                          int nb, int split_bin, tr_aabb *cl_out, tr_aabb *cr_out) {
    tr_aabb cl = box_empty(), cr = box_empty();
    while (i < j) {
        const tr_vec3 c = ref_centroid(&refs[i]);
        if (bin_index(axis_of(c, axis), lo, scale, nb) <= split_bin) {
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
    *cl_out = cl;
    *cr_out = cr;
    return i;
}
#endif

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
    if (t->count <= b->forced_leaf) {
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
        const float lo = axis_of(cbox.min, axis);
        const float scale = (float)nbins / (axis_of(cbox.max, axis) - lo);
        const uint32_t left = partition(b->refs, t->first, t->first + t->count, axis, lo, scale,
                                        nbins, split_bin, &child[0].cbox, &child[1].cbox);
        child[0].box = child_box[0];
        child[1].box = child_box[1];
        return left - t->first;
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
 * number of leaves. */
static uint32_t build_nodes(builder *b, task root, tr_bvh_node *nodes, uint32_t *node_count,
                            uint32_t *deepest) {
    /* Depth-first with the left child popped first: at most one pending sibling per
     * level, and the depth is below TR_BVH_STACK_SIZE. */
    task stack[2 * TR_BVH_STACK_SIZE + 2];
    uint32_t top = 0, leaves = 0;
    *node_count = 1;
    root.node = 0;
    stack[top++] = root;
    while (top > 0) {
        task t = stack[--top];
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
    PARALLEL_MIN = PARALLEL_NODE_MIN,   /* fewer triangles than this build on one thread */
    CUT_DEPTH = 4,                      /* the subtrees below this depth build independently */
    TOP_NODES = 2u << CUT_DEPTH,        /* more than the top levels' nodes */
    TOP_PLACES = (2u << CUT_DEPTH) - 1, /* the top levels and the cut, by place (below) */
};

/* A node of the top levels of a parallel build, or a subtree's root at the cut depth,
 * kept by its place in a complete binary tree (the children of place h at 2h + 1 and
 * 2h + 2) while the threads build them, and numbered after (number_top). */
typedef struct top_node {
    task t;
    tr_bvh_node node;
    enum { TOP_UNUSED, TOP_PENDING, TOP_LEAF, TOP_INNER, TOP_CUT } kind;
    uint32_t sub_count, sub_leaves, sub_depth; /* a subtree's (TOP_CUT) */
} top_node;

/* The region of the node array a subtree over refs[first, first + count) is built in: at
 * TOP_NODES + 2 * first, room for the 2 * count - 1 nodes it can have. Subtrees' runs of
 * refs do not overlap, so neither do their regions. */
static tr_bvh_node *subtree_region(const builder *b, uint32_t first) {
    return b->nodes + TOP_NODES + 2 * (size_t)first;
}

/* Splits node t's run into its children's tasks (split_node has set their bounds). */
static void child_tasks(const task *t, uint32_t left, task child[2]) {
    child[0].first = t->first;
    child[0].count = left;
    child[1].first = t->first + left;
    child[1].count = t->count - left;
    child[0].depth = child[1].depth = t->depth + 1;
}

/* Builds the node at place h, whose task is set: at the cut depth a subtree in its region,
 * above it a split, which sets its children's places' tasks. Each node writes only its own
 * place, run of refs and region, and its split depends on its refs alone, so which thread
 * builds which node changes nothing. */
static void build_top(builder *b, top_node *top, uint32_t h) {
    top_node *tn = &top[h];
    const task t = tn->t;
    if (t.depth == CUT_DEPTH) {
        tn->kind = TOP_CUT;
        tn->sub_leaves =
            build_nodes(b, t, subtree_region(b, t.first), &tn->sub_count, &tn->sub_depth);
        return;
    }
    task child[2];
    const uint32_t left = split_node(b, &t, &tn->node, child);
    if (left == 0) {
        tn->kind = TOP_LEAF;
        return;
    }
    tn->kind = TOP_INNER;
    child_tasks(&t, left, child);
    top[2 * h + 1].t = child[0];
    top[2 * h + 2].t = child[1];
    top[2 * h + 1].kind = top[2 * h + 2].kind = TOP_PENDING;
}

/* Numbers the top levels as build_nodes does (depth first, left child first, a node's
 * children numbered when it is visited), writes their nodes, and lists the cut's subtrees
 * in that order (their runs of refs ascending): their places in cut_place[] and the index
 * each one's root takes in cut_node[]. Returns the number of nodes numbered. */
static uint32_t number_top(builder *b, const top_node *top, uint32_t *cut_place, uint32_t *cut_node,
                           uint32_t *cuts, uint32_t *leaves, uint32_t *deepest) {
    uint32_t place[CUT_DEPTH + 2], index[CUT_DEPTH + 2]; /* one pending sibling per level */
    uint32_t sp = 0, count = 1;
    place[sp] = 0;
    index[sp++] = 0;
    while (sp > 0) {
        --sp;
        const uint32_t h = place[sp], i = index[sp];
        const top_node *tn = &top[h];
        if (tn->kind == TOP_CUT) {
            cut_place[*cuts] = h;
            cut_node[(*cuts)++] = i;
            continue;
        }
        b->nodes[i] = tn->node;
        if (tn->kind == TOP_LEAF) {
            ++*leaves;
            *deepest = tn->t.depth > *deepest ? tn->t.depth : *deepest;
            continue;
        }
        b->nodes[i].left_first = count;
        b->nodes[i].count = 0;
        place[sp] = 2 * h + 2;
        index[sp++] = count + 1;
        place[sp] = 2 * h + 1;
        index[sp++] = count;
        count += 2;
    }
    return count;
}

/* Builds the tree over refs[0, n) into b->nodes. A large tree is built by all threads:
 * its root split with all of them binning, then level by level the nodes below it, each
 * level's shared out one node per thread at a time, down to depth CUT_DEPTH, whose up to
 * 16 nodes are built as whole subtrees, each in a region of the node array of its own
 * (subtree_region); the top is numbered and the subtrees moved into place after, in a
 * fixed order. (Level by level with parallel loops rather than OpenMP tasks: the web
 * build's OpenMP runtime, web/omp, has no tasks.) The result is the serial build's node for node,
 * whatever the thread count, so no image rendered through it depends on that count. */
static int build_tree(builder *b, uint32_t n, uint32_t *leaves_out, uint32_t *depth_out) {
    task root = {.node = 0, .first = 0, .count = n, .depth = 0};
    range_bounds(b, 0, n, &root.box, &root.cbox);
    uint32_t count = 0, leaves = 0, deepest = 0;
    if (n < PARALLEL_MIN) {
        leaves = build_nodes(b, root, b->nodes, &count, &deepest);
        b->node_count = count;
        *leaves_out = leaves;
        *depth_out = deepest;
        return TR_OK;
    }
    top_node top[TOP_PLACES];
    memset(top, 0, sizeof top);
    top[0].t = root;
    build_top(b, top, 0); /* all threads bin the root (find_split) */
    for (uint32_t depth = 1; depth <= CUT_DEPTH; ++depth) {
        /* The level's nodes, split (or, at the cut, built) one per thread at a time. */
        uint32_t level[1u << CUT_DEPTH], nodes = 0;
        for (uint32_t h = (1u << depth) - 1; h < (2u << depth) - 1; ++h) {
            if (top[h].kind == TOP_PENDING) {
                level[nodes++] = h;
            }
        }
#pragma omp parallel for num_threads(tr_default_threads()) schedule(dynamic, 1) if (nodes > 1)
        for (int k = 0; k < (int)nodes; ++k) {
            build_top(b, top, level[k]);
        }
    }
    uint32_t cut_place[1u << CUT_DEPTH], cut_node[1u << CUT_DEPTH], cuts = 0;
    count = number_top(b, top, cut_place, cut_node, &cuts, &leaves, &deepest);
    /* The tree's exact size: the top's nodes and each subtree's but its root, which the
     * top numbered. */
    uint32_t total = count;
    for (uint32_t k = 0; k < cuts; ++k) {
        total += top[cut_place[k]].sub_count - 1;
    }
    /* The nodes go into an array of that size where a kept block holds them (a rebuild),
     * and the worst-case array the subtrees were built in goes back whole to the kept
     * blocks, for the next build to take: shrunk in place, it would be too small for that.
     * Otherwise (a first build) the nodes are moved down in the worst-case array, which
     * bvh_build shrinks after: that writes no memory new to the process. */
    tr_bvh_node *out = tr_bigmem_take((size_t)total * sizeof *out);
    const int in_place = out == NULL;
    if (in_place) {
        out = b->nodes;
    } else {
        memcpy(out, b->nodes, (size_t)count * sizeof *out);
    }
    /* Each subtree's root takes the slot its parent gave it; the rest follows the nodes so
     * far, with child links moved from local index c >= 1 to count + c - 1. In place, that
     * end lies at or below the subtree's region (the subtrees before it had at most twice
     * as many nodes as refs, and the top fewer than TOP_NODES), so copying forward, one
     * subtree after the other, never overwrites a node not yet copied; into another array
     * the subtrees are independent, and all threads share them out. */
    uint32_t offset[1u << CUT_DEPTH];
    for (uint32_t k = 0; k < cuts; ++k) {
        const top_node *tn = &top[cut_place[k]];
        offset[k] = count - 1;
        count += tn->sub_count - 1;
        leaves += tn->sub_leaves;
        deepest = tn->sub_depth > deepest ? tn->sub_depth : deepest;
    }
#pragma omp parallel for num_threads(tr_default_threads()) schedule(dynamic, 1) if (!in_place)
    for (int k = 0; k < (int)cuts; ++k) {
        const top_node *tn = &top[cut_place[k]];
        const tr_bvh_node *region = subtree_region(b, tn->t.first);
        const uint32_t off = offset[k];
        for (uint32_t i = 0; i < tn->sub_count; ++i) {
            tr_bvh_node nd = region[i];
            if (nd.count == 0) {
                nd.left_first += off;
            }
            out[i == 0 ? cut_node[k] : off + i] = nd;
        }
    }
    if (!in_place) {
        tr_bigmem_free(b->nodes);
        b->nodes = out;
        b->nodes_exact = 1;
    }
    b->node_count = count;
    *leaves_out = leaves;
    *depth_out = deepest;
    return TR_OK;
}

/* The leaf-order triangle copy the traversal reads. */
static void bvh_fill_tris(tr_bvh *bvh, const tr_triangle *tris) {
    const int64_t n = bvh->index_count;
#pragma omp parallel for num_threads(tr_default_threads()) schedule(static) if (n >= PARALLEL_MIN)
    for (int64_t k = 0; k < n; ++k) {
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
                     const uint8_t *skip, uint32_t forced_leaf, tr_error *err) {
    double t0 = tr_time_now();
    memset(bvh, 0, sizeof *bvh);
    builder b;
    memset(&b, 0, sizeof b);
    b.forced_leaf = forced_leaf;
    /* The big arrays on huge pages (bigmem.h): their first writes' page faults took a third
     * to a half of a big build's time. The records' block is sized for the leaf-order
     * triangle copy too, which takes it over when the records are done with: memory
     * written for the first time costs most (on a virtual machine whose host takes freed
     * memory back, about 1.2 ms per MiB against 0.07 ms for memory just freed; measured
     * in docs/log/2026-benchmarks.md), and this is 32 bytes per triangle of it. */
    const size_t per_ref = sizeof(ref) > sizeof(tr_bvh_tri) ? sizeof(ref) : sizeof(tr_bvh_tri);
    b.refs = tr_bigmem_malloc((size_t)(n ? n : 1) * per_ref);
    uint32_t *indices = tr_bigmem_malloc((size_t)(n ? n : 1) * sizeof *indices);
    /* A binary tree over m leaves of >= 1 triangle has at most 2m - 1 nodes; the
     * parallel build leaves room for the top levels before its subtrees' regions. */
    b.nodes = tr_bigmem_malloc((size_t)(2 * (uint64_t)n + TOP_NODES) * sizeof *b.nodes);
    if (!b.refs || !indices || !b.nodes) {
        tr_bigmem_free(b.refs);
        tr_bigmem_free(indices);
        tr_bigmem_free(b.nodes);
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY,
                            "out of memory building a BVH over %u triangles", n);
    }
    /* Every entry's record in its own slot, by all threads; those that can never be hit
     * marked (pad = 1) and squeezed out after, in order, where there are any. */
    int64_t bad = 0;
#pragma omp parallel for num_threads(tr_default_threads()) schedule(static)                        \
    reduction(+ : bad) if (n >= PARALLEL_MIN)
    for (int64_t k = 0; k < (int64_t)n; ++k) {
        const uint32_t i = (uint32_t)k;
        tr_aabb box;
        int hit = 1;
        if (boxes) {
            /* An empty or non-finite box (an instance of nothing) can never be hit. */
            box = boxes[i];
            hit = box.min.x <= box.max.x && box.min.y <= box.max.y && box.min.z <= box.max.z &&
                  v3_is_finite(box.min) && v3_is_finite(box.max);
        } else {
            const tr_triangle *t = &tris[i];
            box = tri_box(t);
            hit = !(skip && skip[i]) && t->area > 0.0f && v3_is_finite(t->v0) &&
                  v3_is_finite(t->v1) && v3_is_finite(t->v2);
        }
        b.refs[i] = (ref){box.min, i, box.max, hit ? 0u : 1u};
        bad += !hit;
    }
    uint32_t m = n;
    if (bad > 0) {
        m = 0;
        for (uint32_t i = 0; i < n; ++i) {
            if (b.refs[i].pad == 0) {
                b.refs[m++] = b.refs[i];
            }
        }
    }
    uint32_t leaves = 0, depth = 0;
    int rc = m > 0 ? build_tree(&b, m, &leaves, &depth) : TR_OK;
#pragma omp parallel for num_threads(tr_default_threads()) schedule(static) if (m >= PARALLEL_MIN)
    for (int64_t k = 0; k < (int64_t)m; ++k) {
        indices[k] = b.refs[k].index;
    }
    /* The leaf-order triangle copy takes over the records' block, whose pages are mapped
     * already (growing the records' array with realloc instead came back on small pages:
     * 12 800 page faults and 177 ms of a 1.3 M-triangle build). Entries squeezed out are
     * given back; shrinking a block does not move it. */
    tr_bvh_tri *leaf_tris = (tr_bvh_tri *)(void *)b.refs;
    if (m < n) {
        void *smaller = realloc(b.refs, (size_t)(m ? m : 1) * per_ref);
        leaf_tris = smaller ? smaller : leaf_tris;
    }
    if (rc != TR_OK) {
        tr_bigmem_free(leaf_tris);
        tr_bigmem_free(b.nodes);
        tr_bigmem_free(indices);
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
    if (!b.nodes_exact) {
        tr_bvh_node *shrunk = realloc(bvh->nodes, (size_t)(bvh->node_count ? bvh->node_count : 1) *
                                                      sizeof *bvh->nodes);
        if (shrunk) {
            bvh->nodes = shrunk;
        }
    }
    bvh->tris = leaf_tris;
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
    return bvh_build(bvh, tris, NULL, n, NULL, FORCED_LEAF, err);
}

int tr_bvh_build_wide(tr_bvh *bvh, const tr_triangle *tris, uint32_t n, const uint8_t *skip,
                      tr_error *err) {
    return bvh_build(bvh, tris, NULL, n, skip, TR_WBVH_LEAF_MERGE, err);
}

int tr_bvh_build_boxes(tr_bvh *bvh, const tr_aabb *boxes, uint32_t n, tr_error *err) {
    return bvh_build(bvh, NULL, boxes, n, NULL, FORCED_LEAF, err);
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
    tr_bigmem_free(bvh->nodes);
    tr_bigmem_free(bvh->indices);
    tr_bigmem_free(bvh->tris);
    memset(bvh, 0, sizeof *bvh);
}
