// validateMapCorrectionParams: the defaults pass, each rule refuses its bad value with its reason.
// parseMapCorrectionParams: a private namespace as the parameter server delivers it (XmlRpc values
// of YAML's types) is read into the right fields; a value of the wrong type is an error naming the
// key (roscpp's param() silently kept the default), text numbers and unknown keys are warnings.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "rbd_localization/map_correction_params.h"

namespace rbd_localization {
namespace {

struct Case {
  std::function<void(MapCorrectionNodeParams*, MapCorrection::Params*)> spoil;
  std::string reason;  ///< a part of the expected error
};

TEST(MapCorrectionParams, DefaultsAreValid) {
  std::string error;
  EXPECT_TRUE(validateMapCorrectionParams(MapCorrectionNodeParams(), MapCorrection::Params(), &error))
      << error;
  MapCorrectionNodeParams n;
  n.input = "points";
  n.home_x = 1.0;
  n.home_y = -2.0;
  n.home_yaw = 0.5;
  EXPECT_TRUE(validateMapCorrectionParams(n, MapCorrection::Params(), &error)) << error;
}

TEST(MapCorrectionParams, EachBadValueIsRefusedWithItsReason) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  const Case cases[] = {
      {[](MapCorrectionNodeParams* n, MapCorrection::Params*) { n->input = "laser"; }, "input must be"},
      {[](MapCorrectionNodeParams* n, MapCorrection::Params*) { n->slice_z_max = n->slice_z_min; },
       "slice_z_max"},
      {[](MapCorrectionNodeParams* n, MapCorrection::Params*) { n->slice_bins = 35; }, "slice_bins >= 36"},
      {[](MapCorrectionNodeParams* n, MapCorrection::Params*) { n->odom_frame = "map"; },
       "map_frame != odom_frame"},
      {[](MapCorrectionNodeParams* n, MapCorrection::Params*) { n->base_frame = ""; }, "must be set"},
      {[nan](MapCorrectionNodeParams* n, MapCorrection::Params*) { n->max_match_rate = nan; }, "rates"},
      {[](MapCorrectionNodeParams* n, MapCorrection::Params*) { n->max_points = 9; }, "max_points >= 10"},
      {[](MapCorrectionNodeParams* n, MapCorrection::Params*) { n->max_range = n->min_range; }, "max_range"},
      {[](MapCorrectionNodeParams*, MapCorrection::Params* c) { c->map.max_size = c->map.size / 2; },
       "map_max_size"},
      {[](MapCorrectionNodeParams*, MapCorrection::Params* c) { c->map.size = 8001 * c->map.resolution; },
       "8000 cells"},
      {[](MapCorrectionNodeParams*, MapCorrection::Params* c) { c->search_rotation = 4.0; },
       "search_rotation"},
      {[](MapCorrectionNodeParams*, MapCorrection::Params* c) { c->localized_scans = 0; },
       "localized_scans >= 1"},
      {[](MapCorrectionNodeParams*, MapCorrection::Params* c) { c->ambiguity_margin = -0.01; },
       "ambiguity_margin in [0, 0.3]"},
      {[](MapCorrectionNodeParams*, MapCorrection::Params* c) { c->ambiguity_step = 0.01; },
       "ambiguity_step in [0.05, 1]"},
      {[nan](MapCorrectionNodeParams*, MapCorrection::Params* c) { c->ambiguity_angle_step = nan; },
       "ambiguity_angle_step"},
      {[](MapCorrectionNodeParams*, MapCorrection::Params* c) { c->ambiguity_rotation = 4.0; },
       "ambiguity_rotation in [0, pi]"},
      {[inf](MapCorrectionNodeParams*, MapCorrection::Params* c) { c->ambiguity_retry_interval = inf; },
       "ambiguity_retry_interval >= 0"},
      {[nan](MapCorrectionNodeParams* n, MapCorrection::Params*) { n->home_x = 1.0; }, "all three"},
      {[inf](MapCorrectionNodeParams* n, MapCorrection::Params*) {
         n->home_x = inf;
         n->home_y = 0.0;
         n->home_yaw = 0.0;
       },
       "all three"},
      {[](MapCorrectionNodeParams*, MapCorrection::Params* c) {
         c->matcher.outlier_distance_start = c->matcher.outlier_distance_end / 2;
       },
       "outlier_distance_start"},
      {[](MapCorrectionNodeParams*, MapCorrection::Params* c) { c->matcher.inlier_distance = 0.0; },
       "inlier_distance > 0"},
  };
  int i = 0;
  for (const Case& k : cases) {
    MapCorrectionNodeParams n;
    MapCorrection::Params c;
    k.spoil(&n, &c);
    std::string error;
    EXPECT_FALSE(validateMapCorrectionParams(n, c, &error)) << "case " << i;
    EXPECT_NE(error.find(k.reason), std::string::npos) << "case " << i << ": " << error;
    ++i;
  }
}

XmlRpc::XmlRpcValue text(const char* s) { return XmlRpc::XmlRpcValue(std::string(s)); }

TEST(MapCorrectionParams, ParsesEveryTypeIntoItsField) {
  XmlRpc::XmlRpcValue ns;
  ns["map_size"] = 40;  // an int where a number is expected: YAML writes 40, not 40.0
  ns["resolution"] = 0.1;
  ns["max_points"] = 500;
  ns["correction_enabled"] = false;
  ns["input"] = text("points");
  ns["home_x"] = 1.5;
  ns["home_y"] = -2.0;
  ns["home_yaw"] = 0;
  ns["outlier_distance"] = 0.2;
  ns["max_iterations"] = 7;
  ns["ambiguity_check"] = false;
  ns["ambiguity_margin"] = 0.02;
  ns["ambiguity_translation"] = 1;  // an int where a number is expected
  MapCorrectionNodeParams n;
  MapCorrection::Params c;
  std::vector<std::string> warnings;
  std::string error;
  ASSERT_TRUE(parseMapCorrectionParams(ns, &n, &c, &warnings, &error)) << error;
  EXPECT_TRUE(warnings.empty()) << warnings.front();
  EXPECT_DOUBLE_EQ(c.map.size, 40.0);
  EXPECT_DOUBLE_EQ(c.map.resolution, 0.1);
  EXPECT_EQ(n.max_points, 500);
  EXPECT_FALSE(n.correction_enabled);
  EXPECT_EQ(n.input, "points");
  EXPECT_DOUBLE_EQ(n.home_x, 1.5);
  EXPECT_DOUBLE_EQ(n.home_y, -2.0);
  EXPECT_DOUBLE_EQ(n.home_yaw, 0.0);
  EXPECT_DOUBLE_EQ(c.matcher.outlier_distance_end, 0.2);
  EXPECT_EQ(c.matcher.max_iterations, 7);
  EXPECT_FALSE(c.ambiguity_check);
  EXPECT_DOUBLE_EQ(c.ambiguity_margin, 0.02);
  EXPECT_DOUBLE_EQ(c.ambiguity_translation, 1.0);
  // untouched keys keep their defaults
  EXPECT_EQ(n.map_frame, MapCorrectionNodeParams().map_frame);
  EXPECT_DOUBLE_EQ(c.map_update_weight, MapCorrection::Params().map_update_weight);
}

TEST(MapCorrectionParams, NoNamespaceGivesTheDefaults) {
  MapCorrectionNodeParams n;
  MapCorrection::Params c;
  std::vector<std::string> warnings;
  std::string error;
  EXPECT_TRUE(parseMapCorrectionParams(XmlRpc::XmlRpcValue(), &n, &c, &warnings, &error)) << error;
  EXPECT_TRUE(warnings.empty());
  EXPECT_EQ(n.max_points, MapCorrectionNodeParams().max_points);
}

TEST(MapCorrectionParams, AValueOfTheWrongTypeIsAnErrorNamingTheKey) {
  struct Bad {
    const char* key;
    XmlRpc::XmlRpcValue value;
    const char* reason;
  };
  const Bad cases[] = {
      {"correction_enabled", text("yes"), "correction_enabled must be true or false, got the string 'yes'"},
      {"max_range", text("far"), "max_range must be a number, got the string 'far'"},
      {"map_frame", XmlRpc::XmlRpcValue(3), "map_frame must be a string, got the integer 3"},
      {"slice_bins", XmlRpc::XmlRpcValue(true), "slice_bins must be a number"},
      {"max_points", XmlRpc::XmlRpcValue(5), "max_points >= 10"},  // read, then refused by the validation
  };
  for (const Bad& b : cases) {
    XmlRpc::XmlRpcValue ns;
    ns[b.key] = b.value;
    MapCorrectionNodeParams n;
    MapCorrection::Params c;
    std::vector<std::string> warnings;
    std::string error;
    EXPECT_FALSE(parseMapCorrectionParams(ns, &n, &c, &warnings, &error)) << b.key;
    EXPECT_NE(error.find(b.reason), std::string::npos) << b.key << ": " << error;
  }
}

TEST(MapCorrectionParams, TextNumbersAndUnknownKeysAreWarnings) {
  XmlRpc::XmlRpcValue ns;
  ns["map_update_weight"] = text("5e-1");  // YAML 1.1: text, not a number
  ns["map_sise"] = 40.0;                   // a typo of map_size
  ns["max_match_rate"] = 9.5;
  MapCorrectionNodeParams n;
  MapCorrection::Params c;
  std::vector<std::string> warnings;
  std::string error;
  ASSERT_TRUE(parseMapCorrectionParams(ns, &n, &c, &warnings, &error)) << error;
  EXPECT_DOUBLE_EQ(c.map_update_weight, 0.5);
  EXPECT_DOUBLE_EQ(n.max_match_rate, 9.5);
  EXPECT_DOUBLE_EQ(c.map.size, MapCorrection::Params().map.size);
  ASSERT_EQ(warnings.size(), 2u);
  EXPECT_NE(warnings[0].find("map_update_weight is the string '5e-1'"), std::string::npos) << warnings[0];
  EXPECT_EQ(warnings[0].find("robot_localization"), std::string::npos) << warnings[0];
  EXPECT_EQ(warnings[1], "unknown parameters, ignored: map_sise");
}

}  // namespace
}  // namespace rbd_localization

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
