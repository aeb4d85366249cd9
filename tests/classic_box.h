/* classic_box.h - the classic Cornell box (scenes/cornell-classic.json: triangles,
 * millimetres, a right-handed camera) committed at a test's own size, for the tests that
 * render it (after check.h: failures are recorded with CHECK). */
#ifndef TR_TEST_CLASSIC_BOX_H
#define TR_TEST_CLASSIC_BOX_H

#include "check.h"
#include "trac0r/scene_file.h"
#include "trac0r/trac0r.h"

static inline tr_scene *classic_box(uint32_t width, uint32_t height, tr_error *err) {
    tr_scene *s = tr_scene_create(err);
    CHECK(s && tr_scene_file_load(s, TR_SOURCE_DIR "/scenes/cornell-classic.json", NULL, NULL,
                                  err) == TR_OK,
          "cornell-classic: %s", err->msg);
    tr_camera cam = *tr_scene_camera(s);
    CHECK(tr_camera_resize(&cam, width, height, err) == TR_OK, "%s", err->msg);
    tr_scene_set_camera(s, &cam);
    CHECK(tr_scene_commit(s, TR_ACCEL_TYPE_BVH, err) == TR_OK, "commit: %s", err->msg);
    return s;
}

#endif
