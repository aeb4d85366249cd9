/* bench_instances.c - what moving one instance costs per frame, against the instance
 * count (docs/log/ records the runs).
 *
 *     bench_instances [--accel bvh|embree] [N ...]     (default 10000 100000 1000000)
 *
 * For each N: a floor and a lamp of the scene's own and N instances of a prototype (a
 * two-triangle square) on a grid, committed to the BVH (two levels) or to Embree (its own
 * instancing); then FRAMES frames each move one instance (a different one per frame,
 * tr_scene_set_instance_transform) and bring the structure up to date (tr_scene_update:
 * the top level refitted along that instance's path, or Embree's top scene committed
 * again). Prints the commit's time, the median and the largest frame, the same
 * for a frame that moves the instance and commits anew (the full rebuild a one-level BVH
 * would need), and the process's peak RSS. Uses the public API only. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "trac0r/trac0r.h"

#define FRAMES 101
#define REBUILDS 5

static tr_accel_type accel = TR_ACCEL_TYPE_BVH;

static int cmp_double(const void *a, const void *b) {
    const double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static long peak_rss_kib(void) {
    FILE *f = fopen("/proc/self/status", "r");
    char line[256];
    long kib = -1;
    while (f && fgets(line, sizeof line, f)) {
        if (strncmp(line, "VmHWM:", 6) == 0) {
            kib = strtol(line + 6, NULL, 10);
        }
    }
    if (f) {
        fclose(f);
    }
    return kib;
}

static int run(uint32_t n) {
    tr_error err;
    tr_scene *s = tr_scene_create(&err);
    uint32_t white = 0, lamp = 0, proto = 0;
    if (!s ||
        tr_scene_add_material(s, tr_material_diffuse(tr_vec3_make(0.8f, 0.8f, 0.8f)), &white,
                              &err) != TR_OK ||
        tr_scene_add_material(s, tr_material_emitter(tr_vec3_make(1, 1, 1), 5.0f), &lamp, &err) !=
            TR_OK) {
        fprintf(stderr, "bench_instances: %s\n", err.msg);
        return 1;
    }
    tr_shape_desc d = tr_shape_desc_default(TR_SHAPE_PLANE);
    d.material = white;
    d.transform.scale = tr_vec3_make(0.8f, 1.0f, 0.8f);
    if (tr_scene_add_shape(s, &d, &err) != TR_OK ||
        tr_scene_make_prototype(s, 0, &proto, &err) != TR_OK) {
        fprintf(stderr, "bench_instances: %s\n", err.msg);
        return 1;
    }
    const uint32_t side = (uint32_t)ceil(sqrt((double)n));
    d.transform.scale = tr_vec3_make((float)side, 1.0f, (float)side);
    d.transform.position = tr_vec3_make(0.5f * side, -0.5f, 0.5f * side);
    tr_shape_desc l = tr_shape_desc_default(TR_SHAPE_PLANE);
    l.material = lamp;
    l.transform.position = tr_vec3_make(0.5f * side, 10.0f, 0.5f * side);
    l.transform.orientation = tr_vec3_make(3.14159265f, 0.0f, 0.0f);
    if (tr_scene_add_shape(s, &d, &err) != TR_OK || tr_scene_add_shape(s, &l, &err) != TR_OK) {
        fprintf(stderr, "bench_instances: %s\n", err.msg);
        return 1;
    }
    for (uint32_t i = 0; i < n; ++i) {
        float m[12] = {1, 0, 0, (float)(i % side), 0, 1, 0, 0, 0, 0, 1, (float)(i / side)};
        if (tr_scene_add_instance(s, proto, m, NULL, &err) != TR_OK) {
            fprintf(stderr, "bench_instances: %s\n", err.msg);
            return 1;
        }
    }
    double t0 = tr_time_now();
    if (tr_scene_commit(s, accel, &err) != TR_OK) {
        fprintf(stderr, "bench_instances: %s\n", err.msg);
        return 1;
    }
    const double commit = tr_time_now() - t0;
    double frame[FRAMES], rebuild[REBUILDS];
    for (int f = 0; f < FRAMES + REBUILDS; ++f) {
        const uint32_t i = (uint32_t)(((uint64_t)f * 2654435761u) % n);
        float m[12];
        tr_scene_instance_transform(s, i, m);
        m[7] = 0.25f * (float)((f % 4) + 1); /* lift it */
        t0 = tr_time_now();
        int rc = tr_scene_set_instance_transform(s, i, m, &err);
        if (rc == TR_OK) {
            rc = f < FRAMES ? tr_scene_update(s, NULL, &err) : tr_scene_commit(s, accel, &err);
        }
        const double dt = tr_time_now() - t0;
        if (rc != TR_OK) {
            fprintf(stderr, "bench_instances: %s\n", err.msg);
            return 1;
        }
        if (f < FRAMES) {
            frame[f] = dt;
        } else {
            rebuild[f - FRAMES] = dt;
        }
    }
    qsort(frame, FRAMES, sizeof frame[0], cmp_double);
    qsort(rebuild, REBUILDS, sizeof rebuild[0], cmp_double);
    printf("%s: %8u instances, %9u triangles: commit %8.1f ms; move one + update: median %.4f ms, "
           "max %.4f ms; move one + commit: median %.1f ms; peak RSS %ld MiB\n",
           tr_accel_name(accel), n, tr_scene_triangle_count(s), 1e3 * commit,
           1e3 * frame[FRAMES / 2], 1e3 * frame[FRAMES - 1], 1e3 * rebuild[REBUILDS / 2],
           peak_rss_kib() / 1024);
    tr_scene_destroy(s);
    return 0;
}

int main(int argc, char **argv) {
    static const uint32_t def[] = {10000, 100000, 1000000};
    int rc = 0, first = 1;
    if (argc > 2 && strcmp(argv[1], "--accel") == 0) {
        const int a = tr_accel_from_name(argv[2]);
        if (a < 0 || !tr_accel_available((tr_accel_type)a)) {
            fprintf(stderr, "bench_instances: no acceleration structure '%s' here\n", argv[2]);
            return 2;
        }
        accel = (tr_accel_type)a;
        first = 3;
    }
    if (argc <= first) {
        for (size_t k = 0; k < sizeof def / sizeof def[0]; ++k) {
            rc |= run(def[k]);
        }
    }
    for (int a = first; a < argc; ++a) {
        long n = strtol(argv[a], NULL, 10);
        if (n < 1 || n > 100000000) {
            fprintf(stderr, "bench_instances: expected an instance count, got '%s'\n", argv[a]);
            return 2;
        }
        rc |= run((uint32_t)n);
    }
    return rc;
}
