// The ROS-free map, matcher and map correction on a synthetic room.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "rbd_localization/filter_common.h"
#include "rbd_localization/geometry.h"
#include "rbd_localization/map_correction.h"
#include "rbd_localization/occupancy_map.h"
#include "rbd_localization/scan_matcher.h"
#include "synthetic_room.h"

using namespace rbd_localization;                // NOLINT
using namespace rbd_localization::testing_room;  // NOLINT

namespace {

OccupancyMap builtMap(std::mt19937* rng, int scans = 10) {
  OccupancyMap map;
  const auto walls = room();
  for (int i = 0; i < scans; ++i) {
    map.insertScan(pose2d(0, 0, 0), castScan(pose2d(0, 0, 0), walls, {}, 1024, 0.01, rng), 1.0);
  }
  map.updateDistanceField();
  return map;
}

double yawErr(const Eigen::Isometry2d& a, const Eigen::Isometry2d& b) {
  return std::fabs(wrapAngle(yawOf(a) - yawOf(b)));
}

}  // namespace

TEST(OccupancyMap, DistanceFieldIsEuclidean) {
  OccupancyMap::Params p;
  p.size = 4.0;
  OccupancyMap map(p);
  // One occupied cell at the origin, built from repeated hits.
  Points2d one{Eigen::Vector2d(1.0, 0.0)};
  for (int i = 0; i < 5; ++i) map.insertScan(pose2d(0, 0, 0), one, 1.0);
  EXPECT_EQ(map.occupiedCount(), 1);
  map.updateDistanceField();
  int cx, cy;
  ASSERT_TRUE(map.cellOf(Eigen::Vector2d(1.0, 0.0), &cx, &cy));
  const Eigen::Vector2d centre(map.originX() + (cx + 0.5) * p.resolution,
                               map.originY() + (cy + 0.5) * p.resolution);
  double d;
  Eigen::Vector2d g;
  ASSERT_TRUE(map.distance(centre + Eigen::Vector2d(0.3, 0.4), &d, &g));
  EXPECT_NEAR(d, 0.5, 1e-6);
  EXPECT_NEAR(g.x(), 0.6, 0.1);  // unit vector away from the cell
  EXPECT_NEAR(g.y(), 0.8, 0.1);
  ASSERT_TRUE(map.distance(centre + Eigen::Vector2d(-1.5, 0.0), &d, &g));
  EXPECT_NEAR(d, p.max_distance, 1e-6);  // saturated
  // Cells the beam crossed are free, the origin cell too; unknown elsewhere.
  const auto data = map.toOccupancyData();
  ASSERT_TRUE(map.cellOf(Eigen::Vector2d(0.5, 0.0), &cx, &cy));
  EXPECT_LT(data[cy * map.width() + cx], 50);
  EXPECT_GE(data[cy * map.width() + cx], 0);
  ASSERT_TRUE(map.cellOf(Eigen::Vector2d(0.0, 1.0), &cx, &cy));
  EXPECT_EQ(data[cy * map.width() + cx], -1);
}

TEST(ScanMatcher, RecoversKnownOffsetInRoom) {
  std::mt19937 rng(1);
  const OccupancyMap map = builtMap(&rng);
  const ScanMatcher matcher;
  const Eigen::Isometry2d truth = pose2d(1.2, 0.4, 0.6);
  const Points2d scan = castScan(truth, room(), {}, 1024, 0.01, &rng);
  const Eigen::Isometry2d prior = pose2d(1.2 + 0.2, 0.4 - 0.15, 0.6 + 0.08);
  const ScanMatcher::Result r = matcher.match(map, scan, prior);
  EXPECT_LT((r.pose.translation() - truth.translation()).norm(), 0.02);
  EXPECT_LT(yawErr(r.pose, truth), 0.01);  // 0.57 deg; 5 cm cells quantise the walls
  EXPECT_GT(r.inlier_ratio, 0.9);
  EXPECT_LT(r.rms, 0.03);
  // The prior alone is a poor fit: the gate can tell the two apart.
  ScanMatcher::Params one_step;
  one_step.max_iterations = 1;
  one_step.outlier_distance_start = one_step.outlier_distance_end = 0.1;
  const ScanMatcher::Result at_prior = ScanMatcher(one_step).match(map, scan, prior);
  EXPECT_LT(at_prior.inlier_ratio, r.inlier_ratio);
}

TEST(ScanMatcher, PeopleNearTheRobotDoNotPullTheMatch) {
  std::mt19937 rng(2);
  const OccupancyMap map = builtMap(&rng);
  const Eigen::Isometry2d truth = pose2d(0.5, 0.3, -0.3);
  // A crowd around the robot, all on one side (a systematic pull if they were trusted).
  const std::vector<Circle> people = {{{1.3, 0.3}, 0.25}, {{1.1, 1.0}, 0.25}, {{1.0, -0.5}, 0.25},
                                      {{1.8, 0.6}, 0.25}, {{0.6, 1.2}, 0.2},  {{1.6, -0.2}, 0.25}};
  const Points2d scan = castScan(truth, room(), people, 1024, 0.01, &rng);
  const ScanMatcher::Result r = ScanMatcher().match(map, scan, pose2d(0.62, 0.2, -0.25));
  EXPECT_LT((r.pose.translation() - truth.translation()).norm(), 0.03);
  EXPECT_LT(yawErr(r.pose, truth), 0.01);
  EXPECT_LT(r.inlier_ratio, 0.85);  // the people really occluded part of the room
  EXPECT_GT(r.inlier_ratio, 0.4);
}

TEST(MapCorrection, BuildsMapThenCorrectsDriftingOdometry) {
  std::mt19937 rng(3);
  MapCorrection::Params p;
  MapCorrection mc(p);
  const auto walls = room();
  double t = 0.0;
  // Static at the origin while mapping.
  for (int i = 0; i < 25 && mc.mapping(); ++i, t += 0.1) {
    const auto u = mc.processScan(t, castScan(pose2d(0, 0, 0), walls, {}, 1024, 0.01, &rng), pose2d(0, 0, 0));
    EXPECT_EQ(u.status, MapCorrection::Status::kMapping);
  }
  ASSERT_FALSE(mc.mapping());
  EXPECT_GT(mc.map().occupiedCount(), 300);
  // Drive a square loop; odometry drifts (scale 3 % + heading 2 deg per metre).
  int accepted = 0;
  Eigen::Isometry2d truth = pose2d(0, 0, 0), odom = pose2d(0, 0, 0);
  for (int k = 0; k < 400; ++k, t += 0.1) {
    const double v = 0.3 * 0.1, w = (k % 100 < 80) ? 0.0 : (M_PI / 2) / 20.0;
    truth = truth * pose2d(v, 0, w);
    odom = odom * pose2d(v * 1.03, 0, w + 0.035 * v);
    const Points2d scan = castScan(truth, walls, {}, 1024, 0.01, &rng);
    const auto u = mc.processScan(t, scan, odom);
    if (u.status == MapCorrection::Status::kAccepted) ++accepted;
  }
  const Eigen::Isometry2d est = mc.mapFromOdom() * odom;
  const Eigen::Isometry2d uncorrected = odom;
  EXPECT_GT(accepted, 350);
  EXPECT_LT((est.translation() - truth.translation()).norm(), 0.04);
  EXPECT_LT(yawErr(est, truth), 0.01);
  EXPECT_GT((uncorrected.translation() - truth.translation()).norm(), 0.2);  // drift was real
}

TEST(MapCorrection, GatesBadFitsAndLimitsJumpRate) {
  std::mt19937 rng(4);
  MapCorrection::Params p;
  p.initial_mapping_duration = 0.0;
  p.initial_mapping_min_scans = 5;
  MapCorrection mc(p);
  const auto walls = room();
  double t = 0.0;
  while (mc.mapping()) {
    mc.processScan(t, castScan(pose2d(0, 0, 0), walls, {}, 1024, 0.01, &rng), pose2d(0, 0, 0));
    t += 0.1;
  }
  // A scan from a different room (random clutter) is rejected on fit quality.
  std::vector<Segment> other = {{{-1, 0.7}, {1, 0.9}}, {{0.4, -2}, {0.9, 2}}, {{-2, -1}, {-1.7, 1.5}}};
  auto u = mc.processScan(t, castScan(pose2d(0, 0, 0), other, {}, 1024, 0.01, &rng), pose2d(0, 0, 0));
  EXPECT_EQ(u.status, MapCorrection::Status::kRejectedFit) << u.reason;
  EXPECT_TRUE(mc.mapFromOdom().isApprox(Eigen::Isometry2d::Identity()));
  // Odometry 0.3 m off after 2 s of refused scans: matched, but the corrected pose moves by at
  // most max_correction_step per scan (the speed limit alone would allow 0.5 m/s * 1 s).
  t += 2.0;
  u = mc.processScan(t, castScan(pose2d(0, 0, 0), walls, {}, 1024, 0.01, &rng), pose2d(0.3, 0, 0));
  ASSERT_EQ(u.status, MapCorrection::Status::kAccepted) << u.reason;
  double previous = (mc.mapFromOdom() * pose2d(0.3, 0, 0)).translation().x();
  EXPECT_NEAR(previous, 0.3 - p.max_correction_step, 1e-6);
  for (int i = 0; i < 20; ++i) {
    t += 0.1;
    mc.processScan(t, castScan(pose2d(0, 0, 0), walls, {}, 1024, 0.01, &rng), pose2d(0.3, 0, 0));
    const double x = (mc.mapFromOdom() * pose2d(0.3, 0, 0)).translation().x();
    EXPECT_LE(std::fabs(x - previous), p.max_correction_step + 1e-9) << "scan " << i;
    previous = x;
  }
  EXPECT_NEAR(previous, 0.0, 0.02);
  // Scans 0.02 s apart: the speed limit (0.5 m/s) is the tighter bound, 0.01 m per scan.
  t += 0.1;
  mc.processScan(t, castScan(pose2d(0, 0, 0), walls, {}, 1024, 0.01, &rng), pose2d(0.4, 0, 0));
  previous = (mc.mapFromOdom() * pose2d(0.4, 0, 0)).translation().x();
  t += 0.02;
  mc.processScan(t, castScan(pose2d(0, 0, 0), walls, {}, 1024, 0.01, &rng), pose2d(0.4, 0, 0));
  EXPECT_NEAR(previous - (mc.mapFromOdom() * pose2d(0.4, 0, 0)).translation().x(), 0.5 * 0.02, 1e-4);
  // A 2 m jump of the prior is refused outright.
  t += 0.1;
  u = mc.processScan(t, castScan(pose2d(0, 0, 0), walls, {}, 1024, 0.01, &rng),
                     pose2d(0.3, 0.0, 0.0) * pose2d(2.0, 0, 0));
  EXPECT_NE(u.status, MapCorrection::Status::kAccepted);
  // Too few points: refused, no crash.
  u = mc.processScan(t, Points2d{}, pose2d(0, 0, 0));
  EXPECT_EQ(u.status, MapCorrection::Status::kRejectedEmpty);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
