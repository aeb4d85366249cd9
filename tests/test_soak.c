/* test_soak.c - the real-time loop runs for many frames without growing: a camera moving
 * every frame, the reconstruction methods in turn (temporal and spatial filters, the
 * upscaler, ReSTIR's reservoirs) and a scene whose last shape moves, on the CPU device.
 * After a warm-up (every method and film size met at least once), the peak of the
 * process's resident memory over the second half of the frames may not exceed that over
 * the first half by more than 1 %, and it holds as many file descriptors at the end as
 * after the warm-up. A leak of one small allocation per
 * frame (a pass buffer, a history plane) shows as growth many times that bound.
 *
 * Frames: SOAK_FRAMES in the environment (default 600; `tools/soak` runs 10,000). */
#define _POSIX_C_SOURCE 200809L
#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

#include "check.h"
#include "trac0r/measure.h"
#include "trac0r/trac0r.h"

#define SW 64
#define SH 48

/* AddressSanitizer's allocator keeps freed blocks in per-size caches, so under it the
 * resident set wanders by a few hundred KiB whatever the program does (its quarantine is
 * turned off for this test: tests/CMakeLists.txt); LeakSanitizer, which that build runs
 * at exit, is the stronger check there. A leak of one pass buffer per frame exceeds the
 * bound either way (tens of MiB over the frames). */
#if defined(__SANITIZE_ADDRESS__)
#define ALLOCATOR_SLACK (1024.0 * 1024.0)
#else
#define ALLOCATOR_SLACK 0.0
#endif

/* Resident set in bytes (/proc/self/statm's second field, in pages). */
static double resident_bytes(void) {
    FILE *f = fopen("/proc/self/statm", "r");
    unsigned long size = 0, resident = 0;
    if (!f) {
        return 0.0;
    }
    const int n = fscanf(f, "%lu %lu", &size, &resident);
    fclose(f);
    return n == 2 ? (double)resident * (double)sysconf(_SC_PAGESIZE) : 0.0;
}

/* Open file descriptors (entries of /proc/self/fd, the directory's own included). */
static int open_fds(void) {
    DIR *d = opendir("/proc/self/fd");
    int n = 0;
    for (struct dirent *e; d && (e = readdir(d)) != NULL;) {
        n += e->d_name[0] != '.';
    }
    if (d) {
        closedir(d);
    }
    return n;
}

/* Frame f of the soak: the camera along the benchmark path, the method and upscaling
 * in turn, the last shape moved. */
static int soak_frame(tr_realtime *rt, tr_scene *s, tr_device *dev, const tr_camera *cam0,
                      float diag, uint32_t f, uint32_t frames) {
    static const int methods[] = {TR_RECON_SVGF, TR_RECON_ACCUMULATE, TR_RECON_ATROUS,
                                  TR_RECON_BILATERAL, TR_RECON_OFF};
    tr_error err;
    tr_camera cam;
    if (tr_camera_path(cam0, diag, f % 97, 97, 0, &cam, &err) != TR_OK ||
        tr_scene_animate_sway(s, f + 1, &err) != TR_OK || tr_scene_update(s, NULL, &err) != TR_OK ||
        tr_device_upload(dev, s, &err) != TR_OK) {
        CHECK(0, "frame %u of %u: %s", f, frames, err.msg);
        return TR_ERR;
    }
    tr_realtime_frame_desc fd = {0};
    fd.camera = &cam;
    fd.method = methods[(f / 7) % 5];
    fd.upscale = (f / 35) % 2 ? 2 : 1;
    tr_realtime_result res;
    if (tr_realtime_frame(rt, &fd, &res, &err) != TR_OK) {
        CHECK(0, "frame %u of %u: %s", f, frames, err.msg);
        return TR_ERR;
    }
    return TR_OK;
}

int main(void) {
    const char *env = getenv("SOAK_FRAMES");
    const uint32_t frames = env && atoi(env) >= 300 ? (uint32_t)atoi(env) : 500u;
    const uint32_t warm = 100, mid = warm + (frames - warm) / 2;
    tr_error err;
    tr_scene *s = tr_scene_create(&err);
    tr_device *dev = tr_device_create("cpu", &err);
    CHECK(s && dev && tr_scene_builtin(s, "cornell", SW, SH, &err) == TR_OK &&
              tr_scene_commit(s, TR_ACCEL_TYPE_BVH, &err) == TR_OK &&
              tr_device_upload(dev, s, &err) == TR_OK,
          "%s", err.msg);
    tr_realtime_desc desc = {0};
    desc.animated = 1;
    desc.restir = TR_REALTIME_RESTIR_DI;
    tr_realtime *rt = s && dev ? tr_realtime_create(dev, s, &desc, &err) : NULL;
    CHECK(rt != NULL, "create: %s", err.msg);
    const tr_camera cam0 = s ? *tr_scene_camera(s) : (tr_camera){0};
    /* The resident set rises and falls as films of two sizes and the methods' histories
     * come and go: the peaks of the two halves after the warm-up are compared, each half
     * spanning several of the cycles (70 frames). */
    double peak[2] = {0.0, 0.0};
    int fds_warm = 0;
    for (uint32_t f = 0; rt && f < frames; ++f) {
        if (f == warm) {
            fds_warm = open_fds();
        }
        if (soak_frame(rt, s, dev, &cam0, 2.0f, f, frames) != TR_OK) {
            break;
        }
        const double rss = resident_bytes();
        if (f >= warm && rss > peak[f >= mid]) {
            peak[f >= mid] = rss;
        }
    }
    const int fds_end = open_fds();
    printf("soak: %u frames, resident peak %.0f KiB in frames %u..%u, %.0f KiB in %u..%u "
           "(%+.3f %%), %d and %d file descriptors\n",
           frames, peak[0] / 1024.0, warm, mid - 1, peak[1] / 1024.0, mid, frames - 1,
           peak[0] > 0.0 ? 100.0 * (peak[1] - peak[0]) / peak[0] : 0.0, fds_warm, fds_end);
    CHECK(peak[0] > 0.0 && peak[1] <= 1.01 * peak[0] + ALLOCATOR_SLACK,
          "resident memory grew from %.0f to %.0f KiB", peak[0] / 1024.0, peak[1] / 1024.0);
    CHECK(fds_end == fds_warm, "file descriptors: %d after the warm-up, %d at the end", fds_warm,
          fds_end);
    tr_realtime_destroy(rt);
    tr_device_destroy(dev);
    tr_scene_destroy(s);
    return check_finish("test_soak");
}
