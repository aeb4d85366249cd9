/* test_opencl_restir.c - ReSTIR DI and GI on an OpenCL device (PoCL here;
 * src/kernel/restir_pass.h run by entry.cl's tr_cl_restir_* kernels) against the CPU's.
 *
 * 1. The same real-time frames (tr_realtime, 1 spp, the reservoirs carried from frame to
 *    frame, a camera that moves a little so that the temporal reuse reprojects) on the CPU
 *    and on the device: --restir di on the built-in box and scenes/many-lights.json,
 *    --restir di+gi on the box. The passes are the same text compiled with contraction
 *    off and their random numbers are integer hashes, so the two differ only where a
 *    transcendental function (the neighbours' sin/cos, the light and BSDF sampling's own)
 *    rounds its last bit otherwise on the device (docs/opencl.md): many pixels differ in
 *    their last bits (measured on PoCL: 40-60 % of the box's lit pixels, 0.5 % of
 *    many-lights'), and a pixel whose resampling decision or path flipped differs by
 *    its whole estimate, which the spatial and temporal merges of later frames spread.
 *    The bounds, test_opencl's for pt: at most 2 % of the lit pixels more than 1e-4 apart
 *    (relative; measured 0-2 of ~620), and each frame's mean within 1 % (measured equal to
 *    6-7 digits). A CPU run with another seed fails the first bound (nearly every pixel
 *    apart), so it would notice a device that computed another estimate.
 * 2. The frames stay on the device: reconstructed frames (atrous, on the device) with
 *    ReSTIR DI and GI never read the film back (the device's counter of film reads stays
 *    where it was) and only asking for the film (tr_realtime_film) reads it, once.
 * 3. ReSTIR with an integrator other than pt is refused.
 *
 * Needs an OpenCL platform; it fails (not skips) when no device can be opened. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "device/opencl.h"
#include "trac0r/realtime.h"
#include "trac0r/scene_file.h"
#include "trac0r/trac0r.h"

#define W 48
#define H 36
#define FRAMES 4

static tr_scene *load_scene(const char *name, tr_error *err) {
    tr_scene *s = tr_scene_create(err);
    if (!s) {
        return NULL;
    }
    int rc = strncmp(name, "builtin:", 8) == 0 ? tr_scene_builtin(s, name + 8, W, H, err)
                                               : tr_scene_file_load(s, name, NULL, NULL, err);
    if (rc == TR_OK) {
        tr_camera cam = *tr_scene_camera(s);
        rc = tr_camera_resize(&cam, W, H, err);
        tr_scene_set_camera(s, &cam);
    }
    if (rc != TR_OK || tr_scene_commit(s, TR_ACCEL_TYPE_BVH, err) != TR_OK) {
        tr_scene_destroy(s);
        return NULL;
    }
    return s;
}

/* Frame k's camera: the scene's, moved sideways by a hundredth of its distance to the
 * origin per frame (a pixel or so). */
static tr_camera camera_at(const tr_camera *a, int k) {
    tr_camera b = *a;
    const float d = sqrtf(a->pos.x * a->pos.x + a->pos.y * a->pos.y + a->pos.z * a->pos.z);
    const float step = 0.01f * (d > 0.0f ? d : 1.0f) * (float)k;
    b.pos = tr_vec3_make(a->pos.x + step * a->right.x, a->pos.y + step * a->right.y,
                         a->pos.z + step * a->right.z);
    return b;
}

/* FRAMES frames of `scene` on device `name` into means[FRAMES][3 W H]; returns TR_OK. */
static int run_frames(const char *name, tr_scene *scene, uint64_t seed, int restir, float *means,
                      double *restir_ms, tr_error *err) {
    tr_device *dev = tr_device_create(name, err);
    if (!dev || tr_device_upload(dev, scene, err) != TR_OK) {
        tr_device_destroy(dev);
        return TR_ERR;
    }
    tr_render_config cfg = tr_render_config_default();
    cfg.seed = seed;
    cfg.threads = 2;
    tr_realtime_desc d;
    memset(&d, 0, sizeof d);
    d.config = &cfg;
    d.restir = restir;
    tr_realtime *rt = tr_realtime_create(dev, scene, &d, err);
    int rc = rt ? TR_OK : TR_ERR;
    *restir_ms = 0.0;
    for (int k = 0; k < FRAMES && rc == TR_OK; ++k) {
        const tr_camera cam = camera_at(tr_scene_camera(scene), k);
        tr_realtime_frame_desc fd;
        memset(&fd, 0, sizeof fd);
        fd.camera = &cam;
        tr_realtime_result res;
        rc = tr_realtime_frame(rt, &fd, &res, err);
        if (rc != TR_OK) {
            break;
        }
        *restir_ms += res.restir_ms;
        const tr_film *f = res.film;
        for (size_t i = 0; i < (size_t)W * H; ++i) {
            const float inv = f->count[i] ? 1.0f / (float)f->count[i] : 0.0f;
            for (int c = 0; c < 3; ++c) {
                means[(size_t)k * 3 * W * H + 3 * i + (size_t)c] = f->sum[3 * i + (size_t)c] * inv;
            }
        }
    }
    tr_realtime_destroy(rt);
    tr_device_destroy(dev);
    return rc;
}

typedef struct cmp_stats {
    size_t lit, same, far; /* lit pixels, bit-identical ones, ones more than 1e-4 apart */
    double mean_a, mean_b;
} cmp_stats;

static cmp_stats compare(const float *a, const float *b, size_t n) {
    cmp_stats st;
    memset(&st, 0, sizeof st);
    for (size_t i = 0; i < n; ++i) {
        const float *pa = a + 3 * i, *pb = b + 3 * i;
        if (pa[0] + pa[1] + pa[2] > 0.0f || pb[0] + pb[1] + pb[2] > 0.0f) {
            st.lit += 1;
            st.same += pa[0] == pb[0] && pa[1] == pb[1] && pa[2] == pb[2];
            int far = 0;
            for (int c = 0; c < 3; ++c) {
                const double m = fmax(fabs((double)pa[c]), fabs((double)pb[c]));
                far |= fabs((double)pa[c] - pb[c]) > 1e-4 * m;
            }
            st.far += (size_t)far;
        }
        st.mean_a += (double)pa[0] + pa[1] + pa[2];
        st.mean_b += (double)pb[0] + pb[1] + pb[2];
    }
    st.mean_a /= 3.0 * (double)n;
    st.mean_b /= 3.0 * (double)n;
    return st;
}

static void section1(const char *scene_name, int mode) {
    tr_error err;
    tr_scene *scene = load_scene(scene_name, &err);
    CHECK(scene != NULL, "%s: %s", scene_name, err.msg);
    if (!scene) {
        return;
    }
    const size_t n = (size_t)W * H, per = 3 * n;
    float *cpu = malloc(FRAMES * per * sizeof *cpu);
    float *dev = malloc(FRAMES * per * sizeof *dev);
    float *other = malloc(FRAMES * per * sizeof *other);
    CHECK(cpu && dev && other, "out of memory");
    double ms_cpu = 0.0, ms_dev = 0.0, ms = 0.0;
    if (cpu && dev && other) {
        CHECK(run_frames("cpu", scene, 7, mode, cpu, &ms_cpu, &err) == TR_OK, "%s, cpu: %s",
              scene_name, err.msg);
        CHECK(run_frames("opencl:0", scene, 7, mode, dev, &ms_dev, &err) == TR_OK, "%s, opencl: %s",
              scene_name, err.msg);
        CHECK(ms_dev > 0.0, "%s: the device's frames report no ReSTIR time", scene_name);
        /* What the bounds must tell apart: other random numbers. */
        CHECK(run_frames("cpu", scene, 8, mode, other, &ms, &err) == TR_OK, "%s, cpu seed 8: %s",
              scene_name, err.msg);
        for (int k = 0; k < FRAMES; ++k) {
            const size_t o = (size_t)k * per;
            const cmp_stats s = compare(cpu + o, dev + o, n);
            const cmp_stats so = compare(cpu + o, other + o, n);
            printf(
                "%s, %s, frame %d: of %zu lit pixels %zu bit-identical, %zu more than 1e-4 apart "
                "(another seed: %zu, %zu); mean %.7g (cpu) vs %.7g (opencl)\n",
                scene_name, mode == TR_REALTIME_RESTIR_DI ? "di" : "di+gi", k, s.lit, s.same, s.far,
                so.same, so.far, s.mean_a, s.mean_b);
            CHECK(s.lit > n / 4, "%s frame %d: only %zu lit pixels", scene_name, k, s.lit);
            CHECK(s.far * 50 <= s.lit, "%s frame %d: %zu of %zu pixels more than 1e-4 apart",
                  scene_name, k, s.far, s.lit);
            CHECK(fabs(s.mean_a - s.mean_b) <= 0.01 * s.mean_a, "%s frame %d: mean %.6g vs %.6g",
                  scene_name, k, s.mean_a, s.mean_b);
            /* The bound notices another estimate. */
            CHECK(so.far * 50 > so.lit, "%s frame %d: another seed is %zu of %zu pixels apart",
                  scene_name, k, so.far, so.lit);
        }
    }
    free(cpu);
    free(dev);
    free(other);
    tr_scene_destroy(scene);
}

/* Section 2: the film stays on the device until asked for. */
static void section2(void) {
    tr_error err;
    tr_scene *scene = load_scene("builtin:cornell", &err);
    CHECK(scene != NULL, "%s", err.msg);
    tr_device *dev = scene ? tr_device_create("opencl:0", &err) : NULL;
    CHECK(dev && tr_device_upload(dev, scene, &err) == TR_OK, "%s", err.msg);
    tr_cl_context *cl = dev ? tr_device_cl_context(dev) : NULL;
    CHECK(cl != NULL, "no OpenCL context");
    if (!cl) {
        tr_device_destroy(dev);
        tr_scene_destroy(scene);
        return;
    }
    tr_realtime_desc d;
    memset(&d, 0, sizeof d);
    d.restir = TR_REALTIME_RESTIR_DI_GI;
    tr_realtime *rt = tr_realtime_create(dev, scene, &d, &err);
    CHECK(rt != NULL, "%s", err.msg);
    CHECK(tr_realtime_on_device(rt), "the reconstruction does not run on the device");
    const uint64_t reads0 = tr_cl_film_reads(cl);
    for (int k = 0; k < 3 && rt; ++k) {
        const tr_camera cam = camera_at(tr_scene_camera(scene), k);
        tr_realtime_frame_desc fd;
        memset(&fd, 0, sizeof fd);
        fd.camera = &cam;
        fd.method = TR_RECON_ATROUS;
        tr_realtime_result res;
        CHECK(tr_realtime_frame(rt, &fd, &res, &err) == TR_OK, "frame %d: %s", k, err.msg);
        CHECK(res.rgb != NULL && res.restir_ms > 0.0, "frame %d: no reconstruction or no ReSTIR",
              k);
    }
    CHECK(tr_cl_film_reads(cl) == reads0, "reconstructed frames read the film %llu times",
          (unsigned long long)(tr_cl_film_reads(cl) - reads0));
    const tr_film *film = NULL;
    CHECK(rt && tr_realtime_film(rt, &film, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_cl_film_reads(cl) == reads0 + 1, "asking for the film read it %llu times",
          (unsigned long long)(tr_cl_film_reads(cl) - reads0));
    tr_realtime_destroy(rt);

    /* Section 3: what the device does not run. */
    tr_render_config cfg = tr_render_config_default();
    cfg.integrator = TR_INTEGRATOR_NAIVE;
    d.restir = TR_REALTIME_RESTIR_DI;
    d.config = &cfg;
    rt = tr_realtime_create(dev, scene, &d, &err);
    CHECK(rt == NULL && err.code == TR_STATUS_UNSUPPORTED, "ReSTIR DI with naive: not refused");
    tr_realtime_destroy(rt);
    tr_device_destroy(dev);
    tr_scene_destroy(scene);
}

int main(void) {
    section1("builtin:cornell", TR_REALTIME_RESTIR_DI);
    section1(TR_SOURCE_DIR "/scenes/many-lights.json", TR_REALTIME_RESTIR_DI);
    section1("builtin:cornell", TR_REALTIME_RESTIR_DI_GI);
    section2();
    return check_finish("test_opencl_restir");
}
