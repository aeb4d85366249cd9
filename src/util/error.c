#include "trac0r/error.h"

#include <stdarg.h>
#include <stdio.h>

int tr_error_set(tr_error *err, const char *fmt, ...) {
    if (err) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(err->msg, sizeof err->msg, fmt, ap);
        va_end(ap);
    }
    return TR_ERR;
}
