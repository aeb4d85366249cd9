/* wbvh_sse2.c - the SSE2 traversal (x86; CMakeLists.txt adds -msse2, which x86-64 always has):
 * a node's 8 boxes as two halves of 4. */
#include "accel/wbvh.h"

#define TR_WBVH_TEMPLATE_ISA TR_WBVH_ISA_SSE2
#define TR_WBVH_TEMPLATE_SUFFIX sse2
#include "accel/wbvh_traverse.h"
