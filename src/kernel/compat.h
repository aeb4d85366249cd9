/* compat.h - the only file of the kernel that differs between the CPU and OpenCL C.
 *
 * Everything under src/kernel/ is written in a C99 subset that also compiles as
 * OpenCL C 1.2: no recursion, no function pointers, no dynamic memory, no libc
 * beyond the math functions mapped below. Host code includes the kernel headers
 * directly; the OpenCL backend hands the same text to the device compiler. */
#ifndef TR_KERNEL_COMPAT_H
#define TR_KERNEL_COMPAT_H

#if defined(__OPENCL_C_VERSION__) || defined(__OPENCL_VERSION__)
/* ---- OpenCL C --------------------------------------------------------- */
typedef uint uint32_t;
typedef int int32_t;
typedef ulong uint64_t;
typedef long int64_t;
#define TR_FN static inline
#define TR_FN_INLINE static inline
/* Out of line on a device too, as on the host: the material stage and the principled
 * BSDF's lobes, inlined at each of their call sites (every light's next-event estimate in
 * pt and its wavefront, ReSTIR's passes), made the frame's program about 3x as long (a
 * proxy, clang's PTX with a GPU driver's eager inlining fed to ptxas: 143,637 lines and
 * 39 s against 51,937 lines and 11 s), and a GPU driver compiles it for every process.
 * TR_CL_INLINE_ALL (TRAC0R_OPENCL_INLINE=1, src/device/opencl.c) inlines them again,
 * to measure what the calls cost at run time. */
#ifdef TR_CL_INLINE_ALL
#define TR_FN_NOINLINE static inline
#else
#define TR_FN_NOINLINE static __attribute__((noinline, unused))
#endif
/* The BVH walk is one real function on a device: inlined, each of its call sites (camera
 * and bounce rays, shadow rays of the lights, the environment and the sun, cut-outs)
 * kept a 512-byte stack of its own in private memory, 2 KB per work item in all. Out of
 * line, pt's 1080p frame on an H100 went from 11.3 to 8.3 ms (docs/gpu.md). */
#define TR_FN_TRAVERSE static __attribute__((noinline))
#define TR_GLOBAL __global
#define TR_CONST_GLOBAL __global const
#define tr_sqrtf(x) sqrt(x)
#define tr_sinf(x) sin(x)
#define tr_cosf(x) cos(x)
#define tr_tanf(x) tan(x)
#define tr_atan2f(y, x) atan2((y), (x))
#define tr_acosf(x) acos(x)
#define tr_powf(x, y) pow((x), (y))
#define tr_fabsf(x) fabs(x)
#define tr_expf(x) exp(x)
#define tr_expm1f(x) expm1(x)
#define tr_log1pf(x) log1p(x)
#define tr_floorf(x) floor(x)
#define tr_atan2f(y, x) atan2((y), (x))
#define tr_fminf(a, b) fmin((a), (b))
#define tr_fmaxf(a, b) fmax((a), (b))
#define tr_isfinite(x) isfinite(x)
#define TR_INFINITY INFINITY
#define TR_STATIC_ASSERT(cond, msg)
#else
/* ---- C11 on the host -------------------------------------------------- */
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#define TR_FN static inline
/* Inlining decides the hot paths' speed on the CPU (the device compilers inline
 * everything but TR_FN_TRAVERSE): TR_FN_INLINE for a body a caller copies per constant
 * argument (tr_render_grid_rows), TR_FN_NOINLINE for a large path that only some scenes take
 * (textures, vertex normals, cut-outs, the principled BSDF, the environment), so that
 * its size does not push the code every scene runs out of line. */
#define TR_FN_INLINE static inline __attribute__((always_inline))
#define TR_FN_NOINLINE static __attribute__((noinline, unused))
#define TR_FN_TRAVERSE static inline
#define TR_GLOBAL
#define TR_CONST_GLOBAL const
#define tr_sqrtf(x) sqrtf(x)
#define tr_sinf(x) sinf(x)
#define tr_cosf(x) cosf(x)
#define tr_tanf(x) tanf(x)
#define tr_atan2f(y, x) atan2f((y), (x))
#define tr_acosf(x) acosf(x)
#define tr_powf(x, y) powf((x), (y))
#define tr_fabsf(x) fabsf(x)
#define tr_expf(x) expf(x)
#define tr_expm1f(x) expm1f(x)
#define tr_log1pf(x) log1pf(x)
#define tr_floorf(x) floorf(x)
#define tr_atan2f(y, x) atan2f((y), (x))
/* fminf/fmaxf semantics (a NaN operand yields the other one) without the libm call
 * that gcc emits for them unless NaNs are assumed away; the slab test relies on this. */
static inline float tr_fminf(float a, float b) {
    return b != b ? a : (a < b ? a : b);
}
static inline float tr_fmaxf(float a, float b) {
    return b != b ? a : (a > b ? a : b);
}
#define tr_isfinite(x) isfinite(x)
#define TR_INFINITY INFINITY
#define TR_STATIC_ASSERT(cond, msg) _Static_assert(cond, msg)
#endif

#define TR_PI 3.14159265358979323846f
#define TR_TWO_PI 6.28318530717958647692f
#define TR_HALF_PI 1.57079632679489661923f
#define TR_INV_PI 0.31830988618379067154f

#endif
