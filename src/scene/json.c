/* json.c - scenes from JSON files (docs/scene-format.md), parsed with cJSON.
 *
 * Everything in a file is checked before it is used: types, ranges, unknown keys (with a
 * "did you mean" from the edit distance), references to materials, coordinates after
 * their transforms and the triangle budget. Errors are one line: "FILE:LINE:COL: ..." for
 * syntax errors, "FILE: json.path: ..." for everything else. */
#define _POSIX_C_SOURCE 200809L
#include <cJSON.h>
#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "trac0r/camera.h"
#include "trac0r/film.h"
#include "trac0r/registry.h"
#include "scene/scene_internal.h"
#include "trac0r/scene_file.h"
#include "material_registry.h"
#include "util/infile.h"
#include "scene/texture.h"

#define PATH_MAX_LEN 160

/* A material's name and index, sorted by name. */
struct named {
    const char *name;
    uint32_t index;
};

static int named_cmp(const void *a, const void *b) {
    const struct named *x = a, *y = b;
    int c = strcmp(x->name, y->name);
    return c ? c : (x->index > y->index) - (x->index < y->index);
}

/* Scene files may define at most this many materials. */
#define MAX_FILE_MATERIALS 65536

typedef struct jctx {
    const char *file; /* for messages */
    char dir[4096];   /* directory of the file, for mesh paths ("" = current) */
    tr_error *err;
    tr_scene *scene;
    tr_scene_file *info;
    const tr_scene_file_options *opt;
    uint32_t budget;
    cJSON *materials;      /* the "materials" object: names in file order = material indices */
    struct named *by_name; /* the materials sorted by name, for lookups */
    uint32_t name_count;
    /* Prototypes (parse_prototype): the "prototypes" object, and per member (file order)
     * its state (0 not parsed, 1 being parsed, 2 done) and prototype index (UINT32_MAX:
     * empty, its meshes not loaded). prefix: what messages put before a path (inside a
     * prototype, "prototypes.NAME."). */
    const cJSON *protos;
    uint8_t *proto_state;
    uint32_t *proto_index;
    const char *prefix;
    /* Per scene prototype (its index), what checking its kept placements needs, measured
     * once (proto_shape): NULL until the first kept placement. */
    struct proto_shape *shapes;
    uint32_t shape_count;
} jctx;

/* "FILE: PATH: message" with a code. */
static int vjerr(const jctx *c, tr_status code, const char *path, const char *fmt, va_list ap)
    __attribute__((format(printf, 4, 0)));
static int vjerr(const jctx *c, tr_status code, const char *path, const char *fmt, va_list ap) {
    char msg[400];
    vsnprintf(msg, sizeof msg, fmt, ap);
    if (path && path[0]) {
        return tr_error_set(c->err, code, "%.200s: %s%s: %s", c->file, c->prefix ? c->prefix : "",
                            path, msg);
    }
    return tr_error_set(c->err, code, "%.200s: %s", c->file, msg);
}

/* The file says something wrong (TR_STATUS_PARSE): "FILE: PATH: message". */
static int jerr(const jctx *c, const char *path, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
static int jerr(const jctx *c, const char *path, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    int rc = vjerr(c, TR_STATUS_PARSE, path, fmt, ap);
    va_end(ap);
    return rc;
}

/* The same for the failures that are not the file's content: a budget, memory. */
static int jerr_code(const jctx *c, tr_status code, const char *path, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));
static int jerr_code(const jctx *c, tr_status code, const char *path, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    int rc = vjerr(c, code, path, fmt, ap);
    va_end(ap);
    return rc;
}

/* A library call failed on the file's values: its message goes after "FILE: PATH:" and
 * its code is kept, except that a value it finds out of range is the file's fault. */
static int jerr_from(const jctx *c, const char *path, const tr_error *e) {
    const tr_status code = e->code == TR_STATUS_INVALID_ARGUMENT ? TR_STATUS_PARSE : e->code;
    return jerr_code(c, code, path, "%s", e->msg);
}

static void warn(const jctx *c, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void warn(const jctx *c, const char *fmt, ...) {
    tr_scene_file *info = c->info;
    if (info->warning_count >= TR_SCENE_FILE_MAX_WARNINGS) {
        return;
    }
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(info->warnings[info->warning_count++], sizeof info->warnings[0], fmt, ap);
    va_end(ap);
}

static void path_key(char *out, const char *base, const char *key) {
    int n = base[0] ? snprintf(out, PATH_MAX_LEN, "%s.%.40s", base, key)
                    : snprintf(out, PATH_MAX_LEN, "%.40s", key);
    if (n < 0 || n >= PATH_MAX_LEN) {
        out[PATH_MAX_LEN - 1] = '\0'; /* (paths are short: keys are cut to 40 bytes) */
    }
}

static void path_index(char *out, const char *base, int i) {
    if (snprintf(out, PATH_MAX_LEN, "%s[%d]", base, i) >= PATH_MAX_LEN) {
        out[PATH_MAX_LEN - 1] = '\0';
    }
}

/* A printable, shortened copy of a JSON key or string for messages. */
static const char *shown(const char *s, char *buf, size_t n) {
    size_t j = 0;
    for (size_t i = 0; s[i] && j + 4 < n; ++i) {
        unsigned char ch = (unsigned char)s[i];
        buf[j++] = (ch >= 32 && ch < 127) ? (char)ch : '?';
    }
    if (strlen(s) + 4 >= n) {
        buf[j++] = '.', buf[j++] = '.', buf[j++] = '.';
    }
    buf[j] = '\0';
    return buf;
}

static const char *type_name(const cJSON *v) {
    if (cJSON_IsNumber(v)) {
        return "a number";
    }
    if (cJSON_IsString(v)) {
        return "a string";
    }
    if (cJSON_IsBool(v)) {
        return "a boolean";
    }
    if (cJSON_IsNull(v)) {
        return "null";
    }
    if (cJSON_IsArray(v)) {
        return "an array";
    }
    if (cJSON_IsObject(v)) {
        return "an object";
    }
    return "an invalid value";
}

/* Rejects keys of obj not in allowed[] (with a suggestion) and duplicate keys. */
static int check_keys(const jctx *c, const cJSON *obj, const char *path, const char *const *allowed,
                      size_t count) {
    for (const cJSON *k = obj->child; k; k = k->next) {
        const char *name = k->string ? k->string : "";
        char p[PATH_MAX_LEN], buf[48];
        path_key(p, path, shown(name, buf, sizeof buf));
        int known = 0;
        for (size_t i = 0; i < count; ++i) {
            known |= strcmp(name, allowed[i]) == 0;
        }
        if (!known) {
            const char *near = tr_names_closest(name, allowed, count);
            char list[256] = "";
            for (size_t i = 0; i < count; ++i) {
                size_t used = strlen(list);
                snprintf(list + used, sizeof list - used, "%s%s", i ? ", " : "", allowed[i]);
            }
            if (near) {
                return jerr(c, p, "unknown key (did you mean '%s'?)", near);
            }
            return jerr(c, p, "unknown key (expected one of: %s)", list);
        }
        for (const cJSON *o = obj->child; o != k; o = o->next) {
            if (o->string && strcmp(o->string, name) == 0) {
                return jerr(c, p, "duplicate key");
            }
        }
    }
    return TR_OK;
}

static int expect_object(const jctx *c, const cJSON *v, const char *path) {
    if (!cJSON_IsObject(v)) {
        return jerr(c, path, "expected an object, got %s", type_name(v));
    }
    return TR_OK;
}

/* A number in [lo, hi]; *present says whether the key exists (NULL: required). */
static int get_number(const jctx *c, const cJSON *obj, const char *path, const char *key, double lo,
                      double hi, double *out, int *present) {
    char p[PATH_MAX_LEN];
    path_key(p, path, key);
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(obj, key);
    if (!v) {
        if (present) {
            *present = 0;
            return TR_OK;
        }
        return jerr(c, p, "missing (expected a number in [%g, %g])", lo, hi);
    }
    if (!cJSON_IsNumber(v)) {
        return jerr(c, p, "expected a number in [%g, %g], got %s", lo, hi, type_name(v));
    }
    double x = v->valuedouble;
    if (!isfinite(x) || x < lo || x > hi) {
        return jerr(c, p, "expected a number in [%g, %g], got %g", lo, hi, x);
    }
    if (present) {
        *present = 1;
    }
    *out = x;
    return TR_OK;
}

/* A number kept as a float, in [lo, hi] compared as floats: a documented float limit such
 * as 0.001 then accepts "0.001" (as a double it lies just below the float 0.001f). */
static int get_float(const jctx *c, const cJSON *obj, const char *path, const char *key, float lo,
                     float hi, float *out, int *present) {
    int here = 1;
    double x = 0.0;
    if (get_number(c, obj, path, key, -HUGE_VAL, HUGE_VAL, &x, present ? &here : NULL) != TR_OK) {
        return TR_ERR;
    }
    if (present) {
        *present = here;
    }
    if (!here) {
        return TR_OK;
    }
    const float f = (float)x;
    if (!(f >= lo && f <= hi)) {
        char p[PATH_MAX_LEN];
        path_key(p, path, key);
        return jerr(c, p, "expected a number in [%g, %g], got %g", (double)lo, (double)hi, x);
    }
    *out = f;
    return TR_OK;
}

/* A whole number in [lo, hi]. */
static int get_integer(const jctx *c, const cJSON *obj, const char *path, const char *key,
                       double lo, double hi, double *out, int *present) {
    int here = 0;
    if (get_number(c, obj, path, key, lo, hi, out, present ? present : &here) != TR_OK) {
        return TR_ERR;
    }
    char p[PATH_MAX_LEN];
    path_key(p, path, key);
    if (!present && !here) {
        return jerr(c, p, "missing (expected an integer in %.0f..%.0f)", lo, hi);
    }
    if ((present ? *present : here) && *out != floor(*out)) {
        return jerr(c, p, "expected an integer in %.0f..%.0f, got %g", lo, hi, *out);
    }
    return TR_OK;
}

static int get_bool(const jctx *c, const cJSON *obj, const char *path, const char *key, int *out) {
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(obj, key);
    if (!v) {
        return TR_OK;
    }
    if (!cJSON_IsBool(v)) {
        char p[PATH_MAX_LEN];
        path_key(p, path, key);
        return jerr(c, p, "expected true or false, got %s", type_name(v));
    }
    *out = cJSON_IsTrue(v);
    return TR_OK;
}

/* A string; NULL in *out when absent and not required. */
static int get_string(const jctx *c, const cJSON *obj, const char *path, const char *key,
                      int required, const char **out) {
    char p[PATH_MAX_LEN];
    path_key(p, path, key);
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(obj, key);
    *out = NULL;
    if (!v) {
        return required ? jerr(c, p, "missing (expected a string)") : TR_OK;
    }
    if (!cJSON_IsString(v) || !v->valuestring) {
        return jerr(c, p, "expected a string, got %s", type_name(v));
    }
    *out = v->valuestring;
    return TR_OK;
}

/* [x, y, z] with every |component| <= bound (and >= lo_each if positive is set). */
static int get_vec3(const jctx *c, const cJSON *obj, const char *path, const char *key,
                    int required, int positive, tr_vec3 *out, int *present) {
    char p[PATH_MAX_LEN];
    path_key(p, path, key);
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(obj, key);
    if (present) {
        *present = v != NULL;
    }
    const double bound = TR_SCENE_FILE_MAX_COORD;
    if (!v) {
        return required ? jerr(c, p, "missing (expected [x, y, z])") : TR_OK;
    }
    if (!cJSON_IsArray(v) || cJSON_GetArraySize(v) != 3) {
        return jerr(c, p, "expected an array of 3 numbers [x, y, z], got %s%s", type_name(v),
                    cJSON_IsArray(v) ? " of another length" : "");
    }
    double x[3];
    int i = 0;
    for (const cJSON *e = v->child; e; e = e->next, ++i) {
        char pe[PATH_MAX_LEN];
        path_index(pe, p, i);
        if (!cJSON_IsNumber(e)) {
            return jerr(c, pe, "expected a number, got %s", type_name(e));
        }
        x[i] = e->valuedouble;
        if (!isfinite(x[i]) || fabs(x[i]) > bound) {
            return jerr(c, pe, "expected a finite number with |x| <= %g, got %g", bound, x[i]);
        }
        if (positive && !(x[i] > 0.0)) {
            return jerr(c, pe, "expected a positive number, got %g", x[i]);
        }
    }
    *out = v3((float)x[0], (float)x[1], (float)x[2]);
    return TR_OK;
}

/* A colour: [r, g, b], each in [0, hi]. */
static int get_color(const jctx *c, const cJSON *obj, const char *path, const char *key, double hi,
                     tr_vec3 *out) {
    char p[PATH_MAX_LEN];
    if (get_vec3(c, obj, path, key, 1, 0, out, NULL) != TR_OK) {
        return TR_ERR;
    }
    const float rgb[3] = {out->x, out->y, out->z};
    for (int i = 0; i < 3; ++i) {
        if (rgb[i] < 0.0f || rgb[i] > hi) {
            char pk[PATH_MAX_LEN];
            path_key(pk, path, key);
            path_index(p, pk, i);
            return jerr(c, p, "expected a number in [0, %g], got %g", hi, (double)rgb[i]);
        }
    }
    return TR_OK;
}

/* ---------------------------------------------------------------------------------- */

static int parse_render(jctx *c, const cJSON *r) {
    static const char *const keys[] = {
        "width", "height",           "spp",           "max_depth", "integrator",
        "accel", "allow_no_emitter", "light_sampling"};
    const char *path = "render";
    if (expect_object(c, r, path) != TR_OK ||
        check_keys(c, r, path, keys, sizeof keys / sizeof keys[0]) != TR_OK) {
        return TR_ERR;
    }
    tr_scene_file *in = c->info;
    double x;
    if (get_integer(c, r, path, "width", 1, TR_FILM_MAX_SIDE, &x, &in->has_width) != TR_OK) {
        return TR_ERR;
    }
    if (in->has_width) {
        in->width = (uint32_t)x;
    }
    if (get_integer(c, r, path, "height", 1, TR_FILM_MAX_SIDE, &x, &in->has_height) != TR_OK) {
        return TR_ERR;
    }
    if (in->has_height) {
        in->height = (uint32_t)x;
    }
    if ((uint64_t)in->width * in->height > TR_FILM_MAX_PIXELS) {
        return jerr(c, "render.height", "%ux%u is more than %u pixels", in->width, in->height,
                    TR_FILM_MAX_PIXELS);
    }
    if (get_integer(c, r, path, "spp", 1, 1000000, &x, &in->has_spp) != TR_OK) {
        return TR_ERR;
    }
    if (in->has_spp) {
        in->spp = (uint32_t)x;
    }
    if (get_integer(c, r, path, "max_depth", 1, 1024, &x, &in->has_max_depth) != TR_OK) {
        return TR_ERR;
    }
    if (in->has_max_depth) {
        in->max_depth = (int)x;
    }
    const char *s;
    if (get_string(c, r, path, "integrator", 0, &s) != TR_OK) {
        return TR_ERR;
    }
    if (s) {
        char buf[40];
        /* Checked here, so that `info` refuses what `render` would. */
        if (strlen(s) >= sizeof in->integrator || tr_integrator_from_name(s) < 0) {
            size_t count;
            const char *const *names = tr_integrator_names(&count);
            char expected[128];
            tr_names_join(expected, sizeof expected, names, count, ", ");
            return jerr(c, "render.integrator", "unknown integrator '%s' (available: %s)",
                        shown(s, buf, sizeof buf), expected);
        }
        snprintf(in->integrator, sizeof in->integrator, "%s", s);
        in->has_integrator = 1;
    }
    if (get_string(c, r, path, "accel", 0, &s) != TR_OK) {
        return TR_ERR;
    }
    if (s) {
        int a = tr_accel_from_name(s);
        if (a < 0) {
            size_t count;
            const char *const *names = tr_accel_names(&count);
            char buf[40], expected[128];
            tr_names_join(expected, sizeof expected, names, count, " or ");
            const char *near = tr_names_closest(s, names, count);
            return jerr(c, "render.accel",
                        "unknown acceleration structure '%s' (expected %s%s%s%s)",
                        shown(s, buf, sizeof buf), expected, near ? "; did you mean '" : "",
                        near ? near : "", near ? "'?" : "");
        }
        in->accel = (tr_accel_type)a;
        in->has_accel = 1;
    }
    /* render.light_sampling: how next-event estimation picks emitters, a property of the scene that
     * tr_scene_commit builds for. */
    if (get_string(c, r, path, "light_sampling", 0, &s) != TR_OK) {
        return TR_ERR;
    }
    if (s) {
        int m = tr_light_sampling_from_name(s);
        if (m < 0) {
            char buf[40];
            return jerr(c, "render.light_sampling",
                        "unknown light sampling '%s' (expected auto, tree or power)",
                        shown(s, buf, sizeof buf));
        }
        tr_scene_set_light_sampling(c->scene, m, NULL);
    }
    return get_bool(c, r, path, "allow_no_emitter", &in->allow_no_emitter);
}

/* The thin lens's keys of the camera (made already): aperture_radius or f_number (with
 * sensor_height), and focus_distance, which defaults to look_at's distance along the view
 * direction (look_dist; 0 without look_at). */
static int parse_lens(jctx *c, const cJSON *cam, float look_dist) {
    const char *path = "camera";
    double radius = 0.0, fnum = 0.0, sensor = 0.024, focus = 0.0;
    int has_radius, has_fnum, has_sensor, has_focus;
    if (get_number(c, cam, path, "aperture_radius", 0.0, 1e30, &radius, &has_radius) != TR_OK ||
        get_number(c, cam, path, "f_number", 0.01, 1e30, &fnum, &has_fnum) != TR_OK ||
        get_number(c, cam, path, "sensor_height", 1e-30, 1e30, &sensor, &has_sensor) != TR_OK ||
        get_number(c, cam, path, "focus_distance", 1e-30, 1e30, &focus, &has_focus) != TR_OK) {
        return TR_ERR;
    }
    if (has_radius && has_fnum) {
        return jerr(c, path, "expected at most one of 'aperture_radius' and 'f_number', got both");
    }
    if (has_sensor && !has_fnum) {
        return jerr(c, "camera.sensor_height", "only means something with camera.f_number");
    }
    tr_camera *cm = &c->scene->camera;
    if (has_fnum) {
        radius = tr_camera_lens_radius_for(cm, (float)fnum, (float)sensor);
    }
    if (!(radius > 0.0) && !has_focus) {
        return TR_OK; /* a pinhole */
    }
    if (!has_focus) {
        if (!(look_dist > 0.0f)) {
            return jerr(c, "camera.focus_distance",
                        "missing (expected with an aperture and 'direction': the distance of "
                        "the plane in focus, > 0)");
        }
        focus = look_dist;
    }
    /* A radius of 0 keeps the pinhole (the focus distance is kept, unused). */
    tr_error e;
    if (tr_camera_set_lens(cm, (float)radius, (float)focus, &e) != TR_OK) {
        return jerr_from(c, path, &e);
    }
    return TR_OK;
}

static int parse_camera(jctx *c, const cJSON *cam) {
    static const char *const keys[] = {
        "position", "look_at",    "direction",       "up",       "fov",           "near",
        "far",      "handedness", "aperture_radius", "f_number", "sensor_height", "focus_distance"};
    const char *path = "camera";
    if (expect_object(c, cam, path) != TR_OK ||
        check_keys(c, cam, path, keys, sizeof keys / sizeof keys[0]) != TR_OK) {
        return TR_ERR;
    }
    tr_vec3 pos, look = v3s(0.0f), dir = v3s(0.0f), up = v3(0.0f, 1.0f, 0.0f);
    int has_look = 0, has_dir = 0, has_x = 0;
    if (get_vec3(c, cam, path, "position", 1, 0, &pos, NULL) != TR_OK ||
        get_vec3(c, cam, path, "look_at", 0, 0, &look, &has_look) != TR_OK ||
        get_vec3(c, cam, path, "direction", 0, 0, &dir, &has_dir) != TR_OK ||
        get_vec3(c, cam, path, "up", 0, 0, &up, &has_x) != TR_OK) {
        return TR_ERR;
    }
    if (has_look == has_dir) {
        return jerr(c, path, "expected exactly one of 'look_at' and 'direction'%s",
                    has_look ? ", got both" : "");
    }
    if (has_look) {
        dir = v3_sub(look, pos);
        if (!(v3_length(dir) > 0.0f)) {
            return jerr(c, "camera.look_at", "must differ from camera.position");
        }
    } else if (!(v3_length(dir) > 0.0f)) {
        return jerr(c, "camera.direction", "expected a non-zero vector");
    }
    if (!(v3_length(up) > 0.0f)) {
        return jerr(c, "camera.up", "expected a non-zero vector");
    }
    double fov, near_d = 0.001, far_d = 1e30;
    int present;
    const cJSON *fv = cJSON_GetObjectItemCaseSensitive(cam, "fov");
    if (!fv) {
        return jerr(c, "camera.fov",
                    "missing (expected a vertical field of view in (0, 180) "
                    "degrees)");
    }
    if (!cJSON_IsNumber(fv)) {
        return jerr(c, "camera.fov",
                    "expected a vertical field of view in (0, 180) degrees, got %s", type_name(fv));
    }
    fov = fv->valuedouble;
    if (!(fov > 0.0 && fov < 180.0)) {
        return jerr(c, "camera.fov",
                    "expected a vertical field of view in (0, 180) degrees, got %g", fov);
    }
    if (get_number(c, cam, path, "near", 0.0, 1e30, &near_d, &present) != TR_OK ||
        get_number(c, cam, path, "far", 0.0, 1e30, &far_d, &present) != TR_OK) {
        return TR_ERR;
    }
    if (!(far_d > near_d)) {
        return jerr(c, "camera.far", "expected more than camera.near (%g), got %g", near_d, far_d);
    }
    const char *hand;
    if (get_string(c, cam, path, "handedness", 0, &hand) != TR_OK) {
        return TR_ERR;
    }
    int right_handed = 0;
    if (hand) {
        if (strcmp(hand, "right") == 0) {
            right_handed = 1;
        } else if (strcmp(hand, "left") != 0) {
            char buf[40];
            return jerr(c, "camera.handedness", "expected \"left\" or \"right\", got '%s'",
                        shown(hand, buf, sizeof buf));
        }
    }
    tr_error e;
    tr_scene_file *in = c->info;
    if (tr_camera_make(&c->scene->camera, pos, dir, up, (float)fov, (float)near_d, (float)far_d,
                       in->width, in->height, &e) != TR_OK) {
        return jerr_from(c, path, &e);
    }
    if (right_handed) {
        /* A right-handed world seen with +y up: the camera's right is dir x up, the
         * mirror image of the thesis's up x dir; the up vector stays. */
        c->scene->camera.right = v3_neg(c->scene->camera.right);
    }
    return parse_lens(c, cam, has_look ? v3_dot(v3_sub(look, pos), c->scene->camera.dir) : 0.0f);
}

/* Keys every material but an emitter takes besides its type's (attrib.h's extras). */
static const char *const extra_keys[] = {"texture",
                                         "normal_texture",
                                         "emission",
                                         "emission_texture",
                                         "alpha_cutoff",
                                         "metallic",
                                         "metallic_roughness_texture",
                                         "clearcoat",
                                         "clearcoat_roughness",
                                         "clearcoat_texture",
                                         "clearcoat_roughness_texture",
                                         "clearcoat_normal_texture",
                                         "clearcoat_normal_scale",
                                         "emission_strength",
                                         "transmission",
                                         "transmission_texture",
                                         "attenuation_color",
                                         "attenuation_distance",
                                         "sheen_color",
                                         "sheen_roughness",
                                         "sheen_color_texture",
                                         "sheen_roughness_texture",
                                         "specular",
                                         "specular_color"};
#define EXTRA_KEY_COUNT (sizeof extra_keys / sizeof extra_keys[0])

/* Extras that only the principled material takes. */
static int principled_only(const char *key) {
    return strcmp(key, "metallic") == 0 || strncmp(key, "clearcoat", 9) == 0 ||
           strncmp(key, "transmission", 12) == 0 || strncmp(key, "attenuation_", 12) == 0 ||
           strncmp(key, "sheen_", 6) == 0 || strncmp(key, "specular", 8) == 0;
}

/* A pair of numbers [a, b] in [-1e6, 1e6] at key (left as they are when absent). */
static int get_pair(const jctx *c, const cJSON *obj, const char *path, const char *key,
                    float out[2]) {
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(obj, key);
    if (!v) {
        return TR_OK;
    }
    char p[PATH_MAX_LEN];
    path_key(p, path, key);
    if (!cJSON_IsArray(v) || cJSON_GetArraySize(v) != 2 || !cJSON_IsNumber(v->child) ||
        !cJSON_IsNumber(v->child->next) || !(fabs(v->child->valuedouble) <= 1e6) ||
        !(fabs(v->child->next->valuedouble) <= 1e6)) {
        return jerr(c, p, "expected two numbers [u, v] in [-1e+06, 1e+06]");
    }
    out[0] = (float)v->child->valuedouble;
    out[1] = (float)v->child->next->valuedouble;
    return TR_OK;
}

/* A texture key: "file.png" or {"path": "file.png", "wrap": "repeat" | "clamp", "offset":
 * [u, v], "rotation": radians, "scale": [u, v]} (the last three KHR_texture_transform's);
 * loaded relative to the scene file (not opened when meshes are not loaded: the fuzzer). */
static int get_texture(jctx *c, const cJSON *m, const char *path, const char *key,
                       uint32_t *index) {
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(m, key);
    *index = TR_NO_INDEX;
    if (!v) {
        return TR_OK;
    }
    char p[PATH_MAX_LEN];
    path_key(p, path, key);
    const char *rel = NULL;
    uint32_t flags = 0;
    float offset[2] = {0.0f, 0.0f}, scale[2] = {1.0f, 1.0f};
    double rotation = 0.0;
    if (cJSON_IsString(v) && v->valuestring) {
        rel = v->valuestring;
    } else if (cJSON_IsObject(v)) {
        static const char *const keys[] = {"path", "wrap", "offset", "rotation", "scale"};
        const char *wrap = NULL;
        if (check_keys(c, v, p, keys, 5) != TR_OK ||
            get_string(c, v, p, "path", 1, &rel) != TR_OK ||
            get_string(c, v, p, "wrap", 0, &wrap) != TR_OK ||
            get_pair(c, v, p, "offset", offset) != TR_OK ||
            get_pair(c, v, p, "scale", scale) != TR_OK ||
            get_number(c, v, p, "rotation", -1e3, 1e3, &rotation, &(int){0}) != TR_OK) {
            return TR_ERR;
        }
        if (wrap && strcmp(wrap, "clamp") == 0) {
            flags |= TR_TEXTURE_CLAMP;
        } else if (wrap && strcmp(wrap, "repeat") != 0) {
            char pw[PATH_MAX_LEN], buf[40];
            path_key(pw, p, "wrap");
            return jerr(c, pw, "unknown wrap mode '%s' (expected repeat or clamp)",
                        shown(wrap, buf, sizeof buf));
        }
    } else {
        return jerr(c, p, "expected a file name or {\"path\": ..., \"wrap\": ...}, got %s",
                    type_name(v));
    }
    if (!rel[0]) {
        return jerr(c, p, "expected a file name, got an empty string");
    }
    if (!c->opt->load_meshes) {
        return TR_OK;
    }
    char full[8192];
    if (rel[0] == '/' || !c->dir[0]) {
        snprintf(full, sizeof full, "%s", rel);
    } else {
        snprintf(full, sizeof full, "%s/%s", c->dir, rel);
    }
    tr_error e;
    if (tr_scene_load_texture(c->scene, full, flags, index, &e) != TR_OK) {
        return jerr_from(c, p, &e);
    }
    float xf[6];
    tr_texture_transform_glTF(xf, offset[0], offset[1], (float)rotation, scale[0], scale[1]);
    if (tr_scene_texture_transformed(c->scene, *index, xf, index, &e) != TR_OK) {
        return jerr_from(c, p, &e);
    }
    return TR_OK;
}

/* The extras of material `index` from its keys (check_keys has allowed them); nothing is stored
 * when it has none, so that untextured scenes keep no extras array. */
static int parse_material_extras(jctx *c, const cJSON *m, const char *p, uint32_t index) {
    int any = 0;
    for (size_t k = 0; k < EXTRA_KEY_COUNT; ++k) {
        any |= cJSON_GetObjectItemCaseSensitive(m, extra_keys[k]) != NULL;
    }
    if (!any) {
        return TR_OK;
    }
    tr_material_ext e = tr_material_ext_default();
    int has_cut = 0, has_metal = 0, has_em = 0, has_coat = 0;
    double cut = 0.5, metal = 0.0, coat = 0.0, coat_rough = 0.0;
    if (get_texture(c, m, p, "texture", &e.base_tex) != TR_OK ||
        get_texture(c, m, p, "normal_texture", &e.normal_tex) != TR_OK ||
        get_texture(c, m, p, "emission_texture", &e.emission_tex) != TR_OK ||
        get_texture(c, m, p, "metallic_roughness_texture", &e.mr_tex) != TR_OK ||
        get_texture(c, m, p, "transmission_texture", &e.transmission_tex) != TR_OK ||
        get_texture(c, m, p, "clearcoat_texture", &e.clearcoat_tex) != TR_OK ||
        get_texture(c, m, p, "clearcoat_roughness_texture", &e.clearcoat_rough_tex) != TR_OK ||
        get_texture(c, m, p, "clearcoat_normal_texture", &e.clearcoat_normal_tex) != TR_OK ||
        get_texture(c, m, p, "sheen_color_texture", &e.sheen_color_tex) != TR_OK ||
        get_texture(c, m, p, "sheen_roughness_texture", &e.sheen_rough_tex) != TR_OK ||
        get_vec3(c, m, p, "emission", 0, 0, &e.emission, &has_em) != TR_OK ||
        get_number(c, m, p, "alpha_cutoff", 0.0, 1.0, &cut, &has_cut) != TR_OK ||
        get_number(c, m, p, "metallic", 0.0, 1.0, &metal, &has_metal) != TR_OK ||
        get_number(c, m, p, "clearcoat", 0.0, 1.0, &coat, &has_coat) != TR_OK ||
        get_number(c, m, p, "clearcoat_roughness", 0.0, 1.0, &coat_rough, &has_coat) != TR_OK) {
        return TR_ERR;
    }
    e.clearcoat = (float)coat;
    e.clearcoat_roughness = (float)coat_rough;
    double coat_nscale = 1.0;
    if (get_number(c, m, p, "clearcoat_normal_scale", 0.0, 10.0, &coat_nscale, &(int){0}) !=
        TR_OK) {
        return TR_ERR;
    }
    e.clearcoat_normal_scale = (float)coat_nscale;
    /* KHR_materials_emissive_strength, _transmission and _volume's attenuation. */
    int has_att = 0, has_dist = 0, has_strength = 0, has_tr = 0;
    double strength = 1.0, transmission = 0.0, dist = 0.0;
    tr_vec3 att = v3s(1.0f);
    if (get_number(c, m, p, "emission_strength", 0.0, 1e7, &strength, &has_strength) != TR_OK ||
        get_number(c, m, p, "transmission", 0.0, 1.0, &transmission, &has_tr) != TR_OK ||
        get_vec3(c, m, p, "attenuation_color", 0, 1, &att, &has_att) != TR_OK ||
        get_number(c, m, p, "attenuation_distance", 1e-6, 1e30, &dist, &has_dist) != TR_OK) {
        return TR_ERR;
    }
    if (has_att && (att.x > 1.0f || att.y > 1.0f || att.z > 1.0f)) {
        char pa[PATH_MAX_LEN];
        path_key(pa, p, "attenuation_color");
        return jerr(c, pa, "expected three numbers in (0, 1]");
    }
    e.transmission = (float)transmission;
    /* KHR_materials_sheen: its colour and roughness (bsdf_principled.h). */
    int has_sheen = 0;
    double sheen_rough = 0.0;
    if (get_vec3(c, m, p, "sheen_color", 0, 0, &e.sheen_color, &has_sheen) != TR_OK ||
        get_number(c, m, p, "sheen_roughness", 0.0, 1.0, &sheen_rough, &has_sheen) != TR_OK) {
        return TR_ERR;
    }
    e.sheen_roughness = (float)sheen_rough;
    if (e.sheen_color.x < 0.0f || e.sheen_color.y < 0.0f || e.sheen_color.z < 0.0f ||
        e.sheen_color.x > 1.0f || e.sheen_color.y > 1.0f || e.sheen_color.z > 1.0f) {
        char ps[PATH_MAX_LEN];
        path_key(ps, p, "sheen_color");
        return jerr(c, ps, "expected three numbers in [0, 1]");
    }
    /* KHR_materials_specular: the dielectric layer's F0 scale and tint. */
    int has_spec = 0, has_spec_col = 0;
    double specular = 1.0;
    tr_vec3 spec_col = v3s(1.0f);
    if (get_number(c, m, p, "specular", 0.0, 1.0, &specular, &has_spec) != TR_OK ||
        get_vec3(c, m, p, "specular_color", 0, 0, &spec_col, &has_spec_col) != TR_OK) {
        return TR_ERR;
    }
    if (has_spec_col && !(spec_col.x >= 0.0f && spec_col.y >= 0.0f && spec_col.z >= 0.0f &&
                          spec_col.x <= 10.0f && spec_col.y <= 10.0f && spec_col.z <= 10.0f)) {
        char ps[PATH_MAX_LEN];
        path_key(ps, p, "specular_color");
        return jerr(c, ps, "expected three numbers in [0, 10]");
    }
    if (has_spec || has_spec_col) {
        e.flags |= TR_MATEXT_SPECULAR;
        e.specular = (float)specular;
        e.specular_color = spec_col;
    }
    if (has_dist) {
        e.absorption = tr_volume_absorption(att, (float)dist);
    }
    if (has_em && (e.emission.x < 0.0f || e.emission.y < 0.0f || e.emission.z < 0.0f ||
                   e.emission.x > 1e7f || e.emission.y > 1e7f || e.emission.z > 1e7f)) {
        char pe[PATH_MAX_LEN];
        path_key(pe, p, "emission");
        return jerr(c, pe, "expected three numbers in [0, 1e+07]");
    }
    if (cJSON_GetObjectItemCaseSensitive(m, "emission_texture") &&
        !cJSON_GetObjectItemCaseSensitive(m, "emission")) {
        e.emission = v3s(1.0f); /* the texture alone gives the radiance */
    }
    if (has_strength) {
        e.emission = v3_scale(e.emission, (float)strength);
        if (e.emission.x > 1e7f || e.emission.y > 1e7f || e.emission.z > 1e7f) {
            char ps[PATH_MAX_LEN];
            path_key(ps, p, "emission_strength");
            return jerr(c, ps, "the emission times its strength exceeds 1e+07");
        }
    }
    e.metallic = (float)metal;
    if (has_cut) {
        e.flags |= TR_MATEXT_ALPHA_MASK;
        e.alpha_cutoff = (float)cut;
    }
    tr_error err;
    if (tr_scene_set_material_ext(c->scene, index, &e, &err) != TR_OK) {
        return jerr_from(c, p, &err);
    }
    return TR_OK;
}

static int parse_materials(jctx *c, const cJSON *mats) {
    const char *path = "materials";
    if (expect_object(c, mats, path) != TR_OK) {
        return TR_ERR;
    }
    size_t ntypes, nkeys;
    const char *const *types = tr_material_type_names(&ntypes);
    const tr_material_key_info *keys = tr_material_keys(&nkeys);
    int n = cJSON_GetArraySize(mats);
    c->by_name = malloc((size_t)(n > 0 ? (n < MAX_FILE_MATERIALS ? n : MAX_FILE_MATERIALS) : 1) *
                        sizeof *c->by_name);
    if (!c->by_name) {
        return jerr_code(c, TR_STATUS_OUT_OF_MEMORY, path, "out of memory");
    }
    for (const cJSON *m = mats->child; m; m = m->next) {
        char p[PATH_MAX_LEN], buf[48];
        path_key(p, path, shown(m->string ? m->string : "", buf, sizeof buf));
        if (!m->string || !m->string[0]) {
            return jerr(c, p, "a material needs a non-empty name");
        }
        if (c->name_count == MAX_FILE_MATERIALS) {
            return jerr_code(c, TR_STATUS_LIMIT, p, "more than %d materials", MAX_FILE_MATERIALS);
        }
        c->by_name[c->name_count].name = m->string;
        c->by_name[c->name_count].index = c->name_count;
        c->name_count++;
        if (expect_object(c, m, p) != TR_OK) {
            return TR_ERR;
        }
        const char *type;
        if (get_string(c, m, p, "type", 1, &type) != TR_OK) {
            return TR_ERR;
        }
        int t = tr_material_type_from_name(type);
        uint32_t required, optional;
        if (t < 0 || !tr_material_type_keys((uint32_t)t, &required, &optional)) {
            char pt[PATH_MAX_LEN], tb[40], expected[128];
            path_key(pt, p, "type");
            const char *near = tr_names_closest(type, types, ntypes);
            size_t len = (size_t)snprintf(expected, sizeof expected, "expected ");
            tr_names_join(expected + len, sizeof expected - len, types, ntypes, " or ");
            return jerr(c, pt, "unknown material type '%s' (%s%s%s)", shown(type, tb, sizeof tb),
                        near ? "did you mean '" : expected, near ? near : "", near ? "'?" : "");
        }
        /* The keys this type takes, from the registry: "type", then each key of its masks
         * (a name two keys share, such as "color", once). */
        const char *allowed[48] = {"type"};
        size_t nallowed = 1;
        for (size_t k = 0; k < nkeys && nallowed < 48; ++k) {
            int dup = 0;
            for (size_t i = 0; i < nallowed; ++i) {
                dup |= strcmp(allowed[i], keys[k].name) == 0;
            }
            if (!dup && (keys[k].key & (required | optional))) {
                allowed[nallowed++] = keys[k].name;
            }
        }
        /* Then the extras (textures, emission, cut-outs) every non-emitter takes;
         * "metallic" and the clear coat's keys are the principled material's alone. */
        for (size_t k = 0; t != TR_MATERIAL_EMITTER && k < EXTRA_KEY_COUNT && nallowed < 48; ++k) {
            if (t == TR_MATERIAL_PRINCIPLED || !principled_only(extra_keys[k])) {
                allowed[nallowed++] = extra_keys[k];
            }
        }
        if (check_keys(c, m, p, allowed, nallowed) != TR_OK) {
            return TR_ERR;
        }
        tr_material mat = tr_material_default((uint32_t)t);
        for (size_t k = 0; k < nkeys; ++k) {
            const tr_material_key_info *ki = &keys[k];
            if (!(ki->key & (required | optional))) {
                continue;
            }
            int is_required = (ki->key & required) != 0u, present = 0;
            if (ki->kind == TR_KEY_COLOR) {
                tr_vec3 color; /* (colours are always required) */
                if (get_color(c, m, p, ki->name, ki->hi, &color) != TR_OK) {
                    return TR_ERR;
                }
                memcpy((char *)&mat + ki->offset, &color, sizeof color);
            } else if (ki->kind == TR_KEY_FLAG) {
                /* Absent: the type's default (tr_material_default); false clears it. */
                int on = (mat.flags & ki->flag) != 0u;
                if (get_bool(c, m, p, ki->name, &on) != TR_OK) {
                    return TR_ERR;
                }
                mat.flags = on ? mat.flags | ki->flag : mat.flags & ~ki->flag;
            } else {
                double x;
                if (get_number(c, m, p, ki->name, ki->lo, ki->hi, &x,
                               is_required ? NULL : &present) != TR_OK) {
                    return TR_ERR;
                }
                if (is_required || present) {
                    if (ki->positive && !(x > ki->lo)) {
                        char pe[PATH_MAX_LEN];
                        path_key(pe, p, ki->name);
                        return jerr(c, pe, "expected a positive number, got %g", x);
                    }
                    float f = (float)x;
                    memcpy((char *)&mat + ki->offset, &f, sizeof f);
                }
            }
        }
        tr_error e;
        uint32_t index;
        if (tr_scene_add_material(c->scene, mat, &index, &e) != TR_OK) {
            return jerr_from(c, p, &e);
        }
        if (parse_material_extras(c, m, p, index) != TR_OK) {
            return TR_ERR;
        }
    }
    qsort(c->by_name, c->name_count, sizeof *c->by_name, named_cmp);
    for (uint32_t i = 1; i < c->name_count; ++i) {
        if (strcmp(c->by_name[i].name, c->by_name[i - 1].name) == 0) {
            char p[PATH_MAX_LEN], buf[48];
            path_key(p, path, shown(c->by_name[i].name, buf, sizeof buf));
            return jerr(c, p, "duplicate material name");
        }
    }
    return TR_OK;
}

/* The index of the material named by obj[key]; -1 in *index when absent and optional. */
static int material_ref(const jctx *c, const cJSON *obj, const char *path, int required,
                        int64_t *index) {
    const char *name;
    *index = -1;
    if (get_string(c, obj, path, "material", required, &name) != TR_OK) {
        return TR_ERR;
    }
    if (!name) {
        return TR_OK;
    }
    struct named key = {name, 0};
    size_t lo = 0, hi = c->name_count;
    while (lo < hi) { /* the first entry not below (name, 0) */
        size_t mid = lo + (hi - lo) / 2;
        if (named_cmp(&c->by_name[mid], &key) < 0) {
            lo = mid + 1;
        } else {
            hi = mid;
        }
    }
    if (lo < c->name_count && strcmp(c->by_name[lo].name, name) == 0) {
        *index = c->by_name[lo].index;
        return TR_OK;
    }
    const char **names = malloc((c->name_count ? c->name_count : 1) * sizeof *names);
    size_t count = 0;
    for (uint32_t i = 0; names && i < c->name_count; ++i) {
        names[count++] = c->by_name[i].name;
    }
    char p[PATH_MAX_LEN], buf[48];
    path_key(p, path, "material");
    const char *near = names ? tr_names_closest(name, names, count) : NULL;
    int rc = jerr(c, p, "undefined material '%s'%s%s%s", shown(name, buf, sizeof buf),
                  near ? " (did you mean '" : "", near ? near : "", near ? "'?)" : "");
    free(names);
    return rc;
}

/* position, orientation (degrees) or orientation_rad, scale (number or [x, y, z]). */
static int get_transform(const jctx *c, const cJSON *obj, const char *path, tr_transform *tf) {
    tf->position = v3s(0.0f);
    tf->orientation = v3s(0.0f);
    tf->scale = v3s(1.0f);
    int deg = 0, rad = 0;
    tr_vec3 o;
    if (get_vec3(c, obj, path, "position", 0, 0, &tf->position, NULL) != TR_OK ||
        get_vec3(c, obj, path, "orientation", 0, 0, &o, &deg) != TR_OK) {
        return TR_ERR;
    }
    if (deg) {
        /* In double, so that 90 gives the float nearest pi/2. */
        const double k = 3.14159265358979323846 / 180.0;
        tf->orientation = v3((float)(o.x * k), (float)(o.y * k), (float)(o.z * k));
    }
    if (get_vec3(c, obj, path, "orientation_rad", 0, 0, &o, &rad) != TR_OK) {
        return TR_ERR;
    }
    if (deg && rad) {
        return jerr(c, path,
                    "expected one of 'orientation' (degrees) and 'orientation_rad', "
                    "got both");
    }
    if (rad) {
        tf->orientation = o;
    }
    char p[PATH_MAX_LEN];
    path_key(p, path, "scale");
    const cJSON *s = cJSON_GetObjectItemCaseSensitive(obj, "scale");
    if (cJSON_IsNumber(s)) {
        double x = s->valuedouble;
        if (!isfinite(x) || !(x > 0.0) || x > TR_SCENE_FILE_MAX_COORD) {
            return jerr(c, p, "expected a positive number up to %g, got %g",
                        TR_SCENE_FILE_MAX_COORD, x);
        }
        tf->scale = v3s((float)x);
    } else if (s && !cJSON_IsArray(s)) {
        return jerr(c, p, "expected a positive number or [x, y, z], got %s", type_name(s));
    } else if (get_vec3(c, obj, path, "scale", 0, 1, &tf->scale, NULL) != TR_OK) {
        return TR_ERR;
    }
    return TR_OK;
}

/* Triangle t, number k of what path placed, must be non-degenerate and within the
 * coordinate bound. */
static int check_triangle(const jctx *c, const char *path, const tr_triangle *t, uint32_t k) {
    const float bound = (float)TR_SCENE_FILE_MAX_COORD;
    const tr_vec3 v[3] = {t->v0, t->v1, t->v2};
    for (int j = 0; j < 3; ++j) {
        if (!v3_is_finite(v[j]) || fabsf(v[j].x) > bound || fabsf(v[j].y) > bound ||
            fabsf(v[j].z) > bound) {
            return jerr(c, path, "a vertex lands at (%g, %g, %g), outside the bound |x| <= %g",
                        (double)v[j].x, (double)v[j].y, (double)v[j].z, TR_SCENE_FILE_MAX_COORD);
        }
    }
    if (!(t->area > 0.0f)) {
        char p[PATH_MAX_LEN];
        path_key(p, path, "scale");
        return jerr(c, p, "too small: triangle %u has zero area", k);
    }
    return TR_OK;
}

/* Stored triangles first..count-1, as check_triangle. */
static int check_triangles(const jctx *c, const char *path, uint32_t first) {
    const tr_scene *s = c->scene;
    for (uint32_t i = first; i < s->triangle_count; ++i) {
        if (check_triangle(c, path, &s->triangles[i], i - first) != TR_OK) {
            return TR_ERR;
        }
    }
    return TR_OK;
}

/* What decides whether a prototype's placements can pass check_triangle without reading
 * each placed triangle: its points' box (prototype coordinates), its smallest triangle area
 * and the smallest sine of the angle at a triangle's first corner. */
typedef struct proto_shape {
    int measured;
    tr_vec3 lo, hi;
    double min_area, min_sin;
} proto_shape;

static void measure_proto(const tr_prototype *pr, proto_shape *ps) {
    ps->measured = 1;
    ps->lo = v3s(INFINITY);
    ps->hi = v3s(-INFINITY);
    for (uint32_t i = 0; i < pr->pt_count; ++i) {
        ps->lo = v3_min(ps->lo, pr->pts[i]);
        ps->hi = v3_max(ps->hi, pr->pts[i]);
    }
    ps->min_area = pr->tri_count ? INFINITY : 0.0;
    ps->min_sin = ps->min_area;
    for (uint32_t i = 0; i < pr->tri_count; ++i) {
        const tr_triangle *t = &pr->tris[i];
        const double a[3] = {(double)t->v1.x - t->v0.x, (double)t->v1.y - t->v0.y,
                             (double)t->v1.z - t->v0.z};
        const double b[3] = {(double)t->v2.x - t->v0.x, (double)t->v2.y - t->v0.y,
                             (double)t->v2.z - t->v0.z};
        const double x = a[1] * b[2] - a[2] * b[1], y = a[2] * b[0] - a[0] * b[2],
                     z = a[0] * b[1] - a[1] * b[0];
        const double cross = sqrt(x * x + y * y + z * z);
        const double la = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
        const double lb = sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
        ps->min_area = fmin(ps->min_area, 0.5 * cross);
        ps->min_sin = fmin(ps->min_sin, la > 0.0 && lb > 0.0 ? cross / (la * lb) : 0.0);
    }
}

/* Whether every triangle a placement m (3x4, rows) of a prototype measured as ps places
 * passes check_triangle, shown without placing them; 0: maybe not (then each is read).
 *   - The bound: the prototype's box, its eight corners placed, inside the bound, holds
 *     every placed vertex (an affine map keeps points inside the hull of the box's image).
 *   - The area: a parallelogram's area grows by at least the square of the map's smallest
 *     singular value, σ_min >= |det| / |M|_F² (as σ_max <= |M|_F and the product of the
 *     three is |det|), and the sine of a corner's angle by at least 1 / cond², cond² <=
 *     |M|_F² / σ_min². Far above float rounding on both counts (an area above 1e-30, a sine
 *     above 1e-5 where rounding is 1e-7), the area check_triangle computes is positive. */
static int placed_surely_valid(const proto_shape *ps, const float m[12]) {
    const double bound = TR_SCENE_FILE_MAX_COORD;
    for (int k = 0; k < 8; ++k) {
        const double p[3] = {(k & 1) ? ps->hi.x : ps->lo.x, (k & 2) ? ps->hi.y : ps->lo.y,
                             (k & 4) ? ps->hi.z : ps->lo.z};
        for (int r = 0; r < 3; ++r) {
            const double w = (double)m[4 * r] * p[0] + (double)m[4 * r + 1] * p[1] +
                             (double)m[4 * r + 2] * p[2] + (double)m[4 * r + 3];
            if (!(fabs(w) <= bound * (1.0 - 1e-6))) {
                return 0;
            }
        }
    }
    const double det = (double)m[0] * ((double)m[5] * m[10] - (double)m[6] * m[9]) -
                       (double)m[1] * ((double)m[4] * m[10] - (double)m[6] * m[8]) +
                       (double)m[2] * ((double)m[4] * m[9] - (double)m[5] * m[8]);
    double f2 = 0.0;
    for (int r = 0; r < 3; ++r) {
        for (int k = 0; k < 3; ++k) {
            f2 += (double)m[4 * r + k] * m[4 * r + k];
        }
    }
    if (!(fabs(det) > 0.0) || !(f2 > 0.0) || !isfinite(f2)) {
        return 0;
    }
    const double smin = fabs(det) / f2, cond2 = f2 / (smin * smin);
    return ps->min_area * smin * smin > 1e-30 && ps->min_sin / cond2 > 1e-5;
}

/* check_triangles for the triangles kept instance `inst` places, ids first_id on: shown
 * for all of them at once where placed_surely_valid can, else read one by one. */
static int check_placed(jctx *c, const char *path, uint32_t inst, uint32_t first_id) {
    const tr_instance *in = &c->scene->instances[inst];
    if (in->proto >= c->shape_count) {
        const uint32_t n =
            c->scene->proto_count > in->proto ? c->scene->proto_count : in->proto + 1;
        proto_shape *grown = realloc(c->shapes, (size_t)n * sizeof *grown);
        if (grown) {
            memset(grown + c->shape_count, 0, (size_t)(n - c->shape_count) * sizeof *grown);
            c->shapes = grown;
            c->shape_count = n;
        }
    }
    if (in->proto < c->shape_count) {
        proto_shape *ps = &c->shapes[in->proto];
        if (!ps->measured) {
            measure_proto(&c->scene->protos[in->proto], ps);
        }
        if (placed_surely_valid(ps, in->m)) {
            return TR_OK;
        }
    }
    const uint32_t end = tr_scene_triangle_count(c->scene);
    for (uint32_t i = first_id; i < end; ++i) {
        const tr_triangle t = tr_scene_triangle(c->scene, i);
        if (check_triangle(c, path, &t, i - first_id) != TR_OK) {
            return TR_ERR;
        }
    }
    return TR_OK;
}

/* A quad: four corners, two triangles (v0 v1 v2) and (v0 v2 v3), facing the side that
 * (v1 - v0) x (v2 - v0) points to; the shape transform applies to the corners. */
static int parse_quad(jctx *c, const cJSON *sh, const char *p, const cJSON *verts) {
    char pv[PATH_MAX_LEN], ps[PATH_MAX_LEN];
    path_key(pv, p, "vertices");
    path_key(ps, p, "subdivisions");
    if (cJSON_GetObjectItemCaseSensitive(sh, "subdivisions")) {
        return jerr(c, ps, "only icospheres have subdivisions");
    }
    if (cJSON_GetObjectItemCaseSensitive(sh, "smooth")) {
        char pm[PATH_MAX_LEN];
        path_key(pm, p, "smooth");
        return jerr(c, pm, "only icospheres have 'smooth' (meshes use their vertex normals)");
    }
    if (!verts) {
        return jerr(c, pv, "missing (expected 4 corners [[x, y, z], ...])");
    }
    if (!cJSON_IsArray(verts) || cJSON_GetArraySize(verts) != 4) {
        return jerr(c, pv, "expected an array of 4 corners [[x, y, z], ...], got %s%s",
                    type_name(verts), cJSON_IsArray(verts) ? " of another length" : "");
    }
    float pos[12];
    int k = 0;
    for (const cJSON *v = verts->child; v; v = v->next, ++k) {
        char pe[PATH_MAX_LEN];
        path_index(pe, pv, k);
        if (!cJSON_IsArray(v) || cJSON_GetArraySize(v) != 3) {
            return jerr(c, pe, "expected an array of 3 numbers [x, y, z], got %s", type_name(v));
        }
        int j = 0;
        for (const cJSON *e = v->child; e; e = e->next, ++j) {
            char pj[PATH_MAX_LEN];
            path_index(pj, pe, j);
            if (!cJSON_IsNumber(e)) {
                return jerr(c, pj, "expected a number, got %s", type_name(e));
            }
            if (!isfinite(e->valuedouble) || fabs(e->valuedouble) > TR_SCENE_FILE_MAX_COORD) {
                return jerr(c, pj, "expected a finite number with |x| <= %g, got %g",
                            TR_SCENE_FILE_MAX_COORD, e->valuedouble);
            }
            pos[3 * k + j] = (float)e->valuedouble;
        }
    }
    tr_transform tf;
    int64_t mat;
    if (get_transform(c, sh, p, &tf) != TR_OK || material_ref(c, sh, p, 1, &mat) != TR_OK) {
        return TR_ERR;
    }
    if ((uint64_t)c->scene->triangle_count + 2 > c->budget) {
        return jerr_code(c, TR_STATUS_LIMIT, p,
                         "the scene would have %llu triangles, more than the budget of %u",
                         (unsigned long long)c->scene->triangle_count + 2, c->budget);
    }
    static const uint32_t idx[6] = {0, 1, 2, 0, 2, 3};
    /* Texture coordinates only where the material has textures (vertex attributes cost
     * a fetch at every hit): the image's top-left corner at v0, top-right at v1. */
    static const float uv[8] = {0, 0, 1, 0, 1, 1, 0, 1};
    const tr_material_ext *ext =
        c->scene->material_ext_count == c->scene->material_count && c->scene->material_ext_count > 0
            ? &c->scene->material_exts[mat]
            : NULL;
    const int textured =
        ext && (ext->base_tex != TR_NO_INDEX || ext->emission_tex != TR_NO_INDEX ||
                ext->mr_tex != TR_NO_INDEX || ext->normal_tex != TR_NO_INDEX ||
                ext->transmission_tex != TR_NO_INDEX || ext->clearcoat_tex != TR_NO_INDEX ||
                ext->clearcoat_rough_tex != TR_NO_INDEX || ext->sheen_color_tex != TR_NO_INDEX ||
                ext->sheen_rough_tex != TR_NO_INDEX || ext->clearcoat_normal_tex != TR_NO_INDEX);
    uint32_t first = c->scene->triangle_count, dropped = 0;
    tr_error e;
    if (tr_scene_add_mesh_uv(c->scene, pos, 4, idx, 2, NULL, textured ? uv : NULL, (uint32_t)mat,
                             &tf, &dropped, &e) != TR_OK) {
        return jerr(c, pv, "the corners span no area");
    }
    if (dropped) {
        return jerr(c, pv, "the corners span a triangle of zero area");
    }
    return check_triangles(c, p, first);
}

static int parse_shapes(jctx *c, const cJSON *shapes) {
    static const char *const keys[] = {
        "type",  "name",         "position", "orientation", "orientation_rad",
        "scale", "subdivisions", "material", "vertices",    "smooth"};
    static const char *const types[] = {"plane", "box", "icosphere", "quad"};
    if (!cJSON_IsArray(shapes)) {
        return jerr(c, "shapes", "expected an array, got %s", type_name(shapes));
    }
    /* The budget first, from the types and subdivisions alone, so that a file asking for
     * too much fails before anything big is generated. */
    uint64_t total = c->scene->triangle_count;
    int i = 0;
    for (const cJSON *sh = shapes->child; sh; sh = sh->next, ++i) {
        const cJSON *ty = cJSON_GetObjectItemCaseSensitive(sh, "type");
        const cJSON *sub = cJSON_GetObjectItemCaseSensitive(sh, "subdivisions");
        if (!cJSON_IsString(ty) || !ty->valuestring) {
            continue;
        }
        if (strcmp(ty->valuestring, "icosphere") == 0) {
            double n = cJSON_IsNumber(sub) ? sub->valuedouble : 2.0;
            if (!(n >= 0.0 && n <= TR_ICOSPHERE_MAX_SUBDIVISIONS) || n != floor(n)) {
                continue; /* reported below */
            }
            total += 20ull << (2u * (unsigned)n);
        } else {
            total += 12; /* at most (a box) */
        }
        if (total > c->budget) {
            char p[PATH_MAX_LEN];
            path_index(p, "shapes", i);
            return jerr_code(c, TR_STATUS_LIMIT, p,
                             "the scene would have more than %u triangles (the triangle budget; "
                             "an icosphere has 20*4^subdivisions)",
                             c->budget);
        }
    }
    i = 0;
    for (const cJSON *sh = shapes->child; sh; sh = sh->next, ++i) {
        char p[PATH_MAX_LEN];
        path_index(p, "shapes", i);
        if (expect_object(c, sh, p) != TR_OK ||
            check_keys(c, sh, p, keys, sizeof keys / sizeof keys[0]) != TR_OK) {
            return TR_ERR;
        }
        const char *type, *name;
        if (get_string(c, sh, p, "type", 1, &type) != TR_OK ||
            get_string(c, sh, p, "name", 0, &name) != TR_OK) {
            return TR_ERR;
        }
        int t = -1;
        for (int k = 0; k < 4; ++k) {
            if (strcmp(type, types[k]) == 0) {
                t = k;
            }
        }
        if (t < 0) {
            char pt[PATH_MAX_LEN], buf[40];
            path_key(pt, p, "type");
            const char *near = tr_names_closest(type, types, 4);
            return jerr(c, pt, "unknown shape type '%s' (%s%s%s)", shown(type, buf, sizeof buf),
                        near ? "did you mean '" : "expected plane, box, icosphere or quad",
                        near ? near : "", near ? "'?" : "");
        }
        const cJSON *verts = cJSON_GetObjectItemCaseSensitive(sh, "vertices");
        if (t == 3) {
            if (parse_quad(c, sh, p, verts) != TR_OK) {
                return TR_ERR;
            }
            continue;
        }
        if (verts) {
            char pv[PATH_MAX_LEN];
            path_key(pv, p, "vertices");
            return jerr(c, pv, "only quads have vertices");
        }
        tr_shape_desc d = tr_shape_desc_default(t == 0   ? TR_SHAPE_PLANE
                                                : t == 1 ? TR_SHAPE_BOX
                                                         : TR_SHAPE_ICOSPHERE);
        int64_t mat;
        if (get_transform(c, sh, p, &d.transform) != TR_OK ||
            material_ref(c, sh, p, 1, &mat) != TR_OK) {
            return TR_ERR;
        }
        d.material = (uint32_t)mat;
        double sub = 2;
        int has_sub = 0;
        char ps[PATH_MAX_LEN];
        path_key(ps, p, "subdivisions");
        /* Every number outside the range gets the range that holds: 0..9, not get_integer's
         * own bounds. */
        const cJSON *sv = cJSON_GetObjectItemCaseSensitive(sh, "subdivisions");
        if (sv && t != 2) {
            return jerr(c, ps, "only icospheres have subdivisions");
        }
        if (cJSON_IsNumber(sv) &&
            !(sv->valuedouble >= 0.0 && sv->valuedouble <= TR_ICOSPHERE_MAX_SUBDIVISIONS &&
              sv->valuedouble == floor(sv->valuedouble))) {
            return jerr(c, ps, "expected an integer in 0..%d (20*4^N triangles), got %g",
                        TR_ICOSPHERE_MAX_SUBDIVISIONS, sv->valuedouble);
        }
        if (get_integer(c, sh, p, "subdivisions", 0, TR_ICOSPHERE_MAX_SUBDIVISIONS, &sub,
                        &has_sub) != TR_OK) {
            return TR_ERR;
        }
        d.subdivisions = (uint32_t)sub;
        int smooth = 0;
        if (get_bool(c, sh, p, "smooth", &smooth) != TR_OK) {
            return TR_ERR;
        }
        if (cJSON_GetObjectItemCaseSensitive(sh, "smooth") && t != 2) {
            char pm[PATH_MAX_LEN];
            path_key(pm, p, "smooth");
            return jerr(c, pm, "only icospheres have 'smooth' (meshes use their vertex normals)");
        }
        if (smooth) {
            d.type = TR_SHAPE_ICOSPHERE_SMOOTH;
        }
        uint64_t n = tr_shape_triangle_count(&d);
        if ((uint64_t)c->scene->triangle_count + n > c->budget) {
            return jerr_code(c, TR_STATUS_LIMIT, t == 2 ? ps : p,
                             "the scene would have %llu triangles, more than the budget of %u",
                             (unsigned long long)(c->scene->triangle_count + n), c->budget);
        }
        uint32_t first = c->scene->triangle_count;
        tr_error e;
        if (tr_scene_add_shape(c->scene, &d, &e) != TR_OK) {
            return jerr_from(c, p, &e);
        }
        if (check_triangles(c, p, first) != TR_OK) {
            return TR_ERR;
        }
    }
    c->info->shape_count = (uint32_t)i;
    return TR_OK;
}

/* Warnings from a mesh import (dropped or approximated material properties). */
struct mesh_warn_ctx {
    const jctx *c;
    int index;
    const char *rel;
};

static void mesh_import_warn(void *ctx, const char *message) {
    const struct mesh_warn_ctx *w = ctx;
    char buf[64];
    warn(w->c, "meshes[%d] (%s): %s", w->index, shown(w->rel, buf, sizeof buf), message);
}

static int parse_meshes(jctx *c, const cJSON *meshes) {
    static const char *const keys[] = {
        "path", "name", "position", "orientation", "scale", "orientation_rad", "material"};
    if (!cJSON_IsArray(meshes)) {
        return jerr(c, "meshes", "expected an array, got %s", type_name(meshes));
    }
    int i = 0;
    for (const cJSON *m = meshes->child; m; m = m->next, ++i) {
        char p[PATH_MAX_LEN];
        path_index(p, "meshes", i);
        if (expect_object(c, m, p) != TR_OK ||
            check_keys(c, m, p, keys, sizeof keys / sizeof keys[0]) != TR_OK) {
            return TR_ERR;
        }
        const char *rel, *name;
        tr_transform tf;
        int64_t mat;
        if (get_string(c, m, p, "path", 1, &rel) != TR_OK ||
            get_string(c, m, p, "name", 0, &name) != TR_OK ||
            get_transform(c, m, p, &tf) != TR_OK || material_ref(c, m, p, 0, &mat) != TR_OK) {
            return TR_ERR;
        }
        char pp[PATH_MAX_LEN];
        path_key(pp, p, "path");
        if (!rel[0]) {
            return jerr(c, pp, "expected a file name, got an empty string");
        }
        if (!c->opt->load_meshes) {
            continue;
        }
        char full[8192];
        if (rel[0] == '/' || !c->dir[0]) {
            snprintf(full, sizeof full, "%s", rel);
        } else {
            snprintf(full, sizeof full, "%s/%s", c->dir, rel);
        }
        uint32_t first = c->scene->triangle_count;
        /* The import reads a budget of 0 as "no limit": a full budget must stop here. */
        if (first >= c->budget) {
            return jerr_code(c, TR_STATUS_LIMIT, pp,
                             "the scene already has %u triangles, the whole triangle budget",
                             first);
        }
        tr_mesh_import_stats st;
        tr_error e;
        struct mesh_warn_ctx wc = {c, i, rel};
        if (tr_scene_import_mesh_ex(c->scene, full, &tf, mat, c->budget - first, &st,
                                    mesh_import_warn, &wc, NULL, &e) != TR_OK) {
            return jerr_from(c, pp, &e);
        }
        c->info->mesh_parts += st.parts;
        c->info->mesh_triangles += st.triangles;
        c->info->degenerate_dropped += st.degenerate;
        if (check_triangles(c, p, first) != TR_OK) {
            return TR_ERR;
        }
        if (st.degenerate) {
            char buf[64];
            warn(c, "meshes[%d] (%s): %u degenerate faces dropped (points, lines or zero area)", i,
                 shown(rel, buf, sizeof buf), st.degenerate);
        }
    }
    c->info->mesh_count = (uint32_t)i;
    return TR_OK;
}

/* ---- Prototypes and instances --------------------------------------------------- */

static int parse_instances(jctx *c, const cJSON *list, int copies);

/* Parses member k of "prototypes" (its shapes, meshes and nested instances, which are
 * placed as plain copies) into a prototype. A prototype met again while being parsed is a
 * cycle: refused, naming the reference (`ref`, a path) that closed it. */
static int parse_prototype(jctx *c, int k, const char *ref) {
    static const char *const keys[] = {"description", "shapes", "meshes", "instances"};
    const cJSON *node = c->protos->child;
    for (int i = 0; i < k; ++i) {
        node = node->next;
    }
    char buf[48];
    if (c->proto_state[k] == 1) {
        return jerr(c, ref, "prototype '%s' contains itself (a cycle of prototypes)",
                    shown(node->string, buf, sizeof buf));
    }
    char p[PATH_MAX_LEN];
    path_key(p, "prototypes", node->string);
    if (expect_object(c, node, p) != TR_OK ||
        check_keys(c, node, p, keys, sizeof keys / sizeof keys[0]) != TR_OK) {
        return TR_ERR;
    }
    const char *saved_prefix = c->prefix;
    char prefix[PATH_MAX_LEN + 1];
    snprintf(prefix, sizeof prefix, "%s%s.", saved_prefix ? saved_prefix : "", p);
    const uint32_t saved_shapes = c->info->shape_count, saved_meshes = c->info->mesh_count;
    const uint32_t first_shape = c->scene->shape_count;
    c->proto_state[k] = 1;
    c->prefix = prefix;
    const cJSON *shapes = cJSON_GetObjectItemCaseSensitive(node, "shapes");
    const cJSON *meshes = cJSON_GetObjectItemCaseSensitive(node, "meshes");
    const cJSON *inst = cJSON_GetObjectItemCaseSensitive(node, "instances");
    int rc = TR_OK;
    if (shapes && parse_shapes(c, shapes) != TR_OK) {
        rc = TR_ERR;
    } else if (meshes && parse_meshes(c, meshes) != TR_OK) {
        rc = TR_ERR;
    } else if (inst && parse_instances(c, inst, 1) != TR_OK) {
        rc = TR_ERR;
    }
    c->prefix = saved_prefix;
    c->info->shape_count = saved_shapes;
    c->info->mesh_count = saved_meshes;
    if (rc != TR_OK) {
        return TR_ERR;
    }
    c->proto_index[k] = UINT32_MAX;
    if (c->scene->shape_count == first_shape) {
        if (c->opt->load_meshes || !meshes) {
            return jerr(c, p, "expected 'shapes', 'meshes' or 'instances' with triangles");
        }
    } else {
        tr_error e;
        if (tr_scene_make_prototype(c->scene, first_shape, &c->proto_index[k], &e) != TR_OK) {
            return jerr_from(c, p, &e);
        }
    }
    c->proto_state[k] = 2;
    return TR_OK;
}

/* The prototype named obj.prototype (parsed on first use); UINT32_MAX in *proto for an
 * empty one (meshes not loaded). */
static int prototype_ref(jctx *c, const cJSON *obj, const char *path, uint32_t *proto) {
    const char *name;
    if (get_string(c, obj, path, "prototype", 1, &name) != TR_OK) {
        return TR_ERR;
    }
    char p[PATH_MAX_LEN], buf[48];
    path_key(p, path, "prototype");
    int k = 0, n = 0;
    for (const cJSON *m = c->protos ? c->protos->child : NULL; m; m = m->next, ++n) {
        if (strcmp(m->string, name) == 0) {
            if (c->proto_state[n] != 2 && parse_prototype(c, n, p) != TR_OK) {
                return TR_ERR;
            }
            *proto = c->proto_index[n];
            return TR_OK;
        }
    }
    const char **names = malloc((size_t)(n ? n : 1) * sizeof *names);
    for (const cJSON *m = c->protos ? c->protos->child : NULL; names && m; m = m->next) {
        names[k++] = m->string;
    }
    const char *near = names ? tr_names_closest(name, names, (size_t)k) : NULL;
    int rc = jerr(c, p, "undefined prototype '%s'%s%s%s", shown(name, buf, sizeof buf),
                  near ? " (did you mean '" : "", near ? near : "", near ? "'?)" : "");
    free(names);
    return rc;
}

/* A list of placements: instances, or (copies set: inside a prototype) plain copies. Each
 * is a prototype and either "matrix" (12 numbers, rows of a 3x4 affine matrix) or
 * position / orientation / scale as for shapes. */
static int parse_instances(jctx *c, const cJSON *list, int copies) {
    static const char *const keys[] = {"prototype",       "name",  "position", "orientation",
                                       "orientation_rad", "scale", "matrix"};
    if (!cJSON_IsArray(list)) {
        return jerr(c, "instances", "expected an array, got %s", type_name(list));
    }
    int i = 0;
    for (const cJSON *it = list->child; it; it = it->next, ++i) {
        char p[PATH_MAX_LEN];
        path_index(p, "instances", i);
        if (expect_object(c, it, p) != TR_OK ||
            check_keys(c, it, p, keys, sizeof keys / sizeof keys[0]) != TR_OK) {
            return TR_ERR;
        }
        const char *name;
        uint32_t proto = UINT32_MAX;
        if (get_string(c, it, p, "name", 0, &name) != TR_OK ||
            prototype_ref(c, it, p, &proto) != TR_OK) {
            return TR_ERR;
        }
        float m[12];
        char pm[PATH_MAX_LEN];
        path_key(pm, p, "matrix");
        const cJSON *mat = cJSON_GetObjectItemCaseSensitive(it, "matrix");
        if (mat) {
            if (cJSON_GetObjectItemCaseSensitive(it, "position") ||
                cJSON_GetObjectItemCaseSensitive(it, "orientation") ||
                cJSON_GetObjectItemCaseSensitive(it, "orientation_rad") ||
                cJSON_GetObjectItemCaseSensitive(it, "scale")) {
                return jerr(c, pm, "expected either 'matrix' or position/orientation/scale");
            }
            int n = 0;
            for (const cJSON *v = cJSON_IsArray(mat) ? mat->child : NULL; v; v = v->next, ++n) {
                if (n >= 12 || !cJSON_IsNumber(v) ||
                    !(fabs(v->valuedouble) <= TR_SCENE_FILE_MAX_COORD)) {
                    n = -1;
                    break;
                }
                m[n] = (float)v->valuedouble;
            }
            if (n != 12) {
                return jerr(c, pm,
                            "expected 12 numbers of magnitude up to %g (the rows of a 3x4 matrix)",
                            TR_SCENE_FILE_MAX_COORD);
            }
        } else {
            tr_transform tf;
            if (get_transform(c, it, p, &tf) != TR_OK) {
                return TR_ERR;
            }
            tr_transform_matrix(&tf, m);
        }
        if (proto == UINT32_MAX) {
            continue; /* meshes not loaded */
        }
        const uint64_t n = tr_scene_prototype_triangle_count(c->scene, proto);
        /* A kept instance (tr_scene_add_instance without an emitting prototype) stores
         * nothing per triangle: its triangles count against the id space's limit there,
         * not against the budget of stored ones. */
        const int kept = !copies && !c->scene->protos[proto].emissive;
        if (!kept && (uint64_t)c->scene->triangle_count + n > c->budget) {
            return jerr_code(c, TR_STATUS_LIMIT, p,
                             "the scene would have %llu triangles, more than the budget of %u "
                             "(instances of a prototype with an emitter store every triangle they "
                             "place)",
                             (unsigned long long)(c->scene->triangle_count + n), c->budget);
        }
        tr_error e;
        const uint32_t first = c->scene->triangle_count;
        const uint32_t first_id = tr_scene_triangle_count(c->scene);
        int rc = copies ? tr_scene_add_prototype_copy(c->scene, proto, m, &e)
                        : tr_scene_add_instance(c->scene, proto, m, NULL, &e);
        if (rc != TR_OK) {
            return jerr_from(c, mat ? pm : p, &e);
        }
        if (c->scene->triangle_count == first) {
            /* Kept: its placed triangles pass the same checks. */
            if (check_placed(c, p, c->scene->instance_count - 1, first_id) != TR_OK) {
                return TR_ERR;
            }
        } else if (check_triangles(c, p, first) != TR_OK) {
            return TR_ERR;
        }
    }
    return TR_OK;
}

static int parse_placements(jctx *c, const cJSON *root) {
    c->protos = cJSON_GetObjectItemCaseSensitive(root, "prototypes");
    const cJSON *inst = cJSON_GetObjectItemCaseSensitive(root, "instances");
    if (c->protos && !cJSON_IsObject(c->protos)) {
        return jerr(c, "prototypes", "expected an object of named prototypes, got %s",
                    type_name(c->protos));
    }
    const int n = cJSON_GetArraySize(c->protos);
    c->proto_state = calloc((size_t)(n ? n : 1), 1);
    c->proto_index = calloc((size_t)(n ? n : 1), sizeof *c->proto_index);
    int rc = TR_OK;
    if (!c->proto_state || !c->proto_index) {
        rc = jerr_code(c, TR_STATUS_OUT_OF_MEMORY, NULL, "out of memory");
    }
    if (rc == TR_OK && inst) {
        rc = parse_instances(c, inst, 0);
    }
    /* Prototypes no instance names are still checked. */
    int k = 0;
    for (const cJSON *m = c->protos ? c->protos->child : NULL; rc == TR_OK && m; m = m->next, ++k) {
        if (c->proto_state[k] == 0) {
            rc = parse_prototype(c, k, NULL);
            char buf[48];
            if (rc == TR_OK) {
                warn(c, "prototypes.%s is not placed by any instance",
                     shown(m->string, buf, sizeof buf));
            }
        }
    }
    free(c->proto_state);
    free(c->proto_index);
    free(c->shapes);
    c->proto_state = NULL;
    c->proto_index = NULL;
    c->shapes = NULL;
    c->shape_count = 0;
    return rc;
}

/* An upper bound of the values cJSON would create for `text`: each value but the first
 * follows a ',', '[' or '{' outside a string (an object's member is one value). */
static uint64_t count_json_values(const char *text, size_t len) {
    uint64_t n = 1;
    int in_string = 0;
    for (size_t i = 0; i < len; ++i) {
        const char ch = text[i];
        if (in_string) {
            if (ch == '\\') {
                ++i;
            } else if (ch == '"') {
                in_string = 0;
            }
        } else if (ch == '"') {
            in_string = 1;
        } else if (ch == ',' || ch == '[' || ch == '{') {
            ++n;
        }
    }
    return n;
}

/* cJSON reports a failed allocation as a syntax error at the spot it reached. Its
 * allocator is wrapped (once, for the process; it still calls malloc and free, so nodes
 * from before or from other users of cJSON are unaffected) to tell the two apart. */
static _Thread_local int json_oom;
static pthread_once_t json_hooks_once = PTHREAD_ONCE_INIT;

static void *json_malloc(size_t n) {
    void *p = malloc(n);
    if (!p) {
        json_oom = 1;
    }
    return p;
}

static void json_install_hooks(void) {
    cJSON_Hooks hooks = {json_malloc, free};
    cJSON_InitHooks(&hooks);
}

/* "environment": {"color": [r, g, b], "map": "sky.hdr", "strength": s, "rotation": deg}:
 * a light from every direction that leaves the scene. */
static int parse_environment(jctx *c, const cJSON *env) {
    static const char *const keys[] = {"color", "map", "strength", "rotation"};
    const char *path = "environment";
    if (expect_object(c, env, path) != TR_OK ||
        check_keys(c, env, path, keys, sizeof keys / sizeof keys[0]) != TR_OK) {
        return TR_ERR;
    }
    tr_vec3 color = v3s(1.0f);
    int has_color = 0, has_strength = 0, has_rot = 0;
    double strength = 1.0, rot = 0.0;
    const char *map = NULL;
    if (get_vec3(c, env, path, "color", 0, 0, &color, &has_color) != TR_OK ||
        get_number(c, env, path, "strength", 0.0, 1e7, &strength, &has_strength) != TR_OK ||
        get_number(c, env, path, "rotation", -360.0, 360.0, &rot, &has_rot) != TR_OK ||
        get_string(c, env, path, "map", 0, &map) != TR_OK) {
        return TR_ERR;
    }
    if (color.x < 0.0f || color.y < 0.0f || color.z < 0.0f || color.x > 1e7f || color.y > 1e7f ||
        color.z > 1e7f) {
        return jerr(c, "environment.color", "expected three numbers in [0, 1e+07]");
    }
    if (!has_color && !map) {
        return jerr(c, path, "expected 'color' or 'map'");
    }
    const float rad = (float)(rot * 3.14159265358979323846 / 180.0);
    tr_error e;
    if (map && c->opt->load_meshes) {
        if (!map[0]) {
            return jerr(c, "environment.map", "expected a file name, got an empty string");
        }
        char full[8192];
        if (map[0] == '/' || !c->dir[0]) {
            snprintf(full, sizeof full, "%s", map);
        } else {
            snprintf(full, sizeof full, "%s/%s", c->dir, map);
        }
        if (tr_scene_load_environment(c->scene, full, color, (float)strength, rad, &e) != TR_OK) {
            return jerr_from(c, "environment.map", &e);
        }
    } else if (tr_scene_set_environment(c->scene, color, (float)strength, rad, NULL, 0, 0, &e) !=
               TR_OK) {
        return jerr_from(c, path, &e);
    }
    /* A light: the scene needs no emitter. */
    c->info->allow_no_emitter = 1;
    return TR_OK;
}

/* "sun": {"direction": [x, y, z], "angle": degrees, "irradiance": E or [r, g, b]}: a
 * distant disc (src/kernel/sun.h) towards `direction`, of angular diameter `angle`
 * (default 0.526, the Sun's), giving irradiance E in W/m^2 on a surface facing it. */
static int parse_sun(jctx *c, const cJSON *sun) {
    static const char *const keys[] = {"direction", "angle", "irradiance"};
    const char *path = "sun";
    if (expect_object(c, sun, path) != TR_OK ||
        check_keys(c, sun, path, keys, sizeof keys / sizeof keys[0]) != TR_OK) {
        return TR_ERR;
    }
    tr_vec3 dir, e = v3s(1.0f);
    double ev = 1.0;
    float angle = 0.526f; /* optional: the Sun's */
    int has_angle = 0;
    if (get_vec3(c, sun, path, "direction", 1, 0, &dir, NULL) != TR_OK ||
        get_float(c, sun, path, "angle", TR_SUN_MIN_ANGLE, TR_SUN_MAX_ANGLE, &angle, &has_angle) !=
            TR_OK) {
        return TR_ERR;
    }
    if (!(v3_length(dir) > 0.0f)) {
        return jerr(c, "sun.direction", "expected a non-zero vector, got [0, 0, 0]");
    }
    const cJSON *irr = cJSON_GetObjectItemCaseSensitive(sun, "irradiance");
    if (irr && cJSON_IsNumber(irr)) {
        if (get_number(c, sun, path, "irradiance", 0.0, 1e7, &ev, NULL) != TR_OK) {
            return TR_ERR;
        }
        e = v3s((float)ev);
    } else if (irr) {
        if (get_vec3(c, sun, path, "irradiance", 1, 0, &e, NULL) != TR_OK) {
            return TR_ERR;
        }
        if (e.x < 0.0f || e.y < 0.0f || e.z < 0.0f || e.x > 1e7f || e.y > 1e7f || e.z > 1e7f) {
            return jerr(c, "sun.irradiance", "expected a number or three numbers in [0, 1e+07]");
        }
    }
    tr_error err;
    if (tr_scene_set_sun(c->scene, dir, angle, e, &err) != TR_OK) {
        return jerr_from(c, path, &err);
    }
    c->info->allow_no_emitter = 1; /* a light: the scene needs no emitter */
    return TR_OK;
}

/* "lights": [{"type": "point" | "spot" | "directional", ...}]: punctual lights
 * (src/kernel/punctual.h). Point and spot: position, intensity I (W/sr) times color; a
 * spot's direction (the axis it shines along), cone_angle (the whole angle, degrees) and
 * blend (the share of the cone's half-angle, from its edge, over which it fades in).
 * Directional: direction (the way the light travels), irradiance E (W/m^2) times color. */
static int parse_lights(jctx *c, const cJSON *lights) {
    static const char *const point_keys[] = {"type", "name", "position", "color", "intensity"};
    static const char *const spot_keys[] = {"type",      "name",      "position",   "color",
                                            "intensity", "direction", "cone_angle", "blend"};
    static const char *const dir_keys[] = {"type", "name", "direction", "color", "irradiance"};
    if (!cJSON_IsArray(lights)) {
        return jerr(c, "lights", "expected an array, got %s", type_name(lights));
    }
    int i = 0;
    for (const cJSON *l = lights->child; l; l = l->next, ++i) {
        char path[PATH_MAX_LEN], p[PATH_MAX_LEN];
        path_index(path, "lights", i);
        const char *type;
        if (expect_object(c, l, path) != TR_OK ||
            get_string(c, l, path, "type", 1, &type) != TR_OK) {
            return TR_ERR;
        }
        tr_punctual pl;
        memset(&pl, 0, sizeof pl);
        const char *const *keys;
        size_t nkeys;
        if (strcmp(type, "point") == 0) {
            pl.type = TR_PUNCTUAL_POINT;
            keys = point_keys;
            nkeys = sizeof point_keys / sizeof point_keys[0];
        } else if (strcmp(type, "spot") == 0) {
            pl.type = TR_PUNCTUAL_SPOT;
            keys = spot_keys;
            nkeys = sizeof spot_keys / sizeof spot_keys[0];
        } else if (strcmp(type, "directional") == 0) {
            pl.type = TR_PUNCTUAL_DIRECTIONAL;
            keys = dir_keys;
            nkeys = sizeof dir_keys / sizeof dir_keys[0];
        } else {
            char buf[40];
            path_key(p, path, "type");
            return jerr(c, p, "unknown light type '%s' (expected point, spot or directional)",
                        shown(type, buf, sizeof buf));
        }
        const char *name;
        if (check_keys(c, l, path, keys, nkeys) != TR_OK ||
            get_string(c, l, path, "name", 0, &name) != TR_OK) {
            return TR_ERR;
        }
        tr_vec3 color = v3s(1.0f);
        if (cJSON_GetObjectItemCaseSensitive(l, "color") &&
            get_color(c, l, path, "color", 1e7, &color) != TR_OK) {
            return TR_ERR;
        }
        double k = 1.0;
        if (pl.type == TR_PUNCTUAL_DIRECTIONAL) {
            if (get_vec3(c, l, path, "direction", 1, 0, &pl.dir, NULL) != TR_OK ||
                get_number(c, l, path, "irradiance", 0.0, 1e7, &k, &(int){0}) != TR_OK) {
                return TR_ERR;
            }
        } else {
            if (get_vec3(c, l, path, "position", 1, 0, &pl.pos, NULL) != TR_OK ||
                get_number(c, l, path, "intensity", 0.0, 1e7, &k, &(int){0}) != TR_OK) {
                return TR_ERR;
            }
        }
        if (pl.type == TR_PUNCTUAL_SPOT) {
            double cone = 45.0, blend = 0.15;
            if (get_vec3(c, l, path, "direction", 1, 0, &pl.dir, NULL) != TR_OK ||
                get_number(c, l, path, "cone_angle", 1e-3, 180.0, &cone, &(int){0}) != TR_OK ||
                get_number(c, l, path, "blend", 0.0, 1.0, &blend, &(int){0}) != TR_OK) {
                return TR_ERR;
            }
            /* The cone's half-angle h; the fade from its edge inwards over blend * h. */
            const double h = 0.5 * cone * 3.14159265358979323846 / 180.0;
            pl.cos_outer = (float)cos(h);
            pl.cos_inner = (float)cos(h * (1.0 - blend));
        }
        if (pl.type != TR_PUNCTUAL_POINT && !(v3_length(pl.dir) > 0.0f)) {
            path_key(p, path, "direction");
            return jerr(c, p, "expected a non-zero vector, got [0, 0, 0]");
        }
        pl.intensity = v3_scale(color, (float)k);
        tr_error err;
        if (tr_scene_add_punctual(c->scene, &pl, &err) != TR_OK) {
            return jerr_from(c, path, &err);
        }
    }
    if (i > 0) {
        c->info->allow_no_emitter = 1; /* lights: the scene needs no emitter */
    }
    return TR_OK;
}

/* Line and column (both from 1) of byte offset `off` in text. */
static void line_col(const char *text, size_t off, unsigned *line, unsigned *col) {
    *line = 1;
    *col = 1;
    for (size_t i = 0; i < off; ++i) {
        if (text[i] == '\n') {
            ++*line;
            *col = 1;
        } else {
            ++*col;
        }
    }
}

static int build(jctx *c, const cJSON *root) {
    static const char *const keys[] = {"version",   "description", "render",     "camera",
                                       "materials", "shapes",      "meshes",     "environment",
                                       "sun",       "lights",      "prototypes", "instances"};
    if (!cJSON_IsObject(root)) {
        return jerr(c, NULL, "expected a JSON object at the top level, got %s", type_name(root));
    }
    if (check_keys(c, root, "", keys, sizeof keys / sizeof keys[0]) != TR_OK) {
        return TR_ERR;
    }
    const cJSON *ver = cJSON_GetObjectItemCaseSensitive(root, "version");
    if (ver && !(cJSON_IsNumber(ver) && ver->valuedouble == 1.0)) {
        return jerr(c, "version", "expected 1 (the only version of the format)");
    }
    const char *desc;
    if (get_string(c, root, "", "description", 0, &desc) != TR_OK) {
        return TR_ERR;
    }
    const cJSON *r = cJSON_GetObjectItemCaseSensitive(root, "render");
    if (r && parse_render(c, r) != TR_OK) {
        return TR_ERR;
    }
    const cJSON *cam = cJSON_GetObjectItemCaseSensitive(root, "camera");
    if (!cam) {
        return jerr(c, "camera", "missing (expected an object)");
    }
    if (parse_camera(c, cam) != TR_OK) {
        return TR_ERR;
    }
    c->materials = cJSON_GetObjectItemCaseSensitive(root, "materials");
    if (!c->materials) {
        return jerr(c, "materials", "missing (expected an object of named materials)");
    }
    if (parse_materials(c, c->materials) != TR_OK) {
        return TR_ERR;
    }
    const cJSON *shapes = cJSON_GetObjectItemCaseSensitive(root, "shapes");
    if (shapes && parse_shapes(c, shapes) != TR_OK) {
        return TR_ERR;
    }
    const cJSON *meshes = cJSON_GetObjectItemCaseSensitive(root, "meshes");
    if (meshes && parse_meshes(c, meshes) != TR_OK) {
        return TR_ERR;
    }
    if (parse_placements(c, root) != TR_OK) {
        return TR_ERR;
    }
    const cJSON *env = cJSON_GetObjectItemCaseSensitive(root, "environment");
    if (env && parse_environment(c, env) != TR_OK) {
        return TR_ERR;
    }
    const cJSON *sun = cJSON_GetObjectItemCaseSensitive(root, "sun");
    if (sun && parse_sun(c, sun) != TR_OK) {
        return TR_ERR;
    }
    const cJSON *lights = cJSON_GetObjectItemCaseSensitive(root, "lights");
    if (lights && parse_lights(c, lights) != TR_OK) {
        return TR_ERR;
    }
    tr_scene *s = c->scene;
    tr_scene_file *in = c->info;
    /* Placed triangles count: a scene may be made of kept instances alone. */
    if (tr_scene_triangle_count(s) == 0 && (c->opt->load_meshes || in->mesh_count == 0)) {
        return jerr(c, NULL, "the scene has no triangles (expected 'shapes' or 'meshes')");
    }
    /* Counts, bounds and warnings. */
    uint32_t *used = calloc(s->material_count ? s->material_count : 1, sizeof *used);
    if (!used) {
        return jerr_code(c, TR_STATUS_OUT_OF_MEMORY, NULL, "out of memory");
    }
    for (uint32_t i = 0; i < s->triangle_count; ++i) {
        used[s->triangles[i].material]++;
    }
    /* A kept instance's triangles are its prototype's, placed: counted per prototype. */
    uint32_t *placements = calloc(s->proto_count ? s->proto_count : 1, sizeof *placements);
    if (!placements) {
        free(used);
        return jerr_code(c, TR_STATUS_OUT_OF_MEMORY, NULL, "out of memory");
    }
    for (uint32_t i = 0; i < s->instance_count; ++i) {
        placements[s->instances[i].proto] += !s->instances[i].flat;
    }
    for (uint32_t p = 0; p < s->proto_count; ++p) {
        for (uint32_t k = 0; placements[p] && k < s->protos[p].tri_count; ++k) {
            used[s->protos[p].tris[k].material] += placements[p];
        }
    }
    free(placements);
    in->bounds = tr_scene_all_bounds(s);
    uint32_t mi = 0;
    for (const cJSON *m = c->materials->child; m && mi < s->material_count; m = m->next, ++mi) {
        char buf[48];
        if (!used[mi]) {
            warn(c, "materials.%s is not used by any shape or mesh",
                 shown(m->string, buf, sizeof buf));
        }
    }
    for (uint32_t i = 0; i < s->material_count; ++i) {
        /* A black emitter (colour or emittance 0) lights nothing: it does not count. */
        const tr_material *em = &s->materials[i];
        const float peak = fmaxf(em->color.x, fmaxf(em->color.y, em->color.z));
        if (em->type == TR_MATERIAL_EMITTER && used[i] && peak > 0.0f && em->emittance > 0.0f) {
            in->emitter_materials++;
            in->emissive_triangles += used[i];
        }
    }
    free(used);
    if (in->emissive_triangles == 0 && s->env_count == 0 && s->sun_count == 0 &&
        s->punctual_count == 0) {
        warn(c, "the scene has no emitter, so its image would be black%s",
             in->allow_no_emitter ? " (allowed by render.allow_no_emitter)" : "");
    }
    return TR_OK;
}

int tr_scene_file_parse(tr_scene *s, const char *path, const char *text, size_t len,
                        const tr_scene_file_options *opt, tr_scene_file *info, tr_error *err) {
    tr_scene_clear(s); /* the previous content goes; the generation counts on */
    tr_scene_file local;
    if (!info) {
        info = &local;
    }
    memset(info, 0, sizeof *info);
    info->width = 800;
    info->height = 600;
    info->spp = 16;
    info->max_depth = 0; /* TR_MAX_DEPTH_DEFAULT: the integrator's default */
    info->accel = TR_ACCEL_TYPE_BVH;
    tr_scene_file_options defaults = {1, 0};
    jctx c;
    memset(&c, 0, sizeof c);
    c.file = path;
    c.err = err;
    c.scene = s;
    c.info = info;
    c.opt = opt ? opt : &defaults;
    c.budget = c.opt->max_triangles ? c.opt->max_triangles : TR_SCENE_FILE_MAX_TRIANGLES;
    const char *slash = strrchr(path, '/');
    if (slash) {
        size_t n = (size_t)(slash - path);
        if (n == 0) {
            n = 1; /* "/scene.json" */
        }
        if (n >= sizeof c.dir) {
            return jerr_code(&c, TR_STATUS_INVALID_ARGUMENT, NULL, "path too long");
        }
        memcpy(c.dir, path, n);
        c.dir[n] = '\0';
    }
    if (len > TR_SCENE_FILE_MAX_BYTES) {
        return jerr_code(&c, TR_STATUS_LIMIT, NULL, "%zu bytes is more than the limit of %u", len,
                         TR_SCENE_FILE_MAX_BYTES);
    }
    for (size_t i = 0; i < len; ++i) {
        if (text[i] == '\0') {
            unsigned line, col;
            line_col(text, i, &line, &col);
            return tr_error_set(err, TR_STATUS_PARSE, "%.200s:%u:%u: JSON syntax error: a NUL byte",
                                path, line, col);
        }
    }
    /* cJSON spends a node (about 80 bytes with malloc's overhead) on every value: a 64 MiB
     * file of "[0,0,0,..." would cost 2.7 GB. Values are counted first, and a file with
     * more than the limit is refused before cJSON allocates. */
    const uint64_t values = count_json_values(text, len);
    if (values > TR_SCENE_FILE_MAX_VALUES) {
        return jerr_code(&c, TR_STATUS_LIMIT, NULL,
                         "%llu JSON values is more than the limit of %u (about %u MiB in memory)",
                         (unsigned long long)values, TR_SCENE_FILE_MAX_VALUES,
                         (unsigned)(((uint64_t)TR_SCENE_FILE_MAX_VALUES * 80u) >> 20));
    }
    pthread_once(&json_hooks_once, json_install_hooks);
    json_oom = 0;
    const char *end = NULL;
    cJSON *root = cJSON_ParseWithLengthOpts(text, len, &end, 0);
    if (!root && json_oom) {
        return jerr_code(&c, TR_STATUS_OUT_OF_MEMORY, NULL, "out of memory parsing the file");
    }
    if (!root) {
        size_t off = end && end >= text && end <= text + len ? (size_t)(end - text) : 0;
        unsigned line, col;
        line_col(text, off, &line, &col);
        char near[24];
        size_t k = 0;
        for (size_t i = off; i < len && k < 12; ++i) {
            unsigned char ch = (unsigned char)text[i];
            if (ch == '\n' || ch == '\r') {
                break;
            }
            near[k++] = (ch >= 32 && ch < 127) ? (char)ch : '?';
        }
        near[k] = '\0';
        if (k == 0) {
            /* Nothing follows on the line: show what precedes instead. */
            size_t from = off;
            while (from > 0 && off - from < 12 && text[from - 1] != '\n' &&
                   text[from - 1] != '\r') {
                --from;
            }
            while (from < off && (text[from] == ' ' || text[from] == '\t')) {
                ++from;
            }
            for (size_t i = from; i < off; ++i) {
                unsigned char ch = (unsigned char)text[i];
                near[k++] = (ch >= 32 && ch < 127) ? (char)ch : '?';
            }
            near[k] = '\0';
            return tr_error_set(err, TR_STATUS_PARSE,
                                "%.200s:%u:%u: JSON syntax error at the end of %s%s%s%s", path,
                                line, col, off >= len ? "the file" : "the line",
                                k ? ", after '" : "", near, k ? "'" : "");
        }
        return tr_error_set(err, TR_STATUS_PARSE, "%.200s:%u:%u: JSON syntax error near '%s'", path,
                            line, col, near);
    }
    /* Anything but white space after the value is an error too. */
    size_t off = (size_t)(end - text);
    while (off < len &&
           (text[off] == ' ' || text[off] == '\t' || text[off] == '\n' || text[off] == '\r')) {
        ++off;
    }
    int rc;
    if (off < len) {
        unsigned line, col;
        line_col(text, off, &line, &col);
        rc = tr_error_set(err, TR_STATUS_PARSE,
                          "%.200s:%u:%u: JSON syntax error: text after the top-level value", path,
                          line, col);
    } else {
        rc = build(&c, root);
    }
    cJSON_Delete(root);
    free(c.by_name);
    if (rc != TR_OK) {
        tr_scene_clear(s);
    }
    return rc;
}

int tr_scene_file_load(tr_scene *s, const char *path, const tr_scene_file_options *opt,
                       tr_scene_file *info, tr_error *err) {
    tr_scene_clear(s); /* the previous content goes; the generation counts on */
    uint64_t size = 0;
    FILE *fp = tr_infile_open(path, &size, err); /* a FIFO would block: regular files only */
    if (!fp) {
        return TR_ERR;
    }
    if (size > TR_SCENE_FILE_MAX_BYTES) {
        fclose(fp);
        return tr_error_set(err, TR_STATUS_LIMIT, "%.200s: %llu bytes is more than the limit of %u",
                            path, (unsigned long long)size, TR_SCENE_FILE_MAX_BYTES);
    }
    /* One more byte than the size says, to notice a file that grew meanwhile. */
    char *buf = malloc((size_t)size + 1);
    if (!buf) {
        fclose(fp);
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "%.200s: out of memory reading it", path);
    }
    size_t len = fread(buf, 1, (size_t)size + 1, fp);
    int rc = TR_OK;
    if (ferror(fp)) {
        rc = tr_error_set(err, tr_status_from_errno(errno), "%.200s: cannot read: %s", path,
                          strerror(errno));
    } else if (len > size) {
        rc = tr_error_set(err, TR_STATUS_IO, "%.200s: the file changed while it was read", path);
    }
    fclose(fp);
    if (rc == TR_OK) {
        rc = tr_scene_file_parse(s, path, buf, len, opt, info, err);
    }
    free(buf);
    return rc;
}
