// The parameters ekf_localization_node runs with, as one JSON document (the node's latched
// ~effective_config), written with nlohmann::json.
#ifndef RBD_LOCALIZATION_EFFECTIVE_CONFIG_H
#define RBD_LOCALIZATION_EFFECTIVE_CONFIG_H

#include <string>
#include <vector>

#include "rbd_localization/filter_params.h"

namespace rbd_localization {

/// The parameters as the filter uses them, as JSON (r_l's key names, keys sorted; matrices as 225
/// numbers row-major; a non-finite number as null), with the start-up warnings. q and p0 are the
/// matrices the filter holds.
std::string effectiveConfigJson(const FilterParams& params, const StateMatrix& q, const StateMatrix& p0,
                                const std::vector<std::string>& warnings);

}  // namespace rbd_localization

#endif  // RBD_LOCALIZATION_EFFECTIVE_CONFIG_H
