// ROS-free 2D occupancy grid (log-odds) with a Euclidean distance field for scan matching. The
// grid grows with the area explored; each occupied cell remembers since when it is occupied, so
// only structure that stayed is saved as a wall (visitors are not).
#ifndef RBD_LOCALIZATION_OCCUPANCY_MAP_H
#define RBD_LOCALIZATION_OCCUPANCY_MAP_H

#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

namespace rbd_localization {

using Points2d = std::vector<Eigen::Vector2d, Eigen::aligned_allocator<Eigen::Vector2d>>;

/// Rectangular grid; cells hold log-odds of being occupied. Starts as a square centred on the
/// map origin and grows (in steps of grow_margin) when a scan reaches beyond it.
class OccupancyMap {
 public:
  struct Params {
    double resolution = 0.05;        ///< cell size [m]
    double size = 30.0;              ///< initial side length [m]; the map spans [-size/2, size/2)
    double hit_log_odds = 0.85;      ///< added to the cell a beam ends in
    double miss_log_odds = -0.4;     ///< added to cells a beam passes through
    double occupied_log_odds = 1.5;  ///< a cell is structure above this
    double clamp_log_odds = 3.5;     ///< |log-odds| limit (so the map can still change)
    double max_distance = 1.0;       ///< distance field saturates here [m]
    bool grow = true;                ///< grow the grid when a scan reaches beyond it
    double grow_margin = 5.0;        ///< [m] added beyond the scan when growing
    double max_size = 200.0;         ///< [m] the grid never grows beyond this side length
    /// A cell counts as static structure (saved as a wall) only after it stayed occupied this
    /// long [s] while scans kept confirming it (people who stood and left are cleared before).
    double static_time = 10.0;
  };

  /// How one scan is inserted.
  struct Insert {
    double weight = 1.0;      ///< scales hit and miss log-odds
    bool hits = true;         ///< false: only clear along the beams (no cell becomes occupied)
    double end_margin = 0.0;  ///< [m] the last part of each beam before its end is not cleared
    double time = 0.0;        ///< [s] stamp, for the occupied-since bookkeeping
    /// Beams meeting their surface flatter than this [rad] only hit, they do not clear: such a beam
    /// runs along a wall's cells. The surface is the chord through the neighbours in scan order
    /// that lie within 0.05 r + 0.05 of the point (both, or the one across from a depth step; none:
    /// unknown, no clearing). 0: all beams clear.
    double min_incidence = 0.0;
  };

  OccupancyMap();
  explicit OccupancyMap(const Params& params);
  /// A grid of the given size and origin (lower-left corner of cell (0, 0)), all unknown.
  OccupancyMap(const Params& params, int width, int height, double origin_x, double origin_y);

  const Params& params() const { return params_; }
  void setGrow(bool grow) { params_.grow = grow; }
  int width() const { return width_; }
  int height() const { return height_; }
  double originX() const { return origin_x_; }  ///< world x of cell (0, 0)'s lower-left corner
  double originY() const { return origin_y_; }
  /// Bytes held by the grid's arrays (reported in diagnostics).
  size_t memoryBytes() const;

  /// Ray-casts one scan: misses along each beam (up to, not including, the end cell) and a hit
  /// at the end. Returns true when a cell's occupied state changed (the distance field is then
  /// stale). Beams whose end lies outside a grid that cannot grow only clear.
  bool insertScan(const Eigen::Isometry2d& map_from_sensor, const Points2d& points_in_sensor,
                  const Insert& how);
  bool insertScan(const Eigen::Isometry2d& map_from_sensor, const Points2d& points_in_sensor, double weight) {
    Insert how;
    how.weight = weight;
    return insertScan(map_from_sensor, points_in_sensor, how);
  }

  /// Cell index of a world point; false if outside.
  bool cellOf(const Eigen::Vector2d& p, int* cx, int* cy) const;
  size_t index(int cx, int cy) const { return static_cast<size_t>(cy) * width_ + cx; }
  float logOdds(int cx, int cy) const { return log_odds_[index(cx, cy)]; }
  bool occupied(int cx, int cy) const { return logOdds(cx, cy) > params_.occupied_log_odds; }
  /// Occupied for at least static_time at `now` [s].
  bool isStatic(int cx, int cy, double now) const;
  /// Time [s] since which the cell is occupied (NaN when it is not).
  float occupiedSince(int cx, int cy) const { return occupied_since_[index(cx, cy)]; }
  int occupiedCount() const;

  /// Sets one cell (map loading): log-odds and since when it is occupied (NaN: not).
  void setCell(int cx, int cy, float log_odds, float occupied_since);

  /// Recomputes the distance field from the occupied cells (exact EDT, O(cells)).
  void updateDistanceField();
  /// Distance to the nearest structure [m] (bilinear) and its gradient; saturates at
  /// max_distance and outside the map. Returns false outside the map.
  bool distance(const Eigen::Vector2d& p, double* d, Eigen::Vector2d* gradient) const;

  /// ROS OccupancyGrid convention: -1 unknown, 0 free .. 100 occupied, row-major from (0,0).
  std::vector<int8_t> toOccupancyData() const;

 private:
  /// Grows the grid to contain [lo, hi] (plus grow_margin); false if that would exceed max_size.
  bool growToContain(const Eigen::Vector2d& lo, const Eigen::Vector2d& hi);

  Params params_;
  int width_ = 0, height_ = 0;
  double origin_x_ = 0.0, origin_y_ = 0.0;
  std::vector<float> log_odds_;
  std::vector<float> occupied_since_;  // [s], NaN when not occupied
  std::vector<float> distance_;        // [m], saturated at max_distance
};

}  // namespace rbd_localization

#endif  // RBD_LOCALIZATION_OCCUPANCY_MAP_H
