// ROS-free 2D occupancy grid (log-odds) with a Euclidean distance field for scan matching.
#ifndef RBD_LOCALIZATION_OCCUPANCY_MAP_H
#define RBD_LOCALIZATION_OCCUPANCY_MAP_H

#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

namespace rbd_localization {

using Points2d = std::vector<Eigen::Vector2d, Eigen::aligned_allocator<Eigen::Vector2d>>;

/// Square grid centred on the map origin; cells hold log-odds of being occupied.
class OccupancyMap {
 public:
  struct Params {
    double resolution = 0.05;        ///< cell size [m]
    double size = 30.0;              ///< side length [m]; the map spans [-size/2, size/2)
    double hit_log_odds = 0.85;      ///< added to the cell a beam ends in
    double miss_log_odds = -0.4;     ///< added to cells a beam passes through
    double occupied_log_odds = 1.5;  ///< a cell is structure above this
    double clamp_log_odds = 3.5;     ///< |log-odds| limit (so the map can still change)
    double max_distance = 1.0;       ///< distance field saturates here [m]
  };

  OccupancyMap();
  explicit OccupancyMap(const Params& params);

  const Params& params() const { return params_; }
  int width() const { return width_; }
  double originX() const { return origin_; }  ///< world x of cell (0, 0)'s corner
  double originY() const { return origin_; }

  /// Ray-casts one scan: misses along each beam (up to, not including, the end cell) and a hit
  /// at the end. Beams whose end lies outside the map only clear. weight scales both updates.
  void insertScan(const Eigen::Isometry2d& map_from_sensor, const Points2d& points_in_sensor, double weight);

  /// Cell index of a world point; false if outside.
  bool cellOf(const Eigen::Vector2d& p, int* cx, int* cy) const;
  float logOdds(int cx, int cy) const { return log_odds_[static_cast<size_t>(cy) * width_ + cx]; }
  bool occupied(int cx, int cy) const { return logOdds(cx, cy) > params_.occupied_log_odds; }
  int occupiedCount() const;

  /// Recomputes the distance field from the occupied cells (exact EDT, O(cells)).
  void updateDistanceField();
  /// Distance to the nearest structure [m] (bilinear) and its gradient; saturates at
  /// max_distance and outside the map. Returns false outside the map.
  bool distance(const Eigen::Vector2d& p, double* d, Eigen::Vector2d* gradient) const;

  /// ROS OccupancyGrid convention: -1 unknown, 0 free .. 100 occupied, row-major from (0,0).
  std::vector<int8_t> toOccupancyData() const;

 private:
  Params params_;
  int width_;
  double origin_;
  std::vector<float> log_odds_;
  std::vector<float> distance_;  // [m], saturated at max_distance
};

}  // namespace rbd_localization

#endif  // RBD_LOCALIZATION_OCCUPANCY_MAP_H
