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

static void place_tris(const tr_prototype *p, const float m[12], tr_triangle *out) {
    for (uint32_t i = 0; i < p->tri_count; ++i) {
        tr_triangle t = p->tris[i];
        t.v0 = xform_point(m, t.v0);
        t.v1 = xform_point(m, t.v1);
        t.v2 = xform_point(m, t.v2);
        tr_triangle_finish(&t);
        out[i] = t;
    }
}

static void place_verts(const tr_prototype *p, const float m[12], const float inv[12],
                        tr_vertex *out) {
    for (uint32_t i = 0; i < p->vert_count; ++i) {
        out[i] = p->verts[i];
        out[i].normal = xform_normal(m, inv, p->verts[i].normal);
    }
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

int tr_scene_triangle_instance(const tr_scene *s, uint32_t triangle, uint32_t *instance,
                               uint32_t *prim) {
    uint32_t lo = 0, hi = s->instance_count;
    while (lo < hi) { /* the first instance starting beyond the triangle */
        uint32_t mid = lo + (hi - lo) / 2;
        if (s->shapes[s->instances[mid].shape].first <= triangle) {
            lo = mid + 1;
        } else {
            hi = mid;
        }
    }
    if (lo == 0) {
        return 0;
    }
    const tr_flat_node *sh = &s->shapes[s->instances[lo - 1].shape];
    if (triangle >= sh->first + sh->count) {
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
    for (uint32_t i = 0; i < n; ++i) {
        const tr_material *mt = &s->materials[p.tris[i].material];
        p.emissive |= mt->type == TR_MATERIAL_EMITTER && mt->emittance > 0.0f;
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

int tr_scene_add_instance(tr_scene *s, uint32_t proto, const float m[12], uint32_t *instance,
                          tr_error *err) {
    float inv[12];
    if (proto >= s->proto_count) {
        return tr_error_set(err, TR_STATUS_NOT_FOUND, "prototype %u does not exist (%u made)",
                            proto, s->proto_count);
    }
    if (invert(m, inv, "instance", s->instance_count, err) != TR_OK ||
        grow((void **)&s->instances, &s->instance_capacity, (uint64_t)s->instance_count + 1,
             sizeof *s->instances, err) != TR_OK) {
        return TR_ERR;
    }
    tr_instance in;
    memset(&in, 0, sizeof in);
    in.proto = proto;
    in.vert_base = s->vertex_count;
    memcpy(in.m, m, sizeof in.m);
    memcpy(in.inv, inv, sizeof in.inv);
    if (append_placed(s, &s->protos[proto], m, inv, err) != TR_OK) {
        return TR_ERR;
    }
    in.shape = s->shape_count - 1;
    s->instances[s->instance_count] = in;
    if (instance) {
        *instance = s->instance_count;
    }
    s->instance_count++;
    return TR_OK;
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
    place_tris(p, m, s->triangles + sh->first);
    if (p->idx) {
        place_verts(p, m, inv, s->vertices + in->vert_base);
    }
    sh->box = tr_triangles_bounds(s->triangles + sh->first, sh->count);
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
        tr_bvh_free(&p->bvh);
        tr_wbvh_free(&p->wbvh);
    }
    free(s->protos);
    free(s->instances);
    free(s->moved);
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
        if (tr_bvh_build(&p->bvh, p->tris, p->tri_count, err) != TR_OK) {
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
        memset(skip + sh->first, 1, sh->count);
        memcpy(inst[i].inv, in->inv, sizeof in->inv);
        inst[i].blas = &s->protos[in->proto].wbvh;
        inst[i].tri_base = sh->first;
        inst[i].identity = 0;
        boxes[i] = sh->box;
    }
    if (rc == TR_OK) {
        rc = tr_bvh_build_skip(&s->rest_bvh, s->triangles, s->triangle_count, skip, err);
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
