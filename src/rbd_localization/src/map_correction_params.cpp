#include "rbd_localization/map_correction_params.h"

#include <ros/param.h>

#include <cmath>
#include <string>
#include <vector>

#include "rbd_localization/param_reader.h"

namespace rbd_localization {

namespace {

bool positive(double v) { return v > 0.0 && std::isfinite(v); }

// One reader per field type, so that each parameter is one line below.
bool read(ParamReader* r, const std::string& key, double* out) { return r->number(key, out); }
bool read(ParamReader* r, const std::string& key, int* out) { return r->integer(key, out); }
bool read(ParamReader* r, const std::string& key, bool* out) { return r->boolean(key, out); }
bool read(ParamReader* r, const std::string& key, std::string* out) { return r->text(key, out); }

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
  if (!(c.ambiguity_translation >= 0.0 && c.ambiguity_translation <= 5.0) ||
      !(c.ambiguity_rotation >= 0.0 && c.ambiguity_rotation <= M_PI) ||
      !(c.ambiguity_margin >= 0.0 && c.ambiguity_margin <= ScanMatcher::kTruncate) ||
      !(c.ambiguity_step >= 0.05 && c.ambiguity_step <= 1.0) ||
      !(c.ambiguity_angle_step >= 0.01 && c.ambiguity_angle_step <= 0.35) ||
      !(c.ambiguity_retry_interval >= 0.0 && std::isfinite(c.ambiguity_retry_interval))) {
    *error =
        "ambiguity_translation in [0, 5] m, ambiguity_rotation in [0, pi], ambiguity_margin in [0, 0.3] m, "
        "ambiguity_step in [0.05, 1] m, ambiguity_angle_step in [0.01, 0.35] rad, ambiguity_retry_interval "
        ">= 0";
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

bool parseMapCorrectionParams(const XmlRpc::XmlRpcValue& ns, MapCorrectionNodeParams* n,
                              MapCorrection::Params* c, std::vector<std::string>* warnings,
                              std::string* error) {
  ParamReader r(ns, warnings, error, "");
  const bool read_all =
      read(&r, "map_frame", &n->map_frame) && read(&r, "odom_frame", &n->odom_frame) &&
      read(&r, "base_frame", &n->base_frame) && read(&r, "max_match_rate", &n->max_match_rate) &&
      read(&r, "max_points", &n->max_points) && read(&r, "min_range", &n->min_range) &&
      read(&r, "max_range", &n->max_range) &&
      read(&r, "transform_publish_rate", &n->transform_publish_rate) &&
      read(&r, "transform_tolerance", &n->transform_tolerance) &&
      read(&r, "pose_timeout", &n->pose_timeout) &&
      read(&r, "map_publish_interval", &n->map_publish_interval) &&
      read(&r, "scan_timeout", &n->scan_timeout) && read(&r, "correction_enabled", &n->correction_enabled) &&
      read(&r, "input", &n->input) && read(&r, "slice_z_min", &n->slice_z_min) &&
      read(&r, "slice_z_max", &n->slice_z_max) && read(&r, "slice_bins", &n->slice_bins) &&
      read(&r, "map_file", &n->map_file) && read(&r, "home_x", &n->home_x) &&
      read(&r, "home_y", &n->home_y) && read(&r, "home_yaw", &n->home_yaw) &&
      read(&r, "map_save_dir", &n->map_save_dir) && read(&r, "map_save_name", &n->map_save_name) &&
      read(&r, "initial_mapping_duration", &c->initial_mapping_duration) &&
      read(&r, "initial_mapping_min_scans", &c->initial_mapping_min_scans) &&
      read(&r, "map_update_interval", &c->map_update_interval) &&
      read(&r, "map_update_weight", &c->map_update_weight) &&
      read(&r, "min_inlier_ratio", &c->min_inlier_ratio) && read(&r, "max_rms", &c->max_rms) &&
      read(&r, "min_inliers", &c->min_inliers) &&
      read(&r, "min_translation_information", &c->min_translation_information) &&
      read(&r, "max_jump_translation", &c->max_jump_translation) &&
      read(&r, "max_jump_rotation", &c->max_jump_rotation) &&
      read(&r, "max_correction_speed", &c->max_correction_speed) &&
      read(&r, "max_correction_angular_speed", &c->max_correction_angular_speed) &&
      read(&r, "max_correction_step", &c->max_correction_step) &&
      read(&r, "map_update_min_translation", &c->map_update_min_translation) &&
      read(&r, "map_update_min_rotation", &c->map_update_min_rotation) &&
      read(&r, "max_correction_step_rotation", &c->max_correction_step_rotation) &&
      read(&r, "resolution", &c->map.resolution) && read(&r, "map_size", &c->map.size) &&
      read(&r, "map_max_size", &c->map.max_size) && read(&r, "static_time", &c->map.static_time) &&
      read(&r, "clear_interval", &c->clear_interval) && read(&r, "clear_weight", &c->clear_weight) &&
      read(&r, "clear_end_margin", &c->clear_end_margin) &&
      read(&r, "clear_min_incidence", &c->clear_min_incidence) &&
      read(&r, "search_translation", &c->search_translation) &&
      read(&r, "search_rotation", &c->search_rotation) && read(&r, "localized_scans", &c->localized_scans) &&
      read(&r, "localized_translation", &c->localized_translation) &&
      read(&r, "localized_rotation", &c->localized_rotation) &&
      read(&r, "ambiguity_check", &c->ambiguity_check) &&
      read(&r, "ambiguity_translation", &c->ambiguity_translation) &&
      read(&r, "ambiguity_rotation", &c->ambiguity_rotation) &&
      read(&r, "ambiguity_margin", &c->ambiguity_margin) && read(&r, "ambiguity_step", &c->ambiguity_step) &&
      read(&r, "ambiguity_angle_step", &c->ambiguity_angle_step) &&
      read(&r, "ambiguity_retry_interval", &c->ambiguity_retry_interval) &&
      read(&r, "max_iterations", &c->matcher.max_iterations) &&
      read(&r, "outlier_distance_start", &c->matcher.outlier_distance_start) &&
      read(&r, "outlier_distance", &c->matcher.outlier_distance_end) &&
      read(&r, "inlier_distance", &c->matcher.inlier_distance);
  if (!read_all) return false;
  const std::vector<std::string> unknown = r.unread();
  if (!unknown.empty()) {
    std::string list;
    for (const std::string& k : unknown) list += (list.empty() ? "" : ", ") + k;
    warnings->push_back("unknown parameters, ignored: " + list);
  }
  return validateMapCorrectionParams(*n, *c, error);
}

bool loadMapCorrectionParams(const ros::NodeHandle& pnh, MapCorrectionNodeParams* n, MapCorrection::Params* c,
                             std::vector<std::string>* warnings, std::string* error) {
  XmlRpc::XmlRpcValue ns;
  if (!ros::param::get(pnh.getNamespace(), ns)) ns = XmlRpc::XmlRpcValue();
  return parseMapCorrectionParams(ns, n, c, warnings, error);
}

}  // namespace rbd_localization
