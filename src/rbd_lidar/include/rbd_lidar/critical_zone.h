// ROS-free critical-zone test of rbd_lidar (thesis §3.3.2, extended): which points of a range
// image are critical. The parts it is built from have their own headers: beam_model.h (ray
// geometry), sensor_pose.h (attitude and height), zone_params.h (zone size), zone_growth.h
// (velocity-aware growth and its hold); floor_fit.h measures the pose from the floor and
// collision_latch.h turns occupied scans into the collision state.
//
// The zone is a box around the LiDAR in a gravity-aligned "level" frame whose x axis is the
// robot's heading: a point is critical when its perpendicular distance to the LiDAR, in the
// section (front / left / back / right) its azimuth falls into, is below that side's limit,
// its range is outside the spherical blind zone and its height above the floor lies inside a
// band (so the floor never counts, whatever the body attitude).
//
// Speed: every geometric constraint is linear in the range r along a fixed ray, so the set of
// ranges that can be critical for a pixel is an interval. A lookup table holds that interval
// (as uint16 mm) for a slightly enlarged box; the per-scan pass is one subtract-and-compare per
// pixel, and only the few candidates it yields get the exact floating-point test.
#ifndef RBD_LIDAR_CRITICAL_ZONE_H
#define RBD_LIDAR_CRITICAL_ZONE_H

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

#include "rbd_lidar/beam_model.h"
#include "rbd_lidar/sensor_pose.h"
#include "rbd_lidar/zone_params.h"

namespace rbd_lidar {

struct ZoneResult {
  std::array<uint32_t, 4> counts{{0, 0, 0, 0}};  // critical points per side
  std::array<float, 4> min_distance;             // smallest perpendicular distance per side among
                                                 // points in the stop or slowdown zone [m]; +inf: none
  std::vector<uint32_t> critical;                // indices (row * columns + column) of critical points
  std::vector<uint8_t> critical_side;            // Side of each critical point
  float speed_scale = 1.0f;                      // [0, 1] from the slowdown band
  uint32_t valid_returns = 0;                    // pixels with a non-zero range
  uint32_t total() const { return counts[0] + counts[1] + counts[2] + counts[3]; }
};

class CriticalZone {
 public:
  CriticalZone();

  // Optional debug sink (table rebuilds); nullptr disables.
  void setDebug(std::ostream* out) { debug_ = out; }

  // Set the model; cheap when nothing relevant changed (the table is rebuilt only when the beam
  // model changes, the attitude moves by more than the table's margin or the zone outgrows it).
  // Returns false with a reason when the inputs are unusable.
  bool configure(const BeamModel& beams, const ZoneParams& zone, const SensorPose& pose, std::string* error);

  // Classify one range image (rows x columns uint32 [mm], row-major, 0 = no return).
  void evaluate(const uint32_t* range_mm, ZoneResult* out) const;
  // The same on a strided source: the range of pixel i is the uint32 at range_bytes + i * stride,
  // e.g. the `range` field of an organised PointCloud2 with row_step = width * point_step.
  void evaluateStrided(const uint8_t* range_bytes, size_t stride, ZoneResult* out) const;

  // Change only the sensor height (cheap; the candidate table does not depend on it).
  void setHeight(double height) { pose_.height = height; }

  // Point of pixel `index` at `range_mm` in the level frame, z = height above the floor [m].
  Eigen::Vector3d levelPoint(uint32_t index, uint32_t range_mm) const;
  // Point in the sensor frame [m].
  Eigen::Vector3d sensorPoint(uint32_t index, uint32_t range_mm) const;

  // Azimuths of the zone corners phi1..phi4 [rad]: front-left, back-left, back-right, front-right.
  static std::array<double, 4> cornerAzimuths(const ZoneParams& zone);
  // Section of a horizontal direction (azimuth [rad] in the level frame).
  static Side section(double azimuth, const std::array<double, 4>& corners);

  size_t rows() const { return beams_.rows(); }
  size_t columns() const { return static_cast<size_t>(beams_.columns); }
  const ZoneParams& zone() const { return zone_; }
  const SensorPose& pose() const { return pose_; }
  const BeamModel& beams() const { return beams_; }
  const BeamTrig& trig() const { return trig_; }
  // Whether configure() has succeeded (the model is usable).
  bool configured() const { return table_valid_; }
  size_t tableBuilds() const { return builds_; }

 private:
  struct Interval {
    uint16_t lo;    // first range that may be a candidate [mm]
    uint16_t span;  // candidate if (r - lo) < span (unsigned)
  };
  void buildTable();
  // Per-thread scratch of evaluateStrided: candidates (pixel index, range, column cos/sin), the
  // first candidate of each row, and the candidates' level-frame x, y and height.
  struct Scratch {
    std::vector<uint32_t> index, range;
    std::vector<float> cos_col, sin_col, x, y, h;
    std::vector<size_t> row_first;
    void reserve(size_t pixels, size_t rows);
  };

  BeamModel beams_;
  ZoneParams zone_;
  SensorPose pose_;
  std::array<double, 4> corners_;
  // State the table was built for.
  Eigen::Matrix3d table_rotation_;
  std::array<double, 4> table_extent_{{0, 0, 0, 0}};  // front, left, back, right [m]
  double table_blind_ = -1.0;
  bool table_valid_ = false;
  std::vector<Interval> table_;
  BeamTrig trig_;
  std::ostream* debug_ = nullptr;
  size_t builds_ = 0;
};

}  // namespace rbd_lidar

#endif  // RBD_LIDAR_CRITICAL_ZONE_H
