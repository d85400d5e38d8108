// Validation of an incoming cloud's layout (the ouster-ros organised cloud with a UINT32 `range`
// field) and the names of the rejection kinds.
#include <algorithm>
#include <string>

#include "rbd_lidar/cloud_fields.h"
#include "rbd_lidar/scan_pipeline.h"

namespace rbd_lidar {

const char* errorName(CloudError e) {
  switch (e) {
    case CloudError::NONE:
      return "none";
    case CloudError::EMPTY:
      return "empty cloud";
    case CloudError::NO_RANGE_FIELD:
      return "missing range field";
    case CloudError::BAD_FIELD:
      return "bad field type";
    case CloudError::BAD_POINT_STEP:
      return "wrong point_step";
    case CloudError::BAD_HEIGHT:
      return "height differs from beams";
    case CloudError::BAD_SIZE:
      return "data size mismatch (truncated)";
    case CloudError::NO_VALID_RETURNS:
      return "too few valid returns";
    case CloudError::BAD_GEOMETRY:
      return "unusable beam geometry";
    default:
      return "unknown";
  }
}

CloudError ScanPipeline::validate(const sensor_msgs::PointCloud2& cloud, std::string* message) const {
  auto fail = [message](CloudError e, const std::string& what) {
    if (message) *message = std::string(errorName(e)) + ": " + what;
    return e;
  };
  if (cloud.width == 0 || cloud.height == 0 || cloud.data.empty()) {
    return fail(CloudError::EMPTY, "width " + std::to_string(cloud.width) + ", height " +
                                       std::to_string(cloud.height) + ", " +
                                       std::to_string(cloud.data.size()) + " bytes");
  }
  const sensor_msgs::PointField* range = findField(cloud, "range");
  if (!range)
    return fail(CloudError::NO_RANGE_FIELD, "the cloud has no `range` field (ouster-ros layout needed)");
  if (range->datatype != sensor_msgs::PointField::UINT32 || range->count != 1) {
    return fail(CloudError::BAD_FIELD, "`range` must be one UINT32 (datatype 6)");
  }
  uint32_t end = range->offset + 4;
  for (const char* name : {"x", "y", "z"}) {
    const sensor_msgs::PointField* f = findField(cloud, name);
    if (!f || f->datatype != sensor_msgs::PointField::FLOAT32 || f->count != 1) {
      return fail(CloudError::BAD_FIELD, std::string("field `") + name + "` missing or not FLOAT32");
    }
    end = std::max(end, f->offset + 4);
  }
  if (cloud.is_bigendian) return fail(CloudError::BAD_FIELD, "big-endian clouds are not supported");
  if (cloud.point_step < end) {
    return fail(CloudError::BAD_POINT_STEP, "point_step " + std::to_string(cloud.point_step) +
                                                " is smaller than the fields (" + std::to_string(end) +
                                                " bytes)");
  }
  if (static_cast<uint64_t>(cloud.row_step) < static_cast<uint64_t>(cloud.width) * cloud.point_step) {
    return fail(CloudError::BAD_POINT_STEP,
                "row_step " + std::to_string(cloud.row_step) + " < width * point_step");
  }
  if (cloud.height != beams()) {
    return fail(CloudError::BAD_HEIGHT, "height " + std::to_string(cloud.height) + " but " +
                                            std::to_string(beams()) + " beams (organised cloud needed)");
  }
  if (cloud.width > 65536) return fail(CloudError::BAD_SIZE, "width " + std::to_string(cloud.width));
  const uint64_t need = static_cast<uint64_t>(cloud.row_step) * cloud.height;
  if (cloud.data.size() != need) {
    return fail(CloudError::BAD_SIZE, std::to_string(cloud.data.size()) +
                                          " bytes of data, row_step * height = " + std::to_string(need));
  }
  return CloudError::NONE;
}

}  // namespace rbd_lidar
