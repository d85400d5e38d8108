#include "rbd_localization/scan_matcher.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

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

ScanMatcher::Result ScanMatcher::search(const OccupancyMap& map, const Points2d& points,
                                        const Eigen::Isometry2d& prior, double max_translation,
                                        double max_rotation, double step) const {
  // Score a subset of the points on a pose grid: mean distance to structure, truncated.
  constexpr size_t kSubset = 120;
  constexpr double kTruncate = 0.3;
  constexpr int kCandidates = 6;
  Points2d sub;
  const size_t stride = std::max<size_t>(1, points.size() / kSubset);
  for (size_t i = 0; i < points.size(); i += stride) sub.push_back(points[i]);
  step = std::max(step, map.params().resolution);
  const int nt = static_cast<int>(std::ceil(max_translation / step));
  const double astep = 0.025;
  const int na = static_cast<int>(std::ceil(max_rotation / astep));
  const double x0 = prior.translation().x(), y0 = prior.translation().y(), th0 = yawOf(prior);
  struct Cand {
    double score, x, y, th;
  };
  std::vector<Cand> best;  // sorted, distinct
  Points2d rotated(sub.size());
  for (int ia = -na; ia <= na; ++ia) {
    const double th = th0 + ia * astep;
    const double c = std::cos(th), s = std::sin(th);
    for (size_t k = 0; k < sub.size(); ++k) {
      rotated[k] = Eigen::Vector2d(c * sub[k].x() - s * sub[k].y(), s * sub[k].x() + c * sub[k].y());
    }
    for (int ix = -nt; ix <= nt; ++ix) {
      for (int iy = -nt; iy <= nt; ++iy) {
        const double x = x0 + ix * step, y = y0 + iy * step;
        double sum = 0.0;
        for (const Eigen::Vector2d& q : rotated) {
          double d;
          Eigen::Vector2d g;
          map.distance(q + Eigen::Vector2d(x, y), &d, &g);
          sum += std::min(d, kTruncate);
        }
        const double score = sub.empty() ? kTruncate : sum / sub.size();
        if (static_cast<int>(best.size()) == kCandidates && score >= best.back().score) continue;
        // Keep candidates distinct: a better one replaces a close neighbour.
        bool replaced = false, dominated = false;
        for (Cand& b : best) {
          if (std::hypot(b.x - x, b.y - y) < 2.5 * step && std::fabs(wrapAngle(b.th - th)) < 4 * astep) {
            if (score < b.score) {
              b = Cand{score, x, y, th};
              replaced = true;
            } else {
              dominated = true;
            }
            break;
          }
        }
        if (dominated) continue;
        if (!replaced) best.push_back(Cand{score, x, y, th});
        std::sort(best.begin(), best.end(), [](const Cand& a, const Cand& b) { return a.score < b.score; });
        if (static_cast<int>(best.size()) > kCandidates) best.pop_back();
      }
    }
  }
  Result out;
  bool have = false;
  for (const Cand& c : best) {
    const Result r = match(map, points, pose2d(c.x, c.y, c.th));
    if (!have || r.inliers > out.inliers || (r.inliers == out.inliers && r.rms < out.rms)) {
      out = r;
      have = true;
    }
  }
  if (!have) out.points = static_cast<int>(points.size());
  return out;
}

}  // namespace rbd_localization
