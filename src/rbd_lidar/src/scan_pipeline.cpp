#include "rbd_lidar/scan_pipeline.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "rbd_lidar/floor_fit.h"

namespace rbd_lidar {

namespace {

constexpr double kTwoPi = 2.0 * M_PI;
constexpr unsigned kRecheckScans = 100;  // re-measure the beam angles every this many scans

const sensor_msgs::PointField* findField(const sensor_msgs::PointCloud2& cloud, const char* name) {
  for (const auto& f : cloud.fields) {
    if (f.name == name) return &f;
  }
  return nullptr;
}

void addField(sensor_msgs::PointCloud2* msg, const char* name, uint32_t offset) {
  sensor_msgs::PointField f;
  f.name = name;
  f.offset = offset;
  f.datatype = sensor_msgs::PointField::FLOAT32;
  f.count = 1;
  msg->fields.push_back(f);
}

// An unorganised float cloud with fields x y z intensity at offsets 0 4 8 `intensity_offset`.
// The field list is rebuilt only when it differs (the output messages are reused every scan).
void initCloud(const std_msgs::Header& header, uint32_t point_step, uint32_t intensity_offset,
               sensor_msgs::PointCloud2* msg) {
  msg->header = header;
  msg->height = 1;
  msg->width = 0;
  if (msg->fields.size() != 4 || msg->fields[3].offset != intensity_offset || msg->fields[0].name != "x" ||
      msg->fields[3].name != "intensity") {
    msg->fields.clear();
    addField(msg, "x", 0);
    addField(msg, "y", 4);
    addField(msg, "z", 8);
    addField(msg, "intensity", intensity_offset);
  }
  msg->is_bigendian = false;
  msg->point_step = point_step;
  msg->row_step = 0;
  msg->is_dense = true;
  msg->data.clear();
}

inline float readFloat(const uint8_t* p) {
  float v;
  std::memcpy(&v, p, sizeof(v));
  return v;
}

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

const char* errorName(CloudError e) {
  switch (e) {
    case CloudError::NONE:
      return "none";
    case CloudError::EMPTY:
      return "empty cloud";
    case CloudError::NO_RANGE_FIELD:
      return "missing range field";
    case CloudError::BAD_FIELD:
      return "bad field type";
    case CloudError::BAD_POINT_STEP:
      return "wrong point_step";
    case CloudError::BAD_HEIGHT:
      return "height differs from beams";
    case CloudError::BAD_SIZE:
      return "data size mismatch (truncated)";
    case CloudError::NO_VALID_RETURNS:
      return "too few valid returns";
    case CloudError::BAD_GEOMETRY:
      return "unusable beam geometry";
    default:
      return "unknown";
  }
}

ScanPipeline::ScanPipeline() : latch_(params_.hysteresis_scans) {}

void ScanPipeline::setNominalBeams(const std::vector<double>& altitude_deg,
                                   const std::vector<double>& azimuth_deg,
                                   const std::vector<int>& pixel_shift, int shift_columns, bool destaggered,
                                   double beam_origin_mm, double lidar_z_mm) {
  nominal_altitude_deg_ = altitude_deg;
  nominal_azimuth_deg_ = azimuth_deg;
  pixel_shift_ = pixel_shift;
  shift_columns_ = shift_columns;
  destaggered_ = destaggered;
  beam_origin_mm_ = beam_origin_mm;
  lidar_z_mm_ = lidar_z_mm;
  model_.columns = 0;  // rebuilt on the next cloud
  model_from_cloud_ = false;
}

void ScanPipeline::setParams(const PipelineParams& p) {
  if (p.beams_from_cloud != params_.beams_from_cloud || p.slice_ring != params_.slice_ring) {
    model_.columns = 0;
    model_from_cloud_ = false;
  }
  params_ = p;
  latch_.setClearScans(std::max(1u, p.hysteresis_scans));
}

CloudError ScanPipeline::validate(const sensor_msgs::PointCloud2& cloud, std::string* message) const {
  auto fail = [message](CloudError e, const std::string& what) {
    if (message) *message = std::string(errorName(e)) + ": " + what;
    return e;
  };
  if (cloud.width == 0 || cloud.height == 0 || cloud.data.empty()) {
    return fail(CloudError::EMPTY, "width " + std::to_string(cloud.width) + ", height " +
                                       std::to_string(cloud.height) + ", " +
                                       std::to_string(cloud.data.size()) + " bytes");
  }
  const sensor_msgs::PointField* range = findField(cloud, "range");
  if (!range)
    return fail(CloudError::NO_RANGE_FIELD, "the cloud has no `range` field (ouster-ros layout needed)");
  if (range->datatype != sensor_msgs::PointField::UINT32 || range->count != 1) {
    return fail(CloudError::BAD_FIELD, "`range` must be one UINT32 (datatype 6)");
  }
  uint32_t end = range->offset + 4;
  for (const char* name : {"x", "y", "z"}) {
    const sensor_msgs::PointField* f = findField(cloud, name);
    if (!f || f->datatype != sensor_msgs::PointField::FLOAT32 || f->count != 1) {
      return fail(CloudError::BAD_FIELD, std::string("field `") + name + "` missing or not FLOAT32");
    }
    end = std::max(end, f->offset + 4);
  }
  if (cloud.is_bigendian) return fail(CloudError::BAD_FIELD, "big-endian clouds are not supported");
  if (cloud.point_step < end) {
    return fail(CloudError::BAD_POINT_STEP, "point_step " + std::to_string(cloud.point_step) +
                                                " is smaller than the fields (" + std::to_string(end) +
                                                " bytes)");
  }
  if (static_cast<uint64_t>(cloud.row_step) < static_cast<uint64_t>(cloud.width) * cloud.point_step) {
    return fail(CloudError::BAD_POINT_STEP,
                "row_step " + std::to_string(cloud.row_step) + " < width * point_step");
  }
  if (cloud.height != beams()) {
    return fail(CloudError::BAD_HEIGHT, "height " + std::to_string(cloud.height) + " but " +
                                            std::to_string(beams()) + " beams (organised cloud needed)");
  }
  if (cloud.width > 65536) return fail(CloudError::BAD_SIZE, "width " + std::to_string(cloud.width));
  const uint64_t need = static_cast<uint64_t>(cloud.row_step) * cloud.height;
  if (cloud.data.size() != need) {
    return fail(CloudError::BAD_SIZE, std::to_string(cloud.data.size()) +
                                          " bytes of data, row_step * height = " + std::to_string(need));
  }
  return CloudError::NONE;
}

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
        const double col = kTwoPi * static_cast<double>(c) / cloud.width;
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

CloudError ScanPipeline::process(const sensor_msgs::PointCloud2& cloud, Outputs* out, std::string* message) {
  if (message) message->clear();
  CloudError err = validate(cloud, message);
  if (err == CloudError::NONE) {
    x_off_ = findField(cloud, "x")->offset;
    y_off_ = findField(cloud, "y")->offset;
    z_off_ = findField(cloud, "z")->offset;
    std::string note;
    updateModel(cloud, &note);
    std::string why;
    if (!zone_.configure(model_, zone_params_, pose_, &why)) {
      err = CloudError::BAD_GEOMETRY;
      if (message) *message = std::string(errorName(err)) + ": " + why;
    }
  }
  if (err == CloudError::NONE) {
    // The zone reads the `range` field in place (one strided pass, no range-image copy).
    const size_t n = static_cast<size_t>(cloud.width) * cloud.height;
    // Bytes, not a uint32 reference: the field may sit at any offset (UBSan flagged the iterator's
    // misaligned reference on fuzzed layouts); every read is a memcpy.
    range_off_ = findField(cloud, "range")->offset;
    const uint8_t* range_bytes = cloud.data.data() + range_off_;
    size_t stride = cloud.point_step;
    if (cloud.row_step != cloud.width * cloud.point_step) {  // padded rows: compact the range image
      range_.resize(n);
      for (size_t u = 0; u < cloud.height; ++u) {
        for (size_t c = 0; c < cloud.width; ++c) {
          std::memcpy(&range_[u * cloud.width + c],
                      &cloud.data[u * cloud.row_step + c * cloud.point_step + range_off_], 4);
        }
      }
      range_bytes = reinterpret_cast<const uint8_t*>(range_.data());
      stride = sizeof(uint32_t);
    }
    // Floor: the sensor attitude and height measured every scan from the floor plane under the
    // sensor (the body-pose attitude is only a prior; it lags during body-pose transitions), the
    // height bounded around the nominal height from the body pose.
    height_measured_ = false;
    if (params_.floor_from_cloud) {
      SensorPose floor = pose_;
      if (estimateFloor(zone_, range_bytes, stride, 3.0, params_.floor_max_tilt,
                        std::max<size_t>(1, cloud.width / 64), 50, &floor)) {
        const double tol = std::max(0.0, params_.floor_height_tolerance);
        floor.height = std::min(pose_.height + tol, std::max(pose_.height - tol, floor.height));
        std::string ignored;
        if (zone_.configure(model_, zone_params_, floor, &ignored)) height_measured_ = true;
      } else {
        double h;
        if (estimateHeight(zone_, range_bytes, stride, 3.0, 0.8, std::max<size_t>(1, cloud.width / 128), 50,
                           &h) &&
            std::isfinite(h)) {
          const double tol = std::max(0.0, params_.floor_height_tolerance);
          zone_.setHeight(std::min(pose_.height + tol, std::max(pose_.height - tol, h)));
          height_measured_ = true;
        }
      }
    }
    zone_.evaluateStrided(range_bytes, stride, &out->zone);
    if (out->zone.valid_returns < params_.min_valid_fraction * static_cast<double>(n)) {
      err = CloudError::NO_VALID_RETURNS;
      if (message) {
        *message = std::string(errorName(err)) + ": " + std::to_string(out->zone.valid_returns) + " of " +
                   std::to_string(n) + " pixels have a range";
      }
    }
  }
  if (err != CloudError::NONE) {
    out->zone = ZoneResult();
    initCloud(cloud.header, 32, 16, &out->critical);
    initCloud(cloud.header, 16, 12, &out->slice);
    out->scan = sensor_msgs::LaserScan();
    out->scan.header = cloud.header;
    fail(false, message ? *message : errorName(err), &out->state);
    out->state.header = cloud.header;
    return err;
  }
  latch_.update(out->zone.total() >= std::max(1u, zone_params_.point_threshold));
  buildOutputs(cloud, out);
  return err;
}

void ScanPipeline::extractRange(const sensor_msgs::PointCloud2& cloud, std::vector<uint32_t>* range) {
  range->resize(static_cast<size_t>(cloud.width) * cloud.height);
  const uint32_t off = findField(cloud, "range")->offset;
  for (size_t u = 0; u < cloud.height; ++u) {
    for (size_t c = 0; c < cloud.width; ++c) {
      std::memcpy(&(*range)[u * cloud.width + c],
                  &cloud.data[u * cloud.row_step + c * cloud.point_step + off], 4);
    }
  }
}

void ScanPipeline::fail(bool stale, const std::string& error, rbd_msgs::CollisionState* state) {
  latch_.fail();
  state->collision = true;
  state->stale = stale;
  state->error = error;
  for (size_t s = 0; s < 4; ++s) {
    state->points[s] = 0;
    state->min_distance[s] = std::numeric_limits<float>::infinity();
  }
  state->speed_scale = 0.0f;
}

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
  scan.angle_increment = static_cast<float>(kTwoPi / width);
  scan.angle_max = static_cast<float>(M_PI - kTwoPi / width);
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
  double b0 = (model_.azimuth0[u] + M_PI) * width / kTwoPi;
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
