// The beam model measured from the cloud itself: per-row altitude and azimuth from the points'
// xyz and range (the nominal beams from metadata where a row cannot be measured), the residual of
// the model against the cloud, and the slice ring.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "rbd_lidar/cloud_fields.h"
#include "rbd_lidar/scan_pipeline.h"

namespace rbd_lidar {

namespace {

constexpr unsigned kRecheckScans = 100;  // re-measure the beam angles every this many scans

double circularMean(const std::vector<double>& a) {
  double s = 0, c = 0;
  for (double v : a) {
    s += std::sin(v);
    c += std::cos(v);
  }
  return std::atan2(s, c);
}

// 1 - |mean resultant|: 0 when all angles agree.
double circularSpread(const std::vector<double>& a) {
  if (a.empty()) return 0.0;
  double s = 0, c = 0;
  for (double v : a) {
    s += std::sin(v);
    c += std::cos(v);
  }
  return 1.0 - std::hypot(s, c) / static_cast<double>(a.size());
}

}  // namespace

bool ScanPipeline::updateModel(const sensor_msgs::PointCloud2& cloud, std::string* message) {
  const int width = static_cast<int>(cloud.width);
  const size_t rows = cloud.height;
  if (model_.columns != width || model_.rows() != rows) {
    model_ = BeamModel::fromOuster(nominal_altitude_deg_, nominal_azimuth_deg_, pixel_shift_, shift_columns_,
                                   width, destaggered_, beam_origin_mm_, lidar_z_mm_);
    model_from_cloud_ = false;
    model_checked_ = false;
    scans_since_check_ = 0;
  }
  const bool check = !model_checked_ || ++scans_since_check_ >= kRecheckScans;
  const size_t step = std::max<size_t>(1, cloud.width / 128);
  const uint32_t range_off = findField(cloud, "range")->offset;
  if (check) scans_since_check_ = 0;
  if (params_.beams_from_cloud && (check || !model_from_cloud_)) {
    // Sample up to 128 columns per row; per sample the row's angles follow from xyz and range.
    BeamModel measured = model_;
    std::vector<double> alts;
    size_t measured_rows = 0;
    double spread_minus = 0, spread_plus = 0;
    std::vector<std::vector<double>> rows_minus(rows), rows_plus(rows);
    std::vector<double> row_alt(rows, std::numeric_limits<double>::quiet_NaN());
    for (size_t u = 0; u < rows; ++u) {
      alts.clear();
      for (size_t c = 0; c < cloud.width; c += step) {
        const uint8_t* pt = &cloud.data[u * cloud.row_step + c * cloud.point_step];
        uint32_t r;
        std::memcpy(&r, pt + range_off, 4);
        if (r < 500) continue;
        const Eigen::Vector3d p(readFloat(pt + x_off_), readFloat(pt + y_off_), readFloat(pt + z_off_));
        double alt, az;
        if (!BeamModel::anglesFromPoint(p, r * 1e-3, model_.lidar_z, model_.beam_origin, &alt, &az)) continue;
        alts.push_back(alt);
        const double col = kCloudTwoPi * static_cast<double>(c) / cloud.width;
        rows_minus[u].push_back(az + col);
        rows_plus[u].push_back(az - col);
      }
      if (alts.size() >= 4) {
        std::nth_element(alts.begin(), alts.begin() + alts.size() / 2, alts.end());
        row_alt[u] = alts[alts.size() / 2];
        spread_minus += circularSpread(rows_minus[u]);
        spread_plus += circularSpread(rows_plus[u]);
      }
    }
    const int direction = spread_plus < spread_minus ? 1 : -1;
    measured.direction = direction;
    for (size_t u = 0; u < rows; ++u) {
      if (!std::isfinite(row_alt[u])) continue;
      measured.altitude[u] = row_alt[u];
      measured.azimuth0[u] = circularMean(direction < 0 ? rows_minus[u] : rows_plus[u]);
      ++measured_rows;
    }
    if (measured_rows * 2 >= rows) {
      std::string why;
      if (measured.valid(&why)) {
        model_ = measured;
        model_from_cloud_ = true;
      } else if (message) {
        *message = "beam angles measured from the cloud are unusable (" + why + "); using the nominal beams";
      }
    }
  }
  if (check) {
    // Residual of the model against the cloud's own xyz on a sample of pixels.
    model_checked_ = true;
    residual_ = 0.0;
    for (size_t u = 0; u < rows; u += 3) {
      for (size_t c = 0; c < cloud.width; c += step * 8) {
        const uint8_t* pt = &cloud.data[u * cloud.row_step + c * cloud.point_step];
        uint32_t r;
        std::memcpy(&r, pt + range_off, 4);
        const Eigen::Vector3d p(readFloat(pt + x_off_), readFloat(pt + y_off_), readFloat(pt + z_off_));
        if (r == 0 || !p.allFinite()) continue;
        Eigen::Vector3d d, o;
        model_.ray(u, c, &d, &o);
        residual_ = std::max(residual_, (r * 1e-3 * d + o - p).norm());
      }
    }
  }
  // Slice ring: the beam nearest to horizontal unless configured.
  if (params_.slice_ring >= 0 && static_cast<size_t>(params_.slice_ring) < rows) {
    slice_ring_ = params_.slice_ring;
  } else {
    slice_ring_ = 0;
    for (size_t u = 1; u < rows; ++u) {
      if (std::fabs(model_.altitude[u]) < std::fabs(model_.altitude[slice_ring_]))
        slice_ring_ = static_cast<int>(u);
    }
  }
  return true;
}

}  // namespace rbd_lidar
