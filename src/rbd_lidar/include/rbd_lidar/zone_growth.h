// Velocity-aware growth of the stop zone, and the hold that keeps a stopped motion's growth
// until its collision is released (ROS-free).
#ifndef RBD_LIDAR_ZONE_GROWTH_H
#define RBD_LIDAR_ZONE_GROWTH_H

#include <array>

#include "rbd_lidar/zone_params.h"

namespace rbd_lidar {

struct MotionParams {
  double reaction_time = 0.7;    // each side grows by the commanded speed towards it times this [s]
  double rotation_lever = 0.30;  // turning at w grows every side by |w| * lever * reaction_time [m]
  double max_growth = 0.50;      // growth cap per side [m]
};

// The stop zone grown for the commanded body velocity (vx, vy [m/s], wz [rad/s]).
ZoneParams grownZone(const ZoneParams& base, double vx, double vy, double wz, const MotionParams& motion);

// Keeps a stopped motion's growth until its collision is released. A collision latched while the
// robot moved was found in the zone grown for that motion; once the robot stands still the zone
// shrinks back to its rest size, and an obstacle between the two sizes would release the latch
// at once: the robot resumes, grows the zone, stops again (stop-and-go towards a bag on the path,
// never standing long enough to be judged blocked). While the latch holds and no motion is
// commanded, every side keeps at least the growth of the last motion commanded during the latched
// period (on top of the rest zone as it is now: a reconfigured zone still takes effect); a new
// motion (stepping back, a detour) replaces the held growth with its own.
class ZoneHold {
 public:
  // The zone to check this scan: `grown` (the rest zone `base` grown for the current command), or
  // while `latched` and not `moving`, `base` plus per side the larger of the current and the held
  // growth. `enabled` false: always `grown`.
  ZoneParams apply(const ZoneParams& base, const ZoneParams& grown, bool moving, bool latched,
                   bool enabled = true);
  // Whether the last apply() returned a zone larger than `grown` on some side.
  bool holding() const { return holding_; }

 private:
  std::array<double, 4> growth_{{0.0, 0.0, 0.0, 0.0}};  // front, back, left, right [m]
  bool holding_ = false;
};

}  // namespace rbd_lidar

#endif  // RBD_LIDAR_ZONE_GROWTH_H
