#include "rbd_localization/filter_params.h"

#include <XmlRpcValue.h>

#include <cmath>
#include <limits>
#include <sstream>

namespace rbd_localization {

namespace {

bool readDoubleList(const ros::NodeHandle& pnh, const std::string& key, std::vector<double>* out,
                    std::string* error) {
  XmlRpc::XmlRpcValue v;
  if (!pnh.getParam(key, v)) return false;
  if (v.getType() != XmlRpc::XmlRpcValue::TypeArray) {
    *error = key + " must be a list of numbers";
    return false;
  }
  out->clear();
  for (int i = 0; i < v.size(); ++i) {
    if (v[i].getType() == XmlRpc::XmlRpcValue::TypeDouble) {
      out->push_back(static_cast<double>(v[i]));
    } else if (v[i].getType() == XmlRpc::XmlRpcValue::TypeInt) {
      out->push_back(static_cast<int>(v[i]));
    } else {
      *error = key + "[" + std::to_string(i) + "] is not a number";
      return false;
    }
  }
  return true;
}

bool readConfig(const ros::NodeHandle& pnh, const std::string& key, std::array<bool, STATE_SIZE>* out,
                std::string* error) {
  XmlRpc::XmlRpcValue v;
  if (!pnh.getParam(key, v)) {
    *error = key + " is missing (15 booleans: x y z roll pitch yaw vx vy vz vroll vpitch vyaw ax ay az)";
    return false;
  }
  if (v.getType() != XmlRpc::XmlRpcValue::TypeArray || v.size() != STATE_SIZE) {
    *error = key + " must be a list of 15 booleans";
    return false;
  }
  for (int i = 0; i < STATE_SIZE; ++i) {
    if (v[i].getType() != XmlRpc::XmlRpcValue::TypeBoolean) {
      *error = key + "[" + std::to_string(i) + "] is not a boolean";
      return false;
    }
    (*out)[i] = static_cast<bool>(v[i]);
  }
  return true;
}

double threshold(const ros::NodeHandle& pnh, const std::string& key) {
  double t = std::numeric_limits<double>::max();
  pnh.param(key, t, t);
  return t;
}

bool validFrame(const std::string& f) { return !f.empty() && f[0] != '/'; }

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
    *error = "expected 225 numbers (15x15, row-major) or 15 (diagonal), got " + std::to_string(values.size());
    return false;
  }
  if (!out->allFinite()) {
    *error = "matrix has non-finite entries";
    return false;
  }
  *out = 0.5 * (*out + out->transpose()).eval();
  return true;
}

bool loadFilterParams(const ros::NodeHandle& pnh, FilterParams* p, std::string* error) {
  error->clear();
  pnh.param("frequency", p->frequency, 30.0);
  if (!(p->frequency > 0.0) || p->frequency > 10000.0) {
    *error = "frequency must be in (0, 10000] Hz";
    return false;
  }
  pnh.param("sensor_timeout", p->sensor_timeout, 1.0 / p->frequency);
  pnh.param("two_d_mode", p->two_d_mode, false);
  pnh.param("publish_tf", p->publish_tf, true);
  pnh.param("print_diagnostics", p->print_diagnostics, true);
  pnh.param("debug", p->debug, false);
  pnh.param<std::string>("map_frame", p->map_frame, "map");
  pnh.param<std::string>("odom_frame", p->odom_frame, "odom");
  pnh.param<std::string>("base_link_frame", p->base_link_frame, "base_link");
  pnh.param<std::string>("world_frame", p->world_frame, p->odom_frame);
  pnh.param("transform_time_offset", p->transform_time_offset, 0.0);
  pnh.param("transform_timeout", p->transform_timeout, 0.0);
  pnh.param("gravitational_acceleration", p->gravitational_acceleration, 9.80665);
  pnh.param("sensor_stale_timeout", p->sensor_stale_timeout, 1.0);

  for (const std::string* f : {&p->map_frame, &p->odom_frame, &p->base_link_frame, &p->world_frame}) {
    if (!validFrame(*f)) {
      *error = "frame names must be non-empty and without a leading '/': '" + *f + "'";
      return false;
    }
  }
  if (p->map_frame == p->odom_frame || p->odom_frame == p->base_link_frame ||
      p->map_frame == p->base_link_frame) {
    *error = "map_frame, odom_frame and base_link_frame must differ";
    return false;
  }
  if (p->world_frame != p->map_frame && p->world_frame != p->odom_frame) {
    *error = "world_frame must be map_frame or odom_frame";
    return false;
  }

  std::vector<double> list;
  p->process_noise_covariance = defaultProcessNoise();
  if (readDoubleList(pnh, "process_noise_covariance", &list, error)) {
    if (!parseStateMatrix(list, &p->process_noise_covariance, error)) {
      *error = "process_noise_covariance: " + *error;
      return false;
    }
  } else if (!error->empty()) {
    return false;
  }
  p->initial_estimate_covariance = StateMatrix::Identity() * 1e-9;
  if (readDoubleList(pnh, "initial_estimate_covariance", &list, error)) {
    if (!parseStateMatrix(list, &p->initial_estimate_covariance, error)) {
      *error = "initial_estimate_covariance: " + *error;
      return false;
    }
  } else if (!error->empty()) {
    return false;
  }

  const std::pair<const char*, SensorType> kinds[] = {{"imu", SensorType::kImu},
                                                      {"pose", SensorType::kPose},
                                                      {"odom", SensorType::kOdom},
                                                      {"twist", SensorType::kTwist}};
  p->sensors.clear();
  for (const auto& kind : kinds) {
    for (int n = 0;; ++n) {
      SensorConfig s;
      s.type = kind.second;
      s.name = std::string(kind.first) + std::to_string(n);
      if (!pnh.getParam(s.name, s.topic)) break;
      if (s.topic.empty()) {
        *error = s.name + " is empty";
        return false;
      }
      if (!readConfig(pnh, s.name + "_config", &s.update_vector, error)) return false;
      pnh.param(s.name + "_differential", s.differential, false);
      pnh.param(s.name + "_relative", s.relative, false);
      pnh.param(s.name + "_nodelay", s.nodelay, false);
      pnh.param(s.name + "_queue_size", s.queue_size, 1);
      if (s.queue_size < 1) s.queue_size = 1;
      pnh.param(s.name + "_frame_is_world", s.frame_is_world, false);
      if (readDoubleList(pnh, s.name + "_differential_noise", &list, error)) {
        if (list.size() != 6) {
          *error = s.name + "_differential_noise needs 6 numbers (x y z roll pitch yaw), got " +
                   std::to_string(list.size());
          return false;
        }
        for (size_t i = 0; i < 6; ++i) {
          if (!std::isfinite(list[i]) || list[i] < 0.0) {
            *error = s.name + "_differential_noise must be finite and >= 0";
            return false;
          }
          s.differential_noise[i] = list[i];
        }
        s.has_differential_noise = true;
      } else if (!error->empty()) {
        return false;
      }
      switch (s.type) {
        case SensorType::kImu:
          s.pose_rejection_threshold = threshold(pnh, s.name + "_pose_rejection_threshold");
          s.twist_rejection_threshold = threshold(pnh, s.name + "_twist_rejection_threshold");
          s.linear_acceleration_rejection_threshold =
              threshold(pnh, s.name + "_linear_acceleration_rejection_threshold");
          pnh.param(s.name + "_remove_gravitational_acceleration", s.remove_gravitational_acceleration,
                    false);
          break;
        case SensorType::kPose:
          s.pose_rejection_threshold = threshold(pnh, s.name + "_rejection_threshold");
          break;
        case SensorType::kTwist:
          s.twist_rejection_threshold = threshold(pnh, s.name + "_rejection_threshold");
          break;
        case SensorType::kOdom:
          s.pose_rejection_threshold = threshold(pnh, s.name + "_pose_rejection_threshold");
          s.twist_rejection_threshold = threshold(pnh, s.name + "_twist_rejection_threshold");
          break;
      }
      p->sensors.push_back(s);
    }
  }
  if (p->sensors.empty()) {
    *error = "no sensors configured (set imu0, pose0, odom0 or twist0)";
    return false;
  }
  return true;
}

}  // namespace rbd_localization
