#include "rbd_lidar/beam_model.h"

#include <cmath>

namespace rbd_lidar {

namespace {
constexpr double kTwoPi = 2.0 * M_PI;
}  // namespace

BeamModel BeamModel::fromOuster(const std::vector<double>& altitude_deg,
                                const std::vector<double>& azimuth_deg, const std::vector<int>& pixel_shift,
                                int shift_columns, int columns, bool destaggered, double beam_origin_mm,
                                double lidar_z_mm) {
  BeamModel m;
  m.columns = columns;
  m.direction = -1;
  m.beam_origin = beam_origin_mm * 1e-3;
  m.lidar_z = lidar_z_mm * 1e-3;
  const double deg = M_PI / 180.0;
  for (size_t u = 0; u < altitude_deg.size(); ++u) {
    m.altitude.push_back(altitude_deg[u] * deg);
    const double az = u < azimuth_deg.size() ? azimuth_deg[u] * deg : 0.0;
    double shift = 0.0;
    if (destaggered && u < pixel_shift.size() && shift_columns > 0) {
      shift = static_cast<double>(pixel_shift[u]) * columns / shift_columns;
    }
    // Encoder angle 2*pi*(1 - c_staggered/W), beam offset -az, os_lidar -> os_sensor turns by pi;
    // a destaggered column c holds the staggered column c - shift.
    m.azimuth0.push_back(wrapAngle(M_PI - az + kTwoPi * shift / columns));
  }
  return m;
}

bool BeamModel::valid(std::string* why) const {
  std::string reason;
  if (altitude.empty()) {
    reason = "no beams";
  } else if (azimuth0.size() != altitude.size()) {
    reason = "beam azimuth count differs from beam altitude count";
  } else if (columns <= 0 || columns > 65536) {
    reason = "column count out of range";
  } else if (direction != 1 && direction != -1) {
    reason = "direction must be +1 or -1";
  } else {
    for (size_t u = 0; u < altitude.size(); ++u) {
      if (!std::isfinite(altitude[u]) || !std::isfinite(azimuth0[u]) || std::fabs(altitude[u]) >= M_PI / 2) {
        reason = "beam angle not finite or |altitude| >= 90 deg";
        break;
      }
    }
  }
  if (reason.empty() && (!std::isfinite(beam_origin) || !std::isfinite(lidar_z)))
    reason = "offsets not finite";
  if (why) *why = reason;
  return reason.empty();
}

void BeamModel::ray(size_t row, size_t col, Eigen::Vector3d* d, Eigen::Vector3d* o) const {
  const double a = azimuth0[row] + direction * kTwoPi * static_cast<double>(col) / columns;
  const double ca = std::cos(a), sa = std::sin(a);
  const double cp = std::cos(altitude[row]), sp = std::sin(altitude[row]);
  *d = Eigen::Vector3d(ca * cp, sa * cp, sp);
  *o = Eigen::Vector3d(beam_origin * ca * (1 - cp), beam_origin * sa * (1 - cp), lidar_z - beam_origin * sp);
}

bool BeamModel::anglesFromPoint(const Eigen::Vector3d& p, double range, double lidar_z, double beam_origin,
                                double* altitude, double* azimuth) {
  if (!p.allFinite() || !std::isfinite(range) || range <= beam_origin + 0.05) return false;
  // p_z = (r - n) sin(alt) + lidar_z, exactly; the horizontal n-term is < 1.2 mm and ignored.
  const double s = (p.z() - lidar_z) / (range - beam_origin);
  if (s <= -1.0 || s >= 1.0 || std::hypot(p.x(), p.y()) < 1e-6) return false;
  *altitude = std::asin(s);
  *azimuth = std::atan2(p.y(), p.x());
  return true;
}

void BeamTrig::build(const BeamModel& beams) {
  const size_t rows = beams.rows(), cols = static_cast<size_t>(beams.columns);
  cos_alt.resize(rows);
  sin_alt.resize(rows);
  cos_az0.resize(rows);
  sin_az0.resize(rows);
  for (size_t u = 0; u < rows; ++u) {
    cos_alt[u] = std::cos(beams.altitude[u]);
    sin_alt[u] = std::sin(beams.altitude[u]);
    cos_az0[u] = std::cos(beams.azimuth0[u]);
    sin_az0[u] = std::sin(beams.azimuth0[u]);
  }
  cos_col.resize(cols);
  sin_col.resize(cols);
  for (size_t c = 0; c < cols; ++c) {
    const double a = beams.direction * kTwoPi * static_cast<double>(c) / static_cast<double>(cols);
    cos_col[c] = std::cos(a);
    sin_col[c] = std::sin(a);
  }
}

Eigen::Vector3d BeamTrig::point(const BeamModel& beams, size_t u, size_t c, double r) const {
  double ca, sa;
  azimuth(u, c, &ca, &sa);
  const double cp = cos_alt[u], sp = sin_alt[u], n = beams.beam_origin;
  return Eigen::Vector3d(r * ca * cp + n * ca * (1 - cp), r * sa * cp + n * sa * (1 - cp),
                         r * sp + beams.lidar_z - n * sp);
}

}  // namespace rbd_lidar
