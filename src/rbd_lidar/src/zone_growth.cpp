#include "rbd_lidar/zone_growth.h"

#include <algorithm>
#include <cmath>

namespace rbd_lidar {

ZoneParams grownZone(const ZoneParams& base, double vx, double vy, double wz, const MotionParams& motion) {
  ZoneParams z = base;
  if (!std::isfinite(vx) || !std::isfinite(vy) || !std::isfinite(wz)) {
    vx = vy = 0.0;
    wz = 0.0;
  }
  const double t = std::max(0.0, motion.reaction_time);
  const double cap = std::max(0.0, motion.max_growth);
  const double turn = std::fabs(wz) * std::max(0.0, motion.rotation_lever) * t;
  z.front += std::min(cap, std::max(0.0, vx) * t + turn);
  z.back += std::min(cap, std::max(0.0, -vx) * t + turn);
  z.left += std::min(cap, std::max(0.0, vy) * t + turn);
  z.right += std::min(cap, std::max(0.0, -vy) * t + turn);
  return z;
}

ZoneParams ZoneHold::apply(const ZoneParams& base, const ZoneParams& grown, bool moving, bool latched,
                           bool enabled) {
  holding_ = false;
  const double b[4] = {base.front, base.back, base.left, base.right};
  const double g[4] = {grown.front, grown.back, grown.left, grown.right};
  if (!enabled || !latched || moving) {
    for (int i = 0; i < 4; ++i) growth_[i] = std::max(0.0, g[i] - b[i]);
    return grown;
  }
  ZoneParams z = grown;
  double* sides[4] = {&z.front, &z.back, &z.left, &z.right};
  for (int i = 0; i < 4; ++i) {
    if (b[i] + growth_[i] > g[i]) {
      *sides[i] = b[i] + growth_[i];
      holding_ = true;
    }
  }
  return z;
}

}  // namespace rbd_lidar
