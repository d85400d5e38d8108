// Parameters of ekf_localization_node, read with robot_localization's names, meanings and value
// forms, so an existing r_l YAML works unchanged. The parser works on the XmlRpc values the
// parameter server delivers (no master needed: the tests feed it directly); loadFilterParams()
// fetches the node's private namespace and hands it over.
#ifndef RBD_LOCALIZATION_FILTER_PARAMS_H
#define RBD_LOCALIZATION_FILTER_PARAMS_H

#include <XmlRpcValue.h>

#include <array>
#include <string>
#include <vector>

#include "rbd_localization/filter_common.h"

// Declared only: ros/node_handle.h pulls in most of roscpp, and this header is included by the
// measurement conversions and the parser's tests, which never need it (build time, issue 19).
namespace ros {
class NodeHandle;
}  // namespace ros

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

/// Everything the node reads at startup.
struct FilterParams {
  double frequency = 30.0;
  double sensor_timeout = 1.0 / 30.0;
  bool two_d_mode = false;
  bool publish_tf = true;
  bool publish_acceleration = false;
  bool print_diagnostics = true;
  bool debug = false;
  /// r_l's debug_out_file; empty: the filter trace goes to the ROS log at DEBUG level.
  std::string debug_out_file;
  std::string map_frame = "map";
  std::string odom_frame = "odom";
  std::string base_link_frame = "base_link";
  /// r_l's base_link_frame_output: child frame of the output (defaults to base_link_frame).
  std::string base_link_output_frame = "base_link";
  std::string world_frame = "odom";
  double transform_time_offset = 0.0;
  double transform_timeout = 0.0;
  double gravitational_acceleration = 9.80665;
  /// Predict the estimate to the current time every cycle, not only after sensor_timeout.
  bool predict_to_current_time = false;
  /// Do nothing until the ~enable service is called.
  bool disabled_at_startup = false;
  /// No warnings when a transform is missing (the measurement is still dropped and counted).
  bool silent_tf_failure = false;
  /// RoboDog extension: a sensor silent this long is reported stale; when all are stale the
  /// node stops publishing its estimate (downstream pose consumers then stop the robot).
  double sensor_stale_timeout = 1.0;
  StateMatrix process_noise_covariance;
  StateMatrix initial_estimate_covariance;
  /// Values of the members no first measurement sets (r_l's initial_state; zero if unset).
  StateVector initial_state = StateVector::Zero();
  std::vector<SensorConfig> sensors;
};

/// robot_localization's default process noise (diagonal).
StateMatrix defaultProcessNoise();

/// Reads every parameter from the values of the node's private namespace (an XmlRpc struct as
/// the parameter server returns it: rosparam's YAML 1.1 typing makes `1e-9` a string, `0` an
/// int, `0.05` a double). Returns false with a clear message on any value the node cannot use.
/// Appends to warnings: every accepted r_l option this node does not honour (one line each,
/// naming it and why), and one line listing all unknown keys.
bool parseFilterParams(const XmlRpc::XmlRpcValue& private_namespace, FilterParams* params,
                       std::vector<std::string>* warnings, std::string* error);

/// Fetches the private namespace of pnh from the parameter server and parses it.
bool loadFilterParams(const ros::NodeHandle& pnh, FilterParams* params, std::vector<std::string>* warnings,
                      std::string* error);

/// Parses a 15x15 matrix from a flat list of 225 numbers (row-major) or 15 (the diagonal).
bool parseStateMatrix(const std::vector<double>& values, StateMatrix* out, std::string* error);

/// The parameters as the filter uses them, as JSON (r_l's key names; matrices as 225 numbers
/// row-major; also valid YAML), with the start-up warnings. q and p0 are the matrices the filter
/// holds.
std::string effectiveConfigJson(const FilterParams& params, const StateMatrix& q, const StateMatrix& p0,
                                const std::vector<std::string>& warnings);

}  // namespace rbd_localization

#endif  // RBD_LOCALIZATION_FILTER_PARAMS_H
