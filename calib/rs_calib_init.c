// rs_calib_init.c -- initial camera pose: bearings, degeneracy checks, the non-minimal solves on
// every landmark, and where they do not all agree RANSAC over P3P scored in pixels, non-minimal
// solves on its inliers. See rs_calib_init.h and
// docs/calibration-init.md. The solvers themselves are OpenGV's and OpenCV's, behind the shims
// rs_calib_opengv.h and calib/internal/rs_calib_opencv.h; this file holds the logic.
#include "calib/rs_calib_init.h"
#include "core/rs_lens.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <mrcal/poseutils.h>

#include "calib/internal/rs_calib_opencv.h"
#include "calib/rs_calib_opengv.h"

// Landmarks whose centred point cloud has s2/s1 below this are collinear: the rotation about
// their line is undetermined.
#define RS_INIT_COLLINEAR_RATIO 1e-3
// Observations whose bearings all lie within this angle of each other sit in a tiny patch of
// the image: the pose is not determined (0.2 deg is 3.5 px at f = 1000 px).
#define RS_INIT_MIN_SPREAD_DEG  0.2
// Two landmarks closer than this fraction of the cloud's RMS radius are the same landmark.
#define RS_INIT_DUPLICATE_REL   1e-9
// RANSAC stops once an outlier-free sample has been drawn with this probability.
#define RS_INIT_CONFIDENCE      0.999
// SQPnP is tried on this many observations or more: on fewer, RANSAC's P3P has tried every
// sample or nearly, and SQPnP's search costs more than it gains (a harness of 50 problems of 4
// landmarks: 141 us per calibration with it, 99 us without).
#define RS_INIT_SQPNP_MIN       6
// IPPE and SQPnP need bearings clearly in front of the camera to form x/z, y/z.
#define RS_INIT_MIN_VZ          1e-6

void rs_calib_init_options_default(rs_calib_init_options *opt)
{
    opt->ransac_threshold_px = 8.0;
    opt->ransac_max_iterations = 500;
    opt->seed = 1;
    opt->planarity_ratio = 0.02;
    opt->sigma_enu_m = NULL;
    opt->survey_sigmas = 3.0;
}

// What the pixel scoring needs: the lens and the observations in the centred frame.
typedef struct {
    const mrcal_lensmodel_t *lensmodel;
    const double *intrinsics;
    const double *p_c;  // (N,3) landmarks minus their centroid
    const double *q_px; // (N,2)
    // Survey noise in the inlier test (rs_calib_init_options): when ks_px (N,) is not NULL,
    // errors are scaled by T / sqrt(T^2 + (ks_px[i] / z_i)^2), so that comparing them with T is
    // the per-landmark test. ks_px[i] = k f s_i, pixel metres.
    const double *ks_px;
    double T_px;
} scorer;

// rs_calib_opengv_score_fn: reprojection error in pixels through the lens model (scaled by
// the survey noise when s->ks_px is set); +inf for landmarks not in front of the camera
// (z_cam <= 0) or that do not project.
static void pixel_errors(double *err_px, const double *Rt_cam_c, const int *indices, int Nindices, void *cookie)
{
    const scorer *s = cookie;
    for (int k = 0; k < Nindices; k++) {
        const int i = indices[k];
        const mrcal_point3_t p = {.xyz = {s->p_c[3 * i], s->p_c[3 * i + 1], s->p_c[3 * i + 2]}};
        mrcal_point3_t p_cam;
        mrcal_point2_t q;
        mrcal_transform_point_Rt(p_cam.xyz, NULL, NULL, Rt_cam_c, p.xyz);
        err_px[k] = INFINITY;
        if (!(p_cam.z > 0.0)) continue;
        if (!rs_lens_project(&q, NULL, NULL, &p_cam, 1, s->lensmodel, s->intrinsics)) continue;
        double e = hypot(q.x - s->q_px[2 * i], q.y - s->q_px[2 * i + 1]);
        if (s->ks_px) {
            const double a = s->ks_px[i] / p_cam.z;
            e *= s->T_px / sqrt(s->T_px * s->T_px + a * a);
        }
        if (isfinite(e)) err_px[k] = e;
    }
}

// RMS pixel error of the observations `indices` at the pose rt_cam_c (centred frame); +inf if
// any of them is behind the camera. tmp is (Nindices,) scratch.
static double rms_px_at(const double *rt_cam_c, const int *indices, int Nindices, const scorer *s, double *tmp)
{
    double Rt[12];
    mrcal_Rt_from_rt(Rt, NULL, rt_cam_c);
    pixel_errors(tmp, Rt, indices, Nindices, (void *)s);
    double sum = 0.0;
    for (int k = 0; k < Nindices; k++) sum += tmp[k] * tmp[k];
    return Nindices > 0 ? sqrt(sum / Nindices) : INFINITY;
}

static double angle_deg(const double *a, const double *b)
{
    // atan2(|a x b|, a.b): accurate for tiny angles, unlike acos
    const double c[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
    return atan2(sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]), a[0] * b[0] + a[1] * b[1] + a[2] * b[2]) * 180.0 / M_PI;
}

// A pixel's bearing (any length) is mrcal_unproject's, except where OpenCV's undistortion already
// gave one: OpenCV's model is LENSMODEL_OPENCVn's, and its fixed-point iteration costs a small
// fraction of mrcal's unprojection, a dogleg solve per pixel (9% of a 20-landmark calibration
// with exact survey coordinates). OpenCV's answer xy_cv (2,) (may be NULL) is kept where mrcal
// projects it back within RS_INIT_UNDISTORT_TOL_PX of the pixel, and mrcal unprojects the pixel
// where it does not. False where neither gives a bearing.
#define RS_INIT_UNDISTORT_TOL_PX 1e-6
static bool unproject(mrcal_point3_t *v, const double *xy_cv, const mrcal_point2_t *q,
                      const mrcal_lensmodel_t *lensmodel, const double *intrinsics)
{
    if (xy_cv && isfinite(xy_cv[0]) && isfinite(xy_cv[1])) {
        *v = (mrcal_point3_t){.xyz = {xy_cv[0], xy_cv[1], 1.0}};
        mrcal_point2_t q_back;
        if (rs_lens_project(&q_back, NULL, NULL, v, 1, lensmodel, intrinsics) &&
            hypot(q_back.x - q->x, q_back.y - q->y) <= RS_INIT_UNDISTORT_TOL_PX)
            return true;
    }
    return rs_lens_unproject(v, q, 1, lensmodel, intrinsics);
}

static rs_status check_arguments(const rs_calib_init_result *result, const mrcal_lensmodel_t *lensmodel,
                                 const double *intrinsics, const double *p_enu_m, const double *q_px, int N,
                                 const rs_calib_init_options *opt, rs_err *err)
{
    if (!result || !lensmodel || !intrinsics || N < 0 || (N > 0 && (!p_enu_m || !q_px)))
        return rs_err_set(err, RS_ERR_USAGE,
                          "rs_calib_init_pose: NULL result, lensmodel, intrinsics, p_enu_m or "
                          "q_px, or N < 0 (N = %d)",
                          N);
    if (!(opt->ransac_threshold_px > 0.0) || !isfinite(opt->ransac_threshold_px))
        return rs_err_set(err, RS_ERR_INVALID, "ransac_threshold_px: %g is not a positive pixel count",
                          opt->ransac_threshold_px);
    if (opt->ransac_max_iterations < 1)
        return rs_err_set(err, RS_ERR_INVALID, "ransac_max_iterations: %d is not >= 1", opt->ransac_max_iterations);
    if (!(opt->survey_sigmas >= 0.0) || !isfinite(opt->survey_sigmas))
        return rs_err_set(err, RS_ERR_INVALID, "survey_sigmas: %g is not a finite number >= 0", opt->survey_sigmas);
    if (opt->sigma_enu_m)
        for (int i = 0; i < 3 * N; i++)
            if (!(opt->sigma_enu_m[i] >= 0.0) || !isfinite(opt->sigma_enu_m[i]))
                return rs_err_set(err, RS_ERR_INVALID,
                                  "sigma_enu_m[%d]: landmark %d's survey sigma %g is not a finite "
                                  "number >= 0",
                                  i / 3, i / 3, opt->sigma_enu_m[i]);
    if (!(opt->planarity_ratio >= 0.0 && opt->planarity_ratio < 1.0))
        return rs_err_set(err, RS_ERR_INVALID, "planarity_ratio: %g is not in [0,1)", opt->planarity_ratio);
    const int Nintrinsics = mrcal_lensmodel_num_params(lensmodel);
    if (Nintrinsics <= 0)
        return rs_err_set(err, RS_ERR_INVALID, "lensmodel: not a valid mrcal lens model (type %d)",
                          (int)lensmodel->type);
    for (int j = 0; j < Nintrinsics; j++)
        if (!isfinite(intrinsics[j]))
            return rs_err_set(err, RS_ERR_INVALID, "intrinsics[%d]: non-finite value %g", j, intrinsics[j]);
    for (int i = 0; i < N; i++) {
        const double *p = &p_enu_m[3 * i], *q = &q_px[2 * i];
        if (!isfinite(p[0]) || !isfinite(p[1]) || !isfinite(p[2]))
            return rs_err_set(err, RS_ERR_INVALID, "p_enu_m[%d]: landmark %d has a non-finite coordinate (%g, %g, %g)",
                              i, i, p[0], p[1], p[2]);
        if (!isfinite(q[0]) || !isfinite(q[1]))
            return rs_err_set(err, RS_ERR_INVALID, "q_px[%d]: observation %d has a non-finite pixel (%g, %g)", i, i,
                              q[0], q[1]);
    }
    return RS_OK;
}

// Repeated landmarks (the same point twice, a copied coordinate most often): every later copy
// leaves `usable` (the initial pose uses the first; the refinement still sees every landmark and
// flags whichever copy disagrees with its pixels). Pairwise over the usable observations of one
// camera. Returns how many remain.
static int drop_repeated(const double *p_c, int *usable, int Nusable, const double *s)
{
    const double rms_radius =
        s[0] * s[0] + s[1] * s[1] + s[2] * s[2] > 0.0 ? sqrt((s[0] * s[0] + s[1] * s[1] + s[2] * s[2]) / Nusable) : 0.0;
    int n = 0;
    for (int a = 0; a < Nusable; a++) {
        const double *pa = &p_c[3 * usable[a]];
        bool repeated = false;
        for (int b = 0; b < n && !repeated; b++) {
            const double *pb = &p_c[3 * usable[b]];
            const double d = sqrt((pa[0] - pb[0]) * (pa[0] - pb[0]) + (pa[1] - pb[1]) * (pa[1] - pb[1]) +
                                  (pa[2] - pb[2]) * (pa[2] - pb[2]));
            repeated = d <= RS_INIT_DUPLICATE_REL * rms_radius;
        }
        if (!repeated) usable[n++] = usable[a];
    }
    return n;
}

// Degeneracy checks on the usable observations. s: singular values of the centred landmarks.
static rs_status check_geometry(const double *v, const int *usable, int Nusable, const double *s, rs_err *err)
{
    if (!(s[1] > RS_INIT_COLLINEAR_RATIO * s[0]))
        return rs_err_set(err, RS_ERR_DEGENERATE,
                          "p_enu_m: the %d usable landmarks are collinear (singular values of the "
                          "centred points %.3g, %.3g, %.3g m: s2/s1 < %g): the rotation about "
                          "their line is undetermined",
                          Nusable, s[0], s[1], s[2], RS_INIT_COLLINEAR_RATIO);
    double spread_deg = 0.0; // the largest angle, or the first beyond the limit (N^2 pairs: 4% at N = 200)
    for (int a = 0; a < Nusable && spread_deg < RS_INIT_MIN_SPREAD_DEG; a++)
        for (int b = a + 1; b < Nusable && spread_deg < RS_INIT_MIN_SPREAD_DEG; b++) {
            const double t = angle_deg(&v[3 * usable[a]], &v[3 * usable[b]]);
            if (t > spread_deg) spread_deg = t;
        }
    if (spread_deg < RS_INIT_MIN_SPREAD_DEG)
        return rs_err_set(err, RS_ERR_DEGENERATE,
                          "q_px: all %d usable observations lie in a tiny patch of the image "
                          "(largest angle between their bearings %.3g deg < %g deg): the pose is "
                          "undetermined",
                          Nusable, spread_deg, RS_INIT_MIN_SPREAD_DEG);
    return RS_OK;
}

// rt_cam_enu = rt_cam_c composed with the translation p_c = p_enu - centroid.
static void uncentre(double *rt_cam_enu, const double *rt_cam_c, const double *centroid)
{
    const double rt_c_enu[6] = {0, 0, 0, -centroid[0], -centroid[1], -centroid[2]};
    mrcal_compose_rt(rt_cam_enu, NULL, NULL, NULL, NULL, rt_cam_c, rt_c_enu);
}

// OpenCV's IPPE or SQPnP (rs_calib_opencv_pnp) on the inliers `in` seen in front of the camera.
// xy (Nin,2), p_sel (Nin,3): scratch.
static bool solve_opencv(double *rt_cam_c, rs_calib_opencv_pnp_method method, const double *v, const double *p_c,
                         const int *in, int Nin, double *xy, double *p_sel)
{
    int n = 0;
    for (int k = 0; k < Nin; k++) {
        const double *vi = &v[3 * in[k]];
        if (!(vi[2] > RS_INIT_MIN_VZ)) continue;
        xy[2 * n] = vi[0] / vi[2];
        xy[2 * n + 1] = vi[1] / vi[2];
        memcpy(&p_sel[3 * n], &p_c[3 * in[k]], 3 * sizeof(double));
        n++;
    }
    return n >= 4 && rs_calib_opencv_pnp(rt_cam_c, xy, p_sel, n, method, NULL) == RS_OK;
}

// The non-minimal solves on the observations `in`: SQPnP (the global minimum of the object-space
// error, any configuration) and, on landmarks judged planar, IPPE (exact for coplanar landmarks,
// biased by any relief). The one with the smallest RMS pixel error over `in` replaces rt_best
// if it fits better than *rms_best (in,out); returns its name, or NULL when neither did. xy
// (Nin,2), p_sel (Nin,3), tmp (Nin,): scratch.
static const char *nonminimal(double *rt_best, double *rms_best, bool planar, const double *v, const double *p_c,
                              const int *in, int Nin, const scorer *sc, double *xy, double *p_sel, double *tmp)
{
    const char *best_name = NULL;
    for (int m = 0; m < 2; m++) {
        double rt[6];
        if ((m == 0 && !planar) || (m == 1 && Nin < RS_INIT_SQPNP_MIN)) continue;
        if (!solve_opencv(rt, m == 0 ? RS_CALIB_OPENCV_IPPE : RS_CALIB_OPENCV_SQPNP, v, p_c, in, Nin, xy, p_sel))
            continue;
        const double rms = rms_px_at(rt, in, Nin, sc, tmp);
        if (rms < *rms_best) {
            *rms_best = rms;
            memcpy(rt_best, rt, 6 * sizeof(double));
            best_name = m == 0 ? "opencv-ippe" : "opencv-sqpnp";
        }
    }
    return best_name;
}

// Each landmark's survey sigma as pixels for the RANSAC test, ks (N,): opt->survey_sigmas times the
// larger focal length (px) times its largest survey sigma (opt->sigma_enu_m, (N,3), not NULL).
static void survey_widths_px(double *ks, const rs_calib_init_options *opt, const double *intrinsics, int N)
{
    const double f = intrinsics[0] > intrinsics[1] ? intrinsics[0] : intrinsics[1];
    for (int i = 0; i < N; i++) {
        const double *si = &opt->sigma_enu_m[3 * i];
        const double smax = fmax(si[0], fmax(si[1], si[2]));
        ks[i] = opt->survey_sigmas * fabs(f) * smax;
    }
}

// Whether the pose rt (6, centred frame) puts every usable landmark (usable, (Nusable,)) within
// threshold_px of its pick as sc scores it. tmp: scratch (Nusable,).
static bool all_agree(const double rt[6], const int *usable, int Nusable, const scorer *sc, double threshold_px,
                      double *tmp)
{
    double Rt[12];
    mrcal_Rt_from_rt(Rt, NULL, rt);
    pixel_errors(tmp, Rt, usable, Nusable, (void *)sc);
    int Nagree = 0;
    for (int k = 0; k < Nusable; k++) Nagree += tmp[k] < threshold_px;
    return Nagree == Nusable;
}

rs_status rs_calib_init_pose(rs_calib_init_result *result, bool *inlier, const mrcal_lensmodel_t *lensmodel,
                             const double *intrinsics, const double *p_enu_m, const double *q_px, int N,
                             const rs_calib_init_options *opt, rs_err *err)
{
    rs_calib_init_options defaults;
    if (!opt) {
        rs_calib_init_options_default(&defaults);
        opt = &defaults;
    }
    if (inlier)
        for (int i = 0; i < N; i++) inlier[i] = false;
    rs_status st = check_arguments(result, lensmodel, intrinsics, p_enu_m, q_px, N, opt, err);
    if (st) return st;
    memset(result, 0, sizeof(*result));

    // One block of scratch: v (N,3), p_c (N,3), xy (N,2), p_sel (N,3), tmp (N,), ks (N,),
    // usable (N,), in (N,), ransac_inlier (N,)
    const size_t Nz = (size_t)(N > 0 ? N : 1);
    double *v = malloc(Nz * (3 + 3 + 2 + 3 + 1 + 1) * sizeof(double) + Nz * (2 * sizeof(int) + sizeof(bool)));
    if (!v) return rs_err_set(err, RS_ERR_NOMEM, "rs_calib_init_pose: out of memory (N = %d)", N);
    double *p_c = v + 3 * Nz, *xy = p_c + 3 * Nz, *p_sel = xy + 2 * Nz, *tmp = p_sel + 3 * Nz;
    double *ks = tmp + Nz;
    int *usable = (int *)(ks + Nz), *in = usable + Nz;
    bool *is_in = (bool *)(in + Nz);

    // 1. bearings
    int Nusable = 0, Nunprojectable = 0;
    const bool opencv_model =
        MRCAL_LENSMODEL_IS_OPENCV(lensmodel->type) && N > 0 &&
        rs_calib_opencv_undistort(xy, q_px, N, intrinsics, mrcal_lensmodel_num_params(lensmodel) - 4, NULL) == RS_OK;
    for (int i = 0; i < N; i++) {
        const mrcal_point2_t q = {.xy = {q_px[2 * i], q_px[2 * i + 1]}};
        mrcal_point3_t vi;
        if (unproject(&vi, opencv_model ? &xy[2 * i] : NULL, &q, lensmodel, intrinsics)) {
            const double norm = sqrt(vi.x * vi.x + vi.y * vi.y + vi.z * vi.z);
            if (norm > 0.0 && isfinite(norm)) {
                for (int j = 0; j < 3; j++) v[3 * i + j] = vi.xyz[j] / norm;
                usable[Nusable++] = i;
                continue;
            }
        }
        v[3 * i] = v[3 * i + 1] = v[3 * i + 2] = NAN;
        Nunprojectable++;
    }
    if (Nusable < 4) {
        st = rs_err_set(err, RS_ERR_DEGENERATE, "q_px: only %d of %d observations are usable (need at least 4)%s",
                        Nusable, N, Nunprojectable ? "; some pixels do not unproject through the lens model" : "");
        goto done;
    }

    // 2. centre on the usable landmarks, check the geometry
    double centroid[3] = {0, 0, 0};
    for (int k = 0; k < Nusable; k++)
        for (int j = 0; j < 3; j++) centroid[j] += p_enu_m[3 * usable[k] + j] / Nusable;
    for (int i = 0; i < N; i++)
        for (int j = 0; j < 3; j++) p_c[3 * i + j] = p_enu_m[3 * i + j] - centroid[j];
    for (int k = 0; k < Nusable; k++) memcpy(&p_sel[3 * k], &p_c[3 * usable[k]], 3 * sizeof(double));
    double s[3];
    if ((st = rs_calib_opencv_singular_values3(s, p_sel, Nusable, err))) goto done;
    const int Nwith_repeats = Nusable;
    Nusable = drop_repeated(p_c, usable, Nusable, s);
    if (Nusable < 4) {
        st = rs_err_set(err, RS_ERR_DEGENERATE,
                        "p_enu_m: only %d distinct landmark positions among the %d usable observations (need at "
                        "least 4): landmarks are repeated",
                        Nusable, Nwith_repeats);
        goto done;
    }
    if ((st = check_geometry(v, usable, Nusable, s, err))) goto done;
    result->planar = s[2] < opt->planarity_ratio * s[1];

    // the pixel scores: sc plain, sc_ransac with each landmark's survey noise in the test
    const scorer sc = {lensmodel, intrinsics, p_c, q_px, NULL, opt->ransac_threshold_px};
    scorer sc_ransac = sc;
    const mrcal_lensmodel_metadata_t meta = mrcal_lensmodel_metadata(lensmodel);
    if (opt->sigma_enu_m && opt->survey_sigmas > 0.0 && meta.has_core) {
        survey_widths_px(ks, opt, intrinsics, N);
        sc_ransac.ks_px = ks;
    }
    // 3. every usable landmark at once (step 4's solvers): where that pose puts every one of them
    // within the threshold, it is the consensus RANSAC would find, and RANSAC does not run (a
    // survey without blunders: 8% of a 20-landmark calibration's time went to RANSAC there)
    double rt_best[6], rms_best = INFINITY;
    const char *best_name =
        nonminimal(rt_best, &rms_best, result->planar, v, p_c, usable, Nusable, &sc, xy, p_sel, tmp);
    if (best_name) {
        if (all_agree(rt_best, usable, Nusable, &sc_ransac, opt->ransac_threshold_px, tmp)) {
            for (int i = 0; i < N; i++) is_in[i] = false;
            for (int k = 0; k < Nusable; k++) is_in[usable[k]] = true;
            snprintf(result->method, sizeof(result->method), "%s on every landmark", best_name);
            uncentre(result->rt_cam_enu, rt_best, centroid);
            result->Ninliers = Nusable;
            result->rms_px = rms_best;
            if (inlier) memcpy(inlier, is_in, (size_t)N * sizeof(bool));
            st = RS_OK;
            goto done;
        }
    }

    // 4. RANSAC over P3P, scored in pixels
    double Rt_cam_c[12];
    int Niterations = 0, Nfallback = 0;
    st = rs_calib_opengv_ransac_p3p(Rt_cam_c, is_in, &Niterations, &Nfallback, v, p_c, N, usable, Nusable,
                                    RS_CALIB_OPENGV_P3P_KNEIP, opt->ransac_threshold_px, opt->ransac_max_iterations,
                                    RS_INIT_CONFIDENCE, opt->seed, pixel_errors, (void *)&sc_ransac, err);
    int Nin = 0;
    if (st == RS_OK)
        for (int i = 0; i < N; i++)
            if (is_in[i]) in[Nin++] = i;
    // A pose must be supported by a majority of the usable observations (and by 4 at least):
    // a small consensus among many is as likely a coincidence as the truth.
    const int Nneeded = Nusable / 2 + 1 > 4 ? Nusable / 2 + 1 : 4;
    if (st == RS_ERR_DEGENERATE || (st == RS_OK && Nin < Nneeded)) {
        st = rs_err_set(err, RS_ERR_DEGENERATE,
                        "q_px: no pose puts %d or more of the %d usable landmarks in front of the "
                        "camera within %g px of their pixels%s (best: %d, after %d %s): landmarks behind the "
                        "camera, or too many pixels not matching their landmarks",
                        Nneeded, Nusable, opt->ransac_threshold_px,
                        sc_ransac.ks_px ? " (widened by their survey sigmas)" : "", st == RS_OK ? Nin : 0, Niterations,
                        Nusable <= RS_CALIB_OPENGV_EXHAUSTIVE_MAX ? "triples of landmarks" : "RANSAC iterations");
        goto done;
    }
    if (st) goto done;
    mrcal_rt_from_Rt(rt_best, NULL, Rt_cam_c);
    rms_best = rms_px_at(rt_best, in, Nin, &sc, tmp);
    snprintf(result->method, sizeof(result->method), "opengv-p3p-%s-ransac", Nfallback ? "kneip+gao" : "kneip");

    // 5. the non-minimal solves on the inliers; whichever fits them best
    best_name = nonminimal(rt_best, &rms_best, result->planar, v, p_c, in, Nin, &sc, xy, p_sel, tmp);
    if (best_name) {
        const size_t len = strlen(result->method);
        snprintf(result->method + len, sizeof(result->method) - len, " + %s", best_name);
    }
    if (!isfinite(rms_best)) { // cannot happen: RANSAC inliers are in front by construction
        st = rs_err_set(err, RS_ERR_DEGENERATE, "q_px: the pose found puts some inliers behind the camera");
        goto done;
    }

    uncentre(result->rt_cam_enu, rt_best, centroid);
    result->Ninliers = Nin;
    result->rms_px = rms_best;
    if (inlier) memcpy(inlier, is_in, (size_t)N * sizeof(bool));
    st = RS_OK;

done:
    free(v);
    return st;
}
