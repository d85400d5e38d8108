// ROS-free map correction. Mapping mode: builds the 2D map in the first seconds, then matches
// every scan against it with the EKF pose as prior and maintains map -> odom (gated,
// rate-limited), refining the map slowly from well-matched scans and clearing cells people left.
// Localization mode (a loaded map): the map is the fixed reference; at start the robot is found
// by a search around its home pose, and it is "localized" once the matches agree.
#ifndef RBD_LOCALIZATION_MAP_CORRECTION_H
#define RBD_LOCALIZATION_MAP_CORRECTION_H

#include <Eigen/Geometry>
#include <memory>
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
    /// Mapping mode: while the robot stands (moved less than map_update_min_translation /
    /// _rotation since the last refinement), every clear_interval [s] a matched scan is inserted
    /// (log-odds scaled by clear_weight; a beam does not clear its last clear_end_margin [m], nor
    /// at all when flatter than clear_min_incidence [rad] to its surface): cells people left
    /// become free again, structure they hid appears. clear_interval <= 0: off.
    double clear_interval = 0.5;
    double clear_weight = 0.5;
    double clear_end_margin = 0.15;
    double clear_min_incidence = 0.35;
    /// Localization mode: the start pose is searched within this distance [m] / angle [rad] of
    /// the home pose (the robot may start up to 1 m / 45 deg away from it).
    double search_translation = 1.2;
    double search_rotation = 0.9;
    /// Localization mode: the start search's answer P must be the only pose that fits. The scan is
    /// scored over the whole map (every heading, positions every ambiguity_step [m] on the cells
    /// the map saw free, headings every ambiguity_angle_step [rad]); if a pose farther than
    /// ambiguity_translation [m] or ambiguity_rotation [rad] from P fits as well as P within
    /// ambiguity_margin [m] of the mean truncated distance (ScanMatcher::score), or better, the start
    /// is ambiguous: not taken, searched again at most every ambiguity_retry_interval [s].
    bool ambiguity_check = true;
    double ambiguity_translation = 0.5;
    double ambiguity_rotation = 0.52;  // 30 deg
    double ambiguity_margin = 0.01;
    double ambiguity_step = 0.1;
    double ambiguity_angle_step = 0.05;
    double ambiguity_retry_interval = 2.0;
    /// Localized once this many consecutive matches each moved the pose by less than
    /// localized_translation [m] / localized_rotation [rad].
    int localized_scans = 5;
    double localized_translation = 0.02;
    double localized_rotation = 0.01;
    OccupancyMap::Params map;
    ScanMatcher::Params matcher;
  };

  enum class Status {
    kMapping,
    kAccepted,
    kRejectedFit,
    kRejectedJump,
    kRejectedEmpty,
    kSearched,
    kRejectedAmbiguous
  };

  struct Update {
    Status status = Status::kRejectedEmpty;
    ScanMatcher::Result match;
    Eigen::Isometry2d map_from_odom = Eigen::Isometry2d::Identity();
    bool map_changed = false;
    std::string reason;
    /// A start search ran its ambiguity check (kSearched, kRejectedAmbiguous): what it found.
    bool start_checked = false;
    ScanMatcher::Rival rival;
    double start_score = 0.0;     ///< ScanMatcher::score of the search's answer [m]
    double start_check_ms = 0.0;  ///< CPU time of the check [ms]
  };

  MapCorrection();
  explicit MapCorrection(const Params& params);

  /// Localization mode: `reference` is the fixed map (only its static cells are kept), the robot
  /// starts near `home` (map_from_base at odometry's origin). Call before the first scan.
  void setReference(std::unique_ptr<OccupancyMap> reference, const Eigen::Isometry2d& home);

  /// One scan (points in base_link, z dropped) with the EKF's odom -> base_link at its time.
  Update processScan(double time, const Points2d& points_in_base, const Eigen::Isometry2d& odom_from_base);

  const Eigen::Isometry2d& mapFromOdom() const { return map_from_odom_; }
  void setMapFromOdom(const Eigen::Isometry2d& t) { map_from_odom_ = t; }
  const OccupancyMap& map() const { return *map_; }
  /// Clock of the map's occupied-since times (time of the first scan = 0) for `time` [s].
  double mapTime(double time) const { return started_ ? time - start_time_ : 0.0; }
  bool mapping() const { return mapping_; }
  /// Localization mode (a loaded, fixed map) rather than mapping mode.
  bool localizationMode() const { return localization_mode_; }
  /// The pose is trustworthy in the map: mapping mode after the initial mapping, localization
  /// mode once the matches converged.
  bool localized() const { return localized_; }
  const Params& params() const { return params_; }

  static const char* statusName(Status s);

 private:
  Update searchStart(double time, const Points2d& points, const Eigen::Isometry2d& odom_from_base,
                     const Eigen::Isometry2d& prior);
  /// The ambiguity check of a start search's answer u->match (fills u's start fields; false with
  /// u->reason when another pose fits as well).
  bool startIsUnique(const Points2d& points, Update* u) const;
  bool fitOk(const ScanMatcher::Result& m, std::string* reason) const;
  bool standingUpdate(double time, const Eigen::Isometry2d& pose, const Points2d& points,
                      const OccupancyMap::Insert& base);

  Params params_;
  std::unique_ptr<OccupancyMap> map_;
  ScanMatcher matcher_;
  Eigen::Isometry2d map_from_odom_;
  bool mapping_ = true;
  bool started_ = false;
  int mapping_scans_ = 0;
  double start_time_ = 0.0;
  double last_accept_time_ = 0.0;
  double last_map_update_time_ = 0.0;
  Eigen::Isometry2d last_map_update_pose_ = Eigen::Isometry2d::Identity();
  double last_clear_time_ = 0.0;
  bool localization_mode_ = false;
  bool localized_ = false;
  bool searched_ = false;
  int good_matches_ = 0;
  int failed_matches_ = 0;
  bool ambiguous_ = false;  ///< the last start search was ambiguous (at ambiguous_time_)
  double ambiguous_time_ = 0.0;
  std::string ambiguous_reason_;
};

}  // namespace rbd_localization

#endif  // RBD_LOCALIZATION_MAP_CORRECTION_H
