/* focus.c - the distance a thin lens focuses at to make a screen point sharp
 * (trac0r/scene.h). */
#include "kernel/camera.h"
#include "kernel/scene_view.h"
#include "scene/scene_internal.h"
#include "trac0r/error.h"
#include "trac0r/scene.h"

int tr_scene_focus_distance(const tr_scene *s, const tr_camera *cam, float x, float y,
                            float *dist) {
    if (!s || !cam || !dist || !tr_scene_is_committed(s) || !(x >= 0.0f) || !(y >= 0.0f) ||
        !(x < (float)cam->screen_width) || !(y < (float)cam->screen_height)) {
        return 0;
    }
    /* The pinhole ray through the point: a lens focused at distance z along the view
     * direction images that point of the ray sharply, whatever the lens sample. */
    const tr_ray ray = tr_camera_ray(cam, x, y, 0.0f, 0.0f);
    const tr_scene_view view = tr_scene_view_of(s);
    tr_hit hit;
    if (!tr_intersect_scene(&view, &ray, &hit)) {
        return 0;
    }
    const float along = hit.t * v3_dot(ray.dir, cam->dir);
    if (!(along > 0.0f) || !(along < 1e30f)) {
        return 0;
    }
    *dist = along;
    return 1;
}
