// rs_site_report.c -- the report a site read builds: diagnostics (rs_site__diag, the public
// rs_site_report_free and rs_site_diag_format), and the reader's context that files them at the
// file, feature and line being read, including reading a site file with its problems reported.
// The bottom of the reader's layers (geo/internal/rs_site_internal.h): calls only core/.
#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "core/rs_io.h"
#include "geo/internal/rs_site_internal.h"

// A copy safe to print on one line: control characters (from damaged or binary input quoted
// in a message) become '?'.
static char *dup_printable(const char *s)
{
    char *d = s ? strdup(s) : NULL;
    for (char *p = d; p && *p; p++)
        if ((unsigned char)*p < 0x20 || *p == 0x7f) *p = '?';
    return d;
}

void rs_site__diag(rs_site__report *r, rs_site_severity severity, rs_status status, const char *file, int line,
                   int feature, const char *feature_id, const char *field, const char *fmt, ...)
{
    rs_site_report *p = &r->pub;
    if (p->N == r->cap) {
        int cap = r->cap ? 2 * r->cap : 16;
        rs_site_diag *grown = realloc(p->diags, (size_t)cap * sizeof *grown);
        if (!grown) {
            r->nomem = true;
            return;
        }
        p->diags = grown;
        r->cap = cap;
    }
    char msg[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);

    rs_site_diag d = {
        .severity = severity,
        .status = severity == RS_SITE_ERROR ? status : RS_OK,
        .file = dup_printable(file ? file : "?"),
        .line = line,
        .feature = feature,
        .feature_id = dup_printable(feature_id),
        .field = dup_printable(field),
        .message = dup_printable(msg),
    };
    if (!d.file || !d.message || (feature_id && !d.feature_id) || (field && !d.field)) {
        free(d.file);
        free(d.feature_id);
        free(d.field);
        free(d.message);
        r->nomem = true;
        return;
    }
    p->diags[p->N++] = d;
    if (severity == RS_SITE_ERROR)
        p->Nerrors++;
    else
        p->Nwarnings++;
}

void rs_site_report_free(rs_site_report *report)
{
    if (!report) return;
    for (int i = 0; i < report->N; i++) {
        free(report->diags[i].file);
        free(report->diags[i].feature_id);
        free(report->diags[i].field);
        free(report->diags[i].message);
    }
    free(report->diags);
    free((rs_site__report *)report); // pub is the first member
}

int rs_site_diag_format(char *buf, size_t size, const rs_site_diag *d)
{
    char line[32] = "", feature[300] = "", field[300] = "";
    if (d->line > 0) snprintf(line, sizeof line, ":%d", d->line);
    if (d->feature >= 0) {
        if (d->feature_id)
            snprintf(feature, sizeof feature, " feature %d (id '%s'):", d->feature, d->feature_id);
        else
            snprintf(feature, sizeof feature, " feature %d:", d->feature);
    }
    if (d->field) snprintf(field, sizeof field, " %s:", d->field);
    return snprintf(buf, size, "%s%s:%s%s %s%s", d->file, line, feature, field,
                    d->severity == RS_SITE_WARNING ? "warning: " : "", d->message);
}

// ---- the reader's context ----

void rs_site__say(rs_site__reader *c, rs_site_severity severity, rs_status status, int line, const char *field,
                  const char *fmt, ...)
{
    char msg[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    rs_site__diag(c->r, severity, status, c->file, line, c->feature, c->fid, field, "%s", msg);
}

char *rs_site__dup(rs_site__reader *c, const char *s)
{
    if (!s) return NULL;
    char *d = strdup(s);
    if (!d) c->r->nomem = true;
    return d;
}

char *rs_site__join(rs_site__reader *c, const char *dir, const char *rel)
{
    char *p = rs_io_join(dir, rel);
    if (!p) c->r->nomem = true;
    return p;
}

bool rs_site__inside(const rs_site__reader *c, const char *path)
{
    char *dir = realpath(c->site->dir, NULL), *p = realpath(path, NULL);
    // a path that does not resolve is judged by the nearest folder above it that does: a missing
    // "/nonexistent/x" is outside, and saying "missing" would tell whether an outside path exists
    char *up = p || !dir ? NULL : strdup(path);
    while (up && !p) {
        char *slash = strrchr(up, '/');
        if (!slash) {
            p = realpath(".", NULL);
            break;
        }
        *(slash == up ? slash + 1 : slash) = '\0';
        p = realpath(up, NULL);
        if (slash == up) break;
    }
    free(up);
    bool inside = !dir || !p;
    if (dir && p) {
        const size_t n = strlen(dir);
        inside = !strncmp(p, dir, n) && (p[n] == '/' || p[n] == '\0' || (n == 1 && dir[0] == '/'));
    }
    free(dir);
    free(p);
    return inside;
}

bool rs_site__file_exists(rs_site__reader *c, const char *why)
{
    struct stat sb;
    if (!rs_site__inside(c, c->file)) { // said of site.json, which names it: nothing outside is a diagnostic's file
        char *site_json = rs_io_join(c->site->dir, RS_SITE_JSON);
        if (!site_json) c->r->nomem = true;
        if (site_json)
            rs_site__diag(c->r, RS_SITE_ERROR, RS_ERR_INVALID, site_json, 0, -1, NULL, NULL,
                          "'%.200s' is outside the site folder (%s): a site's files live inside it (links are "
                          "followed); refused unread",
                          c->file, why);
        free(site_json);
    } else if (stat(c->file, &sb) != 0) {
        const int e = errno;
        if (e == ENOENT || e == ENOTDIR)
            ERR(c, RS_ERR_IO, NULL, "missing file (%s)", why);
        else if (e == ELOOP)
            ERR(c, RS_ERR_IO, NULL, "a loop of symbolic links (one leads back to another): no file at its end (%s)",
                why);
        else
            ERR(c, RS_ERR_IO, NULL, "cannot be read: %s (%s)", strerror(e), why);
    } else if (S_ISDIR(sb.st_mode))
        ERR(c, RS_ERR_IO, NULL, "is a folder, expected a file (%s)", why);
    else if (!S_ISREG(sb.st_mode)) // a library reading it by name would wait on a FIFO forever
        ERR(c, RS_ERR_IO, NULL, "not a regular file (%s): refused (%s)",
            S_ISFIFO(sb.st_mode)   ? "a FIFO"
            : S_ISSOCK(sb.st_mode) ? "a socket"
                                   : "a device",
            why);
    else
        return true;
    return false;
}

char *rs_site__read_file(rs_site__reader *c, const char *why, size_t max_bytes, size_t *len)
{
    if (!rs_site__file_exists(c, why)) return NULL;
    char *text = NULL;
    rs_err e = {0};
    if (rs_io_read_file_max(&text, len, c->file, max_bytes, &e) != RS_OK) {
        // e.msg starts with the path, which the diagnostic names already
        const size_t n = strlen(c->file);
        const char *what = strncmp(e.msg, c->file, n) || strncmp(e.msg + n, ": ", 2) ? e.msg : e.msg + n + 2;
        ERR(c, e.status, NULL, "cannot read (%s): %s", why, what);
        return NULL;
    }
    return text;
}
