// Shared definitions of the 15-element state used by the filter, the node and the tests.
// Same ordering and meaning as robot_localization's state so its configuration vectors
// (the 15 booleans of imuN_config, poseN_config, ...) map one to one.
#ifndef RBD_LOCALIZATION_FILTER_COMMON_H
#define RBD_LOCALIZATION_FILTER_COMMON_H

#include <Eigen/Core>

namespace rbd_localization {

/// Index of each member in the state vector.
/// Pose is in the world frame; velocities, angular rates and accelerations in the body frame.
enum StateMembers {
  StateMemberX = 0,
  StateMemberY,
  StateMemberZ,
  StateMemberRoll,
  StateMemberPitch,
  StateMemberYaw,
  StateMemberVx,
  StateMemberVy,
  StateMemberVz,
  StateMemberVroll,
  StateMemberVpitch,
  StateMemberVyaw,
  StateMemberAx,
  StateMemberAy,
  StateMemberAz
};

/// Number of members in the state vector.
constexpr int STATE_SIZE = 15;
/// Offsets of the blocks of three.
constexpr int POSITION_OFFSET = StateMemberX;
constexpr int ORIENTATION_OFFSET = StateMemberRoll;
constexpr int POSITION_V_OFFSET = StateMemberVx;
constexpr int ORIENTATION_V_OFFSET = StateMemberVroll;
constexpr int POSITION_A_OFFSET = StateMemberAx;

using StateVector = Eigen::Matrix<double, STATE_SIZE, 1>;
using StateMatrix = Eigen::Matrix<double, STATE_SIZE, STATE_SIZE>;
/// A vector/matrix of at most STATE_SIZE rows that never allocates on the heap.
using MeasVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, STATE_SIZE, 1>;
using MeasMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, STATE_SIZE, STATE_SIZE>;
using GainMatrix = Eigen::Matrix<double, STATE_SIZE, Eigen::Dynamic, 0, STATE_SIZE, STATE_SIZE>;

/// True for the three angle members (roll, pitch, yaw), whose differences are wrapped.
inline bool isAngleMember(int index) {
  return index == StateMemberRoll || index == StateMemberPitch || index == StateMemberYaw;
}

/// robot_localization's name of a state member ("x" ... "az"), as in its configuration vectors.
inline const char* stateMemberName(int index) {
  static const char* const kNames[STATE_SIZE] = {"x",  "y",     "z",      "roll", "pitch", "yaw", "vx", "vy",
                                                 "vz", "vroll", "vpitch", "vyaw", "ax",    "ay",  "az"};
  return index >= 0 && index < STATE_SIZE ? kNames[index] : "?";
}

/// Wraps an angle to [-pi, pi).
double wrapAngle(double angle);

}  // namespace rbd_localization

#endif  // RBD_LOCALIZATION_FILTER_COMMON_H
