// Pose of the lidar relative to the floor (ROS-free, Eigen only): the rotation into the
// gravity-aligned "level" frame whose x axis is the robot's heading, and the height.
#ifndef RBD_LIDAR_SENSOR_POSE_H
#define RBD_LIDAR_SENSOR_POSE_H

#include <Eigen/Core>

namespace rbd_lidar {

struct SensorPose {
  Eigen::Matrix3d level_from_sensor = Eigen::Matrix3d::Identity();  // rotation sensor -> level frame
  double height = 0.38;                                             // sensor origin above the floor [m]

  // Body roll/pitch [rad] (base_link w.r.t. gravity), the mount base_link -> sensor and the height
  // of base_link above the floor [m].
  static SensorPose fromBody(double roll, double pitch, const Eigen::Matrix3d& mount_rotation,
                             const Eigen::Vector3d& mount_translation, double base_height);
  // Sensor tilt from the specific force measured by an IMU fixed to the sensor (axes parallel to
  // the sensor frame, as the Ouster's internal IMU): the rotation taking `accel` to +z, followed
  // by `heading_yaw` (yaw of the sensor x axis relative to the robot's heading, e.g. the mount yaw).
  // Returns false (and leaves *rotation) for a non-finite or near-zero vector.
  static bool levelFromGravity(const Eigen::Vector3d& accel, double heading_yaw, Eigen::Matrix3d* rotation);
};

}  // namespace rbd_lidar

#endif  // RBD_LIDAR_SENSOR_POSE_H
