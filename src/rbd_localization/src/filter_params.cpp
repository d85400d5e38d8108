#include "rbd_localization/filter_params.h"

#include <ros/node_handle.h>
#include <ros/param.h>

#include <cmath>
#include <map>
#include <regex>

#include "rbd_localization/param_reader.h"

namespace rbd_localization {

namespace {

using XmlRpc::XmlRpcValue;

bool validFrame(const std::string& f) { return !f.empty() && f[0] != '/'; }

bool readMatrix(ParamReader* r, const std::string& key, StateMatrix* out) {
  std::vector<double> values;
  bool present = false;
  if (!r->numberList(key, &values, &present)) return false;
  if (!present) return true;
  std::string why;
  if (!parseStateMatrix(values, out, &why)) return r->fail(key + ": " + why);
  for (int i = 0; i < STATE_SIZE; ++i) {
    if ((*out)(i, i) < 0.0) {
      return r->fail(key + ": the variance of " + stateMemberName(i) + " is negative (" +
                     formatNumber((*out)(i, i)) + ")");
    }
  }
  if (!out->isApprox(out->transpose(), 1e-12)) {
    r->warn(key + " is not symmetric; the filter uses (M + M^T) / 2");
    *out = (0.5 * (*out + out->transpose())).eval();
  }
  return true;
}

/// r_l options read so the configuration is accepted, but whose behaviour this node lacks.
bool readUnsupported(ParamReader* r) {
  bool flag = false;
  if (!r->boolean("use_control", &flag)) return false;
  for (const char* k : {"stamped_control", "control_timeout", "control_config", "acceleration_limits",
                        "acceleration_gains", "deceleration_limits", "deceleration_gains"}) {
    r->take(k);
  }
  if (flag) {
    r->warn(
        "use_control: true is not honoured: the prediction uses no cmd_vel term (control_config, "
        "acceleration_limits/gains, deceleration_limits/gains, stamped_control, control_timeout ignored)");
  }
  flag = false;
  if (!r->boolean("smooth_lagged_data", &flag)) return false;
  r->take("history_length");
  if (flag) {
    r->warn(
        "smooth_lagged_data: true is not honoured: a measurement older than the estimate is fused at the "
        "current state (no history replay), one older by more than 1 s is dropped; history_length ignored");
  }
  flag = false;
  if (!r->boolean("dynamic_process_noise_covariance", &flag)) return false;
  if (flag) r->warn("dynamic_process_noise_covariance: true is not honoured: the process noise is Q * dt");
  flag = true;
  if (!r->boolean("reset_on_time_jump", &flag)) return false;
  if (!flag) {
    r->warn(
        "reset_on_time_jump: false is not honoured: the filter always starts over when ROS time jumps "
        "back by more than 1 s (bag loops, simulator restarts)");
  }
  flag = false;
  if (!r->boolean("permit_corrected_publication", &flag)) return false;
  if (flag) {
    r->warn(
        "permit_corrected_publication: true (robot_localization for ROS 2) is not honoured: the transform "
        "is published only with a newer stamp");
  }
  if (r->has("tf_prefix")) {
    std::string prefix;
    if (!r->text("tf_prefix", &prefix)) return false;
    if (!prefix.empty())
      r->warn("tf_prefix '" + prefix + "' is not honoured (tf2 has no prefixes): write the full frame names");
  }
  std::string ukf;
  for (const char* k : {"alpha", "kappa", "beta"}) {
    if (r->take(k)) ukf += std::string(ukf.empty() ? "" : ", ") + k;
  }
  if (!ukf.empty()) r->warn(ukf + ": ukf_localization_node's parameters, ignored by this EKF");
  return true;
}

}  // namespace

StateMatrix defaultProcessNoise() {
  StateVector d;
  d << 0.05, 0.05, 0.06, 0.03, 0.03, 0.06, 0.025, 0.025, 0.04, 0.01, 0.01, 0.02, 0.01, 0.01, 0.015;
  return d.asDiagonal();
}

bool parseStateMatrix(const std::vector<double>& values, StateMatrix* out, std::string* error) {
  if (values.size() == static_cast<size_t>(STATE_SIZE * STATE_SIZE)) {
    for (int r = 0; r < STATE_SIZE; ++r) {
      for (int c = 0; c < STATE_SIZE; ++c) (*out)(r, c) = values[r * STATE_SIZE + c];
    }
  } else if (values.size() == static_cast<size_t>(STATE_SIZE)) {
    out->setZero();
    for (int i = 0; i < STATE_SIZE; ++i) (*out)(i, i) = values[i];
  } else {
    *error =
        "expected 225 numbers (15x15, row-major) or 15 (the diagonal), got " + std::to_string(values.size());
    return false;
  }
  if (!out->allFinite()) {
    *error = "matrix has non-finite entries";
    return false;
  }
  return true;
}

bool parseFilterParams(const XmlRpc::XmlRpcValue& ns, FilterParams* p, std::vector<std::string>* warnings,
                       std::string* error) {
  error->clear();
  *p = FilterParams();
  if (ns.getType() != XmlRpcValue::TypeStruct && ns.getType() != XmlRpcValue::TypeInvalid) {
    *error = "the private namespace is not a dictionary of parameters";
    return false;
  }
  ParamReader r(ns, warnings, error);

  if (!r.number("frequency", &p->frequency)) return false;
  if (!(p->frequency > 0.0) || p->frequency > 10000.0) return r.fail("frequency must be in (0, 10000] Hz");
  p->sensor_timeout = 1.0 / p->frequency;
  if (!r.number("sensor_timeout", &p->sensor_timeout)) return false;
  if (!(p->sensor_timeout >= 0.0)) return r.fail("sensor_timeout must be >= 0 s");
  if (!r.boolean("two_d_mode", &p->two_d_mode) || !r.boolean("publish_tf", &p->publish_tf) ||
      !r.boolean("publish_acceleration", &p->publish_acceleration) ||
      !r.boolean("print_diagnostics", &p->print_diagnostics) || !r.boolean("debug", &p->debug) ||
      !r.text("debug_out_file", &p->debug_out_file) ||
      !r.boolean("predict_to_current_time", &p->predict_to_current_time) ||
      !r.boolean("disabled_at_startup", &p->disabled_at_startup) ||
      !r.boolean("silent_tf_failure", &p->silent_tf_failure)) {
    return false;
  }
  if (!p->print_diagnostics) {
    r.warn(
        "print_diagnostics: false is not honoured: /diagnostics is always published (stale sensors stop "
        "the robot through it)");
  }
  if (!r.text("map_frame", &p->map_frame) || !r.text("odom_frame", &p->odom_frame) ||
      !r.text("base_link_frame", &p->base_link_frame)) {
    return false;
  }
  p->base_link_output_frame = p->base_link_frame;
  p->world_frame = p->odom_frame;
  if (!r.text("base_link_frame_output", &p->base_link_output_frame) ||
      !r.text("world_frame", &p->world_frame)) {
    return false;
  }
  for (const std::string* f :
       {&p->map_frame, &p->odom_frame, &p->base_link_frame, &p->base_link_output_frame, &p->world_frame}) {
    if (!validFrame(*f))
      return r.fail("frame names must be non-empty and without a leading '/': '" + *f + "'");
  }
  if (p->map_frame == p->odom_frame || p->odom_frame == p->base_link_frame ||
      p->map_frame == p->base_link_frame || p->odom_frame == p->base_link_output_frame ||
      p->map_frame == p->base_link_output_frame) {
    return r.fail("map_frame, odom_frame and base_link_frame (and base_link_frame_output) must differ");
  }
  if (p->world_frame != p->map_frame && p->world_frame != p->odom_frame) {
    return r.fail("world_frame must be map_frame or odom_frame");
  }
  if (!r.number("transform_time_offset", &p->transform_time_offset) ||
      !r.number("transform_timeout", &p->transform_timeout) ||
      !r.number("gravitational_acceleration", &p->gravitational_acceleration) ||
      !r.number("sensor_stale_timeout", &p->sensor_stale_timeout)) {
    return false;
  }
  double diagnostic_period = 1.0;  // read by diagnostic_updater itself from the same namespace
  if (!r.number("diagnostic_period", &diagnostic_period)) return false;
  if (!std::isfinite(p->transform_time_offset)) return r.fail("transform_time_offset must be finite");
  if (!(p->transform_timeout >= 0.0) || !std::isfinite(p->transform_timeout)) {
    return r.fail("transform_timeout must be >= 0 s");
  }
  if (!std::isfinite(p->gravitational_acceleration))
    return r.fail("gravitational_acceleration must be finite");
  if (!(p->sensor_stale_timeout > 0.0)) return r.fail("sensor_stale_timeout must be > 0 s");

  p->process_noise_covariance = defaultProcessNoise();
  p->initial_estimate_covariance = StateMatrix::Identity() * 1e-9;
  if (!readMatrix(&r, "process_noise_covariance", &p->process_noise_covariance) ||
      !readMatrix(&r, "initial_estimate_covariance", &p->initial_estimate_covariance)) {
    return false;
  }
  std::vector<double> state;
  bool present = false;
  if (!r.numberList("initial_state", &state, &present)) return false;
  if (present) {
    if (state.size() != static_cast<size_t>(STATE_SIZE)) {
      return r.fail(
          "initial_state needs 15 numbers (x y z roll pitch yaw vx vy vz vroll vpitch vyaw ax ay az), got " +
          std::to_string(state.size()));
    }
    for (int i = 0; i < STATE_SIZE; ++i) p->initial_state(i) = state[static_cast<size_t>(i)];
    if (!p->initial_state.allFinite()) return r.fail("initial_state has non-finite entries");
  }
  if (!readUnsupported(&r)) return false;

  const std::pair<const char*, SensorType> kinds[] = {{"odom", SensorType::kOdom},
                                                      {"pose", SensorType::kPose},
                                                      {"twist", SensorType::kTwist},
                                                      {"imu", SensorType::kImu}};
  p->sensors.clear();
  std::map<std::string, int> count;
  for (const auto& kind : kinds) {
    int n = 0;
    for (;; ++n) {
      const std::string name = std::string(kind.first) + std::to_string(n);
      if (!r.has(name)) break;
      SensorConfig s;
      bool used = false;
      if (!readSensorParams(&r, kind.second, name, &s, &used)) return false;
      if (used) p->sensors.push_back(s);
    }
    count[kind.first] = n;
  }

  std::vector<std::string> unknown = r.unread();
  if (!unknown.empty()) {
    std::string list;
    bool gap = false;
    const std::regex sensor_key("^(odom|pose|twist|imu)([0-9]+)(_.*)?$");
    for (const std::string& k : unknown) {
      list += (list.empty() ? "" : ", ") + k;
      std::smatch m;
      if (std::regex_match(k, m, sensor_key) && std::stoi(m[2].str()) >= count[m[1].str()]) gap = true;
    }
    std::string hint;
    if (gap) {
      hint =
          " (inputs are numbered from 0 without gaps, as in robot_localization: e.g. imu1 is read only if "
          "imu0 "
          "is set)";
    }
    warnings->push_back("unknown parameters, ignored: " + list + hint);
  }
  if (p->sensors.empty())
    return r.fail("no sensors configured (set imu0, pose0, odom0 or twist0 and its _config)");
  return true;
}

bool loadFilterParams(const ros::NodeHandle& pnh, FilterParams* params, std::vector<std::string>* warnings,
                      std::string* error) {
  XmlRpc::XmlRpcValue ns;
  if (!ros::param::get(pnh.getNamespace(), ns)) ns = XmlRpc::XmlRpcValue();
  return parseFilterParams(ns, params, warnings, error);
}

}  // namespace rbd_localization
