// Map correction CPU per scan on the synthetic room: 1024-beam scans (OS1 1024 columns), the
// node's decimation to ~360 points, matching + gating + periodic map refinement (distance
// field rebuild included). Prints one JSON line.
//
// `bench_map_correction start-check MAP.yaml X Y YAW_DEG [X Y YAW_DEG ...]`: localization mode in a
// saved map (home: the map origin) from each placement: a 360-point scan ray-cast in the map's own
// occupied cells (1 cm noise), the start search and its ambiguity check; one JSON line each (the
// search's answer, the best pose elsewhere, both scores, the check's CPU time).
#include <algorithm>
#include <cstdio>
#include <ctime>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "../test/synthetic_room.h"
#include "rbd_localization/geometry.h"
#include "rbd_localization/map_correction.h"
#include "rbd_localization/map_io.h"

using namespace rbd_localization;                // NOLINT
using namespace rbd_localization::testing_room;  // NOLINT

namespace {
Points2d decimate(const Points2d& in, size_t max_points) {
  const size_t step = std::max<size_t>(1, (in.size() + max_points - 1) / max_points);
  Points2d out;
  for (size_t i = 0; i < in.size(); i += step) out.push_back(in[i]);
  return out;
}
/// A scan of `beams` rays from pose (sensor frame), ray-marched through the map's occupied cells.
Points2d castInMap(const OccupancyMap& map, const Eigen::Isometry2d& pose, int beams, double sigma,
                   std::mt19937* rng) {
  std::normal_distribution<double> noise(0.0, sigma);
  Points2d out;
  const double yaw = yawOf(pose);
  for (int i = 0; i < beams; ++i) {
    const double a = -M_PI + 2.0 * M_PI * i / beams;
    const Eigen::Vector2d d(std::cos(yaw + a), std::sin(yaw + a));
    for (double r = 0.3; r < 20.0; r += 0.01) {
      int cx, cy;
      if (!map.cellOf(pose.translation() + r * d, &cx, &cy)) break;
      if (map.occupied(cx, cy)) {
        const double rr = r + noise(*rng);
        out.emplace_back(rr * std::cos(a), rr * std::sin(a));
        break;
      }
    }
  }
  return out;
}

int startCheck(int argc, char** argv) {
  if (argc < 6 || (argc - 3) % 3 != 0) {
    std::fprintf(stderr, "usage: bench_map_correction start-check MAP.yaml X Y YAW_DEG [X Y YAW_DEG ...]\n");
    return 2;
  }
  std::mt19937 rng(5);
  for (int k = 3; k + 2 < argc; k += 3) {
    const Eigen::Isometry2d truth =
        pose2d(std::atof(argv[k]), std::atof(argv[k + 1]), std::atof(argv[k + 2]) * M_PI / 180);
    MapCorrection::Params params;
    std::unique_ptr<OccupancyMap> ref;
    MapFileInfo info;
    std::string error;
    if (!loadMap(argv[2], params.map, 0.0, &ref, &info, &error)) {
      std::fprintf(stderr, "%s\n", error.c_str());
      return 1;
    }
    MapCorrection mc(params);
    mc.setReference(std::move(ref), pose2d(0, 0, 0));
    const Points2d scan = castInMap(mc.map(), truth, 360, 0.01, &rng);
    const MapCorrection::Update u = mc.processScan(0.0, scan, pose2d(0, 0, 0));
    const Eigen::Isometry2d& p = u.match.pose;
    const Eigen::Isometry2d& r = u.rival.match.pose;
    std::printf(
        "{\"bench\": \"start_check\", \"truth\": [%.2f, %.2f, %.1f], \"points\": %zu, \"status\": \"%s\", "
        "\"answer\": [%.2f, %.2f, %.1f], \"answer_score\": %.4f, \"rival\": [%.2f, %.2f, %.1f], "
        "\"rival_score\": %.4f, \"poses\": %d, \"check_cpu_ms\": %.1f, \"map_cells\": [%d, %d]}\n",
        truth.translation().x(), truth.translation().y(), yawOf(truth) * 180 / M_PI, scan.size(),
        MapCorrection::statusName(u.status), p.translation().x(), p.translation().y(), yawOf(p) * 180 / M_PI,
        u.start_score, r.translation().x(), r.translation().y(), yawOf(r) * 180 / M_PI, u.rival.score,
        u.rival.poses_scored, u.start_check_ms, mc.map().width(), mc.map().height());
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc > 1 && std::string(argv[1]) == "start-check") return startCheck(argc, argv);
  const int n = argc > 1 ? std::atoi(argv[1]) : 300;
  std::mt19937 rng(9);
  const auto walls = room();
  MapCorrection mc;
  double t = 0.0;
  while (mc.mapping()) {
    mc.processScan(t, decimate(castScan(pose2d(0, 0, 0), walls, {}, 1024, 0.015, &rng), 360),
                   pose2d(0, 0, 0));
    t += 0.1;
  }
  std::vector<double> ms;
  Eigen::Isometry2d truth = pose2d(0, 0, 0), odom = pose2d(0, 0, 0);
  int accepted = 0;
  for (int k = 0; k < n; ++k, t += 0.1) {
    const double v = 0.03, w = (k % 100 < 80) ? 0.0 : (M_PI / 2) / 20.0;
    truth = truth * pose2d(v, 0, w);
    odom = odom * pose2d(v * 1.03, 0, w + 0.001);
    const std::vector<Circle> people = {{{1.0 + 0.5 * std::sin(0.1 * k), 1.5}, 0.25},
                                        {{-1.0, 0.5 * std::cos(0.1 * k)}, 0.25}};
    const Points2d scan = decimate(castScan(truth, walls, people, 1024, 0.015, &rng), 360);
    const std::clock_t c0 = std::clock();
    const auto u = mc.processScan(t, scan, odom);
    const std::clock_t c1 = std::clock();
    ms.push_back(1e3 * static_cast<double>(c1 - c0) / CLOCKS_PER_SEC);
    if (u.status == MapCorrection::Status::kAccepted) ++accepted;
  }
  std::vector<double> sorted = ms;
  std::sort(sorted.begin(), sorted.end());
  double mean = 0.0;
  for (double v : ms) mean += v;
  mean /= ms.size();
  const Eigen::Isometry2d est = mc.mapFromOdom() * odom;
  std::printf(
      "{\"bench\": \"map_correction_scan\", \"scans\": %d, \"accepted\": %d, \"cpu_ms_mean\": %.3f, "
      "\"cpu_ms_p95\": %.3f, \"cpu_ms_max\": %.3f, \"goal_ms\": 30.0, \"final_error_m\": %.4f}\n",
      n, accepted, mean, sorted[static_cast<size_t>(0.95 * (sorted.size() - 1))], sorted.back(),
      (est.translation() - truth.translation()).norm());
  return 0;
}
