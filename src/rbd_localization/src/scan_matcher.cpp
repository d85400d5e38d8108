#include "rbd_localization/scan_matcher.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "rbd_localization/filter_common.h"
#include "rbd_localization/geometry.h"

namespace rbd_localization {

ScanMatcher::Result ScanMatcher::match(const OccupancyMap& map, const Points2d& points,
                                       const Eigen::Isometry2d& prior) const {
  Result r;
  r.points = static_cast<int>(points.size());
  double x = prior.translation().x(), y = prior.translation().y(), th = yawOf(prior);
  const int iters = std::max(1, params_.max_iterations);
  for (int it = 0; it < iters; ++it) {
    const double frac = iters > 1 ? std::min(1.0, 2.0 * it / (iters - 1)) : 1.0;
    const double gate = params_.outlier_distance_start +
                        frac * (params_.outlier_distance_end - params_.outlier_distance_start);
    const double c = std::cos(th), s = std::sin(th);
    Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
    Eigen::Vector3d g = Eigen::Vector3d::Zero();
    int used = 0;
    for (const Eigen::Vector2d& p : points) {
      const Eigen::Vector2d q(c * p.x() - s * p.y() + x, s * p.x() + c * p.y() + y);
      double d;
      Eigen::Vector2d grad;
      if (!map.distance(q, &d, &grad) || d > gate) continue;
      // d(q)/d(x, y, th) = grad^T [I | dR/dth p]
      const Eigen::Vector3d j(grad.x(), grad.y(),
                              grad.x() * (-s * p.x() - c * p.y()) + grad.y() * (c * p.x() - s * p.y()));
      h.noalias() += j * j.transpose();
      g.noalias() += j * d;
      ++used;
    }
    r.iterations = it + 1;
    if (used < 3) break;
    h.diagonal().array() += 1e-6 * used;  // Levenberg damping for near-degenerate geometry
    const Eigen::Vector3d step = -h.ldlt().solve(g);
    if (!step.allFinite()) break;
    x += step(0);
    y += step(1);
    th = wrapAngle(th + step(2));
    if (std::hypot(step(0), step(1)) < params_.converged_translation &&
        std::fabs(step(2)) < params_.converged_rotation && frac >= 1.0) {
      break;
    }
  }
  r.pose = pose2d(x, y, th);

  // Fit quality at the final pose.
  const double c = std::cos(th), s = std::sin(th);
  double sum_sq = 0.0;
  Eigen::Matrix2d info = Eigen::Matrix2d::Zero();
  for (const Eigen::Vector2d& p : points) {
    const Eigen::Vector2d q(c * p.x() - s * p.y() + x, s * p.x() + c * p.y() + y);
    double d;
    Eigen::Vector2d grad;
    if (!map.distance(q, &d, &grad) || d > params_.inlier_distance) continue;
    ++r.inliers;
    sum_sq += d * d;
    info.noalias() += grad * grad.transpose();
  }
  if (r.points > 0) r.inlier_ratio = static_cast<double>(r.inliers) / r.points;
  if (r.inliers > 0) {
    r.rms = std::sqrt(sum_sq / r.inliers);
    r.min_translation_information =
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(info / r.inliers).eigenvalues()(0);
  }
  return r;
}

namespace {

/// A pose on a search grid and its score.
struct Cand {
  double score, x, y, th;
};

/// The best `k` grid poses, kept distinct: a better pose replaces a close neighbour (within
/// near_xy [m] and near_th [rad]) instead of being added beside it.
class TopCandidates {
 public:
  TopCandidates(int k, double near_xy, double near_th) : k_(k), near_xy_(near_xy), near_th_(near_th) {}
  /// Scores at or above this cannot enter the list (it is full).
  double bound() const {
    return static_cast<int>(best_.size()) == k_ ? best_.back().score
                                                : std::numeric_limits<double>::infinity();
  }
  void offer(const Cand& c) {
    if (c.score >= bound()) return;
    bool replaced = false;
    for (Cand& b : best_) {
      if (std::hypot(b.x - c.x, b.y - c.y) < near_xy_ && std::fabs(wrapAngle(b.th - c.th)) < near_th_) {
        if (c.score >= b.score) return;  // dominated
        b = c;
        replaced = true;
        break;
      }
    }
    if (!replaced) best_.push_back(c);
    std::sort(best_.begin(), best_.end(), [](const Cand& a, const Cand& b) { return a.score < b.score; });
    if (static_cast<int>(best_.size()) > k_) best_.pop_back();
  }
  const std::vector<Cand>& list() const { return best_; }

 private:
  int k_;
  double near_xy_, near_th_;
  std::vector<Cand> best_;  // sorted by score
};

/// Every n-th point, about `count` of them.
Points2d subsetOf(const Points2d& points, size_t count) {
  Points2d sub;
  const size_t stride = std::max<size_t>(1, points.size() / std::max<size_t>(1, count));
  for (size_t i = 0; i < points.size(); i += stride) sub.push_back(points[i]);
  return sub;
}

/// The points rotated by th (the translation is added per grid position).
void rotateInto(const Points2d& sub, double th, Points2d* rotated) {
  const double c = std::cos(th), s = std::sin(th);
  rotated->resize(sub.size());
  for (size_t k = 0; k < sub.size(); ++k) {
    (*rotated)[k] = Eigen::Vector2d(c * sub[k].x() - s * sub[k].y(), s * sub[k].x() + c * sub[k].y());
  }
}

/// ScanMatcher::score of rotated points shifted by (x, y); stops early (returning a value >= bound)
/// once the score cannot end below bound.
double gridScore(const OccupancyMap& map, const Points2d& rotated, double x, double y, double bound) {
  if (rotated.empty()) return ScanMatcher::kTruncate;
  const double limit = bound * rotated.size();
  double sum = 0.0;
  for (const Eigen::Vector2d& q : rotated) {
    double d;
    Eigen::Vector2d g;
    map.distance(q + Eigen::Vector2d(x, y), &d, &g);
    sum += std::min(d, ScanMatcher::kTruncate);
    if (sum >= limit) return bound;
  }
  return sum / rotated.size();
}

}  // namespace

constexpr double ScanMatcher::kTruncate;

double ScanMatcher::score(const OccupancyMap& map, const Points2d& points, const Eigen::Isometry2d& pose) {
  Points2d rotated;
  rotateInto(points, yawOf(pose), &rotated);
  return gridScore(map, rotated, pose.translation().x(), pose.translation().y(),
                   std::numeric_limits<double>::infinity());
}

ScanMatcher::Result ScanMatcher::search(const OccupancyMap& map, const Points2d& points,
                                        const Eigen::Isometry2d& prior, double max_translation,
                                        double max_rotation, double step) const {
  // Score a subset of the points on a pose grid (score()), keep the best distinct candidates.
  constexpr size_t kSubset = 120;
  constexpr int kCandidates = 6;
  const Points2d sub = subsetOf(points, kSubset);
  step = std::max(step, map.params().resolution);
  const int nt = static_cast<int>(std::ceil(max_translation / step));
  const double astep = 0.025;
  const int na = static_cast<int>(std::ceil(max_rotation / astep));
  const double x0 = prior.translation().x(), y0 = prior.translation().y(), th0 = yawOf(prior);
  TopCandidates best(kCandidates, 2.5 * step, 4 * astep);
  Points2d rotated;
  for (int ia = -na; ia <= na; ++ia) {
    const double th = th0 + ia * astep;
    rotateInto(sub, th, &rotated);
    for (int ix = -nt; ix <= nt; ++ix) {
      for (int iy = -nt; iy <= nt; ++iy) {
        const double x = x0 + ix * step, y = y0 + iy * step;
        best.offer(Cand{gridScore(map, rotated, x, y, best.bound()), x, y, th});
      }
    }
  }
  Result out;
  bool have = false;
  for (const Cand& c : best.list()) {
    const Result r = match(map, points, pose2d(c.x, c.y, c.th));
    if (!have || r.inliers > out.inliers || (r.inliers == out.inliers && r.rms < out.rms)) {
      out = r;
      have = true;
    }
  }
  if (!have) out.points = static_cast<int>(points.size());
  return out;
}

ScanMatcher::Rival ScanMatcher::rivalElsewhere(const OccupancyMap& map, const Points2d& points,
                                               const Eigen::Isometry2d& pose, double min_translation,
                                               double min_rotation, const GlobalSearch& how) const {
  Rival out;
  const double step = std::max(how.step, map.params().resolution);
  const double astep = std::max(how.angle_step, 1e-3);
  const Eigen::Vector2d p0 = pose.translation();
  const double th0 = yawOf(pose);
  auto distinct = [&](double x, double y, double th) {
    return std::hypot(x - p0.x(), y - p0.y()) > min_translation ||
           std::fabs(wrapAngle(th - th0)) > min_rotation;
  };
  // Positions: a step grid over the map, where the map saw free space (a robot stands there).
  std::vector<Eigen::Vector2d> where;
  const double res = map.params().resolution;
  const int stride = std::max(1, static_cast<int>(std::lround(step / res)));
  for (int cy = stride / 2; cy < map.height(); cy += stride) {
    for (int cx = stride / 2; cx < map.width(); cx += stride) {
      if (map.logOdds(cx, cy) < 0.0f) {
        where.emplace_back(map.originX() + (cx + 0.5) * res, map.originY() + (cy + 0.5) * res);
      }
    }
  }
  const Points2d sub = subsetOf(points, static_cast<size_t>(std::max(1, how.subset)));
  const int na = std::max(1, static_cast<int>(std::lround(2.0 * M_PI / astep)));
  TopCandidates best(std::max(1, how.candidates), 2.5 * step, 2.5 * (2.0 * M_PI / na));
  Points2d rotated;
  for (int ia = 0; ia < na; ++ia) {
    const double th = wrapAngle(th0 + ia * 2.0 * M_PI / na);
    rotateInto(sub, th, &rotated);
    for (const Eigen::Vector2d& w : where) {
      if (!distinct(w.x(), w.y(), th)) continue;
      ++out.poses_scored;
      best.offer(Cand{gridScore(map, rotated, w.x(), w.y(), best.bound()), w.x(), w.y(), th});
    }
  }
  for (const Cand& c : best.list()) {
    const Result r = match(map, points, pose2d(c.x, c.y, c.th));
    if (!distinct(r.pose.translation().x(), r.pose.translation().y(), yawOf(r.pose)))
      continue;  // back to pose
    const double s = score(map, points, r.pose);
    if (!out.found || s < out.score) {
      out.found = true;
      out.match = r;
      out.score = s;
    }
  }
  return out;
}

}  // namespace rbd_localization
