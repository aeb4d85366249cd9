/* omp.h - the OpenMP queries the library calls, for the web build: Emscripten ships no
 * OpenMP runtime, so web/omp/omp_runtime.c provides the part of one that clang's
 * -fopenmp code calls (a team of pthreads, which Emscripten runs as web workers). */
#ifndef TR_WEB_OMP_H
#define TR_WEB_OMP_H

#ifdef __cplusplus
extern "C" {
#endif

int omp_get_max_threads(void);
int omp_get_num_threads(void);
int omp_get_thread_num(void);
int omp_get_num_procs(void);
void omp_set_num_threads(int n);
int omp_in_parallel(void);

#ifdef __cplusplus
}
#endif

#endif
