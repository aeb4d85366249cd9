/* clock.c - the library's monotonic wall clock (tr_time_now, render.h) and the process's
 * CPU time (tr_time_cpu). It sits below
 * every other module: the acceleration structures, the scene's commit and the
 * reconstruction time themselves with it. */
#define _POSIX_C_SOURCE 200809L
#include <time.h>

#include "trac0r/render.h"

double tr_time_now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

double tr_time_cpu(void) {
    struct timespec ts;
    if (clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts) != 0) {
        return 0.0;
    }
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}
