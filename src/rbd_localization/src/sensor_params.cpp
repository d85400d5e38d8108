#include "rbd_localization/sensor_params.h"

#include <cmath>
#include <limits>

namespace rbd_localization {

namespace {

using XmlRpc::XmlRpcValue;

constexpr double kNoGate = std::numeric_limits<double>::max();

/// A rejection threshold [standard deviations]; default: never reject.
bool threshold(ParamReader* r, const std::string& key, double* out) {
  *out = kNoGate;
  if (!r->number(key, out)) return false;
  if (std::isnan(*out) || *out < 0.0) return r->fail(key + " must be >= 0 (standard deviations)");
  if (std::isinf(*out)) *out = kNoGate;
  return true;
}

/// A list of exactly 15 booleans (`<sensor>_config`).
bool readUpdateVector(ParamReader* r, const std::string& key, std::array<bool, STATE_SIZE>* out) {
  const XmlRpcValue* v = r->take(key);
  if (!v) {
    return r->fail(key +
                   " is missing (15 booleans: x y z roll pitch yaw vx vy vz vroll vpitch vyaw ax ay az)");
  }
  XmlRpcValue c = *v;
  if (c.getType() != XmlRpcValue::TypeArray || c.size() != STATE_SIZE) {
    return r->fail(
        key +
        " must be a list of 15 booleans (x y z roll pitch yaw vx vy vz vroll vpitch vyaw ax ay az), got " +
        describeValue(c));
  }
  for (int i = 0; i < STATE_SIZE; ++i) {
    XmlRpcValue e = c[i];
    if (e.getType() != XmlRpcValue::TypeBoolean) {
      return r->fail(key + "[" + std::to_string(i) + "] (" + stateMemberName(i) +
                     ") must be true or false, got " + describeValue(e));
    }
    (*out)[i] = static_cast<bool&>(e);
  }
  return true;
}

/// Members an input of this type can carry (r_l clears the others too).
bool typeCarries(SensorType t, int member) {
  switch (t) {
    case SensorType::kPose:
      return member < POSITION_V_OFFSET;
    case SensorType::kTwist:
      return member >= POSITION_V_OFFSET && member < POSITION_A_OFFSET;
    case SensorType::kOdom:
      return member < POSITION_A_OFFSET;
    case SensorType::kImu:
      return (member >= ORIENTATION_OFFSET && member < POSITION_V_OFFSET) || member >= ORIENTATION_V_OFFSET;
  }
  return false;
}

}  // namespace

const char* sensorTypeName(SensorType t) {
  switch (t) {
    case SensorType::kImu:
      return "imu";
    case SensorType::kPose:
      return "pose";
    case SensorType::kOdom:
      return "odom";
    case SensorType::kTwist:
      return "twist";
  }
  return "?";
}

bool readSensorParams(ParamReader* r, SensorType type, const std::string& name, SensorConfig* s, bool* used) {
  s->type = type;
  s->name = name;
  if (!r->text(name, &s->topic)) return false;
  if (s->topic.empty()) return r->fail(name + " (the topic) is empty");
  if (!readUpdateVector(r, name + "_config", &s->update_vector)) return false;
  std::string dropped;
  bool any = false;
  for (int i = 0; i < STATE_SIZE; ++i) {
    if (s->update_vector[i] && !typeCarries(type, i)) {
      dropped += std::string(dropped.empty() ? "" : " ") + stateMemberName(i);
      s->update_vector[i] = false;
    }
    any = any || s->update_vector[i];
  }
  if (!dropped.empty()) {
    r->warn(name + "_config enables " + dropped + ", which a " + sensorTypeName(type) +
            " message does not carry: ignored (as robot_localization does)");
  }
  if (!r->boolean(name + "_differential", &s->differential) ||
      !r->boolean(name + "_relative", &s->relative) || !r->boolean(name + "_nodelay", &s->nodelay) ||
      !r->boolean(name + "_frame_is_world", &s->frame_is_world)) {
    return false;
  }
  if (type == SensorType::kTwist && (s->differential || s->relative)) {
    r->warn(name + "_differential/_relative have no effect on a twist input (as in robot_localization)");
    s->differential = s->relative = false;
  }
  if (s->differential && s->relative) {
    r->warn("Both " + name + "_differential and " + name +
            "_relative are true: differential mode is used (as robot_localization does)");
    s->relative = false;
  }
  s->queue_size = 1;
  if (!r->integer(name + "_queue_size", &s->queue_size)) return false;
  if (s->queue_size < 0) return r->fail(name + "_queue_size must be >= 0 (0: unbounded, as in roscpp)");

  std::vector<double> noise;
  bool noise_present = false;
  if (!r->numberList(name + "_differential_noise", &noise, &noise_present)) return false;
  if (noise_present) {
    if (noise.size() != 6) {
      return r->fail(name + "_differential_noise needs 6 numbers (x y z roll pitch yaw), got " +
                     std::to_string(noise.size()));
    }
    for (size_t i = 0; i < 6; ++i) {
      if (!std::isfinite(noise[i]) || noise[i] < 0.0) {
        return r->fail(name + "_differential_noise must be finite and >= 0");
      }
      s->differential_noise[i] = noise[i];
    }
    s->has_differential_noise = true;
    if (!s->differential)
      r->warn(name + "_differential_noise has no effect without " + name + "_differential");
  }

  switch (type) {
    case SensorType::kImu: {
      if (!threshold(r, name + "_pose_rejection_threshold", &s->pose_rejection_threshold) ||
          !threshold(r, name + "_twist_rejection_threshold", &s->twist_rejection_threshold) ||
          !threshold(r, name + "_linear_acceleration_rejection_threshold",
                     &s->linear_acceleration_rejection_threshold) ||
          !r->boolean(name + "_remove_gravitational_acceleration", &s->remove_gravitational_acceleration)) {
        return false;
      }
      // r_l's documentation names this key; its code reads _twist_rejection_threshold only.
      const std::string alias = name + "_angular_velocity_rejection_threshold";
      if (r->has(alias)) {
        double t = kNoGate;
        if (!threshold(r, alias, &t)) return false;
        if (r->has(name + "_twist_rejection_threshold")) {
          r->warn(alias + " ignored: " + name +
                  "_twist_rejection_threshold is set (robot_localization reads "
                  "only the latter)");
        } else {
          s->twist_rejection_threshold = t;
          r->warn(alias +
                  " (named in robot_localization's documentation, not read by its code) gates the "
                  "angular rates here; robot_localization reads " +
                  name + "_twist_rejection_threshold");
        }
      }
      break;
    }
    case SensorType::kPose:
      if (!threshold(r, name + "_rejection_threshold", &s->pose_rejection_threshold)) return false;
      break;
    case SensorType::kTwist:
      if (!threshold(r, name + "_rejection_threshold", &s->twist_rejection_threshold)) return false;
      break;
    case SensorType::kOdom: {
      if (!threshold(r, name + "_pose_rejection_threshold", &s->pose_rejection_threshold) ||
          !threshold(r, name + "_twist_rejection_threshold", &s->twist_rejection_threshold)) {
        return false;
      }
      bool child = false;
      if (!r->boolean(name + "_pose_use_child_frame", &child)) return false;
      if (child) {
        r->warn(name +
                "_pose_use_child_frame: true (robot_localization for ROS 2) is not honoured: the pose is "
                "the pose of base_link_frame");
      }
      break;
    }
  }
  if (!any) {
    r->warn(name + " (" + s->topic +
            ") is listed as an input, but all its update variables are false: not "
            "subscribed (as robot_localization does)");
  }
  *used = any;
  return true;
}

}  // namespace rbd_localization
