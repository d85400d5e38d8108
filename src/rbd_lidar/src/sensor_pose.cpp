#include "rbd_lidar/sensor_pose.h"

#include <Eigen/Geometry>
#include <cmath>

namespace rbd_lidar {

SensorPose SensorPose::fromBody(double roll, double pitch, const Eigen::Matrix3d& mount_rotation,
                                const Eigen::Vector3d& mount_translation, double base_height) {
  const Eigen::Matrix3d body =
      (Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) * Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
          .toRotationMatrix();
  SensorPose pose;
  pose.level_from_sensor = body * mount_rotation;
  pose.height = base_height + (body * mount_translation).z();
  return pose;
}

bool SensorPose::levelFromGravity(const Eigen::Vector3d& accel, double heading_yaw,
                                  Eigen::Matrix3d* rotation) {
  if (!accel.allFinite() || accel.norm() < 1.0) return false;
  const Eigen::Matrix3d tilt =
      Eigen::Quaterniond::FromTwoVectors(accel.normalized(), Eigen::Vector3d::UnitZ()).toRotationMatrix();
  // FromTwoVectors adds no rotation about z beyond the tilt; keep the sensor's own x as heading.
  const Eigen::Vector3d x = tilt * Eigen::Vector3d::UnitX();
  const double yaw = std::atan2(x.y(), x.x());
  *rotation = Eigen::AngleAxisd(heading_yaw - yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix() * tilt;
  return true;
}

}  // namespace rbd_lidar
