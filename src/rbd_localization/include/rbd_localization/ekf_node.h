// ekf_localization_node: a thin ROS wrapper around the ROS-free Ekf. Parameters are read by
// filter_params.cpp, messages converted by measurement_conversions.cpp.
//
// Sensor messages are handled in batches, once per filter cycle (as robot_localization's
// spinOnce loop does): the subscriptions use a callback queue of their own that the cycle drains
// before fusing, so a 500 Hz IMU wakes only the receiving thread, not the filter thread too.
// The subscriber queues hold at least 1000 messages, so a cycle that runs late loses none.
#ifndef RBD_LOCALIZATION_EKF_NODE_H
#define RBD_LOCALIZATION_EKF_NODE_H

#include <diagnostic_updater/diagnostic_updater.h>
#include <geometry_msgs/AccelWithCovarianceStamped.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <geometry_msgs/TransformStamped.h>
#include <geometry_msgs/TwistWithCovarianceStamped.h>
#include <nav_msgs/Odometry.h>
#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <sensor_msgs/Imu.h>
#include <std_srvs/Empty.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_broadcaster.h>
#include <tf2_ros/transform_listener.h>

#include <fstream>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "rbd_localization/ekf.h"
#include "rbd_localization/filter_params.h"
#include "rbd_localization/measurement_conversions.h"

namespace rbd_localization {

/// True if any of `count` entries of an update vector from `first` on is set.
inline bool updatesAny(const std::array<bool, STATE_SIZE>& v, int first, int count) {
  for (int i = first; i < first + count; ++i) {
    if (v[i]) return true;
  }
  return false;
}

class EkfNode {
 public:
  EkfNode(const ros::NodeHandle& nh, const ros::NodeHandle& pnh);
  /// Reads parameters, subscribes, starts the timer. False (with reason) on bad configuration;
  /// nothing is advertised or published in that case.
  bool init(std::string* error);

 private:
  struct SensorState {
    SensorConfig cfg;
    /// IMU with _relative/_differential: its orientation goes through the pose path with
    /// orientation_cfg (roll, pitch, yaw only); rates and accelerations use rest_cfg.
    bool orientation_as_pose = false;
    SensorConfig orientation_cfg, rest_cfg;
    ros::Subscriber sub;
    ros::Time last_receive;
    uint64_t received = 0, accepted = 0, rejected = 0, invalid = 0;
    uint64_t window_received = 0, window_rejected = 0, window_invalid = 0;
    uint64_t cycle_received = 0, full_queue_cycles = 0;
    std::string last_problem;
    bool have_first = false;
    PoseWithCov first;
    bool have_previous = false;
    PoseWithCov previous;
    double previous_time = 0.0;
    /// The fixed rotation base_link <- rotation_frame (IMU and twist data), cached.
    std::string rotation_frame;
    Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
    bool has_rotation = false;
    /// A message arrived and everything it needed from TF is cached.
    bool frames_ready = false;
  };

  void imuCallback(const sensor_msgs::Imu::ConstPtr& msg, size_t idx);
  void poseCallback(const geometry_msgs::PoseWithCovarianceStamped::ConstPtr& msg, size_t idx);
  void odomCallback(const nav_msgs::Odometry::ConstPtr& msg, size_t idx);
  void twistCallback(const geometry_msgs::TwistWithCovarianceStamped::ConstPtr& msg, size_t idx);
  template <class M>
  ros::Subscriber subscribeSensor(const SensorConfig& cfg,
                                  const boost::function<void(const boost::shared_ptr<M const>&)>& cb);
  void countReceived(size_t idx);

  void handlePose(const geometry_msgs::PoseWithCovariance& msg, const std::string& frame,
                  const ros::Time& stamp, size_t idx);
  /// relative / differential / absolute handling of a pose already in the world frame.
  void fusePose(PoseWithCov pose, double t, const SensorConfig& cfg, size_t idx);
  void enqueue(const Measurement& m, size_t idx);
  void markInvalid(size_t idx, const std::string& why);
  double stampToTime(const ros::Time& stamp) const;
  /// Rotation base_link <- frame for sensor idx (fixed mount), cached per sensor.
  bool sensorRotation(size_t idx, const std::string& frame, Eigen::Matrix3d* out);
  bool lookup(const std::string& target, const std::string& source, const ros::Time& stamp,
              Eigen::Isometry3d* out);
  void ensureTfListener(const std::string& why);
  /// Drop the TF listener once every sensor's frames are cached and nothing needs time-varying
  /// transforms: it would otherwise deserialise all /tf traffic (sim, map correction, ourselves).
  void maybeReleaseTf();
  bool sensorStale(const SensorState& s, const ros::Time& now) const;
  bool enableService(std_srvs::Empty::Request& req, std_srvs::Empty::Response& res);

  void periodicUpdate(const ros::TimerEvent& ev);
  void drainSensorQueue();
  void publish();
  void diagnoseSensor(size_t idx, diagnostic_updater::DiagnosticStatusWrapper& stat);
  void diagnoseFilter(diagnostic_updater::DiagnosticStatusWrapper& stat);

  ros::NodeHandle nh_, pnh_;
  FilterParams params_;
  Ekf ekf_;
  std::ostringstream debug_log_;
  std::ofstream debug_file_;
  std::vector<SensorState> sensors_;
  ros::CallbackQueue sensor_queue_;   // sensor (and TF) messages, drained once per cycle
  std::vector<Measurement> queue_;    // measurements since the last cycle, fused in time order
  std::vector<size_t> queue_sensor_;  // sensor index of each queued measurement
  std::vector<size_t> order_;         // scratch: queue_ indices sorted by time
  ros::Publisher odom_pub_, accel_pub_, config_pub_;
  ros::ServiceServer enable_srv_;
  ros::Timer timer_;
  std::unique_ptr<tf2_ros::Buffer> tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;
  tf2_ros::TransformBroadcaster tf_broadcaster_;
  std::unique_ptr<diagnostic_updater::Updater> diagnostics_;
  nav_msgs::Odometry odom_msg_;
  geometry_msgs::AccelWithCovarianceStamped accel_msg_;
  geometry_msgs::TransformStamped tf_msg_;
  ros::Time start_time_;
  ros::Time last_wall_check_;
  double last_published_stamp_ = -1.0;
  bool publishing_ = false;
  bool enabled_ = true;
  /// Some input (or map -> odom publishing) needs transforms that change over time.
  bool needs_dynamic_tf_ = false;
};

}  // namespace rbd_localization

#endif  // RBD_LOCALIZATION_EKF_NODE_H
