// Message -> Measurement conversions for ekf_localization_node (ROS-side helper).
// Frames are resolved by the caller (TF) and passed in as Eigen transforms.
#ifndef RBD_LOCALIZATION_MEASUREMENT_CONVERSIONS_H
#define RBD_LOCALIZATION_MEASUREMENT_CONVERSIONS_H

#include <geometry_msgs/PoseWithCovariance.h>
#include <geometry_msgs/TwistWithCovariance.h>
#include <sensor_msgs/Imu.h>

#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "rbd_localization/ekf.h"
#include "rbd_localization/filter_params.h"

namespace rbd_localization {

using Matrix6d = Eigen::Matrix<double, 6, 6>;

/// A pose with its 6x6 covariance (x y z, rotation about x y z), as in geometry_msgs.
struct PoseWithCov {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  Matrix6d covariance = Matrix6d::Identity();
};

/// Reads a message pose; false if it has NaN/inf values or a zero quaternion.
bool fromMsg(const geometry_msgs::PoseWithCovariance& msg, PoseWithCov* out);

/// Rotates a 6x6 covariance by R (both 3x3 blocks).
Matrix6d rotateCovariance(const Matrix6d& c, const Eigen::Matrix3d& r);

/// Pose of base_link in the world frame -> measurement on the configured x..yaw members.
Measurement poseMeasurement(const PoseWithCov& world_pose, const SensorConfig& cfg, double time);

/// Differential mode: the motion between two consecutive poses, divided by dt, becomes a
/// body-frame velocity measurement on the members that correspond to the configured x..yaw.
/// Returns false if dt <= 0 or nothing is configured.
bool differentialMeasurement(const PoseWithCov& previous, const PoseWithCov& current, double dt,
                             const SensorConfig& cfg, double time, Measurement* out);

/// Twist in a body-fixed frame (rotated into base_link by base_from_frame) -> vx..vyaw.
bool twistMeasurement(const geometry_msgs::TwistWithCovariance& msg, const Eigen::Matrix3d& base_from_frame,
                      const SensorConfig& cfg, double time, Measurement* out);

/// The IMU's orientation as the orientation of base_link in the IMU's world frame (position
/// zero, position covariance identity), for relative/differential handling as a pose. False if
/// the message carries no usable orientation (orientation_covariance[0] = -1, NaN/inf values or
/// covariance, zero quaternion).
bool imuOrientationPose(const sensor_msgs::Imu& msg, const Eigen::Matrix3d& base_from_imu, PoseWithCov* out);

/// IMU -> up to three measurements (orientation, angular velocity, linear acceleration),
/// each with its own gate, as r_l does. A part is skipped when its covariance[0] is -1
/// (e.g. /ouster/imu orientation) or nothing in it is configured. Gravity is removed using the
/// message orientation when valid, else the filter's current roll/pitch (state).
/// The measurements are appended to out. Returns false (with reason, nothing appended) if the
/// message has NaN/inf in a used part.
bool imuMeasurements(const sensor_msgs::Imu& msg, const Eigen::Matrix3d& base_from_imu,
                     const SensorConfig& cfg, const StateVector& state, double gravity, double time,
                     std::vector<Measurement>* out, std::string* reason);

}  // namespace rbd_localization

#endif  // RBD_LOCALIZATION_MEASUREMENT_CONVERSIONS_H
