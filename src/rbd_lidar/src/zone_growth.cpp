#include "rbd_lidar/zone_growth.h"

#include <algorithm>
#include <cmath>

namespace rbd_lidar {

ZoneParams grownZone(const ZoneParams& base, double vx, double vy, double wz, const MotionParams& motion,
                     double age) {
  ZoneParams z = base;
  if (!std::isfinite(vx) || !std::isfinite(vy) || !std::isfinite(wz)) {
    vx = vy = 0.0;
    wz = 0.0;
  }
  const double t = std::max(0.0, motion.reaction_time);
  const double cap = std::max(0.0, motion.max_growth);
  const double max_age = std::isfinite(motion.max_age) ? std::max(0.0, motion.max_age) : 0.0;
  // NaN and anything older than the oldest judged cloud: max_age; a stamp from the future: 0.
  const double a = std::isnan(age) ? max_age : std::min(max_age, std::max(0.0, age));
  const double turn = std::fabs(wz) * std::max(0.0, motion.rotation_lever);
  auto grow = [&](double speed) {
    const double s = std::max(0.0, speed) + turn;  // speed towards the side [m/s]
    return std::min(cap, s * t) + s * a;
  };
  z.front += grow(vx);
  z.back += grow(-vx);
  z.left += grow(vy);
  z.right += grow(-vy);
  return z;
}

CloudAge classifyCloudAge(double age, double stamp, double last_judged, double max_age) {
  if (!(stamp > 0.0) || !std::isfinite(age) || !(age <= max_age)) return CloudAge::TOO_OLD;
  // Overtaken by a younger cloud judged before it. A newest judged capture later than now
  // (stamp + age) means the clock went back (a replay restarted): nothing to compare with.
  if (last_judged > 0.0 && stamp < last_judged && last_judged <= stamp + age) return CloudAge::OUT_OF_ORDER;
  return CloudAge::JUDGE;
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
