// The EKF node: parameters, subscriptions and the TF it needs, the filter cycle and its output.
// The sensor callbacks (message -> measurement) are in ekf_sensor_input.cpp, the diagnostics in
// ekf_diagnostics.cpp.
#include "rbd_localization/ekf_node.h"

#include <std_msgs/String.h>
#include <tf2_eigen/tf2_eigen.h>

#include <algorithm>
#include <cmath>

#include "rbd_localization/effective_config.h"
#include "rbd_localization/geometry.h"
#include "rbd_localization/node_main.h"
#include "rbd_localization/run_node.h"

namespace rbd_localization {

namespace {

// Measurements older than the filter by more than this are dropped rather than fused.
constexpr double kMaxMeasurementAge = 1.0;

// Messages a subscriber holds at least (2 s of a 500 Hz IMU): inputs are handled once per cycle,
// and a cycle that runs late (load, simulated time) must not lose any. r_l drops what exceeds
// <sensor>_queue_size per cycle; this node fuses more, never less.
constexpr int kMinSubscriberQueue = 1000;

uint32_t subscriberQueue(int queue_size) {
  return queue_size == 0 ? 0u : static_cast<uint32_t>(std::max(queue_size, kMinSubscriberQueue));
}

}  // namespace

EkfNode::EkfNode(const ros::NodeHandle& nh, const ros::NodeHandle& pnh) : nh_(nh), pnh_(pnh) {}

template <class M>
ros::Subscriber EkfNode::subscribeSensor(const SensorConfig& cfg,
                                         const boost::function<void(const boost::shared_ptr<M const>&)>& cb) {
  ros::SubscribeOptions ops;
  ops.template init<M>(cfg.topic, subscriberQueue(cfg.queue_size), cb);
  ops.transport_hints = ros::TransportHints().tcpNoDelay(cfg.nodelay);
  ops.callback_queue = &sensor_queue_;
  return nh_.subscribe(ops);
}

bool EkfNode::init(std::string* error) {
  std::vector<std::string> warnings;
  if (!loadFilterParams(pnh_, &params_, &warnings, error)) return false;
  for (const std::string& w : warnings) ROS_WARN("ekf: %s", w.c_str());

  ekf_.setProcessNoiseCovariance(params_.process_noise_covariance);
  ekf_.setInitialEstimateCovariance(params_.initial_estimate_covariance);
  ekf_.setTwoDMode(params_.two_d_mode);
  ekf_.setInitialState(params_.initial_state);
  if (params_.debug && !params_.debug_out_file.empty()) {
    debug_file_.open(params_.debug_out_file.c_str());
    if (!debug_file_.is_open()) {
      ROS_WARN("ekf: cannot write debug_out_file %s; the filter trace goes to the DEBUG log",
               params_.debug_out_file.c_str());
    }
  }
  ekf_.setDebug(params_.debug,
                debug_file_.is_open() ? static_cast<std::ostream*>(&debug_file_) : &debug_log_);
  enabled_ = !params_.disabled_at_startup;

  tf_buffer_.reset(new tf2_ros::Buffer());
  needs_dynamic_tf_ = params_.world_frame != params_.odom_frame && params_.publish_tf;  // map -> odom
  ensureTfListener("start-up");
  odom_pub_ = nh_.advertise<nav_msgs::Odometry>("odometry/filtered", 20);
  if (params_.publish_acceleration) {
    accel_pub_ = nh_.advertise<geometry_msgs::AccelWithCovarianceStamped>("accel/filtered", 20);
  }
  config_pub_ = pnh_.advertise<std_msgs::String>("effective_config", 1, true);
  enable_srv_ = pnh_.advertiseService("enable", &EkfNode::enableService, this);
  diagnostics_.reset(new diagnostic_updater::Updater(nh_, pnh_));
  diagnostics_->setHardwareID("none");
  diagnostics_->add("Filter", [this](diagnostic_updater::DiagnosticStatusWrapper& s) { diagnoseFilter(s); });

  sensors_.resize(params_.sensors.size());
  for (size_t i = 0; i < params_.sensors.size(); ++i) {
    SensorState& s = sensors_[i];
    s.cfg = params_.sensors[i];
    switch (s.cfg.type) {
      case SensorType::kImu: {
        s.orientation_as_pose =
            (s.cfg.relative || s.cfg.differential) && updatesAny(s.cfg.update_vector, ORIENTATION_OFFSET, 3);
        if (s.orientation_as_pose) {
          s.orientation_cfg = s.rest_cfg = s.cfg;
          for (int k = 0; k < STATE_SIZE; ++k) {
            const bool orientation = k >= ORIENTATION_OFFSET && k < POSITION_V_OFFSET;
            s.orientation_cfg.update_vector[k] = orientation && s.cfg.update_vector[k];
            if (orientation) s.rest_cfg.update_vector[k] = false;
          }
        }
        s.sub = subscribeSensor<sensor_msgs::Imu>(
            s.cfg, [this, i](const sensor_msgs::Imu::ConstPtr& m) { imuCallback(m, i); });
        break;
      }
      case SensorType::kPose:
        s.sub = subscribeSensor<geometry_msgs::PoseWithCovarianceStamped>(
            s.cfg,
            [this, i](const geometry_msgs::PoseWithCovarianceStamped::ConstPtr& m) { poseCallback(m, i); });
        break;
      case SensorType::kOdom:
        s.sub = subscribeSensor<nav_msgs::Odometry>(
            s.cfg, [this, i](const nav_msgs::Odometry::ConstPtr& m) { odomCallback(m, i); });
        break;
      case SensorType::kTwist:
        s.sub = subscribeSensor<geometry_msgs::TwistWithCovarianceStamped>(
            s.cfg,
            [this, i](const geometry_msgs::TwistWithCovarianceStamped::ConstPtr& m) { twistCallback(m, i); });
        break;
    }
    diagnostics_->add(s.cfg.name + " (" + s.sub.getTopic() + ")",
                      [this, i](diagnostic_updater::DiagnosticStatusWrapper& st) { diagnoseSensor(i, st); });
    ROS_INFO("ekf: %s %s <- %s", sensorTypeName(s.cfg.type), s.cfg.name.c_str(), s.sub.getTopic().c_str());
  }
  std_msgs::String config;
  config.data =
      effectiveConfigJson(params_, ekf_.processNoiseCovariance(), ekf_.initialEstimateCovariance(), warnings);
  config_pub_.publish(config);
  if (!enabled_) {
    ROS_WARN("ekf: disabled_at_startup: waiting for %s/enable", pnh_.getNamespace().c_str());
  }
  start_time_ = ros::Time::now();
  timer_ = nh_.createTimer(ros::Duration(1.0 / params_.frequency), &EkfNode::periodicUpdate, this);
  return true;
}

bool EkfNode::enableService(std_srvs::Empty::Request&, std_srvs::Empty::Response&) {
  if (enabled_) {
    ROS_WARN("ekf: enable called, but the filter is already enabled");
  } else {
    ROS_INFO("ekf: enabled");
    enabled_ = true;
    start_time_ = ros::Time::now();
  }
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

void EkfNode::ensureTfListener(const std::string& why) {
  if (tf_listener_) return;
  // Without a transform_timeout no lookup waits, so the listener's messages can be handled with
  // the sensors' in the filter cycle (no thread, no wake-ups of its own); a lookup that waits
  // needs the listener's own thread to fill the buffer meanwhile.
  if (params_.transform_timeout > 0.0) {
    tf_listener_.reset(new tf2_ros::TransformListener(*tf_buffer_, nh_, true));
  } else {
    ros::NodeHandle tf_nh(nh_);
    tf_nh.setCallbackQueue(&sensor_queue_);
    tf_listener_.reset(new tf2_ros::TransformListener(*tf_buffer_, tf_nh, false));
  }
  if (why != "start-up") ROS_WARN("ekf: TF listener restarted: %s", why.c_str());
}

void EkfNode::maybeReleaseTf() {
  if (!tf_listener_ || needs_dynamic_tf_) return;
  for (const SensorState& s : sensors_) {
    if (!s.frames_ready) return;
  }
  tf_listener_.reset();
  ROS_INFO("ekf: all sensor frames resolved, TF listener released");
}

bool EkfNode::sensorRotation(size_t idx, const std::string& frame, Eigen::Matrix3d* out) {
  SensorState& s = sensors_[idx];
  if (s.has_rotation && frame == s.rotation_frame) {
    *out = s.rotation;
    return true;
  }
  if (frame.empty() || frame == params_.base_link_frame) {
    out->setIdentity();
  } else {
    ensureTfListener("new frame " + frame + " for " + s.cfg.name);
    Eigen::Isometry3d t;
    if (!lookup(params_.base_link_frame, frame, ros::Time(0), &t)) return false;
    *out = t.linear();
  }
  s.rotation_frame = frame;
  s.rotation = *out;
  s.has_rotation = true;
  return true;
}

bool EkfNode::lookup(const std::string& target, const std::string& source, const ros::Time& stamp,
                     Eigen::Isometry3d* out) {
  try {
    // Only a lookup that may wait takes the timeout (tf2 refuses one without a listener thread).
    const geometry_msgs::TransformStamped ts =
        params_.transform_timeout > 0.0
            ? tf_buffer_->lookupTransform(target, source, stamp, ros::Duration(params_.transform_timeout))
            : tf_buffer_->lookupTransform(target, source, stamp);
    *out = tf2::transformToEigen(ts);
    return true;
  } catch (const tf2::TransformException& ex) {
    if (!stamp.isZero()) {
      // Fall back to the latest transform (static or slowly changing frames).
      try {
        *out = tf2::transformToEigen(tf_buffer_->lookupTransform(target, source, ros::Time(0)));
        return true;
      } catch (const tf2::TransformException&) {
      }
    }
    if (!params_.silent_tf_failure) {
      ROS_WARN_THROTTLE(2.0, "ekf: no transform %s <- %s: %s", target.c_str(), source.c_str(), ex.what());
    }
    return false;
  }
}

bool EkfNode::sensorStale(const SensorState& s, const ros::Time& now) const {
  if (s.received == 0) return (now - start_time_).toSec() > params_.sensor_stale_timeout;
  return (now - s.last_receive).toSec() > params_.sensor_stale_timeout;
}

void EkfNode::drainSensorQueue() {
  for (SensorState& s : sensors_) s.cycle_received = 0;
  sensor_queue_.callAvailable(ros::WallDuration(0));
  for (SensorState& s : sensors_) {
    // A full subscriber queue drops its oldest messages (roscpp).
    const uint32_t queue = subscriberQueue(s.cfg.queue_size);
    if (queue > 0 && s.cycle_received >= queue) {
      ++s.full_queue_cycles;
      ROS_WARN_THROTTLE(
          10.0,
          "ekf: %s delivered %u messages (its whole subscriber queue) in one filter cycle: older "
          "ones may have been dropped (the filter cycle ran seconds late)",
          s.cfg.name.c_str(), queue);
    }
  }
}

void EkfNode::periodicUpdate(const ros::TimerEvent&) {
  const ros::Time now = ros::Time::now();
  // Time jumped backwards (bag loop, simulator restart): start over.
  if (!last_wall_check_.isZero() && now < last_wall_check_ - ros::Duration(1.0)) {
    ROS_WARN("ekf: time moved backwards, resetting the filter");
    ekf_.reset();
    queue_.clear();
    queue_sensor_.clear();
    for (SensorState& s : sensors_) s.have_first = s.have_previous = false;
    last_published_stamp_ = -1.0;
  }
  last_wall_check_ = now;

  drainSensorQueue();
  maybeReleaseTf();
  if (!enabled_) {
    queue_.clear();
    queue_sensor_.clear();
    diagnostics_->update();
    return;
  }

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
  if (params_.debug) {
    if (debug_file_.is_open()) {
      debug_file_.flush();
    } else if (debug_log_.tellp() > 0) {
      ROS_DEBUG_STREAM("ekf: " << debug_log_.str());
      debug_log_.str("");
    }
  }
  // No news within sensor_timeout (or always, with predict_to_current_time): keep the estimate
  // moving with the model (r_l behaviour).
  if (ekf_.initialized() && (params_.predict_to_current_time ||
                             (!processed && now.toSec() - ekf_.lastUpdateTime() > params_.sensor_timeout))) {
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

  nav_msgs::Odometry& odom = odom_msg_;
  odom.header.stamp.fromSec(t);
  odom.header.frame_id = params_.world_frame;
  odom.child_frame_id = params_.base_link_output_frame;
  odom.pose.pose.position.x = x(StateMemberX);
  odom.pose.pose.position.y = x(StateMemberY);
  odom.pose.pose.position.z = x(StateMemberZ);
  odom.pose.pose.orientation = tf2::toMsg(q);
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

  if (params_.publish_acceleration) {
    geometry_msgs::AccelWithCovarianceStamped& accel = accel_msg_;
    accel.header.stamp = odom.header.stamp;
    accel.header.frame_id = params_.base_link_output_frame;
    accel.accel.accel.linear.x = x(StateMemberAx);
    accel.accel.accel.linear.y = x(StateMemberAy);
    accel.accel.accel.linear.z = x(StateMemberAz);
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c)
        accel.accel.covariance[r * 6 + c] = p(POSITION_A_OFFSET + r, POSITION_A_OFFSET + c);
    }
    accel_pub_.publish(accel);
  }

  if (!params_.publish_tf || t <= last_published_stamp_) return;
  geometry_msgs::TransformStamped& tf = tf_msg_;
  tf.header.stamp.fromSec(t + params_.transform_time_offset);
  if (params_.world_frame == params_.odom_frame) {
    tf.header.frame_id = params_.odom_frame;
    tf.child_frame_id = params_.base_link_output_frame;
    tf.transform.translation.x = x(StateMemberX);
    tf.transform.translation.y = x(StateMemberY);
    tf.transform.translation.z = x(StateMemberZ);
    tf.transform.rotation = tf2::toMsg(q);
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
    tf.transform.rotation = tf2::toMsg(Eigen::Quaterniond(map_from_odom.linear()));
  }
  last_published_stamp_ = t;
  tf_broadcaster_.sendTransform(tf);
}

int ekfLocalizationNodeMain(int argc, char** argv) {
  return runNode<EkfNode>(argc, argv, "ekf_localization_node");
}

}  // namespace rbd_localization
