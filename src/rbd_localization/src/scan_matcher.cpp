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

}  // namespace rbd_localization
