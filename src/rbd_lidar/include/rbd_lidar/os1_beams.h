// Built-in OS1-32 beam table: the fallback when no beam parameters are given (the same values as
// config/os1_32_beams.yaml; an OS-1-32-U0 from the ouster-sdk test metadata).
#ifndef RBD_LIDAR_OS1_BEAMS_H
#define RBD_LIDAR_OS1_BEAMS_H

#include <vector>

namespace rbd_lidar {

inline std::vector<double> os1U0Altitudes() {
  return {20.5477, 19.2919, 18.0171,  16.7242,  15.4141,  14.088,  12.7466,  11.3909,
          10.022,  8.641,   7.249,    5.8474,   4.4377,   3.0216,  1.601,    0.1779,
          -1.2454, -2.6668, -4.0842,  -5.4956,  -6.8994,  -8.2939, -9.6778,  -11.0499,
          -12.409, -13.754, -15.0841, -16.3982, -17.6955, -18.975, -20.2356, -21.4764};
}

inline std::vector<double> os1U0Azimuths() { return std::vector<double>(32, -4.252); }

}  // namespace rbd_lidar

#endif  // RBD_LIDAR_OS1_BEAMS_H
