/* lights.c - the emitter table next-event estimation samples from. */
#include <stdlib.h>

#include "kernel/light.h"
#include "scene/scene_internal.h"
#include "trac0r/scene.h"

int tr_scene_build_lights(tr_scene *s, tr_error *err) {
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
