/* test_model.c - scenes built around model files (src/scene/model.c): their
 * cameras and lights.
 *
 * 1. A glTF file written here with two cameras and KHR_lights_punctual (a point light
 *    and a directional one): the first camera is used, at its node's translation (not
 *    twice it: Assimp 5.2 copies the translation into the camera as well), looking down
 *    the node's -z with glTF's yfov, the image's height taken from its aspect ratio; the
 *    second, on a node turned 90 degrees about +y, by name, looks down -x from its
 *    node; a camera that does not exist is an error; "frame" frames the model. The
 *    directional light becomes the sun (towards -its direction, its colour x intensity
 *    as irradiance), the point light a point light (punctual.h) at its node of
 *    intensity colour x intensity; with lights the environment is Blender's default world
 *    (0.05 grey), which the background shows, and the quad under the point light is lit.
 *    Lights that cannot be had (black, past the emitter's limit) are dropped or adjusted
 *    with warnings, never fail the model.
 * 2. Collada's duck (assimp-testmodels): its camera is placed by the node's translate
 *    and rotations (times the file's unit, centimetres) and its yfov; with the framing
 *    camera the model's pixels (the albedo pass) are centred in the image.
 * 3. A texture the model names by another machine's path and in other case
 *    ("D:\\work\\TEX\\Checker.PNG" for textures/checker.png beside it) is found by its
 *    file name, with a warning; one that exists nowhere is dropped.
 * 4. The framing camera: a box 4 long in z is seen from its side as an OBJ (the larger
 *    silhouette), from +z as glTF (the format's front), and fills 80 % of the image's
 *    width or height without touching its border, the height following 4:3 when only
 *    the width is given.
 * 5. A file's camera or point light inside a closed cube is reported, one warning each; the
 *    enclosed camera gives way to the framing one unless it is asked for by name; a model
 *    whose only light is enclosed gets the default sky.
 * 6. glTF's clear coat (assimp-testmodels' ClearCoatTest.gltf): the six "Coated" materials
 *    become principled with the coat's weight 1 and roughness (0.03, or 1 for the
 *    roughness variations), the others have none; the coat maps the file also uses are
 *    named in warnings. Extensions a glTF file lists in extensionsUsed that trac0r does
 *    not render are named in a warning each.
 * 7. A Silo .sib file written here (a triangle, a material with a texture, a spot light):
 *    Assimp's reader drops the last character of its strings and passes the light's target
 *    point as its direction; the texture is found by the name with one more character
 *    (with a warning) and the spot light points from its position to its target. */
#define _POSIX_C_SOURCE 200809L
#include "check.h"
#include "scene_util.h"
#include "trac0r/device.h"
#include "trac0r/scene_file.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static char dir[512];

/* A quad (x, y in [-1, 1], z = 0, facing +z) under a point light 2 above its centre and
 * a directional light shining down; cameras "front" and "side". */
static const char gltf_fmt[] =
    "{\"asset\": {\"version\": \"2.0\"}, \"extensionsUsed\": [\"KHR_lights_punctual\"],\n"
    " \"extensions\": {\"KHR_lights_punctual\": {\"lights\": [%s]}},\n"
    " \"scene\": 0, \"scenes\": [{\"nodes\": [0, 1, 2, 3, 4]}],\n"
    " \"nodes\": [{\"name\": \"quad\", \"mesh\": 0},\n"
    "   {\"name\": \"front\", \"camera\": 0, \"translation\": [0.5, 0.25, 5.0]},\n"
    "   {\"name\": \"side\", \"camera\": 1, \"translation\": [5.0, 0.0, 0.0],\n"
    "    \"rotation\": [0.0, 0.70710678, 0.0, 0.70710678]},\n"
    "   {\"name\": \"bulb\", \"translation\": [0.0, 0.0, 2.0],\n"
    "    \"extensions\": {\"KHR_lights_punctual\": {\"light\": 0}}},\n"
    "   {\"name\": \"sky\", \"rotation\": [-0.70710678, 0.0, 0.0, 0.70710678],\n"
    "    \"extensions\": {\"KHR_lights_punctual\": {\"light\": 1}}}],\n"
    " \"cameras\": [{\"type\": \"perspective\", \"perspective\": {\"yfov\": 0.5,\n"
    "   \"aspectRatio\": 2.0, \"znear\": 0.1, \"zfar\": 100.0}},\n"
    "   {\"type\": \"perspective\", \"perspective\": {\"yfov\": 0.7, \"aspectRatio\": 1.5,\n"
    "   \"znear\": 0.1, \"zfar\": 100.0}}],\n"
    " \"meshes\": [{\"primitives\": [{\"attributes\": {\"POSITION\": 0}, \"indices\": 1}]}],\n"
    " \"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, \"count\": 4, \"type\": "
    "\"VEC3\",\n"
    "   \"min\": [-1, -1, 0], \"max\": [1, 1, 0]},\n"
    "   {\"bufferView\": 1, \"componentType\": 5123, \"count\": 6, \"type\": \"SCALAR\"}],\n"
    " \"bufferViews\": [{\"buffer\": 0, \"byteOffset\": 0, \"byteLength\": 48},\n"
    "   {\"buffer\": 0, \"byteOffset\": 48, \"byteLength\": 12}],\n"
    " \"buffers\": [{\"byteLength\": 60, \"uri\": \"data:application/octet-stream;base64,"
    "AACAvwAAgL8AAAAAAACAPwAAgL8AAAAAAACAPwAAgD8AAAAAAACAvwAAgD8AAAAAAAABAAIAAAACAAMA\"}]}\n";

static int near3(tr_vec3 a, float x, float y, float z, float tol) {
    return fabsf(a.x - x) <= tol && fabsf(a.y - y) <= tol && fabsf(a.z - z) <= tol;
}

static const char lights_ok[] =
    "{\"type\": \"point\", \"color\": [1.0, 0.5, 0.25], \"intensity\": 4.0},\n"
    " {\"type\": \"directional\", \"color\": [1.0, 1.0, 1.0], \"intensity\": 2.0}";

/* Writes the glTF with the given lights to dir/name; its path in path. */
static void write_gltf(const char *name, const char *lights, char *path, size_t size) {
    snprintf(path, size, "%s/%s", dir, name);
    static char text[8192];
    snprintf(text, sizeof text, gltf_fmt, lights);
    FILE *f = fopen(path, "w");
    CHECK(f && fputs(text, f) >= 0 && fclose(f) == 0, "writing %s", path);
}

static void test_gltf(void) {
    char path[600];
    write_gltf("lit.gltf", lights_ok, path, sizeof path);
    tr_scene s;
    tr_scene_init(&s);
    tr_error err;
    tr_scene_file info;
    tr_model_options opt = {0, 1.0f, 0, 0, NULL};
    if (tr_scene_model_load(&s, path, &opt, &info, &err) != TR_OK) {
        CHECK(0, "%s", err.msg);
        return;
    }
    const tr_camera *cam = &s.camera;
    CHECK(info.width == 800 && info.height == 400 && info.has_height, "image %ux%u (aspect 2)",
          info.width, info.height);
    CHECK(near3(cam->pos, 0.5f, 0.25f, 5.0f, 1e-5f), "front camera at (%g, %g, %g)",
          (double)cam->pos.x, (double)cam->pos.y, (double)cam->pos.z);
    CHECK(near3(cam->dir, 0.0f, 0.0f, -1.0f, 1e-5f) && near3(cam->up, 0.0f, 1.0f, 0.0f, 1e-5f),
          "front camera looks down -z, +y up");
    CHECK(fabsf(cam->vertical_fov - 0.5f * 57.2957795f) < 1e-3f, "vertical fov %g (yfov 0.5)",
          (double)cam->vertical_fov);
    /* The sun: towards +y (the light shines down), irradiance colour x intensity. */
    tr_vec3 sd, se;
    float sa;
    CHECK(tr_scene_sun(&s, &sd, &sa, &se) == 1 && near3(sd, 0.0f, 1.0f, 0.0f, 1e-5f) &&
              near3(se, 2.0f, 2.0f, 2.0f, 1e-3f),
          "sun towards (%g, %g, %g), irradiance %g", (double)sd.x, (double)sd.y, (double)sd.z,
          (double)se.x);
    /* The point light: a punctual light (punctual.h) at (0, 0, 2) of intensity colour x
     * intensity, and no emitter. */
    uint32_t emitters = 0;
    for (uint32_t i = 0; i < s.material_count; ++i) {
        emitters += s.materials[i].type == TR_MATERIAL_EMITTER;
    }
    CHECK(emitters == 0 && s.punctual_count == 1, "%u emitters, %u punctual lights", emitters,
          s.punctual_count);
    if (s.punctual_count == 1) {
        const tr_punctual *l = &s.punctual[0];
        CHECK(l->type == TR_PUNCTUAL_POINT && near3(l->pos, 0.0f, 0.0f, 2.0f, 1e-4f) &&
                  near3(l->intensity, 4.0f, 2.0f, 1.0f, 1e-5f),
              "point light type %u at (%g, %g, %g), intensity (%g, %g, %g)", l->type,
              (double)l->pos.x, (double)l->pos.y, (double)l->pos.z, (double)l->intensity.x,
              (double)l->intensity.y, (double)l->intensity.z);
    }
    CHECK(s.env_count == 1, "the file's lights are lit in Blender's default world");
    /* Rendered through the file's camera: background Blender's world grey, the quad lit. */
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
    tr_camera c = s.camera;
    CHECK(tr_camera_resize(&c, 32, 16, &err) == TR_OK, "%s", err.msg);
    tr_film film;
    CHECK(tr_film_init(&film, 32, 16, &err) == TR_OK, "%s", err.msg);
    tr_render_config cfg = tr_render_config_default();
    cfg.max_depth = 4;
    for (uint32_t k = 0; k < 4; ++k) {
        CHECK(tr_render_frame(&s, &c, &cfg, &film, k, NULL, &err) == TR_OK, "%s", err.msg);
    }
    tr_vec3 corner = tr_film_pixel(&film, 0, 0), centre = tr_film_pixel(&film, 14, 9);
    CHECK(corner.x == TR_MODEL_WORLD && corner.y == TR_MODEL_WORLD && corner.z == TR_MODEL_WORLD,
          "background (%g, %g, %g), not the world's grey", (double)corner.x, (double)corner.y,
          (double)corner.z);
    CHECK(centre.x > 0.0f && centre.x > centre.y && centre.y > centre.z,
          "the quad lit by the orange bulb: (%g, %g, %g)", (double)centre.x, (double)centre.y,
          (double)centre.z);
    tr_film_free(&film);

    /* The second camera by its node's name. */
    opt.camera = "side";
    CHECK(tr_scene_model_load(&s, path, &opt, &info, &err) == TR_OK, "%s", err.msg);
    CHECK(near3(s.camera.pos, 5.0f, 0.0f, 0.0f, 1e-4f) &&
              near3(s.camera.dir, -1.0f, 0.0f, 0.0f, 1e-4f),
          "side camera at (%g, %g, %g) looking (%g, %g, %g)", (double)s.camera.pos.x,
          (double)s.camera.pos.y, (double)s.camera.pos.z, (double)s.camera.dir.x,
          (double)s.camera.dir.y, (double)s.camera.dir.z);
    CHECK(info.height == 533 && fabsf(s.camera.vertical_fov - 0.7f * 57.2957795f) < 1e-3f,
          "side camera: %u high, fov %g", info.height, (double)s.camera.vertical_fov);
    opt.camera = "1";
    CHECK(tr_scene_model_load(&s, path, &opt, &info, &err) == TR_OK &&
              near3(s.camera.pos, 5.0f, 0.0f, 0.0f, 1e-4f),
          "camera 1 is the side camera");
    opt.camera = "2";
    CHECK(tr_scene_model_load(&s, path, &opt, &info, &err) == TR_ERR &&
              err.code == TR_STATUS_NOT_FOUND,
          "no camera 2");
    opt.camera = "frame";
    CHECK(tr_scene_model_load(&s, path, &opt, &info, &err) == TR_OK && info.height == 600 &&
              !near3(s.camera.pos, 0.5f, 0.25f, 5.0f, 0.1f),
          "frame: the framing camera");
    tr_scene_clear(&s);
    unlink(path);
}

/* Lights that cannot be had are dropped or adjusted with a warning, and the model still
 * loads: a spot light of huge intensity is kept (a punctual light has no radiance limit),
 * a black directional light is dropped (no sun). */
static void test_gltf_odd_lights(void) {
    char path[600];
    write_gltf("odd.gltf",
               "{\"type\": \"spot\", \"intensity\": 1e30, \"spot\": {}},\n"
               " {\"type\": \"directional\", \"color\": [0, 0, 0], \"intensity\": 3.0}",
               path, sizeof path);
    tr_scene s;
    tr_scene_init(&s);
    tr_error err;
    tr_scene_file info;
    tr_model_options opt = {0, 1.0f, 0, 0, NULL};
    CHECK(tr_scene_model_load(&s, path, &opt, &info, &err) == TR_OK, "%s", err.msg);
    uint32_t emitters = 0;
    for (uint32_t i = 0; i < s.material_count; ++i) {
        emitters += s.materials[i].type == TR_MATERIAL_EMITTER;
    }
    CHECK(emitters <= 1 && tr_scene_sun(&s, NULL, NULL, NULL) == 0,
          "odd lights: %u emitters, no sun from a black light", emitters);
    CHECK(s.punctual_count == 1 && s.punctual[0].type == TR_PUNCTUAL_SPOT,
          "the spot light kept as one (%u punctual lights)", s.punctual_count);
    CHECK(s.env_count == 1 && s.env.color.x * s.env.strength == TR_MODEL_WORLD,
          "a light left: the world's grey, not the default sky");
    CHECK(info.warning_count >= 2, "odd lights: %u warnings", info.warning_count);
    tr_scene_clear(&s);
    unlink(path);
}

/* A glTF spot light keeps its cone: KHR_lights_punctual's half-angles (which Assimp's glTF
 * importer stores as they are) become the outer and inner cones, around the node's -z. */
static void test_gltf_spot(void) {
    char path[600];
    write_gltf("spot.gltf",
               "{\"type\": \"spot\", \"intensity\": 3.0, \"spot\": {\"innerConeAngle\": 0.2, "
               "\"outerConeAngle\": 0.5}},\n"
               " {\"type\": \"directional\", \"intensity\": 1.0}",
               path, sizeof path);
    tr_scene s;
    tr_scene_init(&s);
    tr_error err;
    tr_scene_file info;
    tr_model_options opt = {0, 1.0f, 0, 0, NULL};
    CHECK(tr_scene_model_load(&s, path, &opt, &info, &err) == TR_OK, "%s", err.msg);
    CHECK(s.punctual_count == 1, "%u punctual lights", s.punctual_count);
    if (s.punctual_count == 1) {
        const tr_punctual *l = &s.punctual[0];
        CHECK(l->type == TR_PUNCTUAL_SPOT && near3(l->pos, 0.0f, 0.0f, 2.0f, 1e-4f) &&
                  near3(l->dir, 0.0f, 0.0f, -1.0f, 1e-5f) && l->intensity.y == 3.0f,
              "spot type %u at (%g, %g, %g) along (%g, %g, %g)", l->type, (double)l->pos.x,
              (double)l->pos.y, (double)l->pos.z, (double)l->dir.x, (double)l->dir.y,
              (double)l->dir.z);
        CHECK(fabs(l->cos_outer - cos(0.5)) < 1e-6 && fabs(l->cos_inner - cos(0.2)) < 1e-6,
              "spot cones: cos %g and %g", (double)l->cos_outer, (double)l->cos_inner);
    }
    tr_scene_clear(&s);
    unlink(path);
}

#define DUCK "/usr/share/assimp/models/Collada/duck.dae"

static void test_duck(void) {
    tr_scene s;
    tr_scene_init(&s);
    tr_error err;
    tr_scene_file info;
    tr_model_options opt = {0, 1.0f, 0, 0, NULL};
    if (tr_scene_model_load(&s, DUCK, &opt, &info, &err) != TR_OK) {
        CHECK(0, "%s", err.msg);
        return;
    }
    /* <translate>400.113 463.264 -431.078</translate> in centimetres; rotateY -223.2, then
     * rotateX -38.4 (applied first) turn the camera's -z. */
    const double ry = -223.2 * 3.14159265358979 / 180.0, rx = -38.4 * 3.14159265358979 / 180.0;
    const double d1y = sin(rx), d1z = -cos(rx); /* Rx (0, 0, -1) */
    const tr_vec3 want = v3((float)(d1z * sin(ry)), (float)d1y, (float)(d1z * cos(ry)));
    CHECK(near3(s.camera.pos, 4.00113f, 4.63264f, -4.31078f, 1e-4f), "duck camera at (%g, %g, %g)",
          (double)s.camera.pos.x, (double)s.camera.pos.y, (double)s.camera.pos.z);
    CHECK(near3(s.camera.dir, want.x, want.y, want.z, 1e-4f), "duck camera looks (%g, %g, %g)",
          (double)s.camera.dir.x, (double)s.camera.dir.y, (double)s.camera.dir.z);
    CHECK(info.height == 533 && fabsf(s.camera.vertical_fov - 37.8492f) < 0.05f,
          "duck camera: %u high, fov %g", info.height, (double)s.camera.vertical_fov);

    /* A width alone keeps the file camera's aspect (3:2): 200 wide is 133 high. */
    {
        tr_scene *o = tr_scene_create(&err);
        tr_scene_open_desc d = {0};
        d.request.width = 200;
        tr_render_settings st;
        CHECK(o && tr_scene_open(o, DUCK, &d, NULL, &st, &err) == TR_OK, "%s", err.msg);
        CHECK(st.width == 200 && st.height == 133, "duck at width 200: %ux%u", st.width, st.height);
        tr_scene_destroy(o);
    }
    /* The framing camera centres the model. */
    opt.camera = "frame";
    CHECK(tr_scene_model_load(&s, DUCK, &opt, &info, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
    const uint32_t w = 64, h = 48;
    tr_camera c = s.camera;
    CHECK(tr_camera_resize(&c, w, h, &err) == TR_OK, "%s", err.msg);
    tr_film film;
    CHECK(tr_film_init_passes(&film, w, h, TR_PASS_ALBEDO, &err) == TR_OK, "%s", err.msg);
    tr_render_config cfg = tr_render_config_default();
    cfg.passes = TR_PASS_ALBEDO;
    cfg.max_depth = 1;
    CHECK(tr_render_frame(&s, &c, &cfg, &film, 0, NULL, &err) == TR_OK, "%s", err.msg);
    double n = 0.0, sx = 0.0, sy = 0.0;
    for (uint32_t y = 0; y < h; ++y) {
        for (uint32_t x = 0; x < w; ++x) {
            float a[3];
            tr_film_pass_pixel(&film, TR_PASS_ALBEDO, x, y, a, &err);
            if (a[0] + a[1] + a[2] > 0.0f) {
                n += 1.0;
                sx += (x + 0.5) / w;
                sy += (y + 0.5) / h;
            }
        }
    }
    CHECK(n > 0.05 * w * h, "the duck covers %.0f pixels", n);
    CHECK(n > 0.0 && fabs(sx / n - 0.5) < 0.08 && fabs(sy / n - 0.5) < 0.08,
          "framed duck's centroid (%.3f, %.3f)", n > 0 ? sx / n : 0.0, n > 0 ? sy / n : 0.0);
    printf("framed duck: %.0f pixels, centroid (%.3f, %.3f)\n", n, sx / n, sy / n);
    tr_film_free(&film);
    tr_scene_clear(&s);
}

static void write_text(const char *path, const char *text);

#define CLEARCOAT "/usr/share/assimp/models/glTF2/ClearCoat-glTF/ClearCoatTest.gltf"

static void test_clearcoat(void) {
    tr_scene s;
    tr_scene_init(&s);
    tr_error err;
    tr_scene_file info;
    tr_model_options opt = {0, 1.0f, 0, 0, NULL};
    if (tr_scene_model_load(&s, CLEARCOAT, &opt, &info, &err) != TR_OK) {
        CHECK(0, "%s", err.msg);
        return;
    }
    int coated = 0, smooth = 0, rough = 0, other = 0, weight_maps = 0, rough_maps = 0;
    int normal_maps = 0;
    for (uint32_t i = 0; i < s.material_count; ++i) {
        const int has =
            s.material_ext_count == s.material_count && s.material_exts[i].clearcoat > 0.0f;
        if (!has) {
            continue;
        }
        coated +=
            s.materials[i].type == TR_MATERIAL_PRINCIPLED && s.material_exts[i].clearcoat == 1.0f;
        smooth += fabsf(s.material_exts[i].clearcoat_roughness - 0.03f) < 1e-6f;
        rough += s.material_exts[i].clearcoat_roughness == 1.0f;
        other += s.materials[i].type != TR_MATERIAL_PRINCIPLED;
        weight_maps += s.material_exts[i].clearcoat_tex != TR_NO_INDEX;
        rough_maps += s.material_exts[i].clearcoat_rough_tex != TR_NO_INDEX;
        normal_maps += s.material_exts[i].clearcoat_normal_tex != TR_NO_INDEX;
    }
    CHECK(coated == 6 && smooth == 5 && rough == 1 && other == 0,
          "ClearCoatTest: %d coated principled materials (%d smooth, %d rough, %d not principled) "
          "of %u",
          coated, smooth, rough, other, s.material_count);
    /* The partial coat's weight map, the rough coat's roughness map and the two coats'
     * normal maps are read; one coating blends alpha: one warning. */
    CHECK(weight_maps == 1 && rough_maps == 1 && normal_maps == 2,
          "ClearCoatTest: %d coat weight maps, %d coat roughness maps, %d coat normal maps",
          weight_maps, rough_maps, normal_maps);
    CHECK(info.warning_count == 1, "ClearCoatTest: %u warnings", info.warning_count);
    tr_scene_clear(&s);

    /* Extensions the file lists and trac0r does not render: one warning each more than
     * the same file without them. */
    char path[600];
    write_gltf("lit.gltf", lights_ok, path, sizeof path);
    tr_scene_init(&s);
    CHECK(tr_scene_model_load(&s, path, &opt, &info, &err) == TR_OK, "%s", err.msg);
    const uint32_t plain = info.warning_count;
    tr_scene_clear(&s);
    static char text[8192];
    snprintf(text, sizeof text, gltf_fmt, lights_ok);
    const char *used = "[\"KHR_lights_punctual\"]";
    char *at = strstr(text, used);
    CHECK(at != NULL, "the test's glTF lists its extensions");
    if (at) {
        static char more[8400];
        snprintf(more, sizeof more,
                 "%.*s[\"KHR_lights_punctual\", \"KHR_materials_iridescence\", "
                 "\"KHR_materials_anisotropy\"]%s",
                 (int)(at - text), text, at + strlen(used));
        snprintf(path, sizeof path, "%s/ext.gltf", dir);
        write_text(path, more);
        tr_scene_init(&s);
        CHECK(tr_scene_model_load(&s, path, &opt, &info, &err) == TR_OK, "%s", err.msg);
        CHECK(info.warning_count == plain + 2, "two unrendered extensions: %u warnings, %u without",
              info.warning_count, plain);
        tr_scene_clear(&s);
        unlink(path);
    }
    snprintf(path, sizeof path, "%s/lit.gltf", dir);
    unlink(path);
}

static void write_text(const char *path, const char *text) {
    FILE *f = fopen(path, "w");
    CHECK(f && fputs(text, f) >= 0 && fclose(f) == 0, "cannot write %s", path);
}

static void test_texture_fallback(void) {
    char sub[600], tex[700], png[800], obj[700], mtl[700];
    snprintf(sub, sizeof sub, "%s/fb", dir);
    snprintf(tex, sizeof tex, "%s/textures", sub);
    snprintf(png, sizeof png, "%s/checker.png", tex);
    snprintf(obj, sizeof obj, "%s/m.obj", sub);
    snprintf(mtl, sizeof mtl, "%s/m.mtl", sub);
    CHECK(mkdir(sub, 0700) == 0 && mkdir(tex, 0700) == 0, "mkdir %s", tex);
    tr_error err;
    tr_film film;
    CHECK(tr_film_init(&film, 4, 4, &err) == TR_OK, "%s", err.msg);
    for (size_t i = 0; i < 16; ++i) {
        film.count[i] = 1;
        film.sum[3 * i] = film.sum[3 * i + 1] = film.sum[3 * i + 2] = (float)(i % 2);
    }
    CHECK(tr_film_write_png(&film, png, 0.0f, &err) == TR_OK, "%s", err.msg);
    tr_film_free(&film);
    write_text(obj, "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n"
                    "usemtl moved\nf 1/1 2/2 3/3\nusemtl gone\nf 1/1 3/3 2/2\n");
    const char *maps[2] = {"D:\\work\\TEX\\Checker.PNG", "nowhere.png"};
    const char *names[2] = {"moved", "gone"};
    char text[400];
    snprintf(text, sizeof text, "newmtl %s\nKd 1 1 1\nmap_Kd %s\nnewmtl %s\nKd 1 1 1\nmap_Kd %s\n",
             names[0], maps[0], names[1], maps[1]);
    write_text(mtl, text);
    tr_scene *s = tr_scene_create(&err);
    tr_scene_file info;
    const tr_model_options opt = {0, 1.0f, 0, 0, NULL};
    CHECK(s && tr_scene_model_load(s, obj, &opt, &info, &err) == TR_OK, "%s", err.msg);
    int moved = -1, gone = -1;
    for (uint32_t i = 0; s && i < tr_scene_material_count(s); ++i) {
        const int base = (tr_scene_material_maps(s, i) & TR_MAP_BASE) != 0;
        /* Materials keep the file's order after the importer's default one, if any. */
        if (moved < 0 && base) {
            moved = (int)i;
        } else if (!base) {
            gone = (int)i;
        }
    }
    CHECK(moved >= 0, "the moved texture was not found by its file name");
    CHECK(gone >= 0 && info.warning_count >= 2, "%u warnings (found, dropped)", info.warning_count);
    tr_scene_destroy(s);
    remove(png);
    remove(obj);
    remove(mtl);
    rmdir(tex);
    rmdir(sub);
}

/* Renders the framing camera's view of the model at `path` (width w, height left to the
 * 4:3 default) and returns the object's pixel bounds in b[0..3] (x0, x1, y0, y1). */
static void frame_bounds(const char *path, uint32_t w, tr_vec3 *view, int b[4]) {
    tr_error err;
    tr_scene *s = tr_scene_create(&err);
    tr_scene_file info;
    const tr_model_options opt = {0, 1.0f, w, 0, "frame"};
    b[0] = b[2] = 1 << 30;
    b[1] = b[3] = -1;
    CHECK(s && tr_scene_model_load(s, path, &opt, &info, &err) == TR_OK, "%s", err.msg);
    CHECK(s && tr_scene_commit(s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
    if (!s) {
        return;
    }
    const tr_camera *c = tr_scene_camera(s);
    *view = c->dir;
    CHECK(c->screen_width == w && c->screen_height == w * 3 / 4, "framing camera %ux%u",
          c->screen_width, c->screen_height);
    tr_film film;
    CHECK(tr_film_init_passes(&film, c->screen_width, c->screen_height, TR_PASS_ALBEDO, &err) ==
              TR_OK,
          "%s", err.msg);
    tr_render_config cfg = tr_render_config_default();
    cfg.passes = TR_PASS_ALBEDO;
    cfg.max_depth = 1;
    CHECK(tr_render_frame(s, c, &cfg, &film, 0, NULL, &err) == TR_OK, "%s", err.msg);
    for (uint32_t y = 0; y < c->screen_height; ++y) {
        for (uint32_t x = 0; x < c->screen_width; ++x) {
            float a[3];
            tr_film_pass_pixel(&film, TR_PASS_ALBEDO, x, y, a, &err);
            if (a[0] + a[1] + a[2] > 0.0f) {
                b[0] = (int)x < b[0] ? (int)x : b[0];
                b[1] = (int)x > b[1] ? (int)x : b[1];
                b[2] = (int)y < b[2] ? (int)y : b[2];
                b[3] = (int)y > b[3] ? (int)y : b[3];
            }
        }
    }
    tr_film_free(&film);
    tr_scene_destroy(s);
}

/* A model without a camera is framed across its larger silhouette and fills the frame;
 * glTF's front (+z) is seen whatever the silhouettes. A box 0.5 wide, 1 high and 4 long
 * in z: from the side (along x) as an OBJ, from +z as glTF. */
static void test_framing(void) {
    char obj[700], gltf[700];
    snprintf(obj, sizeof obj, "%s/long.obj", dir);
    snprintf(gltf, sizeof gltf, "%s/long.gltf", dir);
    write_text(obj, "v -0.25 0 -2\nv 0.25 0 -2\nv 0.25 1 -2\nv -0.25 1 -2\n"
                    "v -0.25 0 2\nv 0.25 0 2\nv 0.25 1 2\nv -0.25 1 2\n"
                    "f 1 2 3 4\nf 8 7 6 5\nf 1 5 6 2\nf 4 3 7 8\nf 1 4 8 5\nf 2 6 7 3\n");
    const uint32_t w = 96, h = 72;
    tr_vec3 d;
    int b[4];
    frame_bounds(obj, w, &d, b);
    CHECK(fabsf(d.x) > 2.0f * fabsf(d.z), "long OBJ seen along (%g, %g, %g), not its side",
          (double)d.x, (double)d.y, (double)d.z);
    /* Filling: the longer extent reaches the 5 % margin on one axis (within two pixels),
     * and nothing touches the border. */
    const int span_x = b[1] - b[0] + 1, span_y = b[3] - b[2] + 1;
    CHECK(b[0] > 0 && b[1] < (int)w - 1 && b[2] > 0 && b[3] < (int)h - 1,
          "box touches the border: x %d..%d, y %d..%d", b[0], b[1], b[2], b[3]);
    CHECK(span_x >= (int)(0.8f * w) || span_y >= (int)(0.8f * h), "box spans %d x %d of %u x %u",
          span_x, span_y, w, h);
    printf("framed long box: x %d..%d, y %d..%d of %ux%u\n", b[0], b[1], b[2], b[3], w, h);
    remove(obj);
    /* glTF: a quad in the y-z plane, 4 long in z; its larger silhouette is along x, but
     * the format's front is +z. */
    write_text(
        gltf,
        "{\"asset\": {\"version\": \"2.0\"}, \"scene\": 0, \"scenes\": [{\"nodes\": "
        "[0]}],\n \"nodes\": [{\"mesh\": 0}],\n \"meshes\": [{\"primitives\": "
        "[{\"attributes\": {\"POSITION\": 0}, \"indices\": 1}]}],\n"
        " \"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, \"count\": 4, "
        "\"type\": \"VEC3\", \"min\": [0, 0, -2], \"max\": [0, 1, 2]},\n"
        "   {\"bufferView\": 1, \"componentType\": 5123, \"count\": 6, \"type\": "
        "\"SCALAR\"}],\n \"bufferViews\": [{\"buffer\": 0, \"byteOffset\": 0, "
        "\"byteLength\": 48},\n   {\"buffer\": 0, \"byteOffset\": 48, \"byteLength\": "
        "12}],\n \"buffers\": [{\"byteLength\": 60, \"uri\": "
        "\"data:application/octet-stream;base64,"
        "AAAAAAAAAAAAAADAAAAAAAAAAAAAAABAAAAAAAAAgD8AAABAAAAAAAAAgD8AAADAAAABAAIAAAACAAMA\"}]}"
        "\n");
    frame_bounds(gltf, w, &d, b);
    CHECK(d.z < 0.0f && fabsf(d.z) > 2.0f * fabsf(d.x), "glTF seen along (%g, %g, %g), not -z",
          (double)d.x, (double)d.y, (double)d.z);
    remove(gltf);
}

/* A closed cube (+-1, outward winding) with a camera and a point light at the given
 * translations. */
static void write_cube(const char *path, const char *cam, const char *lamp) {
    char text[4096];
    snprintf(
        text, sizeof text,
        "{\"asset\": {\"version\": \"2.0\"}, \"extensionsUsed\": [\"KHR_lights_punctual\"],\n"
        " \"extensions\": {\"KHR_lights_punctual\": {\"lights\": [{\"type\": \"point\", "
        "\"color\": [1, 1, 1], \"intensity\": 5}]}},\n"
        " \"scene\": 0, \"scenes\": [{\"nodes\": [0, 1, 2]}],\n"
        " \"nodes\": [{\"mesh\": 0}, {\"name\": \"eye\", \"camera\": 0, \"translation\": [%s]},\n"
        "   {\"name\": \"lamp\", \"translation\": [%s], \"extensions\": "
        "{\"KHR_lights_punctual\": {\"light\": 0}}}],\n"
        " \"cameras\": [{\"type\": \"perspective\", \"perspective\": {\"yfov\": 0.7, "
        "\"znear\": 0.01, \"zfar\": 100}}],\n"
        " \"meshes\": [{\"primitives\": [{\"attributes\": {\"POSITION\": 0}, \"indices\": 1}]}],\n"
        " \"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, \"count\": 8, \"type\": "
        "\"VEC3\", \"min\": [-1, -1, -1], \"max\": [1, 1, 1]},\n"
        "   {\"bufferView\": 1, \"componentType\": 5123, \"count\": 36, \"type\": \"SCALAR\"}],\n"
        " \"bufferViews\": [{\"buffer\": 0, \"byteOffset\": 0, \"byteLength\": 96},\n"
        "   {\"buffer\": 0, \"byteOffset\": 96, \"byteLength\": 72}],\n"
        " \"buffers\": [{\"byteLength\": 168, \"uri\": \"data:application/octet-stream;base64,"
        "AACAvwAAgL8AAIC/AACAvwAAgL8AAIA/AACAvwAAgD8AAIC/AACAvwAAgD8AAIA/AACAPwAAgL8AAIC/"
        "AACAPwAAgL8AAIA/AACAPwAAgD8AAIC/AACAPwAAgD8AAIA/AAADAAIAAAABAAMABAAGAAcABAAHAAUA"
        "AAAEAAUAAAAFAAEAAgAHAAYAAgADAAcAAAAGAAQAAAACAAYAAQAFAAcAAQAHAAMA\"}]}\n",
        cam, lamp);
    write_text(path, text);
}

/* The environment's radiance of the last cube loaded by cube_warnings_at. */
static float cube_world;

/* The warnings of the cube with its camera and lamp at cam and lamp, the camera given as
 * `which` (NULL: the file's first); *pos gets where the scene's camera ended up. */
static uint32_t cube_warnings_at(const char *path, const char *cam, const char *lamp,
                                 const char *which, tr_vec3 *pos) {
    write_cube(path, cam, lamp);
    tr_error err;
    tr_scene *s = tr_scene_create(&err);
    tr_scene_file info;
    memset(&info, 0, sizeof info);
    const tr_model_options opt = {0, 1.0f, 0, 0, which};
    CHECK(s && tr_scene_model_load(s, path, &opt, &info, &err) == TR_OK, "%s", err.msg);
    *pos = s ? tr_scene_camera(s)->pos : v3s(0.0f);
    cube_world = s && s->env_count == 1 ? s->env.color.x * s->env.strength : 0.0f;
    tr_scene_destroy(s);
    remove(path);
    return info.warning_count;
}

static uint32_t cube_warnings(const char *path, const char *cam, const char *lamp) {
    tr_vec3 pos;
    return cube_warnings_at(path, cam, lamp, NULL, &pos);
}

/* A file's camera and lamp inside the model's closed geometry are each reported: the same
 * cube gets one warning more with its camera inside than with both outside, and two with
 * its lamp inside: the lamp, and that every light of the file is inside geometry, so that
 * the model gets the default sky (its radiance, where the lamp outside leaves Blender's dim
 * world). */
static void test_enclosed(void) {
    char path[700];
    snprintf(path, sizeof path, "%s/cube.gltf", dir);
    const uint32_t out = cube_warnings(path, "0, 0, 5", "0, 3, 3");
    const float world_out = cube_world;
    const uint32_t both = cube_warnings(path, "0.1, 0.2, 0.5", "0.2, 0.3, -0.4");
    const uint32_t cam = cube_warnings(path, "0.1, 0.2, 0.5", "0, 3, 3");
    const uint32_t lamp = cube_warnings(path, "0, 0, 5", "0.2, 0.3, -0.4");
    const float world_in = cube_world;
    CHECK(both == out + 3 && cam == out + 1 && lamp == out + 2,
          "warnings: outside %u, both inside %u, camera %u, lamp %u", out, both, cam, lamp);
    CHECK(world_out == TR_MODEL_WORLD && world_in == TR_MODEL_SKY,
          "environment %g with the lamp outside the cube, %g with it inside", (double)world_out,
          (double)world_in);
    /* The enclosed camera is replaced by the framing one (outside the cube) unless it is
     * asked for by name; one outside is kept. */
    tr_vec3 p;
    cube_warnings_at(path, "0.1, 0.2, 0.5", "0, 3, 3", NULL, &p);
    CHECK(fmaxf(fabsf(p.x), fmaxf(fabsf(p.y), fabsf(p.z))) > 1.5f,
          "the enclosed camera was kept: (%g, %g, %g)", (double)p.x, (double)p.y, (double)p.z);
    const uint32_t named = cube_warnings_at(path, "0.1, 0.2, 0.5", "0, 3, 3", "eye", &p);
    CHECK(named == cam && fabsf(p.x - 0.1f) < 1e-4f && fabsf(p.y - 0.2f) < 1e-4f &&
              fabsf(p.z - 0.5f) < 1e-4f,
          "the camera named 'eye' is at (%g, %g, %g), %u warnings", (double)p.x, (double)p.y,
          (double)p.z, named);
    cube_warnings_at(path, "0, 0, 5", "0, 3, 3", NULL, &p);
    CHECK(fabsf(p.z - 5.0f) < 1e-4f, "the camera outside moved to (%g, %g, %g)", (double)p.x,
          (double)p.y, (double)p.z);
}

/* A growing byte buffer for a .sib file: little-endian numbers, tags as written. */
typedef struct sib_buf {
    unsigned char b[2048];
    size_t n;
} sib_buf;

static void sib_bytes(sib_buf *s, const void *p, size_t k) {
    if (s->n + k <= sizeof s->b) {
        memcpy(s->b + s->n, p, k);
    }
    s->n += k;
}
static void sib_u32(sib_buf *s, uint32_t v) {
    const unsigned char b[4] = {(unsigned char)v, (unsigned char)(v >> 8), (unsigned char)(v >> 16),
                                (unsigned char)(v >> 24)};
    sib_bytes(s, b, 4);
}
static void sib_f32(sib_buf *s, float f) {
    uint32_t v;
    memcpy(&v, &f, 4);
    sib_u32(s, v);
}
/* A chunk: its tag, then its body's size, then the body. */
static void sib_chunk(sib_buf *s, const char *tag, const sib_buf *body) {
    sib_bytes(s, tag, 4);
    sib_u32(s, (uint32_t)body->n);
    sib_bytes(s, body->b, body->n);
}
/* A string as Silo writes it: UTF-16LE, with no terminator. */
static void sib_string(sib_buf *s, const char *text) {
    for (const char *c = text; *c; ++c) {
        const unsigned char w[2] = {(unsigned char)*c, 0};
        sib_bytes(s, w, 2);
    }
}

static void test_sib(void) {
    char sub[600], png[700], path[700];
    snprintf(sub, sizeof sub, "%s/sib", dir);
    snprintf(png, sizeof png, "%s/wood.png", sub);
    snprintf(path, sizeof path, "%s/m.sib", sub);
    CHECK(mkdir(sub, 0700) == 0, "mkdir %s", sub);
    tr_error err;
    tr_film film;
    CHECK(tr_film_init(&film, 2, 2, &err) == TR_OK, "%s", err.msg);
    for (size_t i = 0; i < 4; ++i) {
        film.count[i] = 1;
        film.sum[3 * i] = film.sum[3 * i + 1] = film.sum[3 * i + 2] = 0.5f;
    }
    CHECK(tr_film_write_png(&film, png, 0.0f, &err) == TR_OK, "%s", err.msg);
    tr_film_free(&film);

    sib_buf file = {.n = 0}, body = {.n = 0}, part = {.n = 0};
    sib_u32(&body, 1u); /* version */
    sib_chunk(&file, "HEAD", &body);
    /* The material: four colours of four floats, shininess, name, texture. */
    body.n = 0;
    for (int k = 0; k < 16; ++k) {
        sib_f32(&body, k < 3 ? 0.8f : k == 3 ? 1.0f : 0.0f);
    }
    sib_u32(&body, 10u);
    sib_u32(&body, 2u * 4u);
    sib_string(&body, "Wood");
    sib_u32(&body, 2u * 8u);
    sib_string(&body, "wood.png");
    sib_chunk(&file, "MATR", &body);
    /* The shape: three vertices, one face, the face's material the file's first. */
    sib_buf shape = {.n = 0};
    part.n = 0;
    const float v[9] = {-1, 0, -1, 1, 0, -1, 0, 0, 1};
    for (int k = 0; k < 9; ++k) {
        sib_f32(&part, v[k]);
    }
    sib_chunk(&shape, "VRTS", &part);
    part.n = 0;
    sib_u32(&part, 3u);
    for (uint32_t k = 0; k < 3; ++k) {
        sib_u32(&part, k);
    }
    sib_chunk(&shape, "FACS", &part);
    part.n = 0;
    sib_u32(&part, 0u);
    sib_u32(&part, 0u);
    sib_chunk(&shape, "FAMA", &part);
    part.n = 0;
    sib_string(&part, "Tri");
    sib_chunk(&shape, "SNAM", &part);
    sib_chunk(&file, "SHAP", &shape);
    /* A spot light at (0, 2, 0) whose target is (1, 0, 0). */
    sib_buf light = {.n = 0};
    part.n = 0;
    sib_u32(&part, 1u); /* spot */
    const float pos_target[6] = {0, 2, 0, 1, 0, 0};
    for (int k = 0; k < 6; ++k) {
        sib_f32(&part, pos_target[k]);
    }
    for (int k = 0; k < 12; ++k) {
        sib_f32(&part, 1.0f); /* diffuse, ambient and specular colours, four floats each */
    }
    sib_f32(&part, 1.0f);  /* spot exponent */
    sib_f32(&part, 30.0f); /* cutoff, degrees */
    sib_f32(&part, 1.0f);  /* constant, linear, quadratic attenuation */
    sib_f32(&part, 0.0f);
    sib_f32(&part, 0.0f);
    sib_chunk(&light, "LNFO", &part);
    part.n = 0;
    sib_string(&part, "Lamp");
    sib_chunk(&light, "SNAM", &part);
    sib_chunk(&file, "LGHT", &light);
    CHECK(file.n <= sizeof file.b, "the .sib file is %zu bytes", file.n);
    FILE *f = fopen(path, "wb");
    CHECK(f && fwrite(file.b, 1, file.n, f) == file.n && fclose(f) == 0, "writing %s", path);

    tr_scene s;
    tr_scene_init(&s);
    tr_scene_file info;
    const tr_model_options opt = {0, 1.0f, 0, 0, NULL};
    CHECK(tr_scene_model_load(&s, path, &opt, &info, &err) == TR_OK, "%s", err.msg);
    int textured = 0;
    for (uint32_t i = 0; i < tr_scene_material_count(&s); ++i) {
        textured |= (tr_scene_material_maps(&s, i) & TR_MAP_BASE) != 0;
    }
    CHECK(textured, "the texture named 'wood.png' (read as 'wood.pn') was not found");
    CHECK(s.punctual_count == 1, "%u punctual lights", s.punctual_count);
    if (s.punctual_count == 1) {
        const tr_punctual *l = &s.punctual[0];
        const float r = 1.0f / sqrtf(5.0f);
        CHECK(l->type == TR_PUNCTUAL_SPOT && near3(l->pos, 0.0f, 2.0f, 0.0f, 1e-5f) &&
                  near3(l->dir, r, -2.0f * r, 0.0f, 1e-5f),
              "spot type %u at (%g, %g, %g) along (%g, %g, %g)", l->type, (double)l->pos.x,
              (double)l->pos.y, (double)l->pos.z, (double)l->dir.x, (double)l->dir.y,
              (double)l->dir.z);
    }
    tr_scene_clear(&s);
    remove(png);
    remove(path);
    rmdir(sub);
}

int main(void) {
    const char *tmp = getenv("TMPDIR");
    snprintf(dir, sizeof dir, "%s/trac0r-test-model-XXXXXX", tmp && *tmp ? tmp : "/tmp");
    if (!mkdtemp(dir)) {
        perror("mkdtemp");
        return 1;
    }
    test_gltf();
    test_gltf_odd_lights();
    test_gltf_spot();
    test_duck();
    test_clearcoat();
    test_texture_fallback();
    test_framing();
    test_enclosed();
    test_sib();
    rmdir(dir);
    return check_finish("test_model");
}
