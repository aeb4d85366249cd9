/* parse.h - the number rules every command-line option, environment variable and scene
 * key of trac0r follows, in one place:
 *
 *   - the whole text is the number: no leading or trailing blanks, nothing after it;
 *   - unsigned values have no sign; a value too large for its type is refused, never
 *     wrapped (4294967304 is not 8);
 *   - a value and its limits are compared in the value's own type: a float option whose
 *     documented minimum is 0.1 accepts "0.1", which as a float is that very minimum;
 *   - "WxH" sizes are two such unsigned numbers around one 'x'.
 *
 * Each returns TR_OK and sets *out, or TR_ERR leaving *out alone; the caller words the
 * message (it knows the option's name). */
#ifndef TRAC0R_PARSE_H
#define TRAC0R_PARSE_H

#include <stdint.h>

#include "trac0r/error.h"

#ifdef __cplusplus
extern "C" {
#endif

/* A decimal integer in lo..hi; a '-' sign only where lo is negative. */
int tr_parse_int64(const char *text, int64_t lo, int64_t hi, int64_t *out);
/* A decimal integer in lo..hi, no sign. */
int tr_parse_uint64(const char *text, uint64_t lo, uint64_t hi, uint64_t *out);
/* A finite number (decimal or exponent form) that, rounded to float, is in lo..hi. */
int tr_parse_float(const char *text, float lo, float hi, float *out);
/* A finite number in lo..hi, as a double. */
int tr_parse_double(const char *text, double lo, double hi, double *out);
/* "WxH": two unsigned integers in 1..max_side each. */
int tr_parse_size(const char *text, uint32_t max_side, uint32_t *w, uint32_t *h);
/* "X,Y,W,H": four unsigned integers up to max each, W and H at least 1. */
int tr_parse_rect(const char *text, uint32_t max, uint32_t out[4]);
/* A fraction 1/N with N in 1..max_n, written "1/N", as a number ("0.25": exactly 1/N to
 * 1e-6) or as the signs "½" and "¼" (UTF-8); *n gets N. */
int tr_parse_fraction(const char *text, uint32_t max_n, uint32_t *n);

#ifdef __cplusplus
}
#endif

#endif /* TRAC0R_PARSE_H */
