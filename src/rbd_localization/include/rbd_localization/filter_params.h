// Parameters of ekf_localization_node, read with robot_localization's names, meanings and value
// forms, so an existing r_l YAML works unchanged. The parser works on the XmlRpc values the
// parameter server delivers (no master needed: the tests feed it directly); loadFilterParams()
// fetches the node's private namespace and hands it over.
#ifndef RBD_LOCALIZATION_FILTER_PARAMS_H
#define RBD_LOCALIZATION_FILTER_PARAMS_H

#include <XmlRpcValue.h>

#include <string>
#include <vector>

#include "rbd_localization/filter_common.h"
#include "rbd_localization/sensor_params.h"

// Declared only: ros/node_handle.h pulls in most of roscpp, and this header is included by the
// measurement conversions and the parser's tests, which never need it (build time, issue 19).
namespace ros {
class NodeHandle;
}  // namespace ros

namespace rbd_localization {

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

}  // namespace rbd_localization

#endif  // RBD_LOCALIZATION_FILTER_PARAMS_H
