/* omp_runtime.c - the part of an OpenMP runtime that the library's -fopenmp code calls, for
 * the web build (Emscripten has no libomp). clang lowers every `#pragma omp` the library
 * uses to these __kmpc_ entry points (the interface of LLVM's libomp, kmp.h); here they run
 * on one team of pthreads, which Emscripten starts as web workers.
 *
 * What is provided: parallel regions (one team; a region inside a region runs on its one
 * thread, as OMP_MAX_ACTIVE_LEVELS=1 would), static and dynamic loop schedules, barriers,
 * critical sections, reductions through a lock, num_threads. The team is created once by
 * tr_web_omp_start (the page calls it with the browser's core count); until then, and in
 * the single-threaded build, every region runs on the calling thread. Loop partitions
 * follow libomp's, and the renderer's results do not depend on them (each iteration writes
 * its own pixels; reductions add integers). */
#include <pthread.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdlib.h>

#include "omp.h"
#include "../web_api.h"

#define TEAM_MAX 64
#define ARGS_MAX 32
#define SLOTS 8
#define CRIT_LOCKS 31

/* An outlined region: (int32_t *gtid, int32_t *btid, then one pointer per shared
 * variable). Declared without a prototype so that each call passes its own count of
 * pointers, which is the signature WebAssembly checks the callee against. */
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wstrict-prototypes"
typedef void (*microtask)();
#pragma GCC diagnostic pop

typedef struct dispatch_slot {
    atomic_long instance;
    atomic_ullong next;
} dispatch_slot;

typedef struct team {
    pthread_mutex_t lock;
    pthread_cond_t wake, done;
    unsigned generation;
    int size, running, workers;
    microtask fn;
    int argc;
    void *args[ARGS_MAX];
    pthread_mutex_t bar_lock;
    pthread_cond_t bar_cond;
    int bar_count;
    unsigned bar_generation;
    pthread_mutex_t slot_lock;
    dispatch_slot slots[SLOTS];
} team;

static team g_team = {
    .lock = PTHREAD_MUTEX_INITIALIZER,
    .wake = PTHREAD_COND_INITIALIZER,
    .done = PTHREAD_COND_INITIALIZER,
    .bar_lock = PTHREAD_MUTEX_INITIALIZER,
    .bar_cond = PTHREAD_COND_INITIALIZER,
    .slot_lock = PTHREAD_MUTEX_INITIALIZER,
};
static pthread_mutex_t g_fork_lock = PTHREAD_MUTEX_INITIALIZER;
static pthread_mutex_t g_reduce_lock = PTHREAD_MUTEX_INITIALIZER;
static pthread_mutex_t g_crit_lock[CRIT_LOCKS];
static pthread_once_t g_crit_once = PTHREAD_ONCE_INIT;
static atomic_int g_wanted = 0; /* omp_set_num_threads; 0: the whole team */

/* A loop of schedule(dynamic) on this thread: its bounds and the shared counter. */
typedef struct dispatch {
    int64_t lb, st;
    uint64_t trip, chunk;
    dispatch_slot *slot;
} dispatch;

typedef struct thread_state {
    int tid, size, level, push;
    long instance;
    dispatch disp;
    dispatch_slot solo;
} thread_state;

static _Thread_local thread_state tl = {0, 1, 0, 0, 0, {0, 0, 0, 0, 0}, {0, 0}};

static void invoke(microtask fn, int32_t *gtid, int32_t *btid, int argc, void **a) {
    /* One case per count of pointers (the widest region of the library passes 19). */
    switch (argc) {
    case 0:
        fn(gtid, btid);
        break;
    case 1:
        fn(gtid, btid, a[0]);
        break;
    case 2:
        fn(gtid, btid, a[0], a[1]);
        break;
    case 3:
        fn(gtid, btid, a[0], a[1], a[2]);
        break;
    case 4:
        fn(gtid, btid, a[0], a[1], a[2], a[3]);
        break;
    case 5:
        fn(gtid, btid, a[0], a[1], a[2], a[3], a[4]);
        break;
    case 6:
        fn(gtid, btid, a[0], a[1], a[2], a[3], a[4], a[5]);
        break;
    case 7:
        fn(gtid, btid, a[0], a[1], a[2], a[3], a[4], a[5], a[6]);
        break;
    case 8:
        fn(gtid, btid, a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7]);
        break;
    case 9:
        fn(gtid, btid, a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7], a[8]);
        break;
    case 10:
        fn(gtid, btid, a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7], a[8], a[9]);
        break;
    case 11:
        fn(gtid, btid, a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7], a[8], a[9], a[10]);
        break;
    case 12:
        fn(gtid, btid, a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7], a[8], a[9], a[10], a[11]);
        break;
    case 13:
        fn(gtid, btid, a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7], a[8], a[9], a[10], a[11],
           a[12]);
        break;
    case 14:
        fn(gtid, btid, a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7], a[8], a[9], a[10], a[11],
           a[12], a[13]);
        break;
    case 15:
        fn(gtid, btid, a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7], a[8], a[9], a[10], a[11],
           a[12], a[13], a[14]);
        break;
    case 16:
        fn(gtid, btid, a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7], a[8], a[9], a[10], a[11],
           a[12], a[13], a[14], a[15]);
        break;
    case 17:
        fn(gtid, btid, a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7], a[8], a[9], a[10], a[11],
           a[12], a[13], a[14], a[15], a[16]);
        break;
    case 18:
        fn(gtid, btid, a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7], a[8], a[9], a[10], a[11],
           a[12], a[13], a[14], a[15], a[16], a[17]);
        break;
    case 19:
        fn(gtid, btid, a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7], a[8], a[9], a[10], a[11],
           a[12], a[13], a[14], a[15], a[16], a[17], a[18]);
        break;
    case 20:
        fn(gtid, btid, a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7], a[8], a[9], a[10], a[11],
           a[12], a[13], a[14], a[15], a[16], a[17], a[18], a[19]);
        break;
    case 21:
        fn(gtid, btid, a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7], a[8], a[9], a[10], a[11],
           a[12], a[13], a[14], a[15], a[16], a[17], a[18], a[19], a[20]);
        break;
    case 22:
        fn(gtid, btid, a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7], a[8], a[9], a[10], a[11],
           a[12], a[13], a[14], a[15], a[16], a[17], a[18], a[19], a[20], a[21]);
        break;
    case 23:
        fn(gtid, btid, a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7], a[8], a[9], a[10], a[11],
           a[12], a[13], a[14], a[15], a[16], a[17], a[18], a[19], a[20], a[21], a[22]);
        break;
    case 24:
        fn(gtid, btid, a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7], a[8], a[9], a[10], a[11],
           a[12], a[13], a[14], a[15], a[16], a[17], a[18], a[19], a[20], a[21], a[22], a[23]);
        break;
    case 25:
        fn(gtid, btid, a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7], a[8], a[9], a[10], a[11],
           a[12], a[13], a[14], a[15], a[16], a[17], a[18], a[19], a[20], a[21], a[22], a[23],
           a[24]);
        break;
    case 26:
        fn(gtid, btid, a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7], a[8], a[9], a[10], a[11],
           a[12], a[13], a[14], a[15], a[16], a[17], a[18], a[19], a[20], a[21], a[22], a[23],
           a[24], a[25]);
        break;
    case 27:
        fn(gtid, btid, a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7], a[8], a[9], a[10], a[11],
           a[12], a[13], a[14], a[15], a[16], a[17], a[18], a[19], a[20], a[21], a[22], a[23],
           a[24], a[25], a[26]);
        break;
    case 28:
        fn(gtid, btid, a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7], a[8], a[9], a[10], a[11],
           a[12], a[13], a[14], a[15], a[16], a[17], a[18], a[19], a[20], a[21], a[22], a[23],
           a[24], a[25], a[26], a[27]);
        break;
    case 29:
        fn(gtid, btid, a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7], a[8], a[9], a[10], a[11],
           a[12], a[13], a[14], a[15], a[16], a[17], a[18], a[19], a[20], a[21], a[22], a[23],
           a[24], a[25], a[26], a[27], a[28]);
        break;
    case 30:
        fn(gtid, btid, a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7], a[8], a[9], a[10], a[11],
           a[12], a[13], a[14], a[15], a[16], a[17], a[18], a[19], a[20], a[21], a[22], a[23],
           a[24], a[25], a[26], a[27], a[28], a[29]);
        break;
    case 31:
        fn(gtid, btid, a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7], a[8], a[9], a[10], a[11],
           a[12], a[13], a[14], a[15], a[16], a[17], a[18], a[19], a[20], a[21], a[22], a[23],
           a[24], a[25], a[26], a[27], a[28], a[29], a[30]);
        break;
    case 32:
        fn(gtid, btid, a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7], a[8], a[9], a[10], a[11],
           a[12], a[13], a[14], a[15], a[16], a[17], a[18], a[19], a[20], a[21], a[22], a[23],
           a[24], a[25], a[26], a[27], a[28], a[29], a[30], a[31]);
        break;
    default:
        abort();
    }
}

static void run_member(int tid, int size, microtask fn, int argc, void **args) {
    thread_state saved = tl;
    tl.tid = tid;
    tl.size = size;
    tl.level = saved.level + 1;
    tl.push = 0;
    tl.instance = 0;
    int32_t gtid = tid, btid = tid;
    invoke(fn, &gtid, &btid, argc, args);
    tl = saved;
}

static void *worker_main(void *arg) {
    const int tid = (int)(intptr_t)arg;
    unsigned seen = 0;
    for (;;) {
        pthread_mutex_lock(&g_team.lock);
        while (g_team.generation == seen) {
            pthread_cond_wait(&g_team.wake, &g_team.lock);
        }
        seen = g_team.generation;
        const int size = g_team.size;
        microtask fn = g_team.fn;
        const int argc = g_team.argc;
        void *args[ARGS_MAX];
        for (int i = 0; i < argc; ++i) {
            args[i] = g_team.args[i];
        }
        pthread_mutex_unlock(&g_team.lock);
        if (tid >= size) {
            continue;
        }
        run_member(tid, size, fn, argc, args);
        pthread_mutex_lock(&g_team.lock);
        if (--g_team.running == 0) {
            pthread_cond_signal(&g_team.done);
        }
        pthread_mutex_unlock(&g_team.lock);
    }
    return NULL;
}

int tr_web_omp_start(int threads) {
    pthread_mutex_lock(&g_fork_lock);
    if (threads > TEAM_MAX) {
        threads = TEAM_MAX;
    }
    while (g_team.workers + 1 < threads) {
        pthread_t t;
        pthread_attr_t attr;
        pthread_attr_init(&attr);
        pthread_attr_setdetachstate(&attr, PTHREAD_CREATE_DETACHED);
        const int rc =
            pthread_create(&t, &attr, worker_main, (void *)(intptr_t)(g_team.workers + 1));
        pthread_attr_destroy(&attr);
        if (rc != 0) {
            break;
        }
        g_team.workers++;
    }
    const int n = g_team.workers + 1;
    pthread_mutex_unlock(&g_fork_lock);
    return n;
}

static int team_limit(void) {
    const int all = g_team.workers + 1;
    const int want = atomic_load(&g_wanted);
    return want > 0 && want < all ? want : all;
}

int omp_get_max_threads(void) {
    return tl.level > 0 ? 1 : team_limit();
}
int omp_get_num_threads(void) {
    return tl.size;
}
int omp_get_thread_num(void) {
    return tl.tid;
}
int omp_get_num_procs(void) {
    return g_team.workers + 1;
}
void omp_set_num_threads(int n) {
    atomic_store(&g_wanted, n > 0 ? n : 0);
}
int omp_in_parallel(void) {
    return tl.level > 0 && tl.size > 1;
}

/* ---- The entry points clang's code calls (their first argument, the source location, is
 * unused) ---- */

int32_t __kmpc_global_thread_num(void *loc);
void __kmpc_push_num_threads(void *loc, int32_t gtid, int32_t n);
void __kmpc_fork_call(void *loc, int32_t argc, microtask fn, ...);
void __kmpc_serialized_parallel(void *loc, int32_t gtid);
void __kmpc_end_serialized_parallel(void *loc, int32_t gtid);
void __kmpc_barrier(void *loc, int32_t gtid);
void __kmpc_critical(void *loc, int32_t gtid, int32_t (*crit)[8]);
void __kmpc_end_critical(void *loc, int32_t gtid, int32_t (*crit)[8]);
int32_t __kmpc_reduce_nowait(void *loc, int32_t gtid, int32_t nvars, size_t size, void *data,
                             void (*fn)(void *, void *), int32_t (*lck)[8]);
void __kmpc_end_reduce_nowait(void *loc, int32_t gtid, int32_t (*lck)[8]);
int32_t __kmpc_reduce(void *loc, int32_t gtid, int32_t nvars, size_t size, void *data,
                      void (*fn)(void *, void *), int32_t (*lck)[8]);
void __kmpc_end_reduce(void *loc, int32_t gtid, int32_t (*lck)[8]);
int32_t __kmpc_master(void *loc, int32_t gtid);
void __kmpc_end_master(void *loc, int32_t gtid);
void __kmpc_flush(void *loc);

int32_t __kmpc_global_thread_num(void *loc) {
    (void)loc;
    return tl.tid;
}

void __kmpc_push_num_threads(void *loc, int32_t gtid, int32_t n) {
    (void)loc;
    (void)gtid;
    tl.push = n;
}

void __kmpc_fork_call(void *loc, int32_t argc, microtask fn, ...) {
    (void)loc;
    void *args[ARGS_MAX];
    va_list ap;
    va_start(ap, fn);
    for (int i = 0; i < argc && i < ARGS_MAX; ++i) {
        args[i] = va_arg(ap, void *);
    }
    va_end(ap);
    if (argc > ARGS_MAX) {
        abort();
    }
    int n = tl.push > 0 ? tl.push : team_limit();
    tl.push = 0;
    if (n > g_team.workers + 1) {
        n = g_team.workers + 1;
    }
    /* A region inside a region, or a team of one: the calling thread alone. */
    if (tl.level > 0 || n <= 1 || pthread_mutex_trylock(&g_fork_lock) != 0) {
        run_member(0, 1, fn, argc, args);
        return;
    }
    pthread_mutex_lock(&g_team.lock);
    g_team.fn = fn;
    g_team.argc = argc;
    for (int i = 0; i < argc; ++i) {
        g_team.args[i] = args[i];
    }
    g_team.size = n;
    g_team.running = n - 1;
    g_team.bar_count = 0;
    for (int i = 0; i < SLOTS; ++i) {
        atomic_store(&g_team.slots[i].instance, -1);
    }
    g_team.generation++;
    pthread_cond_broadcast(&g_team.wake);
    pthread_mutex_unlock(&g_team.lock);

    run_member(0, n, fn, argc, args);

    pthread_mutex_lock(&g_team.lock);
    while (g_team.running > 0) {
        pthread_cond_wait(&g_team.done, &g_team.lock);
    }
    pthread_mutex_unlock(&g_team.lock);
    pthread_mutex_unlock(&g_fork_lock);
}

/* `#pragma omp parallel if(0)`: the region runs here, as a team of one. */
static _Thread_local thread_state tl_serial_saved[8];
static _Thread_local int tl_serial_depth;

void __kmpc_serialized_parallel(void *loc, int32_t gtid) {
    (void)loc;
    (void)gtid;
    if (tl_serial_depth >= 8) {
        abort();
    }
    tl_serial_saved[tl_serial_depth++] = tl;
    tl.tid = 0;
    tl.size = 1;
    tl.level++;
    tl.push = 0;
    tl.instance = 0;
}

void __kmpc_end_serialized_parallel(void *loc, int32_t gtid) {
    (void)loc;
    (void)gtid;
    tl = tl_serial_saved[--tl_serial_depth];
}

void __kmpc_barrier(void *loc, int32_t gtid) {
    (void)loc;
    (void)gtid;
    if (tl.size <= 1) {
        return;
    }
    pthread_mutex_lock(&g_team.bar_lock);
    const unsigned gen = g_team.bar_generation;
    if (++g_team.bar_count == tl.size) {
        g_team.bar_count = 0;
        g_team.bar_generation++;
        pthread_cond_broadcast(&g_team.bar_cond);
    } else {
        while (gen == g_team.bar_generation) {
            pthread_cond_wait(&g_team.bar_cond, &g_team.bar_lock);
        }
    }
    pthread_mutex_unlock(&g_team.bar_lock);
}

static void crit_init(void) {
    for (int i = 0; i < CRIT_LOCKS; ++i) {
        pthread_mutex_init(&g_crit_lock[i], NULL);
    }
}

static pthread_mutex_t *crit_of(const void *name) {
    pthread_once(&g_crit_once, crit_init);
    return &g_crit_lock[((uintptr_t)name >> 2) % CRIT_LOCKS];
}

void __kmpc_critical(void *loc, int32_t gtid, int32_t (*crit)[8]) {
    (void)loc;
    (void)gtid;
    pthread_mutex_lock(crit_of(crit));
}

void __kmpc_end_critical(void *loc, int32_t gtid, int32_t (*crit)[8]) {
    (void)loc;
    (void)gtid;
    pthread_mutex_unlock(crit_of(crit));
}

/* Reductions: each thread adds its part to the shared variable itself (return value 1),
 * one thread at a time. */
int32_t __kmpc_reduce_nowait(void *loc, int32_t gtid, int32_t nvars, size_t size, void *data,
                             void (*fn)(void *, void *), int32_t (*lck)[8]) {
    (void)loc;
    (void)gtid;
    (void)nvars;
    (void)size;
    (void)data;
    (void)fn;
    (void)lck;
    pthread_mutex_lock(&g_reduce_lock);
    return 1;
}

void __kmpc_end_reduce_nowait(void *loc, int32_t gtid, int32_t (*lck)[8]) {
    (void)loc;
    (void)gtid;
    (void)lck;
    pthread_mutex_unlock(&g_reduce_lock);
}

int32_t __kmpc_reduce(void *loc, int32_t gtid, int32_t nvars, size_t size, void *data,
                      void (*fn)(void *, void *), int32_t (*lck)[8]) {
    return __kmpc_reduce_nowait(loc, gtid, nvars, size, data, fn, lck);
}

void __kmpc_end_reduce(void *loc, int32_t gtid, int32_t (*lck)[8]) {
    __kmpc_end_reduce_nowait(loc, gtid, lck);
    __kmpc_barrier(loc, gtid);
}

int32_t __kmpc_master(void *loc, int32_t gtid) {
    (void)loc;
    (void)gtid;
    return tl.tid == 0;
}

void __kmpc_end_master(void *loc, int32_t gtid) {
    (void)loc;
    (void)gtid;
}

void __kmpc_flush(void *loc) {
    (void)loc;
    atomic_thread_fence(memory_order_seq_cst);
}

/* The lock words clang names for `#pragma omp critical` without a name and for reductions
 * (common symbols in the objects, which WebAssembly's linker does not merge: defined here). */
int32_t tr_web_omp_critical_word[8] __asm__(".gomp_critical_user_.var");
int32_t tr_web_omp_reduction_word[8] __asm__(".gomp_critical_user_.reduction.var");
int32_t tr_web_omp_critical_word[8];
int32_t tr_web_omp_reduction_word[8];

/* ---- Loop schedules ---- */

enum { SCHED_STATIC_CHUNKED = 33, SCHED_STATIC = 34 };

/* schedule(static[, chunk]): this thread's first block [*lower, *upper] and the stride to
 * its next one, as libomp's __kmp_for_static_init computes them. */
#define STATIC_INIT(NAME, T, UT, ST)                                                               \
    void NAME(void *loc, int32_t gtid, int32_t sched, int32_t *plast, T *plower, T *pupper,        \
              ST *pstride, ST incr, ST chunk);                                                     \
    void NAME(void *loc, int32_t gtid, int32_t sched, int32_t *plast, T *plower, T *pupper,        \
              ST *pstride, ST incr, ST chunk) {                                                    \
        (void)loc;                                                                                 \
        (void)gtid;                                                                                \
        const UT n = (UT)tl.size, t = (UT)tl.tid;                                                  \
        const UT trip = incr > 0 ? (UT)(*pupper - *plower) / (UT)incr + 1                          \
                                 : (UT)(*plower - *pupper) / (UT)(-incr) + 1;                      \
        if (n <= 1) {                                                                              \
            if (plast) {                                                                           \
                *plast = 1;                                                                        \
            }                                                                                      \
            *pstride = (ST)(trip * (UT)incr);                                                      \
            return;                                                                                \
        }                                                                                          \
        if (sched == SCHED_STATIC_CHUNKED && chunk > 0) {                                          \
            const UT c = (UT)chunk;                                                                \
            const UT span = c * (UT)incr;                                                          \
            if (plast) {                                                                           \
                *plast = ((trip - 1) / c) % n == t;                                                \
            }                                                                                      \
            *plower = (T)(*plower + (T)(t * span));                                                \
            *pupper = (T)(*plower + (T)span - (T)incr);                                            \
            *pstride = (ST)(span * n);                                                             \
            return;                                                                                \
        }                                                                                          \
        if (trip < n) {                                                                            \
            if (plast) {                                                                           \
                *plast = t == trip - 1;                                                            \
            }                                                                                      \
            if (t < trip) {                                                                        \
                *plower = (T)(*plower + (T)(t * (UT)incr));                                        \
                *pupper = *plower;                                                                 \
            } else {                                                                               \
                *plower = (T)(*pupper + (T)incr);                                                  \
            }                                                                                      \
        } else {                                                                                   \
            const UT small = trip / n, extras = trip % n;                                          \
            const UT first = t * small + (t < extras ? t : extras);                                \
            const UT count = small + (t < extras ? 1 : 0);                                         \
            if (plast) {                                                                           \
                *plast = t == n - 1;                                                               \
            }                                                                                      \
            *plower = (T)(*plower + (T)(first * (UT)incr));                                        \
            *pupper = (T)(*plower + (T)(count * (UT)incr) - (T)incr);                              \
        }                                                                                          \
        *pstride = (ST)(trip * (UT)incr);                                                          \
    }

STATIC_INIT(__kmpc_for_static_init_4, int32_t, uint32_t, int32_t)
STATIC_INIT(__kmpc_for_static_init_4u, uint32_t, uint32_t, int32_t)
STATIC_INIT(__kmpc_for_static_init_8, int64_t, uint64_t, int64_t)
STATIC_INIT(__kmpc_for_static_init_8u, uint64_t, uint64_t, int64_t)

void __kmpc_for_static_fini(void *loc, int32_t gtid);
void __kmpc_for_static_fini(void *loc, int32_t gtid) {
    (void)loc;
    (void)gtid;
}

/* schedule(dynamic[, chunk]) (and every other schedule that goes through dispatch): blocks
 * of `chunk` iterations handed out in order from a counter the team shares. Each loop
 * instance of a region takes the next of SLOTS counters; the first thread to reach it
 * resets it. */
static void dispatch_init(int64_t lb, int64_t st, uint64_t trip, int64_t chunk) {
    dispatch *d = &tl.disp;
    d->lb = lb;
    d->st = st;
    d->trip = trip;
    d->chunk = chunk > 0 ? (uint64_t)chunk : 1u;
    if (tl.size <= 1) {
        d->slot = &tl.solo;
        atomic_store(&d->slot->next, 0);
        return;
    }
    const long k = tl.instance++;
    dispatch_slot *s = &g_team.slots[k % SLOTS];
    if (atomic_load(&s->instance) != k) {
        pthread_mutex_lock(&g_team.slot_lock);
        if (atomic_load(&s->instance) != k) {
            atomic_store(&s->next, 0);
            atomic_store(&s->instance, k);
        }
        pthread_mutex_unlock(&g_team.slot_lock);
    }
    d->slot = s;
}

static int dispatch_next(int64_t *lo, int64_t *hi, int32_t *plast) {
    dispatch *d = &tl.disp;
    const uint64_t i = atomic_fetch_add(&d->slot->next, d->chunk);
    if (i >= d->trip) {
        return 0;
    }
    const uint64_t end = d->trip - i < d->chunk ? d->trip : i + d->chunk;
    *lo = d->lb + (int64_t)i * d->st;
    *hi = d->lb + (int64_t)(end - 1) * d->st;
    if (plast) {
        *plast = end == d->trip;
    }
    return 1;
}

#define DISPATCH(SUFFIX, T, UT, ST)                                                                \
    void __kmpc_dispatch_init_##SUFFIX(void *loc, int32_t gtid, int32_t sched, T lb, T ub, ST st,  \
                                       ST chunk);                                                  \
    int32_t __kmpc_dispatch_next_##SUFFIX(void *loc, int32_t gtid, int32_t *plast, T *plb, T *pub, \
                                          ST *pst);                                                \
    void __kmpc_dispatch_init_##SUFFIX(void *loc, int32_t gtid, int32_t sched, T lb, T ub, ST st,  \
                                       ST chunk) {                                                 \
        (void)loc;                                                                                 \
        (void)gtid;                                                                                \
        (void)sched;                                                                               \
        uint64_t trip = 0;                                                                         \
        if (st > 0 ? ub >= lb : lb >= ub) {                                                        \
            trip = st > 0 ? (uint64_t)(UT)(ub - lb) / (uint64_t)st + 1                             \
                          : (uint64_t)(UT)(lb - ub) / (uint64_t)(-(int64_t)st) + 1;                \
        }                                                                                          \
        dispatch_init((int64_t)lb, (int64_t)st, trip, (int64_t)chunk);                             \
    }                                                                                              \
    int32_t __kmpc_dispatch_next_##SUFFIX(void *loc, int32_t gtid, int32_t *plast, T *plb, T *pub, \
                                          ST *pst) {                                               \
        (void)loc;                                                                                 \
        (void)gtid;                                                                                \
        int64_t lo, hi;                                                                            \
        if (!dispatch_next(&lo, &hi, plast)) {                                                     \
            return 0;                                                                              \
        }                                                                                          \
        *plb = (T)lo;                                                                              \
        *pub = (T)hi;                                                                              \
        if (pst) {                                                                                 \
            *pst = (ST)tl.disp.st;                                                                 \
        }                                                                                          \
        return 1;                                                                                  \
    }

DISPATCH(4, int32_t, uint32_t, int32_t)
DISPATCH(4u, uint32_t, uint32_t, int32_t)
DISPATCH(8, int64_t, uint64_t, int64_t)
DISPATCH(8u, uint64_t, uint64_t, int64_t)
