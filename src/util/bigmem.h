/* bigmem.h - large arrays on transparent huge pages where the kernel offers them.
 *
 * A fresh array of tens of megabytes (a BVH's records and nodes over a million triangles)
 * is backed by memory page by page as it is first written: on a 4 KiB page size a build over
 * 1.3 M triangles took 62 000 page faults, and the kernel's time for them was a third to a
 * half of the build's wall time. Asking for transparent huge pages (2 MiB) over such an array
 * before it is written makes that a few hundred faults (docs/architecture.md). Nothing
 * changes for the caller: the memory is the malloc's, freed with free(). */
#ifndef TRAC0R_UTIL_BIGMEM_H
#define TRAC0R_UTIL_BIGMEM_H

#include <stddef.h>

/* Arrays smaller than this are left alone: they span too few huge pages to matter. */
#define TR_BIGMEM_MIN ((size_t)4 << 20)

/* Advises the kernel to back p[0, bytes) with huge pages, if the array is at least
 * TR_BIGMEM_MIN and the platform has them (Linux's madvise MADV_HUGEPAGE); a no-op
 * otherwise, and when the kernel declines. Call it before the array is first written. */
void tr_bigmem_advise(void *p, size_t bytes);

/* malloc(bytes) advised as above (NULL when malloc fails). */
void *tr_bigmem_malloc(size_t bytes);

/* aligned_alloc(align, bytes) advised as above; bytes a multiple of align. */
void *tr_bigmem_aligned(size_t align, size_t bytes);

#endif
