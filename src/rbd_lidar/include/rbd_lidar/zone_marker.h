// The stop zone as an RViz marker: the box of the zone and its height band, drawn in the cloud frame.
#ifndef RBD_LIDAR_ZONE_MARKER_H
#define RBD_LIDAR_ZONE_MARKER_H

#include <std_msgs/Header.h>
#include <visualization_msgs/Marker.h>

#include "rbd_lidar/sensor_pose.h"
#include "rbd_lidar/zone_params.h"

namespace rbd_lidar {

// LINE_LIST of the box's 12 edges (level-frame box: the zone's sides, from floor_clearance to
// min(max_height, sensor height + 0.3 m) above the floor), in the sensor frame of `header`.
visualization_msgs::Marker zoneMarker(const std_msgs::Header& header, const ZoneParams& zone,
                                      const SensorPose& pose);

}  // namespace rbd_lidar

#endif  // RBD_LIDAR_ZONE_MARKER_H
