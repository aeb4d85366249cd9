/* bigmem.c - large arrays on transparent huge pages (bigmem.h). */
#define _DEFAULT_SOURCE /* madvise, MADV_HUGEPAGE */
#include "util/bigmem.h"

#include <stdint.h>
#include <stdlib.h>

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

void *tr_bigmem_malloc(size_t bytes) {
    void *p = malloc(bytes);
    tr_bigmem_advise(p, bytes);
    return p;
}

void *tr_bigmem_aligned(size_t align, size_t bytes) {
    void *p = aligned_alloc(align, bytes);
    tr_bigmem_advise(p, bytes);
    return p;
}
