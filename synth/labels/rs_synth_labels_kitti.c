// rs_synth_labels_kitti.c -- KITTI's frames of a roadside camera (synth/labels/rs_synth_labels.h):
// the rectified frame that levels a tilted camera (R0_rect), P2 for the undistorted image, and the
// calib file. Calls mrcal and core/.
#include <math.h>
#include <stdio.h>

#include <mrcal/mrcal.h>

#include "core/rs_io.h"
#include "synth/labels/rs_synth_labels.h"

rs_status rs_synth_labels_kitti_rect(double R0_rect[9], double P2[12], const rs_camera *cam, rs_err *err)
{
    mrcal_lensmodel_metadata_t meta = mrcal_lensmodel_metadata(&cam->lensmodel);
    if (!meta.has_core) return rs_err_set(err, RS_ERR_UNSUPPORTED, "KITTI calib: lens model without fx, fy, cx, cy");
    double R[9];
    mrcal_R_from_r(R, NULL, cam->rt_cam_enu);
    // y_r: ENU down (0, 0, -1) in camera coordinates, minus the third column of R_cam_enu
    double *x = R0_rect, *y = R0_rect + 3, *z = R0_rect + 6;
    for (int i = 0; i < 3; i++) y[i] = -R[3 * i + 2];
    // z_r: the optical axis (0, 0, 1) made horizontal; looking straight down: the camera's up
    double a[3] = {0, 0, 1};
    if (fabs(y[2]) > 0.999999) a[1] = -1, a[2] = 0;
    const double ay = a[0] * y[0] + a[1] * y[1] + a[2] * y[2];
    for (int i = 0; i < 3; i++) z[i] = a[i] - ay * y[i];
    const double nz = sqrt(z[0] * z[0] + z[1] * z[1] + z[2] * z[2]);
    for (int i = 0; i < 3; i++) z[i] /= nz;
    x[0] = y[1] * z[2] - y[2] * z[1];
    x[1] = y[2] * z[0] - y[0] * z[2];
    x[2] = y[0] * z[1] - y[1] * z[0];
    if (!P2) return RS_OK;
    const double *f = cam->intrinsics; // K R0^T: row r of K dotted with column c of R0^T (row c of R0)
    const double K[9] = {f[0], 0, f[2], 0, f[1], f[3], 0, 0, 1};
    for (int r = 0; r < 3; r++) {
        for (int c = 0; c < 3; c++)
            P2[4 * r + c] =
                K[3 * r] * R0_rect[3 * c] + K[3 * r + 1] * R0_rect[3 * c + 1] + K[3 * r + 2] * R0_rect[3 * c + 2];
        P2[4 * r + 3] = 0;
    }
    return RS_OK;
}

rs_status rs_synth_labels_write_kitti_calib(const char *path, const rs_camera *cam, rs_err *err)
{
    double R0[9], P2[12], R[9];
    if (!mrcal_lensmodel_metadata(&cam->lensmodel).has_core)
        return rs_err_set(err, RS_ERR_UNSUPPORTED, "%s: KITTI calib: lens model without fx, fy, cx, cy", path);
    rs_status st = rs_synth_labels_kitti_rect(R0, P2, cam, err);
    if (st) return st;
    mrcal_R_from_r(R, NULL, cam->rt_cam_enu);
    const double *t = cam->rt_cam_enu + 3;
    rs_io_atomic a = {0};
    if ((st = rs_io_atomic_open(&a, path, err))) return st;
    for (int i = 0; i < 4; i++) {
        fprintf(a.f, "P%d:", i);
        for (int j = 0; j < 12; j++) fprintf(a.f, " %.12e", P2[j]);
        fputc('\n', a.f);
    }
    fprintf(a.f, "R0_rect:");
    for (int j = 0; j < 9; j++) fprintf(a.f, " %.12e", R0[j]);
    fprintf(a.f, "\nTr_velo_to_cam:");
    for (int r = 0; r < 3; r++) fprintf(a.f, " %.12e %.12e %.12e %.12e", R[3 * r], R[3 * r + 1], R[3 * r + 2], t[r]);
    fprintf(a.f, "\nTr_imu_to_velo: 1 0 0 0 0 1 0 0 0 0 1 0\n");
    return rs_io_atomic_commit(&a, err);
}
