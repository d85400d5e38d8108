// Beam geometry of an organised lidar range image (ROS-free, Eigen only): where the ray of each
// pixel starts and points in the sensor frame, read from Ouster metadata or measured from points.
#ifndef RBD_LIDAR_BEAM_MODEL_H
#define RBD_LIDAR_BEAM_MODEL_H

#include <Eigen/Core>
#include <cmath>
#include <string>
#include <vector>

namespace rbd_lidar {

// Angle wrapped to [-pi, pi) [rad].
inline double wrapAngle(double a) {
  a = std::fmod(a + M_PI, 2.0 * M_PI);
  if (a < 0) a += 2.0 * M_PI;
  return a - M_PI;
}

// Geometry of the beams of an organised (rows x columns) range image, in the sensor frame
// (os_sensor). For pixel (u, c) the beam azimuth is azimuth0[u] + direction * 2*pi*c/columns and
// its elevation altitude[u]; the point is p = r*d + n*((cos a, sin a, 0) - d) + (0, 0, lidar_z)
// with d the unit ray and n the lidar-origin-to-beam-origin distance (ouster-sdk xyzlut model;
// using the beam instead of the encoder azimuth in the n-term changes p by < 1.2 mm).
struct BeamModel {
  std::vector<double> altitude;  // per row [rad], positive up, row 0 = top beam
  std::vector<double> azimuth0;  // per row: azimuth of column 0 in the sensor frame [rad]
  int columns = 0;
  int direction = -1;             // +1: azimuth grows with the column, -1: it falls (Ouster)
  double beam_origin = 0.015806;  // lidar_origin_to_beam_origin [m]
  double lidar_z = 0.03618;       // os_sensor -> os_lidar height [m]

  // From Ouster metadata: altitude/azimuth in degrees, pixel shifts as in the metadata for
  // shift_columns columns (scaled to `columns`), destaggered = the cloud is destaggered.
  static BeamModel fromOuster(const std::vector<double>& altitude_deg, const std::vector<double>& azimuth_deg,
                              const std::vector<int>& pixel_shift, int shift_columns, int columns,
                              bool destaggered, double beam_origin_mm, double lidar_z_mm);

  size_t rows() const { return altitude.size(); }
  bool valid(std::string* why) const;
  // Unit ray d and offset o in the sensor frame: p = r * d + o.
  void ray(size_t row, size_t col, Eigen::Vector3d* d, Eigen::Vector3d* o) const;
  // Replace the angles of row `row` by the ones measured from one point (sensor-frame xyz [m]
  // and range [m]) at column `col`. Returns false if the point is unusable.
  static bool anglesFromPoint(const Eigen::Vector3d& p, double range, double lidar_z, double beam_origin,
                              double* altitude, double* azimuth);

  bool operator==(const BeamModel& o) const {
    return columns == o.columns && direction == o.direction && altitude == o.altitude &&
           azimuth0 == o.azimuth0 && beam_origin == o.beam_origin && lidar_z == o.lidar_z;
  }
  bool operator!=(const BeamModel& o) const { return !(*this == o); }
};

// The trigonometry of a BeamModel split into per-row and per-column tables, so that the
// direction of pixel (u, c) costs four multiplications instead of two cos/sin pairs.
class BeamTrig {
 public:
  void build(const BeamModel& beams);
  // cos/sin of the azimuth of pixel (u, c).
  void azimuth(size_t u, size_t c, double* ca, double* sa) const {
    *ca = cos_az0[u] * cos_col[c] - sin_az0[u] * sin_col[c];
    *sa = sin_az0[u] * cos_col[c] + cos_az0[u] * sin_col[c];
  }
  // Sensor-frame point of pixel (u, c) at range r [m] (the BeamModel formula).
  Eigen::Vector3d point(const BeamModel& beams, size_t u, size_t c, double r) const;

  std::vector<double> cos_alt, sin_alt, cos_az0, sin_az0;  // per row
  std::vector<double> cos_col, sin_col;                    // per column: of direction * 2*pi*c/columns
};

}  // namespace rbd_lidar

#endif  // RBD_LIDAR_BEAM_MODEL_H
