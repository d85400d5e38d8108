// Saved maps (map_server PGM + YAML + sidecar), localization mode in a loaded map, visitors that
// must not become walls, and a grid that grows with the area explored.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <random>
#include <sstream>
#include <string>

#include "rbd_localization/filter_common.h"
#include "rbd_localization/geometry.h"
#include "rbd_localization/map_correction.h"
#include "rbd_localization/map_io.h"
#include "rbd_localization/occupancy_map.h"
#include "synthetic_room.h"

using namespace rbd_localization;                // NOLINT
using namespace rbd_localization::testing_room;  // NOLINT

namespace {

std::string tempDir() {
  char tmpl[] = "/tmp/rbd_map_test_XXXXXX";
  const char* d = mkdtemp(tmpl);
  return d ? d : "/tmp";
}

std::string readAll(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::ostringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

/// Mapping mode standing at `at` (default the origin of room()) for `seconds` (10 Hz), people
/// around as given.
void standAndMap(MapCorrection* mc, double* t, double seconds, const std::vector<Circle>& people,
                 std::mt19937* rng, const std::vector<Segment>& walls = room(),
                 const Eigen::Isometry2d& at = Eigen::Isometry2d::Identity()) {
  for (double end = *t + seconds; *t < end; *t += 0.1) {
    mc->processScan(*t, castScan(at, walls, people, 720, 0.01, rng), at);
  }
}

double yawErr(const Eigen::Isometry2d& a, const Eigen::Isometry2d& b) {
  return std::fabs(wrapAngle(yawOf(a) - yawOf(b)));
}

/// A saved reference map of a room (mapping mode standing at `at`, 12 s so the walls are static;
/// the map frame is the mapping run's odometry frame, home its origin).
std::string savedRoom(const std::string& dir, std::mt19937* rng, const std::vector<Segment>& walls = room(),
                      const Eigen::Isometry2d& at = Eigen::Isometry2d::Identity()) {
  MapCorrection mc;
  double t = 0.0;
  standAndMap(&mc, &t, 12.0, {}, rng, walls, at);
  std::string error;
  EXPECT_TRUE(saveMap(mc.map(), mc.mapTime(t), Eigen::Vector3d::Zero(), dir, "room", &error)) << error;
  return dir + "/room.yaml";
}

/// Localization mode in a saved map, home at the map origin.
std::unique_ptr<MapCorrection> localizing(const std::string& yaml, const MapCorrection::Params& params) {
  std::unique_ptr<OccupancyMap> ref;
  MapFileInfo info;
  std::string error;
  if (!loadMap(yaml, params.map, 0.0, &ref, &info, &error)) {
    ADD_FAILURE() << error;
    return nullptr;
  }
  std::unique_ptr<MapCorrection> mc(new MapCorrection(params));
  mc->setReference(std::move(ref), pose2d(0, 0, 0));
  return mc;
}

/// What localization mode did with `seconds` of scans (10 Hz) from a robot standing at `truth`.
struct StartRun {
  bool localized = false;
  double localized_after = -1.0;  ///< [s] of scans; -1: never
  int searched = 0, ambiguous = 0, checks = 0;
  std::string last_reason;
  MapCorrection::Update last_check;  ///< the last update that ran the ambiguity check
};

StartRun standAndLocalize(MapCorrection* mc, const std::vector<Segment>& walls,
                          const Eigen::Isometry2d& truth, double seconds, std::mt19937* rng) {
  StartRun run;
  for (double t = 0.0; t < seconds; t += 0.1) {
    const MapCorrection::Update u =
        mc->processScan(t, castScan(truth, walls, {}, 720, 0.01, rng), pose2d(0, 0, 0));
    run.searched += u.status == MapCorrection::Status::kSearched;
    run.ambiguous += u.status == MapCorrection::Status::kRejectedAmbiguous;
    if (u.start_checked) {
      run.last_check = u;
      ++run.checks;
    }
    if (!u.reason.empty()) run.last_reason = u.reason;
    if (mc->localized() && !run.localized) {
      run.localized = true;
      run.localized_after = t;
    }
  }
  return run;
}

double distanceOf(const Eigen::Isometry2d& a, const Eigen::Isometry2d& b) {
  return (a.translation() - b.translation()).norm();
}

int pgmAt(const std::string& pgm_path, const OccupancyMap& m, const Eigen::Vector2d& p) {
  // The PGM read back by its own header: last 'w*h' bytes, row 0 = top (highest y).
  const std::string data = readAll(pgm_path);
  int cx, cy;
  if (!m.cellOf(p, &cx, &cy)) return -1;
  const size_t n = static_cast<size_t>(m.width()) * m.height();
  return static_cast<unsigned char>(
      data[data.size() - n + static_cast<size_t>(m.height() - 1 - cy) * m.width() + cx]);
}

}  // namespace

TEST(MapFiles, SaveLoadRoundTripIsExactAndEditedPgmWins) {
  std::mt19937 rng(11);
  const std::string dir = tempDir();
  MapCorrection mc;
  double t = 0.0;
  standAndMap(&mc, &t, 12.0, {}, &rng);
  std::string error;
  ASSERT_TRUE(saveMap(mc.map(), mc.mapTime(t), Eigen::Vector3d(0.5, -0.25, 0.3), dir, "lab", &error))
      << error;
  const std::string yaml = readAll(dir + "/lab.yaml");
  EXPECT_NE(yaml.find("image: lab.pgm"), std::string::npos);
  EXPECT_NE(yaml.find("mode: trinary"), std::string::npos);
  EXPECT_NE(yaml.find("negate: 0"), std::string::npos);

  std::unique_ptr<OccupancyMap> loaded;
  MapFileInfo info;
  ASSERT_TRUE(loadMap(dir + "/lab.yaml", mc.map().params(), 0.0, &loaded, &info, &error)) << error;
  EXPECT_TRUE(info.exact) << info.note;
  ASSERT_TRUE(info.has_home);
  EXPECT_DOUBLE_EQ(info.home.x(), 0.5);
  EXPECT_DOUBLE_EQ(info.home.z(), 0.3);
  ASSERT_EQ(loaded->width(), mc.map().width());
  ASSERT_EQ(loaded->height(), mc.map().height());
  EXPECT_DOUBLE_EQ(loaded->originX(), mc.map().originX());
  int differ = 0, static_cells = 0;
  for (int cy = 0; cy < loaded->height(); ++cy) {
    for (int cx = 0; cx < loaded->width(); ++cx) {
      differ += loaded->logOdds(cx, cy) != mc.map().logOdds(cx, cy);
      static_cells += mc.map().isStatic(cx, cy, mc.mapTime(t));
      EXPECT_EQ(loaded->isStatic(cx, cy, 0.0), mc.map().isStatic(cx, cy, mc.mapTime(t)));
    }
  }
  EXPECT_EQ(differ, 0);
  EXPECT_GT(static_cells, 300);

  // A map editor paints a wall into the free middle of the room: the PGM is the truth then.
  std::string pgm = readAll(dir + "/lab.pgm");
  const Eigen::Vector2d painted(0.5, 0.5);
  ASSERT_EQ(pgmAt(dir + "/lab.pgm", mc.map(), painted), kPgmFree);
  int cx, cy;
  ASSERT_TRUE(mc.map().cellOf(painted, &cx, &cy));
  const size_t n = static_cast<size_t>(mc.map().width()) * mc.map().height();
  pgm[pgm.size() - n + static_cast<size_t>(mc.map().height() - 1 - cy) * mc.map().width() + cx] = 0;
  ASSERT_TRUE(writeFileAtomic(dir + "/lab.pgm", pgm, &error)) << error;
  ASSERT_TRUE(loadMap(dir + "/lab.yaml", mc.map().params(), 0.0, &loaded, &info, &error)) << error;
  EXPECT_FALSE(info.exact);
  EXPECT_FALSE(info.has_home);
  EXPECT_TRUE(loaded->occupied(cx, cy));
  EXPECT_TRUE(loaded->isStatic(cx, cy, 0.0));

  // Bad files: clear errors, no crash.
  std::ofstream(dir + "/bad.yaml") << "image: missing.pgm\nresolution: 0.05\norigin: [0, 0, 0]\n";
  EXPECT_FALSE(loadMap(dir + "/bad.yaml", mc.map().params(), 0.0, &loaded, &info, &error));
  EXPECT_NE(error.find("missing.pgm"), std::string::npos) << error;
  std::ofstream(dir + "/trunc.pgm") << "P5\n10 10\n255\nabc";
  std::ofstream(dir + "/trunc.yaml") << "image: trunc.pgm\nresolution: 0.05\norigin: [0, 0, 0]\n";
  EXPECT_FALSE(loadMap(dir + "/trunc.yaml", mc.map().params(), 0.0, &loaded, &info, &error));
  EXPECT_NE(error.find("truncated"), std::string::npos) << error;
  EXPECT_FALSE(saveMap(mc.map(), 0.0, Eigen::Vector3d::Zero(), dir + "/no/such/dir", "x", &error));
}

TEST(MapFiles, KilledMidSaveLeavesTheOldOrTheNewMapNeverAHalfOne) {
  // Two maps of the same grid (1200 x 1200 cells: the sidecar is 11.5 MB) with different walls.
  OccupancyMap::Params p;
  p.size = 60.0;
  p.grow = false;
  OccupancyMap a(p), b(p);
  for (int i = 0; i < 1200; ++i) {
    a.setCell(i, 100, 3.5f, -100.0f);
    b.setCell(100, i, 3.5f, -100.0f);
    b.setCell(i, 700, 3.5f, -100.0f);
  }
  const std::string dir = tempDir();
  std::string error;
  ASSERT_TRUE(saveMap(a, 0.0, Eigen::Vector3d::Zero(), dir, "m", &error)) << error;
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> delay_us(0, 150000);
  int seen_a = 0, seen_b = 0;
  for (int k = 0; k < 8; ++k) {
    const pid_t child = fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
      std::string e;
      for (;;) saveMap((k % 2) ? a : b, 0.0, Eigen::Vector3d::Zero(), dir, "m", &e);
    }
    usleep(static_cast<useconds_t>(delay_us(rng)));
    kill(child, SIGKILL);
    waitpid(child, nullptr, 0);
    std::unique_ptr<OccupancyMap> loaded;
    MapFileInfo info;
    ASSERT_TRUE(loadMap(dir + "/m.yaml", p, 0.0, &loaded, &info, &error)) << "kill " << k << ": " << error;
    const int occ = loaded->occupiedCount();
    EXPECT_TRUE(occ == a.occupiedCount() || occ == b.occupiedCount()) << "kill " << k << ": " << occ;
    seen_a += occ == a.occupiedCount();
    seen_b += occ == b.occupiedCount();
  }
  EXPECT_GT(seen_a + seen_b, 0);
}

TEST(Localization, StartsAwayFromHomeAndConverges) {
  std::mt19937 rng(12);
  const std::string dir = tempDir();
  const std::string yaml = savedRoom(dir, &rng);
  // 0.8 m / 40 deg and 1.0 m / -45 deg away from home (the map origin).
  const std::vector<Eigen::Isometry2d> starts = {
      pose2d(0.8 * std::cos(2.0), 0.8 * std::sin(2.0), 40 * M_PI / 180), pose2d(0.7, -0.7, -45 * M_PI / 180)};
  for (const Eigen::Isometry2d& truth : starts) {
    std::unique_ptr<OccupancyMap> ref;
    MapFileInfo info;
    std::string error;
    MapCorrection::Params params;
    ASSERT_TRUE(loadMap(yaml, params.map, 0.0, &ref, &info, &error)) << error;
    MapCorrection mc(params);
    mc.setReference(std::move(ref), pose2d(0, 0, 0));
    EXPECT_FALSE(mc.localized());
    double t = 0.0;
    const std::vector<Circle> people = {{{1.5, 1.5}, 0.25}, {{-1.0, 1.0}, 0.25}};
    for (; t < 5.0 && !mc.localized(); t += 0.1) {
      mc.processScan(t, castScan(truth, room(), people, 720, 0.01, &rng), pose2d(0, 0, 0));
    }
    ASSERT_TRUE(mc.localized()) << "not localized within 5 s";
    const Eigen::Isometry2d est = mc.mapFromOdom();
    EXPECT_LT((est.translation() - truth.translation()).norm(), 0.05);
    EXPECT_LT(yawErr(est, truth), 2 * M_PI / 180);
  }
}

// A room whose walls are point-symmetric about its centre: every pose has a twin (turned 180 deg
// about the centre) that sees exactly the same scan. Home (the map origin) is 1 m from the centre;
// the robot starts within the search around home, its twin outside the search's headings.
TEST(Localization, StartInAPointSymmetricRoomIsAmbiguousNeverLocalized) {
  std::mt19937 rng(21);
  const auto walls = symmetricRoom(false);
  // the map from the room's centre (its unknown cells, behind the pillars, are symmetric too)
  const std::string yaml = savedRoom(tempDir(), &rng, walls, pose2d(1.0, 0.0, 0.0));
  const Eigen::Isometry2d truth = pose2d(0.5, -0.4, 30 * M_PI / 180);
  const Eigen::Isometry2d twin = symmetricTwin(truth);  // (1.5, 0.4, -150 deg): outside +-0.9 rad
  MapCorrection::Params params;
  // Without the check the search's answer is taken (right by luck: the map cannot tell).
  params.ambiguity_check = false;
  auto unchecked = localizing(yaml, params);
  ASSERT_TRUE(unchecked);
  const StartRun blind = standAndLocalize(unchecked.get(), walls, truth, 3.0, &rng);
  ASSERT_TRUE(blind.localized) << blind.last_reason;
  // With it: the twin fits as well, the start is ambiguous, never taken, never localized.
  params.ambiguity_check = true;
  auto mc = localizing(yaml, params);
  ASSERT_TRUE(mc);
  const StartRun run = standAndLocalize(mc.get(), walls, truth, 6.0, &rng);
  EXPECT_FALSE(run.localized) << "localized after " << run.localized_after << " s";
  EXPECT_EQ(run.searched, 0);
  EXPECT_GE(run.ambiguous, 55);  // every scan refused
  EXPECT_NE(run.last_reason.find("start search: ambiguous: another pose ("), std::string::npos)
      << run.last_reason;
  // searched and checked again after each retry interval (2 s): 3 times in 6 s, not at every scan
  EXPECT_GE(run.checks, 2);
  EXPECT_LE(run.checks, 4);
  ASSERT_TRUE(run.last_check.start_checked);
  const MapCorrection::Update& c = run.last_check;
  EXPECT_LT(distanceOf(c.match.pose, truth), 0.05);  // the search found the truth ...
  ASSERT_TRUE(c.rival.found);
  EXPECT_LT(distanceOf(c.rival.match.pose, twin), 0.05);  // ... and the check its twin
  EXPECT_LT(yawErr(c.rival.match.pose, twin), 2 * M_PI / 180);
  EXPECT_LE(c.rival.score, c.start_score + params.ambiguity_margin);
  std::printf("symmetric room: start score %.4f m, twin %.4f m, check %.0f ms CPU, %d poses\n", c.start_score,
              c.rival.score, c.start_check_ms, c.rival.poses_scored);
}

// The same room with a cupboard against one wall (no twin): the start is unique and is taken at
// the true pose, converged as before.
TEST(Localization, StartInTheRoomWithAnAsymmetricFeatureIsTakenAtTheTruePose) {
  std::mt19937 rng(22);
  const auto walls = symmetricRoom(true);
  const std::string yaml = savedRoom(tempDir(), &rng, walls, pose2d(1.0, 0.0, 0.0));
  const Eigen::Isometry2d truth = pose2d(0.5, -0.4, 30 * M_PI / 180);
  auto mc = localizing(yaml, MapCorrection::Params());
  ASSERT_TRUE(mc);
  const StartRun run = standAndLocalize(mc.get(), walls, truth, 5.0, &rng);
  ASSERT_TRUE(run.localized) << run.last_reason;
  EXPECT_EQ(run.ambiguous, 0);
  EXPECT_LT(distanceOf(mc->mapFromOdom(), truth), 0.05);
  EXPECT_LT(yawErr(mc->mapFromOdom(), truth), 2 * M_PI / 180);
  const MapCorrection::Update& c = run.last_check;
  ASSERT_TRUE(c.start_checked && c.rival.found);
  // the twin was the best pose elsewhere, but the cupboard made it fit worse by more than the margin
  EXPECT_LT(distanceOf(c.rival.match.pose, symmetricTwin(truth)), 0.1);
  EXPECT_GT(c.rival.score, c.start_score + MapCorrection::Params().ambiguity_margin);
  std::printf("with the cupboard: start score %.4f m, twin %.4f m, check %.0f ms CPU, %d poses\n",
              c.start_score, c.rival.score, c.start_check_ms, c.rival.poses_scored);
}

// The simulator's finding: placed where the true pose lies outside the search (2.0 m from home,
// turned 150 deg) but its twin lies inside it. Without the check the search takes the twin (its
// fit passes the gates: only the cupboard differs) and the robot is "localized" 180 deg off; with
// it the true pose, found over the whole map, fits better: refused, never localized.
TEST(Localization, StartWhoseTwinLiesInsideTheSearchIsRefused) {
  std::mt19937 rng(23);
  const auto walls = symmetricRoom(true);
  const std::string yaml = savedRoom(tempDir(), &rng, walls, pose2d(1.0, 0.0, 0.0));
  const Eigen::Isometry2d truth = pose2d(1.6, -1.2, 150 * M_PI / 180);
  const Eigen::Isometry2d twin = symmetricTwin(truth);  // (0.4, 1.2, -30 deg): inside the search
  MapCorrection::Params params;
  params.ambiguity_check = false;
  auto unchecked = localizing(yaml, params);
  ASSERT_TRUE(unchecked);
  const StartRun blind = standAndLocalize(unchecked.get(), walls, truth, 3.0, &rng);
  ASSERT_TRUE(blind.localized) << blind.last_reason;  // the failure without the check
  EXPECT_LT(distanceOf(unchecked->mapFromOdom(), twin), 0.1);
  params.ambiguity_check = true;
  auto mc = localizing(yaml, params);
  ASSERT_TRUE(mc);
  const StartRun run = standAndLocalize(mc.get(), walls, truth, 5.0, &rng);
  EXPECT_FALSE(run.localized) << "localized after " << run.localized_after << " s";
  EXPECT_EQ(run.searched, 0);
  EXPECT_NE(run.last_reason.find("start search: ambiguous: another pose ("), std::string::npos)
      << run.last_reason;
  const MapCorrection::Update& c = run.last_check;
  ASSERT_TRUE(c.start_checked && c.rival.found);
  EXPECT_LT(distanceOf(c.match.pose, twin), 0.1);          // the search's answer: the twin
  EXPECT_LT(distanceOf(c.rival.match.pose, truth), 0.05);  // the check: the true pose, fitting better
  EXPECT_LT(c.rival.score, c.start_score);
  std::printf("twin inside the search: twin score %.4f m, true pose %.4f m, check %.0f ms CPU\n",
              c.start_score, c.rival.score, c.start_check_ms);
}

// Placed outside the search in the asymmetric room (1.96 m from home, turned 90 deg; the
// simulator's far check): whatever the search finds there is not the robot: never localized.
TEST(Localization, StartOutsideTheSearchIsNeverLocalized) {
  std::mt19937 rng(24);
  const std::string yaml = savedRoom(tempDir(), &rng);
  const Eigen::Isometry2d truth = pose2d(-1.9, 0.5, -M_PI / 2);
  auto mc = localizing(yaml, MapCorrection::Params());
  ASSERT_TRUE(mc);
  const StartRun run = standAndLocalize(mc.get(), room(), truth, 5.0, &rng);
  EXPECT_FALSE(run.localized) << "localized after " << run.localized_after << " s at ("
                              << mc->mapFromOdom().translation().transpose() << ")";
  EXPECT_EQ(run.searched, 0) << run.last_reason;
}

TEST(Localization, LoadedMapIsNotRewrittenByABoxLeftOnTheFloor) {
  std::mt19937 rng(13);
  const std::string dir = tempDir();
  const std::string yaml = savedRoom(dir, &rng);
  std::unique_ptr<OccupancyMap> ref;
  MapFileInfo info;
  std::string error;
  MapCorrection::Params params;
  params.clear_interval = 0.1;  // would clear and refine at every scan in mapping mode
  ASSERT_TRUE(loadMap(yaml, params.map, 0.0, &ref, &info, &error)) << error;
  MapCorrection mc(params);
  mc.setReference(std::move(ref), pose2d(0, 0, 0));
  const OccupancyMap before = mc.map();
  // A box 1.2 m in front for 3 minutes, the robot turning in place now and then.
  const std::vector<Circle> box = {{{1.2, 0.0}, 0.3}};
  double t = 0.0;
  int accepted = 0;
  for (int k = 0; k < 1800; ++k, t += 0.1) {
    const double yaw = 0.3 * std::sin(0.01 * k);
    const auto u =
        mc.processScan(t, castScan(pose2d(0, 0, yaw), room(), box, 360, 0.01, &rng), pose2d(0, 0, yaw));
    accepted += u.status == MapCorrection::Status::kAccepted;
  }
  EXPECT_TRUE(mc.localized());
  EXPECT_GT(accepted, 1500);
  int differ = 0;
  for (int cy = 0; cy < before.height(); ++cy) {
    for (int cx = 0; cx < before.width(); ++cx) differ += before.logOdds(cx, cy) != mc.map().logOdds(cx, cy);
  }
  EXPECT_EQ(differ, 0);
  int cx, cy;
  ASSERT_TRUE(mc.map().cellOf(Eigen::Vector2d(0.9, 0.0), &cx, &cy));
  EXPECT_FALSE(mc.map().occupied(cx, cy));
}

TEST(Visitors, CrowdAtStartThenGoneLeavesNoTraceInTheSavedMap) {
  std::mt19937 rng(14);
  MapCorrection mc;
  double t = 0.0;
  // Five people stand around the robot from the start for 4 s, then walk away.
  const std::vector<Circle> crowd = {
      {{1.0, 0.0}, 0.25}, {{0.0, 1.1}, 0.25}, {{-1.0, 0.3}, 0.25}, {{0.3, -1.0}, 0.25}, {{1.3, 1.2}, 0.25}};
  standAndMap(&mc, &t, 4.0, crowd, &rng);
  ASSERT_FALSE(mc.mapping());
  // They were in the map (the start-up mapping took them for structure) ...
  int in_map = 0;
  for (const Circle& c : crowd) {
    int cx, cy;
    ASSERT_TRUE(mc.map().cellOf(c.c - c.c.normalized() * (c.r - 0.02), &cx, &cy));
    in_map += mc.map().occupied(cx, cy);
  }
  EXPECT_EQ(in_map, static_cast<int>(crowd.size()));
  // ... the robot keeps standing after they left.
  standAndMap(&mc, &t, 15.0, {}, &rng);
  EXPECT_LT(mc.mapFromOdom().translation().norm(), 0.05);
  EXPECT_LT(std::fabs(yawOf(mc.mapFromOdom())), 0.02);
  const std::string dir = tempDir();
  std::string error;
  ASSERT_TRUE(saveMap(mc.map(), mc.mapTime(t), Eigen::Vector3d::Zero(), dir, "crowd", &error)) << error;
  for (const Circle& c : crowd) {
    for (double dx = -0.2; dx <= 0.2; dx += 0.05) {
      for (double dy = -0.2; dy <= 0.2; dy += 0.05) {
        const Eigen::Vector2d q = c.c + Eigen::Vector2d(dx, dy);
        if ((q - c.c).norm() > c.r - 0.03) continue;
        const int v = pgmAt(dir + "/crowd.pgm", mc.map(), q);
        EXPECT_NE(v, kPgmOccupied) << "person at " << c.c.transpose() << " left a wall at " << q.transpose();
      }
    }
    // Where the person stood facing the robot is observed free again.
    EXPECT_EQ(pgmAt(dir + "/crowd.pgm", mc.map(), c.c - c.c.normalized() * (c.r - 0.02)), kPgmFree);
  }
  // The walls the robot saw past the crowd at start are in the saved map (segment midpoints in
  // view from the origin: the standing updates did not eat them).
  int walls = 0, checked = 0;
  for (const Segment& s : room()) {
    const Eigen::Vector2d mid = 0.5 * (s.a + s.b);
    const Points2d ray =
        castScan(pose2d(0, 0, std::atan2(mid.y(), mid.x()) + M_PI), room(), crowd, 1, 1e-9, &rng);
    if (ray.empty() || std::fabs(ray[0].norm() - mid.norm()) > 0.05) continue;  // hidden at start
    int best = 255;
    for (double ox = -0.05; ox <= 0.05; ox += 0.05) {
      for (double oy = -0.05; oy <= 0.05; oy += 0.05) {
        best = std::min(best, pgmAt(dir + "/crowd.pgm", mc.map(), mid + Eigen::Vector2d(ox, oy)));
      }
    }
    ++checked;
    walls += best == kPgmOccupied;
  }
  EXPECT_GE(checked, 4);
  EXPECT_EQ(walls, checked);
}

/// Standing at `pose` for `seconds` (10 Hz, 360 beams = the node's 1 degree after slicing).
void standAt(MapCorrection* mc, double* t, double seconds, const Eigen::Isometry2d& pose,
             const std::vector<Segment>& walls, const std::vector<Circle>& things, std::mt19937* rng) {
  for (double end = *t + seconds; *t < end; *t += 0.1) {
    mc->processScan(*t, castScan(pose, walls, things, 360, 0.01, rng), pose);
  }
}

/// Occupied cells of a saved PGM within `radius` of `c`.
int occupiedNear(const std::string& pgm, const OccupancyMap& m, const Eigen::Vector2d& c, double radius) {
  int n = 0;
  const double res = m.params().resolution;
  for (double dx = -radius; dx <= radius + 1e-9; dx += res) {
    for (double dy = -radius; dy <= radius + 1e-9; dy += res) {
      const Eigen::Vector2d q = c + Eigen::Vector2d(dx, dy);
      if ((q - c).norm() <= radius) n += pgmAt(pgm, m, q) == kPgmOccupied;
    }
  }
  return n;
}

// The simulator's finding (issue 29, lab world): a visitor stood 1.2 m from the robot in front of
// a waste bin 2.7 m away. After it left, the beams through its robot-facing flank were the ones
// along the bin's silhouette: one ends on the bin's edge, the next on the wall behind it (a depth
// step on one side of each). A depth step made a beam not clear at all, so the flank's cells
// stayed occupied and were saved as a wall.
TEST(Visitors, FlankInFrontOfAnObjectEdgeIsClearedWhenThePersonLeft) {
  const Circle bin{{-2.6, -0.8}, 0.2};
  const Circle person{{-1.1, -0.5}, 0.25};
  // Which beams pass which flank cell depends on the robot's exact start (cm): three starts.
  const std::vector<Eigen::Vector2d> starts = {{0.0, 0.04}, {0.01, 0.02}, {0.03, 0.0}};
  for (const Eigen::Vector2d& s : starts) {
    SCOPED_TRACE("robot at " + std::to_string(s.x()) + ", " + std::to_string(s.y()));
    std::mt19937 rng(29);
    MapCorrection mc;
    double t = 0.0;
    const Eigen::Isometry2d pose = pose2d(s.x(), s.y(), 0.0);
    standAt(&mc, &t, 8.0, pose, room(), {person, bin}, &rng);
    ASSERT_FALSE(mc.mapping());
    int cx, cy;
    ASSERT_TRUE(mc.map().cellOf(person.c - person.c.normalized() * (person.r - 0.02), &cx, &cy));
    ASSERT_TRUE(mc.map().occupied(cx, cy));  // the start-up mapping took the person for structure
    standAt(&mc, &t, 15.0, pose, room(), {bin}, &rng);
    const std::string dir = tempDir();
    std::string error;
    ASSERT_TRUE(saveMap(mc.map(), mc.mapTime(t), Eigen::Vector3d::Zero(), dir, "flank", &error)) << error;
    const std::string pgm = dir + "/flank.pgm";
    EXPECT_EQ(occupiedNear(pgm, mc.map(), person.c, person.r + 0.1), 0) << "the person left a wall";
    // The bin behind it is structure and stays (its robot-facing side).
    EXPECT_GT(occupiedNear(pgm, mc.map(), bin.c - bin.c.normalized() * bin.r, 0.08), 0);
  }
}

// Walls the robot sees only at a grazing angle are not eaten by the standing updates: a 4 m
// free-standing partition ending in the open, passed by a robot that walks parallel to it 0.4 m
// away and stands still between steps (standing updates at each stop), then stands at its far end.
// From there the partition's cells near its end are grazed by beams whose far neighbour went past
// the partition's end (a depth step on one side): they must not clear along the partition.
TEST(Visitors, WallSeenAtAGrazingAngleFromAMovingRobotIsNotEaten) {
  std::mt19937 rng(31);
  MapCorrection mc;
  double t = 0.0;
  std::vector<Segment> walls = room();
  const Segment partition{{-2.0, 2.4}, {2.0, 2.4}};
  walls.push_back(partition);
  for (double x = -1.5; x <= 1.5 + 1e-9; x += 0.25) {  // stop and go along the partition
    standAt(&mc, &t, x == -1.5 ? 4.0 : 1.5, pose2d(x, 2.0, 0.0), walls, {}, &rng);
  }
  standAt(&mc, &t, 20.0, pose2d(3.0, 2.3, 0.0), walls, {}, &rng);  // beyond its end, grazing it
  EXPECT_LT((mc.mapFromOdom().translation()).norm(), 0.05);
  const std::string dir = tempDir();
  std::string error;
  ASSERT_TRUE(saveMap(mc.map(), mc.mapTime(t), Eigen::Vector3d::Zero(), dir, "grazing", &error)) << error;
  const std::string pgm = dir + "/grazing.pgm";
  int missing = 0, checked = 0;
  for (double x = partition.a.x() + 0.1; x <= partition.b.x() - 0.1; x += 0.1) {
    ++checked;
    int best = 255;
    for (double oy = -0.05; oy <= 0.05 + 1e-9; oy += 0.05) {
      best = std::min(best, pgmAt(pgm, mc.map(), Eigen::Vector2d(x, partition.a.y() + oy)));
    }
    if (best != kPgmOccupied) {
      ++missing;
      ADD_FAILURE() << "partition eaten at x = " << x;
    }
  }
  EXPECT_GE(checked, 30);
  EXPECT_EQ(missing, 0);
}

TEST(Growth, MapGrowsWithTheAreaExplored) {
  // A 50 m long corridor, driven along: beyond the initial 30 m grid.
  std::vector<Segment> corridor = {
      {{-5, -1.5}, {45, -1.5}}, {{-5, 1.5}, {45, 1.5}}, {{-5, -1.5}, {-5, 1.5}}, {{45, -1.5}, {45, 1.5}}};
  for (int k = 0; k < 25; ++k) corridor.push_back({{2.0 * k, 1.5}, {2.0 * k + 0.3, 1.2}});  // features
  std::mt19937 rng(15);
  MapCorrection::Params p;
  MapCorrection mc(p);
  const size_t bytes0 = mc.map().memoryBytes();
  double t = 0.0;
  Eigen::Isometry2d truth = pose2d(0, 0, 0);
  for (int k = 0; k < 600 && truth.translation().x() < 38.0; ++k, t += 0.1) {
    if (t > 3.0) truth = truth * pose2d(0.08, 0, 0);
    mc.processScan(t, castScan(truth, corridor, {}, 360, 0.01, &rng, 8.0), truth);
  }
  EXPECT_GT(truth.translation().x(), 37.9);
  EXPECT_GT(mc.map().width() * p.map.resolution, 40.0);
  EXPECT_GT(mc.map().memoryBytes(), bytes0);
  int cx, cy;
  // The wall 21 m from the start (beyond the initial grid, between two features) is in the grown map.
  ASSERT_TRUE(mc.map().cellOf(Eigen::Vector2d(21.0, 1.5), &cx, &cy));
  int wall = 0;
  for (int dx = -1; dx <= 1; ++dx) {
    for (int dy = -1; dy <= 1; ++dy) wall += mc.map().occupied(cx + dx, cy + dy);
  }
  EXPECT_GT(wall, 0);
  // Still matched while growing: the pose drifts only along the corridor's axis (no loop
  // closure; 0.14 m after 35 m measured), across it stays on the truth.
  const Eigen::Isometry2d est = mc.mapFromOdom() * truth;
  EXPECT_LT((est.translation() - truth.translation()).norm(), 0.25);
  EXPECT_LT(std::fabs(est.translation().y() - truth.translation().y()), 0.05);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
