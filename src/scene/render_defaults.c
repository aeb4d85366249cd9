/* render_defaults.c - a scene file's render block applied to a program's request
 * (tr_scene_file_apply): what every program that renders scene files would otherwise
 * repeat, with the same defaults and messages as the trac0r command. */
#include "scene/scene_internal.h"
#include "trac0r/camera.h"
#include "trac0r/film.h"
#include "trac0r/registry.h"
#include "trac0r/scene_file.h"
#include "trac0r/session.h"

#include <stdio.h>
#include <math.h>
#include <string.h>

#define DEFAULT_WIDTH 800u
#define DEFAULT_HEIGHT 600u

static uint32_t pick_u32(uint32_t asked, int has, uint32_t file_value, uint32_t fallback) {
    if (asked) {
        return asked;
    }
    return has ? file_value : fallback;
}

/* The integrator: the request's name, else the file's, else pt. */
static int resolve_integrator(const char *path, const tr_scene_file *file,
                              const tr_render_request *req, int *out, tr_error *err) {
    const char *name = req->integrator;
    const int from_file = !name && file->has_integrator;
    if (from_file) {
        name = file->integrator;
    }
    if (!name) {
        *out = TR_INTEGRATOR_PT;
        return TR_OK;
    }
    const int k = tr_integrator_from_name(name);
    if (k >= 0) {
        *out = k;
        return TR_OK;
    }
    char names[128];
    size_t count;
    const char *const *all = tr_integrator_names(&count);
    tr_names_join(names, sizeof names, all, count, NULL);
    if (from_file) {
        return tr_error_set(err, TR_STATUS_PARSE,
                            "%s: render.integrator: unknown integrator '%s' (available: %s)", path,
                            name, names);
    }
    return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                        "integrator: unknown integrator '%s' (available: %s)", name, names);
}

/* The acceleration structure: the request's name, else the file's, else the BVH; one
 * this build lacks is refused. */
static int resolve_accel(const char *path, const tr_scene_file *file, const tr_render_request *req,
                         tr_accel_type *out, tr_error *err) {
    *out = TR_ACCEL_TYPE_BVH;
    if (req->accel) {
        const int k = tr_accel_from_name(req->accel);
        if (k < 0) {
            return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                                "accel: unknown acceleration structure '%s'", req->accel);
        }
        *out = (tr_accel_type)k;
        if (!tr_accel_available(*out)) {
            return tr_error_set(err, TR_STATUS_UNSUPPORTED,
                                "accel: '%s' is not available: this build of trac0r has no "
                                "Embree support",
                                req->accel);
        }
        return TR_OK;
    }
    if (file->has_accel) {
        *out = file->accel;
        if (!tr_accel_available(*out)) {
            return tr_error_set(err, TR_STATUS_UNSUPPORTED,
                                "%s: render.accel: '%s' is not available: this build of trac0r "
                                "has no Embree support",
                                path, tr_accel_name(*out));
        }
    }
    return TR_OK;
}

/* The max depth: the request's, else the file's (written for pt: bdpt and vcm follow at
 * most TR_MAX_DEPTH_BDPT segments, so a longer one is cut to that), else 0, the
 * integrator's default. A request beyond bdpt's limit is left for tr_render_config_check
 * to refuse. */
static int resolve_max_depth(const tr_scene_file *file, const tr_render_request *req,
                             int integrator) {
    if (req->max_depth) {
        return req->max_depth;
    }
    int depth = file->has_max_depth ? file->max_depth : TR_MAX_DEPTH_DEFAULT;
    if (tr_integrator_is_bidirectional(integrator) && depth > TR_MAX_DEPTH_BDPT) {
        depth = TR_MAX_DEPTH_BDPT;
    }
    return depth;
}

void tr_size_fill(uint32_t *width, uint32_t *height, uint32_t dw, uint32_t dh) {
    if (!*width && !*height) {
        *width = dw;
        *height = dh;
    } else if (!*height) {
        *height = (uint32_t)fmin(fmax(round((double)*width * dh / dw), 1.0), TR_FILM_MAX_SIDE);
    } else if (!*width) {
        *width = (uint32_t)fmin(fmax(round((double)*height * dw / dh), 1.0), TR_FILM_MAX_SIDE);
    }
}

int tr_scene_file_apply(tr_scene *s, const char *path, const tr_scene_file *file,
                        const tr_render_request *req, tr_render_settings *out, tr_error *err) {
    static const tr_render_request zero;
    if (!s || !file || !out) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "tr_scene_file_apply: the scene, file and out must not be NULL");
    }
    if (!req) {
        req = &zero;
    }
    if (!path) {
        path = "(scene)";
    }
    memset(out, 0, sizeof *out);
    out->config = tr_render_config_default();
    out->width = pick_u32(req->width, file->has_width, file->width, DEFAULT_WIDTH);
    out->height = pick_u32(req->height, file->has_height, file->height, DEFAULT_HEIGHT);
    /* One side asked for and not the other: the other keeps the image's shape (the file's
     * size, else the default's), as resizing a picture does. */
    if (!req->width != !req->height) {
        out->width = req->width;
        out->height = req->height;
        tr_size_fill(&out->width, &out->height, file->has_width ? file->width : DEFAULT_WIDTH,
                     file->has_height ? file->height : DEFAULT_HEIGHT);
    }
    out->spp = pick_u32(req->spp, file->has_spp, file->spp, TR_SESSION_SPP_DEFAULT);
    int light_sampling = -1;
    if (req->light_sampling) {
        light_sampling = tr_light_sampling_from_name(req->light_sampling);
        if (light_sampling < 0) {
            return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                                "light_sampling: unknown light sampling '%s' (available: auto, "
                                "tree, power)",
                                req->light_sampling);
        }
    }
    if (resolve_accel(path, file, req, &out->accel, err) != TR_OK ||
        resolve_integrator(path, file, req, &out->config.integrator, err) != TR_OK) {
        return TR_ERR;
    }
    out->config.max_depth = resolve_max_depth(file, req, out->config.integrator);
    if (s->punctual_count > 0u && out->config.integrator == TR_INTEGRATOR_NAIVE) {
        /* Delta lights are found by next-event estimation alone (punctual.h). */
        return tr_error_set(err, TR_STATUS_UNSUPPORTED,
                            "%s: lights: %s does not support point, spot or directional lights: "
                            "use pt",
                            path, tr_integrator_name(out->config.integrator));
    }
    if (tr_integrator_is_bidirectional(out->config.integrator) &&
        tr_scene_camera(s)->lens_radius > 0.0f) {
        /* tr_frame_make would refuse the first frame; the file is the place to say it. */
        return tr_error_set(err, TR_STATUS_UNSUPPORTED,
                            "%s: camera.aperture_radius: %s does not support depth of field "
                            "(a camera with an aperture): use pt",
                            path, tr_integrator_name(out->config.integrator));
    }
    /* A sky, a sun or a point, spot or directional light lights a scene without emitters,
     * whichever loader made it. */
    const int lit = s->env_count > 0u || s->sun_count > 0u || s->punctual_count > 0u;
    if (file->emissive_triangles == 0 && !lit && !file->allow_no_emitter && !req->allow_dark) {
        return tr_error_set(err, TR_STATUS_NOT_FOUND,
                            "%s: the scene has no emitter, so the image would be black (set "
                            "render.allow_no_emitter if that is intended)",
                            path);
    }
    if ((uint64_t)out->width * out->height > TR_FILM_MAX_PIXELS) {
        return tr_error_set(err, TR_STATUS_LIMIT, "width/height: %ux%u is more than %u pixels",
                            out->width, out->height, TR_FILM_MAX_PIXELS);
    }
    tr_camera cam = *tr_scene_camera(s);
    tr_error cam_err;
    if (tr_camera_resize(&cam, out->width, out->height, &cam_err) != TR_OK) {
        return tr_error_set(err, cam_err.code, "%s: camera: %s", path, cam_err.msg);
    }
    tr_scene_set_camera(s, &cam);
    if (light_sampling >= 0) {
        return tr_scene_set_light_sampling(s, light_sampling, err);
    }
    return TR_OK;
}

int tr_scene_name_is_builtin(const char *name) {
    return strncmp(name, "builtin:", 8) == 0 || (!strchr(name, '/') && !strchr(name, '.'));
}

int tr_scene_load(tr_scene *s, const char *name, const tr_model_options *opt, tr_scene_file *info,
                  tr_error *err) {
    tr_scene_file local;
    tr_model_options defaults = {0, 1.0f, 0, 0, NULL};
    info = info ? info : &local;
    opt = opt ? opt : &defaults;
    memset(info, 0, sizeof *info);
    if (!tr_scene_name_is_builtin(name)) {
        return tr_scene_path_is_model(name) ? tr_scene_model_load(s, name, opt, info, err)
                                            : tr_scene_file_load(s, name, NULL, info, err);
    }
    uint32_t w = opt->width, h = opt->height;
    tr_size_fill(&w, &h, DEFAULT_WIDTH, DEFAULT_HEIGHT);
    if (tr_scene_builtin(s, strncmp(name, "builtin:", 8) == 0 ? name + 8 : name, w, h, err) !=
        TR_OK) {
        return TR_ERR;
    }
    info->width = w;
    info->height = h;
    info->shape_count = tr_scene_shape_count(s);
    info->bounds = tr_scene_bounds(s);
    /* Kept instances' triangles (past the stored ones) never emit. */
    for (uint32_t i = 0; i < tr_scene_stored_triangle_count(s); ++i) {
        info->emissive_triangles +=
            tr_scene_material(s, tr_scene_triangle(s, i).material).type == TR_MATERIAL_EMITTER;
    }
    for (uint32_t i = 0; i < tr_scene_material_count(s); ++i) {
        info->emitter_materials += tr_scene_material(s, i).type == TR_MATERIAL_EMITTER;
    }
    return TR_OK;
}

/* The request's value where it has one, else the program's default where the file has
 * none; 0 (the file's, else the library's) otherwise. */
static uint32_t pick_default(uint32_t req, int file_has, uint32_t def) {
    return req ? req : file_has ? 0u : def;
}

int tr_scene_open(tr_scene *s, const char *name, const tr_scene_open_desc *d, tr_scene_file *file,
                  tr_render_settings *out, tr_error *err) {
    static const tr_scene_open_desc zero;
    tr_scene_file local;
    d = d ? d : &zero;
    file = file ? file : &local;
    const tr_render_request *rq = &d->request, *df = &d->defaults;
    /* A built-in scene is built at its final size (a model's camera takes the width, and
     * the height where one was asked for: else its own aspect). */
    tr_model_options mo = d->model;
    mo.scale = mo.scale > 0.0f ? mo.scale : 1.0f;
    mo.width = rq->width ? rq->width : rq->height ? 0 : df->width;
    mo.height = rq->height ? rq->height : rq->width ? 0 : df->height;
    if (tr_scene_name_is_builtin(name)) {
        tr_size_fill(&mo.width, &mo.height, df->width ? df->width : DEFAULT_WIDTH,
                     df->height ? df->height : DEFAULT_HEIGHT);
    } else {
        mo.height = rq->height;
    }
    if (tr_scene_load(s, name, &mo, file, err) != TR_OK) {
        file->open_stage = TR_SCENE_OPEN_LOAD;
        return TR_ERR;
    }
    tr_render_request r = *rq;
    if (!rq->width && !rq->height) {
        r.width = pick_default(0, file->has_width, df->width);
        r.height = pick_default(0, file->has_height, df->height);
    }
    r.spp = pick_default(rq->spp, file->has_spp, df->spp);
    r.max_depth =
        (int)pick_default((uint32_t)rq->max_depth, file->has_max_depth, (uint32_t)df->max_depth);
    r.integrator = rq->integrator ? rq->integrator : file->has_integrator ? NULL : df->integrator;
    r.accel = rq->accel ? rq->accel : file->has_accel ? NULL : df->accel;
    r.light_sampling = rq->light_sampling ? rq->light_sampling : df->light_sampling;
    r.allow_dark = rq->allow_dark || d->extras.env || d->extras.sun;
    file->open_stage = TR_SCENE_OPEN_EXTRAS;
    if (tr_scene_add_extras(s, &d->extras, err) == TR_OK) {
        file->open_stage = TR_SCENE_OPEN_SETTINGS;
        if (tr_scene_file_apply(s, name, file, &r, out, err) == TR_OK) {
            file->open_stage = TR_SCENE_OPEN_COMMIT;
            if (tr_scene_commit(s, out->accel, err) == TR_OK) {
                file->open_stage = 0;
                return TR_OK;
            }
        }
    }
    tr_scene_clear(s);
    return TR_ERR;
}
