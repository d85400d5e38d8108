// Parameters of ekf_localization_node, read with robot_localization's names and meanings
// so an existing r_l YAML works. ROS-side helper (reads the parameter server).
#ifndef RBD_LOCALIZATION_FILTER_PARAMS_H
#define RBD_LOCALIZATION_FILTER_PARAMS_H

#include <ros/node_handle.h>

#include <array>
#include <string>
#include <vector>

#include "rbd_localization/filter_common.h"

namespace rbd_localization {

enum class SensorType { kImu, kPose, kOdom, kTwist };

/// One configured input (imuN, poseN, odomN or twistN).
struct SensorConfig {
  SensorType type = SensorType::kPose;
  std::string name;   ///< e.g. "imu0" (parameter prefix)
  std::string topic;  ///< value of the imuN/poseN/... parameter
  std::array<bool, STATE_SIZE> update_vector{};
  bool differential = false;
  bool relative = false;
  bool nodelay = false;
  int queue_size = 1;
  /// Gates in standard deviations (r_l default: max double, i.e. never reject).
  double pose_rejection_threshold = 0.0;
  double twist_rejection_threshold = 0.0;
  double linear_acceleration_rejection_threshold = 0.0;
  bool remove_gravitational_acceleration = false;
  /// RoboDog extension (`<name>_frame_is_world`): treat the message frame as world_frame
  /// instead of transforming through TF (for a camera whose own "map" drifts like odometry).
  bool frame_is_world = false;
  /// RoboDog extension (`<name>_differential_noise`, 6 standard deviations x y z roll pitch yaw):
  /// with `_differential`, the velocity covariance is built from the sensor's per-sample white
  /// noise plus the growth of its reported covariance between the two poses, instead of r_l's
  /// sum of both covariances (which, for a tracker reporting its accumulated drift, makes the
  /// velocities uselessly uncertain and lets jumps through the gate).
  bool has_differential_noise = false;
  std::array<double, 6> differential_noise{};
};

/// Everything the node reads at startup.
struct FilterParams {
  double frequency = 30.0;
  double sensor_timeout = 1.0 / 30.0;
  bool two_d_mode = false;
  bool publish_tf = true;
  bool print_diagnostics = true;
  bool debug = false;
  std::string map_frame = "map";
  std::string odom_frame = "odom";
  std::string base_link_frame = "base_link";
  std::string world_frame = "odom";
  double transform_time_offset = 0.0;
  double transform_timeout = 0.0;
  double gravitational_acceleration = 9.80665;
  /// RoboDog extension: a sensor silent this long is reported stale; when all are stale the
  /// node stops publishing its estimate (downstream pose consumers then stop the robot).
  double sensor_stale_timeout = 1.0;
  StateMatrix process_noise_covariance;
  StateMatrix initial_estimate_covariance;
  std::vector<SensorConfig> sensors;
};

/// robot_localization's default process noise (diagonal).
StateMatrix defaultProcessNoise();

/// Reads all parameters from the private node handle. Returns false and fills error on any
/// malformed value (wrong list length, non-numeric entry, bad frame names, no sensors).
bool loadFilterParams(const ros::NodeHandle& pnh, FilterParams* params, std::string* error);

/// Parses a 15x15 matrix from a flat list of 225 numbers (or 15, taken as the diagonal).
bool parseStateMatrix(const std::vector<double>& values, StateMatrix* out, std::string* error);

}  // namespace rbd_localization

#endif  // RBD_LOCALIZATION_FILTER_PARAMS_H
