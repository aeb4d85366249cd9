/* registry.h - the names of material types, integrators and acceleration structures.
 *
 * Each kind is one X-macro list (TR_MATERIAL_TYPES in trac0r/material_types.h,
 * TR_INTEGRATORS in trac0r/integrator_types.h, TR_ACCEL_TYPES in trac0r/accel.h); these
 * functions are generated from the lists (src/util/registry.c), so that every place that
 * parses or prints a name (scene files, the command line, --help) agrees with the
 * kernel's enums. Name lookups are exact and case-sensitive.
 *
 *     int k = tr_integrator_from_name("pt");  // TR_INTEGRATOR_PT, or -1
 *     size_t n;
 *     const char *const *names = tr_integrator_names(&n);  // "pt", "naive"
 */
#ifndef TRAC0R_REGISTRY_H
#define TRAC0R_REGISTRY_H

#include <stddef.h>
#include <stdint.h>

#include "trac0r/integrator_types.h"
#include "trac0r/material_types.h"
#include "trac0r/accel.h"
#include "trac0r/error.h"

/* Material types: TR_MATERIAL_* <-> scene-file name ("emitter", ...). from_name returns -1
 * for an unknown name; name returns NULL for an unknown type. */
int tr_material_type_from_name(const char *name);
const char *tr_material_type_name(uint32_t type);
/* The names in list order; *count receives their number. */
const char *const *tr_material_type_names(size_t *count);

/* Integrators: TR_INTEGRATOR_* <-> name ("pt", "naive"). from_name returns -1 for an
 * unknown name; name and description return NULL for an unknown integrator. */
int tr_integrator_from_name(const char *name);
const char *tr_integrator_name(int integrator);
const char *tr_integrator_description(int integrator);
const char *const *tr_integrator_names(size_t *count);

/* Acceleration structures (tr_accel_from_name, tr_accel_name and tr_accel_available are
 * in trac0r/accel.h): the description, NULL for an unknown type, and every name in list
 * order, available in this build or not. */
const char *tr_accel_description(tr_accel_type type);
const char *const *tr_accel_names(size_t *count);

/* Writes names[0 .. count) into buf as "a, b, c" (last_sep NULL) or "a, b or c" (last_sep
 * " or "), for messages and --help; always NUL-terminates (truncating when buf is short). */
void tr_names_join(char *buf, size_t size, const char *const *names, size_t count,
                   const char *last_sep);

/* The name of names[0 .. count) closest to s in edit distance (adjacent transpositions
 * counted as one edit), if within 1 + strlen(s) / 4 edits (at most 3); NULL if none is:
 * what a "did you mean" names. */
const char *tr_names_closest(const char *s, const char *const *names, size_t count);

/* Parses a comma-separated list of names ("naive,pt") through `lookup` (a name's value,
 * or a negative number for an unknown name) into out[0 .. max): returns how many (at
 * least 1), or -1 with err set (TR_STATUS_INVALID_ARGUMENT) when an item is unknown or
 * empty ("a,,b", "a,"), or the list holds more than max items. Messages begin with
 * `what` (the option or key), call an unknown item "unknown <kind>" and end with
 * "(available: <available>)" when that is given.
 * The list is read in place, whatever its length: nothing is cut. */
int tr_names_parse_list(const char *list, int (*lookup)(const char *name), int *out, int max,
                        const char *what, const char *kind, const char *available, tr_error *err);

#endif
