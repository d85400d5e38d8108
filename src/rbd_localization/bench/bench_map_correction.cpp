// Map correction CPU per scan on the synthetic room: 1024-beam scans (OS1 1024 columns), the
// node's decimation to ~360 points, matching + gating + periodic map refinement (distance
// field rebuild included). Prints one JSON line.
#include <algorithm>
#include <cstdio>
#include <ctime>
#include <random>
#include <vector>

#include "../test/synthetic_room.h"
#include "rbd_localization/geometry.h"
#include "rbd_localization/map_correction.h"

using namespace rbd_localization;                // NOLINT
using namespace rbd_localization::testing_room;  // NOLINT

namespace {
Points2d decimate(const Points2d& in, size_t max_points) {
  const size_t step = std::max<size_t>(1, (in.size() + max_points - 1) / max_points);
  Points2d out;
  for (size_t i = 0; i < in.size(); i += step) out.push_back(in[i]);
  return out;
}
}  // namespace

int main(int argc, char** argv) {
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
