#include "rbd_localization/effective_config.h"

#include <nlohmann/json.hpp>

namespace rbd_localization {

namespace {

using nlohmann::json;

json matrixJson(const StateMatrix& m) {
  json out = json::array();
  for (int r = 0; r < STATE_SIZE; ++r) {
    for (int c = 0; c < STATE_SIZE; ++c) out.push_back(m(r, c));
  }
  return out;
}

json sensorJson(const SensorConfig& s) {
  json out;
  out["name"] = s.name;
  out["type"] = sensorTypeName(s.type);
  out["topic"] = s.topic;
  out["config"] = json::array();
  for (int i = 0; i < STATE_SIZE; ++i) out["config"].push_back(static_cast<bool>(s.update_vector[i]));
  out["differential"] = s.differential;
  out["relative"] = s.relative;
  out["queue_size"] = s.queue_size;
  out["nodelay"] = s.nodelay;
  out["pose_rejection_threshold"] = s.pose_rejection_threshold;
  out["twist_rejection_threshold"] = s.twist_rejection_threshold;
  out["linear_acceleration_rejection_threshold"] = s.linear_acceleration_rejection_threshold;
  out["remove_gravitational_acceleration"] = s.remove_gravitational_acceleration;
  out["frame_is_world"] = s.frame_is_world;
  if (s.has_differential_noise) {
    out["differential_noise"] = json::array();
    for (double v : s.differential_noise) out["differential_noise"].push_back(v);
  } else {
    out["differential_noise"] = nullptr;
  }
  return out;
}

}  // namespace

std::string effectiveConfigJson(const FilterParams& p, const StateMatrix& q, const StateMatrix& p0,
                                const std::vector<std::string>& warnings) {
  json out;
  out["frequency"] = p.frequency;
  out["sensor_timeout"] = p.sensor_timeout;
  out["two_d_mode"] = p.two_d_mode;
  out["publish_tf"] = p.publish_tf;
  out["publish_acceleration"] = p.publish_acceleration;
  out["debug"] = p.debug;
  out["debug_out_file"] = p.debug_out_file;
  out["map_frame"] = p.map_frame;
  out["odom_frame"] = p.odom_frame;
  out["base_link_frame"] = p.base_link_frame;
  out["base_link_frame_output"] = p.base_link_output_frame;
  out["world_frame"] = p.world_frame;
  out["transform_time_offset"] = p.transform_time_offset;
  out["transform_timeout"] = p.transform_timeout;
  out["gravitational_acceleration"] = p.gravitational_acceleration;
  out["predict_to_current_time"] = p.predict_to_current_time;
  out["disabled_at_startup"] = p.disabled_at_startup;
  out["silent_tf_failure"] = p.silent_tf_failure;
  out["sensor_stale_timeout"] = p.sensor_stale_timeout;
  out["process_noise_covariance"] = matrixJson(q);
  out["initial_estimate_covariance"] = matrixJson(p0);
  out["initial_state"] = json::array();
  for (int i = 0; i < STATE_SIZE; ++i) out["initial_state"].push_back(p.initial_state(i));
  out["sensors"] = json::array();
  for (const SensorConfig& s : p.sensors) out["sensors"].push_back(sensorJson(s));
  out["warnings"] = warnings;
  // A parameter name or value that is not UTF-8 (XmlRpc strings are bytes) must not throw.
#if defined(NLOHMANN_JSON_VERSION_MAJOR) && \
    (NLOHMANN_JSON_VERSION_MAJOR > 3 ||     \
     (NLOHMANN_JSON_VERSION_MAJOR == 3 && NLOHMANN_JSON_VERSION_MINOR >= 4))
  return out.dump(-1, ' ', false, json::error_handler_t::replace) + "\n";
#else
  try {
    return out.dump() + "\n";
  } catch (const json::exception& e) {
    return json{{"error", std::string("effective configuration not representable as JSON: ") + e.what()}}
               .dump() +
           "\n";
  }
#endif
}

}  // namespace rbd_localization
