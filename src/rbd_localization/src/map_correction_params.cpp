#include "rbd_localization/map_correction_params.h"

#include <cmath>
#include <string>

namespace rbd_localization {

namespace {

bool positive(double v) { return v > 0.0 && std::isfinite(v); }

}  // namespace

bool validateMapCorrectionParams(const MapCorrectionNodeParams& n, const MapCorrection::Params& c,
                                 std::string* error) {
  if (n.input != "scan" && n.input != "points") {
    *error = "input must be 'scan' or 'points'";
    return false;
  }
  if (!(n.slice_z_max > n.slice_z_min) || n.slice_bins < 36) {
    *error = "slice_z_max must be > slice_z_min and slice_bins >= 36";
    return false;
  }
  if (n.map_frame.empty() || n.odom_frame.empty() || n.base_frame.empty() || n.map_frame == n.odom_frame) {
    *error = "map_frame, odom_frame, base_frame must be set and map_frame != odom_frame";
    return false;
  }
  if (!positive(n.max_match_rate) || !positive(n.transform_publish_rate) || !positive(c.map.resolution) ||
      !positive(c.map.size) || n.max_points < 10 || !(n.max_range > n.min_range) ||
      c.map.size / c.map.resolution > 8000 || !(c.map.max_size >= c.map.size) ||
      c.map.max_size / c.map.resolution > 8000) {
    *error =
        "rates, resolution, map_size must be > 0, max_points >= 10, max_range > min_range, "
        "map_size <= map_max_size <= 8000 cells wide";
    return false;
  }
  if (!(c.map.static_time >= 0.0) || !(c.clear_weight >= 0.0) || !(c.clear_end_margin >= 0.0) ||
      !(c.search_translation >= 0.0 && c.search_translation <= 5.0) ||
      !(c.search_rotation >= 0.0 && c.search_rotation <= M_PI) || c.localized_scans < 1 ||
      !positive(c.localized_translation) || !positive(c.localized_rotation)) {
    *error =
        "static_time, clear_weight, clear_end_margin >= 0; search_translation in [0, 5] m, search_rotation "
        "in "
        "[0, pi]; localized_scans >= 1; localized_translation/rotation > 0";
    return false;
  }
  const int homes = std::isnan(n.home_x) + std::isnan(n.home_y) + std::isnan(n.home_yaw);
  if ((homes != 0 && homes != 3) || std::isinf(n.home_x) || std::isinf(n.home_y) || std::isinf(n.home_yaw)) {
    *error = "home_x, home_y, home_yaw must be given all three (finite) or none";
    return false;
  }
  if (!(c.matcher.outlier_distance_start >= c.matcher.outlier_distance_end) ||
      !positive(c.matcher.inlier_distance)) {
    *error = "outlier_distance_start must be >= outlier_distance; inlier_distance > 0";
    return false;
  }
  return true;
}

bool loadMapCorrectionParams(const ros::NodeHandle& pnh, MapCorrectionNodeParams* n, MapCorrection::Params* c,
                             std::string* error) {
  pnh.param<std::string>("map_frame", n->map_frame, n->map_frame);
  pnh.param<std::string>("odom_frame", n->odom_frame, n->odom_frame);
  pnh.param<std::string>("base_frame", n->base_frame, n->base_frame);
  pnh.param("max_match_rate", n->max_match_rate, n->max_match_rate);
  pnh.param("max_points", n->max_points, n->max_points);
  pnh.param("min_range", n->min_range, n->min_range);
  pnh.param("max_range", n->max_range, n->max_range);
  pnh.param("transform_publish_rate", n->transform_publish_rate, n->transform_publish_rate);
  pnh.param("transform_tolerance", n->transform_tolerance, n->transform_tolerance);
  pnh.param("pose_timeout", n->pose_timeout, n->pose_timeout);
  pnh.param("map_publish_interval", n->map_publish_interval, n->map_publish_interval);
  pnh.param("scan_timeout", n->scan_timeout, n->scan_timeout);
  pnh.param("correction_enabled", n->correction_enabled, n->correction_enabled);
  pnh.param<std::string>("input", n->input, n->input);
  pnh.param("slice_z_min", n->slice_z_min, n->slice_z_min);
  pnh.param("slice_z_max", n->slice_z_max, n->slice_z_max);
  pnh.param("slice_bins", n->slice_bins, n->slice_bins);
  pnh.param<std::string>("map_file", n->map_file, n->map_file);
  pnh.param("home_x", n->home_x, n->home_x);
  pnh.param("home_y", n->home_y, n->home_y);
  pnh.param("home_yaw", n->home_yaw, n->home_yaw);
  pnh.param<std::string>("map_save_dir", n->map_save_dir, n->map_save_dir);
  pnh.param<std::string>("map_save_name", n->map_save_name, n->map_save_name);
  pnh.param("initial_mapping_duration", c->initial_mapping_duration, c->initial_mapping_duration);
  pnh.param("initial_mapping_min_scans", c->initial_mapping_min_scans, c->initial_mapping_min_scans);
  pnh.param("map_update_interval", c->map_update_interval, c->map_update_interval);
  pnh.param("map_update_weight", c->map_update_weight, c->map_update_weight);
  pnh.param("min_inlier_ratio", c->min_inlier_ratio, c->min_inlier_ratio);
  pnh.param("max_rms", c->max_rms, c->max_rms);
  pnh.param("min_inliers", c->min_inliers, c->min_inliers);
  pnh.param("min_translation_information", c->min_translation_information, c->min_translation_information);
  pnh.param("max_jump_translation", c->max_jump_translation, c->max_jump_translation);
  pnh.param("max_jump_rotation", c->max_jump_rotation, c->max_jump_rotation);
  pnh.param("max_correction_speed", c->max_correction_speed, c->max_correction_speed);
  pnh.param("max_correction_angular_speed", c->max_correction_angular_speed, c->max_correction_angular_speed);
  pnh.param("max_correction_step", c->max_correction_step, c->max_correction_step);
  pnh.param("map_update_min_translation", c->map_update_min_translation, c->map_update_min_translation);
  pnh.param("map_update_min_rotation", c->map_update_min_rotation, c->map_update_min_rotation);
  pnh.param("max_correction_step_rotation", c->max_correction_step_rotation, c->max_correction_step_rotation);
  pnh.param("resolution", c->map.resolution, c->map.resolution);
  pnh.param("map_size", c->map.size, c->map.size);
  pnh.param("map_max_size", c->map.max_size, c->map.max_size);
  pnh.param("static_time", c->map.static_time, c->map.static_time);
  pnh.param("clear_interval", c->clear_interval, c->clear_interval);
  pnh.param("clear_weight", c->clear_weight, c->clear_weight);
  pnh.param("clear_end_margin", c->clear_end_margin, c->clear_end_margin);
  pnh.param("clear_min_incidence", c->clear_min_incidence, c->clear_min_incidence);
  pnh.param("search_translation", c->search_translation, c->search_translation);
  pnh.param("search_rotation", c->search_rotation, c->search_rotation);
  pnh.param("localized_scans", c->localized_scans, c->localized_scans);
  pnh.param("localized_translation", c->localized_translation, c->localized_translation);
  pnh.param("localized_rotation", c->localized_rotation, c->localized_rotation);
  pnh.param("max_iterations", c->matcher.max_iterations, c->matcher.max_iterations);
  pnh.param("outlier_distance_start", c->matcher.outlier_distance_start, c->matcher.outlier_distance_start);
  pnh.param("outlier_distance", c->matcher.outlier_distance_end, c->matcher.outlier_distance_end);
  pnh.param("inlier_distance", c->matcher.inlier_distance, c->matcher.inlier_distance);
  return validateMapCorrectionParams(*n, *c, error);
}

}  // namespace rbd_localization
