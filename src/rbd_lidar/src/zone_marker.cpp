#include "rbd_lidar/zone_marker.h"

#include <geometry_msgs/Point.h>

#include <algorithm>

namespace rbd_lidar {

visualization_msgs::Marker zoneMarker(const std_msgs::Header& header, const ZoneParams& z,
                                      const SensorPose& pose) {
  visualization_msgs::Marker m;
  m.header = header;
  m.ns = "rbd_lidar_zone";
  m.id = 0;
  m.type = visualization_msgs::Marker::LINE_LIST;
  m.action = visualization_msgs::Marker::ADD;
  m.pose.orientation.w = 1.0;
  m.scale.x = 0.01;
  m.color.r = 1.0;
  m.color.a = 0.9;
  const double xs[2] = {z.front, -z.back}, ys[2] = {z.left, -z.right};
  const double hs[2] = {z.floor_clearance, std::min(z.max_height, pose.height + 0.3)};
  // Box corners in the level frame, drawn in the cloud frame.
  auto corner = [&](int i, int j, int k) {
    const Eigen::Vector3d level(xs[i], ys[j], hs[k] - pose.height);
    const Eigen::Vector3d s = pose.level_from_sensor.transpose() * level;
    geometry_msgs::Point p;
    p.x = s.x();
    p.y = s.y();
    p.z = s.z();
    return p;
  };
  for (int k = 0; k < 2; ++k) {  // top and bottom rectangles
    const int order[5][2] = {{0, 0}, {0, 1}, {1, 1}, {1, 0}, {0, 0}};
    for (int e = 0; e < 4; ++e) {
      m.points.push_back(corner(order[e][0], order[e][1], k));
      m.points.push_back(corner(order[e + 1][0], order[e + 1][1], k));
    }
  }
  for (int i = 0; i < 2; ++i) {
    for (int j = 0; j < 2; ++j) {  // vertical edges
      m.points.push_back(corner(i, j, 0));
      m.points.push_back(corner(i, j, 1));
    }
  }
  return m;
}

}  // namespace rbd_lidar
