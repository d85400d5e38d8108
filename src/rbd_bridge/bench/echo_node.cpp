// Fast C++ echo peer for the rbd_bridge benchmark (same topics/services as bench/echo_node).
// Built by bench/run with g++ and pkg-config roscpp; the Python echo_node is the fallback.
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <std_msgs/Header.h>
#include <std_msgs/String.h>
#include <std_srvs/SetBool.h>

namespace {
ros::Publisher g_out;
ros::Publisher g_cloud_out;

void onString(const std_msgs::String::ConstPtr& msg) { g_out.publish(msg); }

void onCloud(const sensor_msgs::PointCloud2::ConstPtr& msg) { g_cloud_out.publish(msg); }

bool onSetBool(std_srvs::SetBool::Request& req, std_srvs::SetBool::Response& res) {
  res.success = req.data;
  res.message = "echo";
  return true;
}
}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "echo_node");
  ros::NodeHandle nh;
  ros::NodeHandle pnh("~");
  g_out = nh.advertise<std_msgs::String>("/echo/out", 1000);
  g_cloud_out = nh.advertise<sensor_msgs::PointCloud2>("/echo/cloud_out", 10);
  ros::Subscriber sub = nh.subscribe("/echo/in", 1000, onString, ros::TransportHints().tcpNoDelay());
  ros::Subscriber cloud = nh.subscribe("/echo/cloud_in", 10, onCloud, ros::TransportHints().tcpNoDelay());
  ros::ServiceServer srv = nh.advertiseService("/echo/set_bool", onSetBool);
  double rate = 0.0;
  pnh.param("tick_rate", rate, 0.0);
  ros::Publisher tick = nh.advertise<std_msgs::Header>("/echo/tick", 10);
  ros::AsyncSpinner spinner(1);
  spinner.start();
  if (rate > 0.0) {
    ros::WallRate r(rate);
    uint32_t seq = 0;
    while (ros::ok()) {
      std_msgs::Header h;
      h.seq = ++seq;
      ros::WallTime now = ros::WallTime::now();
      h.stamp = ros::Time(now.sec, now.nsec);
      h.frame_id = "tick";
      tick.publish(h);
      r.sleep();
    }
  }
  ros::waitForShutdown();
  return 0;
}
