#include "core/rs_status.h"

#include <stdio.h>
#include <string.h>

const char *rs_strerror(rs_status status)
{
    switch (status) {
    case RS_OK: return "success";
    case RS_ERR_IO: return "I/O error";
    case RS_ERR_PARSE: return "parse error";
    case RS_ERR_INVALID: return "invalid input";
    case RS_ERR_NOT_FOUND: return "not found";
    case RS_ERR_NOMEM: return "out of memory";
    case RS_ERR_DEGENERATE: return "degenerate geometry";
    case RS_ERR_NOCONVERGE: return "did not converge";
    case RS_ERR_EXTERNAL: return "external library or program failed";
    case RS_ERR_UNSUPPORTED: return "unsupported";
    case RS_ERR_USAGE: return "usage error";
    case RS_STATUS_COUNT: break;
    }
    return "unknown error";
}

rs_status rs_err_vset(rs_err *err, rs_status status, const char *fmt, va_list ap)
{
    if (err) {
        err->status = status;
        vsnprintf(err->msg, sizeof err->msg, fmt, ap);
    }
    return status;
}

rs_status rs_err_set(rs_err *err, rs_status status, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    rs_err_vset(err, status, fmt, ap);
    va_end(ap);
    return status;
}

rs_status rs_err_prefix(rs_err *err, const char *fmt, ...)
{
    if (!err) return RS_OK;
    char prefix[256];
    va_list ap;
    va_start(ap, fmt);
    int np = vsnprintf(prefix, sizeof prefix - 2, fmt, ap);
    va_end(ap);
    if (np < 0) return err->status;
    if ((size_t)np > sizeof prefix - 3) np = (int)sizeof prefix - 3;
    memcpy(prefix + np, ": ", 3);
    np += 2;
    // shift the old message right by np (truncating its tail), then put the prefix in front
    size_t nold = strnlen(err->msg, sizeof err->msg - 1);
    if (nold + (size_t)np > sizeof err->msg - 1) nold = sizeof err->msg - 1 - (size_t)np;
    memmove(err->msg + np, err->msg, nold);
    memcpy(err->msg, prefix, (size_t)np);
    err->msg[np + nold] = '\0';
    return err->status;
}
