/* test_limits.c - limits a file must not walk around (a hostile or broken file must end in an
 * error): the triangle budget when shapes fill it exactly, a model's references outside its
 * directory (and TRAC0R_MODEL_ROOT allowing them), the scene file's value limit, the PNG reader's
 * pixel cap, and black emitters, which light nothing. */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "trac0r/image.h"
#include "trac0r/scene.h"
#include "trac0r/scene_file.h"

#define DATA TR_SOURCE_DIR "/tests/data"

static const char camera[] =
    "\"camera\": {\"position\": [0, 0, -3], \"look_at\": [0, 0, 0], \"fov\": 60}";

static void test_budget(void) {
    /* Two boxes (12 each) fill a budget of 24 exactly; the mesh after them must not be
     * imported as if the remaining 0 meant "no limit". */
    char text[1024];
    snprintf(text, sizeof text,
             "{%s, \"materials\": {\"l\": {\"type\": \"emitter\", \"color\": [1, 1, 1], "
             "\"emittance\": 1}},\n \"shapes\": [{\"type\": \"box\", \"material\": \"l\"}, "
             "{\"type\": \"box\", \"material\": \"l\", \"position\": [3, 0, 0]}],\n \"meshes\": "
             "[{\"path\": \"%s\", "
             "\"material\": \"l\"}]}",
             camera, DATA "/mesh/quad.ply");
    tr_scene *s = tr_scene_create(NULL);
    tr_error err;
    tr_scene_file_options opt = {1, 24};
    CHECK_STATUS(tr_scene_file_parse(s, "budget.json", text, strlen(text), &opt, NULL, &err), err,
                 TR_STATUS_LIMIT, "a mesh after shapes that fill the budget");
    opt.max_triangles = 26; /* the quad's two triangles fit */
    CHECK(tr_scene_file_parse(s, "budget.json", text, strlen(text), &opt, NULL, &err) == TR_OK,
          "a budget with room for the mesh: %s", err.msg);
    CHECK(tr_scene_triangle_count(s) == 26, "%u triangles", tr_scene_triangle_count(s));
    tr_scene_destroy(s);
}

static void test_confinement(void) {
    tr_scene *s = tr_scene_create(NULL);
    tr_error err;
    const char *obj = DATA "/hostile/models/escape/inner/mtllib_escape.obj";
    unsetenv("TRAC0R_MODEL_ROOT");
    CHECK_STATUS(tr_scene_import_mesh(s, obj, NULL, -1, 0, NULL, &err), err, TR_STATUS_LIMIT,
                 "an mtllib above the model's directory");
    CHECK(tr_scene_triangle_count(s) == 0, "a refused import added triangles");
    const char *gltf = DATA "/hostile/models/escape/gltf_buffer_escape.gltf";
    CHECK_STATUS(tr_scene_import_mesh(s, gltf, NULL, -1, 0, NULL, &err), err, TR_STATUS_LIMIT,
                 "a glTF buffer uri above the model's directory");
    /* The user allows the tree that holds both. */
    setenv("TRAC0R_MODEL_ROOT", DATA, 1);
    tr_mesh_import_stats st;
    CHECK(tr_scene_import_mesh(s, obj, NULL, -1, 0, &st, &err) == TR_OK,
          "TRAC0R_MODEL_ROOT did not allow the mtllib: %s", err.msg);
    CHECK(st.materials == 1, "%u materials from the allowed library, expected 1 (red)",
          st.materials);
    unsetenv("TRAC0R_MODEL_ROOT");
    /* A model's references inside its own tree are fine (tri.obj names tri.mtl). */
    CHECK(tr_scene_import_mesh(s, DATA "/mesh/tri.obj", NULL, -1, 0, &st, &err) == TR_OK,
          "tri.obj: %s", err.msg);
    CHECK(st.materials == 4, "tri.obj: %u materials, expected 4", st.materials);
    tr_scene_destroy(s);
}

static void test_values(void) {
    /* 2^21 + 2 values in 4 MiB: refused before cJSON builds a node for each. */
    const size_t n = (size_t)TR_SCENE_FILE_MAX_VALUES + 1;
    char *text = malloc(2 * n + 16);
    size_t len = 0;
    text[len++] = '[';
    for (size_t i = 0; i < n; ++i) {
        text[len++] = '0';
        text[len++] = i + 1 < n ? ',' : ']';
    }
    tr_scene *s = tr_scene_create(NULL);
    tr_error err;
    CHECK_STATUS(tr_scene_file_parse(s, "values.json", text, len, NULL, NULL, &err), err,
                 TR_STATUS_LIMIT, "more JSON values than the limit");
    /* Commas inside strings are not values. */
    len = 0;
    len += (size_t)sprintf(text, "{\"description\": \"");
    for (size_t i = 0; i < n; ++i) {
        text[len++] = ',';
    }
    len += (size_t)sprintf(text + len, "\", %s}", camera);
    CHECK(tr_scene_file_parse(s, "commas.json", text, len, NULL, NULL, &err) != TR_OK &&
              err.code != TR_STATUS_LIMIT,
          "commas in a string counted as values: %s", err.msg);
    free(text);
    tr_scene_destroy(s);
}

static void test_png_cap(void) {
    tr_image img;
    tr_error err;
    /* 16384 x 8192: within the side limit, twice the pixel limit. */
    CHECK_STATUS(tr_image_read_png(&img, DATA "/hostile/images/png_too_many_pixels.png", &err), err,
                 TR_STATUS_LIMIT, "a PNG over the pixel limit");
    CHECK_STATUS(tr_image_read_png(&img, DATA "/hostile/images/png_huge_dimensions.png", &err), err,
                 TR_STATUS_LIMIT, "a PNG over the side limit");
}

static void test_black_emitter(void) {
    const char *mats[] = {"\"color\": [0, 0, 0], \"emittance\": 5",
                          "\"color\": [1, 1, 1], \"emittance\": 0",
                          "\"color\": [1, 1, 1], \"emittance\": 5"};
    for (int k = 0; k < 3; ++k) {
        char text[1024];
        snprintf(text, sizeof text,
                 "{%s, \"materials\": {\"l\": {\"type\": \"emitter\", %s}},\n"
                 " \"shapes\": [{\"type\": \"plane\", \"material\": \"l\"}]}",
                 camera, mats[k]);
        tr_scene *s = tr_scene_create(NULL);
        tr_error err;
        tr_scene_file info;
        int rc = tr_scene_file_parse(s, "e.json", text, strlen(text), NULL, &info, &err);
        if (rc != TR_OK) {
            /* Refusing the material outright would do as well. */
            CHECK(k < 2, "a lit emitter refused: %s", err.msg);
        } else {
            CHECK(info.emissive_triangles == (k == 2 ? 2u : 0u),
                  "emitter %d: %u emissive triangles", k, info.emissive_triangles);
        }
        tr_scene_destroy(s);
    }
}

int main(void) {
    test_budget();
    test_confinement();
    test_values();
    test_png_cap();
    test_black_emitter();
    return check_finish("test_limits");
}
