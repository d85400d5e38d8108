// PointCloud2 field lookup and the output clouds' layout (see cloud_fields.h).
#include "rbd_lidar/cloud_fields.h"

namespace rbd_lidar {

namespace {

void addField(sensor_msgs::PointCloud2* msg, const char* name, uint32_t offset) {
  sensor_msgs::PointField f;
  f.name = name;
  f.offset = offset;
  f.datatype = sensor_msgs::PointField::FLOAT32;
  f.count = 1;
  msg->fields.push_back(f);
}

}  // namespace

const sensor_msgs::PointField* findField(const sensor_msgs::PointCloud2& cloud, const char* name) {
  for (const auto& f : cloud.fields) {
    if (f.name == name) return &f;
  }
  return nullptr;
}

void initCloud(const std_msgs::Header& header, uint32_t point_step, uint32_t intensity_offset,
               sensor_msgs::PointCloud2* msg) {
  msg->header = header;
  msg->height = 1;
  msg->width = 0;
  if (msg->fields.size() != 4 || msg->fields[3].offset != intensity_offset || msg->fields[0].name != "x" ||
      msg->fields[3].name != "intensity") {
    msg->fields.clear();
    addField(msg, "x", 0);
    addField(msg, "y", 4);
    addField(msg, "z", 8);
    addField(msg, "intensity", intensity_offset);
  }
  msg->is_bigendian = false;
  msg->point_step = point_step;
  msg->row_step = 0;
  msg->is_dense = true;
  msg->data.clear();
}

}  // namespace rbd_lidar
