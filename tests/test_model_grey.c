/* test_model_grey.c - a model file without materials (PLY and STL from Debian's
 * assimp-testmodels) gets the documented 0.6 grey diffuse, not Assimp's white stand-in,
 * which glowed under the white sky a bare model is rendered in; a model's own material
 * colour is kept. */
#include "check.h"
#include "trac0r/scene.h"
#include "trac0r/scene_file.h"

#define MODELS "/usr/share/assimp/models"

static void check_grey(const char *path) {
    tr_error err;
    tr_scene *s = tr_scene_create(&err);
    tr_scene_file info;
    const tr_model_options opt = {0, 1.0f, 0, 0, NULL};
    CHECK(s && tr_scene_model_load(s, path, &opt, &info, &err) == TR_OK, "%s: %s", path, err.msg);
    const uint32_t n = s ? tr_scene_material_count(s) : 0;
    CHECK(n >= 1, "%s: %u materials", path, n);
    for (uint32_t i = 0; i < n; ++i) {
        const tr_material m = tr_scene_material(s, i);
        if (m.type != TR_MATERIAL_DIFFUSE) {
            continue;
        }
        CHECK(m.color.x == 0.6f && m.color.y == 0.6f && m.color.z == 0.6f,
              "%s: material %u is (%g, %g, %g), not the 0.6 grey", path, i, m.color.x, m.color.y,
              m.color.z);
    }
    tr_scene_destroy(s);
}

int main(void) {
    check_grey(MODELS "/PLY/Wuson.ply");
    check_grey(MODELS "/STL/Wuson.stl");
    return check_finish("test_model_grey");
}
