// Reference for the fan-out benchmark: how late the echo peer's 100 Hz tick reaches a plain
// roscpp subscriber on this machine, with no bridge in the path (stamp -> callback).
// Usage: tick_sub SECONDS   (prints one JSON line: n, p50_ms, p99_ms)
#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <std_msgs/Header.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <vector>

namespace {
std::vector<double> g_latency_ms;
ros::WallTime g_start_after;

void onTick(const std_msgs::Header::ConstPtr& tick) {
  const ros::WallTime now = ros::WallTime::now();
  if (now < g_start_after) {
    return;
  }
  const double stamp = tick->stamp.sec + tick->stamp.nsec * 1e-9;
  g_latency_ms.push_back((now.toSec() - stamp) * 1e3);
}

double percentile(std::vector<double> values, double q) {
  if (values.empty()) {
    return -1.0;
  }
  std::sort(values.begin(), values.end());
  return values[static_cast<size_t>(q * static_cast<double>(values.size() - 1))];
}
}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "tick_sub", ros::init_options::AnonymousName | ros::init_options::NoSigintHandler);
  const double seconds = argc > 1 ? std::atof(argv[1]) : 6.0;
  ros::NodeHandle nh;
  ros::Subscriber sub = nh.subscribe("/echo/tick", 10, onTick, ros::TransportHints().tcpNoDelay());
  g_start_after = ros::WallTime::now() + ros::WallDuration(1.0);
  const ros::WallTime end = g_start_after + ros::WallDuration(seconds);
  while (ros::ok() && ros::WallTime::now() < end) {
    ros::getGlobalCallbackQueue()->callAvailable(ros::WallDuration(0.1));
  }
  std::printf("{\"n\": %zu, \"p50_ms\": %.4f, \"p99_ms\": %.4f}\n", g_latency_ms.size(),
              percentile(g_latency_ms, 0.5), percentile(g_latency_ms, 0.99));
  return 0;
}
