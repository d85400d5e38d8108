#include "rbd_localization/map_correction.h"

#include <algorithm>
#include <cmath>

#include "rbd_localization/filter_common.h"
#include "rbd_localization/geometry.h"

namespace rbd_localization {

MapCorrection::MapCorrection() : MapCorrection(Params()) {}

MapCorrection::MapCorrection(const Params& params)
    : params_(params),
      map_(params.map),
      matcher_(params.matcher),
      map_from_odom_(Eigen::Isometry2d::Identity()) {}

const char* MapCorrection::statusName(Status s) {
  switch (s) {
    case Status::kMapping:
      return "mapping";
    case Status::kAccepted:
      return "accepted";
    case Status::kRejectedFit:
      return "rejected (fit quality)";
    case Status::kRejectedJump:
      return "rejected (jump)";
    case Status::kRejectedEmpty:
      return "rejected (too few points)";
  }
  return "?";
}

MapCorrection::Update MapCorrection::processScan(double time, const Points2d& points,
                                                 const Eigen::Isometry2d& odom_from_base) {
  Update u;
  u.map_from_odom = map_from_odom_;
  if (static_cast<int>(points.size()) < params_.min_inliers) {
    u.status = Status::kRejectedEmpty;
    u.reason = "scan has " + std::to_string(points.size()) + " valid points";
    return u;
  }
  if (!started_) {
    started_ = true;
    start_time_ = time;
  }
  const Eigen::Isometry2d prior = map_from_odom_ * odom_from_base;

  if (mapping_) {
    map_.insertScan(prior, points, 1.0);
    ++mapping_scans_;
    u.status = Status::kMapping;
    u.map_changed = true;
    if (time - start_time_ >= params_.initial_mapping_duration &&
        mapping_scans_ >= params_.initial_mapping_min_scans) {
      mapping_ = false;
      map_.updateDistanceField();
      last_accept_time_ = time;
      last_map_update_time_ = time;
      last_map_update_pose_ = prior;
    }
    return u;
  }

  u.match = matcher_.match(map_, points, prior);
  const ScanMatcher::Result& m = u.match;
  if (m.inliers < params_.min_inliers || m.inlier_ratio < params_.min_inlier_ratio ||
      m.rms > params_.max_rms || m.min_translation_information < params_.min_translation_information) {
    u.status = Status::kRejectedFit;
    u.reason = "inliers " + std::to_string(m.inliers) + " ratio " + std::to_string(m.inlier_ratio) + " rms " +
               std::to_string(m.rms) + " info " + std::to_string(m.min_translation_information);
    return u;
  }
  const Eigen::Vector2d dt_vec = m.pose.translation() - prior.translation();
  const double dth = wrapAngle(yawOf(m.pose) - yawOf(prior));
  if (dt_vec.norm() > params_.max_jump_translation || std::fabs(dth) > params_.max_jump_rotation) {
    u.status = Status::kRejectedJump;
    u.reason = "correction " + std::to_string(dt_vec.norm()) + " m / " + std::to_string(dth) + " rad";
    return u;
  }

  // Rate limit: move the corrected robot pose towards the match by at most speed * elapsed.
  const double elapsed = std::max(0.02, std::min(1.0, time - last_accept_time_));
  Eigen::Vector2d step = dt_vec;
  // Bounded per scan as well: after a long run of refused scans (body tilted, crowd) elapsed is
  // large, and the whole accumulated drift must not be applied at once.
  const double max_step = std::min(params_.max_correction_speed * elapsed, params_.max_correction_step);
  if (step.norm() > max_step) step *= max_step / step.norm();
  const double max_rot =
      std::min(params_.max_correction_angular_speed * elapsed, params_.max_correction_step_rotation);
  const double rot = std::max(-max_rot, std::min(max_rot, dth));
  const Eigen::Isometry2d corrected =
      pose2d(prior.translation().x() + step.x(), prior.translation().y() + step.y(), yawOf(prior) + rot);
  map_from_odom_ = corrected * odom_from_base.inverse();
  last_accept_time_ = time;
  u.status = Status::kAccepted;
  u.map_from_odom = map_from_odom_;

  // Slow refinement from the matched pose (people walking through get cleared again by misses).
  const Eigen::Isometry2d moved = last_map_update_pose_.inverse() * m.pose;
  if (time - last_map_update_time_ >= params_.map_update_interval &&
      (moved.translation().norm() >= params_.map_update_min_translation ||
       std::fabs(yawOf(moved)) >= params_.map_update_min_rotation)) {
    last_map_update_pose_ = m.pose;
    map_.insertScan(m.pose, points, params_.map_update_weight);
    map_.updateDistanceField();
    last_map_update_time_ = time;
    u.map_changed = true;
  }
  return u;
}

}  // namespace rbd_localization
