/* model.c - a scene built around one model file, for `trac0r render|view|info model.glb`. */
#include <ctype.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>
#include <strings.h>

#include "scene/scene_internal.h"
#include "trac0r/camera.h"
#include "trac0r/scene_file.h"

int tr_scene_path_is_model(const char *path) {
    size_t n = strlen(path);
    if (strncmp(path, "builtin:", 8) == 0 || (!strchr(path, '/') && !strchr(path, '.'))) {
        return 0;
    }
    const char *ext = ".json";
    if (n < 5) {
        return 1;
    }
    for (size_t i = 0; i < 5; ++i) {
        if (tolower((unsigned char)path[n - 5 + i]) != ext[i]) {
            return 1;
        }
    }
    return 0;
}

static void model_warn(void *ctx, const char *message) {
    tr_scene_file *info = ctx;
    if (info->warning_count < TR_SCENE_FILE_MAX_WARNINGS) {
        snprintf(info->warnings[info->warning_count++], sizeof info->warnings[0], "%s", message);
    }
}

/* Assimp's light types (aiLightSourceType), without its headers here. */
enum { AI_DIRECTIONAL = 1, AI_POINT = 2, AI_SPOT = 3, AI_AMBIENT = 4, AI_AREA = 5 };

/* A spot light's cone: Assimp's angles are the whole cone's (its documentation), except
 * that its glTF importer stores KHR_lights_punctual's half-angles. Missing or odd angles
 * get glTF's defaults (outer pi/4, inner 0). */
static void model_spot_cone(const tr_import_light *l, tr_punctual *p) {
    const float k = l->gltf ? 1.0f : 0.5f;
    float outer = k * l->outer_cone, inner = k * l->inner_cone;
    if (!(outer > 0.0f && outer <= 3.14159265f)) {
        outer = 0.25f * 3.14159265f;
    }
    if (!(inner >= 0.0f && inner <= outer)) {
        inner = 0.0f;
    }
    p->cos_outer = cosf(outer);
    p->cos_inner = fmaxf(cosf(inner), p->cos_outer);
}

/* The intensity (W/sr) of an inverse-square light that gives what the file's falloff
 * 1 / (a0 + a1 d + a2 d^2) gives at distance d (the light to the model's centre, at least
 * a tenth of its radius): colour x d^2 / (a0 + a1 d + a2 d^2). A pure inverse square
 * (glTF: a2 = 1) keeps colour / a2 whatever the distance; a file without a falloff (all
 * zero: Blender's files through Assimp) counts as a constant one, so that its lamp lights
 * the model with its colour as irradiance. Returns the factor on the colour. */
static float model_light_scale(const tr_import_light *l, tr_vec3 centre, float radius) {
    const float a0 = fmaxf(l->att[0], 0.0f), a1 = fmaxf(l->att[1], 0.0f),
                a2 = fmaxf(l->att[2], 0.0f);
    if (a0 == 0.0f && a1 == 0.0f && a2 > 0.0f) {
        return 1.0f / a2;
    }
    const float d = fmaxf(v3_length(v3_sub(l->pos, centre)), 0.1f * radius);
    const float f = a0 + a1 * d + a2 * d * d;
    const float k = d * d / (f > 0.0f ? f : 1.0f);
    return isfinite(k) && k > 0.0f ? k : 1.0f;
}

/* The factor from a file light's colour to trac0r's radiometric units. glTF's lights are
 * photometric and physically based (its renderers divide the diffuse term by pi), so the
 * colour is taken as it is. The other formats Assimp reads describe lights of the
 * fixed-function shading model (OpenGL's, Blender Internal's, 3ds Max's scanline): a white
 * diffuse surface facing the light at its falloff distance shows the light's colour,
 * albedo x colour x cos(theta), with no 1/pi; a Lambertian surface reflects 1/pi of its
 * irradiance, so the irradiance those files mean is pi times the colour. */
static float model_light_units(const tr_import_light *l) {
    return l->gltf ? 1.0f : 3.14159265f;
}

/* A light of the file onto trac0r's: directional -> the sun (the Sun's angular size),
 * point and spot -> punctual lights (punctual.h) of intensity the light's colour (W/sr),
 * ambient -> a constant environment, area -> an emissive rectangle.
 * Returns 1 where it added a light, 0 where it warned and added none, -1 with err. */
static int model_add_light(tr_scene *s, const tr_import_light *l, tr_vec3 centre, float radius,
                           tr_scene_file *info, int *have_sun, tr_error *err) {
    char msg[256];
    const tr_vec3 c = l->color;
    const float peak = fmaxf(c.x, fmaxf(c.y, c.z));
    if (!(peak > 0.0f) || !v3_is_finite(c)) {
        snprintf(msg, sizeof msg, "light '%.64s' is black: not imported", l->name);
        model_warn(info, msg);
        return 0;
    }
    if (l->type == AI_DIRECTIONAL) {
        if (*have_sun) {
            snprintf(msg, sizeof msg, "directional light '%.64s': one sun only, not imported",
                     l->name);
            model_warn(info, msg);
            return 0;
        }
        const float u = model_light_units(l);
        if (tr_scene_set_sun(s, v3_neg(l->dir), 0.526f, v3_scale(c, u), err) != TR_OK) {
            return -1;
        }
        *have_sun = 1;
        snprintf(msg, sizeof msg,
                 "directional light '%.64s': a sun of 0.526 degrees, irradiance %.4g x its colour",
                 l->name, (double)u);
        model_warn(info, msg);
        return 1;
    }
    if (l->type == AI_AMBIENT) {
        if (tr_scene_set_environment(s, c, 1.0f, 0.0f, NULL, 0, 0, err) != TR_OK) {
            return -1;
        }
        snprintf(msg, sizeof msg, "ambient light '%.64s': a constant environment", l->name);
        model_warn(info, msg);
        return 1;
    }
    if (l->type == AI_POINT || l->type == AI_SPOT) {
        tr_punctual p;
        memset(&p, 0, sizeof p);
        p.type = l->type == AI_SPOT ? TR_PUNCTUAL_SPOT : TR_PUNCTUAL_POINT;
        p.pos = l->pos;
        p.dir = l->dir;
        const float k = model_light_scale(l, centre, radius) * model_light_units(l);
        p.intensity = v3_scale(c, k);
        if (l->type == AI_SPOT) {
            model_spot_cone(l, &p);
        }
        if (tr_scene_add_punctual(s, &p, err) != TR_OK) {
            return -1;
        }
        if (l->type == AI_SPOT) {
            snprintf(msg, sizeof msg,
                     "spot light '%.64s': a spot light of intensity %.4g x its colour, cone "
                     "%.4g degrees, fading in over its outer %.4g",
                     l->name, (double)k, 2.0 * acos((double)p.cos_outer) * 57.29577951308232,
                     (acos((double)p.cos_outer) - acos((double)p.cos_inner)) * 57.29577951308232);
        } else {
            snprintf(msg, sizeof msg,
                     "point light '%.64s': a point light of intensity %.4g x its colour", l->name,
                     (double)k);
        }
        model_warn(info, msg);
        return 1;
    }
    if (l->type != AI_AREA) {
        snprintf(msg, sizeof msg, "light '%.64s' of unknown type %d: not imported", l->name,
                 l->type);
        model_warn(info, msg);
        return 0;
    }
    tr_shape_desc d;
    float emittance;
    if (l->type == AI_AREA && l->size_x > 0.0f && l->size_y > 0.0f) {
        /* A plane faces +y; Rx then Ry turns +y to (sin a sin b, cos a, sin a cos b). */
        d = tr_shape_desc_default(TR_SHAPE_PLANE);
        d.transform.scale = v3(l->size_x, 1.0f, l->size_y);
        const float yaw = atan2f(l->dir.x, l->dir.z);
        d.transform.orientation = v3(acosf(fmaxf(-1.0f, fminf(1.0f, l->dir.y))), yaw, 0.0f);
        emittance = peak; /* Assimp's colour taken as the radiance */
        snprintf(msg, sizeof msg,
                 "area light '%.64s': an emissive %gx%g rectangle, radiance its "
                 "colour",
                 l->name, (double)l->size_x, (double)l->size_y);
    } else {
        /* An area light without a size, as a point light of intensity I (W/sr) but with an
         * area: from a sphere of radius r, radiance I / (pi r^2) gives the
         * same power, 4 pi I. The radius is 1 % of the model's, grown if the radiance
         * would pass the emitter's limit. */
        float r = fmaxf(0.01f * radius, sqrtf(peak / (3.14159265f * 0.99e7f)));
        d = tr_shape_desc_default(TR_SHAPE_ICOSPHERE_SMOOTH);
        d.subdivisions = 2;
        d.transform.scale = v3s(r);
        emittance = peak / (3.14159265f * r * r);
        snprintf(msg, sizeof msg,
                 "area light '%.64s' without a size: an emissive sphere of radius %g, intensity "
                 "its colour",
                 l->name, (double)r);
    }
    d.transform.position = l->pos;
    uint32_t mat;
    if (tr_scene_add_material(s, tr_material_emitter(v3_scale(c, 1.0f / peak), emittance), &mat,
                              err) != TR_OK) {
        return -1;
    }
    d.material = mat;
    if (tr_scene_add_shape(s, &d, err) != TR_OK) {
        return -1;
    }
    model_warn(info, msg);
    return 1;
}

/* Whether point p lies inside closed geometry among the first `count` triangles: every one
 * of 32 directions (a Fibonacci sphere) meets a triangle, and at least 3 in 4 of the
 * nearest hits see the triangle from behind (against its winding's normal). A camera or a
 * lamp there sees or lights nothing but the inside of a mesh (Assimp's spider.fbx: its
 * camera and lamp inside a box 15,000 units across). Brute force, Moller-Trumbore; the
 * caller bounds the work. */
static int model_point_enclosed(const tr_scene *s, uint32_t count, tr_vec3 p) {
    enum { DIRS = 32 };
    int behind = 0;
    for (int k = 0; k < DIRS; ++k) {
        const float z = 1.0f - (2.0f * (float)k + 1.0f) / (float)DIRS;
        const float r = sqrtf(fmaxf(0.0f, 1.0f - z * z)), phi = 2.39996323f * (float)k;
        const tr_vec3 d = v3(r * cosf(phi), r * sinf(phi), z);
        float best = INFINITY;
        int back = 0;
        for (uint32_t i = 0; i < count; ++i) {
            const tr_triangle *t = &s->triangles[i];
            const tr_vec3 e1 = v3_sub(t->v1, t->v0), e2 = v3_sub(t->v2, t->v0);
            const tr_vec3 q = v3_cross(d, e2);
            const float det = v3_dot(e1, q);
            if (fabsf(det) < 1e-20f) {
                continue;
            }
            const float inv = 1.0f / det;
            const tr_vec3 o = v3_sub(p, t->v0);
            const float u = v3_dot(o, q) * inv;
            if (u < 0.0f || u > 1.0f) {
                continue;
            }
            const tr_vec3 w = v3_cross(o, e1);
            const float v = v3_dot(d, w) * inv, dist = v3_dot(e2, w) * inv;
            if (v < 0.0f || u + v > 1.0f || !(dist > 0.0f) || dist >= best) {
                continue;
            }
            best = dist;
            back = v3_dot(t->normal, d) > 0.0f;
        }
        if (best == INFINITY) {
            return 0; /* this direction leaves the model */
        }
        behind += back;
    }
    return 4 * behind >= 3 * DIRS;
}

/* Whether the enclosure checks run: models above 2 M triangles are skipped (32 rays by
 * brute force per point). */
#define MODEL_ENCLOSED_MAX 2000000u

/* Whether the file's camera sits inside the model's geometry (seeing the backs of faces
 * all round). Then it is reported, and where the camera was not asked for by name the
 * model is framed instead (returns 1): such a camera shows nothing of what the file is
 * meant to show (FBX/spider.fbx's sits inside a mesh 15,000 units across and renders
 * white), while a room seen from inside sees the fronts of its walls and is kept. */
static int model_camera_enclosed(const tr_scene *s, uint32_t count, const tr_import_extras *ex,
                                 int named, tr_scene_file *info) {
    if (count > MODEL_ENCLOSED_MAX || !model_point_enclosed(s, count, ex->cam_pos)) {
        return 0;
    }
    char msg[256];
    if (named) {
        snprintf(msg, sizeof msg,
                 "camera '%.64s' at (%g, %g, %g) is inside the model's geometry: it may see "
                 "nothing but the inside of a mesh (--camera frame frames the model instead)",
                 ex->cam_name, (double)ex->cam_pos.x, (double)ex->cam_pos.y, (double)ex->cam_pos.z);
    } else {
        snprintf(msg, sizeof msg,
                 "camera '%.40s' at (%.6g, %.6g, %.6g) is inside the model's geometry: the "
                 "model is framed instead (--camera '%.40s' renders from it)",
                 ex->cam_name, (double)ex->cam_pos.x, (double)ex->cam_pos.y, (double)ex->cam_pos.z,
                 ex->cam_name);
    }
    model_warn(info, msg);
    return !named;
}

/* Warns about the file's point or spot lights that sit inside the model's geometry (the
 * first 16 are checked) and marks them in enclosed[]. */
static void model_check_enclosed(const tr_scene *s, uint32_t count, const tr_import_extras *ex,
                                 uint8_t *enclosed, tr_scene_file *info) {
    if (count > MODEL_ENCLOSED_MAX) {
        return;
    }
    char msg[256];
    for (uint32_t i = 0; i < ex->light_count && i < 16; ++i) {
        const tr_import_light *l = &ex->light[i];
        if ((l->type == AI_POINT || l->type == AI_SPOT) && model_point_enclosed(s, count, l->pos)) {
            enclosed[i] = 1;
            snprintf(msg, sizeof msg,
                     "light '%.64s' at (%g, %g, %g) is inside the model's geometry: its light "
                     "may not get out",
                     l->name, (double)l->pos.x, (double)l->pos.y, (double)l->pos.z);
            model_warn(info, msg);
        }
    }
}

/* The framing camera's direction: glTF's front faces +z (the format says so), so a glTF
 * model is seen from +z; any other format has no convention, so the model is seen across
 * its larger silhouette, along z or along x (a long animal from its side, not from its
 * tail). A little from the right and above, so that the view has depth. */
static tr_vec3 model_frame_dir(const char *path, tr_aabb b) {
    const char *dot = strrchr(path, '.');
    const int gltf = dot && (strcasecmp(dot, ".gltf") == 0 || strcasecmp(dot, ".glb") == 0);
    const tr_vec3 e = v3_sub(b.max, b.min);
    if (!gltf && e.z * e.y > 1.25f * e.x * e.y) {
        return v3_normalize(v3(-1.0f, -0.35f, 0.45f));
    }
    return v3_normalize(v3(-0.45f, -0.35f, -1.0f));
}

/* The distance along -dir from the box's centre at which every corner of the box lies
 * inside the view (vertical field of view vfov degrees, aspect w/h) with a 5 % margin:
 * the model fills the frame, its longer side to the frame's edge. */
static float model_frame_distance(tr_aabb b, tr_vec3 dir, tr_vec3 up, float vfov, float aspect) {
    const tr_vec3 right = v3_normalize(v3_cross(dir, up));
    const tr_vec3 u = v3_cross(right, dir);
    const float tv = tanf(0.5f * vfov * 0.0174532925f) * 0.95f, th = tv * aspect;
    const tr_vec3 c = v3_scale(v3_add(b.min, b.max), 0.5f);
    float d = 0.0f;
    for (int k = 0; k < 8; ++k) {
        const tr_vec3 p = v3((k & 1) ? b.max.x : b.min.x, (k & 2) ? b.max.y : b.min.y,
                             (k & 4) ? b.max.z : b.min.z);
        const tr_vec3 o = v3_sub(p, c);
        const float f = v3_dot(o, dir);
        /* The corner is in view when |o.right| <= th (d + f) and |o.u| <= tv (d + f); the
         * camera stays outside the box (d + f > 0 for every corner). */
        d = fmaxf(d, fabsf(v3_dot(o, right)) / th - f);
        d = fmaxf(d, fabsf(v3_dot(o, u)) / tv - f);
        d = fmaxf(d, -f * 1.05f);
    }
    return d;
}

int tr_scene_model_load(tr_scene *s, const char *path, const tr_model_options *opt,
                        tr_scene_file *info, tr_error *err) {
    tr_scene_file local;
    if (!info) {
        info = &local;
    }
    memset(info, 0, sizeof *info);
    tr_scene_clear(s);
    if (!(opt->scale > 0.0f) || !isfinite(opt->scale)) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT, "--scale %g: expected > 0",
                            (double)opt->scale);
    }
    tr_transform tf = {v3s(0.0f), v3s(0.0f), v3s(opt->scale)};
    if (opt->up_z) {
        tf.orientation = v3(-1.57079632679489662f, 0.0f, 0.0f); /* +z to +y */
    }
    int frame = opt->camera && strcmp(opt->camera, "frame") == 0;
    tr_mesh_import_stats st;
    tr_import_extras ex;
    memset(&ex, 0, sizeof ex);
    ex.instance_min = TR_IMPORT_INSTANCE_MIN;
    if (opt->camera && !frame &&
        tr_model_find_camera(path, opt->camera, &ex.camera_want, err) != TR_OK) {
        return TR_ERR;
    }
    if (tr_scene_import_mesh_ex(s, path, &tf, -1, TR_SCENE_FILE_MAX_TRIANGLES, &st, model_warn,
                                info, &ex, err) != TR_OK) {
        tr_scene_clear(s);
        return TR_ERR;
    }
    info->mesh_count = 1;
    info->mesh_parts = st.parts;
    info->mesh_triangles = st.triangles;
    info->degenerate_dropped = st.degenerate;
    info->bounds = tr_scene_bounds(s); /* the model's, before any light's shape */
    if (ex.has_camera && !frame &&
        model_camera_enclosed(s, s->triangle_count, &ex, opt->camera != NULL, info)) {
        frame = 1;
    }
    /* The size the render will have (one side alone keeps 4:3), so that the framing
     * camera fits the model to it. */
    info->width = opt->width;
    info->height = opt->height;
    tr_size_fill(&info->width, &info->height, 800, 600);
    if (ex.has_camera && !frame && !opt->height && ex.cam_aspect > 0.1f && ex.cam_aspect < 10.0f) {
        /* The file camera's aspect ratio, at the width asked for. */
        info->height = (uint32_t)fmaxf(1.0f, roundf((float)info->width / ex.cam_aspect));
        info->has_width = info->has_height = 1; /* the aspect is the camera's */
    }
    info->spp = 16;
    info->max_depth = 8;
    info->accel = TR_ACCEL_TYPE_BVH;
    info->allow_no_emitter = 1; /* the environment or the sun lights it */
    if (st.degenerate) {
        model_warn(info, "degenerate faces dropped (points, lines or zero area)");
    }
    tr_aabb b = info->bounds;
    tr_vec3 centre = v3_scale(v3_add(b.min, b.max), 0.5f);
    float radius = 0.5f * v3_length(v3_sub(b.max, b.min));
    if (!(radius > 0.0f) || !isfinite(radius)) {
        radius = 1.0f;
    }
    uint8_t enclosed[TR_IMPORT_MAX_LIGHTS] = {0};
    model_check_enclosed(s, s->triangle_count, &ex, enclosed, info);
    /* The file's lights, or the default environment. A light inside the model's geometry
     * (inside a solid: it sees the backs of faces all round) lights nothing outside it, so
     * it does not count as lighting the model. */
    int lit = 0, have_sun = 0, shut_in = 0;
    for (uint32_t i = 0; i < ex.light_count; ++i) {
        tr_error le;
        int rc = model_add_light(s, &ex.light[i], centre, radius, info, &have_sun, &le);
        if (rc < 0) {
            /* A light the file places or sizes badly (non-finite, too small to make
             * triangles) is dropped, not the model. */
            char msg[256];
            snprintf(msg, sizeof msg, "light '%.64s' not imported: %.160s", ex.light[i].name,
                     le.msg);
            model_warn(info, msg);
            continue;
        }
        lit += enclosed[i] ? 0 : rc;
        shut_in += enclosed[i] ? rc : 0;
    }
    if (!lit && shut_in) {
        model_warn(info, "every light of the file is inside the model's geometry: the model is "
                         "lit by the default environment too (--env sets another)");
    }
    if (ex.lights > ex.light_count) {
        char msg[96];
        snprintf(msg, sizeof msg, "%u light%s in the file not imported (no node, or past %d)",
                 ex.lights - ex.light_count, ex.lights - ex.light_count == 1 ? "" : "s",
                 TR_IMPORT_MAX_LIGHTS);
        model_warn(info, msg);
    }
    /* Without lights, radiance 0.5: the sky shows light grey and a white surface under it
     * stays below clipping at exposure 0 (at 1 both were clipped white). With lights and
     * no ambient one, Blender's default world (0.05 grey), so that what the lamps leave
     * dark is dim rather than black, as it is when Blender imports the file. */
    const float world = !lit ? TR_MODEL_SKY : s->env_count == 0 ? TR_MODEL_WORLD : 0.0f;
    if (world > 0.0f &&
        tr_scene_set_environment(s, v3s(world), 1.0f, 0.0f, NULL, 0, 0, err) != TR_OK) {
        tr_scene_clear(s);
        return TR_ERR;
    }
    for (uint32_t i = 0; i < s->material_count; ++i) {
        info->emitter_materials += s->materials[i].type == TR_MATERIAL_EMITTER;
    }
    for (uint32_t i = 0; i < s->triangle_count; ++i) {
        info->emissive_triangles +=
            s->materials[s->triangles[i].material].type == TR_MATERIAL_EMITTER;
    }
    const float vfov = 40.0f;
    tr_vec3 pos, dir, up = v3(0.0f, 1.0f, 0.0f);
    float near_d = radius * 1e-3f, far_d;
    if (ex.has_camera && !frame) {
        /* Assimp documents mHorizontalFOV as half the horizontal angle, but its Collada and
         * glTF loaders store the whole angle (xfov; 2 atan(aspect tan(yfov / 2))): taken as
         * the whole, the vertical angle follows from the image's aspect. */
        float aspect = (float)info->width / (float)info->height;
        float vf = 2.0f * atanf(tanf(0.5f * ex.cam_hfov) / aspect) * 57.2957795f;
        if (ex.cam_gltf && ex.cam_aspect > 0.0f) {
            /* Assimp 5.2's glTF importer stores yfov x aspectRatio: glTF's yfov back. */
            vf = ex.cam_hfov / ex.cam_aspect * 57.2957795f;
        }
        pos = ex.cam_pos;
        dir = ex.cam_dir;
        up = ex.cam_up;
        far_d = v3_length(v3_sub(pos, centre)) + 4.0f * radius;
        tr_error e;
        if (vf > 1.0f && vf < 179.0f &&
            tr_camera_make(&s->camera, pos, dir, up, vf, near_d, far_d, info->width, info->height,
                           &e) == TR_OK) {
            s->camera.right = v3_neg(s->camera.right); /* model files are right-handed */
            return TR_OK;
        }
        char msg[160];
        snprintf(msg, sizeof msg, "camera '%.64s' is unusable; framing the model instead",
                 ex.cam_name);
        model_warn(info, msg);
    }
    /* In front, a little to the right and above, the whole box in view. */
    dir = model_frame_dir(path, b);
    float dist = model_frame_distance(b, dir, up, vfov, (float)info->width / (float)info->height);
    pos = v3_sub(centre, v3_scale(dir, dist));
    far_d = dist + 4.0f * radius;
    if (tr_camera_make(&s->camera, pos, dir, up, vfov, near_d, far_d, info->width, info->height,
                       err) != TR_OK) {
        tr_scene_clear(s);
        return TR_ERR;
    }
    s->camera.right = v3_neg(s->camera.right);
    return TR_OK;
}
