// ekf_localization_node: a thin ROS wrapper around the ROS-free Ekf. Parameters are read by
// filter_params.cpp, messages converted by measurement_conversions.cpp.
#ifndef RBD_LOCALIZATION_EKF_NODE_H
#define RBD_LOCALIZATION_EKF_NODE_H

#include <diagnostic_updater/diagnostic_updater.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <geometry_msgs/TwistWithCovarianceStamped.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <sensor_msgs/Imu.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_broadcaster.h>
#include <tf2_ros/transform_listener.h>

#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "rbd_localization/ekf.h"
#include "rbd_localization/filter_params.h"
#include "rbd_localization/measurement_conversions.h"

namespace rbd_localization {

class EkfNode {
 public:
  EkfNode(const ros::NodeHandle& nh, const ros::NodeHandle& pnh);
  /// Reads parameters, subscribes, starts the timer. False (with reason) on bad configuration.
  bool init(std::string* error);

 private:
  struct SensorState {
    SensorConfig cfg;
    ros::Subscriber sub;
    ros::Time last_receive;
    uint64_t received = 0, accepted = 0, rejected = 0, invalid = 0;
    uint64_t window_received = 0, window_rejected = 0, window_invalid = 0;
    std::string last_problem;
    bool have_first = false;
    PoseWithCov first;
    bool have_previous = false;
    PoseWithCov previous;
    double previous_time = 0.0;
  };

  void imuCallback(const sensor_msgs::Imu::ConstPtr& msg, size_t idx);
  void poseCallback(const geometry_msgs::PoseWithCovarianceStamped::ConstPtr& msg, size_t idx);
  void odomCallback(const nav_msgs::Odometry::ConstPtr& msg, size_t idx);
  void twistCallback(const geometry_msgs::TwistWithCovarianceStamped::ConstPtr& msg, size_t idx);

  void handlePose(const geometry_msgs::PoseWithCovariance& msg, const std::string& frame,
                  const ros::Time& stamp, size_t idx);
  void enqueue(const Measurement& m, size_t idx);
  void markInvalid(size_t idx, const std::string& why);
  double stampToTime(const ros::Time& stamp) const;
  bool staticRotation(const std::string& target, const std::string& source, Eigen::Matrix3d* out);
  bool lookup(const std::string& target, const std::string& source, const ros::Time& stamp,
              Eigen::Isometry3d* out);
  bool sensorStale(const SensorState& s, const ros::Time& now) const;
  /// Once every sensor's fixed rotation is cached and nothing needs time-varying TF, drop the
  /// listener: it would otherwise deserialise all /tf traffic (sim, map correction, ourselves).
  void maybeReleaseTf(size_t resolved_sensor);

  void periodicUpdate(const ros::TimerEvent& ev);
  void publish();
  void diagnoseSensor(size_t idx, diagnostic_updater::DiagnosticStatusWrapper& stat);
  void diagnoseFilter(diagnostic_updater::DiagnosticStatusWrapper& stat);

  ros::NodeHandle nh_, pnh_;
  FilterParams params_;
  Ekf ekf_;
  std::ostringstream debug_log_;
  std::vector<SensorState> sensors_;
  std::vector<Measurement> queue_;    // measurements since the last cycle, fused in time order
  std::vector<size_t> queue_sensor_;  // sensor index of each queued measurement
  std::vector<size_t> order_;         // scratch: queue_ indices sorted by time
  ros::Publisher odom_pub_;
  ros::Timer timer_;
  std::unique_ptr<tf2_ros::Buffer> tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;
  tf2_ros::TransformBroadcaster tf_broadcaster_;
  std::unique_ptr<diagnostic_updater::Updater> diagnostics_;
  std::map<std::string, Eigen::Matrix3d> static_rotations_;
  ros::Time start_time_;
  ros::Time last_wall_check_;
  double last_published_stamp_ = -1.0;
  double last_measurement_time_ = 0.0;
  bool publishing_ = false;
  bool needs_dynamic_tf_ = true;
  std::vector<bool> rotation_resolved_;
};

}  // namespace rbd_localization

#endif  // RBD_LOCALIZATION_EKF_NODE_H
