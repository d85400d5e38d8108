// Load generator for the EKF node benchmark: /ouster/imu at 500 Hz (frame os_imu) and the ZED
// pose at 15 Hz, plus the static base_link -> os_imu transform. Runs for argv[1] seconds.
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <geometry_msgs/TransformStamped.h>
#include <ros/ros.h>
#include <sensor_msgs/Imu.h>
#include <tf2_ros/static_transform_broadcaster.h>

#include <cmath>
#include <cstdio>

int main(int argc, char** argv) {
  ros::init(argc, argv, "bench_feeder");
  const double duration = argc > 1 ? std::atof(argv[1]) : 20.0;
  ros::NodeHandle nh;
  ros::Publisher imu_pub = nh.advertise<sensor_msgs::Imu>("/ouster/imu", 100);
  ros::Publisher pose_pub =
      nh.advertise<geometry_msgs::PoseWithCovarianceStamped>("/zed2/zed_node/pose_with_covariance", 10);
  tf2_ros::StaticTransformBroadcaster static_tf;
  geometry_msgs::TransformStamped mount;
  mount.header.stamp = ros::Time::now();
  mount.header.frame_id = "base_link";
  mount.child_frame_id = "os_imu";
  mount.transform.translation.z = 0.1;
  mount.transform.rotation.w = 1.0;
  static_tf.sendTransform(mount);
  ros::Duration(1.0).sleep();

  sensor_msgs::Imu imu;
  imu.header.frame_id = "os_imu";
  imu.orientation.w = 1.0;
  imu.orientation_covariance[0] = -1.0;
  for (int i : {0, 4, 8}) {
    imu.angular_velocity_covariance[i] = 6e-4;
    imu.linear_acceleration_covariance[i] = 0.01;
  }
  geometry_msgs::PoseWithCovarianceStamped pose;
  pose.header.frame_id = "map";
  for (int i : {0, 7, 14, 21, 28, 35}) pose.pose.covariance[i] = 1e-4;

  ros::Rate rate(500.0);
  const ros::Time start = ros::Time::now();
  long imu_count = 0, pose_count = 0;
  while (ros::ok() && (ros::Time::now() - start).toSec() < duration) {
    const ros::Time now = ros::Time::now();
    const double t = (now - start).toSec();
    imu.header.stamp = now;
    imu.angular_velocity.z = 0.2;
    imu.linear_acceleration.y = 0.06;
    imu.linear_acceleration.z = 9.80665;
    imu_pub.publish(imu);
    ++imu_count;
    if (imu_count % 33 == 0) {
      const double yaw = 0.2 * t;
      pose.header.stamp = now;
      pose.pose.pose.position.x = 1.5 * std::sin(yaw);
      pose.pose.pose.position.y = 1.5 * (1 - std::cos(yaw));
      pose.pose.pose.orientation.z = std::sin(yaw / 2);
      pose.pose.pose.orientation.w = std::cos(yaw / 2);
      pose_pub.publish(pose);
      ++pose_count;
    }
    rate.sleep();
  }
  const double elapsed = (ros::Time::now() - start).toSec();
  std::printf("{\"feeder_imu_hz\": %.1f, \"feeder_pose_hz\": %.1f}\n", imu_count / elapsed,
              pose_count / elapsed);
  return 0;
}
