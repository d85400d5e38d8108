#include "rbd_localization/map_correction.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <limits>

#include "rbd_localization/filter_common.h"
#include "rbd_localization/geometry.h"

namespace rbd_localization {

MapCorrection::MapCorrection() : MapCorrection(Params()) {}

MapCorrection::MapCorrection(const Params& params)
    : params_(params),
      map_(new OccupancyMap(params.map)),
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
    case Status::kSearched:
      return "searched the start pose";
    case Status::kRejectedAmbiguous:
      return "rejected (ambiguous start)";
  }
  return "?";
}

void MapCorrection::setReference(std::unique_ptr<OccupancyMap> reference, const Eigen::Isometry2d& home) {
  map_ = std::move(reference);
  map_->setGrow(false);
  // Only structure: cells occupied but not (yet) static when saved are unknown here.
  for (int cy = 0; cy < map_->height(); ++cy) {
    for (int cx = 0; cx < map_->width(); ++cx) {
      if (map_->occupied(cx, cy) && !map_->isStatic(cx, cy, 0.0)) {
        map_->setCell(cx, cy, 0.0f, std::numeric_limits<float>::quiet_NaN());
      }
    }
  }
  map_->updateDistanceField();
  map_from_odom_ = home;  // odometry starts at identity where the robot starts: near home
  localization_mode_ = true;
  mapping_ = false;
  localized_ = false;
  searched_ = false;
}

bool MapCorrection::fitOk(const ScanMatcher::Result& m, std::string* reason) const {
  if (m.inliers < params_.min_inliers || m.inlier_ratio < params_.min_inlier_ratio ||
      m.rms > params_.max_rms || m.min_translation_information < params_.min_translation_information) {
    *reason = "inliers " + std::to_string(m.inliers) + " ratio " + std::to_string(m.inlier_ratio) + " rms " +
              std::to_string(m.rms) + " info " + std::to_string(m.min_translation_information);
    return false;
  }
  return true;
}

MapCorrection::Update MapCorrection::searchStart(double time, const Points2d& points,
                                                 const Eigen::Isometry2d& odom_from_base,
                                                 const Eigen::Isometry2d& prior) {
  Update u;
  u.map_from_odom = map_from_odom_;
  if (ambiguous_ && time - ambiguous_time_ < params_.ambiguity_retry_interval && time >= ambiguous_time_) {
    u.status = Status::kRejectedAmbiguous;  // the whole-map check is not run at every scan
    u.reason = ambiguous_reason_;
    return u;
  }
  ambiguous_ = false;
  u.match = matcher_.search(*map_, points, prior, params_.search_translation, params_.search_rotation);
  if (!fitOk(u.match, &u.reason)) {
    u.status = Status::kRejectedFit;
    u.reason = "start search: " + u.reason;
  } else if (params_.ambiguity_check && !startIsUnique(points, &u)) {
    u.status = Status::kRejectedAmbiguous;
    ambiguous_ = true;
    ambiguous_time_ = time;
    ambiguous_reason_ = u.reason;
  } else {
    map_from_odom_ = u.match.pose * odom_from_base.inverse();  // a jump: not localized yet
    searched_ = true;
    good_matches_ = 0;
    failed_matches_ = 0;
    last_accept_time_ = time;
    u.status = Status::kSearched;
  }
  u.map_from_odom = map_from_odom_;
  return u;
}

bool MapCorrection::startIsUnique(const Points2d& points, Update* u) const {
  const std::clock_t c0 = std::clock();
  ScanMatcher::GlobalSearch how;
  how.step = params_.ambiguity_step;
  how.angle_step = params_.ambiguity_angle_step;
  u->start_checked = true;
  u->start_score = ScanMatcher::score(*map_, points, u->match.pose);
  u->rival = matcher_.rivalElsewhere(*map_, points, u->match.pose, params_.ambiguity_translation,
                                     params_.ambiguity_rotation, how);
  u->start_check_ms = 1e3 * static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC;
  if (!u->rival.found || u->rival.score > u->start_score + params_.ambiguity_margin) return true;
  const Eigen::Isometry2d& r = u->rival.match.pose;
  char buf[256];
  std::snprintf(buf, sizeof(buf),
                "start search: ambiguous: another pose (%.2f, %.2f, %.0f deg) fits as well (score %.3f m vs "
                "%.3f m at (%.2f, %.2f, %.0f deg))",
                r.translation().x(), r.translation().y(), yawOf(r) * 180.0 / M_PI, u->rival.score,
                u->start_score, u->match.pose.translation().x(), u->match.pose.translation().y(),
                yawOf(u->match.pose) * 180.0 / M_PI);
  u->reason = buf;
  return false;
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

  if (localization_mode_ && !localized_) {
    // Find the start (search), then follow the matches fully until they agree scan after scan.
    if (!searched_) return searchStart(time, points, odom_from_base, prior);
    u.match = matcher_.match(*map_, points, prior);
    if (!fitOk(u.match, &u.reason)) {
      u.status = Status::kRejectedFit;
      good_matches_ = 0;
      if (++failed_matches_ >= 10) searched_ = false;  // lost: search again
      return u;
    }
    const double moved = (u.match.pose.translation() - prior.translation()).norm();
    const double turned = std::fabs(wrapAngle(yawOf(u.match.pose) - yawOf(prior)));
    map_from_odom_ = u.match.pose * odom_from_base.inverse();
    last_accept_time_ = time;
    failed_matches_ = 0;
    good_matches_ = (moved < params_.localized_translation && turned < params_.localized_rotation)
                        ? good_matches_ + 1
                        : 0;
    if (good_matches_ >= params_.localized_scans) localized_ = true;
    u.status = Status::kAccepted;
    u.map_from_odom = map_from_odom_;
    return u;
  }

  OccupancyMap::Insert full;
  full.time = mapTime(time);
  if (mapping_) {
    map_->insertScan(prior, points, full);
    ++mapping_scans_;
    u.status = Status::kMapping;
    u.map_changed = true;
    if (time - start_time_ >= params_.initial_mapping_duration &&
        mapping_scans_ >= params_.initial_mapping_min_scans) {
      mapping_ = false;
      localized_ = true;
      map_->updateDistanceField();
      last_accept_time_ = time;
      last_map_update_time_ = time;
      last_map_update_pose_ = prior;
    }
    return u;
  }

  u.match = matcher_.match(*map_, points, prior);
  const ScanMatcher::Result& m = u.match;
  if (!fitOk(m, &u.reason)) {
    u.status = Status::kRejectedFit;
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

  if (localization_mode_) return u;  // the loaded map is the reference: never rewritten

  // Slow refinement from the matched pose (people walking through get cleared again by misses).
  const Eigen::Isometry2d moved = last_map_update_pose_.inverse() * m.pose;
  bool refined = false;
  if (time - last_map_update_time_ >= params_.map_update_interval &&
      (moved.translation().norm() >= params_.map_update_min_translation ||
       std::fabs(yawOf(moved)) >= params_.map_update_min_rotation)) {
    last_map_update_pose_ = m.pose;
    OccupancyMap::Insert how = full;
    how.weight = params_.map_update_weight;
    map_->insertScan(m.pose, points, how);
    map_->updateDistanceField();
    last_map_update_time_ = time;
    u.map_changed = true;
    refined = true;
  }
  // Standing (not moved enough for a refinement since the last one): standing updates.
  const bool standing = !refined && moved.translation().norm() < params_.map_update_min_translation &&
                        std::fabs(yawOf(moved)) < params_.map_update_min_rotation;
  if (standing && standingUpdate(time, m.pose, points, full)) u.map_changed = true;
  return u;
}

bool MapCorrection::standingUpdate(double time, const Eigen::Isometry2d& pose, const Points2d& points,
                                   const OccupancyMap::Insert& base) {
  // Standing updates (also while the robot stands): cells people stood on become free once they
  // left, structure they hid is added; a cell is saved as a wall only once it is static.
  if (params_.clear_interval <= 0.0 || time - last_clear_time_ < params_.clear_interval) return false;
  last_clear_time_ = time;
  OccupancyMap::Insert how = base;
  how.weight = params_.clear_weight;
  how.end_margin = params_.clear_end_margin;
  how.min_incidence = params_.clear_min_incidence;
  if (map_->insertScan(pose, points, how)) map_->updateDistanceField();
  return true;
}

}  // namespace rbd_localization
