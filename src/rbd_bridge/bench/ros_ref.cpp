// References for the rbd_bridge benchmark: what ROS alone takes on this machine, measured by
// a plain roscpp node against the same echo peer, with no bridge in the path.
//   ros_ref tick SECONDS  the peer's 100 Hz tick: stamp -> callback latency
//   ros_ref echo N        String round trips through the peer (/echo/in -> /echo/out)
// Prints one JSON line: n, p50_ms, p99_ms.
#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <std_msgs/Header.h>
#include <std_msgs/String.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

namespace {
std::vector<double> g_latency_ms;
ros::WallTime g_start_after;
std::string g_awaited;
bool g_echoed = false;

void onTick(const std_msgs::Header::ConstPtr& tick) {
  const ros::WallTime now = ros::WallTime::now();
  if (now < g_start_after) {
    return;
  }
  const double stamp = tick->stamp.sec + tick->stamp.nsec * 1e-9;
  g_latency_ms.push_back((now.toSec() - stamp) * 1e3);
}

void onEcho(const std_msgs::String::ConstPtr& msg) {
  if (msg->data == g_awaited) {
    g_echoed = true;
  }
}

double percentile(std::vector<double> values, double q) {
  if (values.empty()) {
    return -1.0;
  }
  std::sort(values.begin(), values.end());
  return values[static_cast<size_t>(q * static_cast<double>(values.size() - 1))];
}

void runTick(ros::NodeHandle& nh, double seconds) {
  ros::Subscriber sub = nh.subscribe("/echo/tick", 10, onTick, ros::TransportHints().tcpNoDelay());
  g_start_after = ros::WallTime::now() + ros::WallDuration(1.0);
  const ros::WallTime end = g_start_after + ros::WallDuration(seconds);
  while (ros::ok() && ros::WallTime::now() < end) {
    ros::getGlobalCallbackQueue()->callAvailable(ros::WallDuration(0.1));
  }
}

// One round trip: publish, then serve callbacks until the echo of this text is back.
bool roundTrip(ros::Publisher& pub, const std::string& text, double timeout_s) {
  std_msgs::String msg;
  msg.data = text;
  g_awaited = text;
  g_echoed = false;
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(timeout_s);
  pub.publish(msg);
  while (!g_echoed && ros::ok() && ros::WallTime::now() < deadline) {
    ros::getGlobalCallbackQueue()->callAvailable(ros::WallDuration(0.01));
  }
  return g_echoed;
}

void runEcho(ros::NodeHandle& nh, int n) {
  ros::Publisher pub = nh.advertise<std_msgs::String>("/echo/in", 1000);
  ros::Subscriber sub = nh.subscribe("/echo/out", 1000, onEcho, ros::TransportHints().tcpNoDelay());
  // wait until both connections exist: a round trip comes back
  for (int i = 0; i < 200 && !roundTrip(pub, "ref-prime", 0.1); ++i) {
  }
  for (int i = 0; i < n + 1000 && ros::ok(); ++i) {
    const ros::WallTime t0 = ros::WallTime::now();
    if (!roundTrip(pub, "ref" + std::to_string(i), 2.0)) {
      continue;
    }
    if (i >= 1000) {
      g_latency_ms.push_back((ros::WallTime::now() - t0).toSec() * 1e3);
    }
  }
}
}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "ros_ref", ros::init_options::AnonymousName | ros::init_options::NoSigintHandler);
  const std::string mode = argc > 1 ? argv[1] : "tick";
  ros::NodeHandle nh;
  if (mode == "echo") {
    runEcho(nh, argc > 2 ? std::atoi(argv[2]) : 3000);
  } else {
    runTick(nh, argc > 2 ? std::atof(argv[2]) : 6.0);
  }
  std::printf("{\"n\": %zu, \"p50_ms\": %.4f, \"p99_ms\": %.4f}\n", g_latency_ms.size(),
              percentile(g_latency_ms, 0.5), percentile(g_latency_ms, 0.99));
  return 0;
}
