/* render_film.h - samples first .. first+spp-1 of a committed scene, through its own
 * camera, into a new w x h film keeping `passes`, for the tests that compare passes
 * (test_direct, test_emission; after check.h: failures are recorded with CHECK). */
#ifndef TR_TEST_RENDER_FILM_H
#define TR_TEST_RENDER_FILM_H

#include "check.h"
#include "trac0r/trac0r.h"

static inline void render_film(const tr_scene *s, uint32_t w, uint32_t h, int integrator,
                               int max_depth, uint32_t passes, uint64_t seed, uint32_t first,
                               uint32_t spp, tr_film *f) {
    tr_error err;
    CHECK(tr_film_init_passes(f, w, h, passes, &err) == TR_OK, "%s", err.msg);
    tr_render_config cfg = tr_render_config_default();
    cfg.integrator = integrator;
    cfg.max_depth = max_depth;
    cfg.passes = passes;
    cfg.seed = seed;
    cfg.threads = 2;
    for (uint32_t k = first; k < first + spp; ++k) {
        CHECK(tr_render_frame(s, tr_scene_camera(s), &cfg, f, k, NULL, &err) == TR_OK, "%s",
              err.msg);
    }
}

#endif
