#include "rbd_lidar/floor_fit.h"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <vector>

namespace rbd_lidar {

bool estimateHeight(const CriticalZone& zone, const uint8_t* range_bytes, size_t stride, double max_distance,
                    double quantile, size_t column_step, size_t min_samples, double* height) {
  if (!zone.configured()) return false;
  const BeamModel& beams = zone.beams();
  const BeamTrig& trig = zone.trig();
  const size_t rows = beams.rows(), cols = static_cast<size_t>(beams.columns);
  const Eigen::Matrix3d& R = zone.pose().level_from_sensor;
  const double n = beams.beam_origin, lz = beams.lidar_z;
  thread_local std::vector<double> sample_buffer;
  std::vector<double>& samples = sample_buffer;
  samples.clear();
  const size_t step = std::max<size_t>(1, column_step);
  const double tilt = std::hypot(R(2, 0), R(2, 1));
  for (size_t u = 0; u < rows; ++u) {
    const double cp = trig.cos_alt[u], sp = trig.sin_alt[u];
    // Only clearly downward rays (> 5 deg below the horizon in the level frame): skip rows that
    // have none without touching their data.
    if (R(2, 2) * sp - tilt * cp > -0.087) continue;
    for (size_t c = u % step; c < cols; c += step) {
      double ca, sa;
      trig.azimuth(u, c, &ca, &sa);
      const double dz = R(2, 0) * ca * cp + R(2, 1) * sa * cp + R(2, 2) * sp;
      if (dz > -0.087) continue;
      uint32_t r;
      std::memcpy(&r, range_bytes + (u * cols + c) * stride, sizeof(r));
      if (r == 0) continue;
      const double rm = r * 1e-3, horiz = rm * cp + n * (1 - cp);
      const double sx = ca * horiz, sy = sa * horiz, sz = rm * sp + lz - n * sp;
      const double x = R(0, 0) * sx + R(0, 1) * sy + R(0, 2) * sz;
      const double y = R(1, 0) * sx + R(1, 1) * sy + R(1, 2) * sz;
      if (x * x + y * y > max_distance * max_distance) continue;
      samples.push_back(-(R(2, 0) * sx + R(2, 1) * sy + R(2, 2) * sz));
    }
  }
  if (samples.size() < std::max<size_t>(1, min_samples)) return false;
  const size_t k = std::min(samples.size() - 1, static_cast<size_t>(quantile * (samples.size() - 1)));
  std::nth_element(samples.begin(), samples.begin() + k, samples.end());
  *height = samples[k];
  return true;
}

bool estimateFloor(const CriticalZone& zone, const uint8_t* range_bytes, size_t stride, double max_distance,
                   double max_tilt, size_t column_step, size_t min_samples, SensorPose* pose) {
  if (!zone.configured() || !pose) return false;
  const BeamModel& beams = zone.beams();
  const BeamTrig& trig = zone.trig();
  const size_t rows = beams.rows(), cols = static_cast<size_t>(beams.columns);
  const Eigen::Matrix3d& R = zone.pose().level_from_sensor;
  const double n = beams.beam_origin, lz = beams.lidar_z, h0 = zone.pose().height;
  const double slope = std::tan(std::max(0.0, max_tilt));
  thread_local std::vector<Eigen::Vector3d> point_buffer;
  std::vector<Eigen::Vector3d>& pts = point_buffer;
  pts.clear();
  const size_t step = std::max<size_t>(1, column_step);
  // Prior-level points of rays that may reach the floor (below the horizon by more than the
  // tolerated tilt error allows upwards).
  const double tilt = std::hypot(R(2, 0), R(2, 1));
  const double min_dz = -std::sin(std::min(0.2, 0.5 * max_tilt));
  for (size_t u = 0; u < rows; ++u) {
    const double cp = trig.cos_alt[u], sp = trig.sin_alt[u];
    if (R(2, 2) * sp - tilt * cp > 0.0) continue;
    for (size_t c = u % step; c < cols; c += step) {
      uint32_t r;
      std::memcpy(&r, range_bytes + (u * cols + c) * stride, sizeof(r));
      if (r == 0) continue;
      double ca, sa;
      trig.azimuth(u, c, &ca, &sa);
      const double dz = R(2, 0) * ca * cp + R(2, 1) * sa * cp + R(2, 2) * sp;
      if (dz > min_dz) continue;
      const double rm = r * 1e-3, horiz = rm * cp + n * (1 - cp);
      const Eigen::Vector3d sp3(ca * horiz, sa * horiz, rm * sp + lz - n * sp);
      Eigen::Vector3d p = R * sp3;
      p.z() += h0;
      const double d2 = p.x() * p.x() + p.y() * p.y();
      if (d2 > max_distance * max_distance) continue;
      if (std::fabs(p.z()) > 0.05 + slope * std::sqrt(d2)) continue;
      pts.push_back(p);
    }
  }
  // Plane z = a x + b y + c, refitted with shrinking bands around the previous fit.
  double a = 0, b = 0, cc = 0;
  // The first fit uses only returns within 1.5 m (walls are rarely that close); later fits use all.
  const double slopes[5] = {slope, 0.5 * slope, 0.06, 0.02, 0.02};
  const double offsets[5] = {0.05, 0.04, 0.03, 0.03, 0.03};
  size_t used = 0;
  for (int it = 0; it < 5; ++it) {
    Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
    Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
    used = 0;
    for (const Eigen::Vector3d& p : pts) {
      const double d = std::sqrt(p.x() * p.x() + p.y() * p.y());
      if (it == 0 && d > 1.5) continue;
      if (std::fabs(p.z() - (a * p.x() + b * p.y() + cc)) > offsets[it] + slopes[it] * d) continue;
      const Eigen::Vector3d q(p.x(), p.y(), 1.0);
      A += q * q.transpose();
      rhs += q * p.z();
      ++used;
    }
    if (used < std::max<size_t>(3, min_samples)) return false;
    const Eigen::Vector3d sol = A.ldlt().solve(rhs);
    if (!sol.allFinite()) return false;
    a = sol.x();
    b = sol.y();
    cc = sol.z();
  }
  const Eigen::Vector3d normal = Eigen::Vector3d(-a, -b, 1.0).normalized();
  if (std::acos(std::min(1.0, normal.z())) > max_tilt) return false;
  const Eigen::Matrix3d correction =
      Eigen::Quaterniond::FromTwoVectors(normal, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  pose->level_from_sensor = correction * R;
  // Sensor origin (0, 0, h0) in the prior level frame; its distance to the plane.
  pose->height = (h0 - cc) * normal.z();
  return std::isfinite(pose->height) && pose->height > 0.0;
}

}  // namespace rbd_lidar
