/* A scene file's render block applied to a program's request (tr_scene_file_apply): the
 * file's values where the request leaves 0, the request's where it gives them, the
 * defaults where neither does, bdpt's depth limit, the refusals (an unknown integrator, an
 * accel this build lacks, a scene without an emitter, too many pixels) and the camera
 * resized to the image. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "check.h"
#include "trac0r/scene_file.h"
#include "trac0r/trac0r.h"

/* A lit box seen from the front; RENDER is spliced in as the file's render block. */
#define SCENE_HEAD                                                                                 \
    "{\"camera\": {\"position\": [0, 0.3, -1.2], \"look_at\": [0, 0.3, 0], \"fov\": 60},"          \
    " \"materials\": {\"white\": {\"type\": \"diffuse\", \"color\": [0.7, 0.7, 0.7]},"             \
    " \"lamp\": {\"type\": \"emitter\", \"color\": [1, 1, 1], \"emittance\": 10}},"                \
    " \"shapes\": [{\"type\": \"box\", \"position\": [0, 0, 0], \"scale\": 0.5, \"material\":"     \
    " \"white\"}"
#define LAMP                                                                                       \
    ", {\"type\": \"plane\", \"position\": [0, 0.9, 0], \"orientation\": [180, 0, 0], \"scale\":"  \
    " 0.4, \"material\": \"lamp\"}"

/* Parses a scene (with the lamp or without) whose render block is `render` (NULL: none)
 * into s and f. */
static int load(tr_scene *s, tr_scene_file *f, int lamp, const char *render) {
    char text[2048];
    snprintf(text, sizeof text, "%s%s]%s%s%s}", SCENE_HEAD, lamp ? LAMP : "",
             render ? ", \"render\": {" : "", render ? render : "", render ? "}" : "");
    tr_error err;
    const int rc = tr_scene_file_parse(s, "mem.json", text, strlen(text), NULL, f, &err);
    CHECK(rc == TR_OK, "parse: %s", err.msg);
    return rc;
}

static const char full_block[] = "\"width\": 24, \"height\": 16, \"spp\": 2, \"max_depth\": 4,"
                                 " \"accel\": \"flat\", \"integrator\": \"naive\"";

/* The zero request is the defaults: 800x600, 16 spp, pt at its own depth, the BVH. */
static void test_zero_request(tr_scene *s) {
    tr_scene_file f;
    if (load(s, &f, 1, NULL) != TR_OK) {
        return;
    }
    tr_render_request req;
    memset(&req, 0, sizeof req);
    tr_render_settings st;
    tr_error err;
    int rc = tr_scene_file_apply(s, "mem.json", &f, &req, &st, &err);
    CHECK(rc == TR_OK, "zero request: %s", err.msg);
    CHECK(st.width == 800 && st.height == 600, "size %ux%u", st.width, st.height);
    CHECK(st.spp == TR_SESSION_SPP_DEFAULT, "spp %u", st.spp);
    CHECK(st.accel == TR_ACCEL_TYPE_BVH, "accel %s", tr_accel_name(st.accel));
    CHECK(st.config.integrator == TR_INTEGRATOR_PT, "integrator %d", st.config.integrator);
    CHECK(st.config.max_depth == TR_MAX_DEPTH_DEFAULT, "max depth %d", st.config.max_depth);
    const tr_render_config def = tr_render_config_default();
    CHECK(st.config.seed == def.seed && st.config.sampler == def.sampler &&
              st.config.stride == def.stride,
          "the rest of the config is not tr_render_config_default()'s");
    CHECK(tr_scene_camera(s)->screen_width == 800 && tr_scene_camera(s)->screen_height == 600,
          "camera %ux%u", tr_scene_camera(s)->screen_width, tr_scene_camera(s)->screen_height);
    /* Without a size in the file, a width alone keeps the default's 4:3. */
    tr_render_request wide = {0};
    wide.width = 640;
    rc = tr_scene_file_apply(s, "mem.json", &f, &wide, &st, &err);
    CHECK(rc == TR_OK && st.width == 640 && st.height == 480, "width alone: %ux%u", st.width,
          st.height);
    /* A NULL request means the same. */
    rc = tr_scene_file_apply(s, "mem.json", &f, NULL, &st, &err);
    CHECK(rc == TR_OK && st.width == 800 && st.spp == TR_SESSION_SPP_DEFAULT,
          "NULL request: rc %d, %ux%u, %u spp", rc, st.width, st.height, st.spp);
}

/* The file's values where the request leaves 0; the request's where it gives them. */
static void test_file_and_request(tr_scene *s) {
    tr_scene_file f;
    if (load(s, &f, 1, full_block) != TR_OK) {
        return;
    }
    tr_render_settings st;
    tr_error err;
    int rc = tr_scene_file_apply(s, "mem.json", &f, NULL, &st, &err);
    CHECK(rc == TR_OK, "file values: %s", err.msg);
    CHECK(st.width == 24 && st.height == 16 && st.spp == 2, "file: %ux%u, %u spp", st.width,
          st.height, st.spp);
    CHECK(st.config.max_depth == 4, "file: depth %d", st.config.max_depth);
    CHECK(st.accel == TR_ACCEL_TYPE_FLAT, "file: accel %s", tr_accel_name(st.accel));
    CHECK(st.config.integrator == TR_INTEGRATOR_NAIVE, "file: integrator %d", st.config.integrator);
    CHECK(tr_scene_camera(s)->screen_width == 24 && tr_scene_camera(s)->screen_height == 16,
          "file: camera %ux%u", tr_scene_camera(s)->screen_width,
          tr_scene_camera(s)->screen_height);

    tr_render_request req = {0};
    req.width = 10;
    req.spp = 5;
    req.max_depth = 7;
    req.integrator = "pt";
    req.accel = "bvh2";
    rc = tr_scene_file_apply(s, "mem.json", &f, &req, &st, &err);
    CHECK(rc == TR_OK, "request values: %s", err.msg);
    /* The width alone: the height keeps the file's 24x16 shape (16 * 10 / 24 = 6.7). */
    CHECK(st.width == 10 && st.height == 7 && st.spp == 5, "request: %ux%u, %u spp", st.width,
          st.height, st.spp);
    CHECK(st.config.max_depth == 7, "request: depth %d", st.config.max_depth);
    CHECK(st.accel == TR_ACCEL_TYPE_BVH2, "request: accel %s", tr_accel_name(st.accel));
    CHECK(st.config.integrator == TR_INTEGRATOR_PT, "request: integrator %d", st.config.integrator);
    CHECK(tr_scene_camera(s)->screen_width == 10 && tr_scene_camera(s)->screen_height == 7,
          "request: camera %ux%u", tr_scene_camera(s)->screen_width,
          tr_scene_camera(s)->screen_height);
    /* The resolved scene commits and renders. */
    rc = tr_scene_commit(s, st.accel, &err);
    CHECK(rc == TR_OK, "commit: %s", err.msg);

    /* The height alone keeps the shape too; both sides are taken as given. */
    req = (tr_render_request){0};
    req.height = 8;
    rc = tr_scene_file_apply(s, "mem.json", &f, &req, &st, &err);
    CHECK(rc == TR_OK && st.width == 12 && st.height == 8, "height alone: %ux%u", st.width,
          st.height);
    req.width = 40;
    rc = tr_scene_file_apply(s, "mem.json", &f, &req, &st, &err);
    CHECK(rc == TR_OK && st.width == 40 && st.height == 8, "both sides: %ux%u", st.width,
          st.height);

    req = (tr_render_request){0};
    req.light_sampling = "power";
    rc = tr_scene_file_apply(s, "mem.json", &f, &req, &st, &err);
    CHECK(rc == TR_OK, "light sampling: %s", err.msg);
    rc = tr_scene_commit(s, st.accel, &err);
    CHECK(rc == TR_OK && tr_scene_light_sampling(s) == TR_LIGHT_SAMPLING_POWER,
          "light sampling power not applied: rc %d, mode %d", rc, tr_scene_light_sampling(s));
}

/* bdpt and vcm follow at most TR_MAX_DEPTH_BDPT segments: a file's longer depth (written
 * for pt) is cut to that; a request's is left for tr_render_config_check to refuse. */
static void test_bdpt_clamp(tr_scene *s) {
    tr_scene_file f;
    if (load(s, &f, 1, "\"max_depth\": 40, \"integrator\": \"bdpt\"") != TR_OK) {
        return;
    }
    tr_render_settings st;
    tr_error err;
    int rc = tr_scene_file_apply(s, "mem.json", &f, NULL, &st, &err);
    CHECK(rc == TR_OK && st.config.integrator == TR_INTEGRATOR_BDPT, "bdpt file: rc %d, %d", rc,
          st.config.integrator);
    CHECK(st.config.max_depth == TR_MAX_DEPTH_BDPT, "bdpt: depth %d, expected %d",
          st.config.max_depth, TR_MAX_DEPTH_BDPT);
    tr_render_request req = {0};
    req.integrator = "pt";
    rc = tr_scene_file_apply(s, "mem.json", &f, &req, &st, &err);
    CHECK(rc == TR_OK && st.config.max_depth == 40, "pt keeps the file's 40: %d",
          st.config.max_depth);
    req.integrator = "vcm";
    req.max_depth = 40;
    rc = tr_scene_file_apply(s, "mem.json", &f, &req, &st, &err);
    CHECK(rc == TR_OK && st.config.max_depth == 40, "a requested depth is kept: %d",
          st.config.max_depth);
    CHECK_STATUS(tr_render_config_check(&st.config, &err), err, TR_STATUS_LIMIT, "vcm at depth 40");
    /* A file depth within the limit is kept. */
    if (load(s, &f, 1, "\"max_depth\": 9, \"integrator\": \"vcm\"") != TR_OK) {
        return;
    }
    rc = tr_scene_file_apply(s, "mem.json", &f, NULL, &st, &err);
    CHECK(rc == TR_OK && st.config.max_depth == 9, "vcm depth 9: %d", st.config.max_depth);
}

static void test_refusals(tr_scene *s) {
    tr_scene_file f;
    tr_render_settings st;
    tr_error err;
    /* The parser refuses an unknown name itself; a tr_scene_file filled another way may
     * still hold one. */
    if (load(s, &f, 1, "\"integrator\": \"naive\"") != TR_OK) {
        return;
    }
    snprintf(f.integrator, sizeof f.integrator, "magic");
    CHECK_STATUS(tr_scene_file_apply(s, "mem.json", &f, NULL, &st, &err), err, TR_STATUS_PARSE,
                 "the file's unknown integrator");
    CHECK(strstr(err.msg, "mem.json: render.integrator: unknown integrator 'magic'") != NULL,
          "message: %s", err.msg);
    tr_render_request req = {0};
    req.integrator = "naive"; /* the request's wins: no error */
    CHECK(tr_scene_file_apply(s, "mem.json", &f, &req, &st, &err) == TR_OK &&
              st.config.integrator == TR_INTEGRATOR_NAIVE,
          "request over a bad file integrator: %s", err.msg);
    req.integrator = "fast";
    CHECK_STATUS(tr_scene_file_apply(s, "mem.json", &f, &req, &st, &err), err,
                 TR_STATUS_INVALID_ARGUMENT, "the request's unknown integrator");
    req = (tr_render_request){0};
    req.integrator = "pt";
    req.accel = "octree";
    CHECK_STATUS(tr_scene_file_apply(s, "mem.json", &f, &req, &st, &err), err,
                 TR_STATUS_INVALID_ARGUMENT, "the request's unknown accel");
    req.accel = NULL;
    req.light_sampling = "random";
    CHECK_STATUS(tr_scene_file_apply(s, "mem.json", &f, &req, &st, &err), err,
                 TR_STATUS_INVALID_ARGUMENT, "the request's unknown light sampling");

    /* Embree where the build has none: the file's and the request's alike. */
    if (load(s, &f, 1, "\"accel\": \"embree\"") != TR_OK) {
        return;
    }
    int rc = tr_scene_file_apply(s, "mem.json", &f, NULL, &st, &err);
    if (tr_accel_available(TR_ACCEL_TYPE_EMBREE)) {
        CHECK(rc == TR_OK && st.accel == TR_ACCEL_TYPE_EMBREE, "embree: %s", err.msg);
    } else {
        CHECK_STATUS(rc, err, TR_STATUS_UNSUPPORTED, "the file's embree without Embree");
        CHECK(strstr(err.msg, "render.accel") != NULL, "message: %s", err.msg);
        req = (tr_render_request){0};
        req.accel = "embree";
        if (load(s, &f, 1, NULL) != TR_OK) {
            return;
        }
        CHECK_STATUS(tr_scene_file_apply(s, "mem.json", &f, &req, &st, &err), err,
                     TR_STATUS_UNSUPPORTED, "the request's embree without Embree");
    }

    /* A structure the library does not know (a tr_scene_file filled by hand) is not
     * available either, in any build. */
    if (load(s, &f, 1, "\"accel\": \"flat\"") != TR_OK) {
        return;
    }
    f.accel = (tr_accel_type)99;
    CHECK_STATUS(tr_scene_file_apply(s, "mem.json", &f, NULL, &st, &err), err,
                 TR_STATUS_UNSUPPORTED, "the file's unknown accel value");
    CHECK(strstr(err.msg, "mem.json: render.accel") != NULL, "message: %s", err.msg);

    /* Too many pixels: the file's height with the request's width. */
    if (load(s, &f, 1, "\"height\": 16384") != TR_OK) {
        return;
    }
    req = (tr_render_request){0};
    req.width = 16384;
    CHECK_STATUS(tr_scene_file_apply(s, "mem.json", &f, &req, &st, &err), err, TR_STATUS_LIMIT,
                 "16384x16384");
    CHECK(st.width == 16384 && st.height == 16384, "the size at fault: %ux%u", st.width, st.height);
}

/* A scene without an emitter renders black: refused unless the file or the request
 * allows it. */
static void test_no_emitter(tr_scene *s) {
    tr_scene_file f;
    tr_render_settings st;
    tr_error err;
    if (load(s, &f, 0, NULL) != TR_OK) {
        return;
    }
    CHECK(f.emissive_triangles == 0, "%u emissive triangles", f.emissive_triangles);
    CHECK_STATUS(tr_scene_file_apply(s, "mem.json", &f, NULL, &st, &err), err, TR_STATUS_NOT_FOUND,
                 "no emitter");
    tr_render_request req = {0};
    req.allow_dark = 1;
    int rc = tr_scene_file_apply(s, "mem.json", &f, &req, &st, &err);
    CHECK(rc == TR_OK, "allow_dark: %s", err.msg);
    if (load(s, &f, 0, "\"allow_no_emitter\": true") != TR_OK) {
        return;
    }
    rc = tr_scene_file_apply(s, "mem.json", &f, NULL, &st, &err);
    CHECK(rc == TR_OK, "render.allow_no_emitter: %s", err.msg);
}

/* Extras added to any scene: a ground is one more shape and material under the bounds,
 * a sun points where asked with the default irradiance, a constant environment is taken;
 * malformed values are refused and leave nothing half-added that the check sees. */
static void test_extras(void) {
    tr_error err;
    tr_scene *s = tr_scene_create(&err);
    CHECK(s && tr_scene_builtin(s, "cornell", 16, 12, &err) == TR_OK, "%s", err.msg);
    const uint32_t shapes = tr_scene_shape_count(s), mats = tr_scene_material_count(s);
    const tr_aabb before = tr_scene_bounds(s);
    tr_scene_extras x = {0};
    CHECK(tr_scene_add_extras(s, &x, &err) == TR_OK && tr_scene_shape_count(s) == shapes,
          "a zero struct added something");
    x.ground = 1;
    x.sun = "0,2,0";
    x.env = "0.1,0.2,0.3";
    CHECK(tr_scene_add_extras(s, &x, &err) == TR_OK, "extras: %s", err.msg);
    CHECK(tr_scene_shape_count(s) == shapes + 1 && tr_scene_material_count(s) == mats + 1,
          "ground: %u shapes, %u materials", tr_scene_shape_count(s), tr_scene_material_count(s));
    const tr_aabb ground = tr_scene_shape_box(s, shapes);
    CHECK(ground.max.y <= before.min.y && ground.min.x < before.min.x &&
              ground.max.z > before.max.z,
          "ground not under the scene: y %g (scene from %g)", ground.max.y, before.min.y);
    tr_vec3 dir, e;
    float angle;
    CHECK(tr_scene_sun(s, &dir, &angle, &e) && fabsf(dir.y - 1.0f) < 1e-6f &&
              fabsf(e.x - TR_SCENE_EXTRAS_SUN) < 1e-3f * TR_SCENE_EXTRAS_SUN,
          "sun: towards (%g, %g, %g), irradiance %g", dir.x, dir.y, dir.z, e.x);
    CHECK(tr_scene_commit(s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "commit: %s", err.msg);
    const char *bad_sun[] = {"0,0,0", "1,2", " 1,2,3", "1,2,3,4", "1,nan,3", ""};
    for (size_t i = 0; i < sizeof bad_sun / sizeof *bad_sun; ++i) {
        const tr_scene_extras b = {.sun = bad_sun[i]};
        err.code = TR_STATUS_OK;
        CHECK(tr_scene_add_extras(s, &b, &err) == TR_ERR && err.code == TR_STATUS_INVALID_ARGUMENT,
              "sun '%s' accepted", bad_sun[i]);
    }
    const tr_scene_extras neg = {.env = "1,-1,1"}, missing = {.env = "no-such-sky.hdr"};
    CHECK(tr_scene_add_extras(s, &neg, &err) == TR_ERR, "negative radiance accepted");
    CHECK(tr_scene_add_extras(s, &missing, &err) == TR_ERR, "a missing map accepted");
    tr_scene_destroy(s);
}

/* tr_scene_open: a name to a committed scene and its settings; the request wins, the
 * program's defaults fill what neither it nor the scene gives, and a failure leaves the
 * scene empty. */
static void test_open(void) {
    tr_error err;
    tr_scene *s = tr_scene_create(&err);
    tr_render_settings st;
    tr_scene_open_desc d = {0};
    d.defaults.width = 320;
    d.defaults.height = 240;
    d.defaults.integrator = "naive";
    CHECK(tr_scene_open(s, "builtin:cornell", &d, NULL, &st, &err) == TR_OK, "%s", err.msg);
    CHECK(st.width == 320 && st.height == 240 && st.config.integrator == TR_INTEGRATOR_NAIVE &&
              tr_scene_accel(s) == TR_ACCEL_TYPE_BVH && tr_scene_camera(s)->screen_width == 320,
          "defaults: %ux%u, integrator %d", st.width, st.height, st.config.integrator);
    d.request.width = 640;
    d.request.integrator = "pt";
    d.request.accel = "bvh2";
    CHECK(tr_scene_open(s, "cornell", &d, NULL, &st, &err) == TR_OK, "%s", err.msg);
    CHECK(st.width == 640 && st.height == 480 && st.config.integrator == TR_INTEGRATOR_PT &&
              tr_scene_accel(s) == TR_ACCEL_TYPE_BVH2,
          "request: %ux%u, integrator %d, accel %s", st.width, st.height, st.config.integrator,
          tr_accel_name(tr_scene_accel(s)));
    /* The same scene built by hand at that size: the same camera, bit for bit. */
    tr_scene *hand = tr_scene_create(&err);
    CHECK(hand && tr_scene_builtin(hand, "cornell", 640, 480, &err) == TR_OK, "%s", err.msg);
    CHECK(hand && memcmp(tr_scene_camera(hand), tr_scene_camera(s), sizeof(tr_camera)) == 0,
          "camera differs from the built-in scene's own");
    tr_scene_destroy(hand);
    /* Each failure names its stage: the load, an extra, the settings, the commit. */
    tr_scene_file f;
    CHECK(tr_scene_open(s, "cornell", &d, &f, &st, &err) == TR_OK && f.open_stage == 0,
          "success: stage %u", f.open_stage);
    CHECK(tr_scene_open(s, "builtin:nope", &d, &f, &st, &err) == TR_ERR &&
              tr_scene_triangle_count(s) == 0 && f.open_stage == TR_SCENE_OPEN_LOAD,
          "an unknown scene opened, or left %u triangles (stage %u)", tr_scene_triangle_count(s),
          f.open_stage);
    d.request.integrator = "nope";
    CHECK(tr_scene_open(s, "cornell", &d, &f, &st, &err) == TR_ERR &&
              f.open_stage == TR_SCENE_OPEN_SETTINGS,
          "an unknown integrator: stage %u", f.open_stage);
    d.request.integrator = "pt";
    d.request.accel = "embree";
    if (tr_scene_open(s, "cornell", &d, &f, &st, &err) == TR_ERR) { /* a build without Embree */
        CHECK(err.code == TR_STATUS_UNSUPPORTED && f.open_stage == TR_SCENE_OPEN_COMMIT,
              "embree refused at stage %u, status %d", f.open_stage, err.code);
    }
    d.request.accel = "bvh2";
    d.extras.sun = "0,0,0";
    CHECK(tr_scene_open(s, "cornell", &d, &f, &st, &err) == TR_ERR &&
              err.code == TR_STATUS_INVALID_ARGUMENT && tr_scene_triangle_count(s) == 0 &&
              f.open_stage == TR_SCENE_OPEN_EXTRAS,
          "a bad sun opened (stage %u)", f.open_stage);
    tr_scene_destroy(s);
}

int main(void) {
    test_extras();
    test_open();
    tr_scene *s = tr_scene_create(NULL);
    CHECK(s != NULL, "tr_scene_create");
    if (!s) {
        return check_finish("test_render_defaults");
    }
    test_zero_request(s);
    test_file_and_request(s);
    test_bdpt_clamp(s);
    test_refusals(s);
    test_no_emitter(s);
    tr_scene_destroy(s);
    return check_finish("test_render_defaults");
}
