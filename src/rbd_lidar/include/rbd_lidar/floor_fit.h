// The floor under the lidar measured from the returns themselves (ROS-free): the sensor height,
// or the whole sensor pose from a plane fit, with a configured CriticalZone's beams and attitude
// as the prior.
#ifndef RBD_LIDAR_FLOOR_FIT_H
#define RBD_LIDAR_FLOOR_FIT_H

#include <cstddef>
#include <cstdint>

#include "rbd_lidar/critical_zone.h"
#include "rbd_lidar/sensor_pose.h"

namespace rbd_lidar {

// Sensor height above the floor measured from the returns themselves: with the attitude
// configured in `zone`, downward rays that end within `max_distance` horizontally give "sensor
// height if this return is on the floor"; the floor is the lowest surface, so a high quantile of
// these (`quantile`, e.g. 0.8) is the estimate. Rows are sampled every `column_step` columns.
// Returns false if `zone` is not configured or fewer than `min_samples` such returns exist. The
// range of pixel i is the uint32 at range_bytes + i * stride (as CriticalZone::evaluateStrided).
bool estimateHeight(const CriticalZone& zone, const uint8_t* range_bytes, size_t stride, double max_distance,
                    double quantile, size_t column_step, size_t min_samples, double* height);

// Floor plane measured from the returns themselves (the attitude configured in `zone` is only a
// prior): downward returns within `max_distance` horizontally whose height lies within a band
// around the prior floor that widens with distance by `max_tilt` (tolerating that much attitude
// error) are fitted with a least-squares plane; more fits with shrinking bands reject obstacles.
// On success *pose is the corrected sensor pose (floor plane = z 0) and true is returned; false
// if fewer than `min_samples` returns support the plane or the correction exceeds `max_tilt`.
bool estimateFloor(const CriticalZone& zone, const uint8_t* range_bytes, size_t stride, double max_distance,
                   double max_tilt, size_t column_step, size_t min_samples, SensorPose* pose);

}  // namespace rbd_lidar

#endif  // RBD_LIDAR_FLOOR_FIT_H
