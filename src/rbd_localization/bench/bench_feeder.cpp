// Load generator for the EKF node benchmark: an IMU at 500 Hz and a pose at 15 Hz (every 33rd
// IMU message), plus the static base_link -> <imu frame> transform. The robot drives a circle
// (0.3 m/s, 0.2 rad/s) and the data are exact, so nothing is gated away. The publisher queues
// hold seconds of data, so a subscriber slowed down by callgrind still gets every message.
//
//   bench_feeder DURATION [--orientation] [--imu TOPIC] [--pose TOPIC] [--pose-frame FRAME]
//                         [--imu-rate HZ]
//
// --orientation  the IMU carries an orientation with a valid covariance (robot_localization's
//                template fuses it); without it orientation_covariance[0] = -1 (as ouster-ros).
// --imu-rate     IMU rate (default 500 Hz); the pose stays at every 33rd IMU message.
// Prints one JSON line with the rates and message counts.
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <geometry_msgs/TransformStamped.h>
#include <ros/ros.h>
#include <sensor_msgs/Imu.h>
#include <tf2_eigen/tf2_eigen.h>
#include <tf2_ros/static_transform_broadcaster.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

namespace {

constexpr int kImuPerPose = 33;   // 500 / 33 = 15.2 Hz
constexpr double kSpeed = 0.3;    // m/s
constexpr double kYawRate = 0.2;  // rad/s

struct Options {
  double duration = 20.0;
  bool orientation = false;
  std::string imu_topic = "/ouster/imu";
  std::string pose_topic = "/zed2/zed_node/pose_with_covariance";
  std::string pose_frame = "map";
  double imu_rate = 500.0;
};

bool parse(int argc, char** argv, Options* o) {
  int i = 1;
  if (i < argc && argv[i][0] != '-') o->duration = std::atof(argv[i++]);
  for (; i < argc; ++i) {
    const std::string a = argv[i];
    const bool has_value = i + 1 < argc;
    if (a == "--orientation") {
      o->orientation = true;
    } else if (a == "--imu" && has_value) {
      o->imu_topic = argv[++i];
    } else if (a == "--pose" && has_value) {
      o->pose_topic = argv[++i];
    } else if (a == "--pose-frame" && has_value) {
      o->pose_frame = argv[++i];
    } else if (a == "--imu-rate" && has_value) {
      o->imu_rate = std::atof(argv[++i]);
    } else {
      std::fprintf(stderr, "bench_feeder: unknown argument %s\n", a.c_str());
      return false;
    }
  }
  return o->duration > 0.0 && o->imu_rate > 0.0;
}

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "bench_feeder");
  Options opt;
  if (!parse(argc, argv, &opt)) return 2;
  ros::NodeHandle nh;

  ros::Publisher imu_pub = nh.advertise<sensor_msgs::Imu>(opt.imu_topic, 5000);
  ros::Publisher pose_pub = nh.advertise<geometry_msgs::PoseWithCovarianceStamped>(opt.pose_topic, 500);
  tf2_ros::StaticTransformBroadcaster static_tf;
  geometry_msgs::TransformStamped mount;
  mount.header.stamp = ros::Time::now();
  mount.header.frame_id = "base_link";
  mount.child_frame_id = "os_imu";
  mount.transform.translation.z = 0.1;
  mount.transform.rotation.w = 1.0;
  static_tf.sendTransform(mount);
  ros::WallDuration(1.0).sleep();

  sensor_msgs::Imu imu;
  imu.header.frame_id = "os_imu";
  imu.orientation.w = 1.0;
  if (opt.orientation) {
    for (int i : {0, 4, 8}) imu.orientation_covariance[i] = 1e-4;
  } else {
    imu.orientation_covariance[0] = -1.0;
  }
  for (int i : {0, 4, 8}) {
    imu.angular_velocity_covariance[i] = 6e-4;
    imu.linear_acceleration_covariance[i] = 0.01;
  }
  geometry_msgs::PoseWithCovarianceStamped pose;
  pose.header.frame_id = opt.pose_frame;
  for (int i : {0, 7, 14, 21, 28, 35}) pose.pose.covariance[i] = 1e-4;

  const ros::Time start = ros::Time::now();
  const ros::WallDuration period(1.0 / opt.imu_rate);
  ros::WallTime next = ros::WallTime::now();
  long imu_count = 0, pose_count = 0;
  const ros::WallTime wall_start = ros::WallTime::now();
  while (ros::ok() && (ros::Time::now() - start).toSec() < opt.duration) {
    const ros::Time stamp = ros::Time::now();
    const double t = (stamp - start).toSec();
    const double yaw = kYawRate * t;
    imu.header.stamp = stamp;
    imu.angular_velocity.z = kYawRate;
    imu.linear_acceleration.y = kSpeed * kYawRate;  // centripetal
    imu.linear_acceleration.z = 9.80665;
    imu.orientation = tf2::toMsg(Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ())));
    imu_pub.publish(imu);
    ++imu_count;
    if (imu_count % kImuPerPose == 0) {
      const double radius = kSpeed / kYawRate;
      pose.header.stamp = stamp;
      pose.pose.pose.position.x = radius * std::sin(yaw);
      pose.pose.pose.position.y = radius * (1 - std::cos(yaw));
      pose.pose.pose.orientation = imu.orientation;
      pose_pub.publish(pose);
      ++pose_count;
    }
    next += period;
    const ros::WallDuration wait = next - ros::WallTime::now();
    if (wait > ros::WallDuration(0)) wait.sleep();
  }
  const double elapsed = (ros::Time::now() - start).toSec();
  std::printf(
      "{\"feeder_imu_hz\": %.1f, \"feeder_pose_hz\": %.1f, \"feeder_imu_messages\": %ld, "
      "\"feeder_pose_messages\": %ld, \"feeder_wall_seconds\": %.1f}\n",
      imu_count / elapsed, pose_count / elapsed, imu_count, pose_count,
      (ros::WallTime::now() - wall_start).toSec());
  return 0;
}
