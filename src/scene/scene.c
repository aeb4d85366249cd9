/* scene.c - the scene's arrays and materials. */
#include <stdlib.h>
#include <string.h>

#include "trac0r/scene.h"

static tr_material material_make(uint32_t type, tr_vec3 color, float roughness, float ior,
                                 float emittance) {
    tr_material m;
    memset(&m, 0, sizeof m);
    m.type = type;
    m.color = color;
    m.roughness = roughness;
    m.ior = ior;
    m.emittance = emittance;
    return m;
}

tr_material tr_material_emitter(tr_vec3 color, float emittance) {
    return material_make(TR_MATERIAL_EMITTER, color, 0.0f, 1.0f, emittance);
}
tr_material tr_material_diffuse(tr_vec3 color) {
    return material_make(TR_MATERIAL_DIFFUSE, color, 0.0f, 1.0f, 0.0f);
}
tr_material tr_material_glass(tr_vec3 color, float ior) {
    return material_make(TR_MATERIAL_GLASS, color, 0.0f, ior, 0.0f);
}
tr_material tr_material_glossy(tr_vec3 color, float roughness) {
    return material_make(TR_MATERIAL_GLOSSY, color, roughness, 1.0f, 0.0f);
}

void tr_scene_init(tr_scene *s) {
    memset(s, 0, sizeof *s);
}

void tr_scene_free(tr_scene *s) {
    free(s->materials);
    free(s->triangles);
    free(s->shapes);
    tr_bvh_free(&s->bvh);
    tr_wbvh_free(&s->wbvh);
    tr_embree_free(&s->embree);
    free(s->lights);
    free(s->light_cdf);
    tr_scene_init(s);
}

int tr_scene_add_material(tr_scene *s, tr_material m, uint32_t *index, tr_error *err) {
    if (m.type < TR_MATERIAL_EMITTER || m.type > TR_MATERIAL_GLOSSY) {
        return tr_error_set(err, "unknown material type %u (expected 1..4)", m.type);
    }
    if (!v3_is_finite(m.color) || m.color.x < 0.0f || m.color.y < 0.0f || m.color.z < 0.0f) {
        return tr_error_set(err, "material colour (%g, %g, %g) must be finite and non-negative",
                            (double)m.color.x, (double)m.color.y, (double)m.color.z);
    }
    if (!isfinite(m.emittance) || m.emittance < 0.0f) {
        return tr_error_set(err, "material emittance %g must be finite and non-negative",
                            (double)m.emittance);
    }
    if (!(m.roughness >= 0.0f && m.roughness <= 1.0f)) {
        return tr_error_set(err, "material roughness %g must be in [0, 1]", (double)m.roughness);
    }
    if (!(m.ior >= 1.0f && m.ior <= 10.0f)) {
        return tr_error_set(err, "material ior %g must be in [1, 10]", (double)m.ior);
    }
    if ((m.flags & ~TR_MATERIAL_TWO_SIDED) != 0u) {
        return tr_error_set(err, "material flags 0x%x have unknown bits", m.flags);
    }
    if (s->material_count == s->material_capacity) {
        uint32_t cap = s->material_capacity ? 2 * s->material_capacity : 8;
        tr_material *grown = realloc(s->materials, (size_t)cap * sizeof *grown);
        if (!grown) {
            return tr_error_set(err, "out of memory adding a material");
        }
        s->materials = grown;
        s->material_capacity = cap;
    }
    s->materials[s->material_count] = m;
    if (index) {
        *index = s->material_count;
    }
    s->material_count++;
    return TR_OK;
}

int tr_scene_commit(tr_scene *s, tr_accel_type accel, tr_error *err) {
    tr_bvh_free(&s->bvh);
    tr_wbvh_free(&s->wbvh);
    tr_embree_free(&s->embree);
    s->accel = TR_ACCEL_TYPE_FLAT;
    s->committed_triangles = 0;
    if (tr_scene_build_lights(s, err) != TR_OK) {
        return TR_ERR;
    }
    switch (accel) {
    case TR_ACCEL_TYPE_FLAT:
        return TR_OK;
    case TR_ACCEL_TYPE_BVH:
        if (tr_bvh_build(&s->bvh, s->triangles, s->triangle_count, err) != TR_OK) {
            return TR_ERR;
        }
        /* The CPU traverses the wide BVH collapsed from the binary one. */
        if (tr_wbvh_build(&s->wbvh, &s->bvh, err) != TR_OK) {
            tr_bvh_free(&s->bvh);
            return TR_ERR;
        }
        s->accel = accel;
        s->committed_triangles = s->triangle_count;
        return TR_OK;
    case TR_ACCEL_TYPE_BVH2:
        if (tr_bvh_build(&s->bvh, s->triangles, s->triangle_count, err) != TR_OK) {
            return TR_ERR;
        }
        s->accel = accel;
        s->committed_triangles = s->triangle_count;
        return TR_OK;
    case TR_ACCEL_TYPE_EMBREE:
        if (tr_embree_build(&s->embree, s->triangles, s->triangle_count, err) != TR_OK) {
            return TR_ERR;
        }
        s->accel = accel;
        s->committed_triangles = s->triangle_count;
        return TR_OK;
    }
    return tr_error_set(err, "unknown acceleration structure %d", (int)accel);
}

int tr_scene_is_committed(const tr_scene *s) {
    return s->accel == TR_ACCEL_TYPE_FLAT || s->committed_triangles == s->triangle_count;
}

int tr_scene_refit(tr_scene *s, tr_error *err) {
    if (s->accel != TR_ACCEL_TYPE_BVH && s->accel != TR_ACCEL_TYPE_BVH2) {
        return TR_OK;
    }
    tr_bvh_refit(&s->bvh, s->triangles);
    if (s->accel == TR_ACCEL_TYPE_BVH) {
        tr_wbvh_free(&s->wbvh);
        if (tr_wbvh_build(&s->wbvh, &s->bvh, err) != TR_OK) {
            return TR_ERR; /* the view falls back to the binary BVH */
        }
    }
    return TR_OK;
}

double tr_scene_bvh_build_seconds(const tr_scene *s) {
    if (s->accel == TR_ACCEL_TYPE_BVH) {
        return s->bvh.build_seconds + s->wbvh.build_seconds;
    }
    return s->accel == TR_ACCEL_TYPE_BVH2 ? s->bvh.build_seconds : 0.0;
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
    v.accel = s->accel == TR_ACCEL_TYPE_BVH2 ? TR_ACCEL_BVH : (uint32_t)s->accel;
    /* The wide BVH only while it matches the binary one (tr_bvh_refit moves the binary
     * boxes; tr_scene_refit refits both). */
    v.wbvh = s->accel == TR_ACCEL_TYPE_BVH && s->wbvh.bvh_refits == s->bvh.refits ? &s->wbvh : NULL;
    v.lights = s->lights;
    v.light_cdf = s->light_cdf;
    /* A table older than the triangles could name triangles that moved: without a
     * current one the pt integrator finds emitters only by hitting them. */
    v.light_count = s->light_triangles == s->triangle_count ? s->light_count : 0;
    v.light_weight_total = s->light_weight_total;
#ifdef TR_SCENE_VIEW_EMBREE
    v.embree_scene = s->embree.scene;
#endif
    return v;
}
