/* threads.c - how many OpenMP threads a parallel region of the library runs
 * (tr_default_threads, render.h). Every module's parallel loops ask here, below them all,
 * so that the BVH builders and the filters do not depend on the devices. */
#include <omp.h>

#include "trac0r/render.h"

int tr_default_threads(void) {
    const int n = omp_get_max_threads();
    return n > TR_MAX_THREADS ? TR_MAX_THREADS : n;
}
