// fuzz_scratch.c -- the scratch files of the single-file harnesses (tests/fuzz/fuzz_scratch.h).
#include "fuzz_scratch.h"

#include <ctype.h>
#include <stdio.h>
#include <stdlib.h>

#include "core/rs_io.h"

static char *dir, *json_path, *other_path; // the per-process folder and its two file names

void fuzz_breach(const char *harness, const char *what, const char *detail)
{
    fprintf(stderr, "%s: contract broken: %s%s%s\n", harness, what, detail ? ": " : "", detail ? detail : "");
    abort();
}

static void remove_dir(void)
{
    if (dir) rs_io_remove_tree(dir);
    free(dir), free(json_path), free(other_path);
    dir = json_path = other_path = NULL;
}

const char *fuzz_scratch_write(const char *harness, const uint8_t *data, size_t size, const char *json_name,
                               const char *other_name)
{
    if (!dir) {
        const char *tmp = getenv("TMPDIR");
        dir = rs_io_join(tmp && *tmp ? tmp : "/tmp", "roadside-fuzz-XXXXXX");
        if (!dir || !mkdtemp(dir)) fuzz_breach(harness, "cannot make a temporary folder", dir);
        atexit(remove_dir);
        json_path = rs_io_join(dir, json_name);
        other_path = rs_io_join(dir, other_name);
        if (!json_path || !other_path) fuzz_breach(harness, "out of memory", NULL);
    }
    size_t i = 0;
    while (i < size && isspace(data[i])) i++;
    const char *path = i < size && data[i] == '{' ? json_path : other_path;
    FILE *f = fopen(path, "wb");
    if (!f || (size && fwrite(data, 1, size, f) != size) || fclose(f) != 0) fuzz_breach(harness, "cannot write", path);
    return path;
}
