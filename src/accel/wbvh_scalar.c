/* wbvh_scalar.c - the portable traversal, compiled for every target with the library's own flags:
 * the fallback on CPUs without the SIMD ISAs, and the reference the tests compare them with. */
#include "accel/wbvh.h"

#define TR_WBVH_TEMPLATE_ISA TR_WBVH_ISA_SCALAR
#define TR_WBVH_TEMPLATE_SUFFIX scalar
#include "accel/wbvh_traverse.h"
