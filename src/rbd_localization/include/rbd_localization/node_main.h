// Entry points of the two localization nodes. Each executable's main() only calls one of these,
// so its translation unit includes this header instead of the node's own (which pulls in roscpp,
// tf2_ros, diagnostic_updater and the message headers: ~12 s of compile each, issue 19).
#ifndef RBD_LOCALIZATION_NODE_MAIN_H
#define RBD_LOCALIZATION_NODE_MAIN_H

namespace rbd_localization {

/// ekf_localization_node: ros::init, an EkfNode on the private parameters, spin.
/// Returns the process exit status (1 on a bad configuration).
int ekfLocalizationNodeMain(int argc, char** argv);

/// map_correction_node: ros::init, a MapCorrectionNode on the private parameters, spin.
/// Returns the process exit status (1 on a bad configuration).
int mapCorrectionNodeMain(int argc, char** argv);

}  // namespace rbd_localization

#endif  // RBD_LOCALIZATION_NODE_MAIN_H
