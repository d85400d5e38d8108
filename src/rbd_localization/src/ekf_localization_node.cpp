// ekf_localization_node: robot_localization-compatible EKF (parameters in params/ekf.yaml).
#include <ros/ros.h>

#include <string>

#include "rbd_localization/ekf_node.h"

int main(int argc, char** argv) {
  ros::init(argc, argv, "ekf_localization_node");
  ros::NodeHandle nh;
  ros::NodeHandle pnh("~");
  rbd_localization::EkfNode node(nh, pnh);
  std::string error;
  if (!node.init(&error)) {
    ROS_FATAL("ekf_localization_node: bad configuration: %s", error.c_str());
    return 1;
  }
  ros::spin();
  return 0;
}
