// ROS-free map correction: builds the 2D map in the first seconds, then matches every scan
// against it with the EKF pose as prior and maintains map -> odom (gated, rate-limited),
// refining the map slowly from well-matched scans.
#ifndef RBD_LOCALIZATION_MAP_CORRECTION_H
#define RBD_LOCALIZATION_MAP_CORRECTION_H

#include <Eigen/Geometry>
#include <string>

#include "rbd_localization/occupancy_map.h"
#include "rbd_localization/scan_matcher.h"

namespace rbd_localization {

class MapCorrection {
 public:
  struct Params {
    double initial_mapping_duration = 2.0;  ///< [s] scans inserted without matching
    int initial_mapping_min_scans = 5;      ///< ... and at least this many
    double map_update_interval = 1.0;       ///< [s] between refinements from matched scans
    /// Refine only after the robot moved this far [m] / turned this much [rad] since the last
    /// refinement: a standing robot would otherwise burn people standing in view, and its own
    /// small match errors, into the map again and again (the map, and the pose, creep).
    double map_update_min_translation = 0.1;
    double map_update_min_rotation = 0.1;
    double map_update_weight = 0.3;             ///< scales hit/miss log-odds during refinement
    double min_inlier_ratio = 0.5;              ///< fit gate: share of points near structure
    double max_rms = 0.06;                      ///< fit gate: inliers' RMS distance [m]
    int min_inliers = 40;                       ///< fit gate
    double min_translation_information = 0.02;  ///< fit gate: degenerate geometry (corridor)
    double max_jump_translation = 0.5;          ///< [m] matched pose vs prior beyond this: rejected
    double max_jump_rotation = 0.35;            ///< [rad]
    double max_correction_speed = 0.5;          ///< [m/s] how fast the corrected pose may move
    double max_correction_angular_speed = 0.5;  ///< [rad/s]
    /// Largest correction applied from one scan [m] / [rad], however long matches were refused
    /// before (the pose consumers then never see a jump, only a bounded step per scan).
    double max_correction_step = 0.02;
    double max_correction_step_rotation = 0.02;
    OccupancyMap::Params map;
    ScanMatcher::Params matcher;
  };

  enum class Status { kMapping, kAccepted, kRejectedFit, kRejectedJump, kRejectedEmpty };

  struct Update {
    Status status = Status::kRejectedEmpty;
    ScanMatcher::Result match;
    Eigen::Isometry2d map_from_odom = Eigen::Isometry2d::Identity();
    bool map_changed = false;
    std::string reason;
  };

  MapCorrection();
  explicit MapCorrection(const Params& params);

  /// One scan (points in base_link, z dropped) with the EKF's odom -> base_link at its time.
  Update processScan(double time, const Points2d& points_in_base, const Eigen::Isometry2d& odom_from_base);

  const Eigen::Isometry2d& mapFromOdom() const { return map_from_odom_; }
  void setMapFromOdom(const Eigen::Isometry2d& t) { map_from_odom_ = t; }
  const OccupancyMap& map() const { return map_; }
  bool mapping() const { return mapping_; }
  const Params& params() const { return params_; }

  static const char* statusName(Status s);

 private:
  Params params_;
  OccupancyMap map_;
  ScanMatcher matcher_;
  Eigen::Isometry2d map_from_odom_;
  bool mapping_ = true;
  bool started_ = false;
  int mapping_scans_ = 0;
  double start_time_ = 0.0;
  double last_accept_time_ = 0.0;
  double last_map_update_time_ = 0.0;
  Eigen::Isometry2d last_map_update_pose_ = Eigen::Isometry2d::Identity();
};

}  // namespace rbd_localization

#endif  // RBD_LOCALIZATION_MAP_CORRECTION_H
