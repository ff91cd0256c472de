#define _GNU_SOURCE // fopencookie(), nftw()
#include "core/rs_io.h"

#include <ctype.h>
#include <errno.h>
#include <fcntl.h>
#include <ftw.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <time.h>
#include <unistd.h>

// Opens path for reading without waiting (a FIFO with no writer would block) and checks that it
// is a regular file of at most max_bytes. Returns the descriptor (blocking again) or -1 (err set).
static int open_regular(const char *path, size_t max_bytes, rs_err *err)
{
    const int fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);
    if (fd < 0) {
        rs_err_set(err, RS_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
        return -1;
    }
    struct stat sb;
    if (fstat(fd, &sb) != 0 || !S_ISREG(sb.st_mode)) {
        rs_err_set(err, RS_ERR_IO, "%s: not a regular file (%s): refused", path,
                   S_ISDIR(sb.st_mode)                          ? "a folder"
                   : S_ISFIFO(sb.st_mode)                       ? "a FIFO"
                   : S_ISCHR(sb.st_mode) || S_ISBLK(sb.st_mode) ? "a device"
                                                                : "not a plain file");
        close(fd);
        return -1;
    }
    if ((uint64_t)sb.st_size > (uint64_t)max_bytes) {
        rs_err_set(err, RS_ERR_INVALID, "%s: %lld bytes, more than the %zu bytes such a file may have", path,
                   (long long)sb.st_size, max_bytes);
        close(fd);
        return -1;
    }
    const int flags = fcntl(fd, F_GETFL);
    if (flags >= 0) fcntl(fd, F_SETFL, flags & ~O_NONBLOCK);
    return fd;
}

rs_status rs_io_check_regular(const char *path, size_t max_bytes, rs_err *err)
{
    const int fd = open_regular(path, max_bytes, err);
    if (fd < 0) return err ? err->status : RS_ERR_IO;
    close(fd);
    return RS_OK;
}

rs_status rs_io_read_file(char **data, size_t *len, const char *path, rs_err *err)
{
    return rs_io_read_file_max(data, len, path, RS_IO_MAX_FILE_BYTES, err);
}

rs_status rs_io_read_file_max(char **data, size_t *len, const char *path, size_t max_bytes, rs_err *err)
{
    *data = NULL;
    if (len) *len = 0;
    rs_err local = {0};
    const int fd = open_regular(path, max_bytes, err ? err : &local);
    if (fd < 0) return err ? err->status : local.status;
    size_t cap = 4096, n = 0;
    char *buf = malloc(cap);
    rs_status st = buf ? RS_OK : rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", path);
    while (st == RS_OK) {
        if (cap - n < 2) {
            char *grown = realloc(buf, cap * 2);
            if (!grown) {
                st = rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", path);
                break;
            }
            buf = grown;
            cap *= 2;
        }
        const ssize_t got = read(fd, buf + n, cap - n - 1);
        if (got < 0 && errno == EINTR) continue;
        if (got < 0) st = rs_err_set(err, RS_ERR_IO, "%s: read error: %s", path, strerror(errno));
        if (got <= 0) break;
        n += (size_t)got;
        if (n > max_bytes)
            st = rs_err_set(err, RS_ERR_INVALID, "%s: more than the %zu bytes such a file may have (it grew)", path,
                            max_bytes);
    }
    close(fd);
    if (st != RS_OK) {
        free(buf);
        return st;
    }
    buf[n] = '\0';
    *data = buf;
    if (len) *len = n;
    return RS_OK;
}

const char *rs_io_write_problem(char *buf, size_t size, const char *path, int errnum)
{
    if (errnum == ENOSPC || errnum == EDQUOT)
        snprintf(buf, size, "disk full writing %s (%s)", path, strerror(errnum));
    else
        snprintf(buf, size, "%s: write failed: %s", path, strerror(errnum ? errnum : EIO));
    return buf;
}

bool rs_io_disk_full(const char *path)
{
    struct statvfs sv;
    return statvfs(path, &sv) == 0 && sv.f_bavail == 0;
}

// Sets err to rs_io_write_problem's text (RS_ERR_IO).
static rs_status write_failed(rs_err *err, const char *path, int errnum)
{
    char text[sizeof err->msg];
    return rs_err_set(err, RS_ERR_IO, "%s", rs_io_write_problem(text, sizeof text, path, errnum));
}

// The output's descriptor behind its FILE (fopencookie): every write(2) goes through sink_write,
// which keeps the first errno of a failed or short write, so that rs_io_atomic_commit reports the
// real cause ("disk full") however many calls later the caller looks.
struct rs_io_sink {
    int fd;
    int errnum; // the first write or close error; 0: none
};

static ssize_t sink_write(void *cookie, const char *buf, size_t n)
{
    struct rs_io_sink *s = cookie;
    size_t done = 0;
    while (done < n) {
        const ssize_t w = write(s->fd, buf + done, n - done);
        if (w < 0 && errno == EINTR) continue;
        if (w <= 0) {
            if (!s->errnum) s->errnum = w < 0 ? errno : ENOSPC; // write(2) of 0 bytes: no room
            errno = s->errnum;
            return done > 0 ? (ssize_t)done : -1;
        }
        done += (size_t)w;
    }
    return (ssize_t)done;
}

static int sink_close(void *cookie)
{
    struct rs_io_sink *s = cookie;
    const int r = s->fd >= 0 ? close(s->fd) : 0;
    if (r != 0 && !s->errnum) s->errnum = errno;
    s->fd = -1;
    return r;
}

// a->f as a FILE over fd, which it owns from now on (closed here on failure).
static rs_status open_sink(rs_io_atomic *a, int fd, rs_err *err)
{
    struct rs_io_sink *s = malloc(sizeof *s);
    if (s) *s = (struct rs_io_sink){.fd = fd, .errnum = 0};
    a->sink = s;
    a->f = s ? fopencookie(s, "wb", (cookie_io_functions_t){.write = sink_write, .close = sink_close}) : NULL;
    if (a->f) return RS_OK;
    close(fd);
    if (s) s->fd = -1;
    return rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", a->path ? a->path : "output");
}

// Opens an existing device or FIFO `path` for writing straight into it (a->tmp_path NULL).
static rs_status open_special(rs_io_atomic *a, const char *path, rs_err *err)
{
    a->path = strdup(path);
    const int fd = a->path ? open(path, O_WRONLY | O_CLOEXEC | O_NONBLOCK | O_NOCTTY) : -1;
    if (fd < 0) {
        const int saved = a->path ? errno : ENOMEM;
        rs_io_atomic_abort(a);
        // a FIFO no one reads: refused at once (ENXIO), never waited on
        return rs_err_set(err, RS_ERR_IO, "%s: cannot open: %s", path,
                          saved == ENXIO ? "a FIFO with no reader" : strerror(saved));
    }
    const int flags = fcntl(fd, F_GETFL);
    if (flags >= 0) fcntl(fd, F_SETFL, flags & ~O_NONBLOCK);
    rs_status st = open_sink(a, fd, err);
    if (st) rs_io_atomic_abort(a);
    return st;
}

rs_status rs_io_atomic_open(rs_io_atomic *a, const char *path, rs_err *err)
{
    memset(a, 0, sizeof *a);
    struct stat sb;
    if (stat(path, &sb) == 0 && S_ISDIR(sb.st_mode))
        return rs_err_set(err, RS_ERR_IO, "%s: cannot write: is a folder", path);
    if (stat(path, &sb) == 0 && !S_ISREG(sb.st_mode)) return open_special(a, path, err);
    size_t n = strlen(path);
    a->path = strdup(path);
    a->tmp_path = malloc(n + sizeof ".tmp.XXXXXX");
    if (!a->path || !a->tmp_path) {
        rs_io_atomic_abort(a);
        return rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", path);
    }
    memcpy(a->tmp_path, path, n);
    memcpy(a->tmp_path + n, ".tmp.XXXXXX", sizeof ".tmp.XXXXXX");
    int fd = mkstemp(a->tmp_path);
    if (fd < 0) {
        const int saved = errno;
        free(a->tmp_path);
        a->tmp_path = NULL;
        rs_io_atomic_abort(a);
        if (saved == ENOSPC || saved == EDQUOT) return write_failed(err, path, saved);
        return rs_err_set(err, RS_ERR_IO, "%s: cannot create: %s", path, strerror(saved));
    }
    // mkstemp makes 0600; outputs are ordinary files.
    mode_t mask = umask(0);
    umask(mask);
    fchmod(fd, 0666 & ~mask);
    rs_status st = open_sink(a, fd, err);
    if (st) rs_io_atomic_abort(a);
    return st;
}

// Flushes and closes a->f (a->f becomes NULL), fsyncing first when `sync`; returns the first
// errno of any write, the fsync or the close (0: all of it reached the file).
static int finish_stream(rs_io_atomic *a, bool sync)
{
    struct rs_io_sink *s = a->sink;
    int e = 0;
    if (fflush(a->f) != 0) e = errno;
    if (!e && s && s->errnum) e = s->errnum;
    // (a device or FIFO cannot be synced: EINVAL, ESPIPE are not failures)
    if (!e && sync && s && fsync(s->fd) != 0 && !(!a->tmp_path && (errno == EINVAL || errno == ESPIPE))) e = errno;
    const bool had_error = ferror(a->f) != 0;
    if (fclose(a->f) != 0 && !e) e = s && s->errnum ? s->errnum : errno;
    a->f = NULL;
    if (!e && s && s->errnum) e = s->errnum;
    if (!e && had_error) e = EIO;
    return e;
}

// fsync of the file at path; returns 0 or the errno of the failure.
static int sync_by_name(const char *path)
{
    const int fd = open(path, O_RDONLY | O_CLOEXEC | O_NOCTTY);
    if (fd < 0) return errno;
    int e = fsync(fd) != 0 ? errno : 0;
    if (close(fd) != 0 && !e) e = errno;
    return e;
}

rs_status rs_io_atomic_release(rs_io_atomic *a, rs_err *err)
{
    if (!a->f) return RS_OK;
    const int e = finish_stream(a, false);
    if (e) return write_failed(err, a->path, e);
    return RS_OK;
}

rs_status rs_io_atomic_commit(rs_io_atomic *a, rs_err *err)
{
    rs_status st = RS_OK;
    // released (a library wrote tmp_path by name): its bytes are synced here
    const int e = a->f ? finish_stream(a, true) : a->tmp_path ? sync_by_name(a->tmp_path) : 0;
    if (e)
        st = write_failed(err, a->path, e);
    else if (a->tmp_path && rename(a->tmp_path, a->path) != 0)
        st = rs_err_set(err, RS_ERR_IO, "%s: cannot rename into place: %s", a->path, strerror(errno));
    if (st != RS_OK && a->tmp_path) remove(a->tmp_path);
    free(a->tmp_path);
    free(a->path);
    free(a->sink);
    a->tmp_path = a->path = NULL;
    a->sink = NULL;
    return st;
}

rs_status rs_io_atomic_finish(rs_io_atomic *a, rs_status st, rs_err *err)
{
    if (st == RS_OK || (a->f && ferror(a->f))) {
        const rs_status cst = rs_io_atomic_commit(a, err);
        return cst ? cst : st; // (a stream error always fails the commit)
    }
    rs_io_atomic_abort(a);
    return st;
}

void rs_io_atomic_abort(rs_io_atomic *a)
{
    if (!a) return;
    if (a->f) fclose(a->f);
    if (a->tmp_path) remove(a->tmp_path);
    free(a->tmp_path);
    free(a->path);
    free(a->sink);
    memset(a, 0, sizeof *a);
}

rs_status rs_io_write_file(const char *path, const void *data, size_t len, rs_err *err)
{
    rs_io_atomic a;
    rs_status st = rs_io_atomic_open(&a, path, err);
    if (st) return st;
    (void)fwrite(data, 1, len, a.f); // a short write is reported by the commit, with its cause
    return rs_io_atomic_commit(&a, err);
}

rs_status rs_io_link_or_copy(const char *src, const char *dst, rs_err *err)
{
    if (link(src, dst) == 0) return RS_OK;
    char *data = NULL;
    size_t len = 0;
    rs_status st = rs_io_read_file(&data, &len, src, err);
    if (!st) st = rs_io_write_file(dst, data, len, err);
    free(data);
    return st;
}

rs_status rs_io_mkdir_p(const char *path, rs_err *err)
{
    char *p = strdup(path);
    if (!p) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    for (char *s = p + 1;; s++) {
        if (*s == '/' || *s == '\0') {
            char c = *s;
            *s = '\0';
            if (mkdir(p, 0777) != 0 && errno != EEXIST) {
                rs_status st = rs_err_set(err, RS_ERR_IO, "%s: cannot create folder: %s", p, strerror(errno));
                free(p);
                return st;
            }
            *s = c;
            if (c == '\0') break;
        }
    }
    free(p);
    struct stat sb;
    if (stat(path, &sb) != 0 || !S_ISDIR(sb.st_mode))
        return rs_err_set(err, RS_ERR_IO, "%s: exists and is not a folder", path);
    return RS_OK;
}

char *rs_io_join(const char *dir, const char *rel)
{
    if (rel[0] == '/' || !dir || !dir[0]) return strdup(rel);
    size_t nd = strlen(dir), nr = strlen(rel);
    while (nd > 1 && dir[nd - 1] == '/') nd--;
    char *out = malloc(nd + 1 + nr + 1);
    if (!out) return NULL;
    memcpy(out, dir, nd);
    out[nd] = '/';
    memcpy(out + nd + 1, rel, nr + 1);
    return out;
}

static int remove_entry(const char *path, const struct stat *sb, int type, struct FTW *ftw)
{
    (void)sb;
    (void)type;
    (void)ftw;
    (void)remove(path);
    return 0; // go on with the rest
}

rs_status rs_io_remove_if_exists(const char *path, bool *removed, rs_err *err)
{
    if (removed) *removed = false;
    struct stat sb;
    if (lstat(path, &sb) == 0 && !S_ISREG(sb.st_mode) && !S_ISLNK(sb.st_mode)) // never a device or FIFO
        return rs_err_set(err, RS_ERR_IO, "%s: not removed: not a regular file", path);
    if (unlink(path) == 0) {
        if (removed) *removed = true;
        return RS_OK;
    }
    if (errno == ENOENT || errno == ENOTDIR) return RS_OK; // nothing there
    return rs_err_set(err, RS_ERR_IO, "%s: cannot remove: %s", path, strerror(errno));
}

void rs_io_remove_tree(const char *path) { nftw(path, remove_entry, 16, FTW_DEPTH | FTW_PHYS); }

// "<anything>.tmp.XXXXXX" with six characters of mkstemp's alphabet: the temporary name of
// rs_io_atomic_open.
static bool is_atomic_temporary(const char *name)
{
    const size_t n = strlen(name), k = sizeof ".tmp.XXXXXX" - 1;
    if (n <= k || memcmp(name + n - k, ".tmp.", 5) != 0) return false;
    for (const char *p = name + n - 6; *p; p++)
        if (!isalnum((unsigned char)*p)) return false;
    return true;
}

size_t rs_io_temporary_base_len(const char *name)
{
    return name && is_atomic_temporary(name) ? strlen(name) - (sizeof ".tmp.XXXXXX" - 1) : 0;
}

static size_t stale_removed; // nftw passes no user pointer; callers hold the folder's lock

static int remove_temporary(const char *path, const struct stat *sb, int type, struct FTW *ftw)
{
    (void)sb;
    if (type == FTW_F && is_atomic_temporary(path + ftw->base) && unlink(path) == 0) stale_removed++;
    return 0; // go on with the rest
}

size_t rs_io_remove_stale_temporaries(const char *dir)
{
    stale_removed = 0;
    nftw(dir, remove_temporary, 16, FTW_PHYS);
    return stale_removed;
}

bool rs_io_has_extension(const char *path, const char *ext)
{
    const char *dot = strrchr(path, '.'), *slash = strrchr(path, '/');
    return dot && dot > path && (!slash || dot > slash + 1) && !strcasecmp(dot + 1, ext);
}

const char *rs_io_name_problem(const char *name)
{
    if (!name || !*name) return "is empty";
    const size_t n = strlen(name);
    if (n > 64) return "is longer than 64 bytes";
    for (const unsigned char *p = (const unsigned char *)name; *p; p++) {
        if (*p < 0x20 || *p == 0x7f) return "contains a control character (a newline, a tab, ...)";
        if (*p == '/' || *p == '\\') return "contains a path separator ('/' or '\\')";
        // UTF-8 of U+0080..U+009F (C1 controls) and of the invisible format characters that
        // reorder or hide text: U+061C, U+200B..U+200F, U+202A..U+202E, U+2060..U+206F, U+FEFF
        const unsigned cp = p[0] == 0xC2 && p[1] >= 0x80 && p[1] <= 0x9F   ? 0x80u + (p[1] - 0x80u)
                            : p[0] == 0xD8 && p[1] == 0x9C                 ? 0x61Cu
                            : p[0] == 0xE2 && p[1] == 0x80                 ? 0x2000u + (p[2] & 0x3Fu)
                            : p[0] == 0xE2 && p[1] == 0x81                 ? 0x2040u + (p[2] & 0x3Fu)
                            : p[0] == 0xEF && p[1] == 0xBB && p[2] == 0xBF ? 0xFEFFu
                                                                           : 0;
        if ((cp >= 0x80 && cp <= 0x9F) || cp == 0x61C || (cp >= 0x200B && cp <= 0x200F) ||
            (cp >= 0x202A && cp <= 0x202E) || (cp >= 0x2060 && cp <= 0x206F) || cp == 0xFEFF)
            return "contains an invisible control character (a bidirectional override, a zero-width space, ...)";
    }
    if (strstr(name, "..")) return "contains \"..\"";
    if (name[0] == ' ' || name[n - 1] == ' ') return "begins or ends with a blank";
    return NULL;
}

char *rs_io_child_path(const char *dir, const char *name, const char *suffix, rs_err *err)
{
    const char *why = rs_io_name_problem(name);
    if (why) {
        rs_err_set(err, RS_ERR_INVALID, "'%.80s' %s: it cannot name a file", name ? name : "", why);
        return NULL;
    }
    const size_t n = strlen(name) + (suffix ? strlen(suffix) : 0) + 1;
    char *file = malloc(n);
    char *path = NULL;
    if (file) {
        snprintf(file, n, "%s%s", name, suffix ? suffix : "");
        path = rs_io_join(dir, file);
    }
    free(file);
    if (!path) rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    return path;
}

// ---- folder locks ----

// The busy message: what the holder wrote into the lock file (fd), quoted field by field.
static rs_status lock_busy(int fd, const char *dir, const char *path, rs_err *err)
{
    char text[512], since[64], what[256];
    long pid = 0;
    const ssize_t n = pread(fd, text, sizeof(text) - 1, 0);
    text[n > 0 ? n : 0] = 0;
    if (sscanf(text, "%ld %63s %255[^\n]", &pid, since, what) == 3 && pid > 0)
        return rs_err_set(err, RS_ERR_IO, "%s is in use by %s (pid %ld) since %s (lock file %s)", dir, what, pid, since,
                          path);
    return rs_err_set(err, RS_ERR_IO, "%s is in use by another process (lock file %s, which names no holder yet)", dir,
                      path);
}

rs_status rs_io_lock_dir(rs_io_lock *lock, const char *dir, const char *what, rs_err *err)
{
    lock->fd = -1;
    lock->path = rs_io_join(dir, ".lock");
    if (!lock->path) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    rs_status st = RS_OK;
    for (int attempt = 0;; attempt++) {
        // O_NOFOLLOW: a link planted as DIR/.lock is refused, never followed
        const int fd = open(lock->path, O_RDWR | O_CREAT | O_CLOEXEC | O_NOFOLLOW | O_NOCTTY | O_NONBLOCK, 0644);
        if (fd < 0) {
            st = errno == ELOOP
                     ? rs_err_set(err, RS_ERR_IO, "%s: a link, not a lock file: refused (remove it)", lock->path)
                     : rs_err_set(err, RS_ERR_IO, "%s: cannot open the lock file: %s", lock->path, strerror(errno));
            break;
        }
        struct stat sb, now;
        if (fstat(fd, &sb) != 0 || !S_ISREG(sb.st_mode)) {
            close(fd);
            st = rs_err_set(err, RS_ERR_IO, "%s: the lock file is not a regular file: refused", lock->path);
            break;
        }
        if (flock(fd, LOCK_EX | LOCK_NB) != 0) {
            const int e = errno;
            st = e == EWOULDBLOCK ? lock_busy(fd, dir, lock->path, err)
                                  : rs_err_set(err, RS_ERR_IO, "%s: cannot lock: %s", lock->path, strerror(e));
            close(fd);
            break;
        }
        // The holder before us removes the file as it ends: if we locked a file no longer at
        // `path`, start again with the one there now.
        if (stat(lock->path, &now) != 0 || now.st_ino != sb.st_ino || now.st_dev != sb.st_dev) {
            close(fd);
            if (attempt < 100) continue;
            st = rs_err_set(err, RS_ERR_IO, "%s: the lock file keeps being replaced", lock->path);
            break;
        }
        char since[64] = "?", line[400];
        const time_t t = time(NULL);
        struct tm tm;
        if (localtime_r(&t, &tm)) strftime(since, sizeof(since), "%Y-%m-%dT%H:%M:%S%z", &tm);
        const int n = snprintf(line, sizeof(line), "%ld %s %s\n", (long)getpid(), since, what && *what ? what : "?");
        if (n < 0 || ftruncate(fd, 0) != 0 || pwrite(fd, line, (size_t)n, 0) != n) {
            st = rs_err_set(err, RS_ERR_IO, "%s: cannot write the lock file: %s", lock->path, strerror(errno));
            unlink(lock->path);
            close(fd);
            break;
        }
        lock->fd = fd;
        return RS_OK;
    }
    free(lock->path);
    lock->path = NULL;
    return st;
}

void rs_io_unlock(rs_io_lock *lock)
{
    if (!lock || !lock->path) return;
    unlink(lock->path); // while still held: no other process can be holding this file
    close(lock->fd);
    free(lock->path);
    lock->path = NULL;
    lock->fd = -1;
}
