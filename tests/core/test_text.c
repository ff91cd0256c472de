// test_text.c -- core/rs_text.h (the strict line reader and decimal numbers) and core/rs_index.h
// (the sorted id index). Oracles: hand-written expectations for the line reader and numbers (issue
// 42: a NUL byte, an overlong line, "0x10", "1e5" as an integer, "nan"), and a loop over every row
// for the index (random ids with repeats and case variants, fixed seed).
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "core/rs_index.h"
#include "core/rs_rng.h"
#include "core/rs_text.h"
#include "tests/common/rs_test.h"

// Reads every line of text[0, len) with rs_text_next_line; returns how many came back before the
// end or an error (*st: the last status, *line_at: the reader's line).
static int count_lines(const char *text, size_t len, size_t max, rs_status *st, int *line_at, char *msg, size_t n)
{
    char *copy = malloc(len + 1);
    memcpy(copy, text, len);
    copy[len] = '\0';
    rs_text_lines t;
    rs_text_lines_init(&t, copy, len, max);
    int count = 0;
    char *s;
    rs_err e = {0};
    while ((*st = rs_text_next_line(&s, &t, "f.csv", &e)) == RS_OK && s) count++;
    *line_at = t.line;
    snprintf(msg, n, "%s", e.msg);
    free(copy);
    return count;
}

static void lines(void)
{
    rs_status st;
    int at;
    char msg[1024];
    // LF, CRLF and a lone CR each end a line; a BOM is skipped; the last line may lack its end
    static const char ends[] = "\xEF\xBB\xBF"
                               "a\nb\r\nc\rd";
    CHECK(count_lines(ends, sizeof ends - 1, 100, &st, &at, msg, sizeof msg) == 4 && st == RS_OK, "%d", at);
    // a NUL on line 3 of 5: an error at line 3, naming the file and the byte
    static const char nul[] = "h\n1\n2\0junk\n3\n4\n";
    CHECK(count_lines(nul, sizeof nul - 1, 100, &st, &at, msg, sizeof msg) == 2 && st == RS_ERR_PARSE && at == 3,
          "st %d at %d", st, at);
    CHECK(strstr(msg, "f.csv:3: a NUL byte at byte 2") != NULL, "%s", msg);
    // a line of 11 bytes where 10 are allowed, 10 bytes pass
    static const char longl[] = "0123456789\n0123456789A\n";
    CHECK(count_lines(longl, sizeof longl - 1, 10, &st, &at, msg, sizeof msg) == 1 && st == RS_ERR_PARSE && at == 2,
          "st %d at %d", st, at);
    CHECK(strstr(msg, "f.csv:2: the line is longer than 10 bytes (11)") != NULL, "%s", msg);

    // the stream reader: the same rules, and it goes on after an overlong line
    FILE *f = tmpfile();
    fputs("1 2\r\n", f);
    for (int k = 0; k < 3000; k++) fputc('7', f);
    fputs("\n3 4\n5\n", f);
    fwrite("5\0006\n", 1, 4, f);
    fputs("last", f);
    rewind(f);
    char *buf = NULL;
    size_t cap = 0;
    int lineno = 0;
    bool more = true;
    const char *want[] = {"1 2", NULL, "3 4", "5", NULL, "last"};
    const rs_status want_st[] = {RS_OK, RS_ERR_PARSE, RS_OK, RS_OK, RS_ERR_PARSE, RS_OK};
    for (int k = 0; k < 6; k++) {
        rs_err e = {0};
        st = rs_text_read_line(&buf, &cap, &more, &lineno, f, 1000, "<stdin>", &e);
        CHECK(more && lineno == k + 1 && st == want_st[k], "line %d: more %d lineno %d st %d", k + 1, more, lineno, st);
        if (want[k]) CHECK(st == RS_OK && !strcmp(buf, want[k]), "line %d: '%s'", k + 1, buf);
        if (k == 1) CHECK(strstr(e.msg, "<stdin>:2: the line is longer than 1000 bytes (3000)") != NULL, "%s", e.msg);
        if (k == 4) CHECK(strstr(e.msg, "<stdin>:5: a NUL byte at byte 2") != NULL, "%s", e.msg);
    }
    rs_err e = {0};
    st = rs_text_read_line(&buf, &cap, &more, &lineno, f, 1000, "<stdin>", &e);
    CHECK(st == RS_OK && !more, "end: st %d more %d", st, more);
    CHECK(cap <= 1002, "the buffer grew to %zu bytes for a bound of 1000", cap);
    free(buf);
    fclose(f);
}

static void numbers(void)
{
    static const struct {
        const char *s;
        bool ok;
        double v;
        const char *why; // part of the message
    } d[] = {
        {"12.5", true, 12.5, NULL},
        {"-0.5e2", true, -50, NULL},
        {".5", true, 0.5, NULL},
        {"7.", true, 7, NULL},
        {"+3", true, 3, NULL},
        {"0x10", false, 0, "only decimal"},
        {"nan", false, 0, "not finite"},
        {"inf", false, 0, "not finite"},
        {"1e999", false, 0, "not finite"},
        {"12,5", false, 0, "decimal comma"},
        {"1 2", false, 0, "not a number"},
        {"12abc", false, 0, "not a number"},
        {"", false, 0, "empty"},
        {"1e", false, 0, "not a number"},
        {".", false, 0, "not a number"},
        {" 1", false, 0, "not a number"},
    };
    for (size_t k = 0; k < sizeof d / sizeof *d; k++) {
        double v = -1;
        char why[RS_TEXT_WHY_BYTES] = "";
        const bool ok = rs_text_parse_double(&v, why, d[k].s);
        CHECK(ok == d[k].ok && (!ok || v == d[k].v), "'%s': ok %d v %g", d[k].s, ok, v);
        if (!ok) CHECK(strstr(why, d[k].why) != NULL, "'%s': '%s'", d[k].s, why);
        if (!ok) CHECK(v == -1, "'%s': out written on failure", d[k].s);
    }
    static const struct {
        const char *s;
        bool ok;
        long long v;
        const char *why;
    } i[] = {
        {"42", true, 42, NULL},
        {"-7", true, -7, NULL},
        {"1e5", false, 0, "not an integer"},
        {"12.0", false, 0, "not an integer"},
        {"0x10", false, 0, "only decimal"},
        {"101", false, 0, "outside [-100, 100]"},
        {"99999999999999999999", false, 0, "outside"},
        {"", false, 0, "empty"},
        {"-", false, 0, "not an integer"},
        {"4 ", false, 0, "not an integer"},
    };
    for (size_t k = 0; k < sizeof i / sizeof *i; k++) {
        long long v = -1;
        char why[RS_TEXT_WHY_BYTES] = "";
        const bool ok = rs_text_parse_integer(&v, why, i[k].s, -100, 100);
        CHECK(ok == i[k].ok && (!ok || v == i[k].v), "'%s': ok %d v %lld", i[k].s, ok, v);
        if (!ok) CHECK(strstr(why, i[k].why) != NULL, "'%s': '%s'", i[k].s, why);
    }
}

// The index against a loop over every row.
static void index_vs_loop(void)
{
    rs_test_seed = 42;
    rs_rng rng;
    rs_rng_seed(&rng, rs_test_seed);
    enum { N = 3000, NQ = 4000 };
    static char ids[N][16];
    const char *keys[N];
    for (int i = 0; i < N; i++) {
        // few distinct ids (repeats), random case: "aB3"
        const int r = (int)(rs_rng_uniform(&rng) * 900);
        snprintf(ids[i], sizeof ids[i], "%c%c%u", (char)('a' + r % 3), rs_rng_uniform(&rng) < 0.5 ? 'b' : 'B',
                 (unsigned)r % 1000 / 3);
        keys[i] = i % 97 == 5 ? NULL : ids[i];
    }
    for (int nocase = 0; nocase < 2; nocase++) {
        rs_index ix;
        rs_err e = {0};
        CHECK(rs_index_init(&ix, keys, N, nocase, &e) == RS_OK, "%s", e.msg);
        for (int q = 0; q < NQ; q++) {
            char query[16];
            const int r = (int)(rs_rng_uniform(&rng) * 1000);
            snprintf(query, sizeof query, "%c%c%u", (char)('a' + r % 3), rs_rng_uniform(&rng) < 0.5 ? 'b' : 'B',
                     (unsigned)r % 1000 / 3);
            int want = -1;
            for (int i = 0; i < N && want < 0; i++)
                if (keys[i] && !(nocase ? strcasecmp(keys[i], query) : strcmp(keys[i], query))) want = i;
            const int got = rs_index_find(&ix, query);
            CHECK(got == want, "nocase %d '%s': %d, the loop finds %d", nocase, query, got, want);
        }
        rs_index_free(&ix);
        rs_index_free(&ix);
    }
    rs_index_free(NULL);
    rs_index empty;
    rs_err e = {0};
    CHECK(rs_index_init(&empty, NULL, 0, false, &e) == RS_OK && rs_index_find(&empty, "x") == -1, "empty");
    rs_index_free(&empty);
}

int main(void)
{
    lines();
    numbers();
    index_vs_loop();
    return rs_test_end("test_text");
}
