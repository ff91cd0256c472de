// rs_io.h -- reading whole files, and writing outputs atomically (temporary name, then rename).
//
// An output is never visible under its final name until it is complete: a crash, a full disk or
// an error mid-way leaves at most a "<path>.tmp.XXXXXX" file, never a half-written "<path>".
#pragma once
#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>

#include "core/rs_status.h"

#ifdef __cplusplus
extern "C" {
#endif

// Reads a whole file into a NUL-terminated buffer.
// out: *data, owned by the caller (free()); *len may be NULL.
rs_status rs_io_read_file(char **data, size_t *len,
                          // in
                          const char *path, rs_err *err);

// An output file being written under a temporary name in the same folder as `path`.
typedef struct {
    FILE *f;        // write here
    char *tmp_path; // owned
    char *path;     // owned: the final name
} rs_io_atomic;

// Opens `path` for atomic writing. On success a->f is open and must be finished with
// rs_io_atomic_commit() or rs_io_atomic_abort().
rs_status rs_io_atomic_open(rs_io_atomic *a, const char *path, rs_err *err);
// Flushes, fsyncs, closes and renames into place. Frees a's strings whatever the outcome; on
// failure removes the temporary file.
rs_status rs_io_atomic_commit(rs_io_atomic *a, rs_err *err);
// Closes a->f (a->f becomes NULL) but keeps the temporary file, so that a library that writes
// by file name (mrcal_write_cameramodel_file, cv::FileStorage, povray) can write a->tmp_path;
// rs_io_atomic_commit() then renames it into place.
rs_status rs_io_atomic_release(rs_io_atomic *a, rs_err *err);
// Closes and removes the temporary file; frees a's strings. Accepts a zeroed or finished `a`.
void rs_io_atomic_abort(rs_io_atomic *a);

// Writes `len` bytes to `path` atomically.
rs_status rs_io_write_file(const char *path, const void *data, size_t len, rs_err *err);

// mkdir -p. Succeeds if the folder already exists.
rs_status rs_io_mkdir_p(const char *path, rs_err *err);

// Joins a folder and a relative path with one '/': returns a malloc'ed string (caller frees),
// or NULL when out of memory. An absolute `rel` is returned as a copy of itself.
char *rs_io_join(const char *dir, const char *rel);

// True when `path` ends in "." followed by `ext` (no dot, compared without case): ("a/b.YML",
// "yml") is true, ("a.yml/b", "yml") and ("yml", "yml") are false.
bool rs_io_has_extension(const char *path, const char *ext);

// The one rule for a name that becomes part of a file name or a table row (camera and landmark
// ids): 1..64 bytes, no control character (bytes below 0x20, and 0x7f), no '/' or '\\', no ".."
// anywhere, no blank at either end. Returns NULL when `name` follows it, else what is wrong
// (a static string: "is empty", "contains '/'", ...). UTF-8 letters are allowed.
const char *rs_io_name_problem(const char *name);

// dir/<name><suffix> (malloc'ed: caller frees): the one way an output named after an id is
// built, so that none escapes its folder. NULL, with RS_ERR_INVALID naming the name and the
// rule it breaks (rs_io_name_problem), or RS_ERR_NOMEM, in err.
char *rs_io_child_path(const char *dir, const char *name, const char *suffix, rs_err *err);

// Removes path and everything under it (files, folders, links themselves), best effort: what
// cannot be removed is left. A missing path is not an error.
void rs_io_remove_tree(const char *path);

#ifdef __cplusplus
}
#endif
