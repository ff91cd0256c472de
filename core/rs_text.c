// rs_text.c -- the strict line reader and decimal numbers of core/rs_text.h.
#include "core/rs_text.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

void rs_text_lines_init(rs_text_lines *t, char *text, size_t len, size_t max_line_bytes)
{
    t->p = text, t->end = text + len, t->line = 0, t->max_line_bytes = max_line_bytes;
    if (len >= 3 && !memcmp(text, "\xEF\xBB\xBF", 3)) t->p += 3; // UTF-8 byte order mark
}

// The message of a line that is not text: a NUL at byte `nul` (0-based), or too long.
static rs_status line_error(const char *name, int line, long long nul, size_t n, size_t max, rs_err *err)
{
    char where[300] = "";
    if (name) snprintf(where, sizeof where, "%.250s:%d: ", name, line);
    if (nul >= 0)
        return rs_err_set(err, RS_ERR_PARSE, "%sa NUL byte at byte %lld of the line: not a text file", where, nul + 1);
    return rs_err_set(err, RS_ERR_PARSE, "%sthe line is longer than %zu bytes (%zu%s): not a row of this file", where,
                      max, n, n > max ? "" : " or more");
}

rs_status rs_text_next_line(char **line, rs_text_lines *t, const char *name, rs_err *err)
{
    *line = NULL;
    if (t->p >= t->end) return RS_OK;
    t->line++;
    char *s = t->p, *eol = s;
    while (eol < t->end && *eol != '\n' && *eol != '\r') eol++;
    char *next = eol;
    if (next < t->end && *next == '\r') next++;
    if (next < t->end && *next == '\n') next++;
    t->p = next;
    const size_t n = (size_t)(eol - s);
    const char *nul = memchr(s, '\0', n);
    if (nul) return line_error(name, t->line, nul - s, n, t->max_line_bytes, err);
    if (n > t->max_line_bytes) return line_error(name, t->line, -1, n, t->max_line_bytes, err);
    if (eol < t->end) *eol = '\0'; // the last line without an end is ended by the text's NUL
    *line = s;
    return RS_OK;
}

rs_status rs_text_read_line(char **buf, size_t *cap, bool *more, int *lineno, FILE *f, size_t max_line_bytes,
                            const char *name, rs_err *err)
{
    *more = false;
    if (*cap < 2) {
        char *b = realloc(*buf, 256);
        if (!b) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        *buf = b, *cap = 256;
    }
    size_t n = 0;
    long long nul = -1;
    int ch;
    bool any = false;
    while ((ch = getc(f)) != EOF) {
        any = true;
        if (ch == '\n') break;
        if (ch == '\r') { // CRLF or a lone CR
            const int c2 = getc(f);
            if (c2 != '\n' && c2 != EOF) ungetc(c2, f);
            break;
        }
        if (ch == '\0' && nul < 0) nul = (long long)n;
        if (n < max_line_bytes) {
            if (n + 2 > *cap) {
                size_t c = *cap * 2 < max_line_bytes + 2 ? *cap * 2 : max_line_bytes + 2;
                char *b = realloc(*buf, c);
                if (!b) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
                *buf = b, *cap = c;
            }
            (*buf)[n] = (char)ch;
        }
        n++;
    }
    if (ferror(f)) return rs_err_set(err, RS_ERR_IO, "%s: read error", name ? name : "input");
    if (!any) return RS_OK;
    *more = true;
    ++*lineno;
    (*buf)[n < max_line_bytes ? n : max_line_bytes] = '\0';
    if (nul >= 0) return line_error(name, *lineno, nul, n, max_line_bytes, err);
    if (n > max_line_bytes) return line_error(name, *lineno, -1, n, max_line_bytes, err);
    return RS_OK;
}

bool rs_text_is_decimal(const char *t)
{
    if (*t == '+' || *t == '-') t++;
    int digits = 0;
    while (isdigit((unsigned char)*t)) t++, digits++;
    if (*t == '.')
        for (t++; isdigit((unsigned char)*t); t++) digits++;
    if (!digits) return false;
    if (*t == 'e' || *t == 'E') {
        t++;
        if (*t == '+' || *t == '-') t++;
        if (!isdigit((unsigned char)*t)) return false;
        while (isdigit((unsigned char)*t)) t++;
    }
    return !*t;
}

// What a text that is not a decimal number looks like, for the message.
static const char *not_decimal_hint(const char *s)
{
    if (strpbrk(s, "xX")) return ": only decimal numbers are read (write 16, not 0x10)";
    if (strchr(s, ',')) return ": a decimal comma? write 12.5, not 12,5";
    return "";
}

bool rs_text_parse_double(double *out, char *why, const char *s)
{
    if (!*s) {
        snprintf(why, RS_TEXT_WHY_BYTES, "empty");
        return false;
    }
    char *end;
    const double v = strtod(s, &end);
    if (!rs_text_is_decimal(s) && (*end || isfinite(v))) {
        snprintf(why, RS_TEXT_WHY_BYTES, "not a number ('%.40s')%s", s, not_decimal_hint(s));
        return false;
    }
    if (!isfinite(v)) {
        snprintf(why, RS_TEXT_WHY_BYTES, "not finite ('%.40s')", s);
        return false;
    }
    *out = v;
    return true;
}

bool rs_text_parse_integer(long long *out, char *why, const char *s, long long lo, long long hi)
{
    const char *t = s + (*s == '+' || *s == '-');
    if (!*s) {
        snprintf(why, RS_TEXT_WHY_BYTES, "empty");
        return false;
    }
    if (!*t || t[strspn(t, "0123456789")]) {
        snprintf(why, RS_TEXT_WHY_BYTES, "not an integer ('%.40s')%s", s,
                 rs_text_is_decimal(s) ? ": write the digits, without a point or an exponent" : not_decimal_hint(s));
        return false;
    }
    errno = 0;
    const long long v = strtoll(s, NULL, 10);
    if (errno == ERANGE || v < lo || v > hi) {
        snprintf(why, RS_TEXT_WHY_BYTES, "%.40s is outside [%lld, %lld]", s, lo, hi);
        return false;
    }
    *out = v;
    return true;
}

rs_status rs_text_check_no_nul(const char *text, size_t len, const char *name, rs_err *err)
{
    const char *z = memchr(text, 0, len);
    if (!z) return RS_OK;
    int line = 1;
    for (const char *p = text; p < z; p++) line += *p == '\n';
    return rs_err_set(err, RS_ERR_PARSE, "%s:%d: a NUL byte: not a text file (every later line would be lost)",
                      name ? name : "text", line);
}
