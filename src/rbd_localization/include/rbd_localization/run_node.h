// The body of a localization node's main(): init, construct the node on nh and ~, check its
// configuration, spin. Only for the .cpp files that define the node classes (node_main.h).
#ifndef RBD_LOCALIZATION_RUN_NODE_H
#define RBD_LOCALIZATION_RUN_NODE_H

#include <ros/ros.h>

#include <string>

namespace rbd_localization {

/// Runs Node (constructed as Node(nh, pnh), configured by node.init(&error)) until shutdown.
/// Returns the process exit status: 1 when init() rejects the configuration.
template <class Node>
int runNode(int argc, char** argv, const char* name) {
  ros::init(argc, argv, name);
  ros::NodeHandle nh;
  ros::NodeHandle pnh("~");
  Node node(nh, pnh);
  std::string error;
  if (!node.init(&error)) {
    ROS_FATAL("%s: bad configuration: %s", name, error.c_str());
    return 1;
  }
  ros::spin();
  return 0;
}

}  // namespace rbd_localization

#endif  // RBD_LOCALIZATION_RUN_NODE_H
