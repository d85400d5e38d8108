// One input of ekf_localization_node (imuN, poseN, odomN or twistN) with robot_localization's
// parameter names, meanings and defaults, and the reader of its `<name>_*` parameters.
#ifndef RBD_LOCALIZATION_SENSOR_PARAMS_H
#define RBD_LOCALIZATION_SENSOR_PARAMS_H

#include <array>
#include <string>

#include "rbd_localization/filter_common.h"
#include "rbd_localization/param_reader.h"

namespace rbd_localization {

enum class SensorType { kImu, kPose, kOdom, kTwist };

/// "imu", "pose", "odom" or "twist".
const char* sensorTypeName(SensorType t);

/// One configured input (imuN, poseN, odomN or twistN).
struct SensorConfig {
  SensorType type = SensorType::kPose;
  std::string name;   ///< e.g. "imu0" (parameter prefix)
  std::string topic;  ///< value of the imuN/poseN/... parameter
  /// The 15 booleans of `<name>_config`, with the members this message type cannot carry cleared.
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

/// Reads input `name` (e.g. "imu0") of this type: the topic, `<name>_config` and the type's
/// options and rejection thresholds. *used is false when no update variable is enabled (r_l then
/// does not subscribe; a warning says so). Returns false with the reader's error on bad values.
bool readSensorParams(ParamReader* r, SensorType type, const std::string& name, SensorConfig* s, bool* used);

}  // namespace rbd_localization

#endif  // RBD_LOCALIZATION_SENSOR_PARAMS_H
