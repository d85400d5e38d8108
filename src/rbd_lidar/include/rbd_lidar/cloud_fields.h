// The byte-level helpers shared by the scan pipeline's files: finding a field of a PointCloud2,
// reading an unaligned float, and (re)initialising the unorganised x y z intensity output clouds.
#ifndef RBD_LIDAR_CLOUD_FIELDS_H
#define RBD_LIDAR_CLOUD_FIELDS_H

#include <sensor_msgs/PointCloud2.h>

#include <cmath>
#include <cstdint>
#include <cstring>

namespace rbd_lidar {

constexpr double kCloudTwoPi = 2.0 * M_PI;

// The field called `name`; nullptr if the cloud has none.
const sensor_msgs::PointField* findField(const sensor_msgs::PointCloud2& cloud, const char* name);

// A float at any byte address (clouds may place fields unaligned; every read is a memcpy).
inline float readFloat(const uint8_t* p) {
  float v;
  std::memcpy(&v, p, sizeof(v));
  return v;
}

// An unorganised float cloud with fields x y z intensity at offsets 0 4 8 `intensity_offset`.
// The field list is rebuilt only when it differs (the output messages are reused every scan).
void initCloud(const std_msgs::Header& header, uint32_t point_step, uint32_t intensity_offset,
               sensor_msgs::PointCloud2* msg);

}  // namespace rbd_lidar

#endif  // RBD_LIDAR_CLOUD_FIELDS_H
