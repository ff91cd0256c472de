// fuzz_text_lines.c -- libFuzzer harness of the strict line reader and decimal numbers of core
// (core/rs_text.h) as `roadside locate` reads its standard input: the input is a stream
// (fmemopen) read with rs_text_read_line, each line split at blanks and its fields parsed with
// rs_text_parse_double, and the same bytes read from memory with rs_text_next_line. Corpus:
// tests/fuzz/corpus/text_lines/.
//
// Held to the header's contract, a breach aborting: a line returned has no NUL before its end and
// at most the bound's bytes; a number parsed is finite and its text decimal; both readers count
// the same lines and stop at the same error.
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/rs_text.h"
#include "fuzz_scratch.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

enum { MAX_LINE = 64 };

static void breach(const char *what, const char *detail) { fuzz_breach("fuzz_text_lines", what, detail); }

static void numbers_of(char *line)
{
    char *save = NULL, why[RS_TEXT_WHY_BYTES];
    for (char *tok = strtok_r(line, " \t", &save); tok; tok = strtok_r(NULL, " \t", &save)) {
        double x;
        long long i;
        if (rs_text_parse_double(&x, why, tok) && (!isfinite(x) || !rs_text_is_decimal(tok)))
            breach("a number read that is not finite or not decimal", tok);
        if (rs_text_parse_integer(&i, why, tok, -1000, 1000) && (i < -1000 || i > 1000))
            breach("an integer read outside its range", tok);
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    // the stream: every line or an error, the error at the line where the memory reader stops
    FILE *f = size ? fmemopen((void *)data, size, "rb") : NULL;
    if (!f) return 0;
    char *buf = NULL, *copy = malloc(size + 1);
    size_t cap = 0;
    int lineno = 0, first_error = 0;
    bool more = true;
    if (!copy) breach("out of memory", NULL);
    while (more) {
        rs_err e = {0};
        const rs_status st = rs_text_read_line(&buf, &cap, &more, &lineno, f, MAX_LINE, "<stdin>", &e);
        if (st == RS_ERR_NOMEM || st == RS_ERR_IO) breach("the stream reader failed", e.msg);
        if (!more) break;
        if (st != RS_OK) {
            if (!first_error) first_error = lineno;
            if (!e.msg[0]) breach("an error without a message", NULL);
            continue;
        }
        if (strlen(buf) > MAX_LINE) breach("a line longer than the bound", NULL);
        if (!first_error) numbers_of(buf);
    }
    fclose(f);
    free(buf);
    // the same bytes in memory
    memcpy(copy, data, size);
    copy[size] = '\0';
    rs_text_lines t;
    rs_text_lines_init(&t, copy, size, MAX_LINE);
    char *line;
    rs_err e = {0};
    rs_status st;
    while ((st = rs_text_next_line(&line, &t, NULL, &e)) == RS_OK && line)
        if (strlen(line) > MAX_LINE || memchr(line, '\0', strlen(line))) breach("a memory line over the bound", NULL);
    // a byte order mark is skipped in memory only; past it the two agree on the first bad line
    if (size < 3 || memcmp(data, "\xEF\xBB\xBF", 3)) {
        if ((st != RS_OK) != (first_error != 0)) breach("the two readers disagree on whether the text is bad", NULL);
        if (st != RS_OK && t.line != first_error) breach("the two readers stop at different lines", NULL);
    }
    free(copy);
    return 0;
}
