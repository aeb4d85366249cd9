/* extras.c - what a user adds to any scene or model before it renders: an environment,
 * a sun, a ground (trac0r/scene_file.h). */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene/scene_internal.h"
#include "trac0r/scene_file.h"

/* "X,Y,Z": three finite numbers, nothing else (no blanks). Returns 1 when it is one. */
static int parse_vec3(const char *s, tr_vec3 *out) {
    float v[3];
    const char *p = s;
    for (int i = 0; i < 3; ++i) {
        char *end = NULL;
        if (!(*p == '-' || *p == '+' || *p == '.' || (*p >= '0' && *p <= '9'))) {
            return 0;
        }
        errno = 0;
        const double x = strtod(p, &end);
        if (end == p || errno == ERANGE || !isfinite(x) || fabs(x) > 3.4e38) {
            return 0;
        }
        v[i] = (float)x;
        p = end;
        if (*p != (i < 2 ? ',' : '\0')) {
            return 0;
        }
        ++p;
    }
    *out = tr_vec3_make(v[0], v[1], v[2]);
    return 1;
}

/* A grey diffuse floor just under the scene's bounds, ten times their width. */
static int add_ground(tr_scene *s, tr_error *err) {
    const tr_aabb b = tr_scene_bounds(s);
    const float dx = b.max.x - b.min.x, dy = b.max.y - b.min.y, dz = b.max.z - b.min.z;
    const float side = 10.0f * fmaxf(fmaxf(dx, dz), dy);
    if (!(side > 0.0f) || !isfinite(side)) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "ground: the scene has no extent to put a floor under");
    }
    uint32_t grey;
    if (tr_scene_add_material(s, tr_material_diffuse(tr_vec3_make(0.5f, 0.5f, 0.5f)), &grey, err) !=
        TR_OK) {
        return TR_ERR;
    }
    tr_shape_desc floor = tr_shape_desc_default(TR_SHAPE_PLANE);
    floor.transform.position = tr_vec3_make(0.5f * (b.min.x + b.max.x), b.min.y - 1e-4f * side,
                                            0.5f * (b.min.z + b.max.z));
    floor.transform.scale = tr_vec3_make(side, 1.0f, side);
    floor.material = grey;
    return tr_scene_add_shape(s, &floor, err);
}

int tr_scene_add_extras(tr_scene *s, const tr_scene_extras *x, tr_error *err) {
    if (!x) {
        return TR_OK;
    }
    tr_vec3 v;
    if (x->env && parse_vec3(x->env, &v)) {
        if (v.x < 0.0f || v.y < 0.0f || v.z < 0.0f) {
            return tr_error_set(
                err, TR_STATUS_INVALID_ARGUMENT,
                "env: expected a radiance R,G,B of three numbers >= 0, got '%.100s'", x->env);
        }
        if (tr_scene_set_environment(s, v, 1.0f, 0.0f, NULL, 0, 0, err) != TR_OK) {
            return TR_ERR;
        }
    } else if (x->env) {
        tr_error e;
        if (tr_scene_load_environment(s, x->env, tr_vec3_make(1, 1, 1), 1.0f, 0.0f, &e) != TR_OK) {
            return tr_error_set(err, e.code, "env: expected R,G,B or an image file: %s", e.msg);
        }
    }
    if (x->sun) {
        if (!parse_vec3(x->sun, &v) || !(v.x * v.x + v.y * v.y + v.z * v.z > 0.0f)) {
            return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                                "sun: expected a direction X,Y,Z towards the sun, not zero, got "
                                "'%.100s'",
                                x->sun);
        }
        const float e = x->sun_irradiance > 0.0f ? x->sun_irradiance : TR_SCENE_EXTRAS_SUN;
        if (tr_scene_set_sun(s, v, 0.53f, tr_vec3_make(e, e, e), err) != TR_OK) {
            return TR_ERR;
        }
    }
    return x->ground ? add_ground(s, err) : TR_OK;
}
