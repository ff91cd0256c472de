// rs_localise.c -- one detection to the ground: its pixel, its point, its covariance
// (rs_localise.h, Method).
#include "eval/localise/rs_localise.h"

#include <math.h>
#include <string.h>

#include <mrcal/poseutils.h>

#include "core/rs_camera_ground.h"

bool rs_localise_point_parse(rs_localise_point *point, const char *s)
{
    static const char *const names[] = {"center", "bottom", "shift"};
    for (int k = 0; k < 3; k++)
        if (!strcmp(s, names[k])) {
            *point = (rs_localise_point)k;
            return true;
        }
    return false;
}

void rs_localise_box_point(double q_px[2], const double b[4], rs_localise_point point, double K)
{
    q_px[0] = b[0] + 0.5 * b[2];
    q_px[1] = point == RS_LOCALISE_POINT_BOTTOM  ? b[1] + b[3]
              : point == RS_LOCALISE_POINT_SHIFT ? b[1] + 0.5 * b[3] + K * b[3]
                                                 : b[1] + 0.5 * b[3];
}

rs_localise_view rs_localise_view_make(const rs_camera *camera, const double *covariance_rt,
                                       const double ground_normal_enu[3], double ground_offset_m, const rs_llh *origin)
{
    rs_localise_view v = {.camera = camera,
                          .covariance_rt = covariance_rt,
                          .ground_offset_m = ground_offset_m,
                          .origin = origin,
                          .max_tan = rs_camera_max_tan(camera)};
    memcpy(v.ground_normal_enu, ground_normal_enu, sizeof v.ground_normal_enu);
    return v;
}

rs_status rs_localise_detection_locate(rs_localise_row *row, const rs_localise_detection *det,
                                       const rs_localise_view *view, const rs_localise_options *opt, rs_err *err)
{
    if (!(opt->pixel_sigma_px >= 0) || !isfinite(opt->pixel_sigma_px) || !isfinite(opt->shift))
        return rs_err_set(err, RS_ERR_INVALID, "pixel sigma %g, shift %g: must be finite, sigma >= 0",
                          opt->pixel_sigma_px, opt->shift);
    double q[2];
    if (det->has_bottom_center)
        memcpy(q, det->bottom_center_px, sizeof q);
    else
        rs_localise_box_point(q, det->bbox_px, opt->point, opt->shift);
    const double s2 = opt->pixel_sigma_px * opt->pixel_sigma_px, cov_q[4] = {s2, 0, 0, s2};
    double p[3], cov[4];
    rs_status st = rs_camera_ground_locate(p, cov, view->camera, view->covariance_rt, q, cov_q, view->ground_normal_enu,
                                           view->ground_offset_m, err);
    if (st) return st;
    double pc[3];
    mrcal_transform_point_rt(pc, NULL, NULL, view->camera->rt_cam_enu, p);
    if (!rs_camera_in_field(pc, view->max_tan))
        return rs_err_set(err, RS_ERR_DEGENERATE, "pixel (%g, %g): outside the lens's valid field", q[0], q[1]);
    *row = (rs_localise_row){.image_id = det->image_id,
                             .frame = det->frame,
                             .time_s = det->time_s,
                             .category_id = det->category_id,
                             .score = det->score,
                             .u_px = q[0],
                             .v_px = q[1],
                             .e_m = p[0],
                             .n_m = p[1],
                             .u_m = p[2],
                             .lat_deg = NAN,
                             .lon_deg = NAN,
                             .sigma_e_m = sqrt(cov[0]),
                             .sigma_n_m = sqrt(cov[3]),
                             .cov_en_m2 = 0.5 * (cov[1] + cov[2])};
    memcpy(row->camera, det->camera, sizeof row->camera);
    if (view->origin) {
        double llh[3];
        if ((st = rs_geo_enu_to_llh(llh, view->origin, p, 1, err))) return st;
        row->lat_deg = llh[0];
        row->lon_deg = llh[1];
    }
    return RS_OK;
}
