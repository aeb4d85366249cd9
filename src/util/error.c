#include "trac0r/error.h"

#include <errno.h>
#include <stdarg.h>
#include <stdio.h>

int tr_error_set(tr_error *err, tr_status code, const char *fmt, ...) {
    if (err) {
        err->code = code;
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(err->msg, sizeof err->msg, fmt, ap);
        va_end(ap);
    }
    return TR_ERR;
}

const char *tr_status_name(tr_status code) {
    /* No default: -Wswitch then flags a code added to the enum but not named here. */
    switch (code) {
    case TR_STATUS_OK:
        return "TR_STATUS_OK";
    case TR_STATUS_INVALID_ARGUMENT:
        return "TR_STATUS_INVALID_ARGUMENT";
    case TR_STATUS_INVALID_OPERATION:
        return "TR_STATUS_INVALID_OPERATION";
    case TR_STATUS_OUT_OF_MEMORY:
        return "TR_STATUS_OUT_OF_MEMORY";
    case TR_STATUS_LIMIT:
        return "TR_STATUS_LIMIT";
    case TR_STATUS_NOT_FOUND:
        return "TR_STATUS_NOT_FOUND";
    case TR_STATUS_IO:
        return "TR_STATUS_IO";
    case TR_STATUS_PARSE:
        return "TR_STATUS_PARSE";
    case TR_STATUS_UNSUPPORTED:
        return "TR_STATUS_UNSUPPORTED";
    case TR_STATUS_STALE_SCENE:
        return "TR_STATUS_STALE_SCENE";
    case TR_STATUS_CANCELLED:
        return "TR_STATUS_CANCELLED";
    case TR_STATUS_DEVICE:
        return "TR_STATUS_DEVICE";
    case TR_STATUS_COUNT:
        break;
    }
    return "TR_STATUS_UNKNOWN";
}

tr_status tr_status_from_errno(int errnum) {
    switch (errnum) {
    case ENOENT:
    case ENOTDIR:
        return TR_STATUS_NOT_FOUND;
    case ENOMEM:
        return TR_STATUS_OUT_OF_MEMORY;
    case ENAMETOOLONG:
        return TR_STATUS_INVALID_ARGUMENT;
    default:
        return TR_STATUS_IO;
    }
}
