// rs_test.h -- the check macro and verdict of roadside's C tests (one copy for every test).
//
//   CHECK(cond, fmt, ...)  counts a failure and prints "FAIL file:line (seed S): cond: message"
//                          when cond is false; the seed is rs_test_seed, which a test sets
//                          before drawing its random data (0 when it draws none)
//   rs_test_end("name")    prints the verdict and returns the exit code (0 pass, 1 fail)
// Failures past the first 60 are counted but not printed. Header-only: one test, one program.
#pragma once
#include <stdio.h>

static int rs_test_failures;
static unsigned long long rs_test_seed;

#define CHECK(cond, ...)                                                                     \
    do {                                                                                     \
        if (!(cond) && rs_test_failures++ < 60) {                                            \
            printf("FAIL %s:%d (seed %llu): %s: ", __FILE__, __LINE__, rs_test_seed, #cond); \
            printf(__VA_ARGS__);                                                             \
            printf("\n");                                                                    \
        }                                                                                    \
    } while (0)

static inline int rs_test_end(const char *name)
{
    if (rs_test_failures)
        printf("%s: %d check(s) FAILED\n", name, rs_test_failures);
    else
        printf("%s: all checks passed\n", name);
    fflush(stdout);
    return rs_test_failures ? 1 : 0;
}
