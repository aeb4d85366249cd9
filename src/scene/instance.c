/* instance.c - prototypes and their instances, and the two-level structure a
 * TR_ACCEL_TYPE_BVH commit builds over them (include/trac0r/scene.h, "Instances"). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "scene_internal.h"
#include "trac0r/scene.h"

static int grow(void **arr, uint32_t *cap, uint64_t need, size_t elem, tr_error *err) {
    if (need <= *cap) {
        return TR_OK;
    }
    uint64_t c = *cap ? *cap : 16;
    while (c < need) {
        c *= 2;
    }
    if (c > UINT32_MAX) {
        c = UINT32_MAX;
    }
    void *p = realloc(*arr, (size_t)c * elem);
    if (!p) {
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory storing instances");
    }
    *arr = p;
    *cap = (uint32_t)c;
    return TR_OK;
}

void tr_transform_matrix(const tr_transform *tf, float m[12]) {
    /* Each column is the image of a unit axis under scale and rotation alone. */
    tr_transform lin = *tf;
    lin.position = v3s(0.0f);
    const tr_vec3 cx = tr_transform_point(&lin, v3(1.0f, 0.0f, 0.0f));
    const tr_vec3 cy = tr_transform_point(&lin, v3(0.0f, 1.0f, 0.0f));
    const tr_vec3 cz = tr_transform_point(&lin, v3(0.0f, 0.0f, 1.0f));
    const float r[12] = {cx.x, cy.x,           cz.x, tf->position.x, cx.y, cy.y,
                         cz.y, tf->position.y, cx.z, cy.z,           cz.z, tf->position.z};
    memcpy(m, r, sizeof r);
}

/* The inverse of an affine matrix into inv, in double; TR_ERR (naming `what`) for a
 * non-finite entry or a singular linear part: |det| tiny next to the product of the
 * rows' lengths (the volume a unit cube keeps, against the most it could). */
static int invert(const float m[12], float inv[12], const char *what, uint32_t which,
                  tr_error *err) {
    for (int i = 0; i < 12; ++i) {
        if (!isfinite(m[i])) {
            return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                                "%s %u: the matrix has a non-finite entry (m[%d])", what, which, i);
        }
    }
    const double a = m[0], b = m[1], c = m[2], d = m[4], e = m[5], f = m[6], g = m[8], h = m[9],
                 k = m[10];
    const double A = e * k - f * h, B = f * g - d * k, C = d * h - e * g;
    const double det = a * A + b * B + c * C;
    const double r0 = sqrt(a * a + b * b + c * c), r1 = sqrt(d * d + e * e + f * f),
                 r2 = sqrt(g * g + h * h + k * k);
    if (!(fabs(det) > 1e-9 * r0 * r1 * r2) || !(r0 * r1 * r2 > 0.0)) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "%s %u: the matrix is singular (determinant %g)", what, which, det);
    }
    const double l[9] = {A / det, (c * h - b * k) / det, (b * f - c * e) / det,
                         B / det, (a * k - c * g) / det, (c * d - a * f) / det,
                         C / det, (b * g - a * h) / det, (a * e - b * d) / det};
    const double t[3] = {m[3], m[7], m[11]};
    for (int r = 0; r < 3; ++r) {
        inv[4 * r + 0] = (float)l[3 * r + 0];
        inv[4 * r + 1] = (float)l[3 * r + 1];
        inv[4 * r + 2] = (float)l[3 * r + 2];
        inv[4 * r + 3] = (float)-(l[3 * r] * t[0] + l[3 * r + 1] * t[1] + l[3 * r + 2] * t[2]);
    }
    for (int i = 0; i < 12; ++i) {
        if (!isfinite(inv[i])) {
            return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                                "%s %u: the matrix's inverse is not finite", what, which);
        }
    }
    return TR_OK;
}

static tr_vec3 xform_point(const float m[12], tr_vec3 p) {
    return v3(m[0] * p.x + m[1] * p.y + m[2] * p.z + m[3],
              m[4] * p.x + m[5] * p.y + m[6] * p.z + m[7],
              m[8] * p.x + m[9] * p.y + m[10] * p.z + m[11]);
}

/* Normals go through the inverse's transpose; a mirroring matrix (det < 0) turns the
 * geometric normal over too, so the vertex normals follow it to its side. A zero normal
 * (none) stays zero. */
static tr_vec3 xform_normal(const float m[12], const float inv[12], tr_vec3 n) {
    if (n.x == 0.0f && n.y == 0.0f && n.z == 0.0f) {
        return n;
    }
    tr_vec3 r =
        v3(inv[0] * n.x + inv[4] * n.y + inv[8] * n.z, inv[1] * n.x + inv[5] * n.y + inv[9] * n.z,
           inv[2] * n.x + inv[6] * n.y + inv[10] * n.z);
    const float det = m[0] * (m[5] * m[10] - m[6] * m[9]) - m[1] * (m[4] * m[10] - m[6] * m[8]) +
                      m[2] * (m[4] * m[9] - m[5] * m[8]);
    float len = v3_length(r);
    if (!(len > 0.0f) || !isfinite(len)) {
        return v3s(0.0f);
    }
    return v3_scale(r, (det < 0.0f ? -1.0f : 1.0f) / len);
}

/* Triangle i of prototype p placed with m: what flattening stores and what a kept
 * instance's id reads (tr_inst_triangle), one function for both. */
static void place_one(const tr_prototype *p, uint32_t i, const float m[12], tr_triangle *out) {
    tr_triangle t = p->tris[i];
    t.v0 = xform_point(m, t.v0);
    t.v1 = xform_point(m, t.v1);
    t.v2 = xform_point(m, t.v2);
    tr_triangle_finish(&t);
    *out = t;
}

static void place_tris(const tr_prototype *p, const float m[12], tr_triangle *out) {
    for (uint32_t i = 0; i < p->tri_count; ++i) {
        place_one(p, i, m, &out[i]);
    }
}

static void place_verts(const tr_prototype *p, const float m[12], const float inv[12],
                        tr_vertex *out) {
    for (uint32_t i = 0; i < p->vert_count; ++i) {
        out[i] = p->verts[i];
        out[i].normal = xform_normal(m, inv, p->verts[i].normal);
    }
}

/* Whether any of a prototype's triangles has a material that emits (a positive emittance:
 * what puts a triangle in the emitter table, src/scene/lights.c). */
static int proto_emits(const tr_scene *s, const tr_prototype *p) {
    for (uint32_t i = 0; i < p->tri_count; ++i) {
        const uint32_t mi = p->tris[i].material;
        if (mi < s->material_count && s->materials[mi].emittance > 0.0f) {
            return 1;
        }
    }
    return 0;
}

static int cmp_vec3(const void *a, const void *b) {
    return memcmp(a, b, sizeof(tr_vec3));
}

/* The prototype's distinct vertex positions (bit for bit), for its instances' boxes. */
static int proto_points(tr_prototype *p) {
    const size_t n = (size_t)p->tri_count * 3;
    p->pts = malloc((n ? n : 1) * sizeof *p->pts);
    if (!p->pts) {
        return TR_ERR;
    }
    for (uint32_t i = 0; i < p->tri_count; ++i) {
        p->pts[3 * (size_t)i] = p->tris[i].v0;
        p->pts[3 * (size_t)i + 1] = p->tris[i].v1;
        p->pts[3 * (size_t)i + 2] = p->tris[i].v2;
    }
    qsort(p->pts, n, sizeof *p->pts, cmp_vec3);
    size_t k = 0;
    for (size_t i = 0; i < n; ++i) {
        if (k == 0 || memcmp(&p->pts[k - 1], &p->pts[i], sizeof *p->pts) != 0) {
            p->pts[k++] = p->pts[i];
        }
    }
    p->pt_count = (uint32_t)k;
    tr_vec3 *shrunk = realloc(p->pts, (k ? k : 1) * sizeof *p->pts);
    p->pts = shrunk ? shrunk : p->pts;
    return TR_OK;
}

/* The world box of prototype p placed with m: its points transformed, the box its
 * transformed triangles have (the same points, the same float operations). */
static tr_aabb placed_box(const tr_prototype *p, const float m[12]) {
    tr_aabb b = {v3s(INFINITY), v3s(-INFINITY)};
    for (uint32_t i = 0; i < p->pt_count; ++i) {
        const tr_vec3 q = xform_point(m, p->pts[i]);
        b.min = v3_min(b.min, q);
        b.max = v3_max(b.max, q);
    }
    return b;
}

uint32_t tr_scene_prototype_count(const tr_scene *s) {
    return s->proto_count;
}

uint32_t tr_scene_instance_count(const tr_scene *s) {
    return s->instance_count;
}

uint32_t tr_scene_prototype_triangle_count(const tr_scene *s, uint32_t proto) {
    return proto < s->proto_count ? s->protos[proto].tri_count : 0;
}

int tr_scene_instance_transform(const tr_scene *s, uint32_t instance, float m[12]) {
    if (instance >= s->instance_count) {
        return 0;
    }
    memcpy(m, s->instances[instance].m, sizeof s->instances[instance].m);
    return 1;
}

uint32_t tr_scene_shape_instance(const tr_scene *s, uint32_t shape) {
    /* Instances are appended with their shapes: ordered by shape. */
    uint32_t lo = 0, hi = s->instance_count;
    while (lo < hi) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (s->instances[mid].shape < shape) {
            lo = mid + 1;
        } else {
            hi = mid;
        }
    }
    return lo < s->instance_count && s->instances[lo].shape == shape ? lo : UINT32_MAX;
}

/* The instance of kept id `id` (past the stored triangles): the last whose first id is at
 * most id (a flattened instance repeats the next kept one's first, so never wins). */
static uint32_t kept_instance(const tr_scene *s, uint32_t id) {
    uint32_t lo = 0, hi = s->instance_count;
    while (lo < hi) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (s->inst_first[mid] <= id) {
            lo = mid + 1;
        } else {
            hi = mid;
        }
    }
    return lo - 1;
}

int tr_scene_triangle_instance(const tr_scene *s, uint32_t triangle, uint32_t *instance,
                               uint32_t *prim) {
    if (triangle >= s->triangle_count) {
        if (s->placed_count == 0 || triangle - s->triangle_count >= s->placed_count) {
            return 0;
        }
        const uint32_t i = kept_instance(s, triangle);
        *instance = i;
        *prim = triangle - s->inst_first[i];
        return 1;
    }
    /* Flattened instances hold their triangles in the arrays, in order; `at` (the stored
     * count when each instance was added) ascends over all of them, and a kept one
     * stores nothing, so the last instance starting at or before the triangle is the
     * only one that can hold it. */
    uint32_t lo = 0, hi = s->instance_count;
    while (lo < hi) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (s->instances[mid].at <= triangle) {
            lo = mid + 1;
        } else {
            hi = mid;
        }
    }
    if (lo == 0 || !s->instances[lo - 1].flat) {
        return 0;
    }
    const tr_flat_node *sh = &s->shapes[s->instances[lo - 1].shape];
    if (triangle < sh->first || triangle >= sh->first + sh->count) {
        return 0;
    }
    *instance = lo - 1;
    *prim = triangle - sh->first;
    return 1;
}

int tr_scene_make_prototype(tr_scene *s, uint32_t first_shape, uint32_t *proto, tr_error *err) {
    if (first_shape >= s->shape_count) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "a prototype needs at least one shape (from shape %u of %u)",
                            first_shape, s->shape_count);
    }
    if (s->instance_count > 0 && s->instances[s->instance_count - 1].shape >= first_shape) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "shape %u is an instance: a prototype holds plain shapes only",
                            s->instances[s->instance_count - 1].shape);
    }
    if (grow((void **)&s->protos, &s->proto_capacity, (uint64_t)s->proto_count + 1,
             sizeof *s->protos, err) != TR_OK) {
        return TR_ERR;
    }
    const uint32_t t0 = s->shapes[first_shape].first, n = s->triangle_count - t0;
    tr_prototype p;
    memset(&p, 0, sizeof p);
    p.tri_count = n;
    /* The vertices the triangles name were appended with them: from the lowest one on. */
    uint32_t vmin = s->vertex_count;
    for (uint32_t i = t0; i < s->tri_verts_count && i < s->triangle_count; ++i) {
        for (int k = 0; k < 3; ++k) {
            const uint32_t v = s->tri_verts[i].v[k];
            vmin = v != TR_NO_INDEX && v < vmin ? v : vmin;
        }
    }
    const int attrs = vmin < s->vertex_count;
    p.tris = malloc((size_t)(n ? n : 1) * sizeof *p.tris);
    if (attrs) {
        p.vert_count = s->vertex_count - vmin;
        p.verts = malloc((size_t)p.vert_count * sizeof *p.verts);
        p.idx = malloc((size_t)n * 3 * sizeof *p.idx);
    }
    if (!p.tris || (attrs && (!p.verts || !p.idx))) {
        free(p.tris);
        free(p.verts);
        free(p.idx);
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory storing a prototype");
    }
    memcpy(p.tris, s->triangles + t0, (size_t)n * sizeof *p.tris);
    p.emissive = proto_emits(s, &p);
    if (proto_points(&p) != TR_OK) {
        free(p.tris);
        free(p.verts);
        free(p.idx);
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory storing a prototype");
    }
    if (attrs) {
        memcpy(p.verts, s->vertices + vmin, (size_t)p.vert_count * sizeof *p.verts);
        for (uint32_t i = 0; i < n; ++i) {
            for (int k = 0; k < 3; ++k) {
                const uint32_t v =
                    t0 + i < s->tri_verts_count ? s->tri_verts[t0 + i].v[k] : TR_NO_INDEX;
                p.idx[3 * i + (uint32_t)k] = v == TR_NO_INDEX ? TR_NO_INDEX : v - vmin;
            }
        }
        s->vertex_count = vmin;
    }
    s->triangle_count = t0;
    s->shape_count = first_shape;
    if (s->tri_verts_count > t0) {
        s->tri_verts_count = t0;
    }
    s->protos[s->proto_count] = p;
    if (proto) {
        *proto = s->proto_count;
    }
    s->proto_count++;
    s->generation++;
    return TR_OK;
}

/* Appends prototype p placed with m (inverse inv) as one shape. */
static int append_placed(tr_scene *s, const tr_prototype *p, const float m[12], const float inv[12],
                         tr_error *err) {
    tr_triangle *tris = malloc((size_t)(p->tri_count ? p->tri_count : 1) * sizeof *tris);
    tr_vertex *verts =
        p->idx ? malloc((size_t)(p->vert_count ? p->vert_count : 1) * sizeof *verts) : NULL;
    if (!tris || (p->idx && !verts)) {
        free(tris);
        free(verts);
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory placing an instance");
    }
    place_tris(p, m, tris);
    if (verts) {
        place_verts(p, m, inv, verts);
    }
    int rc = tr_scene_append_shape_attr(s, tris, p->tri_count, verts, p->vert_count, p->idx, err);
    free(tris);
    free(verts);
    return rc;
}

int tr_scene_add_prototype_copy(tr_scene *s, uint32_t proto, const float m[12], tr_error *err) {
    float inv[12];
    if (proto >= s->proto_count) {
        return tr_error_set(err, TR_STATUS_NOT_FOUND, "prototype %u does not exist (%u made)",
                            proto, s->proto_count);
    }
    if (invert(m, inv, "prototype", proto, err) != TR_OK) {
        return TR_ERR;
    }
    return append_placed(s, &s->protos[proto], m, inv, err);
}

/* Room for one more entry in the shapes arrays (what tr_scene_append_shape_attr grows). */
static int grow_shape(tr_scene *s, tr_error *err) {
    if (grow((void **)&s->shapes, &s->shape_capacity, (uint64_t)s->shape_count + 1,
             sizeof *s->shapes, err) != TR_OK ||
        grow((void **)&s->shape_moved, &s->shape_moved_capacity, (uint64_t)s->shape_count + 1,
             sizeof *s->shape_moved, err) != TR_OK) {
        return TR_ERR;
    }
    return TR_OK;
}

int tr_scene_add_instance(tr_scene *s, uint32_t proto, const float m[12], uint32_t *instance,
                          tr_error *err) {
    float inv[12];
    if (proto >= s->proto_count) {
        return tr_error_set(err, TR_STATUS_NOT_FOUND, "prototype %u does not exist (%u made)",
                            proto, s->proto_count);
    }
    if (invert(m, inv, "instance", s->instance_count, err) != TR_OK ||
        grow((void **)&s->instances, &s->instance_capacity, (uint64_t)s->instance_count + 1,
             sizeof *s->instances, err) != TR_OK ||
        grow((void **)&s->inst_first, &s->inst_first_capacity, (uint64_t)s->instance_count + 1,
             sizeof *s->inst_first, err) != TR_OK) {
        return TR_ERR;
    }
    const tr_prototype *p = &s->protos[proto];
    tr_instance in;
    memset(&in, 0, sizeof in);
    in.proto = proto;
    in.vert_base = s->vertex_count;
    in.at = s->triangle_count;
    memcpy(in.m, m, sizeof in.m);
    memcpy(in.inv, inv, sizeof in.inv);
    const uint64_t total = (uint64_t)s->triangle_count + s->placed_count;
    if (p->emissive) {
        /* Emitting prototypes are flattened: the emitter table names stored triangles. */
        if (append_placed(s, p, m, inv, err) != TR_OK) {
            return TR_ERR;
        }
        in.flat = 1;
        s->inst_first[s->instance_count] = (uint32_t)(total + p->tri_count);
    } else {
        /* Kept: a shape of ids past the stored triangles, and its world box. */
        if (total + p->tri_count > TR_SCENE_MAX_TRIANGLES) {
            return tr_error_set(err, TR_STATUS_LIMIT,
                                "scene would exceed %u triangles (placed by instances or "
                                "stored)",
                                TR_SCENE_MAX_TRIANGLES);
        }
        if (grow_shape(s, err) != TR_OK) {
            return TR_ERR;
        }
        s->shape_moved[s->shape_count] = v3s(0.0f);
        tr_flat_node *node = &s->shapes[s->shape_count++];
        node->box = placed_box(p, m);
        node->first = (uint32_t)total;
        node->count = p->tri_count;
        s->inst_first[s->instance_count] = (uint32_t)total;
        s->placed_count += p->tri_count;
        s->generation++;
    }
    in.shape = s->shape_count - 1;
    s->instances[s->instance_count] = in;
    if (instance) {
        *instance = s->instance_count;
    }
    s->instance_count++;
    return TR_OK;
}

void tr_scene_instance_ids(tr_scene *s) {
    uint64_t base = s->triangle_count;
    for (uint32_t i = 0; i < s->instance_count; ++i) {
        const tr_instance *in = &s->instances[i];
        s->inst_first[i] = (uint32_t)base;
        if (!in->flat) {
            s->shapes[in->shape].first = (uint32_t)base;
            base += s->shapes[in->shape].count;
        }
    }
}

int tr_scene_has_kept_instances(const tr_scene *s) {
    return s->placed_count > 0;
}

tr_aabb tr_scene_all_bounds(const tr_scene *s) {
    tr_aabb b = tr_triangles_bounds(s->triangles, s->triangle_count);
    for (uint32_t i = 0; s->placed_count > 0 && i < s->instance_count; ++i) {
        if (!s->instances[i].flat) {
            const tr_aabb c = s->shapes[s->instances[i].shape].box;
            b.min = v3_min(b.min, c.min);
            b.max = v3_max(b.max, c.max);
        }
    }
    return b;
}

int tr_scene_set_instance_transform(tr_scene *s, uint32_t instance, const float m[12],
                                    tr_error *err) {
    float inv[12];
    if (instance >= s->instance_count) {
        return tr_error_set(err, TR_STATUS_NOT_FOUND,
                            "instance %u does not exist (the scene has %u)", instance,
                            s->instance_count);
    }
    if (invert(m, inv, "instance", instance, err) != TR_OK) {
        return TR_ERR;
    }
    tr_instance *in = &s->instances[instance];
    if (!in->moved && grow((void **)&s->moved, &s->moved_capacity, (uint64_t)s->moved_count + 1,
                           sizeof *s->moved, err) != TR_OK) {
        return TR_ERR;
    }
    const tr_prototype *p = &s->protos[in->proto];
    tr_flat_node *sh = &s->shapes[in->shape];
    if (in->flat) {
        place_tris(p, m, s->triangles + sh->first);
        if (p->idx) {
            place_verts(p, m, inv, s->vertices + in->vert_base);
        }
        sh->box = tr_triangles_bounds(s->triangles + sh->first, sh->count);
    } else {
        sh->box = placed_box(p, m); /* nothing stored to rewrite */
    }
    /* Motion vectors follow the translation (a rotation's motion is not a vector). */
    s->shape_moved[in->shape] =
        v3_add(s->shape_moved[in->shape], v3(m[3] - in->m[3], m[7] - in->m[7], m[11] - in->m[11]));
    memcpy(in->m, m, sizeof in->m);
    memcpy(in->inv, inv, sizeof in->inv);
    if (!in->moved) {
        in->moved = 1;
        s->moved[s->moved_count++] = instance;
    }
    s->generation++;
    return TR_OK;
}

void tr_scene_free_two_level(tr_scene *s) {
    tr_tlas_free(&s->tlas);
    tr_bvh_free(&s->rest_bvh);
    tr_wbvh_free(&s->rest_wbvh);
    s->two_level = 0;
    s->rest_moved = 0;
    for (uint32_t i = 0; i < s->moved_count; ++i) {
        s->instances[s->moved[i]].moved = 0;
    }
    s->moved_count = 0;
}

void tr_scene_free_instances(tr_scene *s) {
    tr_scene_free_two_level(s);
    for (uint32_t i = 0; i < s->proto_count; ++i) {
        tr_prototype *p = &s->protos[i];
        free(p->tris);
        free(p->verts);
        free(p->idx);
        free(p->pts);
        tr_bvh_free(&p->bvh);
        tr_wbvh_free(&p->wbvh);
    }
    free(s->protos);
    free(s->instances);
    free(s->moved);
    free(s->inst_first);
    s->inst_first = NULL;
    s->inst_first_capacity = 0;
    s->placed_count = 0;
    s->protos = NULL;
    s->instances = NULL;
    s->moved = NULL;
    s->proto_count = s->proto_capacity = 0;
    s->instance_count = s->instance_capacity = 0;
    s->moved_capacity = 0;
}

static tr_aabb rest_box(const tr_scene *s) {
    tr_aabb empty = {v3s(INFINITY), v3s(-INFINITY)};
    return s->rest_bvh.node_count > 0 ? s->rest_bvh.nodes[0].box : empty;
}

int tr_scene_build_two_level(tr_scene *s, tr_error *err) {
    tr_scene_free_two_level(s);
    for (uint32_t i = 0; i < s->proto_count; ++i) {
        tr_prototype *p = &s->protos[i];
        if (p->built) {
            continue;
        }
        if (tr_bvh_build_wide(&p->bvh, p->tris, p->tri_count, NULL, err) != TR_OK) {
            return TR_ERR;
        }
        if (tr_wbvh_build(&p->wbvh, &p->bvh, err) != TR_OK) {
            tr_bvh_free(&p->bvh);
            return TR_ERR;
        }
        p->built = 1;
    }
    const uint32_t n = s->instance_count;
    uint8_t *skip = calloc(s->triangle_count ? s->triangle_count : 1, 1);
    tr_wbvh_instance *inst = malloc(((size_t)n + 1) * sizeof *inst);
    tr_aabb *boxes = malloc(((size_t)n + 1) * sizeof *boxes);
    int rc = TR_OK;
    if (!skip || !inst || !boxes) {
        rc = tr_error_set(err, TR_STATUS_OUT_OF_MEMORY,
                          "out of memory building the top level over %u instances", n);
    }
    for (uint32_t i = 0; rc == TR_OK && i < n; ++i) {
        const tr_instance *in = &s->instances[i];
        const tr_flat_node *sh = &s->shapes[in->shape];
        if (in->flat) {
            memset(skip + sh->first, 1, sh->count);
        }
        memcpy(inst[i].inv, in->inv, sizeof in->inv);
        inst[i].blas = &s->protos[in->proto].wbvh;
        inst[i].tri_base = sh->first;
        inst[i].identity = 0;
        boxes[i] = sh->box;
    }
    if (rc == TR_OK) {
        rc = tr_bvh_build_wide(&s->rest_bvh, s->triangles, s->triangle_count, skip, err);
    }
    if (rc == TR_OK) {
        rc = tr_wbvh_build(&s->rest_wbvh, &s->rest_bvh, err);
    }
    if (rc == TR_OK) {
        static const float id[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
        memcpy(inst[n].inv, id, sizeof id);
        inst[n].blas = &s->rest_wbvh;
        inst[n].tri_base = 0;
        inst[n].identity = 1;
        boxes[n] = rest_box(s);
        rc = tr_tlas_build(&s->tlas, inst, boxes, n + 1, err);
    }
    free(skip);
    free(inst);
    free(boxes);
    if (rc != TR_OK) {
        tr_scene_free_two_level(s);
        return TR_ERR;
    }
    s->two_level = 1;
    return TR_OK;
}

int tr_scene_update_two_level(tr_scene *s, tr_error *err) {
    int rebuild = 0, lights = 0;
    if (s->rest_moved) {
        tr_bvh_refit(&s->rest_bvh, s->triangles);
        tr_wbvh_refit(&s->rest_wbvh, &s->rest_bvh);
        static const float id[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
        const tr_aabb b = rest_box(s);
        rebuild |= s->rest_bvh.node_count > 0 && !tr_tlas_move(&s->tlas, s->instance_count, id, b);
        s->rest_moved = 0;
    }
    for (uint32_t k = 0; k < s->moved_count; ++k) {
        tr_instance *in = &s->instances[s->moved[k]];
        rebuild |= !tr_tlas_move(&s->tlas, s->moved[k], in->inv, s->shapes[in->shape].box);
        lights |= s->protos[in->proto].emissive;
        in->moved = 0;
    }
    s->moved_count = 0;
    if (lights && tr_scene_build_lights(s, err) != TR_OK) {
        return TR_ERR;
    }
    if (rebuild) {
        return tr_scene_build_two_level(s, err);
    }
    return TR_OK;
}

/* ---- Kept instances through Embree's instancing -------------------------------------- */

int tr_scene_build_embree(tr_scene *s, tr_error *err) {
    const uint32_t n = s->instance_count;
    tr_embree_proto *protos =
        malloc((size_t)(s->proto_count ? s->proto_count : 1) * sizeof *protos);
    tr_embree_instance *inst = malloc((size_t)(n ? n : 1) * sizeof *inst);
    if (!protos || !inst) {
        free(protos);
        free(inst);
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY,
                            "out of memory handing %u instances to Embree", n);
    }
    for (uint32_t i = 0; i < s->proto_count; ++i) {
        protos[i].tris = s->protos[i].tris;
        protos[i].count = s->protos[i].tri_count;
    }
    for (uint32_t i = 0; i < n; ++i) {
        const tr_instance *in = &s->instances[i];
        inst[i].m = in->m;
        /* A flattened instance's triangles are among the stored ones. */
        inst[i].proto = in->flat ? UINT32_MAX : in->proto;
        inst[i].first = s->inst_first[i];
    }
    const int rc = tr_embree_build_instanced(&s->embree, s->triangles, s->triangle_count, protos,
                                             s->proto_count, inst, n, err);
    free(protos);
    free(inst);
    return rc;
}

int tr_scene_update_embree(tr_scene *s, tr_error *err) {
    int stored = s->rest_moved, lights = 0, rc = TR_OK;
    for (uint32_t k = 0; k < s->moved_count; ++k) {
        tr_instance *in = &s->instances[s->moved[k]];
        if (in->flat) {
            stored = 1; /* its triangles were rewritten in the scene's arrays */
        } else if (rc == TR_OK) {
            rc = tr_embree_set_transform(&s->embree, s->moved[k], in->m, err);
        }
        lights |= s->protos[in->proto].emissive;
        in->moved = 0;
    }
    s->moved_count = 0;
    s->rest_moved = 0;
    if (rc == TR_OK && stored) {
        rc = tr_embree_set_triangles(&s->embree, s->triangles, s->triangle_count, err);
    }
    if (rc == TR_OK) {
        rc = tr_embree_commit(&s->embree, err);
    }
    if (rc == TR_OK && lights) {
        rc = tr_scene_build_lights(s, err);
    }
    return rc;
}

/* ---- Kept instances read by id (the kernel's tr_view_* on the host) ---------------- */

/* The instance each thread found last: a hit is read several times (its triangle,
 * material, vertices), and the search is skipped while the hint's range holds the id.
 * The hint is checked against the scene it is used on, so it is never wrong, only
 * sometimes useless. */
static _Thread_local uint32_t kept_hint;

static const tr_instance *kept_of(const tr_scene *s, uint32_t id, uint32_t *local) {
    uint32_t i = kept_hint;
    if (!(i < s->instance_count && !s->instances[i].flat && s->inst_first[i] <= id &&
          id - s->inst_first[i] < s->protos[s->instances[i].proto].tri_count)) {
        i = kept_instance(s, id);
        kept_hint = i;
    }
    *local = id - s->inst_first[i];
    return &s->instances[i];
}

const tr_triangle *tr_inst_triangle(const tr_scene *s, uint32_t id, tr_triangle *tmp) {
    uint32_t l;
    const tr_instance *in = kept_of(s, id, &l);
    place_one(&s->protos[in->proto], l, in->m, tmp);
    return tmp;
}

uint32_t tr_inst_material(const tr_scene *s, uint32_t id) {
    uint32_t l;
    const tr_instance *in = kept_of(s, id, &l);
    return s->protos[in->proto].tris[l].material;
}

int tr_inst_has_verts(const tr_scene *s, uint32_t id) {
    uint32_t l;
    const tr_instance *in = kept_of(s, id, &l);
    return s->protos[in->proto].idx != NULL;
}

/* As tr_scene_append_shape_attr indexes an instance's vertices: an index past the
 * prototype's vertices is none, and a triangle missing its second or third has none. */
static int proto_tri_verts(const tr_prototype *p, uint32_t l, uint32_t v[3]) {
    for (int k = 0; k < 3; ++k) {
        const uint32_t j = p->idx[3 * (size_t)l + (uint32_t)k];
        v[k] = j < p->vert_count ? j : TR_NO_INDEX;
    }
    return v[0] != TR_NO_INDEX && v[1] != TR_NO_INDEX && v[2] != TR_NO_INDEX;
}

int tr_inst_vertices(const tr_scene *s, uint32_t id, tr_vertex x[3]) {
    uint32_t l, v[3];
    const tr_instance *in = kept_of(s, id, &l);
    const tr_prototype *p = &s->protos[in->proto];
    if (!p->idx || !proto_tri_verts(p, l, v)) {
        return 0;
    }
    for (int k = 0; k < 3; ++k) {
        x[k] = p->verts[v[k]];
        x[k].normal = xform_normal(in->m, in->inv, p->verts[v[k]].normal);
    }
    return 1;
}

/* ---- Flattening kept instances --------------------------------------------------- */

/* Where stored vertex v goes once the kept instances' vertices are put in: after those
 * of every kept instance added when the stored count was at most v. bases[0..n) are
 * their vert_base values (ascending), before[k] the vertices of the first k. */
static uint32_t moved_vertex(uint32_t v, const uint32_t *bases, const uint64_t *before,
                             uint32_t n) {
    uint32_t lo = 0, hi = n;
    while (lo < hi) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (bases[mid] <= v) {
            lo = mid + 1;
        } else {
            hi = mid;
        }
    }
    return (uint32_t)(v + before[lo]);
}

int tr_scene_flatten(tr_scene *s, tr_error *err) {
    if (s->placed_count == 0) {
        return TR_OK;
    }
    const uint64_t nt = (uint64_t)s->triangle_count + s->placed_count;
    uint64_t nv = s->vertex_count;
    uint32_t na = 0;
    for (uint32_t i = 0; i < s->instance_count; ++i) {
        const tr_instance *in = &s->instances[i];
        if (!in->flat && s->protos[in->proto].idx) {
            nv += s->protos[in->proto].vert_count;
            na++;
        }
    }
    if (nv >= TR_NO_INDEX) {
        return tr_error_set(err, TR_STATUS_LIMIT,
                            "flattening the instances would exceed %u vertices", TR_NO_INDEX - 1u);
    }
    tr_triangle *tris = malloc((size_t)nt * sizeof *tris);
    tr_tri_verts *tv = malloc((size_t)nt * sizeof *tv);
    tr_vertex *verts = malloc((size_t)(nv ? nv : 1) * sizeof *verts);
    uint32_t *bases = malloc((size_t)(na ? na : 1) * sizeof *bases);
    uint32_t *new_base = malloc((size_t)(na ? na : 1) * sizeof *new_base);
    uint64_t *before = malloc(((size_t)na + 1) * sizeof *before);
    if (!tris || !tv || !verts || !bases || !new_base || !before) {
        free(tris);
        free(tv);
        free(verts);
        free(bases);
        free(new_base);
        free(before);
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY,
                            "out of memory flattening %llu placed triangles",
                            (unsigned long long)s->placed_count);
    }
    /* Vertices in the order of their addition: stored runs between kept instances'. */
    uint64_t w = 0;
    uint32_t sv = 0, k = 0;
    before[0] = 0;
    for (uint32_t i = 0; i < s->instance_count; ++i) {
        const tr_instance *in = &s->instances[i];
        const tr_prototype *p = &s->protos[in->proto];
        if (in->flat || !p->idx) {
            continue;
        }
        const uint32_t vb = in->vert_base < s->vertex_count ? in->vert_base : s->vertex_count;
        if (vb > sv) {
            memcpy(verts + w, s->vertices + sv, (size_t)(vb - sv) * sizeof *verts);
            w += vb - sv;
            sv = vb;
        }
        new_base[k] = (uint32_t)w;
        place_verts(p, in->m, in->inv, verts + w);
        w += p->vert_count;
        bases[k] = in->vert_base;
        before[k + 1] = before[k] + p->vert_count;
        k++;
    }
    if (s->vertex_count > sv) {
        memcpy(verts + w, s->vertices + sv, (size_t)(s->vertex_count - sv) * sizeof *verts);
    }
    /* Triangles and their vertex indices, shape by shape. */
    uint64_t ft = 0, tvc = 0;
    uint32_t j = 0;
    k = 0;
    for (uint32_t sh = 0; sh < s->shape_count; ++sh) {
        while (j < s->instance_count && s->instances[j].shape < sh) {
            ++j;
        }
        tr_instance *in =
            j < s->instance_count && s->instances[j].shape == sh ? &s->instances[j] : NULL;
        tr_flat_node *node = &s->shapes[sh];
        if (in && !in->flat) {
            const tr_prototype *p = &s->protos[in->proto];
            place_tris(p, in->m, tris + ft);
            for (uint32_t l = 0; l < node->count; ++l) {
                tr_tri_verts *t = &tv[ft + l];
                uint32_t v[3];
                t->v[0] = t->v[1] = t->v[2] = TR_NO_INDEX;
                if (p->idx) {
                    proto_tri_verts(p, l, v);
                    for (int c = 0; c < 3; ++c) {
                        t->v[c] = v[c] == TR_NO_INDEX ? TR_NO_INDEX : new_base[k] + v[c];
                    }
                    if (t->v[1] == TR_NO_INDEX || t->v[2] == TR_NO_INDEX) {
                        t->v[0] = TR_NO_INDEX;
                    }
                }
            }
            if (p->idx) {
                tvc = ft + node->count;
                in->vert_base = new_base[k++];
            } else {
                in->vert_base = moved_vertex(in->vert_base, bases, before, k);
            }
        } else {
            memcpy(tris + ft, s->triangles + node->first, (size_t)node->count * sizeof *tris);
            for (uint32_t l = 0; l < node->count; ++l) {
                const uint32_t st = node->first + l;
                tr_tri_verts *t = &tv[ft + l];
                t->v[0] = t->v[1] = t->v[2] = TR_NO_INDEX;
                if (st < s->tri_verts_count) {
                    for (int c = 0; c < 3; ++c) {
                        const uint32_t v = s->tri_verts[st].v[c];
                        t->v[c] = v == TR_NO_INDEX ? v : moved_vertex(v, bases, before, na);
                    }
                }
            }
            if (node->count > 0 && node->first + node->count <= s->tri_verts_count) {
                tvc = ft + node->count > tvc ? ft + node->count : tvc;
            }
            if (in) {
                in->vert_base = moved_vertex(in->vert_base, bases, before, na);
            }
        }
        if (in) {
            in->flat = 1;
            in->at = (uint32_t)ft;
        }
        node->first = (uint32_t)ft;
        ft += node->count;
    }
    free(bases);
    free(new_base);
    free(before);
    free(s->triangles);
    free(s->vertices);
    free(s->tri_verts);
    s->triangles = tris;
    s->triangle_count = s->triangle_capacity = (uint32_t)nt;
    s->vertices = verts;
    s->vertex_count = (uint32_t)nv;
    s->vertex_capacity = (uint32_t)(nv ? nv : 1);
    s->tri_verts = tv;
    s->tri_verts_count = (uint32_t)tvc;
    s->tri_verts_capacity = (uint32_t)nt;
    s->placed_count = 0;
    tr_scene_free_two_level(s);
    tr_scene_instance_ids(s);
    return TR_OK;
}

int tr_scene_kept_emit(const tr_scene *s) {
    for (uint32_t i = 0; i < s->proto_count; ++i) {
        if (!proto_emits(s, &s->protos[i])) {
            continue;
        }
        for (uint32_t k = 0; k < s->instance_count; ++k) {
            if (!s->instances[k].flat && s->instances[k].proto == i) {
                return 1;
            }
        }
    }
    return 0;
}

/* Prototype p's triangles with a nonzero vertex normal (what an instance's placement
 * keeps: the inverse transpose of an invertible matrix sends no normal to zero). */
static uint64_t proto_normals(const tr_prototype *p) {
    uint64_t n = 0;
    for (uint32_t l = 0; p->idx && l < p->tri_count; ++l) {
        uint32_t v[3];
        if (!proto_tri_verts(p, l, v)) {
            continue;
        }
        int has = 0;
        for (int k = 0; k < 3; ++k) {
            const tr_vec3 q = p->verts[v[k]].normal;
            has |= q.x != 0.0f || q.y != 0.0f || q.z != 0.0f;
        }
        n += (uint64_t)has;
    }
    return n;
}

uint32_t tr_scene_kept_normals(const tr_scene *s) {
    uint64_t n = 0;
    for (uint32_t k = 0; s->placed_count > 0 && k < s->proto_count; ++k) {
        uint64_t placements = 0;
        for (uint32_t i = 0; i < s->instance_count; ++i) {
            placements += !s->instances[i].flat && s->instances[i].proto == k;
        }
        if (placements > 0) {
            n += placements * proto_normals(&s->protos[k]);
        }
    }
    return (uint32_t)n;
}

int tr_scene_flatten_committed(tr_scene *s, tr_error *err) {
    if (!tr_scene_has_kept_instances(s)) {
        return TR_OK;
    }
    const int current = tr_scene_is_committed(s);
    const tr_accel_type accel = s->accel;
    if (tr_scene_flatten(s, err) != TR_OK) {
        return TR_ERR;
    }
    return current ? tr_scene_commit(s, accel, err) : TR_OK;
}
