// rbd_lidar node: thin ROS adapter around ScanPipeline / CriticalZone.
// Shaped like pointcloud_to_laserscan's nodelet (all parameters read in one place, iterator over
// the cloud), but it always subscribes: a safety monitor never listens lazily.
#include <dynamic_reconfigure/server.h>
#include <geometry_msgs/Twist.h>
#include <nav_msgs/Odometry.h>
#include <rbd_lidar/ZoneConfig.h>
#include <ros/ros.h>
#include <sensor_msgs/Imu.h>
#include <std_msgs/Float32.h>
#include <std_srvs/SetBool.h>
#include <tf2/LinearMath/Matrix3x3.h>
#include <tf2/LinearMath/Quaternion.h>
#include <tf2_eigen/tf2_eigen.h>
#include <tf2_ros/transform_listener.h>
#include <visualization_msgs/Marker.h>

#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <condition_variable>
#include <mutex>
#include <thread>

#include "rbd_lidar/os1_beams.h"
#include "rbd_lidar/scan_pipeline.h"
#include "rbd_lidar/zone_growth.h"
#include "rbd_lidar/zone_marker.h"

namespace rbd_lidar {

class LidarNode {
 public:
  LidarNode() : pnh_("~"), tf_listener_(tf_buffer_) {
    readParameters();
    // Publishers first: the reconfigure callback may already use them.
    critical_pub_ = pnh_.advertise<sensor_msgs::PointCloud2>("collision_points", 2);
    slice_pub_ = pnh_.advertise<sensor_msgs::PointCloud2>("slice", 2);
    scan_pub_ = nh_.advertise<sensor_msgs::LaserScan>("scan", 2);
    state_pub_ = pnh_.advertise<rbd_msgs::CollisionState>("state", 10);
    marker_pub_ = pnh_.advertise<visualization_msgs::Marker>("zone_marker", 2, true);
    speed_pub_ = pnh_.advertise<std_msgs::Float32>("speed_scale", 10);
    age_pub_ = pnh_.advertise<std_msgs::Float32>("cloud_age", 10);
    server_.reset(new dynamic_reconfigure::Server<ZoneConfig>(pnh_));
    server_->setCallback([this](ZoneConfig& c, uint32_t level) { reconfigure(c, level); });
    last_valid_ = ros::Time::now();
    // Never lazy: subscribe unconditionally.
    cloud_sub_ =
        nh_.subscribe("ouster/points", 2, &LidarNode::cloudCb, this, ros::TransportHints().tcpNoDelay());
    cmd_sub_ = nh_.subscribe("cmd_vel", 10, &LidarNode::cmdCb, this);
    if (attitude_source_ == "odom") odom_sub_ = nh_.subscribe("odom", 10, &LidarNode::odomCb, this);
    if (attitude_source_ == "imu") imu_sub_ = nh_.subscribe("imu", 50, &LidarNode::imuCb, this);
    worker_ = std::thread(&LidarNode::serviceLoop, this);
    stale_timer_ = nh_.createTimer(ros::Duration(0.05), &LidarNode::staleCb, this);
    ROS_INFO("rbd_lidar: zone F%.2f B%.2f L%.2f R%.2f m, %zu beams, attitude from %s", zone_.front,
             zone_.back, zone_.left, zone_.right, pipeline_.beams(), attitude_source_.c_str());
  }

  ~LidarNode() {
    {
      std::lock_guard<std::mutex> lock(svc_mutex_);
      stop_ = true;
    }
    svc_cv_.notify_all();
    if (worker_.joinable()) worker_.join();
  }

 private:
  template <typename T>
  T param(const std::string& name, const T& fallback) {
    T v;
    pnh_.param<T>(name, v, fallback);
    return v;
  }

  void readParameters() {
    base_frame_ = param<std::string>("base_frame", "base_link");
    zone_frame_ = param<std::string>("zone_frame", "");
    mount_from_tf_ = param("mount_from_tf", true);
    mount_t_ = Eigen::Vector3d(param("lidar_offset_x", 0.0), param("lidar_offset_y", 0.0),
                               param("lidar_offset_z", 0.10));
    mount_r_ = (Eigen::AngleAxisd(param("lidar_offset_yaw", 0.0), Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(param("lidar_offset_pitch", 0.0), Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(param("lidar_offset_roll", 0.0), Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
    base_height_ = param("base_height", 0.28);
    attitude_source_ = param<std::string>("attitude_source", "imu");
    if (attitude_source_ != "odom" && attitude_source_ != "imu" && attitude_source_ != "fixed") {
      ROS_ERROR("rbd_lidar: attitude_source must be 'odom', 'imu' or 'fixed', not '%s'; using 'fixed'",
                attitude_source_.c_str());
      attitude_source_ = "fixed";
    }
    fixed_roll_ = param("body_roll", 0.0);
    fixed_pitch_ = param("body_pitch", 0.0);
    use_odom_height_ = param("use_odom_height", false);
    attitude_timeout_ = param("attitude_timeout", 0.5);
    imu_filter_time_ = param("imu_filter_time", 0.5);
    cmd_timeout_ = param("cmd_vel_timeout", 0.5);
    error_period_ = param("error_log_period", 5.0);
    retry_period_ = param("service_retry_period", 1.0);
    pparams_.beams_from_cloud = param("beams_from_cloud", true);
    pparams_.slice_ring = param("slice_ring", -1);
    pparams_.scan_range_min = param("scan_range_min", 0.30);
    pparams_.scan_range_max = param("scan_range_max", 120.0);
    pparams_.min_valid_fraction = param("min_valid_fraction", 0.01);
    pparams_.floor_from_cloud = param("floor_from_cloud", true);
    pparams_.floor_height_tolerance = param("floor_height_tolerance", 0.20);
    pparams_.floor_max_tilt = param("floor_max_tilt", 0.35);

    std::vector<double> alt, az;
    std::vector<int> shift;
    pnh_.param("beam_altitude_angles", alt, os1U0Altitudes());
    pnh_.param("beam_azimuth_angles", az, os1U0Azimuths());
    pnh_.param("pixel_shift_by_row", shift, std::vector<int>(alt.size(), 0));
    if (az.size() != alt.size() || shift.size() != alt.size() || alt.empty()) {
      ROS_ERROR(
          "rbd_lidar: beam_altitude_angles / beam_azimuth_angles / pixel_shift_by_row sizes differ "
          "(%zu/%zu/%zu);"
          " using the built-in OS1-32 table",
          alt.size(), az.size(), shift.size());
      alt = os1U0Altitudes();
      az = os1U0Azimuths();
      shift.assign(alt.size(), 0);
    }
    pipeline_.setNominalBeams(alt, az, shift, param("pixel_shift_columns", 512), param("destaggered", true),
                              param("lidar_origin_to_beam_origin_mm", 15.806),
                              param("lidar_to_sensor_z_mm", 36.18));
  }

  void reconfigure(ZoneConfig& c, uint32_t /*level*/) {
    zone_.front = c.zone_front;
    zone_.back = c.zone_back;
    zone_.left = c.zone_left;
    zone_.right = c.zone_right;
    zone_.slowdown_front = c.slowdown_front;
    zone_.slowdown_back = c.slowdown_back;
    zone_.slowdown_left = c.slowdown_left;
    zone_.slowdown_right = c.slowdown_right;
    zone_.blind_zone = c.blind_zone;
    zone_.floor_clearance = c.floor_clearance;
    zone_.max_height = c.max_height;
    zone_.point_threshold = static_cast<unsigned>(c.point_threshold);
    motion_.reaction_time = c.reaction_time;
    motion_.rotation_lever = c.rotation_lever;
    motion_.max_growth = c.max_growth;
    velocity_aware_ = c.velocity_aware;
    age_aware_ = c.age_aware;
    hold_zone_ = c.hold_when_stopped;
    stale_periods_ = c.stale_periods;
    scan_rate_ = c.scan_rate;
    motion_.max_age = c.max_cloud_age;  // the oldest cloud judged (not the stale limit: README)
    pparams_.hysteresis_scans = static_cast<unsigned>(c.hysteresis_scans);
    pparams_.scan_time = 1.0 / scan_rate_;
    pipeline_.setParams(pparams_);
    ROS_INFO("rbd_lidar: zone F%.2f B%.2f L%.2f R%.2f m, threshold %d, hysteresis %d", zone_.front,
             zone_.back, zone_.left, zone_.right, c.point_threshold, c.hysteresis_scans);
  }

  void cmdCb(const geometry_msgs::Twist& t) {
    cmd_ = t;
    cmd_time_ = ros::Time::now();
  }

  void odomCb(const nav_msgs::Odometry& o) {
    const auto& q = o.pose.pose.orientation;
    const tf2::Quaternion quat(q.x, q.y, q.z, q.w);
    if (!std::isfinite(quat.length()) || quat.length() < 0.5 || !std::isfinite(o.pose.pose.position.z)) {
      ROS_WARN_THROTTLE(5.0, "rbd_lidar: odom orientation invalid; ignoring it");
      return;
    }
    double yaw;
    tf2::Matrix3x3(quat.normalized()).getRPY(odom_roll_, odom_pitch_, yaw);
    odom_z_ = o.pose.pose.position.z;
    odom_time_ = ros::Time::now();
  }

  // Low-pass filtered specific force of the sensor's IMU (gravity direction).
  void imuCb(const sensor_msgs::Imu& m) {
    const Eigen::Vector3d a(m.linear_acceleration.x, m.linear_acceleration.y, m.linear_acceleration.z);
    if (!a.allFinite() || a.norm() < 1.0 || a.norm() > 50.0) {
      ROS_WARN_THROTTLE(5.0, "rbd_lidar: implausible IMU acceleration; ignoring it");
      return;
    }
    const ros::Time now = ros::Time::now();
    if (imu_time_.isZero() || (now - imu_time_).toSec() > attitude_timeout_) {
      gravity_ = a;
    } else {
      const double dt = std::max(0.0, (now - imu_time_).toSec());
      const double k = imu_filter_time_ > 0.0 ? std::min(1.0, dt / imu_filter_time_) : 1.0;
      gravity_ += k * (a - gravity_);
    }
    imu_time_ = now;
  }

  SensorPose currentPose(const std::string& frame) {
    if (mount_from_tf_ && !mount_found_ && !frame.empty()) {
      try {
        const auto tf = tf_buffer_.lookupTransform(base_frame_, frame, ros::Time(0));
        Eigen::Quaterniond r;
        tf2::fromMsg(tf.transform.rotation, r);
        mount_r_ = r.normalized().toRotationMatrix();
        mount_t_ = tf2::transformToEigen(tf).translation();
        mount_found_ = true;
        ROS_INFO("rbd_lidar: mount %s -> %s from TF: (%.3f %.3f %.3f) m", base_frame_.c_str(), frame.c_str(),
                 mount_t_.x(), mount_t_.y(), mount_t_.z());
      } catch (const tf2::TransformException& e) {
        ROS_WARN_THROTTLE(10.0, "rbd_lidar: no TF %s -> %s yet (%s); using lidar_offset_* parameters",
                          base_frame_.c_str(), frame.c_str(), e.what());
      }
    }
    if (!zone_frame_.empty() && !zone_found_) {
      try {
        const auto tf = tf_buffer_.lookupTransform(base_frame_, zone_frame_, ros::Time(0));
        zone_t_ = Eigen::Vector3d(tf.transform.translation.x, tf.transform.translation.y,
                                  tf.transform.translation.z);
        zone_found_ = true;
        ROS_INFO("rbd_lidar: zone distances measured from %s at (%.3f %.3f) m in %s", zone_frame_.c_str(),
                 zone_t_.x(), zone_t_.y(), base_frame_.c_str());
      } catch (const tf2::TransformException& e) {
        ROS_WARN_THROTTLE(10.0, "rbd_lidar: no TF %s -> %s yet (%s); zone measured from the LiDAR meanwhile",
                          base_frame_.c_str(), zone_frame_.c_str(), e.what());
      }
    }
    double roll = fixed_roll_, pitch = fixed_pitch_, height = base_height_;
    if (attitude_source_ == "odom") {
      if (!odom_time_.isZero() && (ros::Time::now() - odom_time_).toSec() < attitude_timeout_) {
        roll = odom_roll_;
        pitch = odom_pitch_;
        if (use_odom_height_) height = odom_z_;
      } else {
        ROS_WARN_THROTTLE(10.0,
                          "rbd_lidar: no fresh odom for the body attitude; assuming roll %.2f pitch %.2f rad",
                          fixed_roll_, fixed_pitch_);
      }
    }
    if (attitude_source_ == "imu") {
      Eigen::Matrix3d level;
      const Eigen::Vector3d mx = mount_r_ * Eigen::Vector3d::UnitX();
      if (!imu_time_.isZero() && (ros::Time::now() - imu_time_).toSec() < attitude_timeout_ &&
          SensorPose::levelFromGravity(gravity_, std::atan2(mx.y(), mx.x()), &level)) {
        SensorPose pose;
        pose.level_from_sensor = level;
        pose.height = height + (level * mount_r_.transpose() * mount_t_).z();
        return pose;
      }
      ROS_WARN_THROTTLE(10.0,
                        "rbd_lidar: no fresh IMU for the sensor attitude; assuming roll %.2f pitch %.2f rad",
                        fixed_roll_, fixed_pitch_);
    }
    return SensorPose::fromBody(roll, pitch, mount_r_, mount_t_, height);
  }

  void cloudCb(const sensor_msgs::PointCloud2ConstPtr& cloud) {
    const ros::Time now = ros::Time::now();
    const double age = (now - cloud->header.stamp).toSec();  // the robot has moved that long unseen
    std_msgs::Float32 age_msg;
    age_msg.data = static_cast<float>(age);
    age_pub_.publish(age_msg);
    const CloudAge verdict =
        age_aware_ ? classifyCloudAge(age, cloud->header.stamp.toSec(), last_judged_, motion_.max_age)
                   : CloudAge::JUDGE;
    if (verdict != CloudAge::JUDGE) {  // not a valid cloud: the stale fail-safe stops without fresh ones
      ROS_WARN_THROTTLE(5.0, "rbd_lidar: cloud %.3f s old (max_cloud_age %.3f s)%s: not judged", age,
                        motion_.max_age, verdict == CloudAge::OUT_OF_ORDER ? ", overtaken" : "");
      ++(verdict == CloudAge::OUT_OF_ORDER ? overtaken_ : too_old_);
      return;
    }
    last_judged_ = cloud->header.stamp.toSec();
    const SensorPose pose = currentPose(cloud->header.frame_id);
    // Zone distances from the body's zone origin: the LiDAR's offset from it, in the level frame.
    Eigen::Vector2d offset(0.0, 0.0);
    if (zone_found_ && (mount_found_ || !mount_from_tf_)) {
      const Eigen::Vector3d o = pose.level_from_sensor * mount_r_.transpose() * (mount_t_ - zone_t_);
      offset = o.head<2>();
    }
    bool clamped = false;
    const ZoneParams base = zoneAroundOrigin(zone_, offset.x(), offset.y(), &clamped);
    if (clamped) {
      ROS_WARN_THROTTLE(10.0, "rbd_lidar: the LiDAR sits outside the zone around %s; a side was clamped to 0",
                        zone_frame_.c_str());
    }
    ZoneParams zone = base;
    bool moving = false;
    if (velocity_aware_ && !cmd_time_.isZero() && (now - cmd_time_).toSec() < cmd_timeout_) {
      zone = grownZone(base, cmd_.linear.x, cmd_.linear.y, cmd_.angular.z, motion_, age_aware_ ? age : 0.0);
      moving = std::fabs(cmd_.linear.x) > 1e-3 || std::fabs(cmd_.linear.y) > 1e-3 ||
               std::fabs(cmd_.angular.z) > 1e-3;
    }
    zone = hold_.apply(base, zone, moving, pipeline_.collision(), velocity_aware_ && hold_zone_);
    pipeline_.setZone(zone);
    pipeline_.setPose(pose);
    ScanPipeline::Outputs& out = outputs_;
    std::string message;
    const CloudError err = pipeline_.process(*cloud, &out, &message);
    if (err != CloudError::NONE) {
      logError(static_cast<size_t>(err), message);
    } else {
      last_valid_ = now;
      stale_ = false;
      too_old_ = overtaken_ = 0;
      if (pipeline_.modelResidual() > 0.03) {
        ROS_WARN_THROTTLE(30.0, "rbd_lidar: the cloud's xyz differs from the beam model by %.0f mm",
                          pipeline_.modelResidual() * 1000.0);
      }
    }
    // Reported distances are from the zone origin, like the configured ones.
    const double shift[4] = {offset.x(), offset.y(), -offset.x(), -offset.y()};  // FRONT LEFT BACK RIGHT
    for (int s = 0; s < 4; ++s) {
      if (std::isfinite(out.state.min_distance[s])) out.state.min_distance[s] += shift[s];
    }
    critical_pub_.publish(out.critical);
    if (err == CloudError::NONE) {
      slice_pub_.publish(out.slice);
      scan_pub_.publish(out.scan);
    }
    publishState(out.state);
    publishMarker(cloud->header, zone, pose);
  }

  void staleCb(const ros::TimerEvent&) {
    const ros::Time now = ros::Time::now();
    if (now.isZero()) return;
    const double gap = (now - last_valid_).toSec();
    if (gap <= stale_periods_ / scan_rate_) return;
    // Publish the stale state once per scan period.
    if (stale_ && (now - last_stale_pub_).toSec() < 1.0 / scan_rate_) return;
    const std::string refused =
        " (" + std::to_string(too_old_) + " too old, " + std::to_string(overtaken_) + " overtaken)";
    if (!stale_) {
      ROS_ERROR("rbd_lidar: no valid cloud for %.2f s%s: collision (stale)", gap, refused.c_str());
    }
    stale_ = true;
    last_stale_pub_ = now;
    rbd_msgs::CollisionState st;
    pipeline_.fail(true, "stale: no valid cloud for " + std::to_string(gap) + " s" + refused, &st);
    st.header.stamp = now;
    st.header.frame_id = last_frame_;
    publishState(st);
  }

  void publishState(const rbd_msgs::CollisionState& st) {
    if (!st.header.frame_id.empty()) last_frame_ = st.header.frame_id;
    state_pub_.publish(st);
    std_msgs::Float32 s;
    s.data = st.speed_scale;
    speed_pub_.publish(s);
    {
      std::lock_guard<std::mutex> lock(svc_mutex_);
      desired_ = st.collision;
    }
    svc_cv_.notify_all();
  }

  void logError(size_t kind, const std::string& message) {
    const ros::WallTime now = ros::WallTime::now();
    if (kind < last_error_log_.size() &&
        (last_error_log_[kind].isZero() || (now - last_error_log_[kind]).toSec() >= error_period_)) {
      last_error_log_[kind] = now;
      ROS_ERROR("rbd_lidar: cloud rejected (collision until valid clouds return): %s", message.c_str());
    }
  }

  void publishMarker(const std_msgs::Header& header, const ZoneParams& z, const SensorPose& pose) {
    if (marker_pub_.getNumSubscribers() == 0 && marker_sent_) return;
    marker_sent_ = true;
    marker_pub_.publish(zoneMarker(header, z, pose));
  }

  // Calls the controller's collision service when the state changes; tolerates its absence
  // (retried every service_retry_period) and never blocks the cloud callback.
  void serviceLoop() {
    ros::ServiceClient client = nh_.serviceClient<std_srvs::SetBool>("rbd_controller/collision");
    std::unique_lock<std::mutex> lock(svc_mutex_);
    while (!stop_) {
      if (desired_ < 0 || desired_ == reported_) {
        svc_cv_.wait(lock);
        continue;
      }
      const int want = desired_;
      lock.unlock();
      std_srvs::SetBool srv;
      srv.request.data = want != 0;
      const bool ok = client.exists() && client.call(srv);
      lock.lock();
      if (ok) {
        reported_ = want;
        if (!srv.response.success) {
          ROS_WARN("rbd_lidar: collision service refused data=%d: %s", want, srv.response.message.c_str());
        }
      } else {
        ROS_WARN_THROTTLE(10.0, "rbd_lidar: collision service %s unavailable; retrying",
                          client.getService().c_str());
        svc_cv_.wait_for(lock, std::chrono::milliseconds(static_cast<int>(retry_period_ * 1000)));
      }
    }
  }

  ros::NodeHandle nh_, pnh_;
  tf2_ros::Buffer tf_buffer_;
  tf2_ros::TransformListener tf_listener_;
  std::unique_ptr<dynamic_reconfigure::Server<ZoneConfig>> server_;
  ros::Subscriber cloud_sub_, cmd_sub_, odom_sub_, imu_sub_;
  ros::Publisher critical_pub_, slice_pub_, scan_pub_, state_pub_, marker_pub_, speed_pub_, age_pub_;
  ros::Timer stale_timer_;

  ScanPipeline pipeline_;
  ScanPipeline::Outputs outputs_;
  PipelineParams pparams_;
  ZoneParams zone_;
  MotionParams motion_;
  bool velocity_aware_ = true;
  bool age_aware_ = true;     // false: every cloud judged, age ignored (the old rule, to measure it)
  double last_judged_ = 0.0;  // capture stamp of the newest cloud judged [s]
  unsigned too_old_ = 0, overtaken_ = 0;  // clouds not judged since the last valid one
  bool hold_zone_ = true;  // a collision found in a motion's grown zone holds that zone while stopped
  ZoneHold hold_;
  int stale_periods_ = 3;
  double scan_rate_ = 10.0;

  std::string base_frame_, zone_frame_, attitude_source_, last_frame_;
  bool mount_from_tf_ = true, mount_found_ = false, use_odom_height_ = false, marker_sent_ = false;
  bool zone_found_ = false;
  Eigen::Vector3d zone_t_ = Eigen::Vector3d::Zero();
  Eigen::Matrix3d mount_r_ = Eigen::Matrix3d::Identity();
  Eigen::Vector3d mount_t_ = Eigen::Vector3d(0, 0, 0.1);
  double base_height_ = 0.28, fixed_roll_ = 0, fixed_pitch_ = 0, attitude_timeout_ = 0.5, cmd_timeout_ = 0.5;
  double error_period_ = 5.0, retry_period_ = 1.0;
  double odom_roll_ = 0, odom_pitch_ = 0, odom_z_ = 0, imu_filter_time_ = 0.5;
  Eigen::Vector3d gravity_ = Eigen::Vector3d(0, 0, 9.81);
  ros::Time odom_time_, imu_time_, cmd_time_, last_valid_, last_stale_pub_;
  geometry_msgs::Twist cmd_;
  bool stale_ = false;
  std::array<ros::WallTime, static_cast<size_t>(CloudError::COUNT)> last_error_log_;

  std::thread worker_;
  std::mutex svc_mutex_;
  std::condition_variable svc_cv_;
  int desired_ = -1;  // -1: nothing to report yet
  int reported_ = 0;  // the controller starts without a collision flag
  bool stop_ = false;
};

}  // namespace rbd_lidar

int main(int argc, char** argv) {
  ros::init(argc, argv, "rbd_lidar");
  rbd_lidar::LidarNode node;
  ros::spin();
  return 0;
}
