// The parameter parser fed with the XmlRpc values the parameter server really delivers for
// robot_localization-style YAML: rosparam reads YAML 1.1, where `1e-9` (no '.', unsigned
// exponent) is a string, `0` an int and `0.05` a double (rostest rl_config.test checks that typing
// on the live server). Expected values are the numbers written in the YAML, read as r_l reads
// them (every matrix entry through a string stream; 225 entries row-major).
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "rbd_localization/effective_config.h"
#include "rbd_localization/filter_params.h"

using namespace rbd_localization;  // NOLINT: StateMember* enumerators
using XmlRpc::XmlRpcValue;

namespace {

XmlRpcValue str(const std::string& s) { return XmlRpcValue(s); }
XmlRpcValue num(double d) { return XmlRpcValue(d); }
XmlRpcValue integer(int i) { return XmlRpcValue(i); }
XmlRpcValue boolean(bool b) { return XmlRpcValue(b); }

XmlRpcValue list(const std::vector<XmlRpcValue>& values) {
  XmlRpcValue v;
  v.setSize(static_cast<int>(values.size()));
  for (size_t i = 0; i < values.size(); ++i) v[static_cast<int>(i)] = values[i];
  return v;
}

XmlRpcValue config(const std::string& ones) {  // "000111000111111" -> 15 booleans
  std::vector<XmlRpcValue> v;
  for (char c : ones) v.push_back(boolean(c == '1'));
  return list(v);
}

/// 225 entries as the template writes them: diagonal entries given, off-diagonal integer 0.
XmlRpcValue matrix225(const std::vector<XmlRpcValue>& diagonal) {
  std::vector<XmlRpcValue> v;
  for (int r = 0; r < STATE_SIZE; ++r) {
    for (int c = 0; c < STATE_SIZE; ++c) v.push_back(r == c ? diagonal[static_cast<size_t>(r)] : integer(0));
  }
  return list(v);
}

std::vector<XmlRpcValue> repeat(const XmlRpcValue& v) { return std::vector<XmlRpcValue>(STATE_SIZE, v); }

const std::vector<double> kTemplateQ = {0.05, 0.05, 0.06, 0.03, 0.03, 0.06, 0.025, 0.025,
                                        0.04, 0.01, 0.01, 0.02, 0.01, 0.01, 0.015};

/// A minimal valid namespace: one IMU with rates.
XmlRpcValue minimal() {
  XmlRpcValue ns;
  ns["imu0"] = str("imu/data");
  ns["imu0_config"] = config("000000000111000");
  return ns;
}

struct Parsed {
  bool ok;
  FilterParams params;
  std::vector<std::string> warnings;
  std::string error;
};

Parsed parse(const XmlRpcValue& ns) {
  Parsed p;
  p.ok = parseFilterParams(ns, &p.params, &p.warnings, &p.error);
  return p;
}

std::string joined(const Parsed& p) {
  std::string out;
  for (const std::string& w : p.warnings) out += "[" + w + "] ";
  return out;
}

bool anyWarningHas(const Parsed& p, const std::string& text) {
  for (const std::string& w : p.warnings) {
    if (w.find(text) != std::string::npos) return true;
  }
  return false;
}

void expectDiagonal(const StateMatrix& m, const std::vector<double>& diagonal) {
  for (int r = 0; r < STATE_SIZE; ++r) {
    for (int c = 0; c < STATE_SIZE; ++c) {
      EXPECT_EQ(m(r, c), r == c ? diagonal[static_cast<size_t>(r)] : 0.0) << "(" << r << ", " << c << ")";
    }
  }
}

}  // namespace

TEST(FilterParams, TemplateMatricesWithTextExponentsAndIntegerZeros) {
  XmlRpcValue ns = minimal();
  std::vector<XmlRpcValue> q;
  for (double d : kTemplateQ) q.push_back(num(d));
  ns["process_noise_covariance"] = matrix225(q);
  ns["initial_estimate_covariance"] = matrix225(repeat(str("1e-9")));
  const Parsed p = parse(ns);
  ASSERT_TRUE(p.ok) << p.error;
  expectDiagonal(p.params.process_noise_covariance, kTemplateQ);
  expectDiagonal(p.params.initial_estimate_covariance, std::vector<double>(STATE_SIZE, 1e-9));
  EXPECT_TRUE(p.warnings.empty()) << joined(p);
}

TEST(FilterParams, FullMatrixKeepsOffDiagonalEntriesRowMajor) {
  XmlRpcValue ns = minimal();
  std::vector<XmlRpcValue> v;
  for (int r = 0; r < STATE_SIZE; ++r) {
    for (int c = 0; c < STATE_SIZE; ++c)
      v.push_back(r == c ? num(1.0) : (r == 0 && c == 1) || (r == 1 && c == 0) ? str("2.5e-1") : integer(0));
  }
  ns["initial_estimate_covariance"] = list(v);
  const Parsed p = parse(ns);
  ASSERT_TRUE(p.ok) << p.error;
  EXPECT_EQ(p.params.initial_estimate_covariance(0, 1), 0.25);
  EXPECT_EQ(p.params.initial_estimate_covariance(1, 0), 0.25);
  EXPECT_EQ(p.params.initial_estimate_covariance(2, 2), 1.0);
}

TEST(FilterParams, FifteenNumbersAreTheDiagonal) {
  XmlRpcValue ns = minimal();
  ns["initial_estimate_covariance"] = list(repeat(str("1e-9")));
  std::vector<XmlRpcValue> q;
  for (double d : kTemplateQ) q.push_back(num(d));
  q[0] = integer(1);
  ns["process_noise_covariance"] = list(q);
  const Parsed p = parse(ns);
  ASSERT_TRUE(p.ok) << p.error;
  std::vector<double> expected = kTemplateQ;
  expected[0] = 1.0;
  expectDiagonal(p.params.process_noise_covariance, expected);
  expectDiagonal(p.params.initial_estimate_covariance, std::vector<double>(STATE_SIZE, 1e-9));
}

TEST(FilterParams, DefaultsAreRobotLocalizations) {
  const Parsed p = parse(minimal());
  ASSERT_TRUE(p.ok) << p.error;
  expectDiagonal(p.params.process_noise_covariance, kTemplateQ);
  expectDiagonal(p.params.initial_estimate_covariance, std::vector<double>(STATE_SIZE, 1e-9));
  EXPECT_EQ(p.params.frequency, 30.0);
  EXPECT_DOUBLE_EQ(p.params.sensor_timeout, 1.0 / 30.0);
  EXPECT_EQ(p.params.world_frame, "odom");
  EXPECT_EQ(p.params.base_link_output_frame, "base_link");
  ASSERT_EQ(p.params.sensors.size(), 1u);
  const SensorConfig& s = p.params.sensors[0];
  EXPECT_EQ(s.queue_size, 1);
  EXPECT_FALSE(s.nodelay || s.differential || s.relative || s.remove_gravitational_acceleration);
  EXPECT_EQ(s.pose_rejection_threshold, std::numeric_limits<double>::max());
  EXPECT_EQ(s.twist_rejection_threshold, std::numeric_limits<double>::max());
  EXPECT_EQ(s.linear_acceleration_rejection_threshold, std::numeric_limits<double>::max());
}

TEST(FilterParams, MatrixOfWrongSizeOrWithTextThatIsNoNumberIsRefused) {
  for (int n : {14, 16, 224, 226}) {
    XmlRpcValue ns = minimal();
    std::vector<XmlRpcValue> v(static_cast<size_t>(n), num(0.1));
    ns["process_noise_covariance"] = list(v);
    const Parsed p = parse(ns);
    EXPECT_FALSE(p.ok) << n;
    EXPECT_NE(p.error.find("process_noise_covariance"), std::string::npos) << p.error;
    EXPECT_NE(p.error.find(std::to_string(n)), std::string::npos) << p.error;
  }
  for (const char* bad : {"abc", "1e-9x", "", "0,5"}) {
    XmlRpcValue ns = minimal();
    std::vector<XmlRpcValue> v = repeat(num(0.1));
    v[3] = str(bad);
    ns["initial_estimate_covariance"] = list(v);
    const Parsed p = parse(ns);
    EXPECT_FALSE(p.ok) << bad;
    EXPECT_NE(p.error.find("initial_estimate_covariance[3]"), std::string::npos) << p.error;
  }
  XmlRpcValue ns = minimal();
  ns["initial_estimate_covariance"] = str("1e-9");
  EXPECT_FALSE(parse(ns).ok);
  ns = minimal();
  std::vector<XmlRpcValue> rows(STATE_SIZE, list(repeat(integer(0))));  // nested lists
  ns["process_noise_covariance"] = list(rows);
  EXPECT_FALSE(parse(ns).ok);
}

TEST(FilterParams, BooleanEntriesReadAsOneAndZeroWithAWarning) {
  XmlRpcValue ns = minimal();
  std::vector<XmlRpcValue> v = repeat(boolean(false));
  v[0] = boolean(true);
  ns["initial_estimate_covariance"] = list(v);
  const Parsed p = parse(ns);
  ASSERT_TRUE(p.ok) << p.error;
  EXPECT_EQ(p.params.initial_estimate_covariance(0, 0), 1.0);
  EXPECT_EQ(p.params.initial_estimate_covariance(1, 1), 0.0);
  EXPECT_TRUE(anyWarningHas(p, "initial_estimate_covariance[0] is a boolean"));
}

TEST(FilterParams, NegativeVarianceIsRefusedAsymmetryIsAveraged) {
  XmlRpcValue ns = minimal();
  std::vector<XmlRpcValue> v = repeat(num(0.1));
  v[4] = str("-1e-3");
  ns["process_noise_covariance"] = list(v);
  Parsed p = parse(ns);
  EXPECT_FALSE(p.ok);
  EXPECT_NE(p.error.find("pitch"), std::string::npos) << p.error;

  ns = minimal();
  std::vector<XmlRpcValue> m;
  for (int r = 0; r < STATE_SIZE; ++r) {
    for (int c = 0; c < STATE_SIZE; ++c)
      m.push_back(r == c ? num(1.0) : (r == 0 && c == 1) ? num(0.2) : integer(0));
  }
  ns["process_noise_covariance"] = list(m);
  p = parse(ns);
  ASSERT_TRUE(p.ok) << p.error;
  EXPECT_DOUBLE_EQ(p.params.process_noise_covariance(0, 1), 0.1);
  EXPECT_DOUBLE_EQ(p.params.process_noise_covariance(1, 0), 0.1);
  EXPECT_TRUE(anyWarningHas(p, "process_noise_covariance is not symmetric"));
}

TEST(FilterParams, ScalarsAcceptIntsAndNumberTextWithAWarning) {
  XmlRpcValue ns = minimal();
  ns["frequency"] = integer(50);
  ns["sensor_timeout"] = str("1e-1");  // YAML 1.1 text; r_l would silently keep 1/frequency
  ns["transform_time_offset"] = num(0.05);
  ns["gravitational_acceleration"] = integer(10);
  const Parsed p = parse(ns);
  ASSERT_TRUE(p.ok) << p.error;
  EXPECT_EQ(p.params.frequency, 50.0);
  EXPECT_EQ(p.params.sensor_timeout, 0.1);
  EXPECT_EQ(p.params.transform_time_offset, 0.05);
  EXPECT_EQ(p.params.gravitational_acceleration, 10.0);
  ASSERT_EQ(p.warnings.size(), 1u) << joined(p);
  EXPECT_NE(p.warnings[0].find("sensor_timeout"), std::string::npos) << p.warnings[0];
}

TEST(FilterParams, WrongScalarTypesAreClearErrors) {
  const std::vector<std::pair<std::string, XmlRpcValue>> bad = {
      {"two_d_mode", integer(1)},       {"frequency", str("fast")},
      {"frequency", integer(0)},        {"map_frame", integer(3)},
      {"publish_tf", str("yes")},       {"sensor_timeout", num(-1.0)},
      {"world_frame", str("earth")},    {"base_link_frame", str("odom")},
      {"imu0_queue_size", integer(-1)}, {"imu0_twist_rejection_threshold", num(-2.0)},
      {"imu0_nodelay", integer(0)},     {"initial_state", list(std::vector<XmlRpcValue>(14, integer(0)))}};
  for (size_t i = 0; i < bad.size(); ++i) {
    XmlRpcValue ns = minimal();
    ns[bad[i].first] = bad[i].second;
    const Parsed p = parse(ns);
    EXPECT_FALSE(p.ok) << bad[i].first;
    EXPECT_NE(p.error.find(bad[i].first), std::string::npos) << p.error;
  }
}

TEST(FilterParams, SensorOptionsAsTheTemplateWritesThem) {
  // robot_localization's params/ekf_template.yaml, its keys and value types.
  XmlRpcValue ns;
  ns["frequency"] = integer(30);
  ns["sensor_timeout"] = num(0.1);
  ns["two_d_mode"] = boolean(false);
  ns["transform_time_offset"] = num(0.0);
  ns["transform_timeout"] = num(0.0);
  ns["print_diagnostics"] = boolean(true);
  ns["debug"] = boolean(false);
  ns["debug_out_file"] = str("/path/to/debug/file.txt");
  ns["publish_tf"] = boolean(true);
  ns["publish_acceleration"] = boolean(false);
  ns["map_frame"] = str("map");
  ns["odom_frame"] = str("odom");
  ns["base_link_frame"] = str("base_link");
  ns["world_frame"] = str("odom");
  ns["odom0"] = str("example/odom");
  ns["odom0_config"] = config("110000000001000");
  ns["odom0_queue_size"] = integer(2);
  ns["odom0_nodelay"] = boolean(false);
  ns["odom0_differential"] = boolean(false);
  ns["odom0_relative"] = boolean(false);
  ns["odom0_pose_rejection_threshold"] = integer(5);
  ns["odom0_twist_rejection_threshold"] = integer(1);
  ns["odom1"] = str("example/another_odom");
  ns["odom1_config"] = config("001000000001000");
  ns["odom1_differential"] = boolean(false);
  ns["odom1_relative"] = boolean(true);
  ns["odom1_queue_size"] = integer(2);
  ns["odom1_pose_rejection_threshold"] = integer(2);
  ns["odom1_twist_rejection_threshold"] = num(0.2);
  ns["odom1_nodelay"] = boolean(false);
  ns["pose0"] = str("example/pose");
  ns["pose0_config"] = config("110000000000000");
  ns["pose0_differential"] = boolean(true);
  ns["pose0_relative"] = boolean(false);
  ns["pose0_queue_size"] = integer(5);
  ns["pose0_rejection_threshold"] = integer(2);
  ns["pose0_nodelay"] = boolean(false);
  ns["twist0"] = str("example/twist");
  ns["twist0_config"] = config("000000111000000");
  ns["twist0_queue_size"] = integer(3);
  ns["twist0_rejection_threshold"] = integer(2);
  ns["twist0_nodelay"] = boolean(false);
  ns["imu0"] = str("example/imu");
  ns["imu0_config"] = config("000111000111111");
  ns["imu0_nodelay"] = boolean(false);
  ns["imu0_differential"] = boolean(false);
  ns["imu0_relative"] = boolean(true);
  ns["imu0_queue_size"] = integer(5);
  ns["imu0_pose_rejection_threshold"] = num(0.8);
  ns["imu0_twist_rejection_threshold"] = num(0.8);
  ns["imu0_linear_acceleration_rejection_threshold"] = num(0.8);
  ns["imu0_remove_gravitational_acceleration"] = boolean(true);
  ns["use_control"] = boolean(true);
  ns["stamped_control"] = boolean(false);
  ns["control_timeout"] = num(0.2);
  ns["control_config"] = config("100001");
  ns["acceleration_limits"] = list({num(1.3), num(0.0), num(0.0), num(0.0), num(0.0), num(3.4)});
  ns["deceleration_limits"] = list({num(1.3), num(0.0), num(0.0), num(0.0), num(0.0), num(4.5)});
  ns["acceleration_gains"] = list({num(0.8), num(0.0), num(0.0), num(0.0), num(0.0), num(0.9)});
  ns["deceleration_gains"] = list({num(1.0), num(0.0), num(0.0), num(0.0), num(0.0), num(1.0)});
  std::vector<XmlRpcValue> q;
  for (double d : kTemplateQ) q.push_back(num(d));
  ns["process_noise_covariance"] = matrix225(q);
  ns["initial_estimate_covariance"] = matrix225(repeat(str("1e-9")));

  const Parsed p = parse(ns);
  ASSERT_TRUE(p.ok) << p.error;
  ASSERT_EQ(p.params.sensors.size(), 5u);
  const auto find = [&](const std::string& name) -> const SensorConfig& {
    for (const SensorConfig& s : p.params.sensors) {
      if (s.name == name) return s;
    }
    ADD_FAILURE() << name << " missing";
    return p.params.sensors[0];
  };
  const SensorConfig& odom0 = find("odom0");
  EXPECT_EQ(odom0.type, SensorType::kOdom);
  EXPECT_EQ(odom0.topic, "example/odom");
  EXPECT_EQ(odom0.queue_size, 2);
  EXPECT_EQ(odom0.pose_rejection_threshold, 5.0);
  EXPECT_EQ(odom0.twist_rejection_threshold, 1.0);
  EXPECT_TRUE(odom0.update_vector[StateMemberX] && odom0.update_vector[StateMemberY] &&
              odom0.update_vector[StateMemberVyaw]);
  const SensorConfig& odom1 = find("odom1");
  EXPECT_TRUE(odom1.relative);
  EXPECT_EQ(odom1.twist_rejection_threshold, 0.2);
  const SensorConfig& pose0 = find("pose0");
  EXPECT_TRUE(pose0.differential);
  EXPECT_EQ(pose0.pose_rejection_threshold, 2.0);
  EXPECT_EQ(pose0.queue_size, 5);
  const SensorConfig& twist0 = find("twist0");
  EXPECT_EQ(twist0.twist_rejection_threshold, 2.0);
  EXPECT_EQ(twist0.queue_size, 3);
  const SensorConfig& imu0 = find("imu0");
  EXPECT_TRUE(imu0.relative && !imu0.differential && imu0.remove_gravitational_acceleration);
  EXPECT_EQ(imu0.pose_rejection_threshold, 0.8);
  EXPECT_EQ(imu0.linear_acceleration_rejection_threshold, 0.8);
  for (int i = 0; i < STATE_SIZE; ++i) {
    EXPECT_EQ(imu0.update_vector[i], (i >= 3 && i < 6) || i >= 9) << i;
  }
  expectDiagonal(p.params.initial_estimate_covariance, std::vector<double>(STATE_SIZE, 1e-9));
  EXPECT_EQ(p.params.debug_out_file, "/path/to/debug/file.txt");
  // use_control is the one thing of the template this node does not do: said once, by name.
  ASSERT_EQ(p.warnings.size(), 1u) << joined(p);
  EXPECT_NE(p.warnings[0].find("use_control"), std::string::npos) << p.warnings[0];
}

TEST(FilterParams, UnknownKeysAreListedInOneWarning) {
  XmlRpcValue ns = minimal();
  ns["frequncy"] = integer(30);
  ns["imu0_confg"] = config("000000000111000");
  ns["pose1"] = str("pose");  // no pose0: never read, as in r_l
  ns["pose1_config"] = config("110000000000000");
  const Parsed p = parse(ns);
  ASSERT_TRUE(p.ok) << p.error;
  ASSERT_EQ(p.warnings.size(), 1u) << joined(p);
  const std::string& w = p.warnings[0];
  for (const char* key : {"frequncy", "imu0_confg", "pose1", "pose1_config"}) {
    EXPECT_NE(w.find(key), std::string::npos) << key << " not in: " << w;
  }
  EXPECT_NE(w.find("without gaps"), std::string::npos) << w;
  EXPECT_EQ(p.params.sensors.size(), 1u);
}

TEST(FilterParams, RelativeAndDifferentialMeansDifferential) {
  XmlRpcValue ns = minimal();
  ns["pose0"] = str("pose");
  ns["pose0_config"] = config("110001000000000");
  ns["pose0_differential"] = boolean(true);
  ns["pose0_relative"] = boolean(true);
  const Parsed p = parse(ns);
  ASSERT_TRUE(p.ok) << p.error;
  const SensorConfig& s = p.params.sensors[0].name == "pose0" ? p.params.sensors[0] : p.params.sensors[1];
  EXPECT_TRUE(s.differential);
  EXPECT_FALSE(s.relative);
  EXPECT_TRUE(anyWarningHas(p, "pose0_differential"));
}

TEST(FilterParams, MembersTheMessageCannotCarryAreDroppedWithAWarning) {
  XmlRpcValue ns = minimal();
  ns["imu0_config"] = config("111111111111111");
  const Parsed p = parse(ns);
  ASSERT_TRUE(p.ok) << p.error;
  const SensorConfig& s = p.params.sensors[0];
  for (int i = 0; i < STATE_SIZE; ++i) {
    const bool carried = (i >= StateMemberRoll && i <= StateMemberYaw) || i >= StateMemberVroll;
    EXPECT_EQ(s.update_vector[i], carried) << i;
  }
  EXPECT_TRUE(anyWarningHas(p, "x y z vx vy vz"));
}

TEST(FilterParams, AllFalseInputIsNotSubscribedAndNoInputIsAnError) {
  XmlRpcValue ns = minimal();
  ns["pose0"] = str("pose");
  ns["pose0_config"] = config("000000000000000");
  Parsed p = parse(ns);
  ASSERT_TRUE(p.ok) << p.error;
  EXPECT_EQ(p.params.sensors.size(), 1u);
  EXPECT_TRUE(anyWarningHas(p, "pose0"));

  ns = XmlRpcValue();
  ns["imu0"] = str("imu");
  ns["imu0_config"] = config("000000000000000");
  p = parse(ns);
  EXPECT_FALSE(p.ok);
  EXPECT_NE(p.error.find("no sensors"), std::string::npos);
  EXPECT_FALSE(parse(XmlRpcValue()).ok);  // empty namespace
}

TEST(FilterParams, ConfigMustBeFifteenBooleans) {
  XmlRpcValue ns = minimal();
  ns["imu0_config"] = config("00000000011100");  // 14
  Parsed p = parse(ns);
  EXPECT_FALSE(p.ok);
  EXPECT_NE(p.error.find("imu0_config"), std::string::npos);
  ns = minimal();
  std::vector<XmlRpcValue> v = repeat(boolean(false));
  v[9] = integer(1);
  ns["imu0_config"] = list(v);
  p = parse(ns);
  EXPECT_FALSE(p.ok);
  EXPECT_NE(p.error.find("imu0_config[9] (vroll)"), std::string::npos) << p.error;
  ns = XmlRpcValue();
  ns["imu0"] = str("imu");
  p = parse(ns);
  EXPECT_FALSE(p.ok);
  EXPECT_NE(p.error.find("imu0_config is missing"), std::string::npos) << p.error;
}

TEST(FilterParams, QueueSizeReadAsRoscppDoes) {
  XmlRpcValue ns = minimal();
  ns["imu0_queue_size"] = num(5.0);
  Parsed p = parse(ns);
  ASSERT_TRUE(p.ok) << p.error;
  EXPECT_EQ(p.params.sensors[0].queue_size, 5);
  EXPECT_TRUE(p.warnings.empty());
  ns["imu0_queue_size"] = str("10");
  p = parse(ns);
  ASSERT_TRUE(p.ok) << p.error;
  EXPECT_EQ(p.params.sensors[0].queue_size, 10);
  EXPECT_TRUE(anyWarningHas(p, "imu0_queue_size"));
  ns["imu0_queue_size"] = integer(0);  // roscpp: unbounded
  p = parse(ns);
  ASSERT_TRUE(p.ok) << p.error;
  EXPECT_EQ(p.params.sensors[0].queue_size, 0);
}

TEST(FilterParams, OptionsNotHonouredAreNamed) {
  XmlRpcValue ns = minimal();
  ns["smooth_lagged_data"] = boolean(true);
  ns["history_length"] = num(1.0);
  ns["dynamic_process_noise_covariance"] = boolean(true);
  ns["reset_on_time_jump"] = boolean(false);
  ns["print_diagnostics"] = boolean(false);
  ns["tf_prefix"] = str("robot1");
  ns["alpha"] = num(0.001);
  const Parsed p = parse(ns);
  ASSERT_TRUE(p.ok) << p.error;
  for (const char* key : {"smooth_lagged_data", "dynamic_process_noise_covariance", "reset_on_time_jump",
                          "print_diagnostics", "tf_prefix", "alpha"}) {
    EXPECT_TRUE(anyWarningHas(p, key)) << key;
  }
  EXPECT_FALSE(anyWarningHas(p, "unknown"));
  // The same options at the values that change nothing: silent.
  ns = minimal();
  ns["smooth_lagged_data"] = boolean(false);
  ns["use_control"] = boolean(false);
  ns["control_config"] = config("100001");
  ns["reset_on_time_jump"] = boolean(true);
  const Parsed quiet = parse(ns);
  EXPECT_TRUE(quiet.warnings.empty()) << joined(quiet);
}

TEST(FilterParams, HonouredExtrasAreRead) {
  XmlRpcValue ns = minimal();
  std::vector<XmlRpcValue> x = repeat(integer(0));
  x[0] = num(1.5);
  x[5] = str("3.0e-1");
  ns["initial_state"] = list(x);
  ns["predict_to_current_time"] = boolean(true);
  ns["publish_acceleration"] = boolean(true);
  ns["base_link_frame_output"] = str("base_footprint");
  ns["disabled_at_startup"] = boolean(true);
  ns["silent_tf_failure"] = boolean(true);
  ns["diagnostic_period"] = num(0.5);                            // read by diagnostic_updater itself
  ns["imu0_angular_velocity_rejection_threshold"] = integer(3);  // r_l's documentation's name
  const Parsed p = parse(ns);
  ASSERT_TRUE(p.ok) << p.error;
  EXPECT_EQ(p.params.initial_state(StateMemberX), 1.5);
  EXPECT_EQ(p.params.initial_state(StateMemberYaw), 0.3);
  EXPECT_TRUE(p.params.predict_to_current_time && p.params.publish_acceleration &&
              p.params.disabled_at_startup && p.params.silent_tf_failure);
  EXPECT_EQ(p.params.base_link_output_frame, "base_footprint");
  EXPECT_EQ(p.params.sensors[0].twist_rejection_threshold, 3.0);
  EXPECT_TRUE(anyWarningHas(p, "imu0_angular_velocity_rejection_threshold"));
  EXPECT_FALSE(anyWarningHas(p, "unknown"));
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}

// ~effective_config (effective_config.h): the parsed values read back through a JSON parser, and a
// key that is not UTF-8 (XmlRpc strings are bytes) ends up in the warnings without an exception.
TEST(EffectiveConfig, JsonHoldsTheParsedValuesAndSurvivesNonUtf8) {
  XmlRpcValue ns = minimal();
  ns["frequency"] = num(42.5);
  ns["bad\xff key"] = boolean(true);  // unknown, listed in the warnings
  const Parsed p = parse(ns);
  ASSERT_TRUE(p.ok) << p.error;
  StateMatrix q = p.params.process_noise_covariance;
  q(0, 1) = 0.25;
  std::string text;
  ASSERT_NO_THROW(text = effectiveConfigJson(p.params, q, p.params.initial_estimate_covariance, p.warnings));
  const nlohmann::json j = nlohmann::json::parse(text);
  EXPECT_EQ(j["frequency"].get<double>(), 42.5);
  EXPECT_EQ(j["process_noise_covariance"].size(), 225u);
  EXPECT_EQ(j["process_noise_covariance"][1].get<double>(), 0.25);  // row-major
  ASSERT_EQ(j["sensors"].size(), p.params.sensors.size());
  EXPECT_EQ(j["sensors"][0]["name"].get<std::string>(), p.params.sensors[0].name);
  EXPECT_EQ(j["sensors"][0]["config"].size(), static_cast<size_t>(STATE_SIZE));
  ASSERT_EQ(j["warnings"].size(), p.warnings.size());
  EXPECT_NE(j["warnings"].back().get<std::string>().find("unknown parameters"), std::string::npos);
}
