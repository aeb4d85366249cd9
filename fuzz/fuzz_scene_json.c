/* fuzz_scene_json.c - libFuzzer target for the JSON scene loader (src/scene/json.c).
 *
 * Parses the input as a scene file from memory, with mesh files not opened (options
 * load_meshes = 0) and a small triangle budget so that every input stays in-process and
 * fast; a scene that loads is also committed to a BVH. Built with clang by fuzz/build.sh
 * (-fsanitize=fuzzer,address,undefined); run by fuzz/run.sh and .ci/run. */
#define _POSIX_C_SOURCE 200809L
#include <stdint.h>
#include <stdlib.h>

#include "scene/scene_internal.h"
#include "trac0r/scene_file.h"

/* The loader never imports meshes here; this build has no Assimp. Reaching this is a
 * bug in the loader's load_meshes = 0 path. */
int tr_scene_import_mesh(tr_scene *s, const char *path, const tr_transform *tf,
                         int64_t material_override, uint32_t max_triangles,
                         tr_mesh_import_stats *stats, tr_error *err) {
    (void)s, (void)path, (void)tf, (void)material_override, (void)max_triangles, (void)stats;
    (void)err;
    abort();
}
int tr_scene_import_mesh_ex(tr_scene *s, const char *path, const tr_transform *tf,
                            int64_t material_override, uint32_t max_triangles,
                            tr_mesh_import_stats *stats, tr_import_warn_fn warn, void *warn_ctx,
                            tr_import_extras *extras, tr_error *err) {
    (void)s, (void)path, (void)tf, (void)material_override, (void)max_triangles, (void)stats;
    (void)warn, (void)warn_ctx, (void)extras, (void)err;
    abort();
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    tr_scene s = {0};
    tr_scene_file info;
    tr_error err;
    const tr_scene_file_options opt = {0, 20000};
    if (tr_scene_file_parse(&s, "fuzz.json", (const char *)data, size, &opt, &info, &err) ==
        TR_OK) {
        /* A loaded scene must be consistent: every triangle's material exists and every
         * shape's run lies inside the triangle array. */
        for (uint32_t i = 0; i < s.triangle_count; ++i) {
            if (s.triangles[i].material >= s.material_count) {
                abort();
            }
        }
        for (uint32_t i = 0; i < s.shape_count; ++i) {
            if ((uint64_t)s.shapes[i].first + s.shapes[i].count > s.triangle_count) {
                abort();
            }
        }
        if (s.triangle_count == 0 && info.mesh_count == 0) {
            abort();
        }
        /* What the loader accepts, the BVH must build from. */
        if (tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) != TR_OK) {
            abort();
        }
        tr_scene_clear(&s);
    } else if (s.triangles || s.materials || s.shapes || s.triangle_count) {
        abort(); /* a failed load leaves the scene empty */
    }
    return 0;
}
