// map_correction_node: thin ROS wrapper around MapCorrection. Reads /scan and the EKF
// (odom -> base_link via TF and odometry/filtered), publishes map -> odom, /map and
// /rbd_localization/pose.
#ifndef RBD_LOCALIZATION_MAP_CORRECTION_ROS_H
#define RBD_LOCALIZATION_MAP_CORRECTION_ROS_H

#include <diagnostic_updater/diagnostic_updater.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <sensor_msgs/LaserScan.h>
#include <sensor_msgs/PointCloud2.h>
#include <std_srvs/Trigger.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_broadcaster.h>
#include <tf2_ros/transform_listener.h>

#include <map>
#include <memory>
#include <string>

#include "rbd_localization/map_correction.h"
#include "rbd_localization/map_correction_params.h"
#include "rbd_localization/scan_slice.h"

namespace rbd_localization {

class MapCorrectionNode {
 public:
  MapCorrectionNode(const ros::NodeHandle& nh, const ros::NodeHandle& pnh);
  bool init(std::string* error);

 private:
  void scanCallback(const sensor_msgs::LaserScan::ConstPtr& msg);
  void cloudCallback(const sensor_msgs::PointCloud2::ConstPtr& msg);
  bool acceptInput(const ros::Time& stamp);
  bool sensorTransform(const std::string& frame, Eigen::Isometry3d* out);
  ScanSlicer::Params slicerParams() const;
  bool cloudToBase(const sensor_msgs::PointCloud2& cloud, const Eigen::Matrix3d& level, Points2d* out);
  void odomCallback(const nav_msgs::Odometry::ConstPtr& msg);
  void timerCallback(const ros::TimerEvent& ev);
  void processPendingScan();
  bool scanToBase(const sensor_msgs::LaserScan& scan, const Eigen::Matrix3d& level, Points2d* out);
  void publishTransform();
  void publishMap(const ros::Time& stamp);
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat);
  bool saveMapService(std_srvs::Trigger::Request& req, std_srvs::Trigger::Response& res);
  void publishLocalized();

  ros::NodeHandle nh_, pnh_;
  MapCorrectionNodeParams params_;
  std::unique_ptr<MapCorrection> core_;
  ros::Subscriber scan_sub_, odom_sub_;
  ros::Publisher map_pub_, pose_pub_, localized_pub_;
  ros::ServiceServer save_srv_;
  Eigen::Vector3d home_ = Eigen::Vector3d::Zero();
  int localized_published_ = -1;
  ros::Timer timer_;
  std::unique_ptr<tf2_ros::Buffer> tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;
  tf2_ros::TransformBroadcaster tf_broadcaster_;
  std::unique_ptr<diagnostic_updater::Updater> diagnostics_;
  std::map<std::string, Eigen::Isometry3d> base_from_sensor_;
  sensor_msgs::LaserScan::ConstPtr pending_scan_;
  sensor_msgs::PointCloud2::ConstPtr pending_cloud_;
  ros::Time last_match_stamp_;
  ros::Time last_scan_receive_;
  ros::Time last_map_publish_;
  ros::Time start_time_;
  bool map_dirty_ = false;
  uint64_t scans_ = 0, accepted_ = 0, rejected_ = 0, skipped_ = 0;
  std::string last_status_ = "no scan yet";
  double last_cpu_ms_ = 0.0;
};

}  // namespace rbd_localization

#endif  // RBD_LOCALIZATION_MAP_CORRECTION_ROS_H
