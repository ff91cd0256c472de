// rs_status.h -- roadside's one set of result codes, and the detail message that goes with them.
//
// Every fallible library function returns an rs_status (RS_OK == 0 is success) and takes an
// optional `rs_err *err` (may be NULL) that receives a one-line detail naming what is at fault,
// formatted as "FILE:LINE: FIELD: what is wrong" wherever a file, line or field is known.
// The library never prints and never exits: the cli decides what the user sees.
#pragma once
#include <stdarg.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef enum {
    RS_OK = 0,
    RS_ERR_IO,          // a file could not be opened, read, written or renamed
    RS_ERR_PARSE,       // malformed JSON, GeoJSON, CSV, YAML or number
    RS_ERR_INVALID,     // well-formed but invalid: out of range, non-finite, inconsistent
    RS_ERR_NOT_FOUND,   // a named thing (camera, landmark, file) does not exist
    RS_ERR_NOMEM,       // allocation failed
    RS_ERR_DEGENERATE,  // the geometry cannot determine the answer (too few, collinear, ...)
    RS_ERR_NOCONVERGE,  // an iterative method did not converge
    RS_ERR_EXTERNAL,    // a library or external program failed (exception, exit status)
    RS_ERR_UNSUPPORTED, // valid input that this build does not handle
    RS_ERR_USAGE,       // bad arguments from the caller
    RS_STATUS_COUNT
} rs_status;

// Detail of the last error. Fixed size: no allocation on the error path.
typedef struct {
    rs_status status;
    char msg[1024];
} rs_err;

// Short fixed text of a status ("I/O error", ...). Never NULL; unknown codes give "unknown error".
const char *rs_strerror(rs_status status);

// Sets err (if not NULL) to status and a printf-style message, and returns status, so that
// callers can write `return rs_err_set(err, RS_ERR_PARSE, "%s:%d: u: not a number", path, line);`
rs_status rs_err_set(rs_err *err, rs_status status, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
rs_status rs_err_vset(rs_err *err, rs_status status, const char *fmt, va_list ap);

// Prefixes err->msg with "prefix: " (for adding context such as a camera id on the way up).
// Returns err->status (RS_OK if err is NULL).
rs_status rs_err_prefix(rs_err *err, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

#ifdef __cplusplus
}
#endif
