/* bigmem.c - large arrays on transparent huge pages (bigmem.h). */
#define _DEFAULT_SOURCE /* madvise, MADV_HUGEPAGE */
#include "util/bigmem.h"

#include <stdatomic.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* The cache of freed blocks needs the allocator to tell a block's size (glibc's
 * malloc_usable_size). The address sanitizer's builds keep it off, so that a block used
 * after it is freed is still caught. */
#if defined(__GLIBC__) && !defined(__SANITIZE_ADDRESS__) && !defined(__EMSCRIPTEN__)
#define TR_BIGMEM_CACHE 1
#include <malloc.h>
#else
#define TR_BIGMEM_CACHE 0
#endif

#if defined(__linux__) && !defined(__EMSCRIPTEN__)
#include <sys/mman.h>
#include <unistd.h>
#endif

void tr_bigmem_advise(void *p, size_t bytes) {
#if defined(__linux__) && !defined(__EMSCRIPTEN__) && defined(MADV_HUGEPAGE)
    if (!p || bytes < TR_BIGMEM_MIN) {
        return;
    }
    const long page = sysconf(_SC_PAGESIZE);
    if (page <= 0) {
        return;
    }
    /* madvise wants a page-aligned start: the whole pages inside the array. */
    const size_t ps = (size_t)page, off = (ps - (size_t)((uintptr_t)p % ps)) % ps;
    if (bytes > off && (bytes - off) / ps > 0) {
        /* A kernel without them, or with them turned off, says so; nothing to do then. */
        (void)madvise((char *)p + off, (bytes - off) / ps * ps, MADV_HUGEPAGE);
    }
#else
    (void)p;
    (void)bytes;
#endif
}

#if TR_BIGMEM_CACHE
enum { CACHE_SLOTS = 32 };

/* Freed blocks kept for reuse, each with its usable size; guarded by a spin lock (held
 * for a scan of a few slots only). */
static struct {
    atomic_flag lock;
    void *block[CACHE_SLOTS];
    size_t size[CACHE_SLOTS];
    uint64_t stamp[CACHE_SLOTS], clock; /* when each was kept */
    size_t total;
} cache = {.lock = ATOMIC_FLAG_INIT};

static void cache_lock(void) {
    while (atomic_flag_test_and_set_explicit(&cache.lock, memory_order_acquire)) {
    }
}

static void cache_unlock(void) {
    atomic_flag_clear_explicit(&cache.lock, memory_order_release);
}

/* The smallest kept block of at least `bytes` and at most four times that, aligned to
 * `align`, taken out of the cache; NULL when none fits. (Far larger blocks are left for
 * the requests they were kept for, and a small array does not hold a huge block.) */
static void *cache_take(size_t align, size_t bytes) {
    if (bytes < TR_BIGMEM_MIN) {
        return NULL;
    }
    cache_lock();
    int best = -1;
    for (int i = 0; i < CACHE_SLOTS; ++i) {
        if (cache.block[i] && cache.size[i] >= bytes && cache.size[i] / 4 <= bytes &&
            (uintptr_t)cache.block[i] % align == 0 &&
            (best < 0 || cache.size[i] < cache.size[best])) {
            best = i;
        }
    }
    void *p = NULL;
    if (best >= 0) {
        p = cache.block[best];
        cache.total -= cache.size[best];
        cache.block[best] = NULL;
    }
    cache_unlock();
    return p;
}
#endif

void *tr_bigmem_malloc(size_t bytes) {
#if TR_BIGMEM_CACHE
    void *kept = cache_take(1, bytes);
    if (kept) {
        return kept;
    }
#endif
    void *p = malloc(bytes);
    tr_bigmem_advise(p, bytes);
    return p;
}

void *tr_bigmem_take(size_t bytes) {
#if TR_BIGMEM_CACHE
    return cache_take(1, bytes);
#else
    (void)bytes;
    return NULL;
#endif
}

void *tr_bigmem_aligned(size_t align, size_t bytes) {
#if TR_BIGMEM_CACHE
    void *kept = cache_take(align, bytes);
    if (kept) {
        return kept;
    }
#endif
    void *p = aligned_alloc(align, bytes);
    tr_bigmem_advise(p, bytes);
    return p;
}

void tr_bigmem_free(void *p) {
#if TR_BIGMEM_CACHE
    const size_t size = p ? malloc_usable_size(p) : 0;
    if (size >= TR_BIGMEM_MIN && size <= TR_BIGMEM_KEEP) {
        void *evict[CACHE_SLOTS];
        int evicted = 0;
        cache_lock();
        /* Room for it: the blocks kept longest go first. */
        for (;;) {
            int empty = -1, oldest = -1;
            for (int i = 0; i < CACHE_SLOTS; ++i) {
                if (!cache.block[i]) {
                    empty = i;
                } else if (oldest < 0 || cache.stamp[i] < cache.stamp[oldest]) {
                    oldest = i;
                }
            }
            if (empty >= 0 && cache.total + size <= TR_BIGMEM_KEEP) {
                cache.block[empty] = p;
                cache.size[empty] = size;
                cache.stamp[empty] = ++cache.clock;
                cache.total += size;
                break;
            }
            evict[evicted++] = cache.block[oldest];
            cache.total -= cache.size[oldest];
            cache.block[oldest] = NULL;
        }
        cache_unlock();
        for (int i = 0; i < evicted; ++i) {
            free(evict[i]);
        }
        return;
    }
#endif
    free(p);
}

void tr_bigmem_trim(void) {
#if TR_BIGMEM_CACHE
    void *evict[CACHE_SLOTS];
    int evicted = 0;
    cache_lock();
    for (int i = 0; i < CACHE_SLOTS; ++i) {
        if (cache.block[i]) {
            evict[evicted++] = cache.block[i];
            cache.block[i] = NULL;
        }
    }
    cache.total = 0;
    cache_unlock();
    for (int i = 0; i < evicted; ++i) {
        free(evict[i]);
    }
#endif
}

size_t tr_bigmem_kept(void) {
#if TR_BIGMEM_CACHE
    cache_lock();
    const size_t total = cache.total;
    cache_unlock();
    return total;
#else
    return 0;
#endif
}

int tr_bigmem_keeps(void) {
    return TR_BIGMEM_CACHE;
}

void tr_bigmem_fill_kept(int byte) {
#if TR_BIGMEM_CACHE
    cache_lock();
    for (int i = 0; i < CACHE_SLOTS; ++i) {
        if (cache.block[i]) {
            memset(cache.block[i], byte, cache.size[i]);
        }
    }
    cache_unlock();
#else
    (void)byte;
#endif
}
