/* model.c - a scene built around one model file, for `trac0r render|view|info model.glb`. */
#include <ctype.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "scene/scene_internal.h"
#include "trac0r/camera.h"

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

int tr_scene_model_load(tr_scene *s, const char *path, const tr_model_options *opt,
                        tr_scene_file *info, tr_error *err) {
    tr_scene_file local;
    if (!info) {
        info = &local;
    }
    memset(info, 0, sizeof *info);
    tr_scene_free(s);
    if (!(opt->scale > 0.0f) || !isfinite(opt->scale)) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT, "--scale %g: expected > 0",
                            (double)opt->scale);
    }
    tr_transform tf = {v3s(0.0f), v3s(0.0f), v3s(opt->scale)};
    if (opt->up_z) {
        tf.orientation = v3(-1.57079632679489662f, 0.0f, 0.0f); /* +z to +y */
    }
    tr_mesh_import_stats st;
    tr_import_extras ex;
    if (tr_scene_import_mesh_ex(s, path, &tf, -1, TR_SCENE_FILE_MAX_TRIANGLES, &st, model_warn,
                                info, &ex, err) != TR_OK) {
        tr_scene_free(s);
        return TR_ERR;
    }
    info->mesh_count = 1;
    info->mesh_parts = st.parts;
    info->mesh_triangles = st.triangles;
    info->degenerate_dropped = st.degenerate;
    info->bounds = tr_scene_bounds(s);
    info->width = opt->width ? opt->width : 800;
    info->height = opt->height ? opt->height : 600;
    info->spp = 16;
    info->max_depth = 8;
    info->accel = TR_ACCEL_TYPE_BVH;
    info->allow_no_emitter = 1; /* the environment lights it */
    for (uint32_t i = 0; i < s->material_count; ++i) {
        info->emitter_materials += s->materials[i].type == TR_MATERIAL_EMITTER;
    }
    for (uint32_t i = 0; i < s->triangle_count; ++i) {
        info->emissive_triangles +=
            s->materials[s->triangles[i].material].type == TR_MATERIAL_EMITTER;
    }
    if (st.degenerate) {
        model_warn(info, "degenerate faces dropped (points, lines or zero area)");
    }
    if (ex.lights) {
        char msg[96];
        snprintf(msg, sizeof msg, "%u light%s in the file not imported (lit by the environment)",
                 ex.lights, ex.lights == 1 ? "" : "s");
        model_warn(info, msg);
    }
    if (tr_scene_set_environment(s, v3s(1.0f), 1.0f, 0.0f, NULL, 0, 0, err) != TR_OK) {
        tr_scene_free(s);
        return TR_ERR;
    }
    tr_aabb b = info->bounds;
    tr_vec3 centre = v3_scale(v3_add(b.min, b.max), 0.5f);
    float radius = 0.5f * v3_length(v3_sub(b.max, b.min));
    if (!(radius > 0.0f) || !isfinite(radius)) {
        radius = 1.0f;
    }
    const float vfov = 40.0f;
    tr_vec3 pos, dir, up = v3(0.0f, 1.0f, 0.0f);
    float near_d = radius * 1e-3f, far_d;
    if (ex.has_camera) {
        /* Assimp documents mHorizontalFOV as half the horizontal angle, but its Collada and
         * glTF loaders store the whole angle (xfov; 2 atan(aspect tan(yfov / 2))): taken as
         * the whole, the vertical angle follows from the image's aspect. */
        float aspect = (float)info->width / (float)info->height;
        float vf = 2.0f * atanf(tanf(0.5f * ex.cam_hfov) / aspect) * 57.2957795f;
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
        model_warn(info, "the file's camera is unusable; framing the model instead");
    }
    /* In front (+z), a little to the right and above, the whole bounding sphere in view. */
    dir = v3_normalize(v3(-0.45f, -0.35f, -1.0f));
    float dist = radius / sinf(0.5f * vfov * 0.0174532925f) * 1.05f;
    pos = v3_sub(centre, v3_scale(dir, dist));
    far_d = dist + 4.0f * radius;
    if (tr_camera_make(&s->camera, pos, dir, up, vfov, near_d, far_d, info->width, info->height,
                       err) != TR_OK) {
        tr_scene_free(s);
        return TR_ERR;
    }
    s->camera.right = v3_neg(s->camera.right);
    return TR_OK;
}
