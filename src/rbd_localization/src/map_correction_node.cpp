// map_correction_node: LiDAR scan matching against a self-built 2D map -> map -> odom.
#include <ros/ros.h>

#include <string>

#include "rbd_localization/map_correction_ros.h"

int main(int argc, char** argv) {
  ros::init(argc, argv, "map_correction_node");
  ros::NodeHandle nh;
  ros::NodeHandle pnh("~");
  rbd_localization::MapCorrectionNode node(nh, pnh);
  std::string error;
  if (!node.init(&error)) {
    ROS_FATAL("map_correction_node: bad configuration: %s", error.c_str());
    return 1;
  }
  ros::spin();
  return 0;
}
