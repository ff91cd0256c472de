// tests/synth/test_fleet_check.h -- the CHECK macro of the fleet and labels C tests: counts a
// failure and prints where and why, so that one run reports every broken case.
#pragma once
#include <stdio.h>

static int failures = 0;
#define CHECK(cond, ...)                                         \
    do {                                                         \
        if (!(cond)) {                                           \
            failures++;                                          \
            fprintf(stderr, "FAIL %s:%d: ", __FILE__, __LINE__); \
            fprintf(stderr, __VA_ARGS__);                        \
            fprintf(stderr, "\n");                               \
        }                                                        \
    } while (0)
