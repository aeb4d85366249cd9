/* light_tree.c - the light tree next-event estimation walks in scenes with many emitters
 * (kernel/light_tree.h), built over the emitter table at commit.
 *
 * C. Conty Estevez and C. Kulla, "Importance Sampling of Many Lights with Adaptive Tree
 * Splitting", 2018: a binary tree, top down, each node split where the surface area
 * orientation heuristic (their SAOH) is least: for the two halves, power x
 * M_omega (their solid-angle measure of the orientation cone) x box
 * surface area, times the ratio of the box's longest side to its side along the split
 * axis (which keeps thin boxes from being cut along their short side). Candidates are
 * every position in the centroid order along each axis, from prefix and suffix bounds,
 * so a node costs four sorts (the last for the winning axis; two above
 * SAOH_ALL_AXES_MAX emitters, which try one axis). One emitter per leaf: the leaf's
 * probability is the emitter's. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "kernel/light.h"
#include "scene/scene_internal.h"

#define PI_D 3.14159265358979323846
/* Below this depth the heuristic chooses; beyond it (a degenerate arrangement that keeps
 * peeling single emitters off) the median, so the recursion stays shallow. */
#define SAOH_MAX_DEPTH 48
/* Nodes with more emitters than this try one axis (see build). */
#define SAOH_ALL_AXES_MAX 1024u

/* An orientation cone: normals within theta_o of axis, light leaving up to theta_e beyond
 * them. empty for the bounds of nothing. */
typedef struct cone {
    double axis[3];
    double theta_o, theta_e;
    int empty;
} cone;

/* What a node bounds: box, power, cone. */
typedef struct bounds {
    double lo[3], hi[3];
    double power;
    cone c;
} bounds;

typedef struct sort_key {
    float key;
    uint32_t prim;
} sort_key;

typedef struct builder {
    const bounds *prim; /* one per emitter */
    uint32_t *order;    /* emitter indices, permuted by the build */
    sort_key *keys;
    bounds *prefix, *suffix;
    tr_light_node *nodes;
    uint32_t *leaf;
    uint32_t next; /* the next free node */
    /* The least extent saoh_cost gives a box's side: 0 over emitters alone; with point
     * and spot lights, whose boxes have no size (and those of points in a row or a plane
     * no area), a thousandth of the root's longest side, so that the cost still sees
     * how far apart they are instead of peeling single lights off at cost 0. */
    double min_extent;
} builder;

static double dot3(const double *a, const double *b) {
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static void normalize3(double *a) {
    double l = sqrt(dot3(a, a));
    if (l > 0.0) {
        a[0] /= l;
        a[1] /= l;
        a[2] /= l;
    }
}

/* The smallest cone (of this construction) holding both, as Conty Estevez and Kulla
 * merge orientation cones (pbrt-v4's DirectionCone Union does the same). The wider
 * cone's axis is turned towards the other's, in their common plane, by just enough to
 * take it in. */
static cone cone_union(cone a, cone b) {
    if (a.empty) {
        return b;
    }
    if (b.empty) {
        return a;
    }
    if (b.theta_o > a.theta_o) {
        cone t = a;
        a = b;
        b = t;
    }
    double theta_e = fmax(a.theta_e, b.theta_e);
    double theta_d = acos(fmin(fmax(dot3(a.axis, b.axis), -1.0), 1.0));
    cone r = a;
    r.theta_e = theta_e;
    if (fmin(theta_d + b.theta_o, PI_D) <= a.theta_o) {
        return r;
    }
    double theta_o = 0.5 * (a.theta_o + theta_d + b.theta_o);
    if (theta_o >= PI_D) {
        r.theta_o = PI_D;
        return r;
    }
    double k[3] = {a.axis[1] * b.axis[2] - a.axis[2] * b.axis[1],
                   a.axis[2] * b.axis[0] - a.axis[0] * b.axis[2],
                   a.axis[0] * b.axis[1] - a.axis[1] * b.axis[0]};
    if (!(sqrt(dot3(k, k)) > 1e-12)) { /* opposite axes: no plane to turn in */
        r.theta_o = PI_D;
        return r;
    }
    normalize3(k);
    /* Rodrigues' rotation of a.axis about k (perpendicular to it) by theta_r. */
    double theta_r = theta_o - a.theta_o;
    double kxa[3] = {k[1] * a.axis[2] - k[2] * a.axis[1], k[2] * a.axis[0] - k[0] * a.axis[2],
                     k[0] * a.axis[1] - k[1] * a.axis[0]};
    for (int i = 0; i < 3; ++i) {
        r.axis[i] = a.axis[i] * cos(theta_r) + kxa[i] * sin(theta_r);
    }
    normalize3(r.axis);
    r.theta_o = theta_o;
    return r;
}

static bounds bounds_empty(void) {
    bounds b;
    for (int i = 0; i < 3; ++i) {
        b.lo[i] = INFINITY;
        b.hi[i] = -INFINITY;
    }
    b.power = 0.0;
    memset(&b.c, 0, sizeof b.c);
    b.c.empty = 1;
    return b;
}

static bounds bounds_union(const bounds *a, const bounds *b) {
    bounds r;
    for (int i = 0; i < 3; ++i) {
        r.lo[i] = fmin(a->lo[i], b->lo[i]);
        r.hi[i] = fmax(a->hi[i], b->hi[i]);
    }
    r.power = a->power + b->power;
    r.c = cone_union(a->c, b->c);
    return r;
}

/* The SAOH cost of a node with bounds b, split along `axis`. */
static double saoh_cost(const bounds *b, int axis, double min_extent) {
    double ext[3], emax = 0.0;
    for (int i = 0; i < 3; ++i) {
        ext[i] = fmax(b->hi[i] - b->lo[i], min_extent);
        emax = fmax(emax, ext[i]);
    }
    double area = 2.0 * (ext[0] * ext[1] + ext[1] * ext[2] + ext[2] * ext[0]);
    double kr = ext[axis] > 0.0 ? emax / ext[axis] : 1.0;
    double to = b->c.theta_o, tw = fmin(b->c.theta_o + b->c.theta_e, PI_D);
    double m_omega =
        2.0 * PI_D * (1.0 - cos(to)) +
        0.5 * PI_D * (2.0 * tw * sin(to) - cos(to - 2.0 * tw) - 2.0 * to * sin(to) + cos(to));
    return b->power * m_omega * area * kr;
}

static int key_less(const void *a, const void *b) {
    const sort_key *x = a, *y = b;
    if (x->key != y->key) {
        return x->key < y->key ? -1 : 1;
    }
    return x->prim < y->prim ? -1 : (x->prim > y->prim);
}

/* Sorts order[lo, hi) by centroid along axis into bd->keys. */
static void sort_axis(builder *bd, uint32_t lo, uint32_t hi, int axis) {
    for (uint32_t i = lo; i < hi; ++i) {
        const bounds *p = &bd->prim[bd->order[i]];
        bd->keys[i - lo].key = (float)(0.5 * (p->lo[axis] + p->hi[axis]));
        bd->keys[i - lo].prim = bd->order[i];
    }
    qsort(bd->keys, hi - lo, sizeof *bd->keys, key_less);
}

static void store_node(tr_light_node *n, const bounds *b, uint32_t parent) {
    /* The box in float, then its centre and half-diagonal (the radius of the sphere around
     * it) in float arithmetic. */
    const tr_vec3 lo = v3((float)b->lo[0], (float)b->lo[1], (float)b->lo[2]);
    const tr_vec3 hi = v3((float)b->hi[0], (float)b->hi[1], (float)b->hi[2]);
    const tr_vec3 hd = v3_scale(v3_sub(hi, lo), 0.5f);
    n->centre = v3_scale(v3_add(lo, hi), 0.5f);
    n->r2 = v3_dot(hd, hd);
    n->r = sqrtf(n->r2);
    n->axis = v3((float)b->c.axis[0], (float)b->c.axis[1], (float)b->c.axis[2]);
    /* A little wider than built, so that rounding the axis to float never narrows the
     * cone past an emitter's normal. */
    n->cos_o = (float)cos(fmin(b->c.theta_o + 1e-5, PI_D));
    n->sin_o = sqrtf(fmaxf(0.0f, 1.0f - n->cos_o * n->cos_o));
    n->cos_e = (float)cos(b->c.theta_e);
    n->power = (float)b->power;
    n->parent = parent;
}

/* Builds node `node` over order[lo, hi) (at least one emitter). */
static void build(builder *bd, uint32_t node, uint32_t parent, uint32_t lo, uint32_t hi,
                  int depth) {
    bounds all = bounds_empty();
    for (uint32_t i = lo; i < hi; ++i) {
        all = bounds_union(&all, &bd->prim[bd->order[i]]);
    }
    tr_light_node *n = &bd->nodes[node];
    store_node(n, &all, parent);
    const uint32_t count = hi - lo;
    if (count == 1) {
        n->child = bd->order[lo] | TR_LIGHT_LEAF;
        bd->leaf[bd->order[lo]] = node;
        return;
    }
    uint32_t split = count / 2; /* the median of the longest axis unless the SAOH says */
    int best_axis = -1;
    double best = INFINITY;
    /* Large nodes (an emissive mesh) try only the axis along which the centroids spread
     * most: the cone unions of the sweeps are the build's cost. */
    int only = -1;
    if (count > SAOH_ALL_AXES_MAX) {
        double ext[3] = {0.0, 0.0, 0.0};
        for (int axis = 0; axis < 3; ++axis) {
            double cmin = INFINITY, cmax = -INFINITY;
            for (uint32_t i = lo; i < hi; ++i) {
                const bounds *p = &bd->prim[bd->order[i]];
                double c = 0.5 * (p->lo[axis] + p->hi[axis]);
                cmin = fmin(cmin, c);
                cmax = fmax(cmax, c);
            }
            ext[axis] = cmax - cmin;
        }
        only = ext[1] > ext[0] ? (ext[2] > ext[1] ? 2 : 1) : (ext[2] > ext[0] ? 2 : 0);
    }
    if (depth < SAOH_MAX_DEPTH) {
        for (int axis = 0; axis < 3; ++axis) {
            if (only >= 0 && axis != only) {
                continue;
            }
            sort_axis(bd, lo, hi, axis);
            if (!(bd->keys[count - 1].key > bd->keys[0].key)) {
                continue; /* every centroid in one plane across this axis */
            }
            bd->prefix[0] = bd->prim[bd->keys[0].prim];
            for (uint32_t i = 1; i < count; ++i) {
                bd->prefix[i] = bounds_union(&bd->prefix[i - 1], &bd->prim[bd->keys[i].prim]);
            }
            bd->suffix[count - 1] = bd->prim[bd->keys[count - 1].prim];
            for (uint32_t i = count - 1; i-- > 0;) {
                bd->suffix[i] = bounds_union(&bd->suffix[i + 1], &bd->prim[bd->keys[i].prim]);
            }
            for (uint32_t i = 1; i < count; ++i) {
                if (bd->keys[i].key == bd->keys[i - 1].key) {
                    continue; /* equal centroids stay on one side */
                }
                double c = saoh_cost(&bd->prefix[i - 1], axis, bd->min_extent) +
                           saoh_cost(&bd->suffix[i], axis, bd->min_extent);
                if (c < best) {
                    best = c;
                    best_axis = axis;
                    split = i;
                }
            }
        }
    }
    if (best_axis < 0) {
        best_axis = 0;
        for (int i = 1; i < 3; ++i) {
            if (all.hi[i] - all.lo[i] > all.hi[best_axis] - all.lo[best_axis]) {
                best_axis = i;
            }
        }
        split = count / 2;
    }
    /* The winning axis's order once more (the sort is deterministic: ties by index). */
    sort_axis(bd, lo, hi, best_axis);
    for (uint32_t i = 0; i < count; ++i) {
        bd->order[lo + i] = bd->keys[i].prim;
    }
    const uint32_t c = bd->next;
    bd->next += 2;
    n->child = c;
    build(bd, c, node, lo, lo + split, depth + 1);
    build(bd, c + 1, node, lo + split, hi, depth + 1);
}

void tr_scene_free_light_tree(tr_scene *s) {
    free(s->light_nodes);
    free(s->light_leaf);
    s->light_nodes = NULL;
    s->light_leaf = NULL;
    s->light_node_count = 0;
    s->light_tree_punctual = 0;
}

/* The bounds of a point or spot light as a leaf of the tree: a point (the box of no
 * size) of power I, the mean of its intensity's channels, which is what an emitter's
 * weight is along its normal (radiance times area), so that both are weighed alike by
 * the distance. A point light sends it every way (theta_o = pi); a spot within its outer
 * cone, and nothing beyond (theta_e: a hair above 0, so that the kernel's strict test
 * cos theta' > cos theta_e still admits the cone's inside, where theta' = 0). */
static void punctual_bounds(const tr_punctual *l, bounds *b) {
    const double pos[3] = {l->pos.x, l->pos.y, l->pos.z};
    for (int i = 0; i < 3; ++i) {
        b->lo[i] = pos[i];
        b->hi[i] = pos[i];
    }
    b->power = ((double)l->intensity.x + l->intensity.y + l->intensity.z) / 3.0;
    b->c.axis[0] = l->dir.x;
    b->c.axis[1] = l->dir.y;
    b->c.axis[2] = l->dir.z;
    normalize3(b->c.axis);
    if (l->type == TR_PUNCTUAL_SPOT) {
        b->c.theta_o = acos(fmin(fmax((double)l->cos_outer, -1.0), 1.0));
        b->c.theta_e = 1e-3;
    } else {
        b->c.theta_o = PI_D;
        b->c.theta_e = 0.5 * PI_D;
    }
    b->c.empty = 0;
}

int tr_scene_build_light_tree(tr_scene *s, tr_error *err) {
    tr_scene_free_light_tree(s);
    /* Leaves: the emitters 0..light_count-1, then, where the tree holds them, the point
     * and spot lights as light_count + their index into s->punctual (directional lights,
     * which no box bounds, keep a slot but no leaf: they are sampled at every vertex, as
     * the sun is). n counts the leaves, slots the leaf table's entries. */
    const uint32_t punct = tr_scene_light_tree_punctual(s) ? s->punctual_count : 0u;
    const uint32_t slots = s->light_count + punct;
    uint32_t n = s->light_count;
    for (uint32_t j = 0; j < punct; ++j) {
        n += s->punctual[j].type != TR_PUNCTUAL_DIRECTIONAL;
    }
    if (n == 0) {
        return TR_OK;
    }
    builder bd;
    memset(&bd, 0, sizeof bd);
    bounds *prim = malloc((size_t)slots * sizeof *prim);
    bd.order = malloc((size_t)n * sizeof *bd.order);
    bd.keys = malloc((size_t)n * sizeof *bd.keys);
    bd.prefix = malloc((size_t)n * sizeof *bd.prefix);
    bd.suffix = malloc((size_t)n * sizeof *bd.suffix);
    bd.nodes = calloc(2 * (size_t)n - 1, sizeof *bd.nodes);
    bd.leaf = calloc(slots, sizeof *bd.leaf);
    int ok = prim && bd.order && bd.keys && bd.prefix && bd.suffix && bd.nodes && bd.leaf;
    if (ok) {
        for (uint32_t k = 0; k < s->light_count; ++k) {
            const tr_triangle *t = &s->triangles[s->lights[k]];
            const tr_material *m = &s->materials[t->material];
            bounds *b = &prim[k];
            const float *v[3] = {&t->v0.x, &t->v1.x, &t->v2.x};
            for (int i = 0; i < 3; ++i) {
                b->lo[i] = fminf(fminf(v[0][i], v[1][i]), v[2][i]);
                b->hi[i] = fmaxf(fmaxf(v[0][i], v[1][i]), v[2][i]);
            }
            b->power = tr_light_weight(m, t->area);
            b->c.axis[0] = t->normal.x;
            b->c.axis[1] = t->normal.y;
            b->c.axis[2] = t->normal.z;
            normalize3(b->c.axis);
            /* One-sided triangles emit on their normal's side: within pi/2 of it. */
            b->c.theta_o = (m->flags & TR_MATERIAL_TWO_SIDED) ? PI_D : 0.0;
            b->c.theta_e = 0.5 * PI_D;
            b->c.empty = 0;
            bd.order[k] = k;
        }
        uint32_t k = s->light_count;
        for (uint32_t j = 0; j < punct; ++j) {
            if (s->punctual[j].type != TR_PUNCTUAL_DIRECTIONAL) {
                punctual_bounds(&s->punctual[j], &prim[s->light_count + j]);
                bd.order[k++] = s->light_count + j;
            }
        }
        bd.prim = prim;
        if (punct > 0u) {
            bounds all = bounds_empty();
            for (uint32_t i = 0; i < n; ++i) {
                all = bounds_union(&all, &prim[bd.order[i]]);
            }
            for (int i = 0; i < 3; ++i) {
                bd.min_extent = fmax(bd.min_extent, 1e-3 * (all.hi[i] - all.lo[i]));
            }
        }
        bd.next = 1;
        build(&bd, 0, 0, 0, n, 0);
    }
    free(prim);
    free(bd.keys);
    free(bd.prefix);
    free(bd.suffix);
    free(bd.order);
    if (!ok) {
        free(bd.nodes);
        free(bd.leaf);
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY,
                            "out of memory building the light tree (%u emitters)", n);
    }
    s->light_nodes = bd.nodes;
    s->light_leaf = bd.leaf;
    s->light_node_count = 2 * n - 1;
    s->light_tree_punctual = punct;
    return TR_OK;
}
