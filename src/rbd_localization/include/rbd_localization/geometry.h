// Small ROS-free rotation helpers shared by the filter wrapper, the map correction and tests.
#ifndef RBD_LOCALIZATION_GEOMETRY_H
#define RBD_LOCALIZATION_GEOMETRY_H

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace rbd_localization {

/// R = Rz(yaw) Ry(pitch) Rx(roll), the convention of the state vector.
inline Eigen::Matrix3d rotationFromRpy(double roll, double pitch, double yaw) {
  return (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

/// Inverse of rotationFromRpy: (roll, pitch, yaw), pitch in [-pi/2, pi/2].
inline Eigen::Vector3d rpyFromRotation(const Eigen::Matrix3d& r) {
  const double pitch = std::asin(std::max(-1.0, std::min(1.0, -r(2, 0))));
  const double roll = std::atan2(r(2, 1), r(2, 2));
  const double yaw = std::atan2(r(1, 0), r(0, 0));
  return Eigen::Vector3d(roll, pitch, yaw);
}

/// Planar pose (x, y, yaw) as a 3x3 homogeneous transform.
inline Eigen::Isometry2d pose2d(double x, double y, double yaw) {
  Eigen::Isometry2d t = Eigen::Isometry2d::Identity();
  t.linear() = Eigen::Rotation2Dd(yaw).toRotationMatrix();
  t.translation() = Eigen::Vector2d(x, y);
  return t;
}

/// Heading of a planar transform [rad].
inline double yawOf(const Eigen::Isometry2d& t) { return std::atan2(t.linear()(1, 0), t.linear()(0, 0)); }

}  // namespace rbd_localization

#endif  // RBD_LOCALIZATION_GEOMETRY_H
