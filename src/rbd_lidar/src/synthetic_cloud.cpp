#include "rbd_lidar/synthetic_cloud.h"

#include <cmath>
#include <cstring>
#include <limits>

namespace rbd_lidar {

sensor_msgs::PointCloud2 makeOusterCloud(const BeamModel& model, const std::vector<uint32_t>& range_mm,
                                         bool nan_for_zero) {
  sensor_msgs::PointCloud2 msg;
  msg.header.frame_id = "os_sensor";
  msg.height = static_cast<uint32_t>(model.rows());
  msg.width = static_cast<uint32_t>(model.columns);
  struct F {
    const char* name;
    uint32_t offset;
    uint8_t type;
  };
  const F fields[] = {{"x", 0, 7},          {"y", 4, 7},        {"z", 8, 7},
                      {"intensity", 16, 7}, {"t", 20, 6},       {"reflectivity", 24, 4},
                      {"ring", 26, 4},      {"ambient", 28, 4}, {"range", 32, 6}};
  for (const F& f : fields) {
    sensor_msgs::PointField pf;
    pf.name = f.name;
    pf.offset = f.offset;
    pf.datatype = f.type;
    pf.count = 1;
    msg.fields.push_back(pf);
  }
  msg.is_bigendian = false;
  msg.point_step = 48;
  msg.row_step = 48 * msg.width;
  msg.is_dense = false;
  msg.data.assign(static_cast<size_t>(msg.row_step) * msg.height, 0);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (size_t u = 0; u < model.rows(); ++u) {
    for (size_t c = 0; c < static_cast<size_t>(model.columns); ++c) {
      const size_t i = u * model.columns + c;
      uint8_t* p = &msg.data[i * 48];
      const uint32_t r = range_mm[i];
      float xyz[4] = {0, 0, 0, 1};
      if (r > 0) {
        Eigen::Vector3d d, o;
        model.ray(u, c, &d, &o);
        const Eigen::Vector3d q = r * 1e-3 * d + o;
        xyz[0] = static_cast<float>(q.x());
        xyz[1] = static_cast<float>(q.y());
        xyz[2] = static_cast<float>(q.z());
      } else if (nan_for_zero) {
        xyz[0] = xyz[1] = xyz[2] = nan;
      }
      std::memcpy(p, xyz, 16);
      const uint16_t ring = static_cast<uint16_t>(u);
      std::memcpy(p + 26, &ring, 2);
      std::memcpy(p + 32, &r, 4);
    }
  }
  return msg;
}

std::vector<uint32_t> castScene(const BeamModel& model, const SensorPose& pose, double room, bool person,
                                double px, double py, double radius) {
  std::vector<uint32_t> img(model.rows() * model.columns, 0);
  for (size_t u = 0; u < model.rows(); ++u) {
    for (size_t c = 0; c < static_cast<size_t>(model.columns); ++c) {
      Eigen::Vector3d d, o;
      model.ray(u, c, &d, &o);
      d = pose.level_from_sensor * d;
      o = pose.level_from_sensor * o;
      o.z() += pose.height;
      double best = std::numeric_limits<double>::infinity();
      if (d.z() < -1e-9) best = std::min(best, -o.z() / d.z());  // floor
      for (int axis = 0; axis < 2; ++axis) {                     // walls
        if (std::fabs(d[axis]) > 1e-9) {
          const double t = ((d[axis] > 0 ? room : -room) - o[axis]) / d[axis];
          if (t > 0) best = std::min(best, t);
        }
      }
      if (person) {  // vertical cylinder, 1.8 m tall
        const double ax = d.x(), ay = d.y(), bx = o.x() - px, by = o.y() - py;
        const double a = ax * ax + ay * ay, b = 2 * (ax * bx + ay * by),
                     cc = bx * bx + by * by - radius * radius;
        const double disc = b * b - 4 * a * cc;
        if (a > 1e-12 && disc >= 0) {
          const double t = (-b - std::sqrt(disc)) / (2 * a);
          if (t > 0 && o.z() + t * d.z() < 1.8 && o.z() + t * d.z() > 0) best = std::min(best, t);
        }
      }
      if (std::isfinite(best) && best < 60.0)
        img[u * model.columns + c] = static_cast<uint32_t>(std::lround(best * 1e3));
    }
  }
  return img;
}

}  // namespace rbd_lidar
