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
  double max_growth = 0.50;      // cap of the reaction-time growth per side [m]
  double max_age = 0.50;         // oldest cloud judged [s] (~max_cloud_age); bounds the age term
};

// The stop zone grown for the commanded body velocity (vx, vy [m/s], wz [rad/s]) and the age of
// the cloud judged (`age` [s]: now - the cloud's capture stamp). Each side grows by
//   min(max_growth, s * reaction_time) + s * age,   s = speed towards that side + |wz| * lever
// The robot has already moved s * age since the cloud was captured, unseen: that distance is real
// and is added on top of the capped reaction-time growth (the cap rises with the age; the age
// term itself is bounded by max_age, the oldest cloud judged). An age that is NaN or above max_age
// counts as max_age (unknown means worst); a negative age (a stamp ahead of this clock, an
// unsynchronised sensor clock) counts as 0.
ZoneParams grownZone(const ZoneParams& base, double vx, double vy, double wz, const MotionParams& motion,
                     double age);

// What the node does with a received cloud, from its age and stamp.
enum class CloudAge {
  JUDGE,         // age <= max_age: judged, with its age in the zone growth
  TOO_OLD,       // older than max_age (or no usable stamp): not judged; the stale fail-safe stops
  OUT_OF_ORDER,  // captured before a cloud already judged: says nothing newer; not judged
};

// `age` = now - stamp [s]; `stamp` and `last_judged` are capture stamps [s] (0 = none: a cloud
// without a stamp has an unknown age and is TOO_OLD; last_judged 0 = nothing judged yet). A
// last_judged later than now (stamp + age: the clock went back, a replay restarted) is ignored.
// max_age (the node's ~max_cloud_age, 0.5 s) is deliberately separate from, and longer than, the
// stale limit (stale_periods / scan_rate, 0.3 s): the stale limit is the longest time without a
// judged cloud; max_age is how old a cloud may be when it is judged (its age is then in the zone).
CloudAge classifyCloudAge(double age, double stamp, double last_judged, double max_age);

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
