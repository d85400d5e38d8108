// The critical zone as an RViz marker: the box's twelve edges (a LINE_LIST) in the cloud's frame.
#ifndef RBD_LIDAR_ZONE_MARKER_H
#define RBD_LIDAR_ZONE_MARKER_H

#include <std_msgs/Header.h>
#include <visualization_msgs/Marker.h>

#include "rbd_lidar/critical_zone.h"

namespace rbd_lidar {

// The zone box (front/back/left/right, from the floor clearance up to min(max_height, sensor
// height + 0.3 m)), set in the level frame of `pose` and drawn in the sensor frame of `header`.
visualization_msgs::Marker zoneMarker(const std_msgs::Header& header, const ZoneParams& z,
                                      const SensorPose& pose);

}  // namespace rbd_lidar

#endif  // RBD_LIDAR_ZONE_MARKER_H
