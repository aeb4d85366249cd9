/* scene.c - the scene's arrays and materials. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "kernel/ggx_ms.h"
#include "kernel/punctual.h"
#include "scene_internal.h"
#include "trac0r/render.h"
#include "trac0r/parse.h"
#include "trac0r/scene.h"
#include "material_registry.h"
#include "scene_internal.h"
#include "util/bigmem.h"

tr_material tr_material_emitter(tr_vec3 color, float emittance) {
    tr_material m = tr_material_default(TR_MATERIAL_EMITTER);
    m.color = color;
    m.emittance = emittance;
    return m;
}
tr_material tr_material_diffuse(tr_vec3 color) {
    tr_material m = tr_material_default(TR_MATERIAL_DIFFUSE);
    m.color = color;
    return m;
}
tr_material tr_material_glass(tr_vec3 color, float ior) {
    tr_material m = tr_material_default(TR_MATERIAL_GLASS);
    m.color = color;
    m.ior = ior;
    return m;
}
tr_material tr_material_glossy(tr_vec3 color, float roughness) {
    tr_material m = tr_material_default(TR_MATERIAL_GLOSSY);
    m.color = color;
    m.roughness = roughness;
    return m;
}

static int grow(void **arr, uint32_t *cap, uint64_t need, size_t elem, const char *what,
                tr_error *err);

void tr_scene_init(tr_scene *s) {
    memset(s, 0, sizeof *s);
}

tr_scene *tr_scene_create(tr_error *err) {
    tr_scene *s = malloc(sizeof *s);
    if (!s) {
        tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory creating a scene");
        return NULL;
    }
    tr_scene_init(s);
    return s;
}

void tr_scene_destroy(tr_scene *s) {
    if (s) {
        tr_scene_clear(s);
        free(s);
        /* The blocks its structures gave back were kept for its next build (bigmem.h). */
        tr_bigmem_trim();
    }
}

void tr_scene_clear(tr_scene *s) {
    /* The generation goes on counting: a device holding an upload of the old content
     * must not take the emptied (or reloaded) scene for the one it has. */
    const uint64_t generation = s->generation;
    free(s->materials);
    free(s->light_base);
    free(s->triangles);
    free(s->shapes);
    free(s->shape_moved);
    free(s->vertices);
    free(s->tri_verts);
    free(s->textures);
    free(s->texels);
    for (uint32_t i = 0; i < s->texture_file_count; ++i) {
        free(s->texture_files[i]);
    }
    free(s->texture_files);
    free(s->material_exts);
    free(s->env_texels);
    free(s->env_cdf);
    free(s->punctual);
    tr_bvh_free(&s->bvh);
    tr_wbvh_free(&s->wbvh);
    tr_embree_free(&s->embree);
    free(s->lights);
    free(s->light_cdf);
    tr_scene_free_light_tree(s);
    tr_scene_free_instances(s);
    tr_scene_init(s);
    s->generation = generation + 1;
}

int tr_scene_add_material(tr_scene *s, tr_material m, uint32_t *index, tr_error *err) {
    if (tr_material_check(&m, err) != TR_OK) {
        return TR_ERR;
    }
    if (s->material_count == s->material_capacity) {
        uint32_t cap = s->material_capacity ? 2 * s->material_capacity : 8;
        tr_material *grown = realloc(s->materials, (size_t)cap * sizeof *grown);
        if (!grown) {
            return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory adding a material");
        }
        s->materials = grown;
        s->material_capacity = cap;
    }
    if (s->material_ext_count == s->material_count && s->material_ext_count > 0) {
        if (grow((void **)&s->material_exts, &s->material_ext_capacity,
                 (uint64_t)s->material_ext_count + 1, sizeof *s->material_exts, "material extras",
                 err) != TR_OK) {
            return TR_ERR;
        }
        s->material_exts[s->material_ext_count++] = tr_material_ext_default();
    }
    s->materials[s->material_count] = m;
    if (index) {
        *index = s->material_count;
    }
    s->material_count++;
    s->generation++;
    return TR_OK;
}

/* Grows *arr (capacity *cap elements of `elem` bytes) to hold at least `need`. */
static int grow(void **arr, uint32_t *cap, uint64_t need, size_t elem, const char *what,
                tr_error *err) {
    if (need <= *cap) {
        return TR_OK;
    }
    if (need > UINT32_MAX) {
        return tr_error_set(err, TR_STATUS_LIMIT, "more than %u %s", UINT32_MAX, what);
    }
    uint64_t c = (uint64_t)*cap * 2;
    if (c < need) {
        c = need;
    }
    if (c > UINT32_MAX) {
        c = UINT32_MAX;
    }
    void *grown = realloc(*arr, (size_t)c * elem);
    if (!grown) {
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory storing %llu %s",
                            (unsigned long long)need, what);
    }
    /* The part not yet written on huge pages, for a big scene's arrays (bigmem.h). */
    tr_bigmem_advise(grown, (size_t)c * elem);
    *arr = grown;
    *cap = (uint32_t)c;
    return TR_OK;
}

tr_material_ext tr_material_ext_default(void) {
    tr_material_ext e;
    memset(&e, 0, sizeof e);
    e.base_tex = e.emission_tex = e.mr_tex = e.normal_tex = e.transmission_tex = TR_NO_INDEX;
    e.clearcoat_tex = e.clearcoat_rough_tex = TR_NO_INDEX;
    e.sheen_color_tex = e.sheen_rough_tex = e.clearcoat_normal_tex = TR_NO_INDEX;
    e.clearcoat_normal_scale = 1.0f;
    e.alpha_cutoff = 0.5f;
    e.normal_scale = 1.0f;
    return e;
}

tr_vec3 tr_volume_absorption(tr_vec3 color, float distance) {
    const float c[3] = {color.x, color.y, color.z};
    float a[3];
    for (int k = 0; k < 3; ++k) {
        a[k] = c[k] > 0.0f && c[k] < 1.0f && distance > 0.0f ? -logf(c[k]) / distance : 0.0f;
    }
    return v3(a[0], a[1], a[2]);
}

int tr_scene_set_material_ext(tr_scene *s, uint32_t index, const tr_material_ext *ext,
                              tr_error *err) {
    if (index >= s->material_count) {
        return tr_error_set(err, TR_STATUS_NOT_FOUND, "material %u of %u", index,
                            s->material_count);
    }
    const uint32_t tex[10] = {ext->base_tex,
                              ext->emission_tex,
                              ext->mr_tex,
                              ext->normal_tex,
                              ext->transmission_tex,
                              ext->clearcoat_tex,
                              ext->clearcoat_rough_tex,
                              ext->sheen_color_tex,
                              ext->sheen_rough_tex,
                              ext->clearcoat_normal_tex};
    for (int k = 0; k < 10; ++k) {
        if (tex[k] != TR_NO_INDEX && tex[k] >= s->texture_count) {
            return tr_error_set(err, TR_STATUS_NOT_FOUND,
                                "material %u refers to texture %u, but the scene has %u", index,
                                tex[k], s->texture_count);
        }
    }
    if (!v3_is_finite(ext->emission) || !isfinite(ext->metallic) || !isfinite(ext->alpha_cutoff) ||
        !isfinite(ext->normal_scale) || !isfinite(ext->clearcoat_normal_scale)) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "material %u has a non-finite parameter", index);
    }
    if (!(ext->clearcoat >= 0.0f && ext->clearcoat <= 1.0f) ||
        !(ext->clearcoat_roughness >= 0.0f && ext->clearcoat_roughness <= 1.0f)) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "material %u: clear coat weight or roughness outside [0, 1]", index);
    }
    if (!(ext->sheen_color.x >= 0.0f && ext->sheen_color.x <= 1.0f) ||
        !(ext->sheen_color.y >= 0.0f && ext->sheen_color.y <= 1.0f) ||
        !(ext->sheen_color.z >= 0.0f && ext->sheen_color.z <= 1.0f) ||
        !(ext->sheen_roughness >= 0.0f && ext->sheen_roughness <= 1.0f)) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "material %u: sheen colour or roughness outside [0, 1]", index);
    }
    if ((ext->flags & TR_MATEXT_SPECULAR) != 0u &&
        (!(ext->specular >= 0.0f && ext->specular <= 1.0f) ||
         !(ext->specular_color.x >= 0.0f && ext->specular_color.x <= 10.0f) ||
         !(ext->specular_color.y >= 0.0f && ext->specular_color.y <= 10.0f) ||
         !(ext->specular_color.z >= 0.0f && ext->specular_color.z <= 10.0f))) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "material %u: specular outside [0, 1] or its colour outside [0, 10]",
                            index);
    }
    if (!(ext->transmission >= 0.0f && ext->transmission <= 1.0f) ||
        !(ext->absorption.x >= 0.0f && ext->absorption.y >= 0.0f && ext->absorption.z >= 0.0f) ||
        !v3_is_finite(ext->absorption)) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "material %u: transmission outside [0, 1] or a negative or "
                            "non-finite absorption",
                            index);
    }
    if (s->material_ext_count < s->material_count) {
        if (grow((void **)&s->material_exts, &s->material_ext_capacity, s->material_count,
                 sizeof *s->material_exts, "material extras", err) != TR_OK) {
            return TR_ERR;
        }
        for (uint32_t i = s->material_ext_count; i < s->material_count; ++i) {
            s->material_exts[i] = tr_material_ext_default();
        }
        s->material_ext_count = s->material_count;
    }
    s->material_exts[index] = *ext;
    s->generation++;
    return TR_OK;
}

int tr_scene_texel_budget(uint32_t *budget, tr_error *err) {
    *budget = TR_TEXEL_BUDGET_DEFAULT;
    const char *e = getenv("TRAC0R_TEXEL_BUDGET");
    uint64_t v = 0;
    if (e && *e) {
        if (tr_parse_uint64(e, 1, UINT32_MAX, &v) != TR_OK) {
            return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                                "TRAC0R_TEXEL_BUDGET=\"%.40s\": expected a texel count in 1..%u", e,
                                UINT32_MAX);
        }
        *budget = (uint32_t)v;
    }
    return TR_OK;
}

void tr_texture_transform_glTF(float xf[6], float offset_u, float offset_v, float rotation,
                               float scale_u, float scale_v) {
    /* T R S: scale, then rotate, then offset. The rotation's rows are (cos, sin) and
     * (-sin, cos), the direction glTF's TextureTransformTest model asks for (its arrows
     * point at the green markers; the other sign points them at the red one). */
    const float c = cosf(rotation), sn = sinf(rotation);
    xf[0] = c * scale_u;
    xf[1] = sn * scale_v;
    xf[2] = offset_u;
    xf[3] = -sn * scale_u;
    xf[4] = c * scale_v;
    xf[5] = offset_v;
}

int tr_scene_texture_transformed(tr_scene *s, uint32_t tex, const float xf[6], uint32_t *index,
                                 tr_error *err) {
    if (tex >= s->texture_count) {
        return tr_error_set(err, TR_STATUS_NOT_FOUND, "texture %u of %u", tex, s->texture_count);
    }
    for (int k = 0; k < 6; ++k) {
        if (!isfinite(xf[k])) {
            return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                                "a texture transform with a non-finite entry");
        }
    }
    if (xf[0] == 1.0f && xf[1] == 0.0f && xf[2] == 0.0f && xf[3] == 0.0f && xf[4] == 1.0f &&
        xf[5] == 0.0f) {
        *index = tex; /* the identity: the image as it is */
        return TR_OK;
    }
    if (grow((void **)&s->textures, &s->texture_capacity, (uint64_t)s->texture_count + 1,
             sizeof *s->textures, "textures", err) != TR_OK) {
        return TR_ERR;
    }
    tr_texture *t = &s->textures[s->texture_count];
    *t = s->textures[tex];
    t->flags |= TR_TEXTURE_TRANSFORM;
    memcpy(t->xf, xf, sizeof t->xf);
    *index = s->texture_count++;
    s->generation++;
    return TR_OK;
}

int tr_scene_add_texture(tr_scene *s, const uint32_t *rgba, uint32_t width, uint32_t height,
                         uint32_t flags, uint32_t *index, tr_error *err) {
    uint64_t n = (uint64_t)width * height;
    if (width == 0 || height == 0) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT, "a texture of %ux%u texels", width,
                            height);
    }
    uint32_t budget = 0;
    if (tr_scene_texel_budget(&budget, err) != TR_OK) {
        return TR_ERR;
    }
    if (n + s->texel_count > budget) {
        return tr_error_set(err, TR_STATUS_LIMIT,
                            "textures would hold %llu texels, more than the budget of %u "
                            "(TRAC0R_TEXEL_BUDGET)",
                            (unsigned long long)(n + s->texel_count), budget);
    }
    if (grow((void **)&s->texels, &s->texel_capacity, s->texel_count + n, sizeof *s->texels,
             "texels", err) != TR_OK ||
        grow((void **)&s->textures, &s->texture_capacity, (uint64_t)s->texture_count + 1,
             sizeof *s->textures, "textures", err) != TR_OK) {
        return TR_ERR;
    }
    memcpy(s->texels + s->texel_count, rgba, (size_t)n * sizeof *rgba);
    tr_texture *t = &s->textures[s->texture_count];
    t->offset = s->texel_count;
    t->width = width;
    t->height = height;
    t->flags = flags;
    tr_texture_transform_glTF(t->xf, 0.0f, 0.0f, 0.0f, 1.0f, 1.0f);
    s->texel_count += (uint32_t)n;
    if (index) {
        *index = s->texture_count;
    }
    s->texture_count++;
    s->generation++;
    return TR_OK;
}

void tr_scene_truncate(tr_scene *s, uint32_t triangles, uint32_t shapes, uint32_t materials) {
    s->triangle_count = triangles;
    s->shape_count = shapes;
    while (s->instance_count > 0 && s->instances[s->instance_count - 1].shape >= shapes) {
        s->instance_count--; /* instances among the shapes dropped go with them */
        const tr_instance *in = &s->instances[s->instance_count];
        if (!in->flat) {
            s->placed_count -= s->protos[in->proto].tri_count;
        }
    }
    s->material_count = materials;
    if (s->tri_verts_count > triangles) {
        s->tri_verts_count = triangles;
    }
    if (s->material_ext_count > materials) {
        s->material_ext_count = materials;
    }
    s->generation++;
}

int tr_scene_append_shape(tr_scene *s, const tr_triangle *tris, uint32_t n, const tr_vec3 *normals,
                          tr_error *err) {
    if (!normals) {
        return tr_scene_append_shape_attr(s, tris, n, NULL, 0, NULL, err);
    }
    if ((uint64_t)n * 3 > UINT32_MAX) {
        return tr_error_set(err, TR_STATUS_LIMIT, "more than %u vertices", UINT32_MAX);
    }
    tr_vertex *v = malloc((size_t)(n ? n : 1) * 3 * sizeof *v);
    uint32_t *idx = malloc((size_t)(n ? n : 1) * 3 * sizeof *idx);
    int rc = TR_OK;
    if (!v || !idx) {
        rc = tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory storing vertex normals");
    } else {
        for (uint32_t i = 0; i < 3 * n; ++i) {
            v[i].normal = normals[i];
            v[i].u = 0.0f;
            v[i].v = 0.0f;
            idx[i] = i;
        }
        rc = tr_scene_append_shape_attr(s, tris, n, v, 3 * n, idx, err);
    }
    free(v);
    free(idx);
    return rc;
}

int tr_scene_append_shape_attr(tr_scene *s, const tr_triangle *tris, uint32_t n,
                               const tr_vertex *verts, uint32_t nv, const uint32_t *idx,
                               tr_error *err) {
    if ((uint64_t)s->triangle_count + s->placed_count + n > TR_SCENE_MAX_TRIANGLES) {
        return tr_error_set(err, TR_STATUS_LIMIT, "scene would exceed %u triangles",
                            TR_SCENE_MAX_TRIANGLES);
    }
    if (verts && (uint64_t)s->vertex_count + nv >= TR_NO_INDEX) {
        return tr_error_set(err, TR_STATUS_LIMIT, "scene would exceed %u vertices",
                            TR_NO_INDEX - 1u);
    }
    int rc = grow((void **)&s->triangles, &s->triangle_capacity, (uint64_t)s->triangle_count + n,
                  sizeof *s->triangles, "triangles", err);
    if (rc == TR_OK) {
        rc = grow((void **)&s->shapes, &s->shape_capacity, (uint64_t)s->shape_count + 1,
                  sizeof *s->shapes, "shapes", err);
    }
    if (rc == TR_OK) {
        rc = grow((void **)&s->shape_moved, &s->shape_moved_capacity, (uint64_t)s->shape_count + 1,
                  sizeof *s->shape_moved, "shapes", err);
    }
    if (rc == TR_OK && verts) {
        rc = grow((void **)&s->vertices, &s->vertex_capacity, (uint64_t)s->vertex_count + nv,
                  sizeof *s->vertices, "vertices", err);
        if (rc == TR_OK) {
            rc = grow((void **)&s->tri_verts, &s->tri_verts_capacity,
                      (uint64_t)s->triangle_count + n, sizeof *s->tri_verts, "triangles", err);
        }
    }
    if (rc != TR_OK) {
        return rc;
    }
    memcpy(s->triangles + s->triangle_count, tris, (size_t)n * sizeof *tris);
    if (verts) {
        /* Triangles between the last attributed shape and this one have none. */
        for (uint32_t i = s->tri_verts_count; i < s->triangle_count; ++i) {
            s->tri_verts[i].v[0] = s->tri_verts[i].v[1] = s->tri_verts[i].v[2] = TR_NO_INDEX;
        }
        memcpy(s->vertices + s->vertex_count, verts, (size_t)nv * sizeof *verts);
        for (uint32_t i = 0; i < n; ++i) {
            for (int k = 0; k < 3; ++k) {
                uint32_t j = idx[3 * i + (uint32_t)k];
                s->tri_verts[s->triangle_count + i].v[k] =
                    j < nv ? s->vertex_count + j : TR_NO_INDEX;
            }
            if (s->tri_verts[s->triangle_count + i].v[1] == TR_NO_INDEX ||
                s->tri_verts[s->triangle_count + i].v[2] == TR_NO_INDEX) {
                s->tri_verts[s->triangle_count + i].v[0] = TR_NO_INDEX;
            }
        }
        s->vertex_count += nv;
        s->tri_verts_count = s->triangle_count + n;
    }
    s->shape_moved[s->shape_count] = v3s(0.0f);
    tr_flat_node *node = &s->shapes[s->shape_count++];
    node->box = tr_triangles_bounds(tris, n);
    node->first = s->triangle_count;
    node->count = n;
    s->triangle_count += n;
    s->generation++;
    return TR_OK;
}

int tr_scene_add_mesh(tr_scene *s, const float *positions, uint32_t vertex_count,
                      const uint32_t *indices, uint32_t triangle_count, const float *normals,
                      uint32_t material, const tr_transform *tf, uint32_t *dropped, tr_error *err) {
    return tr_scene_add_mesh_uv(s, positions, vertex_count, indices, triangle_count, normals, NULL,
                                material, tf, dropped, err);
}

int tr_scene_add_mesh_uv(tr_scene *s, const float *positions, uint32_t vertex_count,
                         const uint32_t *indices, uint32_t triangle_count, const float *normals,
                         const float *uvs, uint32_t material, const tr_transform *tf,
                         uint32_t *dropped, tr_error *err) {
    if (dropped) {
        *dropped = 0;
    }
    if (material >= s->material_count) {
        return tr_error_set(err, TR_STATUS_NOT_FOUND,
                            "mesh refers to material %u, but the scene has %u materials", material,
                            s->material_count);
    }
    if ((uint64_t)s->triangle_count + s->placed_count + triangle_count > TR_SCENE_MAX_TRIANGLES) {
        return tr_error_set(err, TR_STATUS_LIMIT, "scene would exceed %u triangles",
                            UINT32_MAX / 2);
    }
    tr_transform identity = {v3s(0.0f), v3s(0.0f), v3s(1.0f)};
    if (!tf) {
        tf = &identity;
    }
    for (uint32_t i = 0; i < 3 * vertex_count; ++i) {
        if (!isfinite(positions[i])) {
            return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                                "mesh vertex %u has a non-finite coordinate", i / 3);
        }
    }
    for (uint32_t i = 0; i < 3 * triangle_count; ++i) {
        if (indices[i] >= vertex_count) {
            return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                                "mesh triangle %u uses vertex %u of %u", i / 3, indices[i],
                                vertex_count);
        }
    }
    tr_triangle *tris = malloc((size_t)(triangle_count ? triangle_count : 1) * sizeof *tris);
    const int attr = normals || uvs;
    uint32_t *idx =
        attr ? malloc((size_t)(triangle_count ? triangle_count : 1) * 3 * sizeof *idx) : NULL;
    tr_vertex *verts =
        attr ? malloc((size_t)(vertex_count ? vertex_count : 1) * sizeof *verts) : NULL;
    if (!tris || (attr && (!idx || !verts))) {
        free(tris);
        free(idx);
        free(verts);
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY,
                            "out of memory adding a mesh of %u triangles", triangle_count);
    }
    uint32_t n = 0, bad = 0;
    for (uint32_t i = 0; i < triangle_count; ++i) {
        tr_triangle t;
        memset(&t, 0, sizeof t);
        tr_vec3 *v[3] = {&t.v0, &t.v1, &t.v2};
        for (int k = 0; k < 3; ++k) {
            const float *p = positions + (size_t)3 * indices[3 * i + k];
            *v[k] = tr_transform_point(tf, v3(p[0], p[1], p[2]));
        }
        t.material = material;
        tr_triangle_finish(&t);
        if (!(t.area > 0.0f) || !v3_is_finite(t.v0) || !v3_is_finite(t.v1) || !v3_is_finite(t.v2)) {
            bad++;
            continue;
        }
        if (idx) {
            for (int k = 0; k < 3; ++k) {
                idx[3 * n + (uint32_t)k] = indices[3 * i + (uint32_t)k];
            }
        }
        tris[n++] = t;
    }
    if (dropped) {
        *dropped = bad;
    }
    for (uint32_t i = 0; verts && i < vertex_count; ++i) {
        tr_vertex *o = &verts[i];
        o->normal = v3s(0.0f);
        if (normals) {
            tr_vec3 nv = v3(normals[3 * i], normals[3 * i + 1], normals[3 * i + 2]);
            if (v3_is_finite(nv) && v3_dot(nv, nv) > 0.0f) {
                o->normal = tr_transform_normal(tf, nv);
                if (!v3_is_finite(o->normal)) {
                    o->normal = v3s(0.0f);
                }
            }
        }
        o->u = uvs && isfinite(uvs[2 * i]) ? uvs[2 * i] : 0.0f;
        o->v = uvs && isfinite(uvs[2 * i + 1]) ? uvs[2 * i + 1] : 0.0f;
    }
    if (n == 0) {
        free(tris);
        free(idx);
        free(verts);
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "mesh has no triangles of non-zero area (%u dropped)", bad);
    }
    int rc = tr_scene_append_shape_attr(s, tris, n, verts, verts ? vertex_count : 0, idx, err);
    free(tris);
    free(idx);
    free(verts);
    return rc;
}

int tr_scene_commit(tr_scene *s, tr_accel_type accel, tr_error *err) {
    tr_bvh_free(&s->bvh);
    tr_wbvh_free(&s->wbvh);
    tr_embree_free(&s->embree);
    tr_scene_free_two_level(s);
    if (accel != TR_ACCEL_TYPE_BVH && accel != TR_ACCEL_TYPE_BVH2) {
        /* The blocks the structures just freed were kept for the next build of one of
         * this library's own (bigmem.h); another builder's memory must not wait on them. */
        tr_bigmem_trim();
    }
    s->accel = TR_ACCEL_TYPE_FLAT;
    s->committed_triangles = 0;
    s->committed = 0;
    /* Kept instances are traced by the CPU's two levels and by Embree's instancing: any
     * other structure gets them flattened here, as does a scene whose kept prototypes now
     * emit (a material's emittance changed), since the emitter table names stored
     * triangles. */
    const int traces_instances = accel == TR_ACCEL_TYPE_BVH || accel == TR_ACCEL_TYPE_EMBREE;
    if (tr_scene_has_kept_instances(s) && (!traces_instances || tr_scene_kept_emit(s)) &&
        tr_scene_flatten(s, err) != TR_OK) {
        return TR_ERR;
    }
    tr_scene_instance_ids(s);
    const uint32_t total = tr_scene_triangle_count(s);
    if (tr_scene_build_lights(s, err) != TR_OK) {
        return TR_ERR;
    }
    s->lights_dirty = 0;
    tr_scene_build_punctual(s);
    tr_scene_free_light_tree(s);
    if (tr_scene_light_tree_wanted(s) && tr_scene_build_light_tree(s, err) != TR_OK) {
        return TR_ERR;
    }
    /* Every successful case below builds for the scene as it is now. */
    s->committed_generation = s->generation;
    switch (accel) {
    case TR_ACCEL_TYPE_FLAT:
        s->committed_triangles = total;
        s->committed = 1;
        return TR_OK;
    case TR_ACCEL_TYPE_BVH:
        if (s->instance_count > 0) {
            /* Instances: the two-level structure (src/scene/instance.c). */
            if (tr_scene_build_two_level(s, err) != TR_OK) {
                return TR_ERR;
            }
            s->accel = accel;
            s->committed_triangles = total;
            s->committed = 1;
            return TR_OK;
        }
        if (tr_bvh_build_wide(&s->bvh, s->triangles, s->triangle_count, NULL, err) != TR_OK) {
            return TR_ERR;
        }
        /* The CPU traverses the wide BVH collapsed from the binary one. */
        if (tr_wbvh_build(&s->wbvh, &s->bvh, err) != TR_OK) {
            tr_bvh_free(&s->bvh);
            return TR_ERR;
        }
        s->accel = accel;
        s->committed_triangles = total;
        s->committed = 1;
        return TR_OK;
    case TR_ACCEL_TYPE_BVH2:
        if (tr_bvh_build(&s->bvh, s->triangles, s->triangle_count, err) != TR_OK) {
            return TR_ERR;
        }
        s->accel = accel;
        s->committed_triangles = total;
        s->committed = 1;
        return TR_OK;
    case TR_ACCEL_TYPE_EMBREE:
        /* Kept instances through Embree's instancing (src/scene/instance.c). */
        if ((tr_scene_has_kept_instances(s)
                 ? tr_scene_build_embree(s, err)
                 : tr_embree_build(&s->embree, s->triangles, s->triangle_count, err)) != TR_OK) {
            return TR_ERR;
        }
        s->accel = accel;
        s->committed_triangles = total;
        s->committed = 1;
        return TR_OK;
    }
    return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT, "unknown acceleration structure %d",
                        (int)accel);
}

int tr_scene_is_committed(const tr_scene *s) {
    return s->committed && s->committed_generation == s->generation;
}

int tr_scene_check_committed(const tr_scene *s, tr_error *err) {
    if (!s->committed) {
        return tr_error_set(err, TR_STATUS_STALE_SCENE,
                            "the scene is not committed: call tr_scene_commit first");
    }
    if (s->committed_generation != s->generation) {
        return tr_error_set(err, TR_STATUS_STALE_SCENE,
                            "the scene changed since its %s was built (generation %llu, built "
                            "for %llu): call tr_scene_commit, or tr_scene_update after moving "
                            "shapes",
                            tr_accel_name(s->accel), (unsigned long long)s->generation,
                            (unsigned long long)s->committed_generation);
    }
    return TR_OK;
}

uint64_t tr_scene_generation(const tr_scene *s) {
    return s->generation;
}

int tr_scene_refit(tr_scene *s, tr_error *err) {
    if (s->accel != TR_ACCEL_TYPE_BVH && s->accel != TR_ACCEL_TYPE_BVH2) {
        return TR_OK;
    }
    if (s->two_level) {
        return tr_scene_update_two_level(s, err);
    }
    /* Whether the wide BVH was collapsed from this tree as it stood before this refit. */
    const int wide_current = s->wbvh.nodes && s->wbvh.bvh_refits == s->bvh.refits;
    tr_bvh_refit(&s->bvh, s->triangles);
    if (s->accel == TR_ACCEL_TYPE_BVH) {
        if (wide_current) {
            tr_wbvh_refit(&s->wbvh, &s->bvh); /* same shape, new boxes and packets */
            return TR_OK;
        }
        tr_wbvh_free(&s->wbvh);
        if (tr_wbvh_build(&s->wbvh, &s->bvh, err) != TR_OK) {
            return TR_ERR; /* the view falls back to the binary BVH */
        }
    }
    return TR_OK;
}

int tr_scene_move_shape(tr_scene *s, uint32_t shape, tr_vec3 delta, tr_error *err) {
    if (shape >= s->shape_count) {
        return tr_error_set(err, TR_STATUS_NOT_FOUND, "shape %u does not exist (the scene has %u)",
                            shape, s->shape_count);
    }
    if (!isfinite(delta.x) || !isfinite(delta.y) || !isfinite(delta.z)) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT, "shape %u: the offset is not finite",
                            shape);
    }
    const uint32_t inst = tr_scene_shape_instance(s, shape);
    if (inst != UINT32_MAX) {
        /* An instance's shape moves with its matrix, so that the top level follows. */
        float m[12];
        memcpy(m, s->instances[inst].m, sizeof m);
        m[3] += delta.x;
        m[7] += delta.y;
        m[11] += delta.z;
        return tr_scene_set_instance_transform(s, inst, m, err);
    }
    s->rest_moved = 1;
    tr_flat_node *node = &s->shapes[shape];
    for (uint32_t i = node->first; i < node->first + node->count; ++i) {
        tr_triangle *t = &s->triangles[i];
        t->v0 = v3_add(t->v0, delta);
        t->v1 = v3_add(t->v1, delta);
        t->v2 = v3_add(t->v2, delta);
        t->centroid = v3_add(t->centroid, delta);
    }
    node->box = tr_triangles_bounds(s->triangles + node->first, node->count);
    s->shape_moved[shape] = v3_add(s->shape_moved[shape], delta);
    s->generation++;
    return TR_OK;
}

int tr_scene_take_motion(tr_scene *s, tr_vec3 *motion, uint32_t n, int *moved, tr_error *err) {
    const uint32_t nt = tr_scene_triangle_count(s);
    if (n != nt + 1u) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "motion table of %u entries for %u triangles (needs %u)", n, nt,
                            nt + 1u);
    }
    int any = 0;
    motion[0] = v3s(0.0f); /* id 0: nothing hit */
    for (uint32_t i = 0; i < s->shape_count; ++i) {
        const tr_flat_node *node = &s->shapes[i];
        const tr_vec3 d = s->shape_moved[i];
        any |= d.x != 0.0f || d.y != 0.0f || d.z != 0.0f;
        for (uint32_t t = node->first; t < node->first + node->count; ++t) {
            motion[t + 1] = d;
        }
        s->shape_moved[i] = v3s(0.0f);
    }
    *moved = any;
    return TR_OK;
}

const char *tr_scene_update_kind(const tr_scene *s) {
    switch (s->accel) {
    case TR_ACCEL_TYPE_BVH:
    case TR_ACCEL_TYPE_BVH2:
        return "refit";
    case TR_ACCEL_TYPE_EMBREE:
        return "rebuild";
    case TR_ACCEL_TYPE_FLAT:
        break;
    }
    return "none";
}

int tr_scene_update(tr_scene *s, double *seconds, tr_error *err) {
    const double t0 = tr_time_now();
    int rc = TR_OK;
    /* Moves keep every count; anything else since the commit (shapes or meshes added, the
     * scene emptied or reloaded) needs tr_scene_commit. */
    if (!s->committed || s->committed_triangles != tr_scene_triangle_count(s)) {
        rc = tr_error_set(err, TR_STATUS_STALE_SCENE,
                          "the scene changed beyond moved shapes since it was committed "
                          "(or was never committed): commit it again");
    } else if (s->lights_dirty && tr_scene_has_kept_instances(s) && tr_scene_kept_emit(s)) {
        /* A kept prototype's material came to emit: the emitter table names stored
         * triangles, so the instances are flattened and the scene committed anew. */
        rc = tr_scene_commit(s, s->accel, err);
        if (seconds) {
            *seconds = tr_time_now() - t0;
        }
        return rc;
    } else if (s->accel == TR_ACCEL_TYPE_BVH || s->accel == TR_ACCEL_TYPE_BVH2) {
        rc = tr_scene_refit(s, err);
    } else if (s->accel == TR_ACCEL_TYPE_EMBREE && s->embree.first) {
        /* Kept instances: new matrices and the top scene committed again. */
        rc = tr_scene_update_embree(s, err);
        if (rc != TR_OK) {
            tr_embree_free(&s->embree);
            s->accel = TR_ACCEL_TYPE_FLAT; /* as a failed commit leaves it */
            s->committed_triangles = 0;
            s->committed = 0;
        }
    } else if (s->accel == TR_ACCEL_TYPE_EMBREE) {
        tr_embree_free(&s->embree);
        rc = tr_embree_build(&s->embree, s->triangles, s->triangle_count, err);
        if (rc != TR_OK) {
            s->accel = TR_ACCEL_TYPE_FLAT; /* as a failed commit leaves it */
            s->committed_triangles = 0;
            s->committed = 0;
        }
    }
    /* An emittance changed (tr_scene_set_emittance): the emitter table and its light
     * tree are built anew, as tr_scene_commit builds them. */
    if (rc == TR_OK && s->lights_dirty) {
        rc = tr_scene_rebuild_lights(s, err);
    } else if (rc == TR_OK && s->light_node_count > 0) {
        /* The tree bounds where the emitters are: moved ones need it built anew. */
        rc = tr_scene_build_light_tree(s, err);
    }
    if (rc == TR_OK) {
        if (s->env_count + s->sun_count > 0u) {
            tr_scene_sky_bounds(s); /* shapes moved: the sky's light subpaths cover them */
        }
        s->committed_generation = s->generation;
    }
    if (seconds) {
        *seconds = tr_time_now() - t0;
    }
    return rc;
}

double tr_scene_bvh_build_seconds(const tr_scene *s) {
    if (s->accel == TR_ACCEL_TYPE_BVH && s->two_level) {
        return s->rest_bvh.build_seconds + s->rest_wbvh.build_seconds + s->tlas.build_seconds;
    }
    if (s->accel == TR_ACCEL_TYPE_BVH) {
        return s->bvh.build_seconds + s->wbvh.build_seconds;
    }
    return s->accel == TR_ACCEL_TYPE_BVH2 ? s->bvh.build_seconds : 0.0;
}

double tr_scene_build_seconds(const tr_scene *s) {
    return s->accel == TR_ACCEL_TYPE_EMBREE ? tr_scene_embree_build_seconds(s)
                                            : tr_scene_bvh_build_seconds(s);
}

double tr_scene_embree_build_seconds(const tr_scene *s) {
    return s->accel == TR_ACCEL_TYPE_EMBREE ? s->embree.build_seconds : 0.0;
}

tr_scene_view tr_scene_view_of(const tr_scene *s) {
    tr_scene_view v;
    v.triangles = s->triangles;
    v.materials = s->materials;
    v.flat_nodes = s->shapes;
    v.bvh_nodes = s->bvh.nodes;
    v.bvh_tris = s->bvh.tris;
    v.triangle_count = s->triangle_count;
    v.material_count = s->material_count;
    v.flat_node_count = s->shape_count;
    v.bvh_node_count = s->bvh.node_count;
    v.bvh_tri_count = s->bvh.index_count;
    v.accel = s->accel == TR_ACCEL_TYPE_BVH2 ? TR_ACCEL_BVH : (uint32_t)s->accel;
    /* The wide BVH only while it matches the binary one (tr_bvh_refit moves the binary
     * boxes; tr_scene_refit refits both). */
    v.wbvh = s->accel == TR_ACCEL_TYPE_BVH && s->wbvh.bvh_refits == s->bvh.refits ? &s->wbvh : NULL;
    if (s->accel == TR_ACCEL_TYPE_BVH && s->two_level) {
        v.wbvh = &s->tlas.wbvh; /* instances: the two-level structure, host only */
    }
    v.kept = tr_scene_has_kept_instances(s) ? s : NULL;
    v.cwbvh_nodes = NULL; /* a device's own (src/device/opencl.c), never the host's */
    v.cwbvh_node_count = 0u;
    v.cwbvh_tris = NULL;
    v.cwbvh_tri_count = 0u;
    v.lights = s->lights;
    v.light_cdf = s->light_cdf;
    /* A table older than the triangles could name triangles that moved: without a
     * current one the pt integrator finds emitters only by hitting them. */
    v.light_count = s->light_triangles == s->triangle_count ? s->light_count : 0;
    v.light_cdf_count = v.light_count;
    v.light_weight_total = s->light_weight_total;
    v.sky_cx = s->sky_center[0];
    v.sky_cy = s->sky_center[1];
    v.sky_cz = s->sky_center[2];
    v.sky_radius = s->sky_radius;
    v.light_nodes = s->light_nodes;
    /* A tree over a stale table is left out; one over punctual lights alone is not. */
    v.light_node_count = v.light_count > 0 || (s->light_count == 0 && s->light_tree_punctual > 0u)
                             ? s->light_node_count
                             : 0;
    v.light_leaf = s->light_leaf;
    v.light_leaf_count = v.light_node_count > 0 ? v.light_count + s->light_tree_punctual : 0;
    v.vertices = s->vertices;
    v.vertex_count = s->vertex_count;
    v.tri_verts = s->tri_verts;
    v.tri_verts_count =
        s->tri_verts_count < s->triangle_count ? s->tri_verts_count : s->triangle_count;
    v.textures = s->textures;
    v.texture_count = s->texture_count;
    v.texels = s->texels;
    v.texel_count = s->texel_count;
    v.material_exts = s->material_exts;
    v.material_ext_count = s->material_ext_count == s->material_count ? s->material_ext_count : 0;
    v.env = &s->env;
    v.env_count = s->env_count;
    v.env_texels = s->env_texels;
    v.env_texel_count = s->env_texel_count;
    v.env_cdf = s->env_cdf;
    v.env_cdf_count = s->env_cdf_count;
    v.sun = &s->sun;
    v.sun_count = s->sun_count;
    v.punctual = s->punctual;
    /* Lights added since the last commit have no CDF yet: none are exposed until then. */
    v.punctual_count = s->punctual_built == s->punctual_count ? s->punctual_count : 0u;
    /* The multiple-scattering table, for a scene with a material that asks for it. */
    v.ggx_ms = NULL;
    v.ggx_ms_count = 0u;
    for (uint32_t i = 0; i < s->material_count; ++i) {
        /* A sheen reads its albedo from the same table (bsdf_principled.h). */
        const int sheen = i < s->material_ext_count && (s->material_exts[i].sheen_color.x > 0.0f ||
                                                        s->material_exts[i].sheen_color.y > 0.0f ||
                                                        s->material_exts[i].sheen_color.z > 0.0f);
        if ((s->materials[i].flags & TR_MATERIAL_MULTISCATTER) != 0u || sheen) {
            v.ggx_ms = tr_ggx_ms_table();
            v.ggx_ms_count = TR_GGX_MS_COUNT;
            break;
        }
    }
#ifdef TR_SCENE_VIEW_EMBREE
    v.embree_scene = s->embree.scene;
    v.embree_first = s->embree.first;
#endif
    return v;
}

uint32_t tr_scene_triangle_count(const tr_scene *s) {
    return (uint32_t)(s->triangle_count + s->placed_count);
}

uint32_t tr_scene_stored_triangle_count(const tr_scene *s) {
    return s->triangle_count;
}

uint32_t tr_scene_material_count(const tr_scene *s) {
    return s->material_count;
}

uint32_t tr_scene_shape_count(const tr_scene *s) {
    return s->shape_count;
}

int tr_scene_light_tree_punctual(const tr_scene *s) {
    if (s->light_sampling == TR_LIGHT_SAMPLING_POWER) {
        return 0;
    }
    uint32_t n = 0;
    for (uint32_t i = 0; i < s->punctual_count; ++i) {
        n += s->punctual[i].type != TR_PUNCTUAL_DIRECTIONAL;
    }
    return n > TR_PUNCTUAL_ALL;
}

int tr_scene_light_tree_wanted(const tr_scene *s) {
    if (tr_scene_light_tree_punctual(s)) {
        return 1;
    }
    if (s->light_sampling == TR_LIGHT_SAMPLING_AUTO) {
        return s->light_count >= TR_LIGHT_TREE_MIN_EMITTERS;
    }
    return s->light_sampling == TR_LIGHT_SAMPLING_TREE && s->light_count > 0;
}

int tr_scene_set_light_sampling(tr_scene *s, int mode, tr_error *err) {
    if (mode != TR_LIGHT_SAMPLING_AUTO && mode != TR_LIGHT_SAMPLING_TREE &&
        mode != TR_LIGHT_SAMPLING_POWER) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "unknown light sampling %d (expected TR_LIGHT_SAMPLING_AUTO, _TREE "
                            "or _POWER)",
                            mode);
    }
    s->light_sampling = mode;
    return TR_OK;
}

int tr_scene_light_sampling(const tr_scene *s) {
    return (tr_scene_light_count(s) > 0 || s->light_tree_punctual > 0u) && s->light_node_count > 0
               ? TR_LIGHT_SAMPLING_TREE
               : TR_LIGHT_SAMPLING_POWER;
}

const char *tr_light_sampling_name(int mode) {
    switch (mode) {
    case TR_LIGHT_SAMPLING_AUTO:
        return "auto";
    case TR_LIGHT_SAMPLING_TREE:
        return "tree";
    case TR_LIGHT_SAMPLING_POWER:
        return "power";
    default:
        return NULL;
    }
}

int tr_light_sampling_from_name(const char *name) {
    for (int m = TR_LIGHT_SAMPLING_AUTO; m <= TR_LIGHT_SAMPLING_POWER; ++m) {
        if (name && strcmp(name, tr_light_sampling_name(m)) == 0) {
            return m;
        }
    }
    return -1;
}

uint32_t tr_scene_light_count(const tr_scene *s) {
    return s->light_triangles == s->triangle_count ? s->light_count : 0;
}

tr_triangle tr_scene_triangle(const tr_scene *s, uint32_t i) {
    tr_triangle t;
    if (i < s->triangle_count) {
        return s->triangles[i];
    }
    memset(&t, 0, sizeof t);
    if (i - s->triangle_count < s->placed_count) {
        tr_inst_triangle(s, i, &t);
    }
    return t;
}

tr_material tr_scene_material(const tr_scene *s, uint32_t i) {
    tr_material m;
    if (i < s->material_count) {
        return s->materials[i];
    }
    memset(&m, 0, sizeof m);
    return m;
}

tr_aabb tr_scene_shape_box(const tr_scene *s, uint32_t shape) {
    tr_aabb box;
    if (shape < s->shape_count) {
        return s->shapes[shape].box;
    }
    memset(&box, 0, sizeof box);
    return box;
}

int tr_scene_triangle_normals(const tr_scene *s, uint32_t i, tr_vec3 out[3]) {
    memset(out, 0, 3 * sizeof *out);
    if (i >= s->triangle_count && i - s->triangle_count < s->placed_count) {
        tr_vertex x[3];
        if (!tr_inst_vertices(s, i, x)) {
            return 0;
        }
        int has = 0;
        for (int k = 0; k < 3; ++k) {
            out[k] = x[k].normal;
            has |= out[k].x != 0.0f || out[k].y != 0.0f || out[k].z != 0.0f;
        }
        return has;
    }
    if (i >= s->tri_verts_count || i >= s->triangle_count || s->tri_verts[i].v[0] == TR_NO_INDEX) {
        return 0;
    }
    int has = 0;
    for (int k = 0; k < 3; ++k) {
        out[k] = s->vertices[s->tri_verts[i].v[k]].normal;
        has |= out[k].x != 0.0f || out[k].y != 0.0f || out[k].z != 0.0f;
    }
    return has;
}

uint32_t tr_scene_material_maps(const tr_scene *s, uint32_t i) {
    if (i >= s->material_count || s->material_ext_count != s->material_count) {
        return 0u;
    }
    const tr_material_ext *e = &s->material_exts[i];
    return (e->base_tex != TR_NO_INDEX ? TR_MAP_BASE : 0u) |
           (e->emission_tex != TR_NO_INDEX ? TR_MAP_EMISSION : 0u) |
           (e->mr_tex != TR_NO_INDEX ? TR_MAP_METALLIC_ROUGHNESS : 0u) |
           (e->normal_tex != TR_NO_INDEX ? TR_MAP_NORMAL : 0u) |
           ((e->flags & TR_MATEXT_ALPHA_MASK) ? TR_MAP_CUTOUT : 0u) |
           (e->transmission_tex != TR_NO_INDEX ? TR_MAP_TRANSMISSION : 0u) |
           (e->clearcoat_tex != TR_NO_INDEX ? TR_MAP_CLEARCOAT : 0u) |
           (e->clearcoat_rough_tex != TR_NO_INDEX ? TR_MAP_CLEARCOAT_ROUGHNESS : 0u) |
           (e->sheen_color_tex != TR_NO_INDEX ? TR_MAP_SHEEN_COLOR : 0u) |
           (e->sheen_rough_tex != TR_NO_INDEX ? TR_MAP_SHEEN_ROUGHNESS : 0u) |
           (e->clearcoat_normal_tex != TR_NO_INDEX ? TR_MAP_CLEARCOAT_NORMAL : 0u);
}

uint32_t tr_scene_shape_triangle_count(const tr_scene *s, uint32_t shape) {
    return shape < s->shape_count ? s->shapes[shape].count : 0u;
}

tr_aabb tr_scene_bounds(const tr_scene *s) {
    return tr_scene_all_bounds(s);
}

const tr_camera *tr_scene_camera(const tr_scene *s) {
    return &s->camera;
}

void tr_scene_set_camera(tr_scene *s, const tr_camera *cam) {
    s->camera = *cam;
}

tr_accel_type tr_scene_accel(const tr_scene *s) {
    return s->accel;
}

void tr_scene_accel_info(const tr_scene *s, tr_accel_info *info) {
    memset(info, 0, sizeof *info);
    info->type = s->accel;
    info->wide_width = TR_WBVH_WIDTH;
    info->wide_isa = tr_wbvh_isa();
    if (s->accel == TR_ACCEL_TYPE_BVH || s->accel == TR_ACCEL_TYPE_BVH2) {
        info->bvh_nodes = s->bvh.node_count;
        info->bvh_leaves = s->bvh.leaf_count;
        info->bvh_depth = s->bvh.depth;
        info->bvh_seconds = s->bvh.build_seconds;
    }
    if (s->accel == TR_ACCEL_TYPE_BVH) {
        info->wide_nodes = s->wbvh.node_count;
        info->wide_leaves = s->wbvh.leaf_count;
        info->wide_depth = s->wbvh.depth;
        info->wide_seconds = s->wbvh.build_seconds;
    }
    if (s->accel == TR_ACCEL_TYPE_EMBREE) {
        info->embree_seconds = s->embree.build_seconds;
    }
    if (s->accel == TR_ACCEL_TYPE_BVH && s->two_level) {
        /* Instances: the top level (over the instances and the scene's own triangles). */
        info->bvh_nodes = s->tlas.bvh.node_count;
        info->bvh_leaves = s->tlas.bvh.leaf_count;
        info->bvh_depth = s->tlas.bvh.depth;
        info->bvh_seconds = s->tlas.bvh.build_seconds + s->rest_bvh.build_seconds;
        info->wide_nodes = s->tlas.wbvh.node_count;
        info->wide_leaves = s->tlas.wbvh.leaf_count;
        info->wide_depth = s->tlas.wbvh.depth;
        info->wide_seconds = s->tlas.wbvh.build_seconds + s->rest_wbvh.build_seconds;
    }
}

uint32_t tr_scene_bvh_node_count(const tr_scene *s) {
    return s->accel == TR_ACCEL_TYPE_BVH || s->accel == TR_ACCEL_TYPE_BVH2 ? s->bvh.node_count : 0;
}

int tr_scene_bvh_node(const tr_scene *s, uint32_t i, tr_aabb *box, uint32_t *first_child) {
    if (i >= tr_scene_bvh_node_count(s)) {
        return -1;
    }
    const tr_bvh_node *n = &s->bvh.nodes[i];
    *box = n->box;
    if (first_child) {
        *first_child = n->count == 0 ? n->left_first : 0;
    }
    return n->count == 0;
}

static double sway_offset(double width, uint32_t frame) {
    const double two_pi = 6.283185307179586;
    return 0.25 * width * sin(two_pi * (double)(frame % 60u) / 60.0);
}

int tr_scene_animate_sway(tr_scene *s, uint32_t frame, tr_error *err) {
    const uint32_t shapes = tr_scene_shape_count(s);
    if (shapes == 0 || frame == 0) {
        return TR_OK;
    }
    const uint32_t shape = shapes - 1;
    const tr_aabb box = tr_scene_shape_box(s, shape);
    const double width = box.max.x - box.min.x;
    const double dx = sway_offset(width, frame) - sway_offset(width, frame - 1);
    return tr_scene_move_shape(s, shape, tr_vec3_make((float)dx, 0.0f, 0.0f), err);
}
