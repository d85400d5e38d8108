// A 2D room for tests and benchmarks: wall segments plus circular "people", and a ray caster
// producing the points a planar LiDAR at a given pose would see.
#ifndef RBD_LOCALIZATION_TEST_SYNTHETIC_ROOM_H
#define RBD_LOCALIZATION_TEST_SYNTHETIC_ROOM_H

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "rbd_localization/occupancy_map.h"

namespace rbd_localization {
namespace testing_room {

struct Segment {
  Eigen::Vector2d a, b;
};
struct Circle {
  Eigen::Vector2d c;
  double r;
};

/// 8 m x 6 m room with an inner box, a pillar and an L-shaped cupboard (asymmetric on purpose).
inline std::vector<Segment> room() {
  auto s = [](double ax, double ay, double bx, double by) { return Segment{{ax, ay}, {bx, by}}; };
  return {s(-3, -2.5, 5, -2.5),    s(5, -2.5, 5, 3.5),      s(5, 3.5, -3, 3.5),  s(-3, 3.5, -3, -2.5),
          s(2, 1, 3, 1),           s(3, 1, 3, 1.6),         s(3, 1.6, 2, 1.6),   s(2, 1.6, 2, 1),
          s(-2, -1.5, -1.5, -1.5), s(-1.5, -1.5, -1.5, -1), s(-1.5, -1, -2, -1), s(-2, -1, -2, -1.5),
          s(3.5, -2.5, 3.5, -1.2), s(3.5, -1.2, 4.2, -1.2)};
}

/// Centre of symmetricRoom().
inline Eigen::Vector2d symmetricRoomCentre() { return Eigen::Vector2d(1.0, 0.0); }

/// 8 m x 6 m room, centred on (1, 0), that is point-symmetric: every wall, pillar and stub has its
/// twin turned 180 deg about the centre, so a pose and its twin (turned 180 deg about the centre)
/// see the same scan. with_cupboard: plus a 1.0 m x 0.5 m cupboard against the south wall, whose
/// twin is missing (the room is then almost, not exactly, symmetric).
inline std::vector<Segment> symmetricRoom(bool with_cupboard) {
  const Eigen::Vector2d c = symmetricRoomCentre();
  auto s = [](double ax, double ay, double bx, double by) { return Segment{{ax, ay}, {bx, by}}; };
  const std::vector<Segment> half = {s(-3, -3, 5, -3),
                                     s(5, -3, 5, 3),  // south and east walls
                                                      // a 0.4 m pillar and a stub from the east wall
                                     s(2.8, 1.3, 3.2, 1.3), s(3.2, 1.3, 3.2, 1.7), s(3.2, 1.7, 2.8, 1.7),
                                     s(2.8, 1.7, 2.8, 1.3), s(5, 0.8, 4.2, 0.8)};
  std::vector<Segment> out = half;
  for (const Segment& w : half) out.push_back(Segment{2.0 * c - w.a, 2.0 * c - w.b});  // the twins
  if (with_cupboard) {
    out.push_back(s(2.5, -3, 2.5, -2.5));
    out.push_back(s(2.5, -2.5, 3.5, -2.5));
    out.push_back(s(3.5, -2.5, 3.5, -3));
  }
  return out;
}

/// The twin of a pose in symmetricRoom(): turned 180 deg about the room's centre.
inline Eigen::Isometry2d symmetricTwin(const Eigen::Isometry2d& pose) {
  Eigen::Isometry2d half_turn = Eigen::Isometry2d::Identity();
  half_turn.linear() = -Eigen::Matrix2d::Identity();
  half_turn.translation() = 2.0 * symmetricRoomCentre();
  return half_turn * pose;
}

/// Points (in the sensor frame) of a 360 deg scan with `beams` rays from pose, range noise sigma.
inline Points2d castScan(const Eigen::Isometry2d& pose, const std::vector<Segment>& walls,
                         const std::vector<Circle>& people, int beams, double sigma, std::mt19937* rng,
                         double max_range = 20.0) {
  std::normal_distribution<double> noise(0.0, sigma);
  Points2d out;
  const Eigen::Vector2d o = pose.translation();
  const double yaw = std::atan2(pose.linear()(1, 0), pose.linear()(0, 0));
  for (int i = 0; i < beams; ++i) {
    const double a = -M_PI + 2.0 * M_PI * i / beams;
    const Eigen::Vector2d d(std::cos(yaw + a), std::sin(yaw + a));
    double best = std::numeric_limits<double>::infinity();
    for (const Segment& w : walls) {
      const Eigen::Vector2d e = w.b - w.a;
      const double den = d.x() * e.y() - d.y() * e.x();
      if (std::fabs(den) < 1e-12) continue;
      const Eigen::Vector2d ao = w.a - o;
      const double t = (ao.x() * e.y() - ao.y() * e.x()) / den;
      const double u = (ao.x() * d.y() - ao.y() * d.x()) / den;
      if (t > 0 && u >= 0 && u <= 1) best = std::min(best, t);
    }
    for (const Circle& c : people) {
      const Eigen::Vector2d oc = o - c.c;
      const double b = oc.dot(d), cc = oc.squaredNorm() - c.r * c.r;
      const double disc = b * b - cc;
      if (disc < 0) continue;
      const double t = -b - std::sqrt(disc);
      if (t > 0) best = std::min(best, t);
    }
    if (!(best < max_range)) continue;
    const double r = best + noise(*rng);
    out.emplace_back(r * std::cos(a), r * std::sin(a));
  }
  return out;
}

}  // namespace testing_room
}  // namespace rbd_localization

#endif  // RBD_LOCALIZATION_TEST_SYNTHETIC_ROOM_H
