// rs_pose_eigen.cc -- the Eigen shim of core: a half-turn-safe Rodrigues vector. Eigen does not
// throw; the boundary still catches everything, so that no exception crosses into C.
#include <Eigen/Geometry>

extern "C" {
#include "core/internal/rs_pose_eigen.h"
}

extern "C" void rs_pose_eigen_r_from_R(double r[3], const double R[9])
{
    try {
        const Eigen::Matrix3d M = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(R);
        const Eigen::AngleAxisd aa(M);
        const Eigen::Vector3d v = aa.axis() * aa.angle();
        for (int i = 0; i < 3; i++) r[i] = v(i);
    } catch (...) {
        for (int i = 0; i < 3; i++) r[i] = __builtin_nan("");
    }
}
