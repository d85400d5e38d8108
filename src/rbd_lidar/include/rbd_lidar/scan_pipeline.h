// Per-scan pipeline of rbd_lidar on ROS messages, without a node: layout validation, range
// extraction (the `range` field read in place), beam geometry, critical zone, and the
// output messages (critical cloud, slice cloud, LaserScan, CollisionState). The node and the
// benchmark both run exactly this.
#ifndef RBD_LIDAR_SCAN_PIPELINE_H
#define RBD_LIDAR_SCAN_PIPELINE_H

#include <rbd_msgs/CollisionState.h>
#include <sensor_msgs/LaserScan.h>
#include <sensor_msgs/PointCloud2.h>

#include <string>
#include <vector>

#include "rbd_lidar/collision_latch.h"
#include "rbd_lidar/critical_zone.h"

namespace rbd_lidar {

// Kinds of rejected clouds (each is logged once per kind, throttled, by the node).
enum class CloudError {
  NONE = 0,
  EMPTY,             // no points / no data
  NO_RANGE_FIELD,    // no `range` field
  BAD_FIELD,         // range not UINT32, x/y/z not FLOAT32, or big-endian
  BAD_POINT_STEP,    // point_step too small for the fields, or row_step < width * point_step
  BAD_HEIGHT,        // height differs from the number of beams
  BAD_SIZE,          // data shorter or longer than row_step * height (truncated)
  NO_VALID_RETURNS,  // too few non-zero ranges (blinded sensor, all-NaN cloud)
  BAD_GEOMETRY,      // beam model unusable for this cloud
  COUNT
};
const char* errorName(CloudError e);

struct PipelineParams {
  int slice_ring = -1;                   // row of the slice / LaserScan; -1: the beam nearest to horizontal
  double scan_range_min = 0.30;          // LaserScan range_min [m]
  double scan_range_max = 120.0;         // LaserScan range_max [m]
  double scan_time = 0.1;                // LaserScan scan_time [s] (1 / scan rate)
  double min_valid_fraction = 0.01;      // fewer non-zero ranges than this fraction => NO_VALID_RETURNS
  bool beams_from_cloud = true;          // measure per-row altitude / azimuth from the cloud's own xyz
  unsigned hysteresis_scans = 3;         // clear scans needed to release a collision
  bool floor_from_cloud = true;          // measure the sensor height above the floor from the returns
  double floor_height_tolerance = 0.20;  // the measurement may move the nominal height by at most this [m]
  double floor_max_tilt = 0.35;          // the floor fit may correct the prior attitude by at most this [rad]
};

class ScanPipeline {
 public:
  struct Outputs {
    ZoneResult zone;
    sensor_msgs::PointCloud2 critical;  // x y z intensity (pcl::PointXYZI layout); intensity = 1 + side
    sensor_msgs::PointCloud2 slice;     // x y z intensity(range [m]) of the slice ring, valid points only
    sensor_msgs::LaserScan scan;
    rbd_msgs::CollisionState state;
  };

  ScanPipeline();

  // Nominal beams (from parameters): used for rows the cloud cannot measure, and for all rows
  // when beams_from_cloud is false. Angles in degrees as in Ouster metadata.
  void setNominalBeams(const std::vector<double>& altitude_deg, const std::vector<double>& azimuth_deg,
                       const std::vector<int>& pixel_shift, int shift_columns, bool destaggered,
                       double beam_origin_mm, double lidar_z_mm);
  void setParams(const PipelineParams& p);
  void setZone(const ZoneParams& zone) { zone_params_ = zone; }
  void setPose(const SensorPose& pose) { pose_ = pose; }
  size_t beams() const { return nominal_altitude_deg_.size(); }

  // Full scan. On a rejected cloud: returns the error, `message` explains, the latch goes to
  // collision and out->state reports it (clouds are emptied).
  CloudError process(const sensor_msgs::PointCloud2& cloud, Outputs* out, std::string* message);
  // Validation alone.
  CloudError validate(const sensor_msgs::PointCloud2& cloud, std::string* message) const;
  // Range image (row-major uint32 mm) of a validated cloud, and the zone core alone on such an
  // image with the current configuration (benchmark, tests).
  static void extractRange(const sensor_msgs::PointCloud2& cloud, std::vector<uint32_t>* range);
  void evaluateOnly(const std::vector<uint32_t>& range, ZoneResult* out) const {
    zone_.evaluate(range.data(), out);
  }
  // Failure from outside (stale input): collision, fills a state message.
  void fail(bool stale, const std::string& error, rbd_msgs::CollisionState* state);
  bool collision() const { return latch_.collision(); }
  const CriticalZone& zone() const { return zone_; }
  const BeamModel& model() const { return model_; }
  int sliceRing() const { return slice_ring_; }
  // Largest disagreement between the cloud's xyz and the beam model on the last check [m].
  double modelResidual() const { return residual_; }
  // Sensor height used for the last scan [m] and whether it was measured from the cloud.
  double sensorHeight() const { return zone_.pose().height; }
  bool heightMeasured() const { return height_measured_; }

 private:
  bool updateModel(const sensor_msgs::PointCloud2& cloud, std::string* message);
  void buildOutputs(const sensor_msgs::PointCloud2& cloud, Outputs* out) const;

  std::vector<double> nominal_altitude_deg_, nominal_azimuth_deg_;
  std::vector<int> pixel_shift_;
  int shift_columns_ = 512;
  bool destaggered_ = true;
  double beam_origin_mm_ = 15.806, lidar_z_mm_ = 36.18;
  PipelineParams params_;
  ZoneParams zone_params_;
  SensorPose pose_;
  BeamModel model_;
  bool model_from_cloud_ = false;  // model_ holds measured angles for the current width
  bool model_checked_ = false;     // residual_ computed for the current model
  unsigned scans_since_check_ = 0;
  double residual_ = 0.0;
  bool height_measured_ = false;
  int slice_ring_ = 0;
  CriticalZone zone_;
  CollisionLatch latch_;
  std::vector<uint32_t> range_;  // compacted range image, only for clouds with padded rows
  uint32_t x_off_ = 0, y_off_ = 4, z_off_ = 8, range_off_ = 32;
};

}  // namespace rbd_lidar

#endif  // RBD_LIDAR_SCAN_PIPELINE_H
