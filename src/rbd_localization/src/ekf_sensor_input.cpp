// The EKF node's sensor callbacks: each IMU / pose / odometry / twist message checked, rotated
// into the filter's frames and queued as measurements for the next filter cycle.
#include <algorithm>
#include <cmath>

#include "rbd_localization/ekf_node.h"
#include "rbd_localization/geometry.h"

namespace rbd_localization {

void EkfNode::countReceived(size_t idx) {
  SensorState& s = sensors_[idx];
  s.last_receive = ros::Time::now();
  ++s.received;
  ++s.window_received;
  ++s.cycle_received;
}

void EkfNode::imuCallback(const sensor_msgs::Imu::ConstPtr& msg, size_t idx) {
  countReceived(idx);
  SensorState& s = sensors_[idx];
  Eigen::Matrix3d base_from_imu;
  if (!sensorRotation(idx, msg->header.frame_id, &base_from_imu)) {
    markInvalid(idx, "no transform " + params_.base_link_frame + " <- " + msg->header.frame_id);
    return;
  }
  s.frames_ready = true;
  const double t = stampToTime(msg->header.stamp);
  std::string reason;
  if (s.orientation_as_pose) {
    PoseWithCov orientation;
    if (imuOrientationPose(*msg, base_from_imu, &orientation))
      fusePose(orientation, t, s.orientation_cfg, idx);
  }
  if (!imuMeasurements(*msg, base_from_imu, s.orientation_as_pose ? s.rest_cfg : s.cfg, ekf_.state(),
                       params_.gravitational_acceleration, t, &queue_, &reason)) {
    markInvalid(idx, reason);
    return;
  }
  queue_sensor_.resize(queue_.size(), idx);  // the IMU parts were appended in place
}

void EkfNode::handlePose(const geometry_msgs::PoseWithCovariance& msg, const std::string& frame,
                         const ros::Time& stamp, size_t idx) {
  SensorState& s = sensors_[idx];
  PoseWithCov pose;
  if (!fromMsg(msg, &pose)) {
    markInvalid(idx, "pose with NaN/inf or zero quaternion");
    return;
  }
  // Differential poses become body-frame velocities, which no fixed world <- frame transform
  // changes: like r_l, they are not transformed.
  const bool transform =
      !s.cfg.frame_is_world && !s.cfg.differential && !frame.empty() && frame != params_.world_frame;
  if (transform) {
    if (!needs_dynamic_tf_) {
      needs_dynamic_tf_ = true;
      ensureTfListener(s.cfg.name + " poses are in " + frame + ", not " + params_.world_frame);
    }
    Eigen::Isometry3d world_from_frame;
    if (!lookup(params_.world_frame, frame, stamp, &world_from_frame)) {
      markInvalid(idx, "no transform " + params_.world_frame + " <- " + frame);
      return;
    }
    pose.pose = world_from_frame * pose.pose;
    pose.covariance = rotateCovariance(pose.covariance, world_from_frame.linear());
  }
  fusePose(pose, stampToTime(stamp), s.cfg, idx);
}

void EkfNode::fusePose(PoseWithCov pose, double t, const SensorConfig& cfg, size_t idx) {
  SensorState& s = sensors_[idx];
  if (cfg.relative) {
    if (!s.have_first) {
      s.first = pose;
      s.have_first = true;
    }
    pose.pose = s.first.pose.inverse() * pose.pose;
  }
  if (cfg.differential) {
    Measurement m;
    if (s.have_previous && differentialMeasurement(s.previous, pose, t - s.previous_time, cfg, t, &m)) {
      enqueue(m, idx);
    }
    s.previous = pose;
    s.previous_time = t;
    s.have_previous = true;
    return;
  }
  enqueue(poseMeasurement(pose, cfg, t), idx);
}

void EkfNode::poseCallback(const geometry_msgs::PoseWithCovarianceStamped::ConstPtr& msg, size_t idx) {
  countReceived(idx);
  handlePose(msg->pose, msg->header.frame_id, msg->header.stamp, idx);
  sensors_[idx].frames_ready = true;
}

void EkfNode::odomCallback(const nav_msgs::Odometry::ConstPtr& msg, size_t idx) {
  countReceived(idx);
  SensorState& s = sensors_[idx];
  if (updatesAny(s.cfg.update_vector, POSITION_OFFSET, 6)) {
    handlePose(msg->pose, msg->header.frame_id, msg->header.stamp, idx);
  }
  if (!updatesAny(s.cfg.update_vector, POSITION_V_OFFSET, 6)) {
    s.frames_ready = true;
    return;
  }
  Eigen::Matrix3d base_from_child;
  if (!sensorRotation(idx, msg->child_frame_id, &base_from_child)) {
    markInvalid(idx, "no transform " + params_.base_link_frame + " <- " + msg->child_frame_id);
    return;
  }
  s.frames_ready = true;
  Measurement m;
  if (!twistMeasurement(msg->twist, base_from_child, s.cfg, stampToTime(msg->header.stamp), &m)) {
    markInvalid(idx, "twist with NaN/inf");
    return;
  }
  enqueue(m, idx);
}

void EkfNode::twistCallback(const geometry_msgs::TwistWithCovarianceStamped::ConstPtr& msg, size_t idx) {
  countReceived(idx);
  Eigen::Matrix3d base_from_frame;
  if (!sensorRotation(idx, msg->header.frame_id, &base_from_frame)) {
    markInvalid(idx, "no transform " + params_.base_link_frame + " <- " + msg->header.frame_id);
    return;
  }
  sensors_[idx].frames_ready = true;
  Measurement m;
  if (!twistMeasurement(msg->twist, base_from_frame, sensors_[idx].cfg, stampToTime(msg->header.stamp), &m)) {
    markInvalid(idx, "twist with NaN/inf");
    return;
  }
  enqueue(m, idx);
}

void EkfNode::enqueue(const Measurement& m, size_t idx) {
  queue_.push_back(m);
  queue_sensor_.push_back(idx);
}

}  // namespace rbd_localization
