// map_correction_node's parameters: the node's own and MapCorrection's, read from the private
// namespace and validated (the validation is ROS-free and unit-tested: test_map_correction_params).
#ifndef RBD_LOCALIZATION_MAP_CORRECTION_PARAMS_H
#define RBD_LOCALIZATION_MAP_CORRECTION_PARAMS_H

#include <XmlRpcValue.h>
#include <ros/node_handle.h>

#include <limits>
#include <string>
#include <vector>

#include "rbd_localization/map_correction.h"

namespace rbd_localization {

/// Node parameters besides the MapCorrection ones (see README).
struct MapCorrectionNodeParams {
  std::string map_frame = "map";
  std::string odom_frame = "odom";
  std::string base_frame = "base_link";
  double max_match_rate = 10.0;          ///< [Hz] scans matched at most this often
  int max_points = 360;                  ///< scan decimated to about this many points
  double min_range = 0.3;                ///< [m] OS1 blind zone
  double max_range = 20.0;               ///< [m]
  double transform_publish_rate = 50.0;  ///< [Hz] map -> odom
  double transform_tolerance = 0.1;      ///< [s] map -> odom is stamped this far ahead
  double pose_timeout = 0.5;             ///< [s] no pose output from odometry older than this
  double map_publish_interval = 2.0;     ///< [s]
  double scan_timeout = 1.0;             ///< [s] diagnostics: scans stale after this
  bool correction_enabled = true;        ///< false: map -> odom stays identity (comparison runs)
  /// Input: "scan" (LaserScan on `scan`) or "points" (PointCloud2 on `points`, sliced here).
  std::string input = "scan";
  double slice_z_min = 0.0;  ///< [m] above base_frame (levelled): cloud points kept for the 2D slice
  double slice_z_max = 0.4;  ///< [m]
  int slice_bins = 720;      ///< azimuth bins of the slice (nearest point per bin)
  /// map_server YAML of a saved map: localization mode in it. Empty: mapping mode.
  std::string map_file;
  /// Home pose in the loaded map [m, m, rad] (where the robot starts); NaN: the map's sidecar
  /// home, else (0, 0, 0).
  double home_x = std::numeric_limits<double>::quiet_NaN();
  double home_y = std::numeric_limits<double>::quiet_NaN();
  double home_yaw = std::numeric_limits<double>::quiet_NaN();
  std::string map_save_dir = ".";     ///< ~save_map writes here (read at each call)
  std::string map_save_name = "map";  ///< ... as NAME.pgm, NAME.yaml, NAME.rbdmap
};

/// Checks node + MapCorrection parameters (ROS-free); false with the first reason on an invalid value.
bool validateMapCorrectionParams(const MapCorrectionNodeParams& node, const MapCorrection::Params& core,
                                 std::string* error);

/// Reads node + MapCorrection parameters from a private namespace as the parameter server
/// delivers it (an XmlRpc struct) over the defaults in node and core, with rbd_localization's
/// ParamReader (as the EKF's parameters: a value of the wrong type is an error, a number written
/// as text is read with a warning, unknown keys are listed in one warning), then
/// validateMapCorrectionParams. ROS-free (no master); false with the reason on an invalid value.
bool parseMapCorrectionParams(const XmlRpc::XmlRpcValue& ns, MapCorrectionNodeParams* node,
                              MapCorrection::Params* core, std::vector<std::string>* warnings,
                              std::string* error);

/// parseMapCorrectionParams on pnh's namespace, fetched from the parameter server.
bool loadMapCorrectionParams(const ros::NodeHandle& pnh, MapCorrectionNodeParams* node,
                             MapCorrection::Params* core, std::vector<std::string>* warnings,
                             std::string* error);

}  // namespace rbd_localization

#endif  // RBD_LOCALIZATION_MAP_CORRECTION_PARAMS_H
