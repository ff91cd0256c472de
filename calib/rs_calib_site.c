#include "calib/rs_calib_site.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>
#include <mrcal/mrcal.h>
#include <mrcal/poseutils.h>

#include "core/rs_camera.h"
#include "core/rs_io.h"
#include "core/rs_pose.h"
#include "geo/rs_geo.h"

// ---------------------------------------------------------------- homography

// Inverse of a 3x3 by the adjugate; false when singular relative to its scale.
static bool mat3_inv(double *Ai, const double *A)
{
    double c[9] = {
        A[4] * A[8] - A[5] * A[7], A[2] * A[7] - A[1] * A[8], A[1] * A[5] - A[2] * A[4],
        A[5] * A[6] - A[3] * A[8], A[0] * A[8] - A[2] * A[6], A[2] * A[3] - A[0] * A[5],
        A[3] * A[7] - A[4] * A[6], A[1] * A[6] - A[0] * A[7], A[0] * A[4] - A[1] * A[3],
    };
    double det = A[0] * c[0] + A[1] * c[3] + A[2] * c[6];
    double scale = 0;
    for (int i = 0; i < 9; i++) scale = fmax(scale, fabs(A[i]));
    if (!isfinite(det) || fabs(det) <= 1e-14 * scale * scale * scale) return false;
    for (int i = 0; i < 9; i++) Ai[i] = c[i] / det;
    return true;
}

static void normalise_h(double *H)
{
    double s = H[8];
    if (fabs(s) < 1e-12) return;
    for (int i = 0; i < 9; i++) H[i] /= s;
}

rs_status rs_calib_ground_homography(double H_px_from_ground[9], double H_ground_from_px[9], const double fxycxy[4],
                                     const double rt_cam_enu[6], const double plane_normal_enu[3],
                                     double plane_offset_m, rs_err *err)
{
    const double *n = plane_normal_enu;
    double nn = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(nn > 0) || fabs(n[2]) < 1e-9 * nn)
        return rs_err_set(err, RS_ERR_DEGENERATE, "ground plane: vertical or zero normal: no (E, N) parametrisation");
    // p(E, N) = p0 + E a + N b on the plane
    double a[3] = {1, 0, -n[0] / n[2]}, b[3] = {0, 1, -n[1] / n[2]}, p0[3] = {0, 0, plane_offset_m / n[2]};
    double R[9];
    mrcal_R_from_r(R, NULL, rt_cam_enu);
    // M = [R a | R b | R p0 + t]: camera-frame point of (E, N, 1)
    double M[9];
    for (int i = 0; i < 3; i++) {
        M[3 * i + 0] = R[3 * i] * a[0] + R[3 * i + 1] * a[1] + R[3 * i + 2] * a[2];
        M[3 * i + 1] = R[3 * i] * b[0] + R[3 * i + 1] * b[1] + R[3 * i + 2] * b[2];
        M[3 * i + 2] = R[3 * i] * p0[0] + R[3 * i + 1] * p0[1] + R[3 * i + 2] * p0[2] + rt_cam_enu[3 + i];
    }
    double K[9] = {fxycxy[0], 0, fxycxy[2], 0, fxycxy[1], fxycxy[3], 0, 0, 1};
    double H[9], Hi[9];
    rs_pose_mat3_mul(H, K, M);
    if (!mat3_inv(Hi, H))
        return rs_err_set(err, RS_ERR_DEGENERATE, "ground homography: singular (the camera lies in the ground plane)");
    normalise_h(H);
    normalise_h(Hi);
    memcpy(H_px_from_ground, H, sizeof H);
    memcpy(H_ground_from_px, Hi, sizeof Hi);
    return RS_OK;
}

// ---------------------------------------------------------------- surveyed reprojection

double rs_calib_site_rms_surveyed_px(const rs_site *site, int icam, const rs_calib_result *r, double *q_px)
{
    const rs_site_camera *cam = &site->cameras[icam];
    const rs_camera calibrated = rs_calib_result_camera(&cam->camera, r);
    double sum = 0;
    int n = 0;
    for (int i = 0; i < r->N && i < cam->Nobservations; i++) {
        const rs_site_observation *o = &cam->observations[i];
        double q[2] = {NAN, NAN}, p_enu[3];
        rs_site_seen_point(p_enu, q, site, o, &calibrated); // along: the nearest point of its polyline
        if (q_px) {
            q_px[2 * i] = q[0];
            q_px[2 * i + 1] = q[1];
        }
        if (!r->inlier[i] || !isfinite(q[0]) || !isfinite(q[1])) continue;
        sum += (q[0] - o->q_px[0]) * (q[0] - o->q_px[0]) + (q[1] - o->q_px[1]) * (q[1] - o->q_px[1]);
        n++;
    }
    return n ? sqrt(sum / n) : NAN;
}

// ---------------------------------------------------------------- JSON

static cJSON *json_array(const double *v, int n) { return cJSON_CreateDoubleArray(v, n); }

// (rows, cols) row-major as a list of rows
static cJSON *json_matrix(const double *m, int rows, int cols)
{
    cJSON *a = cJSON_CreateArray();
    if (!a) return NULL;
    for (int i = 0; i < rows; i++) cJSON_AddItemToArray(a, cJSON_CreateDoubleArray(m + i * cols, cols));
    return a;
}

static const char *lensmodel_name(char *buf, int size, const mrcal_lensmodel_t *m)
{
    if (!mrcal_lensmodel_name(buf, size, m)) snprintf(buf, (size_t)size, "(unnamed)");
    return buf;
}

// The noise model (docs/calibration.md, "Noise model") as root's "noise": each group's stated and
// estimated 1-sigma, the estimate's own 1-sigma and the redundancy it rests on.
static void json_noise(cJSON *root, const rs_calib_result *r)
{
    cJSON *noise = cJSON_AddArrayToObject(root, "noise");
    static const char *const groups[RS_CALIB_NOISE_NGROUPS] = {"pixel", "survey_horizontal", "survey_vertical"};
    static const char *const units[RS_CALIB_NOISE_NGROUPS] = {"px", "m", "m"};
    for (int g = 0; g < RS_CALIB_NOISE_NGROUPS; g++) {
        const rs_calib_noise_group *n = &r->noise[g];
        if (!n->Nobservations) continue;
        cJSON *o = cJSON_CreateObject();
        cJSON_AddStringToObject(o, "group", groups[g]);
        cJSON_AddStringToObject(o, "unit", units[g]);
        cJSON_AddNumberToObject(o, "stated", n->stated);
        cJSON_AddNumberToObject(o, "estimated", n->estimated);
        cJSON_AddNumberToObject(o, "sigma_estimated", n->sigma_estimated);
        cJSON_AddNumberToObject(o, "redundancy", n->redundancy);
        cJSON_AddNumberToObject(o, "observations", n->Nobservations);
        cJSON_AddBoolToObject(o, "estimated_from_data", n->estimated_from_data);
        cJSON_AddItemToArray(noise, o);
    }
}

// The intrinsics against the image (rs_calib_intrinsics_check; docs/calibration.md 7a) as root's
// "intrinsics_check"; null figures: not tested.
static void json_intrinsics_check(cJSON *root, const rs_calib_intrinsics_check *k)
{
    cJSON *ic = cJSON_AddObjectToObject(root, "intrinsics_check");
    if (k->focal_tested) {
        cJSON_AddNumberToObject(ic, "focal_rel", k->focal_rel);
        cJSON_AddNumberToObject(ic, "sigma_focal_rel", k->sigma_focal_rel);
        cJSON_AddNumberToObject(ic, "focal_stated_rel", k->focal_stated_rel);
        cJSON_AddNumberToObject(ic, "chi2_focal", k->chi2_focal);
        cJSON_AddNumberToObject(ic, "critical_focal", k->critical_focal);
        cJSON_AddNumberToObject(ic, "focal_mdb_rel", k->focal_mdb_rel);
        cJSON_AddNumberToObject(ic, "focal_mdb_shift_position_m", k->shift_position_m);
        cJSON_AddNumberToObject(ic, "focal_mdb_shift_mahalanobis2", k->shift_mahalanobis2);
    } else {
        cJSON_AddNullToObject(ic, "focal_rel");
    }
    if (k->center_tested) {
        cJSON_AddItemToObject(ic, "center_px", json_array(k->center_px, 2));
        cJSON_AddItemToObject(ic, "sigma_center_px", json_array(k->sigma_center_px, 2));
        cJSON_AddNumberToObject(ic, "center_stated_px", k->center_stated_px);
        cJSON_AddNumberToObject(ic, "chi2_center", k->chi2_center);
        cJSON_AddNumberToObject(ic, "critical_center", k->critical_center);
    } else {
        cJSON_AddNullToObject(ic, "center_px");
    }
    cJSON_AddBoolToObject(ic, "warned", k->warned);
}

char *rs_calib_site_result_json(const rs_site *site, int icam, const rs_calib_result *r)
{
    const rs_site_camera *cam = &site->cameras[icam];
    cJSON *root = cJSON_CreateObject();
    if (!root) return NULL;
    char name[256];
    cJSON_AddStringToObject(root, "camera", cam->id);
    cJSON_AddStringToObject(root, "site", site->name ? site->name : "");
    cJSON_AddStringToObject(root, "lensmodel", lensmodel_name(name, sizeof name, &cam->camera.lensmodel));
    double size[2] = {cam->camera.width, cam->camera.height};
    cJSON_AddItemToObject(root, "imagersize", json_array(size, 2));
    cJSON_AddItemToObject(root, "intrinsics", json_array(r->intrinsics, r->Nintrinsics));
    if (r->sigma_intrinsics)
        cJSON_AddItemToObject(root, "sigma_intrinsics", json_array(r->sigma_intrinsics, r->Nintrinsics));
    // the frame rt_cam_enu maps from: the site's ENU, whose origin a camera file alone cannot tell
    cJSON *origin = cJSON_AddObjectToObject(root, "enu_origin");
    cJSON_AddNumberToObject(origin, "lat_deg", site->origin.lat_deg);
    cJSON_AddNumberToObject(origin, "lon_deg", site->origin.lon_deg);
    cJSON_AddNumberToObject(origin, "h_m", site->origin.h_m);
    cJSON_AddStringToObject(origin, "frame",
                            "local east-north-up (metres) tangent to the WGS84 ellipsoid at this origin; h "
                            "ellipsoidal; rt_cam_enu maps it into the camera (x right, y down, z forward)");
    cJSON_AddItemToObject(root, "rt_cam_enu", json_array(r->rt_cam_enu, 6));
    cJSON_AddItemToObject(root, "covariance_rt_cam_enu", json_matrix(r->covariance_rt_cam_enu, 6, 6));
    cJSON_AddItemToObject(root, "position_enu_m", json_array(r->position_enu_m, 3));
    double llh[3];
    if (rs_geo_enu_to_llh(llh, &site->origin, r->position_enu_m, 1, NULL) == RS_OK)
        cJSON_AddItemToObject(root, "position_llh", json_array(llh, 3));
    else
        cJSON_AddNullToObject(root, "position_llh");
    cJSON_AddItemToObject(root, "yaw_pitch_roll_deg", json_array(r->yaw_pitch_roll_deg, 3));
    cJSON_AddItemToObject(root, "sigma_position_enu_m", json_array(r->sigma_position_enu_m, 3));
    cJSON_AddItemToObject(root, "sigma_yaw_pitch_roll_deg", json_array(r->sigma_yaw_pitch_roll_deg, 3));
    // the residuals (docs/calibration.md, "Residuals: which is which"): the headline is against
    // the surveyed positions; the one after the adjustment is named as such
    double *q_surveyed = malloc((size_t)(r->N > 0 ? r->N : 1) * 2 * sizeof(double));
    if (!q_surveyed) {
        cJSON_Delete(root);
        return NULL;
    }
    double rms_surveyed = rs_calib_site_rms_surveyed_px(site, icam, r, q_surveyed);
    if (isfinite(rms_surveyed))
        cJSON_AddNumberToObject(root, "rms_surveyed_px", rms_surveyed);
    else
        cJSON_AddNullToObject(root, "rms_surveyed_px");
    cJSON_AddNumberToObject(root, "rms_adjusted_px", r->rms_px);
    cJSON_AddNumberToObject(root, "landmarks_used", r->Ninliers);
    cJSON_AddNumberToObject(root, "landmarks_rejected", r->N - r->Ninliers);
    cJSON_AddNumberToObject(root, "chi2", r->chi2);
    cJSON_AddNumberToObject(root, "dof", r->dof);
    cJSON_AddNumberToObject(root, "variance_factor", r->variance_factor);
    cJSON_AddNumberToObject(root, "condition_number", r->condition_number);
    // the pose's 99.9% region in its covariance, and the degrees of freedom behind its scale
    cJSON_AddNumberToObject(root, "region999_m2", r->region_m2);
    if (isfinite(r->pose_dof))
        cJSON_AddNumberToObject(root, "pose_dof", r->pose_dof);
    else
        cJSON_AddNullToObject(root, "pose_dof");
    json_noise(root, r);
    cJSON_AddNumberToObject(root, "landmarks_rejected_by_snooping", r->Nrejected_snooping);
    cJSON_AddBoolToObject(root, "noise_model_wrong", r->noise_model_wrong);
    json_intrinsics_check(root, &r->intrinsics_check);
    cJSON *warnings = cJSON_AddArrayToObject(root, "warnings");
    char judged[512]; // the site's heights, nobody having declared them, taken from its ground model
    if (rs_site_heights_judgement(judged, sizeof judged, &site->ground)[0])
        cJSON_AddItemToArray(warnings, cJSON_CreateString(judged));
    char one[sizeof r->warnings + 512];
    for (const char *w = r->warnings; (w = rs_calib_site_warning_sentence(one, sizeof one, w, site, icam));)
        cJSON_AddItemToArray(warnings, cJSON_CreateString(one));
    cJSON *lms = cJSON_AddArrayToObject(root, "landmarks");
    for (int i = 0; i < r->N && i < cam->Nobservations; i++) {
        const rs_site_observation *o = &cam->observations[i];
        cJSON *l = cJSON_CreateObject();
        cJSON_AddStringToObject(l, "id", site->landmarks[o->ilandmark].id);
        cJSON_AddItemToObject(l, "observed_px", json_array(o->q_px, 2));
        const double *qs = &q_surveyed[2 * i];
        if (isfinite(qs[0]) && isfinite(qs[1])) {
            const double d[2] = {qs[0] - o->q_px[0], qs[1] - o->q_px[1]};
            cJSON_AddItemToObject(l, "predicted_surveyed_px", json_array(qs, 2));
            cJSON_AddItemToObject(l, "residual_surveyed_px", json_array(d, 2));
        } else { // behind the camera, or outside the lens model's domain
            cJSON_AddNullToObject(l, "predicted_surveyed_px");
            cJSON_AddNullToObject(l, "residual_surveyed_px");
        }
        cJSON_AddItemToObject(l, "predicted_adjusted_px", json_array(&r->predicted_px[2 * i], 2));
        cJSON_AddItemToObject(l, "residual_adjusted_px", json_array(&r->residual_px[2 * i], 2));
        cJSON_AddNumberToObject(l, "normalised_residual", r->normalised_residual[i]);
        cJSON_AddBoolToObject(l, "inlier", r->inlier[i]);
        // reliability (docs/calibration.md, "Outliers and reliability"); null where undefined
        cJSON_AddNumberToObject(l, "w_test", r->w_test[i]);
        cJSON_AddNumberToObject(l, "redundancy", r->redundancy[i]);
        cJSON_AddNumberToObject(l, "weight", r->weight[i]);
        cJSON_AddNumberToObject(l, "mdb_px", r->mdb_px[i]);
        cJSON_AddNumberToObject(l, "mdb_m", r->mdb_m[i]);
        cJSON_AddNumberToObject(l, "external_position_m", r->external_m[i]);
        cJSON_AddNumberToObject(l, "external_ground_m", r->external_ground_m[i]);
        double p_surveyed[3]; // along a pole or a line: the point of it nearest the pick
        const rs_camera calibrated = rs_calib_result_camera(&cam->camera, r);
        if (!rs_site_seen_point(p_surveyed, NULL, site, o, &calibrated))
            memcpy(p_surveyed, site->landmarks[o->ilandmark].p_enu_m, sizeof p_surveyed);
        cJSON_AddItemToObject(l, "p_enu_surveyed_m", json_array(p_surveyed, 3));
        cJSON_AddStringToObject(l, "at", rs_site_at_name(o->at));
        cJSON_AddItemToObject(l, "p_enu_adjusted_m", json_array(&r->p_enu_refined_m[3 * i], 3));
        cJSON_AddItemToArray(lms, l);
    }
    free(q_surveyed);
    cJSON *solver = cJSON_AddObjectToObject(root, "solver");
    cJSON_AddStringToObject(solver, "method", r->method);
    cJSON_AddNumberToObject(solver, "iterations", r->iterations);
    cJSON_AddNumberToObject(solver, "time_us", r->time_us);
    char *text = cJSON_Print(root);
    cJSON_Delete(root);
    return text;
}

// ---------------------------------------------------------------- files

static const char *const calib_suffixes[] = {RS_CAMERA_EXT_CAMERAMODEL, RS_CALIB_SITE_EXT_JSON,
                                             RS_CAMERA_EXT_OPENCV_YAML, RS_CALIB_SITE_EXT_HOMOGRAPHY};
enum { F_MODEL, F_JSON, F_YAML, F_HOMOGRAPHY, NFILES };
const rs_calib_site_outputs rs_calib_site_calib_outputs = {"calib.run.json", "roadside calib", calib_suffixes, NFILES};

// The text of <id>.homography.json into *text (caller frees).
static rs_status homography_json(char **text, const rs_site *site, const rs_site_camera *cam, const rs_calib_result *r,
                                 rs_err *err)
{
    *text = NULL;
    double H[9], Hi[9];
    rs_status st = rs_calib_ground_homography(H, Hi, r->intrinsics, r->rt_cam_enu, site->ground_normal_enu,
                                              site->ground_offset_m, err);
    if (st) return rs_err_prefix(err, "%s%s", cam->id, calib_suffixes[F_HOMOGRAPHY]);
    cJSON *root = cJSON_CreateObject();
    if (!root) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    cJSON_AddStringToObject(root, "camera", cam->id);
    cJSON_AddStringToObject(root, "description",
                            "H_ground_from_px maps undistorted pixels (u, v, 1) of the pinhole core "
                            "(fx, fy, cx, cy; pixel (0,0) = centre of the top-left pixel) to ground "
                            "(E, N, 1) in site ENU metres on the ground plane, up to scale; "
                            "H_px_from_ground is its inverse");
    cJSON_AddItemToObject(root, "pinhole_fxycxy", json_array(r->intrinsics, 4));
    cJSON *plane = cJSON_AddObjectToObject(root, "ground_plane");
    cJSON_AddItemToObject(plane, "normal_enu", json_array(site->ground_normal_enu, 3));
    cJSON_AddNumberToObject(plane, "offset_m", site->ground_offset_m);
    cJSON_AddItemToObject(root, "H_ground_from_px", json_matrix(Hi, 3, 3));
    cJSON_AddItemToObject(root, "H_px_from_ground", json_matrix(H, 3, 3));
    if (r->focal_undetermined && r->Nground_fit > 0) { // what the data determine (rs_calib_result)
        cJSON *ls = cJSON_AddObjectToObject(root, "least_squares");
        cJSON_AddStringToObject(ls, "why", "the landmarks cannot tell the focal length from the camera's distance");
        cJSON_AddItemToObject(ls, "H_ground_from_px", json_matrix(r->H_ground_from_px_fit, 3, 3));
        cJSON_AddNumberToObject(ls, "landmarks", r->Nground_fit);
        if (isfinite(r->sigma_ground_fit_m)) cJSON_AddNumberToObject(ls, "sigma_m", r->sigma_ground_fit_m);
    }
    *text = cJSON_Print(root);
    cJSON_Delete(root);
    return *text ? RS_OK : rs_err_set(err, RS_ERR_NOMEM, "out of memory");
}

// Puts comment lines (each starting with "# ") saying which frame the extrinsics map from into a
// camera file core/rs_camera.h just wrote under its temporary name: at the top of a .cameramodel
// (mrcal reads '#' comments), after the "%YAML:1.0" and "---" lines of an OpenCV YAML.
static rs_status annotate_frame(const char *tmp_path, const rs_site *site, const rs_site_camera *cam, bool yaml,
                                rs_err *err)
{
    char *text = NULL;
    size_t len = 0;
    rs_status st = rs_io_read_file(&text, &len, tmp_path, err);
    if (st) return st;
    char note[1536];
    snprintf(note, sizeof note,
             "# roadside calib: camera %s of site '%s'\n"
             "# %s map site ENU into the camera frame (x right, y down, z forward):\n"
             "# ENU = local east-north-up in metres, tangent to the WGS84 ellipsoid at the site's origin\n"
             "# enu_origin: lat %.9f deg, lon %.9f deg, h %.4f m (ellipsoidal)\n%s",
             cam->id, site->name ? site->name : "", yaml ? "rvec, tvec and R_cam_enu" : "The extrinsics (rt_cam_enu)",
             site->origin.lat_deg, site->origin.lon_deg, site->origin.h_m,
             yaml ? ""
                  : "# No optimization_inputs: the pose was solved by roadside (Ceres), not by mrcal's optimizer, so\n"
                    "# mrcal-show-projection-uncertainty and mrcal-show-residuals cannot read this model; the pose's\n"
                    "# uncertainty is in <id>.json, and 'roadside audit SITE --calib DIR' maps it on the ground\n");
    size_t at = 0; // where the note goes
    if (yaml)
        for (int lines = 0; lines < 2 && at < len; lines++) {
            const char *nl = memchr(text + at, '\n', len - at);
            if (!nl || (lines == 1 && strncmp(text + at, "---", 3))) break;
            at = (size_t)(nl - text) + 1;
        }
    FILE *f = fopen(tmp_path, "wb");
    if (!f) st = rs_err_set(err, RS_ERR_IO, "%s: %s", tmp_path, strerror(errno));
    if (!st && (fwrite(text, 1, at, f) != at || fputs(note, f) < 0 || fwrite(text + at, 1, len - at, f) != len - at))
        st = rs_err_set(err, RS_ERR_IO, "%s: write failed: %s", tmp_path, strerror(errno));
    if (f && fclose(f) != 0 && !st) st = rs_err_set(err, RS_ERR_IO, "%s: write failed: %s", tmp_path, strerror(errno));
    free(text);
    return st;
}

// Writes text into a file still under its temporary name.
static rs_status stage_text(rs_io_atomic *a, const char *text, rs_err *err)
{
    const size_t n = strlen(text);
    if (fwrite(text, 1, n, a->f) != n)
        return rs_err_set(err, RS_ERR_IO, "%s: write failed: %s", a->path, strerror(errno));
    return RS_OK;
}

rs_status rs_calib_site_write(unsigned *written, unsigned *removed, const char *out_dir, const rs_site *site, int icam,
                              const rs_calib_result *r, rs_err *err)
{
    rs_err local = {0};
    if (!err) err = &local;
    if (written) *written = 0;
    if (removed) *removed = 0;
    const rs_site_camera *cam = &site->cameras[icam];
    const rs_camera calibrated = rs_calib_result_camera(&cam->camera, r);
    const bool yaml = rs_camera_has_opencv_equivalent(&calibrated);
    rs_io_atomic staged[NFILES];
    memset(staged, 0, sizeof staged);
    char *json = NULL, *homography = NULL;
    if (!strcmp(cam->id, "calib.run") || !strcmp(cam->id, "audit.run")) // nothing written, nothing removed
        return rs_err_set(err, RS_ERR_INVALID, "camera id '%s': its %s.json would take a run record's name: rename it",
                          cam->id, cam->id);
    rs_status st = RS_OK;
    // the contents first, then every file under a temporary name, then all of them into place
    if (!st && !(json = rs_calib_site_result_json(site, icam, r))) st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    if (!st) st = homography_json(&homography, site, cam, r, err);
    for (int k = 0; k < NFILES && !st; k++) {
        if (k == F_YAML && !yaml) continue;
        // every name is built by rs_io_child_path: an id that could leave out_dir is refused
        char *path = rs_io_child_path(out_dir, cam->id, calib_suffixes[k], err);
        st = path ? rs_io_atomic_open(&staged[k], path, err) : err->status;
        free(path);
    }
    if (!st) st = rs_io_atomic_release(&staged[F_MODEL], err);
    if (!st) st = rs_camera_write_cameramodel(&calibrated, staged[F_MODEL].tmp_path, err);
    if (!st) st = annotate_frame(staged[F_MODEL].tmp_path, site, cam, false, err);
    if (!st) st = stage_text(&staged[F_JSON], json, err);
    if (!st && yaml) st = rs_io_atomic_release(&staged[F_YAML], err);
    if (!st && yaml) st = rs_camera_write_opencv_yaml(&calibrated, staged[F_YAML].tmp_path, err);
    if (!st && yaml) st = annotate_frame(staged[F_YAML].tmp_path, site, cam, true, err);
    if (!st) st = stage_text(&staged[F_HOMOGRAPHY], homography, err);
    for (int k = 0; k < NFILES && !st; k++)
        if (staged[k].path) st = rs_io_atomic_commit(&staged[k], err);
    for (int k = 0; k < NFILES; k++) rs_io_atomic_abort(&staged[k]); // the temporaries not committed
    free(json);
    free(homography);

    rs_err rerr = {0};
    rs_status rst = RS_OK;
    unsigned gone = 0;
    if (st) // nothing of this camera stays: neither a file committed before the failure nor an earlier run's
        rst = rs_calib_site_outputs_remove(&gone, out_dir, cam->id, &rs_calib_site_calib_outputs, &rerr);
    else if (!yaml) { // an earlier run's <id>.opencv.yaml would describe another calibration
        char *path = rs_io_child_path(out_dir, cam->id, calib_suffixes[F_YAML], &rerr);
        bool was = false;
        rst = path ? rs_io_remove_if_exists(path, &was, &rerr) : rerr.status;
        free(path);
        gone = was ? 1u << F_YAML : 0;
    }
    if (removed) *removed = gone;
    if (st && rst && rst != RS_ERR_INVALID) { // the failure, and what could not be cleaned up
        char first[sizeof err->msg];
        snprintf(first, sizeof first, "%s", err->msg);
        rs_err_set(err, st, "%s; and %s", first, rerr.msg);
    } else if (!st && rst)
        st = rs_err_set(err, rst, "%s", rerr.msg);
    if (!st && written) *written = (1u << NFILES) - 1 - (yaml ? 0 : 1u << F_YAML);
    return st;
}

// ---------------------------------------------------------------- reading <id>.json back

static rs_status json_numbers(double *out, int n, const cJSON *obj, const char *name, const char *path, rs_err *err)
{
    const cJSON *a = cJSON_GetObjectItemCaseSensitive(obj, name);
    if (!cJSON_IsArray(a) || cJSON_GetArraySize(a) != n)
        return rs_err_set(err, RS_ERR_PARSE, "%s: %s: expected an array of %d numbers", path, name, n);
    int i = 0;
    const cJSON *x;
    cJSON_ArrayForEach(x, a)
    {
        if (!cJSON_IsNumber(x) || !isfinite(x->valuedouble))
            return rs_err_set(err, RS_ERR_PARSE, "%s: %s[%d]: not a finite number", path, name, i);
        out[i++] = x->valuedouble;
    }
    return RS_OK;
}

static rs_status json_number(double *out, const cJSON *obj, const char *name, const char *path, rs_err *err)
{
    const cJSON *x = cJSON_GetObjectItemCaseSensitive(obj, name);
    if (!cJSON_IsNumber(x)) return rs_err_set(err, RS_ERR_PARSE, "%s: %s: expected a number", path, name);
    *out = x->valuedouble;
    return RS_OK;
}

// The member `name`, or when the file has none (written before the residuals were renamed) the
// member `old_name`: a file is read by the names it was written with.
static const char *member_name(const cJSON *obj, const char *name, const char *old_name)
{
    return !cJSON_GetObjectItemCaseSensitive(obj, name) && cJSON_GetObjectItemCaseSensitive(obj, old_name) ? old_name
                                                                                                           : name;
}

// An optional array of n numbers: NaN when absent or null (not computable when written).
static rs_status json_numbers_or_nan(double *out, int n, const cJSON *obj, const char *name, const char *path,
                                     rs_err *err)
{
    const cJSON *a = cJSON_GetObjectItemCaseSensitive(obj, name);
    if (!a || cJSON_IsNull(a)) {
        for (int i = 0; i < n; i++) out[i] = NAN;
        return RS_OK;
    }
    return json_numbers(out, n, obj, name, path, err);
}

static rs_status read_warnings(rs_calib_site_result *r, const cJSON *root, const char *path, rs_err *err)
{
    const cJSON *warnings = cJSON_GetObjectItemCaseSensitive(root, "warnings");
    if (!cJSON_IsArray(warnings)) return rs_err_set(err, RS_ERR_PARSE, "%s: warnings: expected an array", path);
    r->warnings = calloc((size_t)cJSON_GetArraySize(warnings) + 1, sizeof *r->warnings);
    if (!r->warnings) return rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", path);
    const cJSON *w;
    cJSON_ArrayForEach(w, warnings)
    {
        if (!cJSON_IsString(w))
            return rs_err_set(err, RS_ERR_PARSE, "%s: warnings[%d]: expected a string", path, r->Nwarnings);
        if (!(r->warnings[r->Nwarnings++] = strdup(w->valuestring)))
            return rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", path);
    }
    return RS_OK;
}

static rs_status read_landmarks(rs_calib_site_result *r, const cJSON *root, const char *path, rs_err *err)
{
    const cJSON *lms = cJSON_GetObjectItemCaseSensitive(root, "landmarks");
    if (!cJSON_IsArray(lms)) return rs_err_set(err, RS_ERR_PARSE, "%s: landmarks: expected an array", path);
    r->landmarks = calloc((size_t)cJSON_GetArraySize(lms) + 1, sizeof *r->landmarks);
    if (!r->landmarks) return rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", path);
    const cJSON *l;
    cJSON_ArrayForEach(l, lms)
    {
        rs_calib_site_landmark *m = &r->landmarks[r->N];
        char field[64];
        snprintf(field, sizeof field, "landmarks[%d]", r->N);
        const cJSON *id = cJSON_GetObjectItemCaseSensitive(l, "id");
        const cJSON *inl = cJSON_GetObjectItemCaseSensitive(l, "inlier");
        if (!cJSON_IsString(id) || !cJSON_IsBool(inl))
            return rs_err_set(err, RS_ERR_PARSE, "%s: %s: expected a string id and a boolean inlier", path, field);
        if (!(m->id = strdup(id->valuestring))) return rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", path);
        r->N++;
        m->inlier = cJSON_IsTrue(inl);
        rs_status st = json_numbers(m->observed_px, 2, l, "observed_px", path, err);
        if (!st)
            st = json_numbers(m->predicted_adjusted_px, 2, l, member_name(l, "predicted_adjusted_px", "predicted_px"),
                              path, err);
        if (!st)
            st = json_numbers(m->residual_adjusted_px, 2, l, member_name(l, "residual_adjusted_px", "residual_px"),
                              path, err);
        if (!st) st = json_numbers_or_nan(m->predicted_surveyed_px, 2, l, "predicted_surveyed_px", path, err);
        if (!st) st = json_numbers_or_nan(m->residual_surveyed_px, 2, l, "residual_surveyed_px", path, err);
        // a file with the surveyed prediction but not its residual (written before it was)
        if (!st && !cJSON_GetObjectItemCaseSensitive(l, "residual_surveyed_px"))
            for (int k = 0; k < 2; k++) m->residual_surveyed_px[k] = m->predicted_surveyed_px[k] - m->observed_px[k];
        if (!st) st = json_number(&m->normalised_residual, l, "normalised_residual", path, err);
        if (st) return rs_err_prefix(err, "%s", field);
    }
    return RS_OK;
}

// intrinsics_check's chi2 above its critical value (absent, in older files: not off)
static bool check_off(const cJSON *ic, const char *chi2, const char *critical)
{
    const cJSON *x = cJSON_GetObjectItemCaseSensitive(ic, chi2), *c = cJSON_GetObjectItemCaseSensitive(ic, critical);
    return cJSON_IsNumber(x) && cJSON_IsNumber(c) && x->valuedouble > c->valuedouble;
}

rs_status rs_calib_site_result_read(rs_calib_site_result *r, const char *path, rs_err *err)
{
    memset(r, 0, sizeof *r);
    char *text = NULL;
    rs_status st = rs_io_read_file(&text, NULL, path, err);
    if (st) return st;
    cJSON *root = cJSON_Parse(text);
    free(text);
    if (!cJSON_IsObject(root)) {
        cJSON_Delete(root);
        return rs_err_set(err, RS_ERR_PARSE, "%s: not a JSON object (run 'roadside calib' again?)", path);
    }
    double used = 0, rejected = 0;
    if (!st) st = json_numbers(r->position_enu_m, 3, root, "position_enu_m", path, err);
    if (!st) st = json_numbers(r->sigma_position_enu_m, 3, root, "sigma_position_enu_m", path, err);
    if (!st) st = json_numbers(r->position_llh, 3, root, "position_llh", path, err);
    if (!st) st = json_numbers(r->yaw_pitch_roll_deg, 3, root, "yaw_pitch_roll_deg", path, err);
    if (!st) st = json_numbers(r->sigma_yaw_pitch_roll_deg, 3, root, "sigma_yaw_pitch_roll_deg", path, err);
    // the headline, against the surveyed positions: null when it could not be computed, absent
    // from files older than it (NaN); the one after the adjustment is required
    const char *srv = member_name(root, "rms_surveyed_px", "rms_px_surveyed");
    const cJSON *rms_srv = cJSON_GetObjectItemCaseSensitive(root, srv);
    r->rms_surveyed_px = NAN;
    if (!st && rms_srv && !cJSON_IsNull(rms_srv)) st = json_number(&r->rms_surveyed_px, root, srv, path, err);
    if (!st) st = json_number(&r->rms_adjusted_px, root, member_name(root, "rms_adjusted_px", "rms_px"), path, err);
    if (!st) st = json_number(&r->variance_factor, root, "variance_factor", path, err);
    if (!st) st = json_number(&r->condition_number, root, "condition_number", path, err);
    if (!st) st = json_number(&used, root, "landmarks_used", path, err);
    if (!st) st = json_number(&rejected, root, "landmarks_rejected", path, err);
    r->Nused = (int)used;
    r->Nrejected = (int)rejected;
    const cJSON *lm = cJSON_GetObjectItemCaseSensitive(root, "lensmodel");
    if (!st && !cJSON_IsString(lm)) st = rs_err_set(err, RS_ERR_PARSE, "%s: lensmodel: expected a string", path);
    if (!st && !(r->lensmodel = strdup(lm->valuestring))) st = rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", path);
    if (!st) st = read_warnings(r, root, path, err);
    if (!st) st = read_landmarks(r, root, path, err);
    const cJSON *ic = cJSON_GetObjectItemCaseSensitive(root, "intrinsics_check"), *f;
    r->focal_rel = cJSON_IsNumber(f = cJSON_GetObjectItemCaseSensitive(ic, "focal_rel")) ? f->valuedouble : NAN;
    r->focal_off = check_off(ic, "chi2_focal", "critical_focal");
    r->center_off = check_off(ic, "chi2_center", "critical_center");
    cJSON_Delete(root);
    return st;
}

void rs_calib_site_result_free(rs_calib_site_result *r)
{
    if (!r) return;
    for (int i = 0; i < r->N; i++) free(r->landmarks[i].id);
    free(r->landmarks);
    for (int i = 0; i < r->Nwarnings; i++) free(r->warnings[i]);
    free(r->warnings);
    free(r->lensmodel);
    memset(r, 0, sizeof *r);
}
