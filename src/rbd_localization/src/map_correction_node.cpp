// map_correction_node: LiDAR scan matching against a self-built 2D map -> map -> odom.
#include "rbd_localization/node_main.h"

int main(int argc, char** argv) { return rbd_localization::mapCorrectionNodeMain(argc, argv); }
