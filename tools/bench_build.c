/* bench_build.c - what one acceleration-structure build costs, counted in ways that do not
 * depend on the machine's load as well as timed (docs/log/ records the runs).
 *
 *     bench_build ACCELS COMMITS SCENE [SCENE ...]
 *
 * ACCELS is a comma-separated list of structures (bvh, bvh2, embree), each SCENE a built-in scene's
 * name (cornell-ico-8: 1.3 M triangles; cornell-ico-9: 5.2 M). Each scene in turn is loaded afresh
 * and committed COMMITS times in a row with each structure in turn, then destroyed; each commit
 * prints the build time the library reports (the one `trac0r bench` prints), the commit's wall
 * time, the process's user and system CPU time during it (every thread's), the calling thread's
 * user time alone and the process's minor page faults (getrusage). `bench complexity` times the
 * first commit of each of cornell-ico-0 to cornell-ico-L, `bench rays` the second commit of one
 * scene (its ray sets were made with the scene committed once). Run it with OMP_NUM_THREADS=1 for
 * CPU times that the other threads on the machine do not change. Uses the public API only. */
#define _GNU_SOURCE /* RUSAGE_THREAD */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>

#include "trac0r/trac0r.h"

static double seconds(struct timeval t) {
    return (double)t.tv_sec + 1e-6 * (double)t.tv_usec;
}

/* Commits s with `accel` and prints the commit's row; 0 on success. */
static int commit(tr_scene *s, const char *scene, int index, int c, tr_accel_type accel) {
    tr_error err;
    struct rusage r0, r1, m0, m1;
    getrusage(RUSAGE_SELF, &r0);
    getrusage(RUSAGE_THREAD, &m0);
    const double t0 = tr_time_now();
    if (tr_scene_commit(s, accel, &err) != TR_OK) {
        fprintf(stderr, "bench_build: %s\n", err.msg);
        return 1;
    }
    const double wall = tr_time_now() - t0;
    getrusage(RUSAGE_THREAD, &m1);
    getrusage(RUSAGE_SELF, &r1);
    const double build = tr_scene_build_seconds(s);
    printf("%-14s %-6s %5d %6d %9.1f %9.1f %9.1f %9.1f %9.1f %9ld\n", scene, tr_accel_name(accel),
           index, c, 1e3 * build, 1e3 * wall, 1e3 * (seconds(r1.ru_utime) - seconds(r0.ru_utime)),
           1e3 * (seconds(r1.ru_stime) - seconds(r0.ru_stime)),
           1e3 * (seconds(m1.ru_utime) - seconds(m0.ru_utime)), r1.ru_minflt - r0.ru_minflt);
    fflush(stdout);
    return 0;
}

int main(int argc, char **argv) {
    if (argc < 4) {
        fprintf(stderr, "usage: bench_build ACCELS COMMITS SCENE [SCENE ...]\n");
        return 2;
    }
    tr_accel_type accels[8];
    int count = 0;
    for (char *name = strtok(argv[1], ","); name; name = strtok(NULL, ",")) {
        const int a = tr_accel_from_name(name);
        if (a < 0 || !tr_accel_available((tr_accel_type)a) || count == 8) {
            fprintf(stderr, "bench_build: unknown or unavailable structure '%s'\n", name);
            return 2;
        }
        accels[count++] = (tr_accel_type)a;
    }
    const int commits = atoi(argv[2]);
    if (commits < 1) {
        fprintf(stderr, "bench_build: expected a commit count, got '%s'\n", argv[2]);
        return 2;
    }
    printf("%-14s %-6s %5s %6s %9s %9s %9s %9s %9s %9s\n", "scene", "accel", "scene", "commit",
           "build ms", "wall ms", "user ms", "sys ms", "main usr", "minflt");
    for (int sc = 3; sc < argc; ++sc) {
        tr_error err;
        tr_scene *s = tr_scene_create(&err);
        if (!s || tr_scene_builtin(s, argv[sc], 64, 64, &err) != TR_OK) {
            fprintf(stderr, "bench_build: %s\n", err.msg);
            return 1;
        }
        for (int k = 0; k < count; ++k) {
            for (int c = 0; c < commits; ++c) {
                if (commit(s, argv[sc], sc - 3, c, accels[k]) != 0) {
                    return 1;
                }
            }
        }
        tr_scene_destroy(s);
    }
    return 0;
}
