// The scan pipeline's sequence: configuration, then per cloud validation (cloud_validation.cpp),
// the beam model (beam_measurement.cpp), floor, zone, latch and outputs (scan_outputs.cpp).
#include "rbd_lidar/scan_pipeline.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "rbd_lidar/cloud_fields.h"
#include "rbd_lidar/floor_fit.h"

namespace rbd_lidar {

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

}  // namespace rbd_lidar
