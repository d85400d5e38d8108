// ekf_localization_node: robot_localization-compatible EKF (parameters in params/ekf.yaml).
#include "rbd_localization/node_main.h"

int main(int argc, char** argv) { return rbd_localization::ekfLocalizationNodeMain(argc, argv); }
