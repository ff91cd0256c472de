// fuzz_cameramodel.c -- libFuzzer harness of the mrcal .cameramodel reader of core
// (rs_camera_read_cameramodel_text, core/rs_camera.h): the input is the text of a .cameramodel,
// handed over in a buffer of exactly its length (the header promises that the text need not be
// NUL-terminated). Corpus: tests/fuzz/corpus/cameramodel/.
//
// Held to the header's contract, a breach aborting: a camera that reads passes rs_camera_check
// (the reader checks "as rs_camera_read does") and has an image size of 1..10^6 pixels a side; a
// failed read leaves the camera zeroed and says why. A camera that reads also projects a point
// (rs_camera_project): counted as projected only when the pixel is finite.
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/rs_camera.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static void breach(const char *what, const char *detail)
{
    fprintf(stderr, "fuzz_cameramodel: contract broken: %s%s%s\n", what, detail ? ": " : "", detail ? detail : "");
    abort();
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char *text = malloc(size ? size : 1); // exactly the input: a read past it is ASan's to see
    if (!text) breach("out of memory", NULL);
    if (size) memcpy(text, data, size);
    rs_camera cam;
    rs_err err = {0};
    rs_status st = rs_camera_read_cameramodel_text(&cam, text, size, "fuzz.cameramodel", &err);
    if (st == RS_OK) {
        if (rs_camera_check(&cam, "fuzz.cameramodel", &err) != RS_OK)
            breach("a camera that reads fails rs_camera_check", err.msg);
        if (!(cam.width >= 1 && cam.width <= 1000000 && cam.height >= 1 && cam.height <= 1000000))
            breach("a camera that reads has an image size outside 1..10^6", NULL);
        const double p_enu_m[3] = {0, 0, 10}; // the pose is the file's: any point will do
        double q_px[2];
        int n = rs_camera_project(q_px, &cam, p_enu_m, 1);
        if (n < 0 || n > 1) breach("rs_camera_project counted more points than it was given", NULL);
        if (n == 1 && !(isfinite(q_px[0]) && isfinite(q_px[1]))) breach("a projected point is not finite", NULL);
    } else {
        if (cam.intrinsics || cam.Nintrinsics || cam.width || cam.height) breach("a failed read left a camera", NULL);
        if (!err.msg[0]) breach("a failed read without a message", NULL);
    }
    rs_camera_free(&cam);
    free(text);
    return 0;
}
