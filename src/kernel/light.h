/* light.h - sampling emissive triangles for next-event estimation.
 *
 * An emitter is chosen from the scene's table with probability proportional to its
 * weight (emitted power: mean radiance x area x number of emitting sides), by binary
 * search in the table's CDF, or, where the scene has a light tree (light_tree.h: scenes
 * with many emitters), by the tree's estimate of what each can send to the shading
 * point; then a point on it: uniformly in the solid angle it
 * subtends from the shading point where that angle is neither tiny nor nearly a
 * hemisphere (Arvo 1995), uniformly in area otherwise. */
#ifndef TR_KERNEL_LIGHT_H
#define TR_KERNEL_LIGHT_H

#include "compat.h"
#include "light_tree.h"
#include "scene_view.h"
#include "types.h"
#include "vec.h"

/* Selection weight of triangle t of material m: the power it emits up to the common
 * factor pi, with the RGB mean as the scalar radiance. 0 for non-emitters. */
TR_FN float tr_light_weight(const tr_material *m, float area) {
    if (!(m->emittance > 0.0f) || !(area > 0.0f)) {
        return 0.0f;
    }
    float l = m->emittance * (m->color.x + m->color.y + m->color.z) * (1.0f / 3.0f);
    float sides = (m->flags & TR_MATERIAL_TWO_SIDED) ? 2.0f : 1.0f;
    return l * area * sides;
}

/* Index into s->lights of the entry u in [0,1) selects: the first with cdf > u (the last
 * where none is). A binary search without branches, so that the compiler makes each step
 * a conditional move: the range [lo, lo + n) holds the answer; a step tests the entry
 * before lo + step (step = n / 2) and keeps [lo + step, lo + n) where it is <= u, else
 * [lo, lo + n - step), which holds [lo, lo + step) since n - step >= step. With branches
 * each step was a coin toss the processor guessed wrong half the time: a quarter of
 * ReSTIR's candidate loop on 96 lamps went to those mispredictions. */
TR_FN uint32_t tr_light_pick(const tr_scene_view *s, float u) {
    uint32_t lo = 0u, n = s->light_count;
    while (n > 1u) {
        const uint32_t step = n >> 1u; /* not "half": a type in OpenCL C */
        lo = s->light_cdf[lo + step - 1u] <= u ? lo + step : lo;
        n -= step;
    }
    return lo;
}

/* tr_light_pick, with u rescaled in place to its position inside the picked entry's CDF
 * interval (kept in [0, 1)) and the interval's width, the pick's probability, in *prob:
 * the same number then picks the point on the emitter, keeping the pair's stratification
 * (tr_light_sample_np). */
TR_FN uint32_t tr_light_pick_rescale(const tr_scene_view *s, float *u, float *prob) {
    const uint32_t k = tr_light_pick(s, *u);
    const float lo = k > 0u ? s->light_cdf[k - 1u] : 0.0f, hi = s->light_cdf[k];
    *u = hi > lo ? tr_fminf(tr_fmaxf((*u - lo) / (hi - lo), 0.0f), 0.99999994f) : *u;
    *prob = hi - lo;
    return k;
}

/* The point of triangle tri at barycentrics b1, b2 of its second and third vertex. */
TR_FN tr_vec3 tr_light_triangle_at(TR_CONST_GLOBAL tr_triangle *tri, float b1, float b2) {
    return v3_add(v3_add(v3_scale(tri->v0, 1.0f - b1 - b2), v3_scale(tri->v1, b1)),
                  v3_scale(tri->v2, b2));
}

/* A point uniform on triangle tri's area from (u1, u2): b0 = 1 - sqrt(u1), b1 = u2 sqrt(u1)
 * (Pharr et al., Physically Based Rendering, 3rd ed., section 13.6.5); its barycentrics of
 * the second and third vertex into *b1, *b2. */
TR_FN tr_vec3 tr_light_area_point(TR_CONST_GLOBAL tr_triangle *tri, float u1, float u2, float *b1,
                                  float *b2) {
    const float su = tr_sqrtf(u1);
    *b1 = u2 * su;
    *b2 = 1.0f - (1.0f - su) - *b1;
    return tr_light_triangle_at(tri, *b1, *b2);
}

/* Area density (per unit area) of sampling a point on triangle `tri` (material m)
 * through tr_light_sample. */
TR_FN float tr_light_pdf_area(const tr_scene_view *s, const tr_material *m, float area) {
    if (s->light_count == 0 || !(s->light_weight_total > 0.0f) || !(area > 0.0f)) {
        return 0.0f;
    }
    return tr_light_weight(m, area) / (s->light_weight_total * area);
}

/* Solid angles between these are sampled uniformly in solid angle (Arvo's spherical
 * triangle sampling); outside, uniformly in area. Below the lower bound a triangle looks
 * so small from p that the two densities agree to well under a percent and area sampling
 * is cheaper; near 2 pi the point is almost in the triangle's plane, where the spherical
 * triangle degenerates. */
#define TR_LIGHT_SPHERICAL_MIN 1e-3f
#define TR_LIGHT_SPHERICAL_MAX 6.0f

/* Beyond this many radii of its bounding sphere (about the centroid) a triangle is
 * sampled by area without its spherical triangle being found: from there the distance to
 * its points varies by at most (d + R) / (d - R) = 5/3. Area sampling there added 0.8 %
 * to the classic Cornell box's relative MSE per sample and the test saved 14 % of its
 * time (the atan2, sin and cos of the solid-angle path); on small lamps over a floor
 * (scenes/many-lights.json) the error grew 5.5 % for 0-3 % less time
 * (docs/benchmarks.md, "Cheap test for far lights"). */
#define TR_LIGHT_FAR_RADII 4.0f

/* Whether p lies beyond TR_LIGHT_FAR_RADII bounding radii of triangle tri's centroid. */
TR_FN int tr_light_far(TR_CONST_GLOBAL tr_triangle *tri, tr_vec3 p) {
    const tr_vec3 cen = v3_scale(v3_add(v3_add(tri->v0, tri->v1), tri->v2), 1.0f / 3.0f);
    const tr_vec3 e0 = v3_sub(tri->v0, cen), e1 = v3_sub(tri->v1, cen), e2 = v3_sub(tri->v2, cen);
    const float r2 = tr_fmaxf(v3_dot(e0, e0), tr_fmaxf(v3_dot(e1, e1), v3_dot(e2, e2)));
    const tr_vec3 d = v3_sub(cen, p);
    return v3_dot(d, d) > TR_LIGHT_FAR_RADII * TR_LIGHT_FAR_RADII * r2;
}

/* Whether light sampling at p picks a point of triangle tri by solid angle (p not far
 * from it, tr_light_far, and the solid angle between the bounds above): returns the
 * solid angle of the spherical triangle tri subtends from p when it does (with the unit
 * directions to its vertices in *a, *b, *c and the cosine and sine of its angle at a in
 * *ca, *sa), 0 when it samples by area. Sampling and the pdf call this alike, so they
 * always agree. The solid angle by Van Oosterom and Strackee's formula (IEEE Trans.
 * Biomed. Eng. 30(2), 1983), tan(omega / 2) = |a . (b x c)| / (1 + a.b + b.c + c.a): one
 * atan2 and no cancellation, unlike alpha + beta + gamma - pi. */
TR_FN float tr_light_spherical(TR_CONST_GLOBAL tr_triangle *tri, tr_vec3 p, tr_vec3 *a, tr_vec3 *b,
                               tr_vec3 *c, float *ca, float *sa) {
    if (tr_light_far(tri, p)) {
        return 0.0f;
    }
    tr_vec3 da = v3_sub(tri->v0, p), db = v3_sub(tri->v1, p), dc = v3_sub(tri->v2, p);
    float la = v3_length(da), lb = v3_length(db), lc = v3_length(dc);
    if (!(la > 0.0f) || !(lb > 0.0f) || !(lc > 0.0f)) {
        return 0.0f;
    }
    *a = v3_scale(da, 1.0f / la);
    *b = v3_scale(db, 1.0f / lb);
    *c = v3_scale(dc, 1.0f / lc);
    float ab = v3_dot(*a, *b), bc = v3_dot(*b, *c), ca_dot = v3_dot(*c, *a);
    float triple = tr_fabsf(v3_dot(*a, v3_cross(*b, *c)));
    float omega = 2.0f * tr_atan2f(triple, 1.0f + ab + bc + ca_dot);
    if (!(omega > TR_LIGHT_SPHERICAL_MIN && omega < TR_LIGHT_SPHERICAL_MAX)) {
        return 0.0f;
    }
    /* The angle at a is the one between the planes (a, b) and (a, c): from their normals,
     * |(a x b) x (a x c)| = |a . (b x c)| |a| = triple. */
    tr_vec3 nb = v3_cross(*a, *b), nc = v3_cross(*a, *c);
    float len = v3_length(nb) * v3_length(nc);
    if (!(len > 0.0f)) {
        return 0.0f;
    }
    *ca = v3_dot(nb, nc) / len;
    *sa = triple / len;
    return omega;
}

/* Probability that light sampling picks triangle t (material m): its weight's share. */
TR_FN float tr_light_select_prob(const tr_scene_view *s, const tr_material *m, float area) {
    return tr_light_pdf_area(s, m, area) * area;
}

/* Probability that tr_light_sample_n at p (normal nr, zero for none) picks triangle t: the
 * branch probabilities of the light tree when the view has one, the power share
 * otherwise. */
TR_FN float tr_light_select_pdf_n(const tr_scene_view *s, tr_vec3 p, tr_vec3 nr, uint32_t t) {
    if (s->light_node_count > 0u) {
        const uint32_t k = tr_light_index_of(s, t); /* light_count for no emitter */
        return k < s->light_count ? tr_light_tree_prob(s, p, nr, k) : 0.0f;
    }
    tr_triangle tri_tmp;
    TR_CONST_GLOBAL tr_triangle *tri = tr_view_triangle(s, t, &tri_tmp);
    tr_material m = s->materials[tri->material];
    return tr_light_select_prob(s, &m, tri->area);
}

/* tr_light_select_pdf_n without a receiver normal (tr_light_sample's choice). */
TR_FN float tr_light_select_pdf(const tr_scene_view *s, tr_vec3 p, uint32_t t) {
    return tr_light_select_pdf_n(s, p, v3s(0.0f), t);
}

/* The area-sampled density of the point y of triangle tri, picked with probability sel,
 * in solid angle from p: sel / area times r^2 / |cos theta_light|. */
TR_FN float tr_light_pdf_by_area(TR_CONST_GLOBAL tr_triangle *tri, float sel, tr_vec3 p,
                                 tr_vec3 y) {
    tr_vec3 d = v3_sub(y, p);
    float d2 = v3_dot(d, d);
    float cos_l = tr_fabsf(v3_dot(d, tri->normal));
    if (!(cos_l > 0.0f)) {
        return 0.0f;
    }
    /* r^2 / |cos| = d2 / (|d . n| / |d|) */
    return sel / tri->area * d2 * tr_sqrtf(d2) / cos_l;
}

/* Solid-angle density, seen from p, with which tr_light_sample_n called at p (normal nr)
 * picks the point y of triangle t: 1/omega times the selection probability when the triangle is
 * sampled by solid angle, the area density times r^2 / |cos theta_light| otherwise.
 * Both MIS strategies use it, so their weights sum to one. */
TR_FN float tr_light_pdf_n(const tr_scene_view *s, tr_vec3 p, tr_vec3 nr, uint32_t t, tr_vec3 y) {
    tr_triangle tri_tmp;
    TR_CONST_GLOBAL tr_triangle *tri = tr_view_triangle(s, t, &tri_tmp);
    float sel = tr_light_select_pdf_n(s, p, nr, t);
    if (!(sel > 0.0f)) {
        return 0.0f;
    }
    tr_vec3 a, b, c;
    float ca, sa;
    float omega = tr_light_spherical(tri, p, &a, &b, &c, &ca, &sa);
    if (omega > 0.0f) {
        return sel / omega;
    }
    return tr_light_pdf_by_area(tri, sel, p, y);
}

/* tr_light_pdf_n without a receiver normal: tr_light_sample's density. */
TR_FN float tr_light_pdf(const tr_scene_view *s, tr_vec3 p, uint32_t t, tr_vec3 y) {
    return tr_light_pdf_n(s, p, v3s(0.0f), t, y);
}

/* A point on an emitter for the shading point p, from the uniform numbers (u1, u2):
 * u1 picks the emitter, and its position inside the emitter's CDF interval (or inside
 * the light tree's branch intervals), rescaled to [0,1), and u2 pick the point on it. Reusing u1
 * keeps the pair's stratification on every emitter: the points of a (0,m,2)-net that fall into an
 * interval of u1 are stratified there too, which a separate selection number would undo (each
 * emitter would get an unstratified share). *tri_index the triangle, *y the point, *u and *v its
 * barycentrics of the triangle's second and third vertex (as tr_hit's, for the material stage);
 * returns the solid-angle density of the choice seen from p (tr_light_pdf), 0 when the scene has no
 * emitters or the sample failed.
 *
 * Where the light tree also holds punctual lights (light_tree.h) and the walk ends at one,
 * its index into s->punctual goes to *punct and the walk's probability to *punct_prob,
 * and the function returns 0 (no point on an emitter); *punct_prob is 0 otherwise.
 * tr_light_sample_n is this without them: a caller that does not light with the punctual
 * lights it reaches (bdpt's connection, ReSTIR's candidates) finds nothing there. */
TR_FN float tr_light_sample_np(const tr_scene_view *s, tr_vec3 p, tr_vec3 nr, float u1, float u2,
                               uint32_t *tri_index, tr_vec3 *y, float *u, float *v, uint32_t *punct,
                               float *punct_prob) {
    *tri_index = 0u;
    *y = v3s(0.0f);
    *u = 0.0f;
    *v = 0.0f;
    *punct = 0u;
    *punct_prob = 0.0f;
    if (s->light_count == 0 && s->light_node_count == 0u) {
        return 0.0f;
    }
    uint32_t k;
    float sel = 0.0f; /* the tree's probability; the CDF's is found below */
    if (s->light_node_count > 0u) {
        k = tr_light_tree_pick(s, p, nr, &u1, &sel);
        if (!(sel > 0.0f)) {
            return 0.0f;
        }
        if (k >= s->light_count) { /* a point or spot light's leaf */
            *punct = k - s->light_count;
            *punct_prob = sel;
            return 0.0f;
        }
    } else {
        float interval;
        k = tr_light_pick_rescale(s, &u1, &interval);
    }
    uint32_t t = s->lights[k];
    tr_triangle tri_tmp;
    TR_CONST_GLOBAL tr_triangle *tri = tr_view_triangle(s, t, &tri_tmp);
    *tri_index = t;
    tr_vec3 a, b, c;
    float ca = 0.0f, sa = 0.0f;
    float omega = tr_light_spherical(tri, p, &a, &b, &c, &ca, &sa);
    float b1, b2;
    if (omega > 0.0f) {
        /* J. Arvo, "Stratified Sampling of Spherical Triangles", SIGGRAPH 1995: u1 picks
         * the sub-triangle of area u1 omega with vertices a, b and a point c_hat on arc
         * ac, whose cosine q from a follows from the area; u2 picks the point on arc
         * b c_hat by the cosine from b, which is uniform in solid angle along it. */
        float area_hat = u1 * omega;
        float sh = tr_sinf(area_hat), ch = tr_cosf(area_hat);
        float sp = sh * ca - ch * sa, cp = ch * ca + sh * sa; /* of area_hat - alpha */
        float uu = cp - ca, vv = sp + sa * v3_dot(a, b);
        float den = (vv * sp + uu * cp) * sa;
        float q = den != 0.0f ? ((vv * cp - uu * sp) * ca - vv) / den : 1.0f;
        q = tr_fminf(tr_fmaxf(q, -1.0f), 1.0f);
        tr_vec3 ct = v3_sub(c, v3_scale(a, v3_dot(c, a)));
        float lct = v3_length(ct);
        if (!(lct > 0.0f)) {
            return 0.0f;
        }
        tr_vec3 c_hat = v3_add(v3_scale(a, q), v3_scale(ct, tr_sqrtf(1.0f - q * q) / lct));
        float z = 1.0f - u2 * (1.0f - v3_dot(c_hat, b));
        z = tr_fminf(tr_fmaxf(z, -1.0f), 1.0f);
        tr_vec3 ht = v3_sub(c_hat, v3_scale(b, v3_dot(c_hat, b)));
        float lht = v3_length(ht);
        tr_vec3 w =
            lht > 0.0f ? v3_add(v3_scale(b, z), v3_scale(ht, tr_sqrtf(1.0f - z * z) / lht)) : b;
        /* Where the direction meets the triangle's plane, in barycentrics (Moller and
         * Trumbore's solution of the ray-triangle system, without the bounds test; the
         * clamp absorbs rounding at the edges). */
        tr_vec3 e1 = v3_sub(tri->v1, tri->v0), e2 = v3_sub(tri->v2, tri->v0);
        tr_vec3 pv = v3_cross(w, e2);
        float det = v3_dot(e1, pv);
        if (!(tr_fabsf(det) > 0.0f)) {
            return 0.0f;
        }
        tr_vec3 tv = v3_sub(p, tri->v0);
        tr_vec3 qv = v3_cross(tv, e1);
        b1 = tr_fminf(tr_fmaxf(v3_dot(tv, pv) / det, 0.0f), 1.0f);
        b2 = tr_fminf(tr_fmaxf(v3_dot(w, qv) / det, 0.0f), 1.0f - b1);
        *y = tr_light_triangle_at(tri, b1, b2);
    } else {
        *y = tr_light_area_point(tri, u1, u2, &b1, &b2);
    }
    *u = b1;
    *v = b2;
    /* tr_light_pdf's value, without finding the spherical triangle or walking the tree
     * again. */
    if (s->light_node_count == 0u) {
        tr_material m = s->materials[tri->material];
        sel = tr_light_select_prob(s, &m, tri->area);
        if (!(sel > 0.0f)) {
            return 0.0f;
        }
    }
    return omega > 0.0f ? sel / omega : tr_light_pdf_by_area(tri, sel, p, *y);
}

TR_FN float tr_light_sample_n(const tr_scene_view *s, tr_vec3 p, tr_vec3 nr, float u1, float u2,
                              uint32_t *tri_index, tr_vec3 *y, float *u, float *v) {
    uint32_t punct;
    float punct_prob;
    return tr_light_sample_np(s, p, nr, u1, u2, tri_index, y, u, v, &punct, &punct_prob);
}

/* tr_light_sample_n without a receiver normal. */
TR_FN float tr_light_sample(const tr_scene_view *s, tr_vec3 p, float u1, float u2,
                            uint32_t *tri_index, tr_vec3 *y, float *u, float *v) {
    return tr_light_sample_n(s, p, v3s(0.0f), u1, u2, tri_index, y, u, v);
}

#endif
