/* wbvh_avx512.c - the AVX-512 traversal (x86; this file alone is compiled with -mavx2
 * -mavx512f -mavx512vl and is only called on CPUs that report AVX-512F and VL): the AVX2
 * code, with the node's hit mask taken straight from the compare. */
#include "accel/wbvh.h"

#define TR_WBVH_TEMPLATE_ISA TR_WBVH_ISA_AVX512
#define TR_WBVH_TEMPLATE_SUFFIX avx512
#include "accel/wbvh_traverse.h"
