/* builtin.c - scenes compiled into the program. */
#include <stdlib.h>
#include <string.h>

#include "trac0r/camera.h"
#include "scene/scene_internal.h"
#include "trac0r/registry.h"
#include "trac0r/scene.h"

typedef struct shape_spec {
    tr_shape_type type;
    float pos[3], rot[3], scale[3];
    uint32_t subdivisions;
    int material;
} shape_spec;

/* The thesis's listing 16, number for number: a Cornell-like box with a red left wall,
 * a green right wall, a glossy and a white box, a glass and a glossy icosphere and a
 * plane emitter under the ceiling. Plane sizes are (x, z) extents, box sizes full
 * extents, icosphere scales the radius. */
static int build_cornell(tr_scene *s, uint32_t width, uint32_t height, int ico_level, int variant,
                         tr_error *err) {
    enum { EMISSIVE, WHITE, RED, GREEN, GLASS, GLOSSY, MATERIAL_COUNT };
    tr_material materials[MATERIAL_COUNT] = {
        [EMISSIVE] = tr_material_emitter(v3(1.0f, 0.93f, 0.85f), 15.0f),
        [WHITE] = tr_material_diffuse(v3(0.740063f, 0.742313f, 0.733934f)),
        [RED] = tr_material_diffuse(v3(0.366046f, 0.0371827f, 0.0416385f)),
        [GREEN] = tr_material_diffuse(v3(0.162928f, 0.408903f, 0.0833759f)),
        [GLASS] = tr_material_glass(v3(0.5f, 0.5f, 0.9f), 1.51714f),
        [GLOSSY] = tr_material_glossy(v3(1.0f, 1.0f, 1.0f), 0.09f),
    };
    /* The lamp is a plane with its normal up (+y), towards the ceiling: the thesis's
     * emitters shine from both sides, so the built-in one is two-sided for the pt
     * integrator too (the naive integrator ignores the flag). */
    materials[EMISSIVE].flags = TR_MATERIAL_TWO_SIDED;
    if (variant == 1) { /* cornell-mirror */
        materials[GLOSSY].roughness = 0.0f;
    } else if (variant == 2) { /* cornell-diffuse */
        materials[GLOSSY] = materials[WHITE];
        materials[GLASS] = materials[WHITE];
    }
    const float hp = TR_HALF_PI, pi = TR_PI;
    const shape_spec shapes[] = {
        {TR_SHAPE_PLANE, {-0.5f, 0.4f, 0}, {0, 0, -hp}, {1, 1, 1}, 0, RED},  /* wall_left */
        {TR_SHAPE_PLANE, {0.5f, 0.4f, 0}, {0, 0, hp}, {1, 1, 1}, 0, GREEN},  /* wall_right */
        {TR_SHAPE_PLANE, {0, 0.4f, 0.5f}, {-hp, 0, 0}, {1, 1, 1}, 0, WHITE}, /* wall_back */
        {TR_SHAPE_PLANE, {0, 0.9f, 0}, {pi, 0, 0}, {1, 1, 1}, 0, WHITE},     /* wall_top */
        {TR_SHAPE_PLANE, {0, -0.1f, 0}, {0, 0, 0}, {1, 1, 1}, 0, WHITE},     /* wall_bottom */
        {TR_SHAPE_PLANE, {0, 0.85f, -0.1f}, {0, 0, 0}, {0.4f, 1, 0.4f}, 0, EMISSIVE},   /* lamp */
        {TR_SHAPE_BOX, {0.3f, 0.1f, 0.1f}, {0, 0.6f, 0}, {0.2f, 0.5f, 0.2f}, 0, WHITE}, /* box1 */
        {TR_SHAPE_BOX, {-0.2f, 0.15f, 0.1f}, {0, -0.5f, 0}, {0.3f, 0.6f, 0.3f}, 0, GLOSSY},
        {TR_SHAPE_ICOSPHERE, {0, 0.1f, -0.3f}, {0, 0, 0}, {0.15f, 0.15f, 0.15f}, 2, GLASS},
        {TR_SHAPE_ICOSPHERE, {0.3f, 0.45f, 0.1f}, {0, 0, 0}, {0.15f, 0.15f, 0.15f}, 2, GLOSSY},
    };
    size_t shape_count = sizeof shapes / sizeof shapes[0];
    shape_spec varied;
    if (ico_level >= 0) {
        /* The complexity scene (thesis figure 3.5): one icosphere, the glass one, whose
         * subdivision varies; the glossy icosphere is left out. */
        varied = shapes[8];
        varied.subdivisions = (uint32_t)ico_level;
        shape_count = 8;
    }
    uint32_t index[MATERIAL_COUNT];
    for (int i = 0; i < MATERIAL_COUNT; ++i) {
        if (tr_scene_add_material(s, materials[i], &index[i], err) != TR_OK) {
            return TR_ERR;
        }
    }
    for (size_t i = 0; i < shape_count + (ico_level >= 0); ++i) {
        const shape_spec *sp = i < shape_count ? &shapes[i] : &varied;
        tr_shape_desc d = tr_shape_desc_default(sp->type);
        d.transform.position = v3(sp->pos[0], sp->pos[1], sp->pos[2]);
        d.transform.orientation = v3(sp->rot[0], sp->rot[1], sp->rot[2]);
        d.transform.scale = v3(sp->scale[0], sp->scale[1], sp->scale[2]);
        d.subdivisions = sp->subdivisions;
        d.material = index[sp->material];
        if (tr_scene_add_shape(s, &d, err) != TR_OK) {
            return TR_ERR;
        }
    }
    return tr_camera_make(&s->camera, v3(0.0f, 0.31f, -1.2f), v3(0.0f, 0.0f, 1.0f),
                          v3(0.0f, 1.0f, 0.0f), 90.0f, 0.001f, 100.0f, width, height, err);
}

/* A small hash of (i, k) into [0, 1): the forest's placements, the same on every run. */
static float forest_rand(uint32_t i, uint32_t k) {
    uint32_t h = i * 0x9E3779B1u ^ (k + 0x7F4A7C15u) * 0x85EBCA77u;
    h ^= h >> 15;
    h *= 0x2C1B3C6Du;
    h ^= h >> 12;
    h *= 0x297A2D39u;
    h ^= h >> 15;
    return (float)(h >> 8) * (1.0f / 16777216.0f);
}

/* forest-N: N x N trees on a ground plane under a sun and a sky, every tree an instance
 * of one prototype (a trunk and an icosphere crown of 1280 triangles), placed on a grid
 * with a random offset, turn and size; the camera looks over it from one corner. */
static int build_forest(tr_scene *s, uint32_t side, uint32_t width, uint32_t height,
                        tr_error *err) {
    uint32_t bark, leaves, ground, proto;
    if (tr_scene_add_material(s, tr_material_diffuse(v3(0.30f, 0.20f, 0.12f)), &bark, err) !=
            TR_OK ||
        tr_scene_add_material(s, tr_material_diffuse(v3(0.15f, 0.40f, 0.12f)), &leaves, err) !=
            TR_OK ||
        tr_scene_add_material(s, tr_material_diffuse(v3(0.35f, 0.30f, 0.22f)), &ground, err) !=
            TR_OK) {
        return TR_ERR;
    }
    tr_shape_desc trunk = tr_shape_desc_default(TR_SHAPE_BOX);
    trunk.transform.position = v3(0.0f, 0.5f, 0.0f);
    trunk.transform.scale = v3(0.15f, 1.0f, 0.15f);
    trunk.material = bark;
    tr_shape_desc crown = tr_shape_desc_default(TR_SHAPE_ICOSPHERE_SMOOTH);
    crown.transform.position = v3(0.0f, 1.5f, 0.0f);
    crown.transform.scale = v3(0.6f, 0.8f, 0.6f);
    crown.subdivisions = 3;
    crown.material = leaves;
    if (tr_scene_add_shape(s, &trunk, err) != TR_OK ||
        tr_scene_add_shape(s, &crown, err) != TR_OK ||
        tr_scene_make_prototype(s, 0, &proto, err) != TR_OK) {
        return TR_ERR;
    }
    const float spacing = 2.0f, extent = spacing * (float)side;
    tr_shape_desc floor = tr_shape_desc_default(TR_SHAPE_PLANE);
    floor.transform.position = v3(0.5f * extent, 0.0f, 0.5f * extent);
    floor.transform.scale = v3(extent + 4.0f, 1.0f, extent + 4.0f);
    floor.material = ground;
    if (tr_scene_add_shape(s, &floor, err) != TR_OK) {
        return TR_ERR;
    }
    for (uint32_t i = 0; i < side * side; ++i) {
        tr_transform tf;
        const float k = 0.7f + 0.6f * forest_rand(i, 2);
        tf.position = v3(spacing * ((float)(i % side) + 0.2f + 0.6f * forest_rand(i, 0)), 0.0f,
                         spacing * ((float)(i / side) + 0.2f + 0.6f * forest_rand(i, 1)));
        tf.orientation = v3(0.0f, TR_TWO_PI * forest_rand(i, 3), 0.0f);
        tf.scale = v3(k, k * (0.8f + 0.4f * forest_rand(i, 4)), k);
        float m[12];
        tr_transform_matrix(&tf, m);
        if (tr_scene_add_instance(s, proto, m, NULL, err) != TR_OK) {
            return TR_ERR;
        }
    }
    if (tr_scene_set_environment(s, v3(0.5f, 0.65f, 1.0f), 0.6f, 0.0f, NULL, 0, 0, err) != TR_OK ||
        tr_scene_set_sun(s, v3(0.4f, 0.8f, 0.3f), 1.0f, v3(3.0f, 2.8f, 2.5f), err) != TR_OK) {
        return TR_ERR;
    }
    return tr_camera_make(&s->camera, v3(-3.0f, 6.0f, -3.0f), v3(1.0f, -0.35f, 1.0f),
                          v3(0.0f, 1.0f, 0.0f), 60.0f, 0.001f, 1e6f, width, height, err);
}

int tr_scene_builtin(tr_scene *s, const char *name, uint32_t width, uint32_t height,
                     tr_error *err) {
    tr_scene_clear(s); /* the previous content goes; the generation counts on */
    int rc;
    const char *ico = "cornell-ico-";
    char *end = NULL;
    long level = -1;
    if (strncmp(name, ico, strlen(ico)) == 0) {
        level = strtol(name + strlen(ico), &end, 10);
    }
    if (strcmp(name, "cornell") == 0) {
        rc = build_cornell(s, width, height, -1, 0, err);
    } else if (strcmp(name, "cornell-mirror") == 0) {
        rc = build_cornell(s, width, height, -1, 1, err);
    } else if (strcmp(name, "cornell-diffuse") == 0) {
        rc = build_cornell(s, width, height, -1, 2, err);
    } else if (end && *end == '\0' && end != name + strlen(ico) && level >= 0 &&
               level <= TR_ICOSPHERE_MAX_SUBDIVISIONS) {
        rc = build_cornell(s, width, height, (int)level, 0, err);
    } else if (strncmp(name, "forest-", 7) == 0 && name[7] >= '1' && name[7] <= '9' &&
               (level = strtol(name + 7, &end, 10)) <= 1000 && *end == '\0') {
        rc = build_forest(s, (uint32_t)level, width, height, err);
    } else {
        static const char *const names[] = {"cornell", "cornell-mirror", "cornell-diffuse",
                                            "cornell-ico-0", "forest-10"};
        const char *near = tr_names_closest(name, names, 5);
        return tr_error_set(err, TR_STATUS_NOT_FOUND,
                            "unknown built-in scene '%s' (%s%s%savailable: cornell, "
                            "cornell-mirror, cornell-diffuse, cornell-ico-N with N = 0..%d, "
                            "forest-N with N = 1..1000)",
                            name, near ? "did you mean '" : "", near ? near : "", near ? "'? " : "",
                            TR_ICOSPHERE_MAX_SUBDIVISIONS);
    }
    if (rc != TR_OK) {
        tr_scene_clear(s);
    }
    return rc;
}
