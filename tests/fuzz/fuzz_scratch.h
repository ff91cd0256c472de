// fuzz_scratch.h -- what the harnesses of single camera and point files share
// (tests/fuzz/fuzz_camera_opencv.c, tests/fuzz/fuzz_import_points.c): a per-process scratch folder
// in which each input is written to a file whose name picks the reader, and the breach of a
// contract.
#pragma once
#include <stddef.h>
#include <stdint.h>

// Prints "HARNESS: contract broken: WHAT[: DETAIL]" on stderr and aborts (libFuzzer reports it as
// a crash).
void fuzz_breach(const char *harness, const char *what, const char *detail);

// Writes data (size bytes) to json_name in the per-process scratch folder (made on the first call,
// removed at exit) when its first non-blank byte is '{', else to other_name, and returns that path
// (owned by the scratch folder; the names must be the same on every call). Plain stdio: the input
// is rewritten for every run, an atomic write would fsync each time. Breaches on failure.
const char *fuzz_scratch_write(const char *harness, const uint8_t *data, size_t size, const char *json_name,
                               const char *other_name);
