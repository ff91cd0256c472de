// test_appearance_dump -- runs one appearance estimator (synth/backdrop/rs_synth_appearance.h) on an image
// file and prints the result, for tests/synth/backdrop/test_appearance.py (which makes the images with a
// known truth).
//   test_appearance_dump noise FILE | blur FILE | gain FILE [REF] | jpeg FILE
//   test_appearance_dump model FILE [JPEG_QUALITY] | blockiness FILE
//   test_appearance_dump apply IN_RGBA OUT_RGBA g0 g1 g2 noise blur layer_blur seed
//   test_appearance_dump onnx MODEL IN_RGB OUT_RGB
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "synth/backdrop/rs_synth_appearance.h"

static int fail(const rs_err *err)
{
    fprintf(stderr, "test_appearance_dump: %s\n", err->msg);
    return 1;
}

int main(int argc, char **argv)
{
    rs_err err = {0};
    rs_image img = {0}, ref = {0};
    if (argc < 3) return 2;
    const char *what = argv[1];
    if (!strcmp(what, "jpeg")) {
        int q, exact;
        if (rs_synth_estimate_jpeg_quality(&q, &exact, argv[2], &err)) return fail(&err);
        printf("%d %d\n", q, exact);
        return 0;
    }
    if (!strcmp(what, "onnx") && argc == 5) { // onnx MODEL IN OUT
        rs_image out = {0};
        int rc = rs_image_read(&img, argv[3], &err) || rs_synth_dnn_translate(&out, argv[2], &img, &err) ||
                         rs_image_write(argv[4], &out, 16, &err)
                     ? fail(&err)
                     : 0;
        rs_image_free(&img);
        rs_image_free(&out);
        return rc;
    }
    if (rs_image_read(&img, argv[2], &err)) return fail(&err);
    int rc = 0;
    if (!strcmp(what, "noise") || !strcmp(what, "blur")) {
        double s;
        if ((what[0] == 'n' ? rs_synth_estimate_noise(&s, &img, &err) : rs_synth_estimate_blur(&s, &img, &err)))
            rc = fail(&err);
        else
            printf("%.9g\n", s);
    } else if (!strcmp(what, "model")) { // model FILE [JPEG_QUALITY]
        double a, b;
        if (rs_synth_estimate_noise_model(&a, &b, &img, argc > 3 ? atoi(argv[3]) : 0, &err))
            rc = fail(&err);
        else
            printf("%.9g %.9g\n", a, b);
    } else if (!strcmp(what, "blockiness")) {
        double r;
        if (rs_synth_estimate_blockiness(&r, &img, &err))
            rc = fail(&err);
        else
            printf("%.9g\n", r);
    } else if (!strcmp(what, "gain")) {
        double g[3];
        if (argc > 3 && rs_image_read(&ref, argv[3], &err))
            rc = fail(&err);
        else if (rs_synth_estimate_gain(g, &img, argc > 3 ? &ref : NULL, NULL, &err))
            rc = fail(&err);
        else
            printf("%.9g %.9g %.9g\n", g[0], g[1], g[2]);
    } else if (!strcmp(what, "apply") && argc == 11) {
        rs_synth_appearance a = {.gain = {atof(argv[4]), atof(argv[5]), atof(argv[6])},
                                 .noise_sigma = atof(argv[7]),
                                 .blur_sigma_px = atof(argv[8])};
        if (rs_synth_appearance_apply(&img, &a, atof(argv[9]), strtoull(argv[10], NULL, 10), &err) ||
            rs_image_write(argv[3], &img, 16, &err))
            rc = fail(&err);
    } else
        rc = 2;
    rs_image_free(&img);
    rs_image_free(&ref);
    return rc;
}
