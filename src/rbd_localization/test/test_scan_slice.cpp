// The levelled 2D slice of a 3D cloud: a tilted body (attentive nose-up pitch, wiggle roll)
// must give the same 2D scan as a level one, so the match does not settle off while standing.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "rbd_localization/geometry.h"
#include "rbd_localization/occupancy_map.h"
#include "rbd_localization/scan_matcher.h"
#include "rbd_localization/scan_slice.h"
#include "synthetic_room.h"

namespace rbd_localization {
namespace {

using testing_room::Segment;

const double kWallHeight = 2.8;
const double kBaseHeight = 0.28;

/// Mount of the OS1 on the A1's back (base_link -> os_sensor).
Eigen::Isometry3d mount() {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() = Eigen::Vector3d(-0.05, 0.0, 0.12);
  return t;
}

/// Robot at (x, y, yaw) on the floor with body roll/pitch: world_from_base.
Eigen::Isometry3d body(double x, double y, double yaw, double roll, double pitch,
                       double height = kBaseHeight) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = rotationFromRpy(roll, pitch, yaw);
  t.translation() = Eigen::Vector3d(x, y, height);
  return t;
}

/// OS1-32-like cloud (32 beams over +-22.5 deg, `columns` azimuths) of the room's walls
/// (kWallHeight tall) and the floor, in the sensor frame.
std::vector<Eigen::Vector3d> castCloud(const Eigen::Isometry3d& world_from_base, int columns = 512) {
  const std::vector<Segment> walls = testing_room::room();
  const Eigen::Isometry3d world_from_sensor = world_from_base * mount();
  const Eigen::Vector3d o = world_from_sensor.translation();
  std::vector<Eigen::Vector3d> out;
  for (int beam = 0; beam < 32; ++beam) {
    const double el = (-22.5 + 45.0 * beam / 31.0) * M_PI / 180.0;
    for (int col = 0; col < columns; ++col) {
      const double az = -M_PI + 2.0 * M_PI * col / columns;
      const Eigen::Vector3d ds(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
      const Eigen::Vector3d d = world_from_sensor.linear() * ds;
      double best = std::numeric_limits<double>::infinity();
      if (d.z() < -1e-9) best = -o.z() / d.z();  // floor
      const double h = std::hypot(d.x(), d.y());
      if (h > 1e-9) {
        for (const Segment& w : walls) {
          const Eigen::Vector2d e = w.b - w.a, ao = w.a - o.head<2>();
          const double den = d.x() * e.y() - d.y() * e.x();
          if (std::fabs(den) < 1e-12) continue;
          const double t = (ao.x() * e.y() - ao.y() * e.x()) / den;
          const double u = (ao.x() * d.y() - ao.y() * d.x()) / den;
          const double z = o.z() + t * d.z();
          if (t > 0 && u >= 0 && u <= 1 && z >= 0.0 && z <= kWallHeight) best = std::min(best, t);
        }
      }
      if (best < 50.0) out.push_back(ds * best);
    }
  }
  return out;
}

double distanceToWalls(const Eigen::Vector2d& p) {
  double best = std::numeric_limits<double>::infinity();
  for (const Segment& w : testing_room::room()) {
    const Eigen::Vector2d e = w.b - w.a;
    const double u = std::max(0.0, std::min(1.0, (p - w.a).dot(e) / e.squaredNorm()));
    best = std::min(best, (w.a + u * e - p).norm());
  }
  return best;
}

ScanSlicer::Params sliceParams() {
  ScanSlicer::Params p;
  p.max_points = 720;
  return p;
}

Points2d slice(const std::vector<Eigen::Vector3d>& cloud, const Eigen::Matrix3d& level) {
  ScanSlicer s(sliceParams());
  s.begin(mount(), level);
  for (const auto& p : cloud) s.add(p);
  return s.finish();
}

/// Largest and mean distance of the slice (placed at the robot's planar pose) from the walls.
void wallError(const Points2d& pts, double x, double y, double yaw, double* max_err, double* mean_err) {
  const Eigen::Isometry2d pose = pose2d(x, y, yaw);
  *max_err = 0.0;
  double sum = 0.0;
  for (const auto& p : pts) {
    const double d = distanceToWalls(pose * p);
    *max_err = std::max(*max_err, d);
    sum += d;
  }
  *mean_err = pts.empty() ? 0.0 : sum / pts.size();
}

TEST(ScanSlice, LevelFromBaseRemovesOnlyRollAndPitch) {
  const Eigen::Matrix3d r = rotationFromRpy(0.2, -0.25, 1.3);
  const Eigen::Vector3d rpy = rpyFromRotation(levelFromBase(r));
  EXPECT_NEAR(rpy(0), 0.2, 1e-9);
  EXPECT_NEAR(rpy(1), -0.25, 1e-9);
  EXPECT_NEAR(rpy(2), 0.0, 1e-9);
  // A base_link vector rotated into the levelled frame has the world's height component.
  const Eigen::Vector3d v(1.0, 0.3, -0.2);
  EXPECT_NEAR((levelFromBase(r) * v).z(), (r * v).z(), 1e-12);
}

TEST(ScanSlice, TiltedBodyGivesTheLevelSlice) {
  const double x = 0.3, y = 0.2, yaw = 0.4;
  struct Tilt {
    double roll, pitch;
  };
  // level, the attentive nose-up pitch, the wiggle's rolls, a nose-down pitch
  for (const Tilt& t : {Tilt{0.0, 0.0}, Tilt{0.0, -0.25}, Tilt{0.3, 0.0}, Tilt{-0.3, 0.0}, Tilt{0.1, 0.15}}) {
    const Eigen::Isometry3d b = body(x, y, yaw, t.roll, t.pitch);
    const std::vector<Eigen::Vector3d> cloud = castCloud(b);
    const Points2d pts = slice(cloud, levelFromBase(b.linear()));
    double max_err, mean_err;
    wallError(pts, x, y, yaw, &max_err, &mean_err);
    EXPECT_GT(pts.size(), 400u) << "roll " << t.roll << " pitch " << t.pitch;
    EXPECT_LT(max_err, 0.01) << "roll " << t.roll << " pitch " << t.pitch;  // no floor, no shortened range
  }
  // The unlevelled slice (the old behaviour) of the nose-up body is far off the walls: floor
  // returns behind the robot and ranges shortened by cos(pitch).
  const Eigen::Isometry3d b = body(x, y, yaw, 0.0, -0.25);
  double max_err, mean_err;
  wallError(slice(castCloud(b), Eigen::Matrix3d::Identity()), x, y, yaw, &max_err, &mean_err);
  EXPECT_GT(max_err, 0.5);
  EXPECT_GT(mean_err, 0.05);
}

TEST(ScanSlice, LoweredBodyKeepsTheSliceOnTheWalls) {
  // lie_down: the body 0.16 m lower and pitched; the band moves with the body, stays on walls.
  const Eigen::Isometry3d b = body(-0.5, 0.1, -2.0, 0.05, -0.1, kBaseHeight - 0.16);
  const Points2d pts = slice(castCloud(b), levelFromBase(b.linear()));
  double max_err, mean_err;
  wallError(pts, -0.5, 0.1, -2.0, &max_err, &mean_err);
  EXPECT_GT(pts.size(), 400u);
  EXPECT_LT(max_err, 0.01);
}

TEST(ScanSlice, MatchOfTiltedScanStaysAtTheTruePose) {
  // Map from the level robot, then the attentive (nose-up) robot at the same pose: the match
  // from the true pose must stay where the level robot's matches (it settled 0.18 m off in the
  // simulator without levelling; here the unlevelled slice matches ~0.14 m off).
  const double x = 0.0, y = 0.0, yaw = 0.0;
  OccupancyMap::Params mp;
  mp.resolution = 0.05;
  mp.size = 20.0;
  OccupancyMap map(mp);
  const Eigen::Isometry3d level_body = body(x, y, yaw, 0.0, 0.0);
  for (int i = 0; i < 5; ++i)
    map.insertScan(pose2d(x, y, yaw), slice(castCloud(level_body), Eigen::Matrix3d::Identity()), 1.0);
  map.updateDistanceField();
  ScanMatcher::Params sp;
  sp.outlier_distance_start = 0.25;
  sp.outlier_distance_end = 0.10;
  const ScanMatcher matcher(sp);
  const ScanMatcher::Result ref =
      matcher.match(map, slice(castCloud(level_body), Eigen::Matrix3d::Identity()), pose2d(x, y, yaw));
  const Eigen::Isometry3d tilted = body(x, y, yaw, 0.0, -0.25);
  const std::vector<Eigen::Vector3d> cloud = castCloud(tilted);
  const ScanMatcher::Result good =
      matcher.match(map, slice(cloud, levelFromBase(tilted.linear())), pose2d(x, y, yaw));
  // Against the level robot's own match (the 5 cm grid puts these walls on cell borders, which
  // biases both alike by up to half a cell).
  EXPECT_LT((good.pose.translation() - ref.pose.translation()).norm(), 0.01);
  EXPECT_LT(std::fabs(yawOf(good.pose) - yawOf(ref.pose)), 0.005);
  EXPECT_GT(good.inlier_ratio, 0.9);
  const ScanMatcher::Result bad =
      matcher.match(map, slice(cloud, Eigen::Matrix3d::Identity()), pose2d(x, y, yaw));
  std::cout << "unlevelled match of the nose-up scan: " << bad.pose.translation().transpose() << " inliers "
            << bad.inlier_ratio << std::endl;
  EXPECT_GT((bad.pose.translation() - ref.pose.translation()).norm(), 0.05);
}

TEST(ScanSlice, PlanarScanIsLevelledAndRangeGated) {
  ScanSlicer::Params p;
  p.min_range = 0.3;
  p.max_range = 10.0;
  ScanSlicer s(p);
  // Sensor frame = base_link, body pitched nose-up 0.25 rad: a return 4 m along the scan's x
  // axis is 4 cos(0.25) m away horizontally.
  s.begin(Eigen::Isometry3d::Identity(), levelFromBase(rotationFromRpy(0.0, -0.25, 0.0)));
  const Points2d out =
      s.levelPlanar({Eigen::Vector3d(4.0, 0.0, 0.0), Eigen::Vector3d(0.1, 0.0, 0.0),
                     Eigen::Vector3d(20.0, 0.0, 0.0), Eigen::Vector3d(std::nan(""), 0.0, 0.0)});
  ASSERT_EQ(out.size(), 1u);
  EXPECT_NEAR(out[0].x(), 4.0 * std::cos(0.25), 1e-9);
  EXPECT_NEAR(out[0].y(), 0.0, 1e-9);
}

}  // namespace
}  // namespace rbd_localization

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
