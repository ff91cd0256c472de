// rs_pose.h -- roadside's one pose toolkit: 3x3 rotations, yaw/pitch/roll, camera position,
// and a Rodrigues vector that is right at a half-turn. mrcal's poseutils does the rest
// (mrcal_R_from_r, mrcal_transform_point_rt, mrcal_invert_rt, mrcal_compose_rt): call it
// directly; what is here is what mrcal lacks or gets wrong.
//
// Conventions (docs/conventions.md): matrices are row-major 3x3; rt_cam_enu = mrcal Rodrigues r
// + translation t (metres), p_cam = R(r) p_enu + t; camera x right, y down, z forward.
// yaw/pitch/roll in degrees: R_enu_cam = Rz(-yaw) Rx(pitch) R_enu_cam0 Rz(roll), with
// R_enu_cam0 a level camera looking north; yaw in [0, 360) clockwise from north, pitch in
// [-90, 90] positive up, roll in (-180, 180] positive clockwise seen from behind the camera.
// At pitch = +-90 (looking straight up or down) yaw is undefined: yaw is then 0 and the whole
// turn goes into roll.
//
// Accuracy: yaw/pitch/roll -> R -> yaw/pitch/roll within 1e-12 deg away from |pitch| = 90
// (tests/core/test_pose.c); rs_pose_r_from_R within 1e-12 in the matrix for every rotation,
// half-turns included (tests/core/test_r_from_R_halfturn.c).
#pragma once

#ifdef __cplusplus
extern "C" {
#endif

// out = a b (3x3). out may alias a or b.
void rs_pose_mat3_mul(double out[9], const double a[9], const double b[9]);
// out = a^T (3x3). out may alias a.
void rs_pose_mat3_transpose(double out[9], const double a[9]);
// Rotations about x and z by `angle_rad` (right-handed): Rx = [1 0 0; 0 c -s; 0 s c],
// Rz = [c -s 0; s c 0; 0 0 1].
void rs_pose_Rx(double R[9], double angle_rad);
void rs_pose_Rz(double R[9], double angle_rad);

// R_cam_enu (maps ENU vectors into the camera frame) from yaw, pitch, roll in degrees.
void rs_pose_R_from_ypr( // out
    double R_cam_enu[9],
    // in
    const double yaw_pitch_roll_deg[3]);

// yaw, pitch, roll in degrees (ranges above) of a rotation R_cam_enu.
void rs_pose_ypr_from_R( // out
    double yaw_pitch_roll_deg[3],
    // in
    const double R_cam_enu[9]);

// Camera position and yaw/pitch/roll of a pose.
void rs_pose_ypr_from_rt( // out
    double yaw_pitch_roll_deg[3],
    double position_enu_m[3], // may be NULL
    // in
    const double rt_cam_enu[6]);

// The pose of a camera at position_enu_m with the given yaw/pitch/roll (degrees).
void rs_pose_rt_from_ypr( // out
    double rt_cam_enu[6],
    // in
    const double yaw_pitch_roll_deg[3], const double position_enu_m[3]);

// Camera centre in ENU: -R(r)^T t.
void rs_pose_position_from_rt( // out
    double position_enu_m[3],
    double *dpos_drt, // (3,6) row-major, may be NULL
    // in
    const double rt_cam_enu[6]);

// A pose rt prepared for transforming many points: its rotation and the rotation's gradient,
// computed once (mrcal_R_from_r) instead of per point as mrcal_transform_point_rt does (with
// gradients that was 2,600 instructions a point, a tenth of a calibration).
typedef struct {
    double R[9];      // row-major
    double dR_dr[27]; // d R[i][j] / d r[k] at [9 i + 3 j + k]
    double t[3];
} rs_pose_prepared;
void rs_pose_prepare(rs_pose_prepared *pose, const double rt[6]);
// p_cam = R p + t, as mrcal_transform_point_rt(p_cam, dpcam_drt, dpcam_dp, rt, p), to rounding.
// dpcam_drt (3,6) and dpcam_dp (3,3) row-major, each may be NULL.
void rs_pose_prepared_apply(double p_cam[3], double *dpcam_drt, double *dpcam_dp, const rs_pose_prepared *pose,
                            const double p[3]);

// Rodrigues vector of a rotation matrix, correct for every rotation. mrcal 2.2's r_from_R
// returns r = 0 for a half-turn (e.g. diag(1,-1,-1): a camera looking straight down) and is
// wrong by pi within ~1e-6 rad of it (OpenCV's cv::Rodrigues snaps such rotations to exactly
// pi: 1e-6 off). So mrcal's answer is checked by turning it back into a matrix (max element
// difference 1e-12), and where it fails Eigen's AngleAxisd (through a quaternion) gives r
// (core/rs_pose_eigen.cc).
// in: R (3,3) row-major rotation; out: r (3,) radians.
void rs_pose_r_from_R(double r[3], const double R[9]);

// The rotation between two orientations: R_ab = R(r_a) R(r_b)^T, the turn that takes b's
// orientation to a's (for two poses of one camera, rt_cam_enu's r of each: how far the camera
// turned). Returns its angle in radians, in [0, pi]: |r_ab|, equal to
// acos((trace(R_ab) - 1) / 2) but computed by mrcal_compose_r(r_a, -r_b), which stays accurate
// for tiny angles (where acos loses half the digits) and up to a half-turn.
// Accuracy: within 2e-12 rad of the constructed angle over [0, pi] (tests/core/test_pose.c;
// within 1e-7 rad of acos((trace - 1) / 2), which itself is that coarse near 0 and pi).
// (mrcal_compose_r itself may return a vector of norm up to 2 pi, the same rotation as the one of
// norm 2 pi - |r| about the opposite axis: r_ab is always that shorter one, |r_ab| <= pi.)
// out: r_ab (3,) Rodrigues vector of R_ab, |r_ab| <= pi, may be NULL; dr_ab_dr_a (3,3) row-major,
//      d r_ab / d r_a, may be NULL
// in:  r_a, r_b (3,) Rodrigues vectors, radians
double rs_pose_rotation_between( // out
    double r_ab[3], double dr_ab_dr_a[9],
    // in
    const double r_a[3], const double r_b[3]);

#ifdef __cplusplus
}
#endif
