// rs_pose_eigen.h -- the Eigen shim of core (core/rs_pose_eigen.cc). Internal to core.
#pragma once

#ifdef __cplusplus
extern "C" {
#endif

// Rodrigues vector of the rotation R (3,3 row-major) by Eigen's AngleAxisd, which goes through
// a quaternion (Shepperd's method) and is accurate at and near a half-turn.
void rs_pose_eigen_r_from_R(double r[3], const double R[9]);

#ifdef __cplusplus
}
#endif
