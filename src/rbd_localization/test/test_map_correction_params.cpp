// validateMapCorrectionParams: the defaults pass, each rule refuses its bad value with its reason.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <string>

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

}  // namespace
}  // namespace rbd_localization

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
