#include "rbd_localization/filter_params.h"

#include <ros/node_handle.h>
#include <ros/param.h>

#include <cmath>
#include <limits>
#include <locale>
#include <map>
#include <regex>
#include <set>
#include <sstream>

namespace rbd_localization {

namespace {

using XmlRpc::XmlRpcValue;

constexpr double kNoGate = std::numeric_limits<double>::max();
const char* const kStateNames[STATE_SIZE] = {"x",  "y",     "z",      "roll", "pitch", "yaw", "vx", "vy",
                                             "vz", "vroll", "vpitch", "vyaw", "ax",    "ay",  "az"};

/// A short description of a parameter value for error messages ("the string 'abc'", "a list of 3").
std::string describe(const XmlRpcValue& value) {
  XmlRpcValue v = value;  // the conversion operators are non-const
  std::ostringstream os;
  switch (v.getType()) {
    case XmlRpcValue::TypeBoolean:
      os << "the boolean " << (static_cast<bool&>(v) ? "true" : "false");
      break;
    case XmlRpcValue::TypeInt:
      os << "the integer " << static_cast<int&>(v);
      break;
    case XmlRpcValue::TypeDouble:
      os << "the number " << static_cast<double&>(v);
      break;
    case XmlRpcValue::TypeString:
      os << "the string '" << static_cast<std::string&>(v) << "'";
      break;
    case XmlRpcValue::TypeArray:
      os << "a list of " << v.size();
      break;
    case XmlRpcValue::TypeStruct:
      os << "a dictionary";
      break;
    default:
      os << "a value of XmlRpc type " << static_cast<int>(v.getType());
  }
  return os.str();
}

/// A number written as text, read as r_l reads matrix entries (a C-locale stream), but the
/// whole text must be the number (r_l silently keeps the leading number or 0).
bool parseNumberText(const std::string& text, double* out) {
  std::istringstream is(text);
  is.imbue(std::locale::classic());
  double v = 0.0;
  is >> v;
  if (is.fail()) return false;
  is >> std::ws;
  if (!is.eof()) return false;
  *out = v;
  return true;
}

std::string formatNumber(double v) {
  if (std::isnan(v)) return "NaN";
  if (std::isinf(v)) return v > 0 ? "Infinity" : "-Infinity";
  std::ostringstream os;
  os.imbue(std::locale::classic());
  os.precision(17);
  os << v;
  return os.str();
}

/// Reads typed values out of the private namespace and remembers which keys were read.
class Reader {
 public:
  Reader(const XmlRpcValue& ns, std::vector<std::string>* warnings, std::string* error)
      : warnings_(warnings), error_(error) {
    XmlRpcValue copy = ns;  // begin()/end() are non-const in older xmlrpcpp (Melodic)
    if (copy.getType() == XmlRpcValue::TypeStruct) {
      for (auto it = copy.begin(); it != copy.end(); ++it) values_[it->first] = it->second;
    }
  }

  bool has(const std::string& key) const { return values_.count(key) > 0; }

  /// The value of key (marked as read), or nullptr when it is not set.
  const XmlRpcValue* take(const std::string& key) {
    auto it = values_.find(key);
    if (it == values_.end()) return nullptr;
    read_.insert(key);
    return &it->second;
  }

  bool fail(const std::string& message) {
    *error_ = message;
    return false;
  }

  void warn(const std::string& message) { warnings_->push_back(message); }

  /// A scalar number. Absent: out untouched. Text holding a number is read (YAML 1.1 makes
  /// `1e-2` text), with a warning: r_l's nh.param() ignores text and keeps its default.
  bool number(const std::string& key, double* out) {
    const XmlRpcValue* v = take(key);
    if (!v) return true;
    XmlRpcValue c = *v;
    switch (c.getType()) {
      case XmlRpcValue::TypeInt:
        *out = static_cast<int&>(c);
        return true;
      case XmlRpcValue::TypeDouble:
        *out = static_cast<double&>(c);
        return true;
      case XmlRpcValue::TypeString: {
        double d = 0.0;
        if (parseNumberText(static_cast<std::string&>(c), &d)) {
          warn(
              key + " is " + describe(c) +
              " (YAML 1.1 reads a number such as 1e-2, without '.' and sign in " +
              "the exponent, as text); read as " + formatNumber(d) +
              ". robot_localization would ignore it and use its default; write it as 1.0e-2 to be read alike "
              "by both.");
          *out = d;
          return true;
        }
        break;
      }
      default:
        break;
    }
    return fail(key + " must be a number, got " + describe(c));
  }

  /// A whole number (a double is rounded as roscpp does; text as for number()).
  bool integer(const std::string& key, int* out) {
    if (!has(key)) return true;
    double d = *out;
    if (!number(key, &d)) return false;
    if (!std::isfinite(d) || std::fabs(d) > 1e9) return fail(key + " must be a whole number");
    const double rounded = std::floor(d + 0.5);
    if (rounded != d)
      warn(key + " = " + formatNumber(d) + " is not a whole number; rounded to " + formatNumber(rounded));
    *out = static_cast<int>(rounded);
    return true;
  }

  bool boolean(const std::string& key, bool* out) {
    const XmlRpcValue* v = take(key);
    if (!v) return true;
    XmlRpcValue c = *v;
    if (c.getType() != XmlRpcValue::TypeBoolean) {
      return fail(key + " must be true or false, got " + describe(c) +
                  " (robot_localization would silently use its default)");
    }
    *out = static_cast<bool&>(c);
    return true;
  }

  bool text(const std::string& key, std::string* out) {
    const XmlRpcValue* v = take(key);
    if (!v) return true;
    XmlRpcValue c = *v;
    if (c.getType() != XmlRpcValue::TypeString) return fail(key + " must be a string, got " + describe(c));
    *out = static_cast<std::string&>(c);
    return true;
  }

  /// A list of numbers as r_l reads its matrices: every entry through a string stream, so ints,
  /// doubles and text such as `1e-9` (YAML 1.1 text) are all numbers; booleans read as 1 and 0.
  bool numberList(const std::string& key, std::vector<double>* out, bool* present) {
    const XmlRpcValue* v = take(key);
    *present = v != nullptr;
    if (!v) return true;
    XmlRpcValue c = *v;
    if (c.getType() != XmlRpcValue::TypeArray)
      return fail(key + " must be a list of numbers, got " + describe(c));
    out->clear();
    bool warned_bool = false;
    for (int i = 0; i < c.size(); ++i) {
      XmlRpcValue e = c[i];
      const std::string where = key + "[" + std::to_string(i) + "]";
      switch (e.getType()) {
        case XmlRpcValue::TypeInt:
          out->push_back(static_cast<int&>(e));
          break;
        case XmlRpcValue::TypeDouble:
          out->push_back(static_cast<double&>(e));
          break;
        case XmlRpcValue::TypeBoolean:
          if (!warned_bool) {
            warn(where + " is a boolean; read as " + (static_cast<bool&>(e) ? "1" : "0") +
                 " (and so are the list's other booleans), as robot_localization does");
            warned_bool = true;
          }
          out->push_back(static_cast<bool&>(e) ? 1.0 : 0.0);
          break;
        case XmlRpcValue::TypeString: {
          double d = 0.0;
          if (!parseNumberText(static_cast<std::string&>(e), &d)) {
            return fail(where + " is " + describe(e) + ", not a number");
          }
          out->push_back(d);
          break;
        }
        default:
          return fail(where + " is " + describe(e) + ", not a number");
      }
    }
    return true;
  }

  /// A list of exactly 15 booleans (`<sensor>_config`).
  bool updateVector(const std::string& key, std::array<bool, STATE_SIZE>* out) {
    const XmlRpcValue* v = take(key);
    if (!v) {
      return fail(key +
                  " is missing (15 booleans: x y z roll pitch yaw vx vy vz vroll vpitch vyaw ax ay az)");
    }
    XmlRpcValue c = *v;
    if (c.getType() != XmlRpcValue::TypeArray || c.size() != STATE_SIZE) {
      return fail(
          key +
          " must be a list of 15 booleans (x y z roll pitch yaw vx vy vz vroll vpitch vyaw ax ay az), got " +
          describe(c));
    }
    for (int i = 0; i < STATE_SIZE; ++i) {
      XmlRpcValue e = c[i];
      if (e.getType() != XmlRpcValue::TypeBoolean) {
        return fail(key + "[" + std::to_string(i) + "] (" + kStateNames[i] + ") must be true or false, got " +
                    describe(e));
      }
      (*out)[i] = static_cast<bool&>(e);
    }
    return true;
  }

  /// Keys present but never read.
  std::vector<std::string> unread() const {
    std::vector<std::string> out;
    for (const auto& kv : values_) {
      if (!read_.count(kv.first)) out.push_back(kv.first);
    }
    return out;
  }

 private:
  std::map<std::string, XmlRpcValue> values_;
  std::set<std::string> read_;
  std::vector<std::string>* warnings_;
  std::string* error_;
};

bool validFrame(const std::string& f) { return !f.empty() && f[0] != '/'; }

/// A rejection threshold [standard deviations]; default: never reject.
bool threshold(Reader* r, const std::string& key, double* out) {
  *out = kNoGate;
  if (!r->number(key, out)) return false;
  if (std::isnan(*out) || *out < 0.0) return r->fail(key + " must be >= 0 (standard deviations)");
  if (std::isinf(*out)) *out = kNoGate;
  return true;
}

bool readMatrix(Reader* r, const std::string& key, StateMatrix* out) {
  std::vector<double> values;
  bool present = false;
  if (!r->numberList(key, &values, &present)) return false;
  if (!present) return true;
  std::string why;
  if (!parseStateMatrix(values, out, &why)) return r->fail(key + ": " + why);
  for (int i = 0; i < STATE_SIZE; ++i) {
    if ((*out)(i, i) < 0.0) {
      return r->fail(key + ": the variance of " + kStateNames[i] + " is negative (" +
                     formatNumber((*out)(i, i)) + ")");
    }
  }
  if (!out->isApprox(out->transpose(), 1e-12)) {
    r->warn(key + " is not symmetric; the filter uses (M + M^T) / 2");
    *out = (0.5 * (*out + out->transpose())).eval();
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

bool readSensor(Reader* r, SensorType type, const std::string& name, SensorConfig* s, bool* used) {
  s->type = type;
  s->name = name;
  if (!r->text(name, &s->topic)) return false;
  if (s->topic.empty()) return r->fail(name + " (the topic) is empty");
  if (!r->updateVector(name + "_config", &s->update_vector)) return false;
  std::string dropped;
  bool any = false;
  for (int i = 0; i < STATE_SIZE; ++i) {
    if (s->update_vector[i] && !typeCarries(type, i)) {
      dropped += std::string(dropped.empty() ? "" : " ") + kStateNames[i];
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

/// r_l options read so the configuration is accepted, but whose behaviour this node lacks.
bool readUnsupported(Reader* r) {
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
  Reader r(ns, warnings, error);

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
      if (!readSensor(&r, kind.second, name, &s, &used)) return false;
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

std::string effectiveConfigJson(const FilterParams& p, const StateMatrix& q, const StateMatrix& p0,
                                const std::vector<std::string>& warnings) {
  // JSON, which is also YAML: one line per key, matrices row-major.
  std::ostringstream os;
  os.imbue(std::locale::classic());
  const auto b = [](bool v) { return v ? "true" : "false"; };
  const auto str = [](const std::string& s) {
    std::string out = "\"";
    for (char c : s) {
      if (c == '"' || c == '\\') out += '\\';
      out += c;
    }
    return out + "\"";
  };
  const auto matrix = [&](const StateMatrix& m) {
    std::string out = "[";
    for (int r = 0; r < STATE_SIZE; ++r) {
      for (int c = 0; c < STATE_SIZE; ++c) out += (r || c ? ", " : "") + formatNumber(m(r, c));
    }
    return out + "]";
  };
  os << "{\n";
  os << "\"frequency\": " << formatNumber(p.frequency) << ",\n";
  os << "\"sensor_timeout\": " << formatNumber(p.sensor_timeout) << ",\n";
  os << "\"two_d_mode\": " << b(p.two_d_mode) << ",\n";
  os << "\"publish_tf\": " << b(p.publish_tf) << ",\n";
  os << "\"publish_acceleration\": " << b(p.publish_acceleration) << ",\n";
  os << "\"debug\": " << b(p.debug) << ",\n";
  os << "\"debug_out_file\": " << str(p.debug_out_file) << ",\n";
  os << "\"map_frame\": " << str(p.map_frame) << ",\n";
  os << "\"odom_frame\": " << str(p.odom_frame) << ",\n";
  os << "\"base_link_frame\": " << str(p.base_link_frame) << ",\n";
  os << "\"base_link_frame_output\": " << str(p.base_link_output_frame) << ",\n";
  os << "\"world_frame\": " << str(p.world_frame) << ",\n";
  os << "\"transform_time_offset\": " << formatNumber(p.transform_time_offset) << ",\n";
  os << "\"transform_timeout\": " << formatNumber(p.transform_timeout) << ",\n";
  os << "\"gravitational_acceleration\": " << formatNumber(p.gravitational_acceleration) << ",\n";
  os << "\"predict_to_current_time\": " << b(p.predict_to_current_time) << ",\n";
  os << "\"disabled_at_startup\": " << b(p.disabled_at_startup) << ",\n";
  os << "\"silent_tf_failure\": " << b(p.silent_tf_failure) << ",\n";
  os << "\"sensor_stale_timeout\": " << formatNumber(p.sensor_stale_timeout) << ",\n";
  os << "\"process_noise_covariance\": " << matrix(q) << ",\n";
  os << "\"initial_estimate_covariance\": " << matrix(p0) << ",\n";
  os << "\"initial_state\": [";
  for (int i = 0; i < STATE_SIZE; ++i) os << (i ? ", " : "") << formatNumber(p.initial_state(i));
  os << "],\n\"sensors\": [";
  for (size_t k = 0; k < p.sensors.size(); ++k) {
    const SensorConfig& s = p.sensors[k];
    os << (k ? "," : "") << "\n  {\"name\": " << str(s.name) << ", \"type\": \"" << sensorTypeName(s.type)
       << "\", \"topic\": " << str(s.topic) << ", \"config\": [";
    for (int i = 0; i < STATE_SIZE; ++i) os << (i ? ", " : "") << b(s.update_vector[i]);
    os << "], \"differential\": " << b(s.differential) << ", \"relative\": " << b(s.relative)
       << ", \"queue_size\": " << s.queue_size << ", \"nodelay\": " << b(s.nodelay)
       << ", \"pose_rejection_threshold\": " << formatNumber(s.pose_rejection_threshold)
       << ", \"twist_rejection_threshold\": " << formatNumber(s.twist_rejection_threshold)
       << ", \"linear_acceleration_rejection_threshold\": "
       << formatNumber(s.linear_acceleration_rejection_threshold)
       << ", \"remove_gravitational_acceleration\": " << b(s.remove_gravitational_acceleration)
       << ", \"frame_is_world\": " << b(s.frame_is_world) << ", \"differential_noise\": ";
    if (s.has_differential_noise) {
      os << "[";
      for (size_t i = 0; i < 6; ++i) os << (i ? ", " : "") << formatNumber(s.differential_noise[i]);
      os << "]";
    } else {
      os << "null";
    }
    os << "}";
  }
  os << "\n],\n\"warnings\": [";
  for (size_t k = 0; k < warnings.size(); ++k) os << (k ? ",\n  " : "\n  ") << str(warnings[k]);
  os << "\n]\n}\n";
  return os.str();
}

}  // namespace rbd_localization
