#include "rbd_localization/map_correction_ros.h"

#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/TransformStamped.h>
#include <nav_msgs/OccupancyGrid.h>
#include <sensor_msgs/point_cloud2_iterator.h>
#include <std_msgs/Bool.h>
#include <tf2_eigen/tf2_eigen.h>

#include <cmath>
#include <ctime>
#include <vector>

#include "rbd_localization/geometry.h"
#include "rbd_localization/map_io.h"
#include "rbd_localization/node_main.h"
#include "rbd_localization/run_node.h"
#include "rbd_localization/scan_slice.h"

namespace rbd_localization {

namespace {

Eigen::Isometry2d planar(const Eigen::Isometry3d& t) {
  const Eigen::Vector3d rpy = rpyFromRotation(t.linear());
  return pose2d(t.translation().x(), t.translation().y(), rpy(2));
}

Eigen::Isometry3d lift(const Eigen::Isometry2d& t) {
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  out.linear() = Eigen::AngleAxisd(yawOf(t), Eigen::Vector3d::UnitZ()).toRotationMatrix();
  out.translation() = Eigen::Vector3d(t.translation().x(), t.translation().y(), 0.0);
  return out;
}

double cpuSeconds() { return static_cast<double>(std::clock()) / CLOCKS_PER_SEC; }

}  // namespace

MapCorrectionNode::MapCorrectionNode(const ros::NodeHandle& nh, const ros::NodeHandle& pnh)
    : nh_(nh), pnh_(pnh) {}

bool MapCorrectionNode::init(std::string* error) {
  MapCorrection::Params core;
  std::vector<std::string> warnings;
  const bool params_ok = loadMapCorrectionParams(pnh_, &params_, &core, &warnings, error);
  for (const std::string& w : warnings) ROS_WARN("map_correction: %s", w.c_str());
  if (!params_ok) return false;
  core_.reset(new MapCorrection(core));
  if (!params_.map_file.empty()) {
    std::unique_ptr<OccupancyMap> loaded;
    MapFileInfo info;
    if (!loadMap(params_.map_file, core.map, 0.0, &loaded, &info, error)) return false;
    if (loaded->occupiedCount() == 0) {
      *error = params_.map_file + " has no occupied cell: nothing to localize in";
      return false;
    }
    if (!std::isnan(params_.home_x)) {
      home_ = Eigen::Vector3d(params_.home_x, params_.home_y, params_.home_yaw);
    } else if (info.has_home) {
      home_ = info.home;
    }
    ROS_INFO("map_correction: localization mode in %s (%d x %d cells, %s), home (%.2f, %.2f, %.1f deg)%s%s",
             params_.map_file.c_str(), loaded->width(), loaded->height(),
             info.exact ? "exact log-odds from the sidecar" : "cells from the PGM", home_.x(), home_.y(),
             home_.z() * 180.0 / M_PI, info.note.empty() ? "" : ": ", info.note.c_str());
    core_->setReference(std::move(loaded), pose2d(home_.x(), home_.y(), home_.z()));
  }
  tf_buffer_.reset(new tf2_ros::Buffer());
  tf_listener_.reset(new tf2_ros::TransformListener(*tf_buffer_, nh_));
  map_pub_ = nh_.advertise<nav_msgs::OccupancyGrid>("map", 1, true);
  pose_pub_ = nh_.advertise<geometry_msgs::PoseStamped>("rbd_localization/pose", 10);
  localized_pub_ = nh_.advertise<std_msgs::Bool>("rbd_localization/localized", 1, true);
  publishLocalized();
  save_srv_ = pnh_.advertiseService("save_map", &MapCorrectionNode::saveMapService, this);
  if (core_->localizationMode()) publishMap(ros::Time::now());
  if (params_.input == "points") {
    scan_sub_ = nh_.subscribe("points", 2, &MapCorrectionNode::cloudCallback, this);
  } else {
    scan_sub_ = nh_.subscribe("scan", 2, &MapCorrectionNode::scanCallback, this);
  }
  odom_sub_ = nh_.subscribe("odometry/filtered", 10, &MapCorrectionNode::odomCallback, this,
                            ros::TransportHints().tcpNoDelay());
  diagnostics_.reset(new diagnostic_updater::Updater(nh_, pnh_));
  diagnostics_->setHardwareID("none");
  diagnostics_->add("Map correction", this, &MapCorrectionNode::diagnose);
  start_time_ = ros::Time::now();
  timer_ = nh_.createTimer(ros::Duration(1.0 / params_.transform_publish_rate),
                           &MapCorrectionNode::timerCallback, this);
  return true;
}

bool MapCorrectionNode::acceptInput(const ros::Time& stamp) {
  last_scan_receive_ = ros::Time::now();
  ++scans_;
  if (!params_.correction_enabled) {
    last_status_ = "correction disabled (correction_enabled: false)";
    return false;
  }
  if (!last_match_stamp_.isZero() && (stamp - last_match_stamp_).toSec() < 1.0 / params_.max_match_rate &&
      stamp >= last_match_stamp_) {
    ++skipped_;
    return false;
  }
  return true;
}

void MapCorrectionNode::scanCallback(const sensor_msgs::LaserScan::ConstPtr& msg) {
  if (acceptInput(msg->header.stamp)) pending_scan_ = msg;  // processed once odom -> base is known
}

void MapCorrectionNode::cloudCallback(const sensor_msgs::PointCloud2::ConstPtr& msg) {
  if (acceptInput(msg->header.stamp)) pending_cloud_ = msg;
}

void MapCorrectionNode::odomCallback(const nav_msgs::Odometry::ConstPtr& msg) {
  // Pose for the position controller: map -> odom (ours) composed with the EKF's odom pose.
  if ((ros::Time::now() - msg->header.stamp).toSec() > params_.pose_timeout) {
    ROS_WARN_THROTTLE(2.0, "map_correction: odometry is %.2f s old: no pose published",
                      (ros::Time::now() - msg->header.stamp).toSec());
    return;
  }
  const auto& p = msg->pose.pose;
  Eigen::Quaterniond q;
  tf2::fromMsg(p.orientation, q);
  if (!q.coeffs().allFinite() || q.norm() < 1e-6 || !std::isfinite(p.position.x) ||
      !std::isfinite(p.position.y) || !std::isfinite(p.position.z)) {
    ROS_WARN_THROTTLE(2.0, "map_correction: odometry with NaN/inf or zero quaternion ignored");
    return;
  }
  Eigen::Isometry3d odom_from_base = Eigen::Isometry3d::Identity();
  odom_from_base.linear() = q.normalized().toRotationMatrix();
  odom_from_base.translation() = Eigen::Vector3d(p.position.x, p.position.y, p.position.z);
  const Eigen::Isometry3d map_from_base = lift(core_->mapFromOdom()) * odom_from_base;
  geometry_msgs::PoseStamped out;
  out.header.stamp = msg->header.stamp;
  out.header.frame_id = params_.map_frame;
  out.pose = tf2::toMsg(map_from_base);
  pose_pub_.publish(out);
}

bool MapCorrectionNode::sensorTransform(const std::string& frame, Eigen::Isometry3d* out) {
  auto it = base_from_sensor_.find(frame);
  if (it == base_from_sensor_.end()) {
    try {
      const auto ts = tf_buffer_->lookupTransform(params_.base_frame, frame, ros::Time(0));
      it = base_from_sensor_.emplace(frame, tf2::transformToEigen(ts)).first;
    } catch (const tf2::TransformException& ex) {
      ROS_WARN_THROTTLE(2.0, "map_correction: no transform %s <- %s: %s", params_.base_frame.c_str(),
                        frame.c_str(), ex.what());
      return false;
    }
  }
  *out = it->second;
  return true;
}

ScanSlicer::Params MapCorrectionNode::slicerParams() const {
  ScanSlicer::Params sp;
  sp.z_min = params_.slice_z_min;
  sp.z_max = params_.slice_z_max;
  sp.min_range = params_.min_range;
  sp.max_range = params_.max_range;
  sp.bins = params_.slice_bins;
  sp.max_points = params_.max_points;
  return sp;
}

bool MapCorrectionNode::cloudToBase(const sensor_msgs::PointCloud2& cloud, const Eigen::Matrix3d& level,
                                    Points2d* out) {
  Eigen::Isometry3d t;
  if (!sensorTransform(cloud.header.frame_id, &t)) return false;
  bool has_xyz[3] = {false, false, false};
  for (const auto& f : cloud.fields) {
    for (int k = 0; k < 3; ++k) {
      if (f.name == std::string(1, "xyz"[k]) && f.datatype == sensor_msgs::PointField::FLOAT32)
        has_xyz[k] = true;
    }
  }
  if (!has_xyz[0] || !has_xyz[1] || !has_xyz[2] || cloud.point_step < 12 ||
      cloud.data.size() < static_cast<size_t>(cloud.row_step) * cloud.height) {
    ROS_WARN_THROTTLE(2.0, "map_correction: cloud without float x/y/z or with a short data array ignored");
    return false;
  }
  // Levelled horizontal slice around the base height, nearest return per azimuth bin.
  ScanSlicer slicer(slicerParams());
  slicer.begin(t, level);
  sensor_msgs::PointCloud2ConstIterator<float> ix(cloud, "x"), iy(cloud, "y"), iz(cloud, "z");
  for (; ix != ix.end(); ++ix, ++iy, ++iz) slicer.add(Eigen::Vector3d(*ix, *iy, *iz));
  *out = slicer.finish();
  return true;
}

bool MapCorrectionNode::scanToBase(const sensor_msgs::LaserScan& scan, const Eigen::Matrix3d& level,
                                   Points2d* out) {
  Eigen::Isometry3d t;
  if (!sensorTransform(scan.header.frame_id, &t)) return false;
  const double lo = std::max(static_cast<double>(scan.range_min), params_.min_range);
  const double hi = std::min(static_cast<double>(scan.range_max), params_.max_range);
  std::vector<Eigen::Vector3d> pts;
  pts.reserve(scan.ranges.size());
  for (size_t i = 0; i < scan.ranges.size(); ++i) {
    const double r = scan.ranges[i];
    if (!(std::isfinite(r) && r >= lo && r <= hi)) continue;
    const double a = scan.angle_min + i * static_cast<double>(scan.angle_increment);
    pts.emplace_back(r * std::cos(a), r * std::sin(a), 0.0);
  }
  ScanSlicer slicer(slicerParams());
  slicer.begin(t, level);
  *out = slicer.levelPlanar(pts);
  return true;
}

void MapCorrectionNode::processPendingScan() {
  if (!pending_scan_ && !pending_cloud_) return;
  const ros::Time stamp = pending_scan_ ? pending_scan_->header.stamp : pending_cloud_->header.stamp;
  Eigen::Isometry3d odom_from_base;
  try {
    odom_from_base =
        tf2::transformToEigen(tf_buffer_->lookupTransform(params_.odom_frame, params_.base_frame, stamp));
  } catch (const tf2::TransformException& ex) {
    // Wait for the EKF to catch up, but not forever.
    if ((ros::Time::now() - stamp).toSec() > 0.5) {
      ROS_WARN_THROTTLE(2.0, "map_correction: dropping scan, no %s -> %s at its stamp: %s",
                        params_.odom_frame.c_str(), params_.base_frame.c_str(), ex.what());
      pending_scan_.reset();
      pending_cloud_.reset();
      ++skipped_;
    }
    return;
  }
  last_match_stamp_ = stamp;
  Points2d points;
  // Levelled with the EKF's roll/pitch at the scan's stamp (a tilted body must not shorten the
  // ranges or move the slice's height band).
  const Eigen::Matrix3d level = levelFromBase(odom_from_base.linear());
  const bool ok = pending_scan_ ? scanToBase(*pending_scan_, level, &points)
                                : cloudToBase(*pending_cloud_, level, &points);
  pending_scan_.reset();
  pending_cloud_.reset();
  if (!ok) return;

  const double cpu0 = cpuSeconds();
  const MapCorrection::Update u = core_->processScan(stamp.toSec(), points, planar(odom_from_base));
  last_cpu_ms_ = (cpuSeconds() - cpu0) * 1e3;
  last_status_ = MapCorrection::statusName(u.status);
  if (u.start_checked) {
    const Eigen::Isometry2d& r = u.rival.match.pose;
    ROS_INFO(
        "map_correction: start search at (%.2f, %.2f, %.1f deg), score %.3f m; best pose elsewhere%s "
        "(%.2f, %.2f, %.1f deg), score %.3f m; %s (check: %d poses, %.0f ms CPU)",
        u.match.pose.translation().x(), u.match.pose.translation().y(), yawOf(u.match.pose) * 180.0 / M_PI,
        u.start_score, u.rival.found ? "" : " (none)", r.translation().x(), r.translation().y(),
        yawOf(r) * 180.0 / M_PI, u.rival.score,
        u.status == MapCorrection::Status::kSearched ? "taken" : "ambiguous, not taken", u.rival.poses_scored,
        u.start_check_ms);
  }
  if (u.status == MapCorrection::Status::kAccepted || u.status == MapCorrection::Status::kSearched) {
    ++accepted_;
  } else if (u.status != MapCorrection::Status::kMapping) {
    ++rejected_;
    last_status_ += ": " + u.reason;
    ROS_WARN_THROTTLE(2.0, "map_correction: scan %s", last_status_.c_str());
  }
  if (u.map_changed) map_dirty_ = true;
  if (map_dirty_ && !core_->mapping() &&
      (last_map_publish_.isZero() ||
       (ros::Time::now() - last_map_publish_).toSec() >= params_.map_publish_interval)) {
    publishMap(stamp);
  }
}

void MapCorrectionNode::publishLocalized() {
  if (!params_.correction_enabled) return;  // nothing to be localized in: silent, not false for ever
  const int now = core_->localized() ? 1 : 0;
  if (now == localized_published_) return;
  std_msgs::Bool msg;
  msg.data = now == 1;
  localized_pub_.publish(msg);
  localized_published_ = now;
  if (core_->localizationMode()) {
    ROS_INFO("map_correction: %s", msg.data ? "localized in the map" : "not localized in the map");
  }
}

bool MapCorrectionNode::saveMapService(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res) {
  pnh_.param<std::string>("map_save_dir", params_.map_save_dir, params_.map_save_dir);
  pnh_.param<std::string>("map_save_name", params_.map_save_name, params_.map_save_name);
  if (core_->mapping()) {
    res.success = false;
    res.message = "no map yet: still in the initial mapping";
    return true;
  }
  const double now = core_->mapTime(last_match_stamp_.isZero() ? 0.0 : last_match_stamp_.toSec());
  std::string error;
  const std::string prefix = params_.map_save_dir + "/" + params_.map_save_name;
  if (!saveMap(core_->map(), now, home_, params_.map_save_dir, params_.map_save_name, &error)) {
    res.success = false;
    res.message = "save failed: " + error;
    ROS_ERROR("map_correction: %s", res.message.c_str());
    return true;
  }
  res.success = true;
  res.message = "saved " + prefix + ".yaml, .pgm, .rbdmap (" + std::to_string(core_->map().width()) + " x " +
                std::to_string(core_->map().height()) + " cells)";
  ROS_INFO("map_correction: %s", res.message.c_str());
  return true;
}

void MapCorrectionNode::timerCallback(const ros::TimerEvent&) {
  processPendingScan();
  publishLocalized();
  publishTransform();
  diagnostics_->update();
}

void MapCorrectionNode::publishTransform() {
  geometry_msgs::TransformStamped tf = tf2::eigenToTransform(lift(core_->mapFromOdom()));
  tf.header.stamp = ros::Time::now() + ros::Duration(params_.transform_tolerance);
  tf.header.frame_id = params_.map_frame;
  tf.child_frame_id = params_.odom_frame;
  tf_broadcaster_.sendTransform(tf);
}

void MapCorrectionNode::publishMap(const ros::Time& stamp) {
  const OccupancyMap& m = core_->map();
  nav_msgs::OccupancyGrid grid;
  grid.header.stamp = stamp;
  grid.header.frame_id = params_.map_frame;
  grid.info.map_load_time = stamp;
  grid.info.resolution = static_cast<float>(m.params().resolution);
  grid.info.width = static_cast<uint32_t>(m.width());
  grid.info.height = static_cast<uint32_t>(m.height());
  grid.info.origin.position.x = m.originX();
  grid.info.origin.position.y = m.originY();
  grid.info.origin.orientation.w = 1.0;
  grid.data = m.toOccupancyData();
  map_pub_.publish(grid);
  last_map_publish_ = ros::Time::now();
  map_dirty_ = false;
}

void MapCorrectionNode::diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat) {
  const ros::Time now = ros::Time::now();
  stat.add("scans", scans_);
  stat.add("accepted", accepted_);
  stat.add("rejected", rejected_);
  stat.add("skipped", skipped_);
  stat.add("last cpu per scan [ms]", last_cpu_ms_);
  stat.add("mapping", core_->mapping());
  stat.add("mode",
           core_->localizationMode() ? "localization (" + params_.map_file + ")" : std::string("mapping"));
  stat.add("localized", core_->localized());
  stat.add("map cells", std::to_string(core_->map().width()) + " x " + std::to_string(core_->map().height()));
  stat.add("map memory [MB]", core_->map().memoryBytes() / 1e6);
  const bool stale = last_scan_receive_.isZero() ? (now - start_time_).toSec() > params_.scan_timeout
                                                 : (now - last_scan_receive_).toSec() > params_.scan_timeout;
  if (!params_.correction_enabled) {
    stat.summary(diagnostic_msgs::DiagnosticStatus::OK, "correction disabled: map -> odom is identity");
  } else if (stale) {
    stat.summary(diagnostic_msgs::DiagnosticStatus::ERROR, "stale: no scan within scan_timeout");
  } else if (core_->localizationMode() && !core_->localized()) {
    stat.summary(diagnostic_msgs::DiagnosticStatus::WARN, "not localized in the map: " + last_status_);
  } else if (last_status_.find("rejected") == 0) {
    stat.summary(diagnostic_msgs::DiagnosticStatus::WARN, last_status_);
  } else {
    stat.summary(diagnostic_msgs::DiagnosticStatus::OK, last_status_);
  }
}

int mapCorrectionNodeMain(int argc, char** argv) {
  return runNode<MapCorrectionNode>(argc, argv, "map_correction_node");
}

}  // namespace rbd_localization
