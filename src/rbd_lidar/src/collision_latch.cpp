#include "rbd_lidar/collision_latch.h"

namespace rbd_lidar {

bool CollisionLatch::update(bool occupied) {
  if (occupied) {
    collision_ = true;
    clear_run_ = 0;
  } else if (collision_) {
    if (++clear_run_ >= clear_scans_) {
      collision_ = false;
      clear_run_ = 0;
    }
  }
  return collision_;
}

}  // namespace rbd_lidar
