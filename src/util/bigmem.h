/* bigmem.h - large arrays on transparent huge pages where the kernel offers them.
 *
 * A fresh array of tens of megabytes (a BVH's records and nodes over a million triangles)
 * is backed by memory page by page as it is first written: on a 4 KiB page size a build over
 * 1.3 M triangles took 62 000 page faults, and the kernel's time for them was a third to a
 * half of the build's wall time. Asking for transparent huge pages (2 MiB) over such an array
 * before it is written makes that a few hundred faults (docs/architecture.md).
 *
 * Even on huge pages, memory new to the process is cleared by the kernel as it is first
 * written: in a build repeated over the same 1.3 M triangles that clearing was a sixth of
 * the CPU time. So blocks given back with tr_bigmem_free are kept (up to TR_BIGMEM_KEEP in
 * all, the longest kept freed first) and handed out again for a request they can hold, as
 * Embree's allocator keeps its memory between builds; tr_bigmem_trim frees them. The memory
 * is the malloc's: free() may free it too, but then it is not kept. */
#ifndef TRAC0R_UTIL_BIGMEM_H
#define TRAC0R_UTIL_BIGMEM_H

#include <stddef.h>

/* Arrays smaller than this are left alone: they span too few huge pages to matter. */
#define TR_BIGMEM_MIN ((size_t)4 << 20)

/* Freed blocks kept for reuse, in all, at most this. */
#define TR_BIGMEM_KEEP ((size_t)2 << 30)

/* Advises the kernel to back p[0, bytes) with huge pages, if the array is at least
 * TR_BIGMEM_MIN and the platform has them (Linux's madvise MADV_HUGEPAGE); a no-op
 * otherwise, and when the kernel declines. Call it before the array is first written. */
void tr_bigmem_advise(void *p, size_t bytes);

/* A kept block of at least `bytes` (and at most four times that) where there is one, else
 * malloc(bytes) advised as above (NULL when malloc fails). Its contents are undefined, as malloc's
 * are. */
void *tr_bigmem_malloc(size_t bytes);

/* A kept block of at least `bytes`, or NULL where none is kept: for a caller that has a way
 * without new memory when there is none. */
void *tr_bigmem_take(size_t bytes);

/* As tr_bigmem_malloc, aligned to `align` (aligned_alloc's rules: bytes a multiple of it). */
void *tr_bigmem_aligned(size_t align, size_t bytes);

/* Frees p (any malloc'd pointer, or NULL), keeping it for reuse when it is at least
 * TR_BIGMEM_MIN and the platform tells a block's size (glibc; not in the address
 * sanitizer's builds, where a use after free must still be caught). */
void tr_bigmem_free(void *p);

/* Frees every kept block (a scene's destruction calls it). */
void tr_bigmem_trim(void);

/* The bytes kept for reuse now. */
size_t tr_bigmem_kept(void);

/* Whether this build keeps freed blocks (1) or frees them at once (0). */
int tr_bigmem_keeps(void);

/* Sets every byte of every kept block to `byte`: tests use it to show that nothing built in
 * a kept block depends on what was in it. */
void tr_bigmem_fill_kept(int byte);

#endif
