/* shape.c - shapes as generators of triangles (the thesis's Shape::make_*). */
#include <stdlib.h>
#include <string.h>

#include "trac0r/scene.h"
#include "scene_internal.h"

tr_shape_desc tr_shape_desc_default(tr_shape_type type) {
    tr_shape_desc d;
    memset(&d, 0, sizeof d);
    d.type = type;
    d.transform.scale = v3s(1.0f);
    return d;
}

void tr_triangle_finish(tr_triangle *t) {
    t->centroid = v3_scale(v3_add(v3_add(t->v0, t->v1), t->v2), 1.0f / 3.0f);
    /* In double: the squared length of a float cross product overflows for edges
     * beyond about 4e9, which would mark large triangles degenerate. */
    double ax = (double)t->v1.x - t->v0.x, ay = (double)t->v1.y - t->v0.y;
    double az = (double)t->v1.z - t->v0.z, bx = (double)t->v2.x - t->v0.x;
    double by = (double)t->v2.y - t->v0.y, bz = (double)t->v2.z - t->v0.z;
    double cx = ay * bz - az * by, cy = az * bx - ax * bz, cz = ax * by - ay * bx;
    double len = sqrt(cx * cx + cy * cy + cz * cz);
    if (len > 0.0 && isfinite(len)) {
        t->normal = v3((float)(cx / len), (float)(cy / len), (float)(cz / len));
        t->area = (float)(0.5 * len);
    } else {
        t->normal = v3s(0.0f);
        t->area = 0.0f;
    }
}

tr_aabb tr_triangles_bounds(const tr_triangle *t, uint32_t n) {
    tr_aabb b = {v3s(INFINITY), v3s(-INFINITY)};
    for (uint32_t i = 0; i < n; ++i) {
        b.min = v3_min(b.min, v3_min(t[i].v0, v3_min(t[i].v1, t[i].v2)));
        b.max = v3_max(b.max, v3_max(t[i].v0, v3_max(t[i].v1, t[i].v2)));
    }
    return b;
}

uint64_t tr_shape_triangle_count(const tr_shape_desc *desc) {
    switch (desc->type) {
    case TR_SHAPE_PLANE:
        return 2;
    case TR_SHAPE_BOX:
        return 12;
    case TR_SHAPE_ICOSPHERE:
    case TR_SHAPE_ICOSPHERE_SMOOTH:
        if (desc->subdivisions > TR_ICOSPHERE_MAX_SUBDIVISIONS) {
            return 0;
        }
        return 20ull << (2u * desc->subdivisions);
    }
    return 0;
}

/* Rotation about x, then y, then z. */
static tr_vec3 rotate_xyz(tr_vec3 p, tr_vec3 angles) {
    float c = cosf(angles.x), s = sinf(angles.x);
    p = v3(p.x, c * p.y - s * p.z, s * p.y + c * p.z);
    c = cosf(angles.y), s = sinf(angles.y);
    p = v3(c * p.x + s * p.z, p.y, -s * p.x + c * p.z);
    c = cosf(angles.z), s = sinf(angles.z);
    return v3(c * p.x - s * p.y, s * p.x + c * p.y, p.z);
}

static tr_vec3 apply_transform(const tr_transform *tf, tr_vec3 p) {
    return v3_add(rotate_xyz(v3_mul(p, tf->scale), tf->orientation), tf->position);
}

tr_vec3 tr_transform_point(const tr_transform *tf, tr_vec3 p) {
    return apply_transform(tf, p);
}

tr_vec3 tr_transform_normal(const tr_transform *tf, tr_vec3 n) {
    /* M = R S, so (M^-1)^T = R S^-1. */
    tr_vec3 m =
        rotate_xyz(v3(n.x / tf->scale.x, n.y / tf->scale.y, n.z / tf->scale.z), tf->orientation);
    float len = v3_length(m);
    return len > 0.0f && isfinite(len) ? v3_scale(m, 1.0f / len) : v3s(0.0f);
}

static tr_triangle make_tri(tr_vec3 a, tr_vec3 b, tr_vec3 c) {
    tr_triangle t;
    memset(&t, 0, sizeof t);
    t.v0 = a;
    t.v1 = b;
    t.v2 = c;
    return t;
}

/* Two triangles spanning [-0.5, 0.5]^2 in the xz plane, wound so the normal is +y. */
static uint32_t gen_plane(tr_triangle *out) {
    tr_vec3 a = v3(-0.5f, 0.0f, -0.5f), b = v3(0.5f, 0.0f, -0.5f);
    tr_vec3 c = v3(0.5f, 0.0f, 0.5f), d = v3(-0.5f, 0.0f, 0.5f);
    out[0] = make_tri(a, c, b);
    out[1] = make_tri(a, d, c);
    return 2;
}

/* The unit cube [-0.5, 0.5]^3: two triangles per face, normals outward. */
static uint32_t gen_box(tr_triangle *out) {
    uint32_t n = 0;
    for (int axis = 0; axis < 3; ++axis) {
        for (int side = -1; side <= 1; side += 2) {
            /* Face with outward normal side * e_axis; (u, v) span it so that u x v = normal. */
            float h = 0.5f * (float)side;
            tr_vec3 nrm, u, v;
            if (axis == 0) {
                nrm = v3(h, 0, 0), u = v3(0, 0.5f, 0), v = v3(0, 0, 0.5f);
            } else if (axis == 1) {
                nrm = v3(0, h, 0), u = v3(0, 0, 0.5f), v = v3(0.5f, 0, 0);
            } else {
                nrm = v3(0, 0, h), u = v3(0.5f, 0, 0), v = v3(0, 0.5f, 0);
            }
            if (side < 0) {
                u = v3_neg(u);
            }
            tr_vec3 p00 = v3_sub(v3_sub(nrm, u), v), p10 = v3_sub(v3_add(nrm, u), v);
            tr_vec3 p11 = v3_add(v3_add(nrm, u), v), p01 = v3_add(v3_sub(nrm, u), v);
            out[n++] = make_tri(p00, p10, p11);
            out[n++] = make_tri(p00, p11, p01);
        }
    }
    return n;
}

/* An icosahedron on the unit sphere, each face split into four n times with the new
 * vertices pushed out to the sphere: 20 * 4^n triangles. `out` holds the final count;
 * `tmp` is scratch of the same size. */
static uint32_t gen_icosphere(tr_triangle *out, tr_triangle *tmp, uint32_t levels) {
    const float g = 1.6180339887498949f; /* golden ratio */
    tr_vec3 v[12] = {v3(-1, g, 0), v3(1, g, 0), v3(-1, -g, 0), v3(1, -g, 0),
                     v3(0, -1, g), v3(0, 1, g), v3(0, -1, -g), v3(0, 1, -g),
                     v3(g, 0, -1), v3(g, 0, 1), v3(-g, 0, -1), v3(-g, 0, 1)};
    static const int f[20][3] = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                 {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                 {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                 {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
    for (int i = 0; i < 12; ++i) {
        v[i] = v3_normalize(v[i]);
    }
    /* Ping-pong between the buffers so that the last level lands in `out`. */
    tr_triangle *cur = (levels % 2 == 0) ? out : tmp;
    tr_triangle *next = (levels % 2 == 0) ? tmp : out;
    for (int i = 0; i < 20; ++i) {
        cur[i] = make_tri(v[f[i][0]], v[f[i][1]], v[f[i][2]]);
    }
    uint32_t n = 20;
    for (uint32_t l = 0; l < levels; ++l) {
        for (uint32_t i = 0; i < n; ++i) {
            tr_vec3 a = cur[i].v0, b = cur[i].v1, c = cur[i].v2;
            tr_vec3 ab = v3_normalize(v3_add(a, b));
            tr_vec3 bc = v3_normalize(v3_add(b, c));
            tr_vec3 ca = v3_normalize(v3_add(c, a));
            next[4 * i + 0] = make_tri(a, ab, ca);
            next[4 * i + 1] = make_tri(ab, b, bc);
            next[4 * i + 2] = make_tri(ca, bc, c);
            next[4 * i + 3] = make_tri(ab, bc, ca);
        }
        n *= 4;
        tr_triangle *t = cur;
        cur = next;
        next = t;
    }
    return n;
}

static int check_vec(tr_vec3 v, const char *what, tr_error *err) {
    const float huge = 1e30f;
    if (!v3_is_finite(v) || fabsf(v.x) > huge || fabsf(v.y) > huge || fabsf(v.z) > huge) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "shape %s (%g, %g, %g) is not a finite number below 1e30", what,
                            (double)v.x, (double)v.y, (double)v.z);
    }
    return TR_OK;
}

/* Generates the shape's triangles into a new array (caller frees); for a smooth icosphere
 * also its vertex normals, three per triangle (*normals, caller frees; NULL otherwise). */
static int shape_generate(const tr_shape_desc *desc, tr_triangle **out, uint32_t *count,
                          tr_vec3 **normals, tr_error *err) {
    const int ico = desc->type == TR_SHAPE_ICOSPHERE || desc->type == TR_SHAPE_ICOSPHERE_SMOOTH;
    *normals = NULL;
    if (check_vec(desc->transform.position, "position", err) != TR_OK ||
        check_vec(desc->transform.orientation, "orientation", err) != TR_OK ||
        check_vec(desc->transform.scale, "scale", err) != TR_OK) {
        return TR_ERR;
    }
    tr_vec3 sc = desc->transform.scale;
    if (!(sc.x > 0.0f && sc.y > 0.0f && sc.z > 0.0f)) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "shape scale (%g, %g, %g) must be positive", (double)sc.x, (double)sc.y,
                            (double)sc.z);
    }
    if (ico && desc->subdivisions > TR_ICOSPHERE_MAX_SUBDIVISIONS) {
        return tr_error_set(err, TR_STATUS_LIMIT,
                            "icosphere subdivisions %u exceed the limit of %d (%llu triangles)",
                            desc->subdivisions, TR_ICOSPHERE_MAX_SUBDIVISIONS,
                            20ull << (2u * TR_ICOSPHERE_MAX_SUBDIVISIONS));
    }
    uint64_t n = tr_shape_triangle_count(desc);
    if (n == 0) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT, "unknown shape type %d",
                            (int)desc->type);
    }
    tr_triangle *tris = malloc((size_t)n * sizeof *tris);
    tr_triangle *tmp = ico ? malloc((size_t)n * sizeof *tmp) : NULL;
    tr_vec3 *nrm =
        desc->type == TR_SHAPE_ICOSPHERE_SMOOTH ? malloc((size_t)n * 3 * sizeof *nrm) : NULL;
    if (!tris || (ico && !tmp) || (desc->type == TR_SHAPE_ICOSPHERE_SMOOTH && !nrm)) {
        free(tris);
        free(tmp);
        free(nrm);
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory generating %llu triangles",
                            (unsigned long long)n);
    }
    uint32_t made = 0;
    switch (desc->type) {
    case TR_SHAPE_PLANE:
        made = gen_plane(tris);
        break;
    case TR_SHAPE_BOX:
        made = gen_box(tris);
        break;
    case TR_SHAPE_ICOSPHERE:
    case TR_SHAPE_ICOSPHERE_SMOOTH:
        made = gen_icosphere(tris, tmp, desc->subdivisions);
        break;
    }
    free(tmp);
    for (uint32_t i = 0; nrm && i < made; ++i) {
        /* The unit sphere's normal at a vertex is the vertex. */
        nrm[3 * i + 0] = tr_transform_normal(&desc->transform, tris[i].v0);
        nrm[3 * i + 1] = tr_transform_normal(&desc->transform, tris[i].v1);
        nrm[3 * i + 2] = tr_transform_normal(&desc->transform, tris[i].v2);
    }
    *normals = nrm;
    for (uint32_t i = 0; i < made; ++i) {
        tris[i].v0 = apply_transform(&desc->transform, tris[i].v0);
        tris[i].v1 = apply_transform(&desc->transform, tris[i].v1);
        tris[i].v2 = apply_transform(&desc->transform, tris[i].v2);
        tris[i].material = desc->material;
        tr_triangle_finish(&tris[i]);
    }
    *out = tris;
    *count = made;
    return TR_OK;
}

int tr_scene_add_shape(tr_scene *s, const tr_shape_desc *desc, tr_error *err) {
    if (desc->material >= s->material_count) {
        return tr_error_set(err, TR_STATUS_NOT_FOUND,
                            "shape refers to material %u, but the scene has %u materials",
                            desc->material, s->material_count);
    }
    tr_triangle *tris = NULL;
    tr_vec3 *normals = NULL;
    uint32_t n = 0;
    if (shape_generate(desc, &tris, &n, &normals, err) != TR_OK) {
        return TR_ERR;
    }
    int rc = tr_scene_append_shape(s, tris, n, normals, err);
    free(tris);
    free(normals);
    return rc;
}
