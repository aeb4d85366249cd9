/* Scene files and mesh import: the JSON loader from files and memory, Assimp import of
 * OBJ (with MTL mapping), PLY and glTF 2.0 (our small files and Debian's
 * assimp-testmodels), tr_scene_add_mesh, and the classic Cornell box's orientation. */
#define _POSIX_C_SOURCE 200809L /* setenv */
#include <math.h>
#include <stdlib.h>
#include <stdio.h>
#include <string.h>

#include "check.h"
#include "kernel/camera.h"
#include "kernel/intersect.h"
#include "kernel/kernel.h"
#include "scene/scene_internal.h"
#include "trac0r/scene_file.h"
#include "trac0r/trac0r.h"

#define DATA TR_SOURCE_DIR "/tests/data"
#define MODELS "/usr/share/assimp/models"

static const tr_material *mat_of(const tr_scene *s, uint32_t tri) {
    return &s->materials[s->triangles[tri].material];
}

/* tri.obj: a red quad with normals, a lamp (Ke), a glass (illum 4, Ni, d) and a glossy
 * (illum 3, Ks, Ns) triangle, one zero-area face and one line. */
static void test_obj(void) {
    tr_scene s = {0};
    tr_scene_init(&s);
    tr_error err;
    tr_mesh_import_stats st;
    int rc = tr_scene_import_mesh(&s, DATA "/mesh/tri.obj", NULL, -1, 0, &st, &err);
    CHECK(rc == TR_OK, "%s", err.msg);
    if (rc != TR_OK) {
        return;
    }
    CHECK(st.triangles == 5 && s.triangle_count == 5, "%u triangles", st.triangles);
    CHECK(st.degenerate == 2, "%u degenerate faces (a zero-area one and a line)", st.degenerate);
    CHECK(st.materials == 4, "%u materials", st.materials);
    int seen[5] = {0};
    for (uint32_t i = 0; i < s.triangle_count; ++i) {
        const tr_material *m = mat_of(&s, i);
        const tr_triangle *t = &s.triangles[i];
        seen[m->type]++;
        if (m->type == TR_MATERIAL_DIFFUSE) {
            CHECK_NEAR(m->color.x, 0.8, 1e-6, "Kd red");
            CHECK_NEAR(m->color.y, 0.1, 1e-6, "Kd green");
            CHECK(t->v0.x < 1.5f, "the red faces are the quad");
            /* Vertex normals as written: (0, 0, 1) at v1, v2 and (0, 0.6, 0.8) at v3, v4. */
            tr_vec3 n[3];
            CHECK(tr_scene_triangle_normals(&s, i, n), "normals stored");
            for (int k = 0; k < 3; ++k) {
                const tr_vec3 v = k == 0 ? t->v0 : k == 1 ? t->v1 : t->v2;
                const double ey = v.y > 0.5f ? 0.6 : 0.0, ez = v.y > 0.5f ? 0.8 : 1.0;
                CHECK_NEAR(n[k].y, ey, 1e-6, "normal y");
                CHECK_NEAR(n[k].z, ez, 1e-6, "normal z");
            }
        } else if (m->type == TR_MATERIAL_EMITTER) {
            /* Ke (4, 2, 1): colour Ke / 4, emittance 4. */
            CHECK_NEAR(m->emittance, 4.0, 1e-6, "emittance");
            CHECK_NEAR(m->color.y * m->emittance, 2.0, 1e-6, "Ke green");
            CHECK_NEAR(m->color.z * m->emittance, 1.0, 1e-6, "Ke blue");
        } else if (m->type == TR_MATERIAL_GLASS) {
            CHECK_NEAR(m->ior, 1.45, 1e-6, "Ni");
            CHECK_NEAR(m->color.z, 1.0, 1e-6, "glass colour from Kd");
        } else if (m->type == TR_MATERIAL_GLOSSY) {
            CHECK_NEAR(m->color.x, 0.8, 1e-6, "glossy colour from Ks");
            CHECK_NEAR(m->roughness, sqrt(2.0 / 100.0), 1e-6, "roughness from Ns 98");
        }
    }
    CHECK(seen[TR_MATERIAL_DIFFUSE] == 2 && seen[TR_MATERIAL_EMITTER] == 1 &&
              seen[TR_MATERIAL_GLASS] == 1 && seen[TR_MATERIAL_GLOSSY] == 1,
          "material mix %d %d %d %d", seen[1], seen[2], seen[3], seen[4]);

    /* With an override and a transform: every triangle gets material 0, placed. */
    tr_scene o = {0};
    tr_scene_init(&o);
    uint32_t white;
    tr_scene_add_material(&o, tr_material_diffuse(v3s(0.5f)), &white, &err);
    tr_transform tf = {v3(10, 0, 0), v3(0, 0, 0), v3(2, 2, 2)};
    rc = tr_scene_import_mesh(&o, DATA "/mesh/tri.obj", &tf, white, 0, &st, &err);
    CHECK(rc == TR_OK && o.material_count == 1 && st.materials == 0, "override: %s", err.msg);
    tr_aabb b = tr_triangles_bounds(o.triangles, o.triangle_count);
    CHECK_NEAR(b.min.x, 10.0, 1e-5, "placed min x");
    CHECK_NEAR(b.max.x, 24.0, 1e-5, "placed max x (7 * 2 + 10)");
    /* The budget: fewer triangles allowed than the file has fails and adds nothing. */
    rc = tr_scene_import_mesh(&o, DATA "/mesh/tri.obj", NULL, white, 3, &st, &err);
    CHECK_STATUS(rc, err, TR_STATUS_LIMIT, "a budget of 3 triangles");
    CHECK(o.triangle_count == 5, "nothing added on failure: %u", o.triangle_count);
    tr_scene_clear(&o);
    tr_scene_clear(&s);
}

static void test_ply_gltf(void) {
    tr_scene s = {0};
    tr_scene_init(&s);
    tr_error err;
    tr_mesh_import_stats st;
    int rc = tr_scene_import_mesh(&s, DATA "/mesh/quad.ply", NULL, -1, 0, &st, &err);
    CHECK(rc == TR_OK && st.triangles == 2 && st.degenerate == 0, "ply: %s", err.msg);
    tr_vec3 pn[3];
    CHECK(s.tri_verts_count == 2 && tr_scene_triangle_normals(&s, 0, pn) && pn[0].z == 1.0f,
          "ply normals kept");
    CHECK(s.triangles[0].normal.z > 0.99f, "ply winding: front face +z");
    tr_scene_clear(&s);

    tr_scene_init(&s);
    rc = tr_scene_import_mesh(&s, DATA "/mesh/tri.gltf", NULL, -1, 0, &st, &err);
    CHECK(rc == TR_OK && st.triangles == 1, "gltf: %s", err.msg);
    if (rc == TR_OK) {
        /* The node's scale 2 and translation (0, 0, 5) applied. */
        tr_aabb b = tr_triangles_bounds(s.triangles, s.triangle_count);
        CHECK_NEAR(b.max.x, 2.0, 1e-6, "gltf node scale");
        CHECK_NEAR(b.min.z, 5.0, 1e-6, "gltf node translation");
        CHECK_NEAR(mat_of(&s, 0)->color.y, 0.4, 1e-6, "gltf baseColorFactor");
        CHECK(mat_of(&s, 0)->type == TR_MATERIAL_PRINCIPLED,
              "gltf: principled (metallic-roughness)");
    }
    tr_scene_clear(&s);
}

/* Debian's assimp-testmodels (installed by scripts/install-deps): required. */
static void test_installed_models(void) {
    static const struct {
        const char *path;
        uint32_t min_tris, max_tris;
        uint32_t type; /* the type every material of the file maps to */
        int textured;  /* some material has a base colour map that loaded */
    } models[] = {
        {MODELS "/OBJ/spider.obj", 1000, 2000, TR_MATERIAL_DIFFUSE, 1},
        {MODELS "/PLY/Wuson.ply", 3732, 3732, TR_MATERIAL_DIFFUSE, 0},
        {MODELS "/glTF2/BoxTextured-glTF/BoxTextured.gltf", 12, 12, TR_MATERIAL_PRINCIPLED, 1},
        {MODELS "/glTF2/BoxTextured-glTF-Binary/BoxTextured.glb", 12, 12, TR_MATERIAL_PRINCIPLED,
         1},
        {MODELS "/Collada/duck.dae", 4000, 4300, TR_MATERIAL_DIFFUSE, 1},
        /* Partly transparent in the file: cut-outs or opaque, never glass. Its texture lies
         * in ../LWO, outside the model's directory: dropped (a model may not reach outside its
         * directory) unless TRAC0R_MODEL_ROOT allows the whole models tree (the last row). */
        {MODELS "/Collada/teapots.DAE", 1000, 100000, TR_MATERIAL_DIFFUSE, 0},
        {MODELS "/Collada/teapots.DAE", 1000, 100000, TR_MATERIAL_DIFFUSE, 1},
    };
    const size_t allow_row = sizeof models / sizeof models[0] - 1;
    for (size_t i = 0; i < sizeof models / sizeof models[0]; ++i) {
        if (i == allow_row) {
            setenv("TRAC0R_MODEL_ROOT", MODELS, 1);
        }
        tr_scene s = {0};
        tr_scene_init(&s);
        tr_error err;
        tr_mesh_import_stats st;
        int rc = tr_scene_import_mesh(&s, models[i].path, NULL, -1, 0, &st, &err);
        CHECK(rc == TR_OK, "%s (install assimp-testmodels)", err.msg);
        CHECK(st.triangles >= models[i].min_tris && st.triangles <= models[i].max_tris,
              "%s: %u triangles", models[i].path, st.triangles);
        for (uint32_t t = 0; t < s.triangle_count; ++t) {
            if (!(s.triangles[t].area > 0.0f)) {
                CHECK(0, "%s: triangle %u has zero area", models[i].path, t);
                break;
            }
        }
        int textured = 0;
        for (uint32_t m = 0; m < s.material_count; ++m) {
            CHECK(s.materials[m].type == models[i].type, "%s: material %u has type %u",
                  models[i].path, m, s.materials[m].type);
            textured |= s.material_ext_count == s.material_count &&
                        s.material_exts[m].base_tex != TR_NO_INDEX;
        }
        CHECK(textured == models[i].textured, "%s: textured %d", models[i].path, textured);
        CHECK(!textured || s.tri_verts_count > 0, "%s: texture coordinates kept", models[i].path);
        tr_scene_clear(&s);
    }
    unsetenv("TRAC0R_MODEL_ROOT");
}

static void test_add_mesh(void) {
    tr_scene s = {0};
    tr_scene_init(&s);
    tr_error err;
    uint32_t m;
    tr_scene_add_material(&s, tr_material_diffuse(v3s(0.5f)), &m, &err);
    const float pos[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 2, 0, 0};
    const float nrm[] = {1, 1, 0, 1, 1, 0, 1, 1, 0, 1, 1, 0};
    const uint32_t idx[] = {0, 1, 2, 0, 1, 3}; /* the second is degenerate (collinear) */
    tr_transform tf = {v3(0, 0, 0), v3(0, 0, 0), v3(1, 4, 1)};
    uint32_t dropped = 9;
    int rc = tr_scene_add_mesh(&s, pos, 4, idx, 2, nrm, m, &tf, &dropped, &err);
    CHECK(rc == TR_OK && s.triangle_count == 1 && dropped == 1, "add_mesh: %s", err.msg);
    /* Normal (1, 1, 0) under scale (1, 4, 1) goes to (1, 1/4, 0), normalised. */
    const double l = sqrt(1.0 + 1.0 / 16.0);
    tr_vec3 tn[3];
    CHECK(tr_scene_triangle_normals(&s, 0, tn), "normals kept");
    CHECK_NEAR(tn[0].x, 1.0 / l, 1e-6, "inverse-transpose normal x");
    CHECK_NEAR(tn[0].y, 0.25 / l, 1e-6, "inverse-transpose normal y");
    CHECK_NEAR(s.triangles[0].v2.y, 4.0, 1e-6, "scaled position");
    const uint32_t bad[] = {0, 1, 7};
    rc = tr_scene_add_mesh(&s, pos, 4, bad, 1, NULL, m, NULL, NULL, &err);
    CHECK_STATUS(rc, err, TR_STATUS_INVALID_ARGUMENT, "vertex index 7 of 4");
    rc = tr_scene_add_mesh(&s, pos, 4, idx, 2, NULL, 5, NULL, NULL, &err);
    CHECK_STATUS(rc, err, TR_STATUS_NOT_FOUND, "material 5 of 1");
    const float nan_pos[] = {0, 0, 0, NAN, 0, 0, 0, 1, 0};
    rc = tr_scene_add_mesh(&s, nan_pos, 3, idx, 1, NULL, m, NULL, NULL, &err);
    CHECK_STATUS(rc, err, TR_STATUS_INVALID_ARGUMENT, "a NaN vertex");
    CHECK(s.triangle_count == 1 && s.shape_count == 1, "failures add nothing");
    /* A shape after a mesh with normals: the normals array still covers only the mesh. */
    tr_shape_desc d = tr_shape_desc_default(TR_SHAPE_BOX);
    CHECK(tr_scene_add_shape(&s, &d, &err) == TR_OK, "%s", err.msg);
    CHECK(s.tri_verts_count == 1, "normals cover %u triangles", s.tri_verts_count);
    CHECK(!tr_scene_triangle_normals(&s, 1, tn), "the box has none");
    tr_scene_clear(&s);
}

/* The loader from memory: meshes skipped, messages, render defaults, paths. */
static void test_parse_memory(void) {
    const char *text =
        "{\"render\": {\"width\": 64, \"spp\": 3},\n"
        " \"camera\": {\"position\": [0, 0, -2], \"direction\": [0, 0, 1], \"fov\": 45},\n"
        " \"materials\": {\"l\": {\"type\": \"emitter\", \"color\": [1, 1, 1], \"emittance\": 2,"
        " \"two_sided\": true}},\n"
        " \"shapes\": [{\"type\": \"icosphere\", \"subdivisions\": 1, \"material\": \"l\"}],\n"
        " \"meshes\": [{\"path\": \"does-not-exist.obj\"}]}";
    tr_scene s = {0};
    tr_scene_file f;
    tr_error err;
    tr_scene_file_options opt = {0, 0};
    int rc = tr_scene_file_parse(&s, "mem.json", text, strlen(text), &opt, &f, &err);
    CHECK(rc == TR_OK, "%s", err.msg);
    if (rc == TR_OK) {
        CHECK(s.triangle_count == 80 && f.shape_count == 1 && f.mesh_count == 1, "counts");
        CHECK(f.has_width && f.width == 64 && !f.has_height && f.height == 600, "width");
        CHECK(f.has_spp && f.spp == 3, "spp");
        CHECK(s.camera.screen_width == 64 && s.camera.screen_height == 600, "camera size");
        CHECK(s.materials[0].flags == TR_MATERIAL_TWO_SIDED,
              "two_sided sets TR_MATERIAL_TWO_SIDED");
        CHECK(f.emissive_triangles == 80 && f.emitter_materials == 1, "emitters");
        CHECK_NEAR(f.bounds.max.x, 1.0, 1e-6, "bounds");
        tr_scene_clear(&s);
    }
    /* The same with meshes loaded: the missing file is named relative to the scene. */
    opt.load_meshes = 1;
    rc = tr_scene_file_parse(&s, "some/dir/mem.json", text, strlen(text), &opt, &f, &err);
    CHECK_STATUS(rc, err, TR_STATUS_NOT_FOUND, "a missing mesh");
    /* The documented form "FILE: json.path: ...", the mesh named relative to the file. */
    CHECK(rc == TR_ERR && strstr(err.msg, "some/dir/mem.json: meshes[0].path: cannot open "
                                          "'some/dir/does-not-exist.obj'"),
          "%s", err.msg);
    CHECK(s.triangle_count == 0 && s.triangles == NULL, "scene left empty on failure");
    /* A smaller budget. */
    opt.load_meshes = 0;
    opt.max_triangles = 79;
    rc = tr_scene_file_parse(&s, "mem.json", text, strlen(text), &opt, &f, &err);
    CHECK_STATUS(rc, err, TR_STATUS_LIMIT, "a budget of 79 triangles");
    /* Not NUL-terminated: only len bytes are read. */
    char buf[8] = {'{', '}', 'x', 'x', 'x', 'x', 'x', 'x'};
    rc = tr_scene_file_parse(&s, "m.json", buf, 2, NULL, NULL, &err);
    CHECK_STATUS(rc, err, TR_STATUS_PARSE, "only '{}' of '{}xxxxxx'");
    CHECK(rc == TR_ERR && strncmp(err.msg, "m.json: camera: ", 16) == 0, "FILE: PATH: %s", err.msg);
    /* render.light_sampling: the scene keeps it for its commit; an unknown
     * name is refused at its path. */
    const char *ls_text =
        "{\"render\": {\"light_sampling\": \"tree\"},\n"
        " \"camera\": {\"position\": [0, 0, -2], \"direction\": [0, 0, 1], \"fov\": 45},\n"
        " \"materials\": {\"l\": {\"type\": \"emitter\", \"color\": [1, 1, 1], \"emittance\": "
        "2}},\n"
        " \"shapes\": [{\"type\": \"plane\", \"material\": \"l\"}]}";
    rc = tr_scene_file_parse(&s, "ls.json", ls_text, strlen(ls_text), NULL, NULL, &err);
    CHECK(rc == TR_OK, "%s", err.msg);
    CHECK(rc == TR_OK && tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK &&
              tr_scene_light_sampling(&s) == TR_LIGHT_SAMPLING_TREE,
          "render.light_sampling tree: a scene of two emitters is not sampled by the tree");
    char ls_bad[512];
    snprintf(ls_bad, sizeof ls_bad, "%s", ls_text);
    memcpy(strstr(ls_bad, "tree"), "tref", 4);
    rc = tr_scene_file_parse(&s, "ls.json", ls_bad, strlen(ls_bad), NULL, NULL, &err);
    CHECK_STATUS(rc, err, TR_STATUS_PARSE, "light_sampling 'tref'");
    CHECK(rc == TR_ERR && strstr(err.msg, "render.light_sampling"), "%s", err.msg);
    tr_scene_clear(&s);
    /* Line and column count from 1 across lines. */
    const char *bad = "{\n  \"camera\":\n    tru }";
    rc = tr_scene_file_parse(&s, "b.json", bad, strlen(bad), NULL, NULL, &err);
    CHECK_STATUS(rc, err, TR_STATUS_PARSE, "a syntax error");
    CHECK(rc == TR_ERR && strncmp(err.msg, "b.json:3:5: ", 12) == 0, "FILE:LINE:COL: %s", err.msg);
}

/* The classic Cornell box: red wall on the left of the image, green on the right, both
 * in the camera's primary hits and in a small render. */
static void test_cornell_classic(void) {
    tr_scene s = {0};
    tr_scene_file f;
    tr_error err;
    int rc = tr_scene_file_load(&s, TR_SOURCE_DIR "/scenes/cornell-classic.json", NULL, &f, &err);
    CHECK(rc == TR_OK, "%s", err.msg);
    if (rc != TR_OK) {
        return;
    }
    const uint32_t w = 32, h = 32;
    CHECK(tr_camera_resize(&s.camera, w, h, &err) == TR_OK, "%s", err.msg);
    CHECK(s.camera.right.x < -0.99f, "right-handed: the camera's right is -x");
    /* The light faces down: its triangles' normals are -y. */
    int lights = 0;
    for (uint32_t i = 0; i < s.triangle_count; ++i) {
        if (mat_of(&s, i)->type == TR_MATERIAL_EMITTER) {
            lights++;
            CHECK(s.triangles[i].normal.y < -0.999f, "light triangle %u faces down", i);
            CHECK_NEAR(mat_of(&s, i)->color.x * mat_of(&s, i)->emittance, 17.0, 1e-5, "L red");
        }
    }
    CHECK(lights == 2, "%d light triangles", lights);
    /* Primary hits along the middle row: the left edge sees red, the right edge green. */
    const tr_vec3 red = v3(0.65f, 0.05f, 0.05f), green = v3(0.12f, 0.45f, 0.15f);
    for (int side = 0; side < 2; ++side) {
        tr_ray ray = tr_camera_ray(&s.camera, side ? (float)(w - 1) : 0.0f, h / 2.0f, 0.5f, 0.5f);
        float best = INFINITY;
        uint32_t hit = UINT32_MAX;
        for (uint32_t i = 0; i < s.triangle_count; ++i) {
            float t, u, v;
            const tr_triangle *tri = &s.triangles[i];
            if (tr_intersect_triangle(&ray, tri->v0, tri->v1, tri->v2, &t, &u, &v) && t < best) {
                best = t;
                hit = i;
            }
        }
        CHECK(hit != UINT32_MAX, "side %d: no hit", side);
        if (hit != UINT32_MAX) {
            tr_vec3 c = mat_of(&s, hit)->color, want = side ? green : red;
            CHECK(c.x == want.x && c.y == want.y && c.z == want.z,
                  "%s edge sees colour (%g, %g, %g)", side ? "right" : "left", (double)c.x,
                  (double)c.y, (double)c.z);
        }
    }
    /* A small render: the left quarter is red-dominated, the right quarter green. */
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
    tr_film film;
    CHECK(tr_film_init(&film, w, h, &err) == TR_OK, "%s", err.msg);
    tr_render_config cfg = tr_render_config_default();
    cfg.seed = 1;
    for (uint32_t k = 0; k < 64; ++k) {
        CHECK(tr_render_frame(&s, &s.camera, &cfg, &film, k, NULL, &err) == TR_OK, "%s", err.msg);
    }
    double l[3] = {0}, r[3] = {0};
    for (uint32_t y = h / 4; y < 3 * h / 4; ++y) {
        for (uint32_t x = 0; x < w / 4; ++x) {
            tr_vec3 a = tr_film_pixel(&film, x, y), b = tr_film_pixel(&film, w - 1 - x, y);
            l[0] += a.x, l[1] += a.y, l[2] += a.z;
            r[0] += b.x, r[1] += b.y, r[2] += b.z;
        }
    }
    /* Albedo ratios are 13 (red wall) and 3.75 (green wall); indirect light evens
     * them out a little; a mirrored image would invert them. */
    CHECK(l[0] > 3.0 * l[1], "left quarter: red %g vs green %g", l[0], l[1]);
    CHECK(r[1] > 1.5 * r[0], "right quarter: green %g vs red %g", r[1], r[0]);
    tr_film_free(&film);
    tr_scene_clear(&s);
}

int main(void) {
    test_obj();
    test_ply_gltf();
    test_installed_models();
    test_add_mesh();
    test_parse_memory();
    test_cornell_classic();
    return check_finish("test_scene_file");
}
