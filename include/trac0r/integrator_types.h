/* integrator_types.h - the one list of integrators.
 *
 * Each row is X(NAME, value, "name", "description") and generates the TR_INTEGRATOR_NAME
 * constant the kernel dispatches on (kernel.h) and, on the host, the names
 * tr_integrator_from_name / tr_integrator_name know and the descriptions --help prints
 * (src/util/registry.c). Rows are in the order messages list them: the default first. A
 * new integrator is one row here, its integrator_NAME.h and its case in
 * tr_render_sample. Valid C99 and OpenCL C. */
#ifndef TRAC0R_INTEGRATOR_TYPES_H
#define TRAC0R_INTEGRATOR_TYPES_H

/* clang-format off */
#define TR_INTEGRATORS(X)                                                                    \
    X(PT,    1, "pt",    "next-event estimation, MIS and GGX glossy")      \
    X(NAIVE, 0, "naive", "the thesis's path tracer")                     \
    X(BDPT,  2, "bdpt",  "bidirectional path tracing, MIS over all strategies (CPU)")  \
    X(VCM,   3, "vcm",   "vertex connection and merging: bdpt plus photon merging (CPU)")
/* clang-format on */

#define TR_INTEGRATOR_ENUM_ROW(id, value, name, description) TR_INTEGRATOR_##id = value,
enum tr_integrator_type { TR_INTEGRATORS(TR_INTEGRATOR_ENUM_ROW) };
#undef TR_INTEGRATOR_ENUM_ROW

#endif
