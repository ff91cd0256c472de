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

// The largest file rs_io_read_file reads; readers that know what a file holds pass a tighter
// bound to rs_io_read_file_max (a site.json, a camera model: RS_IO_MAX_SMALL_FILE_BYTES).
#define RS_IO_MAX_FILE_BYTES       ((size_t)1 << 30)  // 1 GiB
#define RS_IO_MAX_SMALL_FILE_BYTES ((size_t)16 << 20) // 16 MiB

// Reads a whole file into a NUL-terminated buffer. Only a regular file is read: a FIFO, a device
// (/dev/zero), a socket or a folder is refused before anything is read (the open does not wait
// for a FIFO's writer), and so is a file larger than max_bytes (RS_ERR_INVALID "PATH: N bytes,
// more than the M bytes a ... may have"; a file that grows past the bound while being read too).
// Errors: RS_ERR_IO (missing, unreadable, not a regular file), RS_ERR_INVALID (too large),
// RS_ERR_NOMEM; the message starts with the path and never quotes the file's contents.
// out: *data, owned by the caller (free()); *len may be NULL.
rs_status rs_io_read_file_max(char **data, size_t *len,
                              // in
                              const char *path, size_t max_bytes, rs_err *err);

// rs_io_read_file_max with RS_IO_MAX_FILE_BYTES.
rs_status rs_io_read_file(char **data, size_t *len,
                          // in
                          const char *path, rs_err *err);

// The checks of rs_io_read_file_max without reading: for files a library opens by name
// (cv::FileStorage, cv::imread, mrcal). RS_OK when `path` is a regular file of at most max_bytes.
rs_status rs_io_check_regular(const char *path, size_t max_bytes, rs_err *err);

// An output file being written under a temporary name in the same folder as `path`.
typedef struct {
    FILE *f;                 // write here
    char *tmp_path;          // owned; NULL when writing straight into a device or FIFO
    char *path;              // owned: the final name
    struct rs_io_sink *sink; // owned: f's descriptor and the first write error (rs_io.c)
} rs_io_atomic;

// The one wording of a failed write, in buf (size bytes; returned): "disk full writing PATH (...)"
// when errnum is ENOSPC or EDQUOT, else "PATH: write failed: <strerror>". For the cli's own
// standard output too, so that a full disk reads the same whoever wrote.
const char *rs_io_write_problem(char *buf, size_t size, const char *path, int errnum);

// True when the file system holding `path` (a file or folder) has no block left for this user
// (statvfs: f_bavail 0): why a program that does not say so itself (povray: "Fatal error in
// renderer") failed to write there. False when it cannot be told.
bool rs_io_disk_full(const char *path);

// Opens `path` for atomic writing. On success a->f is open and must be finished with
// rs_io_atomic_commit() or rs_io_atomic_abort(). A `path` that exists and is not a regular file
// -- /dev/null, /dev/stdout, a FIFO -- is written straight into (renaming a file over it would
// replace the device: as root, `-o /dev/null` once turned /dev/null into a regular file); a folder
// is refused (RS_ERR_IO, "is a folder").
rs_status rs_io_atomic_open(rs_io_atomic *a, const char *path, rs_err *err);
// Flushes, fsyncs, closes and renames into place. Every write into a->f is checked to the end:
// a failed or short write (however many calls before), the fsync, the close and the rename are
// RS_ERR_IO naming the path ("disk full writing PATH" for ENOSPC, rs_io_write_problem), and then
// nothing is left under the final name. After rs_io_atomic_release, the file the library wrote
// is fsynced by name. Frees a's strings whatever the outcome; on failure removes the temporary.
rs_status rs_io_atomic_commit(rs_io_atomic *a, rs_err *err);
// Ends an atomic output after its writer returned st: commits when st is RS_OK; when the writer
// failed because a write into a->f failed (its stream has an error), commits all the same so that
// the commit's message -- the cause, "disk full writing PATH" -- replaces the writer's "write
// error" (the commit then fails and leaves nothing); else aborts and returns st.
rs_status rs_io_atomic_finish(rs_io_atomic *a, rs_status st, rs_err *err);
// Closes a->f (a->f becomes NULL) but keeps the temporary file, so that a library that writes
// by file name (mrcal_write_cameramodel_file, cv::FileStorage, povray) can write a->tmp_path;
// rs_io_atomic_commit() then renames it into place.
rs_status rs_io_atomic_release(rs_io_atomic *a, rs_err *err);
// Closes and removes the temporary file; frees a's strings. Accepts a zeroed or finished `a`.
void rs_io_atomic_abort(rs_io_atomic *a);

// Writes `len` bytes to `path` atomically.
rs_status rs_io_write_file(const char *path, const void *data, size_t len, rs_err *err);

// Puts the file src at dst as a hard link (the same file system), else as a copy of its bytes
// written atomically (rs_io_write_file). dst must not exist yet. Returns RS_ERR_IO (src
// unreadable, dst not writable) / RS_ERR_NOMEM.
rs_status rs_io_link_or_copy(const char *src, const char *dst, rs_err *err);

// mkdir -p. Succeeds if the folder already exists.
rs_status rs_io_mkdir_p(const char *path, rs_err *err);

// Joins a folder and a relative path with one '/': returns a malloc'ed string (caller frees),
// or NULL when out of memory. An absolute `rel` is returned as a copy of itself.
char *rs_io_join(const char *dir, const char *rel);

// True when `path` ends in "." followed by `ext` (no dot, compared without case): ("a/b.YML",
// "yml") is true, ("a.yml/b", "yml") and ("yml", "yml") are false.
bool rs_io_has_extension(const char *path, const char *ext);

// The one rule for a name that becomes part of a file name or a table row (camera and landmark
// ids): 1..64 bytes, no control character (bytes below 0x20, and 0x7f; C1 controls and the
// invisible format characters that reorder or hide text: bidirectional overrides and isolates,
// zero-width spaces and joiners, U+FEFF), no '/' or '\\', no ".." anywhere, no blank at either end. Returns NULL when `name` follows it, else what is wrong
// (a static string: "is empty", "contains '/'", ...). UTF-8 letters are allowed.
const char *rs_io_name_problem(const char *name);

// dir/<name><suffix> (malloc'ed: caller frees): the one way an output named after an id is
// built, so that none escapes its folder. NULL, with RS_ERR_INVALID naming the name and the
// rule it breaks (rs_io_name_problem), or RS_ERR_NOMEM, in err.
char *rs_io_child_path(const char *dir, const char *name, const char *suffix, rs_err *err);

// Removes the file `path` if there is one (unlink: a folder is never removed; a link is removed,
// not what it points to; a device, FIFO or socket is never removed: RS_ERR_IO). *removed (may be NULL) says whether a file was removed. A missing path
// is RS_OK with *removed false; any other failure is RS_ERR_IO naming the path.
rs_status rs_io_remove_if_exists(const char *path, bool *removed, rs_err *err);

// Removes path and everything under it (files, folders, links themselves), best effort: what
// cannot be removed is left. A missing path is not an error.
void rs_io_remove_tree(const char *path);

// Removes, under dir and its subfolders, every regular file named like rs_io_atomic_open's
// temporaries ("<name>.tmp.XXXXXX"): what a process killed while writing leaves behind. Only for
// a folder whose writers are all gone, i.e. one the caller holds rs_io_lock_dir on. Best effort;
// returns how many were removed. Not thread-safe (nftw has no user pointer).
size_t rs_io_remove_stale_temporaries(const char *dir);

// When `name` (a file name, no folder) is one of rs_io_atomic_open's temporaries,
// "<base>.tmp.XXXXXX" (six letters or digits), the length of <base>; else 0. For a caller that
// removes only the temporaries of its own file names.
size_t rs_io_temporary_base_len(const char *name);

// ---- folder locks ----

// An exclusive lock on a folder, so that two processes never write one output folder at once
// (two `roadside synth` runs into one dataset would overwrite each other's work files). It is
// flock(2) on DIR/.lock: the kernel drops it when the holder exits, however it ends, so a crashed
// holder never leaves a stale lock. The lock file holds one line, "<pid> <start time> <what>",
// that a second process quotes; it is removed by rs_io_unlock (one left by a crash is harmless:
// the next holder takes it over). Forked children share their parent's lock (the same open file;
// they must not call rs_io_unlock); programs they exec do not inherit it (close-on-exec).
typedef struct {
    int fd;     // the lock file, open while the lock is held (path != NULL)
    char *path; // owned: DIR/.lock while held; NULL otherwise
} rs_io_lock;

// Takes the lock on the existing folder `dir` for `what` (a short text, e.g. "roadside synth")
// without waiting. When another process holds it, returns RS_ERR_IO with
//   "DIR is in use by WHAT (pid N) since YYYY-MM-DD HH:MM:SS +ZZZZ: ..."
// and changes nothing in dir. Errors: RS_ERR_IO (the lock file cannot be made, is not a regular
// file, or the file system refuses locks), RS_ERR_NOMEM. On failure *lock is not held (path NULL).
// out: *lock, to be released with rs_io_unlock
rs_status rs_io_lock_dir(rs_io_lock *lock,
                         // in
                         const char *dir, const char *what, rs_err *err);

// Removes the lock file and releases the lock. Accepts NULL, a zeroed lock and a lock not held.
void rs_io_unlock(rs_io_lock *lock);

#ifdef __cplusplus
}
#endif
