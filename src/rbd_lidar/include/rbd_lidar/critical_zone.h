// ROS-free critical-zone model of rbd_lidar (thesis §3.3.2, extended).
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

namespace rbd_lidar {

// Side indices, the same order as rbd_msgs/CollisionState.
enum Side : uint8_t { FRONT = 0, LEFT = 1, BACK = 2, RIGHT = 3 };

// Geometry of the beams of an organised (rows x columns) range image, in the sensor frame
// (os_sensor). For pixel (u, c) the beam azimuth is azimuth0[u] + direction * 2*pi*c/columns and
// its elevation altitude[u]; the point is p = r*d + n*((cos a, sin a, 0) - d) + (0, 0, lidar_z)
// with d the unit ray and n the lidar-origin-to-beam-origin distance (ouster-sdk xyzlut model;
// using the beam instead of the encoder azimuth in the n-term changes p by < 1.2 mm).
struct BeamModel {
  std::vector<double> altitude;  // per row [rad], positive up, row 0 = top beam
  std::vector<double> azimuth0;  // per row: azimuth of column 0 in the sensor frame [rad]
  int columns = 0;
  int direction = -1;             // +1: azimuth grows with the column, -1: it falls (Ouster)
  double beam_origin = 0.015806;  // lidar_origin_to_beam_origin [m]
  double lidar_z = 0.03618;       // os_sensor -> os_lidar height [m]

  // From Ouster metadata: altitude/azimuth in degrees, pixel shifts as in the metadata for
  // shift_columns columns (scaled to `columns`), destaggered = the cloud is destaggered.
  static BeamModel fromOuster(const std::vector<double>& altitude_deg, const std::vector<double>& azimuth_deg,
                              const std::vector<int>& pixel_shift, int shift_columns, int columns,
                              bool destaggered, double beam_origin_mm, double lidar_z_mm);

  size_t rows() const { return altitude.size(); }
  bool valid(std::string* why) const;
  // Unit ray d and offset o in the sensor frame: p = r * d + o.
  void ray(size_t row, size_t col, Eigen::Vector3d* d, Eigen::Vector3d* o) const;
  // Replace the angles of row `row` by the ones measured from one point (sensor-frame xyz [m]
  // and range [m]) at column `col`. Returns false if the point is unusable.
  static bool anglesFromPoint(const Eigen::Vector3d& p, double range, double lidar_z, double beam_origin,
                              double* altitude, double* azimuth);
};

// Zone sizes and filters. Distances are perpendicular distances from the LiDAR [m].
struct ZoneParams {
  double front = 0.70;
  double back = 0.55;
  double left = 0.35;
  double right = 0.35;
  double slowdown_front = 0.50;  // width of the slowdown band outside the stop zone, per side [m]
  double slowdown_back = 0.30;
  double slowdown_left = 0.20;
  double slowdown_right = 0.20;
  double blind_zone = 0.30;       // ranges below this are ignored [m]
  double floor_clearance = 0.10;  // points lower than this above the floor are ignored [m]
  double max_height = 2.0;        // points higher than this above the floor are ignored [m]
  unsigned point_threshold = 5;   // this many critical points make a collision
};

// Pose of the sensor relative to the floor.
struct SensorPose {
  Eigen::Matrix3d level_from_sensor = Eigen::Matrix3d::Identity();  // rotation sensor -> level frame
  double height = 0.38;                                             // sensor origin above the floor [m]

  // Body roll/pitch [rad] (base_link w.r.t. gravity), the mount base_link -> sensor and the height
  // of base_link above the floor [m].
  static SensorPose fromBody(double roll, double pitch, const Eigen::Matrix3d& mount_rotation,
                             const Eigen::Vector3d& mount_translation, double base_height);
  // Sensor tilt from the specific force measured by an IMU fixed to the sensor (axes parallel to
  // the sensor frame, as the Ouster's internal IMU): the rotation taking `accel` to +z, followed
  // by `heading_yaw` (yaw of the sensor x axis relative to the robot's heading, e.g. the mount yaw).
  // Returns false (and leaves *rotation) for a non-finite or near-zero vector.
  static bool levelFromGravity(const Eigen::Vector3d& accel, double heading_yaw, Eigen::Matrix3d* rotation);
};

// Velocity-aware growth of the stop zone.
struct MotionParams {
  double reaction_time = 0.7;    // each side grows by the commanded speed towards it times this [s]
  double rotation_lever = 0.30;  // turning at w grows every side by |w| * lever * reaction_time [m]
  double max_growth = 0.50;      // growth cap per side [m]
};

// The stop zone grown for the commanded body velocity (vx, vy [m/s], wz [rad/s]).
ZoneParams grownZone(const ZoneParams& base, double vx, double vy, double wz, const MotionParams& motion);

// Keeps a stopped motion's zone until its collision is released. A collision latched while the
// robot moved was found in the zone grown for that motion; once the robot stands still the zone
// shrinks back to its rest size, and an obstacle between the two sizes would release the latch
// at once: the robot resumes, grows the zone, stops again (stop-and-go towards a bag on the path,
// never standing long enough to be judged blocked). While the latch holds and no motion is
// commanded, every side stays at least as large as in the last motion commanded during the
// latched period; a new motion (stepping back, a detour) replaces the held zone with its own.
class ZoneHold {
 public:
  // The zone to check this scan: `now` (the zone for the current command), or while `latched` and
  // not `moving`, `now` with every side at least the held zone's. `enabled` false: always `now`.
  ZoneParams apply(const ZoneParams& now, bool moving, bool latched, bool enabled = true);
  // Whether the last apply() returned a zone larger than `now` on some side.
  bool holding() const { return holding_; }

 private:
  ZoneParams held_;
  bool valid_ = false;
  bool holding_ = false;
};

// A zone whose distances are measured from a point fixed to the body (the zone origin) instead of
// from the LiDAR, expressed around the LiDAR: (dx, dy) [m] is the LiDAR's position relative to the
// zone origin in the level frame (x = heading). Front/left shrink and back/right grow by the
// offset, never below 0. *clamped (optional) tells whether a side had to be clamped (the LiDAR
// sits outside the zone). Non-finite offsets leave the zone unchanged.
ZoneParams zoneAroundOrigin(const ZoneParams& zone, double dx, double dy, bool* clamped = nullptr);

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

  // Sensor height above the floor measured from the returns themselves: with the configured
  // attitude, downward rays that end within `max_distance` horizontally give "sensor height if
  // this return is on the floor"; the floor is the lowest surface, so a high quantile of these
  // (`quantile`, e.g. 0.8) is the estimate. Rows are sampled every `column_step` columns. Returns
  // false if fewer than `min_samples` such returns exist. Strided source as evaluateStrided.
  bool estimateHeight(const uint8_t* range_bytes, size_t stride, double max_distance, double quantile,
                      size_t column_step, size_t min_samples, double* height) const;
  // Floor plane measured from the returns themselves (the configured attitude is only a prior):
  // downward returns within `max_distance` horizontally whose height lies within a band around the
  // prior floor that widens with distance by `max_tilt` (tolerating that much attitude error) are
  // fitted with a least-squares plane; two more fits with shrinking bands reject obstacles. On
  // success *pose is the corrected sensor pose (floor plane = z 0) and true is returned; false if
  // fewer than `min_samples` returns support the plane or the correction exceeds `max_tilt`.
  bool estimateFloor(const uint8_t* range_bytes, size_t stride, double max_distance, double max_tilt,
                     size_t column_step, size_t min_samples, SensorPose* pose) const;
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
  // Per-pixel trigonometry split into per-row and per-column tables.
  std::vector<double> cos_alt_, sin_alt_, cos_az0_, sin_az0_, cos_col_, sin_col_;
  std::ostream* debug_ = nullptr;
  size_t builds_ = 0;
};

// Hysteresis: collision as soon as a scan is occupied; clear only after `clear_scans`
// consecutive clear scans. Starts in collision (nothing has been seen yet).
class CollisionLatch {
 public:
  explicit CollisionLatch(unsigned clear_scans = 3) : clear_scans_(clear_scans) {}
  void setClearScans(unsigned n) { clear_scans_ = n; }
  // One valid scan; returns the collision state.
  bool update(bool occupied);
  // Invalid or stale input: collision, and the clear count starts again.
  void fail() {
    collision_ = true;
    clear_run_ = 0;
  }
  bool collision() const { return collision_; }

 private:
  unsigned clear_scans_;
  unsigned clear_run_ = 0;
  bool collision_ = true;
};

}  // namespace rbd_lidar

#endif  // RBD_LIDAR_CRITICAL_ZONE_H
