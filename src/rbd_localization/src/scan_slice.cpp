#include "rbd_localization/scan_slice.h"

#include <algorithm>
#include <cmath>

#include "rbd_localization/geometry.h"

namespace rbd_localization {

Eigen::Matrix3d levelFromBase(const Eigen::Matrix3d& odom_from_base_rotation) {
  const Eigen::Vector3d rpy = rpyFromRotation(odom_from_base_rotation);
  return rotationFromRpy(rpy(0), rpy(1), 0.0);
}

namespace {

Points2d decimate(const Points2d& in, int max_points) {
  const size_t step = std::max<size_t>(1, (in.size() + max_points - 1) / std::max(1, max_points));
  if (step == 1) return in;
  Points2d out;
  out.reserve(in.size() / step + 1);
  for (size_t i = 0; i < in.size(); i += step) out.push_back(in[i]);
  return out;
}

}  // namespace

void ScanSlicer::begin(const Eigen::Isometry3d& base_from_sensor, const Eigen::Matrix3d& level_from_base) {
  Eigen::Isometry3d level = Eigen::Isometry3d::Identity();
  level.linear() = level_from_base;
  level_from_sensor_ = level * base_from_sensor;
  best_.assign(std::max(1, params_.bins), std::numeric_limits<double>::infinity());
  pts_.assign(best_.size(), Eigen::Vector2d::Zero());
}

void ScanSlicer::add(const Eigen::Vector3d& point_in_sensor) {
  if (!point_in_sensor.allFinite()) return;
  const Eigen::Vector3d p = level_from_sensor_ * point_in_sensor;
  if (p.z() < params_.z_min || p.z() > params_.z_max) return;
  const Eigen::Vector3d& origin = level_from_sensor_.translation();
  const double dx = p.x() - origin.x(), dy = p.y() - origin.y();
  const double r = std::hypot(dx, dy);
  if (r < params_.min_range || r > params_.max_range) return;
  const int bins = static_cast<int>(best_.size());
  int b = static_cast<int>((std::atan2(dy, dx) + M_PI) / (2.0 * M_PI) * bins);
  b = std::min(std::max(b, 0), bins - 1);
  if (r < best_[b]) {
    best_[b] = r;
    pts_[b] = p.head<2>();
  }
}

Points2d ScanSlicer::finish() const {
  Points2d out;
  out.reserve(best_.size());
  for (size_t b = 0; b < best_.size(); ++b) {
    if (std::isfinite(best_[b])) out.push_back(pts_[b]);
  }
  return decimate(out, params_.max_points);
}

Points2d ScanSlicer::levelPlanar(const std::vector<Eigen::Vector3d>& points_in_sensor) const {
  Points2d out;
  out.reserve(points_in_sensor.size());
  const Eigen::Vector3d& origin = level_from_sensor_.translation();
  for (const Eigen::Vector3d& s : points_in_sensor) {
    if (!s.allFinite()) continue;
    const Eigen::Vector3d p = level_from_sensor_ * s;
    const double r = std::hypot(p.x() - origin.x(), p.y() - origin.y());
    if (r < params_.min_range || r > params_.max_range) continue;
    out.push_back(p.head<2>());
  }
  return decimate(out, params_.max_points);
}

}  // namespace rbd_localization
