// Hysteresis of the collision state (ROS-free).
#ifndef RBD_LIDAR_COLLISION_LATCH_H
#define RBD_LIDAR_COLLISION_LATCH_H

namespace rbd_lidar {

// Collision as soon as a scan is occupied; clear only after `clear_scans` consecutive clear
// scans. Starts in collision (nothing has been seen yet).
class CollisionLatch {
 public:
  explicit CollisionLatch(unsigned clear_scans = 3) : clear_scans_(clear_scans) {}
  void setClearScans(unsigned n) { clear_scans_ = n; }
  // One valid scan; returns the collision state.
  bool update(bool occupied);
  // Invalid or stale input: collision, and the clear count starts again.
  void fail() {
    collision_ = true;
    clear_run_ = 0;
  }
  bool collision() const { return collision_; }

 private:
  unsigned clear_scans_;
  unsigned clear_run_ = 0;
  bool collision_ = true;
};

}  // namespace rbd_lidar

#endif  // RBD_LIDAR_COLLISION_LATCH_H
