#include "rbd_lidar/zone_params.h"

#include <algorithm>
#include <cmath>

namespace rbd_lidar {

ZoneParams zoneAroundOrigin(const ZoneParams& zone, double dx, double dy, bool* clamped) {
  ZoneParams z = zone;
  if (clamped) *clamped = false;
  if (!std::isfinite(dx) || !std::isfinite(dy)) return z;
  const double sides[4] = {zone.front - dx, zone.back + dx, zone.left - dy, zone.right + dy};
  double* out[4] = {&z.front, &z.back, &z.left, &z.right};
  for (int i = 0; i < 4; ++i) {
    if (sides[i] < 0.0 && clamped) *clamped = true;
    *out[i] = std::max(0.0, sides[i]);
  }
  return z;
}

}  // namespace rbd_lidar
