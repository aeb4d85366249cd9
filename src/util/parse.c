/* parse.c - the shared number rules (trac0r/parse.h). */
#include "trac0r/parse.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Digits from *p, accumulated without wrapping; the first byte must be a digit. */
static int digits(const char **p, uint64_t *out) {
    const char *s = *p;
    if (*s < '0' || *s > '9') {
        return TR_ERR;
    }
    uint64_t v = 0;
    for (; *s >= '0' && *s <= '9'; ++s) {
        const unsigned d = (unsigned)(*s - '0');
        if (v > (UINT64_MAX - d) / 10u) {
            return TR_ERR;
        }
        v = v * 10u + d;
    }
    *p = s;
    *out = v;
    return TR_OK;
}

int tr_parse_uint64(const char *text, uint64_t lo, uint64_t hi, uint64_t *out) {
    const char *p = text;
    uint64_t v = 0;
    if (!text || digits(&p, &v) != TR_OK || *p != '\0' || v < lo || v > hi) {
        return TR_ERR;
    }
    *out = v;
    return TR_OK;
}

int tr_parse_int64(const char *text, int64_t lo, int64_t hi, int64_t *out) {
    if (!text) {
        return TR_ERR;
    }
    const int neg = *text == '-';
    const char *p = text + neg;
    uint64_t v = 0;
    if (digits(&p, &v) != TR_OK || *p != '\0') {
        return TR_ERR;
    }
    int64_t x;
    if (neg) {
        if (v > (uint64_t)INT64_MAX + 1u) {
            return TR_ERR;
        }
        x = v == (uint64_t)INT64_MAX + 1u ? INT64_MIN : -(int64_t)v;
    } else {
        if (v > (uint64_t)INT64_MAX) {
            return TR_ERR;
        }
        x = (int64_t)v;
    }
    if (x < lo || x > hi) {
        return TR_ERR;
    }
    *out = x;
    return TR_OK;
}

/* strtod on the whole text, which must start with a sign, a digit or a point (strtod
 * itself skips blanks and reads "inf" and "nan"). */
static int whole_double(const char *text, double *out) {
    if (!text) {
        return TR_ERR;
    }
    const char c = text[*text == '-' || *text == '+'];
    if (!((c >= '0' && c <= '9') || c == '.')) {
        return TR_ERR;
    }
    char *end = NULL;
    errno = 0;
    const double x = strtod(text, &end);
    if (end == text || *end != '\0' || errno == ERANGE || !isfinite(x)) {
        return TR_ERR;
    }
    *out = x;
    return TR_OK;
}

int tr_parse_float(const char *text, float lo, float hi, float *out) {
    double x = 0.0;
    if (whole_double(text, &x) != TR_OK) {
        return TR_ERR;
    }
    const float f = (float)x;
    if (!isfinite(f) || f < lo || f > hi) {
        return TR_ERR;
    }
    *out = f;
    return TR_OK;
}

int tr_parse_double(const char *text, double lo, double hi, double *out) {
    double x = 0.0;
    if (whole_double(text, &x) != TR_OK || x < lo || x > hi) {
        return TR_ERR;
    }
    *out = x;
    return TR_OK;
}

int tr_parse_size(const char *text, uint32_t max_side, uint32_t *w, uint32_t *h) {
    if (!text) {
        return TR_ERR;
    }
    const char *p = text;
    uint64_t x = 0, y = 0;
    if (digits(&p, &x) != TR_OK || *p != 'x') {
        return TR_ERR;
    }
    ++p;
    if (digits(&p, &y) != TR_OK || *p != '\0' || x < 1 || y < 1 || x > max_side || y > max_side) {
        return TR_ERR;
    }
    *w = (uint32_t)x;
    *h = (uint32_t)y;
    return TR_OK;
}

int tr_parse_fraction(const char *text, uint32_t max_n, uint32_t *n) {
    if (!text) {
        return TR_ERR;
    }
    uint64_t k = 0;
    double f = 0.0;
    if (strcmp(text, "\xc2\xbd") == 0 || strcmp(text, "\xc2\xbc") == 0) { /* the signs */
        k = text[1] == '\xbd' ? 2u : 4u;
    } else if (strncmp(text, "1/", 2) == 0) {
        if (tr_parse_uint64(text + 2, 1, max_n, &k) != TR_OK) {
            return TR_ERR;
        }
    } else if (tr_parse_double(text, 1e-9, 1.0, &f) == TR_OK) {
        const double r = floor(1.0 / f + 0.5);
        k = r <= (double)max_n && fabs(r * f - 1.0) < 1e-6 ? (uint64_t)r : 0u;
    }
    if (k < 1 || k > max_n) {
        return TR_ERR;
    }
    *n = (uint32_t)k;
    return TR_OK;
}

int tr_parse_rect(const char *text, uint32_t max, uint32_t out[4]) {
    const char *p = text;
    uint64_t v[4];
    for (int k = 0; k < 4; ++k) {
        if (!p || digits(&p, &v[k]) != TR_OK || v[k] > max || *p != (k < 3 ? ',' : '\0')) {
            return TR_ERR;
        }
        p += k < 3;
    }
    if (v[2] == 0 || v[3] == 0) {
        return TR_ERR;
    }
    for (int k = 0; k < 4; ++k) {
        out[k] = (uint32_t)v[k];
    }
    return TR_OK;
}
