// ROS-free: turns a 3D cloud (or a LaserScan's points) into the 2D scan the map correction
// matches, LEVELLED with the body's roll and pitch from the EKF. Without levelling, a tilted
// body (the attentive nose-up pitch of -0.25 rad while waiting for a gesture, the wiggle's
// +-0.3 rad roll) shortens every range by cos(tilt), moves the height band of the slice (floor
// behind the robot, wall tops ahead) and the match settles 0.1-0.2 m off while the robot stands.
#ifndef RBD_LOCALIZATION_SCAN_SLICE_H
#define RBD_LOCALIZATION_SCAN_SLICE_H

#include <Eigen/Geometry>
#include <limits>
#include <vector>

#include "rbd_localization/occupancy_map.h"

namespace rbd_localization {

/// Rotation taking base_link vectors into the gravity-aligned frame with the same heading and
/// origin ("levelled base"): Ry(pitch) Rx(roll) of odom_from_base's rotation (yaw removed).
Eigen::Matrix3d levelFromBase(const Eigen::Matrix3d& odom_from_base_rotation);

class ScanSlicer {
 public:
  struct Params {
    double z_min = 0.0;  ///< [m] height band kept, relative to base_link, in the levelled frame
    double z_max = 0.4;
    double min_range = 0.3;  ///< [m] horizontal range from the sensor
    double max_range = 20.0;
    int bins = 720;        ///< azimuth bins, nearest return per bin
    int max_points = 360;  ///< result decimated to about this many points
  };

  explicit ScanSlicer(const Params& params) : params_(params) {}

  /// Starts a scan: sensor pose in base_link (static mount) and levelFromBase() at its stamp.
  void begin(const Eigen::Isometry3d& base_from_sensor, const Eigen::Matrix3d& level_from_base);
  /// One 3D point in the sensor frame (non-finite points are ignored).
  void add(const Eigen::Vector3d& point_in_sensor);
  /// Nearest return per azimuth bin inside the height band, in levelled base_link (x, y),
  /// decimated to about max_points.
  Points2d finish() const;
  /// LaserScan-style input: every point kept (no height band; the scan plane is what it is),
  /// only levelled, range-gated and decimated.
  Points2d levelPlanar(const std::vector<Eigen::Vector3d>& points_in_sensor) const;

 private:
  Params params_;
  Eigen::Isometry3d level_from_sensor_ = Eigen::Isometry3d::Identity();
  std::vector<double> best_;
  Points2d pts_;
};

}  // namespace rbd_localization

#endif  // RBD_LOCALIZATION_SCAN_SLICE_H
