// Size of the critical zone (ROS-free): a box around the LiDAR in the level frame, a stop zone
// with a slowdown band around it, the blind zone and the height band of the points that count.
#ifndef RBD_LIDAR_ZONE_PARAMS_H
#define RBD_LIDAR_ZONE_PARAMS_H

#include <cstdint>

namespace rbd_lidar {

// Side indices, the same order as rbd_msgs/CollisionState.
enum Side : uint8_t { FRONT = 0, LEFT = 1, BACK = 2, RIGHT = 3 };

// Zone sizes and filters. Distances are perpendicular distances from the LiDAR [m].
struct ZoneParams {
  double front = 0.70;
  double back = 0.55;
  double left = 0.35;
  double right = 0.35;
  double slowdown_front = 0.50;  // width of the slowdown band outside the stop zone, per side [m]
  double slowdown_back = 0.30;
  double slowdown_left = 0.20;
  double slowdown_right = 0.20;
  double blind_zone = 0.30;       // ranges below this are ignored [m]
  double floor_clearance = 0.10;  // points lower than this above the floor are ignored [m]
  double max_height = 2.0;        // points higher than this above the floor are ignored [m]
  unsigned point_threshold = 5;   // this many critical points make a collision
};

// A zone whose distances are measured from a point fixed to the body (the zone origin) instead of
// from the LiDAR, expressed around the LiDAR: (dx, dy) [m] is the LiDAR's position relative to the
// zone origin in the level frame (x = heading). Front/left shrink and back/right grow by the
// offset, never below 0. *clamped (optional) tells whether a side had to be clamped (the LiDAR
// sits outside the zone). Non-finite offsets leave the zone unchanged.
ZoneParams zoneAroundOrigin(const ZoneParams& zone, double dx, double dy, bool* clamped = nullptr);

}  // namespace rbd_lidar

#endif  // RBD_LIDAR_ZONE_PARAMS_H
