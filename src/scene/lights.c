/* lights.c - the emitter table next-event estimation samples from. */
#include <math.h>
#include <stdlib.h>

#include "kernel/light.h"
#include "scene/scene_internal.h"
#include "trac0r/scene.h"

void tr_scene_sky_bounds(tr_scene *s) {
    s->sky_center[0] = s->sky_center[1] = s->sky_center[2] = 0.0f;
    s->sky_radius = 0.0f;
    if (s->triangle_count == 0 && !tr_scene_has_kept_instances(s)) {
        return;
    }
    const tr_aabb b = tr_scene_all_bounds(s);
    const float h[3] = {0.5f * (b.max.x - b.min.x), 0.5f * (b.max.y - b.min.y),
                        0.5f * (b.max.z - b.min.z)};
    s->sky_center[0] = b.min.x + h[0];
    s->sky_center[1] = b.min.y + h[1];
    s->sky_center[2] = b.min.z + h[2];
    /* A little more than half the diagonal: the disc the subpaths start on stays clear
     * of the box's corners after rounding. */
    const float r = sqrtf(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
    s->sky_radius = isfinite(r) && r > 0.0f ? r * 1.001f + 1e-4f : 0.0f;
}

int tr_scene_build_lights(tr_scene *s, tr_error *err) {
    tr_scene_sky_bounds(s);
    free(s->lights);
    free(s->light_cdf);
    s->lights = NULL;
    s->light_cdf = NULL;
    s->light_count = 0;
    s->light_weight_total = 0.0f;
    s->light_triangles = s->triangle_count;
    uint32_t n = 0;
    for (uint32_t i = 0; i < s->triangle_count; ++i) {
        n += tr_light_weight(&s->materials[s->triangles[i].material], s->triangles[i].area) > 0.0f;
    }
    if (n == 0) {
        return TR_OK;
    }
    s->lights = malloc((size_t)n * sizeof *s->lights);
    s->light_cdf = malloc((size_t)n * sizeof *s->light_cdf);
    if (!s->lights || !s->light_cdf) {
        free(s->lights);
        free(s->light_cdf);
        s->lights = NULL;
        s->light_cdf = NULL;
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY,
                            "out of memory building the emitter table (%u emitters)", n);
    }
    /* The running sum in double, so that a million small emitters still add up. */
    double total = 0.0;
    uint32_t k = 0;
    for (uint32_t i = 0; i < s->triangle_count; ++i) {
        float w = tr_light_weight(&s->materials[s->triangles[i].material], s->triangles[i].area);
        if (w > 0.0f) {
            total += (double)w;
            s->lights[k] = i;
            s->light_cdf[k] = (float)total;
            ++k;
        }
    }
    for (uint32_t j = 0; j < n; ++j) {
        s->light_cdf[j] = (float)((double)s->light_cdf[j] / total);
    }
    s->light_cdf[n - 1] = 1.0f;
    s->light_count = n;
    s->light_weight_total = (float)total;
    return TR_OK;
}
