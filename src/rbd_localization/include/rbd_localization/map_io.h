// ROS-free map files: map_server's PGM + YAML (what every ROS 1 tool reads) plus RoboDog's own
// sidecar NAME.rbdmap holding the exact log-odds, so the node continues from a saved map exactly.
// Every file is written to a temporary name, synced and renamed over the old one (atomic).
#ifndef RBD_LOCALIZATION_MAP_IO_H
#define RBD_LOCALIZATION_MAP_IO_H

#include <Eigen/Core>
#include <memory>
#include <string>

#include "rbd_localization/occupancy_map.h"

namespace rbd_localization {

/// PGM pixel values written (map_server's trinary convention, negate 0).
constexpr int kPgmOccupied = 0;
constexpr int kPgmFree = 254;
constexpr int kPgmUnknown = 205;
constexpr double kOccupiedThresh = 0.65;
constexpr double kFreeThresh = 0.196;

/// What a loaded map says besides the grid.
struct MapFileInfo {
  bool has_home = false;                           ///< the sidecar named a home pose
  Eigen::Vector3d home = Eigen::Vector3d::Zero();  ///< x [m], y [m], yaw [rad] in the map
  bool exact = false;                              ///< log-odds from the sidecar (else the PGM)
  std::string note;                                ///< why the sidecar was not used, if so
};

/// Writes DIR/NAME.pgm, DIR/NAME.yaml (map_server) and DIR/NAME.rbdmap (sidecar). A cell is
/// occupied in the PGM when static at `now` (OccupancyMap::isStatic), free when its log-odds is
/// below 0, unknown otherwise. Files are replaced in the order sidecar, PGM, YAML, each atomically.
bool saveMap(const OccupancyMap& map, double now, const Eigen::Vector3d& home, const std::string& dir,
             const std::string& name, std::string* error);

/// Reads a map_server YAML (and its image, binary PGM P5 only). When NAME.rbdmap lies beside
/// the YAML and names this very PGM (hash), its log-odds are used exactly; otherwise the PGM's
/// occupied/free/unknown cells (map_server's thresholds and negate) become +clamp/-clamp/0.
/// `now` is the clock the map will be used with (occupied-since times are restored from ages).
bool loadMap(const std::string& yaml_path, const OccupancyMap::Params& params, double now,
             std::unique_ptr<OccupancyMap>* out, MapFileInfo* info, std::string* error);

/// Writes `data` to path via a temporary file in the same directory, fsync and rename.
bool writeFileAtomic(const std::string& path, const std::string& data, std::string* error);

/// FNV-1a 64-bit hash (ties the sidecar to the PGM it was saved with).
uint64_t fnv1a64(const std::string& data);

}  // namespace rbd_localization

#endif  // RBD_LOCALIZATION_MAP_IO_H
