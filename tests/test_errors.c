/* Error codes: tr_status_name names every code, tr_error_set and tr_status_from_errno
 * do what error.h says, and each public failure that is cheap to cause reports the code
 * its kind of failure is documented to have (include/trac0r/error.h). The messages'
 * wording is not checked here; only that there is one. */
#include <errno.h>
#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "kernel/kernel.h"
#include "scene/scene_internal.h"
#include "trac0r/trac0r.h"

#define DATA TR_SOURCE_DIR "/tests/data"

/* Every code with its name spelt from the identifier itself. */
#define NAMED(code)                                                                                \
    { code, #code }
static const struct {
    tr_status code;
    const char *name;
} all_codes[] = {
    NAMED(TR_STATUS_OK),
    NAMED(TR_STATUS_INVALID_ARGUMENT),
    NAMED(TR_STATUS_INVALID_OPERATION),
    NAMED(TR_STATUS_OUT_OF_MEMORY),
    NAMED(TR_STATUS_LIMIT),
    NAMED(TR_STATUS_NOT_FOUND),
    NAMED(TR_STATUS_IO),
    NAMED(TR_STATUS_PARSE),
    NAMED(TR_STATUS_UNSUPPORTED),
    NAMED(TR_STATUS_STALE_SCENE),
    NAMED(TR_STATUS_CANCELLED),
    NAMED(TR_STATUS_DEVICE),
};
_Static_assert(sizeof all_codes / sizeof all_codes[0] == TR_STATUS_COUNT,
               "a tr_status is missing from all_codes");

static void test_names(void) {
    int seen[TR_STATUS_COUNT] = {0};
    for (size_t i = 0; i < sizeof all_codes / sizeof all_codes[0]; ++i) {
        const tr_status c = all_codes[i].code;
        CHECK((int)c >= 0 && c < TR_STATUS_COUNT, "%s = %d is out of range", all_codes[i].name,
              (int)c);
        if ((int)c >= 0 && c < TR_STATUS_COUNT) {
            seen[c]++;
        }
        const char *name = tr_status_name(c);
        CHECK(name && strcmp(name, all_codes[i].name) == 0, "tr_status_name(%d) = %s, not %s",
              (int)c, name ? name : "NULL", all_codes[i].name);
    }
    for (int c = 0; c < TR_STATUS_COUNT; ++c) {
        CHECK(seen[c] == 1, "code %d appears %d times", c, seen[c]);
    }
    CHECK(strcmp(tr_status_name(TR_STATUS_COUNT), "TR_STATUS_UNKNOWN") == 0, "COUNT named %s",
          tr_status_name(TR_STATUS_COUNT));
    CHECK(strcmp(tr_status_name((tr_status)(TR_STATUS_COUNT + 7)), "TR_STATUS_UNKNOWN") == 0,
          "an out-of-range code named %s", tr_status_name((tr_status)(TR_STATUS_COUNT + 7)));
}

static void test_set_and_errno(void) {
    tr_error err;
    memset(&err, 0, sizeof err);
    CHECK(tr_error_set(&err, TR_STATUS_PARSE, "line %d", 7) == TR_ERR, "tr_error_set returns");
    CHECK(err.code == TR_STATUS_PARSE && strcmp(err.msg, "line 7") == 0, "set: %s %s",
          tr_status_name(err.code), err.msg);
    CHECK(tr_error_set(NULL, TR_STATUS_IO, "nobody listens") == TR_ERR, "a NULL tr_error");
    /* A message longer than the buffer is cut, NUL-terminated, and keeps its code. */
    char *long_text = malloc(2000);
    if (long_text) {
        memset(long_text, 'x', 1999);
        long_text[1999] = '\0';
        tr_error_set(&err, TR_STATUS_LIMIT, "%s", long_text);
        CHECK(err.code == TR_STATUS_LIMIT && strlen(err.msg) == sizeof err.msg - 1,
              "long message: %s, %zu bytes", tr_status_name(err.code), strlen(err.msg));
        free(long_text);
    }
    CHECK(tr_status_from_errno(ENOENT) == TR_STATUS_NOT_FOUND, "ENOENT");
    CHECK(tr_status_from_errno(ENOTDIR) == TR_STATUS_NOT_FOUND, "ENOTDIR");
    CHECK(tr_status_from_errno(ENOMEM) == TR_STATUS_OUT_OF_MEMORY, "ENOMEM");
    CHECK(tr_status_from_errno(ENAMETOOLONG) == TR_STATUS_INVALID_ARGUMENT, "ENAMETOOLONG");
    CHECK(tr_status_from_errno(EACCES) == TR_STATUS_IO, "EACCES");
    CHECK(tr_status_from_errno(EISDIR) == TR_STATUS_IO, "EISDIR");
    CHECK(tr_status_from_errno(ENOSPC) == TR_STATUS_IO, "ENOSPC");
}

/* Sizes: zero is an invalid argument, too big a limit. */
static void test_sizes(void) {
    tr_error err;
    tr_film f;
    CHECK_STATUS(tr_film_init(&f, 0, 4, &err), err, TR_STATUS_INVALID_ARGUMENT, "film 0x4");
    CHECK_STATUS(tr_film_init(&f, TR_FILM_MAX_SIDE + 1, 4, &err), err, TR_STATUS_LIMIT,
                 "film wider than the limit");
    CHECK_STATUS(tr_film_init(&f, TR_FILM_MAX_SIDE, TR_FILM_MAX_SIDE, &err), err, TR_STATUS_LIMIT,
                 "film over the pixel limit");
    tr_scene s = {0};
    CHECK(tr_scene_builtin(&s, "cornell", 8, 6, &err) == TR_OK, "%s", err.msg);
    CHECK_STATUS(tr_camera_resize(&s.camera, 8, 0, &err), err, TR_STATUS_INVALID_ARGUMENT,
                 "camera 8x0");
    CHECK_STATUS(tr_camera_resize(&s.camera, TR_FILM_MAX_SIDE + 1, 8, &err), err, TR_STATUS_LIMIT,
                 "camera wider than the limit");
    tr_scene_clear(&s);
}

/* Scenes built through the API. */
static void test_scene_api(void) {
    tr_error err;
    tr_scene s = {0};
    CHECK_STATUS(tr_scene_builtin(&s, "no-such-scene", 8, 6, &err), err, TR_STATUS_NOT_FOUND,
                 "unknown built-in scene");
    CHECK(err.msg[0] != '\0', "no message");
    tr_scene_init(&s);
    tr_material glass = tr_material_glass(v3s(1.0f), 0.5f);
    CHECK_STATUS(tr_scene_add_material(&s, glass, NULL, &err), err, TR_STATUS_INVALID_ARGUMENT,
                 "ior 0.5");
    uint32_t white;
    CHECK(tr_scene_add_material(&s, tr_material_diffuse(v3s(0.5f)), &white, &err) == TR_OK, "%s",
          err.msg);
    tr_shape_desc d = tr_shape_desc_default(TR_SHAPE_BOX);
    d.material = white + 1;
    CHECK_STATUS(tr_scene_add_shape(&s, &d, &err), err, TR_STATUS_NOT_FOUND,
                 "material index 1 of 1");
    d.material = white;
    d.transform.scale = v3(1, 0, 1);
    CHECK_STATUS(tr_scene_add_shape(&s, &d, &err), err, TR_STATUS_INVALID_ARGUMENT, "scale 0");
    d = tr_shape_desc_default(TR_SHAPE_ICOSPHERE);
    d.subdivisions = TR_ICOSPHERE_MAX_SUBDIVISIONS + 1;
    CHECK_STATUS(tr_scene_add_shape(&s, &d, &err), err, TR_STATUS_LIMIT, "subdivisions");
    const float pos[] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    const uint32_t bad_index[] = {0, 1, 3};
    CHECK_STATUS(tr_scene_add_mesh(&s, pos, 3, bad_index, 1, NULL, white, NULL, NULL, &err), err,
                 TR_STATUS_INVALID_ARGUMENT, "vertex index 3 of 3");
    d = tr_shape_desc_default(TR_SHAPE_BOX);
    CHECK(tr_scene_add_shape(&s, &d, &err) == TR_OK, "%s", err.msg);
    CHECK_STATUS(tr_scene_move_shape(&s, 1, v3(1, 0, 0), &err), err, TR_STATUS_NOT_FOUND,
                 "shape 1 of 1");
    CHECK_STATUS(tr_scene_move_shape(&s, 0, v3(NAN, 0, 0), &err), err, TR_STATUS_INVALID_ARGUMENT,
                 "NaN offset");
    CHECK_STATUS(tr_scene_commit(&s, (tr_accel_type)99, &err), err, TR_STATUS_INVALID_ARGUMENT,
                 "accel 99");
    if (!tr_accel_available(TR_ACCEL_TYPE_EMBREE)) {
        CHECK_STATUS(tr_scene_commit(&s, TR_ACCEL_TYPE_EMBREE, &err), err, TR_STATUS_UNSUPPORTED,
                     "embree without Embree");
    }
    tr_scene_clear(&s);
}

/* Rendering: bad configurations, a stale scene, the cancel flag. */
/* A cancel callback that always answers "stop". */
static int always_cancel(void *user) {
    (void)user;
    return 1;
}

static void test_render(void) {
    tr_error err;
    tr_scene s = {0};
    CHECK(tr_scene_builtin(&s, "cornell", 8, 6, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_FLAT, &err) == TR_OK, "%s", err.msg);
    tr_film f;
    CHECK(tr_film_init(&f, 8, 6, &err) == TR_OK, "%s", err.msg);
    tr_render_config cfg = tr_render_config_default();
    CHECK(tr_render_frame(&s, &s.camera, &cfg, &f, 0, NULL, &err) == TR_OK, "%s", err.msg);
    cfg.max_depth = -1; /* 0 is the integrator's default */
    CHECK_STATUS(tr_render_frame(&s, &s.camera, &cfg, &f, 0, NULL, &err), err,
                 TR_STATUS_INVALID_ARGUMENT, "max depth -1");
    cfg.max_depth = TR_MAX_DEPTH_LIMIT + 1;
    CHECK_STATUS(tr_render_frame(&s, &s.camera, &cfg, &f, 0, NULL, &err), err,
                 TR_STATUS_INVALID_ARGUMENT, "max depth past the limit");
    cfg = tr_render_config_default();
    cfg.integrator = 99;
    CHECK_STATUS(tr_render_frame(&s, &s.camera, &cfg, &f, 0, NULL, &err), err,
                 TR_STATUS_INVALID_ARGUMENT, "integrator 99");
    cfg = tr_render_config_default();
    tr_film other;
    CHECK(tr_film_init(&other, 9, 6, &err) == TR_OK, "%s", err.msg);
    CHECK_STATUS(tr_render_frame(&s, &s.camera, &cfg, &other, 0, NULL, &err), err,
                 TR_STATUS_INVALID_ARGUMENT, "a 9x6 film for an 8x6 camera");
    tr_film_free(&other);
    cfg.cancel = always_cancel;
    CHECK_STATUS(tr_render_frame(&s, &s.camera, &cfg, &f, 1, NULL, &err), err, TR_STATUS_CANCELLED,
                 "cancel flag set");
    cfg.cancel = NULL;
    /* A shape added after a BVH commit makes the scene stale for rendering and updating. */
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
    tr_shape_desc d = tr_shape_desc_default(TR_SHAPE_BOX);
    d.transform.scale = v3s(0.1f);
    CHECK(tr_scene_add_shape(&s, &d, &err) == TR_OK, "%s", err.msg);
    CHECK_STATUS(tr_render_frame(&s, &s.camera, &cfg, &f, 0, NULL, &err), err,
                 TR_STATUS_STALE_SCENE, "render after adding a shape");
    CHECK_STATUS(tr_scene_update(&s, NULL, &err), err, TR_STATUS_STALE_SCENE,
                 "update after adding a shape");
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_render_frame(&s, &s.camera, &cfg, &f, 0, NULL, &err) == TR_OK, "%s", err.msg);
    tr_film_free(&f);
    tr_scene_clear(&s);
}

static int parse(const char *text, uint32_t max_triangles, tr_error *err) {
    tr_scene s = {0};
    tr_scene_file_options opt = {0, max_triangles};
    int rc = tr_scene_file_parse(&s, "e.json", text, strlen(text), &opt, NULL, err);
    if (rc == TR_OK) {
        tr_scene_clear(&s);
    }
    return rc;
}

/* Scene files: a file's content is PARSE, its budget LIMIT, a missing file NOT_FOUND. */
static void test_scene_files(void) {
    tr_error err;
    const char *good =
        "{\"camera\": {\"position\": [0, 0, -3], \"direction\": [0, 0, 1], \"fov\": 40},\n"
        " \"materials\": {\"w\": {\"type\": \"diffuse\", \"color\": [1, 1, 1]}},\n"
        " \"shapes\": [{\"type\": \"box\", \"material\": \"w\"}]}";
    CHECK(parse(good, 0, &err) == TR_OK, "the good file: %s", err.msg);
    CHECK_STATUS(parse("{\"camera\": tru}", 0, &err), err, TR_STATUS_PARSE, "syntax");
    CHECK_STATUS(parse("{\"camera\": {}, \"zzz\": 1}", 0, &err), err, TR_STATUS_PARSE,
                 "unknown key");
    CHECK_STATUS(parse(good, 11, &err), err, TR_STATUS_LIMIT, "a box in a budget of 11");
    /* The camera's own check rejects an up vector along the direction: a value the file
     * gave, so the file's fault. */
    const char *up = "{\"camera\": {\"position\": [0, 0, -3], \"direction\": [0, 0, 1],"
                     " \"fov\": 40, \"up\": [0, 0, 2]},\n"
                     " \"materials\": {\"w\": {\"type\": \"diffuse\", \"color\": [1, 1, 1]}},\n"
                     " \"shapes\": [{\"type\": \"box\", \"material\": \"w\"}]}";
    CHECK_STATUS(parse(up, 0, &err), err, TR_STATUS_PARSE, "up along the direction");
    /* Too long: rejected before any byte is read. */
    char *huge = calloc((size_t)TR_SCENE_FILE_MAX_BYTES + 1, 1);
    if (huge) {
        tr_scene s = {0};
        CHECK_STATUS(tr_scene_file_parse(&s, "huge.json", huge, (size_t)TR_SCENE_FILE_MAX_BYTES + 1,
                                         NULL, NULL, &err),
                     err, TR_STATUS_LIMIT, "a file over the size limit");
        free(huge);
    }
    tr_scene s = {0};
    CHECK_STATUS(tr_scene_file_load(&s, "no-such-dir/scene.json", NULL, NULL, &err), err,
                 TR_STATUS_NOT_FOUND, "a missing scene file");
    CHECK(strstr(err.msg, "no-such-dir/scene.json") != NULL, "the file is not named: %s", err.msg);
    /* A directory is not a regular file: refused before reading. */
    CHECK_STATUS(tr_scene_file_load(&s, DATA, NULL, NULL, &err), err, TR_STATUS_IO,
                 "a directory as a scene file");
    /* A mesh inside a scene file keeps the import's code. */
    const char *mesh =
        "{\"camera\": {\"position\": [0, 0, -3], \"direction\": [0, 0, 1], \"fov\": 40},\n"
        " \"materials\": {\"w\": {\"type\": \"diffuse\", \"color\": [1, 1, 1]}},\n"
        " \"meshes\": [{\"path\": \"no-such-model.obj\", \"material\": \"w\"}]}";
    CHECK_STATUS(tr_scene_file_parse(&s, DATA "/e.json", mesh, strlen(mesh), NULL, NULL, &err), err,
                 TR_STATUS_NOT_FOUND, "a missing mesh");
}

/* Mesh import. */
static void test_meshes(void) {
    tr_error err;
    tr_scene s = {0};
    tr_scene_init(&s);
    tr_mesh_import_stats st;
    CHECK_STATUS(tr_scene_import_mesh(&s, DATA "/no-such-model.obj", NULL, -1, 0, &st, &err), err,
                 TR_STATUS_NOT_FOUND, "missing model");
    CHECK_STATUS(tr_scene_import_mesh(&s, DATA "/bad/garbage.ply", NULL, -1, 0, &st, &err), err,
                 TR_STATUS_PARSE, "garbage PLY");
    CHECK_STATUS(tr_scene_import_mesh(&s, DATA "/mesh/tri.obj", NULL, 3, 0, &st, &err), err,
                 TR_STATUS_NOT_FOUND, "override material 3 of none");
    CHECK_STATUS(tr_scene_import_mesh(&s, DATA "/mesh/tri.obj", NULL, -1, 3, &st, &err), err,
                 TR_STATUS_LIMIT, "a budget of 3 triangles");
    CHECK(s.triangle_count == 0, "failures added %u triangles", s.triangle_count);
    tr_scene_clear(&s);
}

/* Images: files named by paths that do not exist, unknown formats. */
static void test_images(void) {
    tr_error err;
    tr_film f;
    CHECK(tr_film_init(&f, 2, 2, &err) == TR_OK, "%s", err.msg);
    CHECK_STATUS(tr_film_write(&f, "no-such-dir/a.pfm", 0.0f, &err), err, TR_STATUS_NOT_FOUND,
                 "write into a missing directory");
    CHECK_STATUS(tr_film_write(&f, "no-such-dir/a.bmp", 0.0f, &err), err, TR_STATUS_UNSUPPORTED,
                 "write a .bmp");
    tr_film_free(&f);
    tr_image img;
    CHECK_STATUS(tr_image_read_pfm(&img, "no-such-dir/a.pfm", &err), err, TR_STATUS_NOT_FOUND,
                 "read a missing PFM");
    CHECK_STATUS(tr_image_read_png(&img, "no-such-dir/a.png", &err), err, TR_STATUS_NOT_FOUND,
                 "read a missing PNG");
    CHECK_STATUS(tr_image_read_png(&img, DATA "/bad/garbage.ply", &err), err, TR_STATUS_PARSE,
                 "read a PLY file as PNG");
}

int main(void) {
    test_names();
    test_set_and_errno();
    test_sizes();
    test_scene_api();
    test_render();
    test_scene_files();
    test_meshes();
    test_images();
    return check_finish("test_errors");
}
