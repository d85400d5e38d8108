#include "rbd_localization/ekf_node.h"

#include <geometry_msgs/TransformStamped.h>

#include <algorithm>
#include <cmath>

#include "rbd_localization/geometry.h"

namespace rbd_localization {

namespace {

Eigen::Isometry3d toEigen(const geometry_msgs::Transform& t) {
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  out.linear() = Eigen::Quaterniond(t.rotation.w, t.rotation.x, t.rotation.y, t.rotation.z)
                     .normalized()
                     .toRotationMatrix();
  out.translation() = Eigen::Vector3d(t.translation.x, t.translation.y, t.translation.z);
  return out;
}

geometry_msgs::Quaternion toQuaternionMsg(const Eigen::Quaterniond& q) {
  geometry_msgs::Quaternion m;
  m.x = q.x();
  m.y = q.y();
  m.z = q.z();
  m.w = q.w();
  return m;
}

const char* typeName(SensorType t) {
  switch (t) {
    case SensorType::kImu:
      return "imu";
    case SensorType::kPose:
      return "pose";
    case SensorType::kOdom:
      return "odom";
    case SensorType::kTwist:
      return "twist";
  }
  return "?";
}

// Measurements older than the filter by more than this are dropped rather than fused.
constexpr double kMaxMeasurementAge = 1.0;

}  // namespace

EkfNode::EkfNode(const ros::NodeHandle& nh, const ros::NodeHandle& pnh) : nh_(nh), pnh_(pnh) {}

bool EkfNode::init(std::string* error) {
  if (!loadFilterParams(pnh_, &params_, error)) return false;
  ekf_.setProcessNoiseCovariance(params_.process_noise_covariance);
  ekf_.setInitialEstimateCovariance(params_.initial_estimate_covariance);
  ekf_.setTwoDMode(params_.two_d_mode);
  ekf_.setDebug(params_.debug, &debug_log_);

  tf_buffer_.reset(new tf2_ros::Buffer());
  tf_listener_.reset(new tf2_ros::TransformListener(*tf_buffer_, nh_));
  odom_pub_ = nh_.advertise<nav_msgs::Odometry>("odometry/filtered", 20);
  diagnostics_.reset(new diagnostic_updater::Updater(nh_, pnh_));
  diagnostics_->setHardwareID("none");
  diagnostics_->add("Filter", [this](diagnostic_updater::DiagnosticStatusWrapper& s) { diagnoseFilter(s); });

  sensors_.resize(params_.sensors.size());
  for (size_t i = 0; i < params_.sensors.size(); ++i) {
    SensorState& s = sensors_[i];
    s.cfg = params_.sensors[i];
    const ros::TransportHints hints = ros::TransportHints().tcpNoDelay(s.cfg.nodelay);
    switch (s.cfg.type) {
      case SensorType::kImu:
        s.sub = nh_.subscribe<sensor_msgs::Imu>(
            s.cfg.topic, s.cfg.queue_size,
            [this, i](const sensor_msgs::Imu::ConstPtr& m) { imuCallback(m, i); }, ros::VoidConstPtr(),
            hints);
        break;
      case SensorType::kPose:
        s.sub = nh_.subscribe<geometry_msgs::PoseWithCovarianceStamped>(
            s.cfg.topic, s.cfg.queue_size,
            [this, i](const geometry_msgs::PoseWithCovarianceStamped::ConstPtr& m) { poseCallback(m, i); },
            ros::VoidConstPtr(), hints);
        break;
      case SensorType::kOdom:
        s.sub = nh_.subscribe<nav_msgs::Odometry>(
            s.cfg.topic, s.cfg.queue_size,
            [this, i](const nav_msgs::Odometry::ConstPtr& m) { odomCallback(m, i); }, ros::VoidConstPtr(),
            hints);
        break;
      case SensorType::kTwist:
        s.sub = nh_.subscribe<geometry_msgs::TwistWithCovarianceStamped>(
            s.cfg.topic, s.cfg.queue_size,
            [this, i](const geometry_msgs::TwistWithCovarianceStamped::ConstPtr& m) { twistCallback(m, i); },
            ros::VoidConstPtr(), hints);
        break;
    }
    diagnostics_->add(s.cfg.name + " (" + s.sub.getTopic() + ")",
                      [this, i](diagnostic_updater::DiagnosticStatusWrapper& st) { diagnoseSensor(i, st); });
    ROS_INFO("ekf: %s %s <- %s", typeName(s.cfg.type), s.cfg.name.c_str(), s.sub.getTopic().c_str());
  }
  needs_dynamic_tf_ = params_.world_frame != params_.odom_frame;
  rotation_resolved_.assign(sensors_.size(), true);
  for (size_t i = 0; i < sensors_.size(); ++i) {
    const SensorConfig& c = sensors_[i].cfg;
    bool pose_part = false, rotated_part = false;
    for (int k = 0; k < 6; ++k) pose_part = pose_part || c.update_vector[k];
    for (int k = 6; k < STATE_SIZE; ++k) rotated_part = rotated_part || c.update_vector[k];
    if ((c.type == SensorType::kPose || c.type == SensorType::kOdom) && pose_part && !c.frame_is_world) {
      needs_dynamic_tf_ = true;
    }
    if (c.type == SensorType::kImu || (c.type != SensorType::kPose && rotated_part))
      rotation_resolved_[i] = false;
  }
  start_time_ = ros::Time::now();
  timer_ = nh_.createTimer(ros::Duration(1.0 / params_.frequency), &EkfNode::periodicUpdate, this);
  return true;
}

double EkfNode::stampToTime(const ros::Time& stamp) const {
  return stamp.isZero() ? ros::Time::now().toSec() : stamp.toSec();
}

void EkfNode::markInvalid(size_t idx, const std::string& why) {
  SensorState& s = sensors_[idx];
  ++s.invalid;
  ++s.window_invalid;
  s.last_problem = why;
  ROS_WARN_THROTTLE(2.0, "ekf: %s (%s): %s", s.cfg.name.c_str(), s.cfg.topic.c_str(), why.c_str());
}

bool EkfNode::staticRotation(const std::string& target, const std::string& source, Eigen::Matrix3d* out) {
  if (source.empty() || source == target) {
    out->setIdentity();
    return true;
  }
  const std::string key = target + "<-" + source;
  auto it = static_rotations_.find(key);
  if (it != static_rotations_.end()) {
    *out = it->second;
    return true;
  }
  if (!tf_listener_) {  // released earlier; a new frame appeared
    tf_listener_.reset(new tf2_ros::TransformListener(*tf_buffer_, nh_));
    ROS_WARN("ekf: new sensor frame %s: TF listener restarted", source.c_str());
  }
  Eigen::Isometry3d t;
  if (!lookup(target, source, ros::Time(0), &t)) return false;
  static_rotations_[key] = t.linear();
  *out = t.linear();
  return true;
}

void EkfNode::maybeReleaseTf(size_t resolved_sensor) {
  if (rotation_resolved_[resolved_sensor]) return;
  rotation_resolved_[resolved_sensor] = true;
  if (needs_dynamic_tf_ || !tf_listener_) return;
  for (bool r : rotation_resolved_) {
    if (!r) return;
  }
  tf_listener_.reset();
  ROS_INFO("ekf: all sensor frames resolved, TF listener released");
}

bool EkfNode::lookup(const std::string& target, const std::string& source, const ros::Time& stamp,
                     Eigen::Isometry3d* out) {
  try {
    const geometry_msgs::TransformStamped ts =
        tf_buffer_->lookupTransform(target, source, stamp, ros::Duration(params_.transform_timeout));
    *out = toEigen(ts.transform);
    return true;
  } catch (const tf2::TransformException& ex) {
    if (!stamp.isZero()) {
      // Fall back to the latest transform (static or slowly changing frames).
      try {
        *out = toEigen(tf_buffer_->lookupTransform(target, source, ros::Time(0)).transform);
        return true;
      } catch (const tf2::TransformException&) {
      }
    }
    ROS_WARN_THROTTLE(2.0, "ekf: no transform %s <- %s: %s", target.c_str(), source.c_str(), ex.what());
    return false;
  }
}

void EkfNode::imuCallback(const sensor_msgs::Imu::ConstPtr& msg, size_t idx) {
  SensorState& s = sensors_[idx];
  s.last_receive = ros::Time::now();
  ++s.received;
  ++s.window_received;
  Eigen::Matrix3d base_from_imu;
  if (!staticRotation(params_.base_link_frame, msg->header.frame_id, &base_from_imu)) {
    markInvalid(idx, "no transform " + params_.base_link_frame + " <- " + msg->header.frame_id);
    return;
  }
  maybeReleaseTf(idx);
  std::string reason;
  if (!imuMeasurements(*msg, base_from_imu, s.cfg, ekf_.state(), params_.gravitational_acceleration,
                       stampToTime(msg->header.stamp), &queue_, &reason)) {
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
  if (!s.cfg.frame_is_world && !frame.empty() && frame != params_.world_frame) {
    Eigen::Isometry3d world_from_frame;
    if (!lookup(params_.world_frame, frame, stamp, &world_from_frame)) {
      markInvalid(idx, "no transform " + params_.world_frame + " <- " + frame);
      return;
    }
    pose.pose = world_from_frame * pose.pose;
    pose.covariance = rotateCovariance(pose.covariance, world_from_frame.linear());
  }
  if (s.cfg.relative) {
    if (!s.have_first) {
      s.first = pose;
      s.have_first = true;
    }
    pose.pose = s.first.pose.inverse() * pose.pose;
  }
  const double t = stampToTime(stamp);
  if (s.cfg.differential) {
    Measurement m;
    if (s.have_previous && differentialMeasurement(s.previous, pose, t - s.previous_time, s.cfg, t, &m)) {
      enqueue(m, idx);
    }
    s.previous = pose;
    s.previous_time = t;
    s.have_previous = true;
    return;
  }
  enqueue(poseMeasurement(pose, s.cfg, t), idx);
}

void EkfNode::poseCallback(const geometry_msgs::PoseWithCovarianceStamped::ConstPtr& msg, size_t idx) {
  SensorState& s = sensors_[idx];
  s.last_receive = ros::Time::now();
  ++s.received;
  ++s.window_received;
  handlePose(msg->pose, msg->header.frame_id, msg->header.stamp, idx);
}

void EkfNode::odomCallback(const nav_msgs::Odometry::ConstPtr& msg, size_t idx) {
  SensorState& s = sensors_[idx];
  s.last_receive = ros::Time::now();
  ++s.received;
  ++s.window_received;
  bool pose_used = false;
  for (int i = 0; i < 6; ++i) pose_used = pose_used || s.cfg.update_vector[i];
  if (pose_used) handlePose(msg->pose, msg->header.frame_id, msg->header.stamp, idx);
  bool twist_used = false;
  for (int i = POSITION_V_OFFSET; i < POSITION_V_OFFSET + 6; ++i)
    twist_used = twist_used || s.cfg.update_vector[i];
  if (!twist_used) return;
  Eigen::Matrix3d base_from_child;
  if (!staticRotation(params_.base_link_frame, msg->child_frame_id, &base_from_child)) {
    markInvalid(idx, "no transform " + params_.base_link_frame + " <- " + msg->child_frame_id);
    return;
  }
  maybeReleaseTf(idx);
  Measurement m;
  if (!twistMeasurement(msg->twist, base_from_child, s.cfg, stampToTime(msg->header.stamp), &m)) {
    markInvalid(idx, "twist with NaN/inf");
    return;
  }
  enqueue(m, idx);
}

void EkfNode::twistCallback(const geometry_msgs::TwistWithCovarianceStamped::ConstPtr& msg, size_t idx) {
  SensorState& s = sensors_[idx];
  s.last_receive = ros::Time::now();
  ++s.received;
  ++s.window_received;
  Eigen::Matrix3d base_from_frame;
  if (!staticRotation(params_.base_link_frame, msg->header.frame_id, &base_from_frame)) {
    markInvalid(idx, "no transform " + params_.base_link_frame + " <- " + msg->header.frame_id);
    return;
  }
  maybeReleaseTf(idx);
  Measurement m;
  if (!twistMeasurement(msg->twist, base_from_frame, s.cfg, stampToTime(msg->header.stamp), &m)) {
    markInvalid(idx, "twist with NaN/inf");
    return;
  }
  enqueue(m, idx);
}

void EkfNode::enqueue(const Measurement& m, size_t idx) {
  queue_.push_back(m);
  queue_sensor_.push_back(idx);
}

bool EkfNode::sensorStale(const SensorState& s, const ros::Time& now) const {
  if (s.received == 0) return (now - start_time_).toSec() > params_.sensor_stale_timeout;
  return (now - s.last_receive).toSec() > params_.sensor_stale_timeout;
}

void EkfNode::periodicUpdate(const ros::TimerEvent&) {
  const ros::Time now = ros::Time::now();
  // Time jumped backwards (bag loop, simulator restart): start over.
  if (!last_wall_check_.isZero() && now < last_wall_check_ - ros::Duration(1.0)) {
    ROS_WARN("ekf: time moved backwards, resetting the filter");
    ekf_.reset();
    queue_.clear();
    queue_sensor_.clear();
    last_published_stamp_ = -1.0;
  }
  last_wall_check_ = now;

  bool processed = false;
  order_.resize(queue_.size());
  for (size_t i = 0; i < order_.size(); ++i) order_[i] = i;
  std::stable_sort(order_.begin(), order_.end(),
                   [this](size_t a, size_t b) { return queue_[a].time < queue_[b].time; });
  for (size_t oi : order_) {
    const Measurement& meas = queue_[oi];
    const size_t sensor = queue_sensor_[oi];
    SensorState& s = sensors_[sensor];
    if (ekf_.initialized() && meas.time < ekf_.lastUpdateTime() - kMaxMeasurementAge) {
      markInvalid(sensor, "measurement older than the filter by more than 1 s (stamp problem?)");
      continue;
    }
    switch (ekf_.processMeasurement(meas)) {
      case CorrectResult::kAccepted:
        ++s.accepted;
        processed = true;
        last_measurement_time_ = meas.time;
        break;
      case CorrectResult::kRejected:
        ++s.rejected;
        ++s.window_rejected;
        s.last_problem = meas.source + " rejected: squared Mahalanobis distance " +
                         std::to_string(ekf_.lastSquaredMahalanobis());
        ROS_WARN_THROTTLE(1.0, "ekf: %s", s.last_problem.c_str());
        break;
      case CorrectResult::kInvalid:
        markInvalid(sensor, meas.source + " has invalid values or covariance");
        break;
    }
  }
  queue_.clear();
  queue_sensor_.clear();
  if (params_.debug && debug_log_.tellp() > 0) {
    ROS_DEBUG_STREAM("ekf: " << debug_log_.str());
    debug_log_.str("");
  }
  // No news within sensor_timeout: keep the estimate moving with the model (r_l behaviour).
  if (ekf_.initialized() && !processed && now.toSec() - ekf_.lastUpdateTime() > params_.sensor_timeout) {
    ekf_.predictTo(now.toSec());
  }

  bool all_stale = true;
  for (const SensorState& s : sensors_) all_stale = all_stale && sensorStale(s, now);
  const bool was_publishing = publishing_;
  publishing_ = ekf_.initialized() && !all_stale;
  if (was_publishing && !publishing_) {
    ROS_ERROR("ekf: every sensor is stale (> %.2f s): estimate no longer published",
              params_.sensor_stale_timeout);
  }
  if (publishing_) publish();
  diagnostics_->update();
}

void EkfNode::publish() {
  const StateVector& x = ekf_.state();
  const StateMatrix& p = ekf_.covariance();
  const double t = ekf_.lastUpdateTime();
  const Eigen::Quaterniond q(rotationFromRpy(x(StateMemberRoll), x(StateMemberPitch), x(StateMemberYaw)));

  nav_msgs::Odometry odom;
  odom.header.stamp.fromSec(t);
  odom.header.frame_id = params_.world_frame;
  odom.child_frame_id = params_.base_link_frame;
  odom.pose.pose.position.x = x(StateMemberX);
  odom.pose.pose.position.y = x(StateMemberY);
  odom.pose.pose.position.z = x(StateMemberZ);
  odom.pose.pose.orientation = toQuaternionMsg(q);
  odom.twist.twist.linear.x = x(StateMemberVx);
  odom.twist.twist.linear.y = x(StateMemberVy);
  odom.twist.twist.linear.z = x(StateMemberVz);
  odom.twist.twist.angular.x = x(StateMemberVroll);
  odom.twist.twist.angular.y = x(StateMemberVpitch);
  odom.twist.twist.angular.z = x(StateMemberVyaw);
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) {
      odom.pose.covariance[r * 6 + c] = p(r, c);
      odom.twist.covariance[r * 6 + c] = p(POSITION_V_OFFSET + r, POSITION_V_OFFSET + c);
    }
  }
  odom_pub_.publish(odom);

  if (!params_.publish_tf || t <= last_published_stamp_) return;
  last_published_stamp_ = t;
  geometry_msgs::TransformStamped tf;
  tf.header.stamp.fromSec(t + params_.transform_time_offset);
  if (params_.world_frame == params_.odom_frame) {
    tf.header.frame_id = params_.odom_frame;
    tf.child_frame_id = params_.base_link_frame;
    tf.transform.translation.x = x(StateMemberX);
    tf.transform.translation.y = x(StateMemberY);
    tf.transform.translation.z = x(StateMemberZ);
    tf.transform.rotation = toQuaternionMsg(q);
  } else {
    // world_frame == map_frame: publish map -> odom so that map -> base_link is the estimate.
    Eigen::Isometry3d odom_from_base;
    if (!lookup(params_.odom_frame, params_.base_link_frame, odom.header.stamp, &odom_from_base)) return;
    Eigen::Isometry3d map_from_base = Eigen::Isometry3d::Identity();
    map_from_base.linear() = q.toRotationMatrix();
    map_from_base.translation() = Eigen::Vector3d(x(StateMemberX), x(StateMemberY), x(StateMemberZ));
    const Eigen::Isometry3d map_from_odom = map_from_base * odom_from_base.inverse();
    tf.header.frame_id = params_.map_frame;
    tf.child_frame_id = params_.odom_frame;
    tf.transform.translation.x = map_from_odom.translation().x();
    tf.transform.translation.y = map_from_odom.translation().y();
    tf.transform.translation.z = map_from_odom.translation().z();
    tf.transform.rotation = toQuaternionMsg(Eigen::Quaterniond(map_from_odom.linear()));
  }
  tf_broadcaster_.sendTransform(tf);
}

void EkfNode::diagnoseSensor(size_t idx, diagnostic_updater::DiagnosticStatusWrapper& stat) {
  SensorState& s = sensors_[idx];
  const ros::Time now = ros::Time::now();
  stat.add("topic", s.sub.getTopic());
  stat.add("type", typeName(s.cfg.type));
  stat.add("received", s.received);
  stat.add("accepted", s.accepted);
  stat.add("rejected", s.rejected);
  stat.add("invalid", s.invalid);
  stat.add("last message age [s]", s.received ? (now - s.last_receive).toSec() : -1.0);
  if (sensorStale(s, now)) {
    stat.summaryf(diagnostic_msgs::DiagnosticStatus::ERROR, "stale: %s",
                  s.received ? "no message within sensor_stale_timeout" : "no message received yet");
  } else if (s.window_rejected > 0) {
    stat.summaryf(diagnostic_msgs::DiagnosticStatus::WARN,
                  "rejected %lu measurement(s) since last report: %s",
                  static_cast<unsigned long>(s.window_rejected), s.last_problem.c_str());
  } else if (s.window_invalid > 0) {
    stat.summaryf(diagnostic_msgs::DiagnosticStatus::WARN, "%lu invalid message(s) since last report: %s",
                  static_cast<unsigned long>(s.window_invalid), s.last_problem.c_str());
  } else {
    stat.summary(diagnostic_msgs::DiagnosticStatus::OK, "ok");
  }
  s.window_received = s.window_rejected = s.window_invalid = 0;
}

void EkfNode::diagnoseFilter(diagnostic_updater::DiagnosticStatusWrapper& stat) {
  stat.add("initialized", ekf_.initialized());
  stat.add("filter time", ekf_.lastUpdateTime());
  stat.add("world_frame", params_.world_frame);
  if (!ekf_.initialized()) {
    stat.summary(diagnostic_msgs::DiagnosticStatus::WARN, "waiting for the first measurement");
  } else if (!publishing_) {
    stat.summary(diagnostic_msgs::DiagnosticStatus::ERROR, "all sensors stale: estimate not published");
  } else if (!ekf_.state().allFinite()) {
    stat.summary(diagnostic_msgs::DiagnosticStatus::ERROR, "state not finite");
  } else {
    stat.summary(diagnostic_msgs::DiagnosticStatus::OK, "publishing");
  }
}

}  // namespace rbd_localization
