// test_camera_dump.c -- drives core/rs_camera.h for test_camera.py, which checks it against mrcal's
// and OpenCV's Python modules.
//   test_camera_dump read PATH                      the camera as JSON (or "ERROR <status>: <msg>", exit 1)
//   test_camera_dump write IN OUT.cameramodel OUT.yaml
//   test_camera_dump project PATH < points          one "u v" line per "e n u" line (nan: not projected)
//   test_camera_dump locate PATH NE NN NU OFFSET < pixels   one "e n u" line per "u v" line
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/rs_camera.h"

static int read_or_fail(rs_camera *cam, rs_camera_extra *extra, const char *path)
{
    rs_err err = {0};
    if (rs_camera_read(cam, extra, path, &err)) {
        printf("ERROR %s: %s\n", rs_strerror(err.status), err.msg);
        return 1;
    }
    return 0;
}

static void print_array(const char *name, const double *x, int n)
{
    printf("\"%s\": [", name);
    for (int i = 0; i < n; i++) printf("%s%.17g", i ? ", " : "", x[i]);
    printf("]");
}

int main(int argc, char **argv)
{
    rs_camera cam;
    rs_camera_extra extra;
    if (argc == 3 && !strcmp(argv[1], "read")) {
        if (read_or_fail(&cam, &extra, argv[2])) return 1;
        printf("{\"lensmodel\": \"%s\", \"width\": %d, \"height\": %d, ",
               mrcal_lensmodel_name_unconfigured(&cam.lensmodel), cam.width, cam.height);
        print_array("intrinsics", cam.intrinsics, cam.Nintrinsics);
        printf(", ");
        print_array("rt_cam_enu", cam.rt_cam_enu, 6);
        printf(", \"has_pose\": %s, \"has_R\": %s, \"has_P\": %s, ", extra.has_pose ? "true" : "false",
               extra.has_R ? "true" : "false", extra.has_P ? "true" : "false");
        print_array("P", extra.P, 12);
        printf("}\n");
        rs_camera_free(&cam);
        return 0;
    }
    if (argc == 5 && !strcmp(argv[1], "write")) {
        if (read_or_fail(&cam, NULL, argv[2])) return 1;
        rs_err err = {0};
        rs_status st = rs_camera_write_cameramodel(&cam, argv[3], &err);
        if (st == RS_OK) st = rs_camera_write_opencv_yaml(&cam, argv[4], &err);
        if (st) printf("ERROR %s: %s\n", rs_strerror(st), err.msg);
        rs_camera_free(&cam);
        return st ? 1 : 0;
    }
    if (argc == 3 && !strcmp(argv[1], "project")) {
        if (read_or_fail(&cam, NULL, argv[2])) return 1;
        double p[3], q[2];
        while (scanf("%lf %lf %lf", &p[0], &p[1], &p[2]) == 3) {
            rs_camera_project(q, &cam, p, 1);
            printf("%.17g %.17g\n", q[0], q[1]);
        }
        rs_camera_free(&cam);
        return 0;
    }
    if (argc == 7 && !strcmp(argv[1], "locate")) {
        if (read_or_fail(&cam, NULL, argv[2])) return 1;
        const double n[3] = {atof(argv[3]), atof(argv[4]), atof(argv[5])}, offset = atof(argv[6]);
        double q[2], p[3];
        while (scanf("%lf %lf", &q[0], &q[1]) == 2) {
            if (rs_camera_locate_ground(p, &cam, q, n, offset, NULL)) p[0] = p[1] = p[2] = NAN;
            printf("%.17g %.17g %.17g\n", p[0], p[1], p[2]);
        }
        rs_camera_free(&cam);
        return 0;
    }
    fprintf(stderr, "usage: see the top of test_camera_dump.c\n");
    return 2;
}
