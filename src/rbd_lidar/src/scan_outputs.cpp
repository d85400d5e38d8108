// The pipeline's output messages for an accepted scan: the critical points (pcl::PointXYZI
// layout), the slice ring as a cloud and a LaserScan, and the CollisionState.
#include <cmath>
#include <cstring>
#include <limits>

#include "rbd_lidar/cloud_fields.h"
#include "rbd_lidar/scan_pipeline.h"

namespace rbd_lidar {

void ScanPipeline::buildOutputs(const sensor_msgs::PointCloud2& cloud, Outputs* out) const {
  const ZoneResult& z = out->zone;
  const size_t width = cloud.width;
  // Field offsets in locals: the byte stores below could alias the members, which made every
  // point reload them.
  const uint32_t x_off = x_off_, y_off = y_off_, z_off = z_off_, range_off = range_off_;

  // Critical points: pcl::PointXYZI layout (32 bytes: x y z pad intensity pad).
  sensor_msgs::PointCloud2& crit = out->critical;
  initCloud(cloud.header, 32, 16, &crit);
  crit.width = static_cast<uint32_t>(z.critical.size());
  crit.row_step = crit.width * crit.point_step;
  crit.data.resize(crit.row_step);  // capacity reused across scans; every byte is written below
  // Critical indices ascend (row-major pass), so the row follows by stepping, not by division.
  const uint8_t* base = cloud.data.data();
  const uint32_t* idx_ptr = z.critical.data();
  const uint8_t* side_ptr = z.critical_side.data();
  uint8_t* dst = crit.data.data();
  uint32_t crow = 0, row_begin = 0;
  for (size_t k = 0; k < z.critical.size(); ++k, dst += 32) {
    const uint32_t idx = idx_ptr[k];
    if (idx < row_begin) {  // not ascending (never from evaluateStrided): fall back to division
      crow = static_cast<uint32_t>(idx / width);
      row_begin = static_cast<uint32_t>(crow * width);
    }
    while (idx - row_begin >= width) {
      ++crow;
      row_begin += static_cast<uint32_t>(width);
    }
    const uint8_t* src = base + static_cast<size_t>(crow) * cloud.row_step +
                         static_cast<size_t>(idx - row_begin) * cloud.point_step;
    // pcl::PointXYZI: x y z 1 | intensity 0 0 0. Written field by field: assembling the point in
    // a local array and copying it as one block stalled every point on store forwarding.
    float x = readFloat(src + x_off), y = readFloat(src + y_off), zz = readFloat(src + z_off);
    if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(zz)) {
      // ouster-ros >= 0.13 may publish NaN xyz below its min_range: use the beam model.
      uint32_t r;
      std::memcpy(&r, src + range_off, 4);
      const Eigen::Vector3d p = zone_.sensorPoint(idx, r);
      x = static_cast<float>(p.x());
      y = static_cast<float>(p.y());
      zz = static_cast<float>(p.z());
    }
    const float one = 1.0f, intensity = 1.0f + side_ptr[k];
    std::memcpy(dst, &x, 4);
    std::memcpy(dst + 4, &y, 4);
    std::memcpy(dst + 8, &zz, 4);
    std::memcpy(dst + 12, &one, 4);
    std::memcpy(dst + 16, &intensity, 4);
    std::memset(dst + 20, 0, 12);
  }

  // Slice ring: cloud of its valid points and the LaserScan.
  sensor_msgs::PointCloud2& slice = out->slice;
  initCloud(cloud.header, 16, 12, &slice);
  slice.data.resize(width * 16);
  sensor_msgs::LaserScan& scan = out->scan;
  scan.header = cloud.header;
  scan.angle_min = static_cast<float>(-M_PI);
  scan.angle_increment = static_cast<float>(kCloudTwoPi / width);
  scan.angle_max = static_cast<float>(M_PI - kCloudTwoPi / width);
  scan.time_increment = static_cast<float>(params_.scan_time / width);
  scan.scan_time = static_cast<float>(params_.scan_time);
  scan.range_min = static_cast<float>(params_.scan_range_min);
  scan.range_max = static_cast<float>(params_.scan_range_max);
  scan.ranges.assign(width, std::numeric_limits<float>::infinity());
  scan.intensities.clear();
  const size_t u = static_cast<size_t>(slice_ring_);
  const uint8_t* row = &cloud.data[u * cloud.row_step];
  size_t count = 0;
  // Bin of column c: the ring's azimuth is azimuth0 + direction * 2*pi*c/W, so the bin index is
  // an offset plus +-c (no atan2 per point; the beam-origin offset keeps the point on that azimuth).
  double b0 = (model_.azimuth0[u] + M_PI) * width / kCloudTwoPi;
  b0 = std::fmod(b0, static_cast<double>(width));
  if (b0 < 0) b0 += width;
  const long first_bin = static_cast<long>(std::floor(b0 + 1e-9));
  const long w = static_cast<long>(width);
  for (size_t c = 0; c < width; ++c) {
    const uint8_t* src = row + c * cloud.point_step;
    uint32_t range_mm;
    std::memcpy(&range_mm, src + range_off, 4);
    if (range_mm == 0) continue;
    const float x = readFloat(src + x_off), y = readFloat(src + y_off), zz = readFloat(src + z_off);
    if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(zz)) continue;
    const float range_m = range_mm * 1e-3f;
    uint8_t* out_pt = &slice.data[count * 16];
    std::memcpy(out_pt, &x, 4);
    std::memcpy(out_pt + 4, &y, 4);
    std::memcpy(out_pt + 8, &zz, 4);
    std::memcpy(out_pt + 12, &range_m, 4);
    ++count;
    const float planar = std::sqrt(x * x + y * y);
    if (planar < scan.range_min || planar > scan.range_max) continue;
    long bin = (first_bin + model_.direction * static_cast<long>(c)) % w;
    if (bin < 0) bin += w;
    float& slot = scan.ranges[static_cast<size_t>(bin)];
    if (planar < slot) slot = planar;
  }
  slice.width = static_cast<uint32_t>(count);
  slice.row_step = slice.width * 16;
  slice.data.resize(slice.row_step);

  rbd_msgs::CollisionState& st = out->state;
  st.header = cloud.header;
  st.collision = latch_.collision();
  st.stale = false;
  st.error.clear();
  for (size_t s = 0; s < 4; ++s) {
    st.points[s] = z.counts[s];
    st.min_distance[s] = z.min_distance[s];
  }
  st.speed_scale = st.collision ? 0.0f : z.speed_scale;
}

}  // namespace rbd_lidar
