// fuzz_camera_opencv.c -- libFuzzer harness of the OpenCV-style camera reader of core
// (rs_camera_read, core/rs_camera.h, with cv::FileStorage underneath): the input is written to a
// per-process temporary file (tests/fuzz/fuzz_scratch.h) and read back, as cam.json when its
// first non-blank byte is '{' and as cam.yaml otherwise (the name picks the reader). Corpus:
// tests/fuzz/corpus/camera_opencv/.
//
// Held to the header's contract, a breach aborting: a camera that reads passes rs_camera_check;
// each side of the image, when given, is 1..10^6 pixels; a rotation matrix R is part of a pose
// only with a translation (extra.has_R implies extra.has_pose); a failed read leaves the camera
// zeroed and says why.
#include <stdint.h>

#include "core/rs_camera.h"
#include "fuzz_scratch.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static void breach(const char *what, const char *detail) { fuzz_breach("fuzz_camera_opencv", what, detail); }

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *path = fuzz_scratch_write("fuzz_camera_opencv", data, size, "cam.json", "cam.yaml");
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
