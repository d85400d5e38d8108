// Synthetic ouster-ros clouds for tests and the benchmark (not used by the node).
#ifndef RBD_LIDAR_SYNTHETIC_CLOUD_H
#define RBD_LIDAR_SYNTHETIC_CLOUD_H

#include <sensor_msgs/PointCloud2.h>

#include <cstdint>
#include <vector>

#include "rbd_lidar/critical_zone.h"
#include "rbd_lidar/os1_beams.h"

namespace rbd_lidar {

// Ouster-ros "original" point layout (point_step 48, range UINT32 at 32), organised rows x columns,
// xyz from the model; zero range gives NaN xyz when nan_for_zero (ouster-ros >= 0.13) else 0.
sensor_msgs::PointCloud2 makeOusterCloud(const BeamModel& model, const std::vector<uint32_t>& range_mm,
                                         bool nan_for_zero = true);

// Ray-cast range image [mm]: floor at height 0, walls of a square room of half size `room`
// centred on the sensor, and optionally a vertical cylinder (person) of radius 0.2 m whose axis is
// at (px, py) in the level frame. `pose` places the sensor.
std::vector<uint32_t> castScene(const BeamModel& model, const SensorPose& pose, double room, bool person,
                                double px = 0.5, double py = 0.0, double radius = 0.2);

}  // namespace rbd_lidar

#endif  // RBD_LIDAR_SYNTHETIC_CLOUD_H
