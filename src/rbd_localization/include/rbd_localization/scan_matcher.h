// ROS-free 2D scan-to-map matcher: Gauss-Newton on the map's distance field, starting from a
// prior pose (the EKF's), with points far from any structure (people, new furniture) ignored.
#ifndef RBD_LOCALIZATION_SCAN_MATCHER_H
#define RBD_LOCALIZATION_SCAN_MATCHER_H

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

#include "rbd_localization/occupancy_map.h"

namespace rbd_localization {

class ScanMatcher {
 public:
  struct Params {
    int max_iterations = 30;
    /// Correspondence gates [m]: points farther than this from structure are outliers. The gate
    /// shrinks from the first value to the last over the iterations (coarse-to-fine).
    double outlier_distance_start = 0.5;
    double outlier_distance_end = 0.15;
    /// A point within this distance [m] of structure counts as an inlier for the fit quality.
    double inlier_distance = 0.10;
    /// Stop when the step is below these [m], [rad].
    double converged_translation = 1e-4;
    double converged_rotation = 1e-4;
  };

  struct Result {
    Eigen::Isometry2d pose = Eigen::Isometry2d::Identity();  ///< map_from_base
    int points = 0;
    int inliers = 0;
    double inlier_ratio = 0.0;
    double rms = 0.0;  ///< of the inliers' distances [m]
    int iterations = 0;
    /// Smallest eigenvalue of the normalised Gauss-Newton Hessian (translation block, per
    /// inlier): small means the geometry does not constrain the pose (a corridor).
    double min_translation_information = 0.0;
  };

  ScanMatcher() : params_(Params()) {}
  explicit ScanMatcher(const Params& params) : params_(params) {}
  const Params& params() const { return params_; }

  /// How rivalElsewhere() scans the whole map.
  struct GlobalSearch {
    double step = 0.1;         ///< [m] position grid
    double angle_step = 0.05;  ///< [rad] heading grid (all headings)
    int subset = 60;           ///< points scored per pose (every n-th of the scan)
    int candidates = 8;        ///< best distinct grid poses refined with match()
  };

  /// The best pose found over the whole map, away from a given one (rivalElsewhere()).
  struct Rival {
    bool found = false;  ///< a refined pose farther than the distinctness radius exists
    Result match;        ///< that pose, refined with match()
    double score = 0.0;  ///< its score() [m]
    int poses_scored = 0;
  };

  /// Aligns points (in the base frame) to the map's distance field starting at prior.
  Result match(const OccupancyMap& map, const Points2d& points_in_base, const Eigen::Isometry2d& prior) const;

  /// Exhaustive search of poses within +-max_translation [m] and +-max_rotation [rad] of prior
  /// (grid of `step` [m] and about step/2 m of arc at 5 m range), scored by the mean truncated
  /// distance of a subset of the points; the best candidates are refined with match() and the
  /// best refined fit (most inliers) returned. For a start far from the prior.
  Result search(const OccupancyMap& map, const Points2d& points_in_base, const Eigen::Isometry2d& prior,
                double max_translation, double max_rotation, double step = 0.1) const;

  /// The truncated-distance score search() ranks poses by: the mean over the points of their
  /// distance to structure, each capped at kTruncate [m] (0 = every point on a wall; lower is better).
  static double score(const OccupancyMap& map, const Points2d& points_in_base, const Eigen::Isometry2d& pose);
  static constexpr double kTruncate = 0.3;

  /// Scores poses over the whole map (every heading; positions on a `how.step` grid over the
  /// cells the map saw free, where a robot can stand) and refines the best distinct ones with
  /// match(); returns the best refined pose (lowest score()) farther than min_translation [m] or
  /// min_rotation [rad] from `pose`. A start search uses it to tell whether its answer is the
  /// only pose that fits the scan (a room that is almost symmetric has a twin of every pose).
  Rival rivalElsewhere(const OccupancyMap& map, const Points2d& points_in_base, const Eigen::Isometry2d& pose,
                       double min_translation, double min_rotation, const GlobalSearch& how) const;

 private:
  Params params_;
};

}  // namespace rbd_localization

#endif  // RBD_LOCALIZATION_SCAN_MATCHER_H
