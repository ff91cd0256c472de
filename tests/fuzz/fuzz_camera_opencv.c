// fuzz_camera_opencv.c -- libFuzzer harness of the OpenCV-style camera reader of core
// (rs_camera_read, core/rs_camera.h, with cv::FileStorage underneath): the input is written to a
// per-process temporary file and read back, as cam.json when its first non-blank byte is '{'
// and as cam.yaml otherwise (the name picks the reader). Corpus: tests/fuzz/corpus/camera_opencv/.
//
// Held to the header's contract, a breach aborting: a camera that reads passes rs_camera_check;
// each side of the image, when given, is 1..10^6 pixels; a rotation matrix R is part of a pose
// only with a translation (extra.has_R implies extra.has_pose); a failed read leaves the camera
// zeroed and says why.
#include <ctype.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/rs_camera.h"
#include "core/rs_io.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static char *dir, *yaml_path, *json_path; // the per-process folder and its two file names

static void breach(const char *what, const char *detail)
{
    fprintf(stderr, "fuzz_camera_opencv: contract broken: %s%s%s\n", what, detail ? ": " : "", detail ? detail : "");
    abort();
}

static void remove_dir(void)
{
    if (dir) rs_io_remove_tree(dir);
    free(dir);
    free(yaml_path);
    free(json_path);
    dir = yaml_path = json_path = NULL;
}

static void make_dir(void)
{
    const char *tmp = getenv("TMPDIR");
    dir = rs_io_join(tmp && *tmp ? tmp : "/tmp", "roadside-fuzz-XXXXXX");
    if (!dir || !mkdtemp(dir)) breach("cannot make a temporary folder", dir);
    atexit(remove_dir);
    yaml_path = rs_io_join(dir, "cam.yaml");
    json_path = rs_io_join(dir, "cam.json");
    if (!yaml_path || !json_path) breach("out of memory", NULL);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (!dir) make_dir();
    size_t i = 0;
    while (i < size && isspace(data[i])) i++;
    const char *path = i < size && data[i] == '{' ? json_path : yaml_path;
    // A scratch input rewritten for every run: plain stdio (an atomic write would fsync each time).
    FILE *f = fopen(path, "wb");
    if (!f || (size && fwrite(data, 1, size, f) != size) || fclose(f) != 0) breach("cannot write", path);

    rs_camera cam;
    rs_camera_extra extra;
    rs_err err = {0};
    rs_status st = rs_camera_read(&cam, &extra, path, &err);
    if (st == RS_OK) {
        if (rs_camera_check(&cam, path, &err) != RS_OK) breach("a camera that reads fails rs_camera_check", err.msg);
        if (!(cam.width >= 0 && cam.width <= 1000000 && cam.height >= 0 && cam.height <= 1000000))
            breach("a camera that reads has an image side outside 0..10^6", NULL);
        if (extra.has_R && !extra.has_pose) breach("R given without the pose it belongs to", NULL);
    } else {
        if (cam.intrinsics || cam.Nintrinsics || cam.width || cam.height) breach("a failed read left a camera", NULL);
        if (!err.msg[0]) breach("a failed read without a message", NULL);
    }
    rs_camera_free(&cam);
    return 0;
}
