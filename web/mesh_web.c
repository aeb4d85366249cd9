/* mesh_web.c - mesh import in the web build, which has no Assimp (src/scene/mesh.c
 * imports through it natively): every import fails as unsupported. web/main.c loads
 * scene files with load_meshes 0, so their meshes are skipped rather than failing. */
#include "scene/scene_internal.h"
#include "trac0r/scene_file.h"

static int no_meshes(const char *path, tr_error *err) {
    return tr_error_set(err, TR_STATUS_UNSUPPORTED,
                        "'%.200s': meshes cannot be imported in the web build (no Assimp)", path);
}

int tr_model_find_camera(const char *path, const char *name, int *index, tr_error *err) {
    (void)name;
    *index = -1;
    return no_meshes(path, err);
}

int tr_scene_import_mesh_ex(tr_scene *s, const char *path, const tr_transform *tf,
                            int64_t material_override, uint32_t max_triangles,
                            tr_mesh_import_stats *stats, tr_import_warn_fn warn, void *warn_ctx,
                            tr_import_extras *extras, tr_error *err) {
    (void)s;
    (void)tf;
    (void)material_override;
    (void)max_triangles;
    (void)stats;
    (void)warn;
    (void)warn_ctx;
    (void)extras;
    return no_meshes(path, err);
}
