// rs_text.h -- reading a user's text (CSV files, standard input) line by line, strictly, and
// its decimal numbers: the one line reader and number parser every text reader shares.
//
// A reader reads all of its text or refuses it: a NUL byte (a binary or corrupt file; C string
// functions would silently stop there and drop every later line) and a line longer than the
// reader's bound (a line cut in two would read as two rows) are errors naming the line, never
// skipped. Numbers are decimal only: "0x10", "1e5" where an integer is wanted, "nan", "inf" and
// trailing text are refused, where strtod/strtol would accept or half-read them.
#pragma once
#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>

#include "core/rs_status.h"

#ifdef __cplusplus
extern "C" {
#endif

// The longest line a reader of user text takes by default, bytes without its end: a CSV row of
// observations or a locate query is well under a hundred.
#define RS_TEXT_MAX_LINE_BYTES 4096

// Lines of a text held in memory, each ended by LF, CRLF or a lone CR (spreadsheets on old Macs
// write CR only); a UTF-8 byte order mark at the start is skipped.
typedef struct {
    char *p, *end;         // the text not read yet
    int line;              // the line last returned, from 1 (0 before the first)
    size_t max_line_bytes; // longer lines are an error
} rs_text_lines;

// Starts reading text[0, len) (modified in place: each line's end becomes a NUL).
void rs_text_lines_init( // out
    rs_text_lines *t,
    // in
    char *text, size_t len, size_t max_line_bytes);

// The next line into *line (NUL-terminated, inside the text, without its end; NULL at the end of
// the text). Errors (RS_ERR_PARSE, t->line is the line at fault): a NUL byte ("NAME:LINE: a NUL
// byte at byte K of the line: not a text file"), a line longer than t->max_line_bytes. `name`
// (may be NULL: the message then starts at what is wrong) names the text in messages.
rs_status rs_text_next_line( // out
    char **line,
    // in,out
    rs_text_lines *t,
    // in
    const char *name, rs_err *err);

// The next line of a stream (standard input), with the rules of rs_text_next_line: into *buf
// (malloc'ed and grown as needed, at most max_line_bytes + 1 bytes; the caller frees it, and
// passes NULL and 0 the first time), NUL-terminated, without its end; *more is false at the end
// of the stream. *lineno counts lines from 1. An overlong line is consumed to its end before the
// error is returned, so that the caller may go on with the next line. Errors: those of
// rs_text_next_line, RS_ERR_IO (the stream), RS_ERR_NOMEM.
rs_status rs_text_read_line( // out
    char **buf, size_t *cap, bool *more,
    // in,out
    int *lineno,
    // in
    FILE *f, size_t max_line_bytes, const char *name, rs_err *err);

// Refuses a text read whole that holds a NUL byte (C string functions would stop there and drop
// every later line): "NAME:LINE: a NUL byte: not a text file". For readers that split a text
// they hold in memory themselves.
rs_status rs_text_check_no_nul(const char *text, size_t len, const char *name, rs_err *err);

// True when t is a decimal number: [+-]digits[.digits][(e|E)[+-]digits], with digits on at
// least one side of the point, and nothing else (no blanks, no hexadecimal, no nan or inf).
bool rs_text_is_decimal(const char *t);

// Parses a decimal number (rs_text_is_decimal) that is finite as a double. Returns true on
// success; else false with what is wrong in why, ready to follow "FIELD: " ("empty", "not a
// number ('0x10'): only decimal numbers are read (write 16, not 0x10)", "not finite ('1e999')").
// out: *out, untouched on failure; why[RS_TEXT_WHY_BYTES]
bool rs_text_parse_double(double *out, char *why,
                          // in
                          const char *s);

// Parses a decimal integer ([+-]digits, nothing else) in [lo, hi]; "1e5", "12.0" and "0x10" are
// refused ("not an integer"), as is a value outside [lo, hi] (the message gives the range).
// out: *out, untouched on failure; why[RS_TEXT_WHY_BYTES] as rs_text_parse_double
bool rs_text_parse_integer(long long *out, char *why,
                           // in
                           const char *s, long long lo, long long hi);

// The size of the `why` buffers above.
#define RS_TEXT_WHY_BYTES 160

#ifdef __cplusplus
}
#endif
