/* test_model_instances.c - a model file whose node graph places one mesh several times
 * is imported as one prototype and an instance per placement (src/scene/mesh.c), and
 * renders as the same file imported flattened.
 *
 *  (a) A glTF file written here: a tetrahedron placed by three nodes (one of them a
 *      mirror, one under a parent node, one rotated and scaled unevenly) and a floor placed
 *      once, imported through an import transform (offset, turn, scale). With instancing
 *      it holds one prototype and three instances, flattened none; both hold the same
 *      triangles, counted alike by the import.
 *  (b) pt and bdpt render both scenes to the same image: the instance's matrix is the
 *      node's and the import's composed once, where the flattened import applies them
 *      one after the other, so vertex positions differ by float rounding only (~1e-7 of
 *      the coordinates): the image means agree within 1e-4 and no more than 0.5 % of the
 *      pixels differ by more than 1e-3 (a camera ray grazing an edge may land on the other
 *      side of it).
 *  (c) The id pass's triangles name an instance and its primitive.
 *  (d) Below the import's threshold of shared placed triangles it stays flattened. */
#define _POSIX_C_SOURCE 200809L
#include "check.h"
#include "render_film.h"
#include "scene/scene_internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

enum { W = 64, H = 48, SPP = 16 };

/* A tetrahedron (positions and unsigned-short indices) and a floor quad, base64. */
#define TETRA                                                                                      \
    "AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAAAAAAAAAAAAAIA/AAACAAEAAAABAAMAAAADAAIAAQA"  \
    "CAAMA"
#define FLOOR "AABAwAAAgL8AAEDAAABAQAAAgL8AAEDAAABAQAAAgL8AAEBAAABAwAAAgL8AAEBAAAACAAEAAAADAAIA"

static int write_gltf(const char *path) {
    FILE *f = fopen(path, "w");
    if (!f) {
        return 0;
    }
    fprintf(f, "{\"asset\": {\"version\": \"2.0\"},\n"
               " \"buffers\": [{\"byteLength\": 72, \"uri\": "
               "\"data:application/octet-stream;base64," TETRA "\"},\n"
               "   {\"byteLength\": 60, \"uri\": \"data:application/octet-stream;base64," FLOOR
               "\"}],\n"
               " \"bufferViews\": [{\"buffer\": 0, \"byteOffset\": 0, \"byteLength\": 48},\n"
               "   {\"buffer\": 0, \"byteOffset\": 48, \"byteLength\": 24},\n"
               "   {\"buffer\": 1, \"byteOffset\": 0, \"byteLength\": 48},\n"
               "   {\"buffer\": 1, \"byteOffset\": 48, \"byteLength\": 12}],\n"
               " \"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, \"count\": 4, "
               "\"type\": \"VEC3\", \"min\": [0, 0, 0], \"max\": [1, 1, 1]},\n"
               "   {\"bufferView\": 1, \"componentType\": 5123, \"count\": 12, \"type\": "
               "\"SCALAR\"},\n"
               "   {\"bufferView\": 2, \"componentType\": 5126, \"count\": 4, "
               "\"type\": \"VEC3\", \"min\": [-3, -1, -3], \"max\": [3, -1, 3]},\n"
               "   {\"bufferView\": 3, \"componentType\": 5123, \"count\": 6, \"type\": "
               "\"SCALAR\"}],\n"
               " \"materials\": [{\"pbrMetallicRoughness\": {\"baseColorFactor\": [0.8, 0.3, "
               "0.2, 1], \"metallicFactor\": 0, \"roughnessFactor\": 0.6}},\n"
               "   {\"pbrMetallicRoughness\": {\"baseColorFactor\": [0.7, 0.7, 0.7, 1], "
               "\"metallicFactor\": 0, \"roughnessFactor\": 1}}],\n"
               " \"meshes\": [{\"primitives\": [{\"attributes\": {\"POSITION\": 0}, \"indices\": "
               "1, \"material\": 0}]},\n"
               "   {\"primitives\": [{\"attributes\": {\"POSITION\": 2}, \"indices\": 3, "
               "\"material\": 1}]}],\n"
               " \"nodes\": [{\"mesh\": 0, \"translation\": [-1.5, 0, 0]},\n"
               "   {\"mesh\": 0, \"scale\": [-1, 1, 1], \"translation\": [1.5, 0, 0]},\n"
               "   {\"mesh\": 0, \"rotation\": [0, 0.3826834, 0, 0.9238795], \"scale\": [0.5, 2, "
               "0.5], \"translation\": [0, 0, -1.5]},\n"
               "   {\"mesh\": 1},\n"
               "   {\"children\": [0, 1], \"translation\": [0, 0.2, 0]}],\n"
               " \"scenes\": [{\"nodes\": [4, 2, 3]}], \"scene\": 0}\n");
    return fclose(f) == 0;
}

/* Imports `path` (instancing shared meshes or not) into *s, lit and seen from a fixed
 * camera, and commits it. */
static int load(tr_scene *s, const char *path, uint64_t instance_min, tr_mesh_import_stats *st) {
    tr_scene_init(s);
    tr_import_extras ex;
    memset(&ex, 0, sizeof ex);
    ex.instance_min = instance_min; /* model files: TR_IMPORT_INSTANCE_MIN */
    const int instancing = instance_min > 0u;
    const tr_transform tf = {v3(0.25f, 0.1f, -0.2f), v3(0.0f, 0.4f, 0.0f), v3s(1.5f)};
    tr_error err;
    if (tr_scene_import_mesh_ex(s, path, &tf, -1, 0, st, NULL, NULL, &ex, &err) != TR_OK) {
        CHECK(0, "import (instancing %d): %s", instancing, err.msg);
        return 0;
    }
    CHECK(tr_scene_set_environment(s, v3(0.9f, 0.95f, 1.0f), 1.0f, 0.0f, NULL, 0, 0, &err) == TR_OK,
          "%s", err.msg);
    tr_camera cam;
    CHECK(tr_camera_make(&cam, v3(0.5f, 3.0f, 7.0f), v3(-0.05f, -0.4f, -1.0f), v3(0, 1, 0), 50.0f,
                         1e-3f, 1e4f, W, H, &err) == TR_OK,
          "%s", err.msg);
    tr_scene_set_camera(s, &cam);
    if (tr_scene_commit(s, TR_ACCEL_TYPE_BVH, &err) != TR_OK) {
        CHECK(0, "commit: %s", err.msg);
        return 0;
    }
    return 1;
}

/* (b) */
static void same_image(const tr_scene *a, const tr_scene *b, int integrator, const char *name) {
    tr_film fa, fb;
    render_film(a, W, H, integrator, 6, 0, 5, 0, SPP, &fa);
    render_film(b, W, H, integrator, 6, 0, 5, 0, SPP, &fb);
    double ma = 0.0, mb = 0.0;
    int off = 0;
    for (uint32_t y = 0; y < H; ++y) {
        for (uint32_t x = 0; x < W; ++x) {
            const tr_vec3 p = tr_film_pixel(&fa, x, y), q = tr_film_pixel(&fb, x, y);
            ma += (double)(p.x + p.y + p.z) / (3.0 * W * H);
            mb += (double)(q.x + q.y + q.z) / (3.0 * W * H);
            off += fabsf(p.x - q.x) > 1e-3f || fabsf(p.y - q.y) > 1e-3f || fabsf(p.z - q.z) > 1e-3f;
        }
    }
    printf("%s: mean %.6f instanced, %.6f flattened; %d pixels differ\n", name, ma, mb, off);
    CHECK(ma > 0.05 && fabs(ma - mb) <= 1e-4 * ma, "%s: means %.6f and %.6f", name, ma, mb);
    CHECK(off <= W * H / 200, "%s: %d of %d pixels differ", name, off, W * H);
    tr_film_free(&fa);
    tr_film_free(&fb);
}

int main(void) {
    char dir[] = "/tmp/trac0r-model-inst-XXXXXX";
    if (!mkdtemp(dir)) {
        CHECK(0, "mkdtemp");
        return check_finish("test_model_instances");
    }
    char path[700];
    snprintf(path, sizeof path, "%s/shared.gltf", dir);
    CHECK(write_gltf(path), "cannot write %s", path);
    tr_scene inst, flat;
    tr_mesh_import_stats si, sf;
    /* Below the threshold (12 triangles placed by the shared mesh) it stays flattened. */
    if (load(&inst, path, 13, &si)) {
        CHECK(tr_scene_instance_count(&inst) == 0 && tr_scene_prototype_count(&inst) == 0,
              "%u instances below the threshold", tr_scene_instance_count(&inst));
    }
    tr_scene_clear(&inst);
    if (load(&inst, path, 12, &si) && load(&flat, path, 0, &sf)) {
        /* (a) */
        CHECK(tr_scene_prototype_count(&inst) == 1 && tr_scene_instance_count(&inst) == 3,
              "%u prototypes and %u instances (expected 1 and 3)", tr_scene_prototype_count(&inst),
              tr_scene_instance_count(&inst));
        CHECK(tr_scene_instance_count(&flat) == 0, "the flattened import has %u instances",
              tr_scene_instance_count(&flat));
        CHECK(tr_scene_triangle_count(&inst) == 14 && tr_scene_triangle_count(&flat) == 14,
              "triangles: %u instanced, %u flattened (expected 3 x 4 + 2)",
              tr_scene_triangle_count(&inst), tr_scene_triangle_count(&flat));
        CHECK(si.parts == sf.parts && si.triangles == sf.triangles && si.triangles == 14,
              "import counts: %u parts %u triangles instanced, %u and %u flattened", si.parts,
              si.triangles, sf.parts, sf.triangles);
        const tr_aabb bi = tr_scene_bounds(&inst), bf = tr_scene_bounds(&flat);
        CHECK(fabsf(bi.min.x - bf.min.x) < 1e-5f && fabsf(bi.max.y - bf.max.y) < 1e-5f &&
                  fabsf(bi.max.z - bf.max.z) < 1e-5f,
              "bounds differ: (%g %g %g) vs (%g %g %g)", (double)bi.min.x, (double)bi.max.y,
              (double)bi.max.z, (double)bf.min.x, (double)bf.max.y, (double)bf.max.z);
        /* (b) */
        same_image(&inst, &flat, TR_INTEGRATOR_PT, "pt");
        same_image(&inst, &flat, TR_INTEGRATOR_BDPT, "bdpt");
        /* (c) */
        int named = 0;
        for (uint32_t t = 0; t < tr_scene_triangle_count(&inst); ++t) {
            uint32_t in = UINT32_MAX, prim = UINT32_MAX;
            if (tr_scene_triangle_instance(&inst, t, &in, &prim)) {
                CHECK(in < 3 && prim < 4, "triangle %u: instance %u, primitive %u", t, in, prim);
                ++named;
            }
        }
        CHECK(named == 12, "%d triangles name an instance (expected 12)", named);
    }
    tr_scene_clear(&inst);
    tr_scene_clear(&flat);
    unlink(path);
    rmdir(dir);
    return check_finish("test_model_instances");
}
