/* wbvh_avx2.c - the AVX2 traversal (x86; this file alone is compiled with -mavx2 and is
 * only called on CPUs that report AVX2): a node's 8 boxes in one 256-bit operation. */
#include "accel/wbvh.h"

#define TR_WBVH_TEMPLATE_ISA TR_WBVH_ISA_AVX2
#define TR_WBVH_TEMPLATE_SUFFIX avx2
#include "accel/wbvh_traverse.h"
