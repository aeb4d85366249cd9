/* light_tree.h - picking an emitter for a shading point through the light tree.
 *
 * C. Conty Estevez and C. Kulla, "Importance Sampling of Many Lights with Adaptive Tree
 * Splitting", Proc. ACM Comput. Graph. Interact. Tech. 1(2), 2018: a binary tree over the
 * emissive triangles whose nodes bound the position (box), the power and the orientation
 * (a cone of normals, and how far beyond it light leaves) of the emitters below. From the
 * root down, the walk steps into each child with probability proportional to the child's
 * importance for the shading point: an upper bound of the light it can send there, power
 * over squared distance times the cosine of the smallest angle between the emitters'
 * possible normals and the direction to the point. Without the paper's splitting (one
 * light per next-event sample), so the choice is one pass down the tree and its
 * probability the product of the branch probabilities along the way, which
 * tr_light_tree_prob finds again from the leaf up for MIS.
 *
 * The receiver's normal nr (the shading normal; zero where the caller has none) bounds the
 * cosine at the receiver as well, on both sides of the surface.
 *
 * Where the scene has many point and spot lights (src/scene/light_tree.c), the tree holds
 * them too, as leaves light_count + their index into s->punctual: a point of power I with
 * every orientation (a point light) or its outer cone and nothing beyond (a spot), so that
 * one walk chooses among emitters and punctual lights alike (as pbrt-v4's
 * BVHLightSampler does). light_leaf_count is then light_count + punctual_count. */
#ifndef TR_KERNEL_LIGHT_TREE_H
#define TR_KERNEL_LIGHT_TREE_H

#include "compat.h"
#include "scene_view.h"
#include "types.h"
#include "vec.h"

/* The largest float below 1, where a rescaled number in [0,1) must stay. */
#define TR_ONE_MINUS_EPS 0.99999994f

/* Importance of node n for the point p. theta_w is the angle between the cone's axis and
 * the direction from the box's centre to p, theta_b the half angle the box's bounding
 * sphere subtends from p (pi inside it); no emitter below can send light at an angle to
 * its normal smaller than theta' = max(0, theta_w - theta_o - theta_b) (the triangle
 * inequality on the sphere of directions), and none sends any beyond theta_e. Cosines of
 * the differences by the angle-difference formula, no inverse trigonometry. The squared
 * distance is clamped at the bounding radius squared, so that points inside a node do not
 * make it infinitely important. 0 exactly where no emitter below can light p. */
TR_FN float tr_light_importance(TR_CONST_GLOBAL tr_light_node *n, tr_vec3 p, tr_vec3 nr) {
    if (!(n->power > 0.0f)) {
        return 0.0f;
    }
    tr_vec3 d = v3_sub(p, n->centre);
    float d2 = v3_dot(d, d), r2 = n->r2;
    float cos_p = 1.0f, cos_r = 1.0f;
    if (d2 > r2) {
        /* One square root and one division for the distance; the rest multiplies. */
        float inv_d = 1.0f / tr_sqrtf(d2);
        float sin_b = tr_fminf(n->r * inv_d, 1.0f);
        float cos_b = tr_sqrtf(tr_fmaxf(0.0f, 1.0f - sin_b * sin_b));
        float cos_w = tr_fminf(tr_fmaxf(v3_dot(n->axis, d) * inv_d, -1.0f), 1.0f);
        float sin_w = tr_sqrtf(tr_fmaxf(0.0f, 1.0f - cos_w * cos_w));
        float cos_o = n->cos_o, sin_o = n->sin_o;
        if (cos_w < cos_o) { /* theta_w > theta_o: theta_1 = theta_w - theta_o */
            float cos_1 = cos_w * cos_o + sin_w * sin_o;
            float sin_1 = sin_w * cos_o - cos_w * sin_o;
            if (cos_1 < cos_b) { /* theta_1 > theta_b */
                cos_p = cos_1 * cos_b + sin_1 * sin_b;
            }
        }
        if (!(cos_p > n->cos_e)) {
            return 0.0f;
        }
        /* The receiver's side, as pbrt-v4's LightBounds::Importance has it: light arrives
         * at an angle theta_i from the normal nr, at least max(0, theta_i - theta_b) from
         * any point of the node, and is weighed by its cosine; |cos|, so that a
         * transmitting surface's other side counts too. Skipped without a normal (nr zero)
         * or inside. */
        if (!(nr.x == 0.0f && nr.y == 0.0f && nr.z == 0.0f)) {
            float cos_i = tr_fminf(tr_fabsf(v3_dot(nr, d)) * inv_d, 1.0f);
            float sin_i = tr_sqrtf(tr_fmaxf(0.0f, 1.0f - cos_i * cos_i));
            if (cos_i < cos_b) { /* theta_i > theta_b */
                cos_r = tr_fmaxf(cos_i * cos_b + sin_i * sin_b, 0.0f);
            }
        }
    } else if (!(cos_p > n->cos_e)) {
        return 0.0f;
    }
    /* The floor keeps a point light's leaf (r = 0) finite at its own position. */
    return n->power * cos_p * cos_r / tr_fmaxf(tr_fmaxf(d2, r2), 1e-30f);
}

/* The branch weights where neither child's bound admits light at p (the parent's looser
 * bound did, or p is behind every emitter): their powers. The walk then always ends at a
 * leaf, so the probabilities of all emitters sum to one at every point; the emitter it
 * ends at sends nothing to p, which costs a wasted sample but no shadow ray. */
TR_FN void tr_light_branch_fallback(const tr_scene_view *s, uint32_t c, float *i0, float *i1) {
    *i0 = s->light_nodes[c].power;
    *i1 = s->light_nodes[c + 1u].power;
}

/* Walks the tree from the root for the point p (normal nr) with the uniform number *u, which is
 * rescaled at every branch to the part of [0,1) the branch took (so it stays uniform and
 * keeps its stratification for the point on the emitter). Returns the index into
 * s->lights of the emitter reached, with its probability in *prob (0, and the index
 * meaningless, only for a tree without power). */
TR_FN uint32_t tr_light_tree_pick(const tr_scene_view *s, tr_vec3 p, tr_vec3 nr, float *u,
                                  float *prob) {
    uint32_t n = 0u;
    float pr = 1.0f, x = *u;
    while (!(s->light_nodes[n].child & TR_LIGHT_LEAF)) {
        uint32_t c = s->light_nodes[n].child;
        float i0 = tr_light_importance(&s->light_nodes[c], p, nr);
        float i1 = tr_light_importance(&s->light_nodes[c + 1u], p, nr);
        if (!(i0 + i1 > 0.0f)) {
            tr_light_branch_fallback(s, c, &i0, &i1);
        }
        if (!(i0 + i1 > 0.0f)) {
            *prob = 0.0f;
            return 0u;
        }
        float p0 = i0 / (i0 + i1);
        if (x < p0) {
            x = tr_fminf(x / p0, TR_ONE_MINUS_EPS);
            pr *= p0;
            n = c;
        } else {
            x = tr_fminf((x - p0) / (1.0f - p0), TR_ONE_MINUS_EPS);
            pr *= 1.0f - p0;
            n = c + 1u;
        }
    }
    *u = x;
    *prob = pr;
    return s->light_nodes[n].child & ~TR_LIGHT_LEAF;
}

/* The probability that tr_light_tree_pick at p reaches emitter k (an index into
 * s->lights): the same branch probabilities, computed from the same nodes and point,
 * multiplied from the leaf up (so equal to the pick's up to rounding in the order of the
 * product). */
TR_FN float tr_light_tree_prob(const tr_scene_view *s, tr_vec3 p, tr_vec3 nr, uint32_t k) {
    if (k >= s->light_leaf_count) {
        return 0.0f;
    }
    uint32_t n = s->light_leaf[k];
    float pr = 1.0f;
    while (n != 0u) {
        uint32_t par = s->light_nodes[n].parent;
        uint32_t c = s->light_nodes[par].child;
        float i0 = tr_light_importance(&s->light_nodes[c], p, nr);
        float i1 = tr_light_importance(&s->light_nodes[c + 1u], p, nr);
        if (!(i0 + i1 > 0.0f)) {
            tr_light_branch_fallback(s, c, &i0, &i1);
        }
        if (!(i0 + i1 > 0.0f)) {
            return 0.0f;
        }
        float p0 = i0 / (i0 + i1);
        pr *= n == c ? p0 : 1.0f - p0;
        n = par;
    }
    return pr;
}

/* The index into s->lights of triangle t, or s->light_count when t is no emitter: the
 * table lists emitters in triangle order (src/scene/lights.c), so a binary search. */
TR_FN uint32_t tr_light_index_of(const tr_scene_view *s, uint32_t t) {
    uint32_t lo = 0u, hi = s->light_count;
    while (lo < hi) {
        uint32_t mid = lo + (hi - lo) / 2u;
        if (s->lights[mid] < t) {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    return lo < s->light_count && s->lights[lo] == t ? lo : s->light_count;
}

#endif
