/* fresh_run.h - the real-time instances the fresh samples' tests share (test_fresh.c on
 * the CPU, test_opencl_fresh.c on an OpenCL device beside it): SVGF frames of one sample
 * per pixel with tr_recon_params.fresh_spp set, and the film each frame leaves. */
#ifndef TR_TESTS_FRESH_RUN_H
#define TR_TESTS_FRESH_RUN_H

#include "check.h"
#include "trac0r/trac0r.h"

/* A real-time instance on dev (the scene uploaded first) with fresh_spp `fresh` and
 * `threads` threads (0: the default). */
static tr_realtime *make(tr_device *dev, tr_scene *s, int fresh, int threads) {
    tr_error err;
    CHECK(tr_device_upload(dev, s, &err) == TR_OK, "%s", err.msg);
    tr_render_config cfg = tr_render_config_default();
    cfg.threads = threads;
    tr_recon_params p = tr_recon_params_default();
    p.fresh_spp = fresh;
    tr_realtime_desc desc = {0};
    desc.config = &cfg;
    desc.recon = &p;
    tr_realtime *rt = tr_realtime_create(dev, s, &desc, &err);
    CHECK(rt != NULL, "create: %s", err.msg);
    return rt;
}

/* Renders a frame through cam and returns its film. */
static const tr_film *frame(tr_realtime *rt, const tr_camera *cam) {
    tr_error err;
    tr_realtime_frame_desc fd = {0};
    fd.camera = cam;
    fd.method = TR_RECON_SVGF;
    CHECK(tr_realtime_render(rt, &fd, &err) == TR_OK, "render: %s", err.msg);
    const tr_film *f = NULL;
    CHECK(tr_realtime_film(rt, &f, &err) == TR_OK && f, "film: %s", err.msg);
    return f;
}

#endif
