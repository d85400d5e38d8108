// ROS-free extended Kalman filter over robot_localization's 15-element state
// (pose in the world frame, velocities / angular rates / accelerations in the body frame).
// Logging is passed in as a std::ostream; nothing here depends on ROS.
#ifndef RBD_LOCALIZATION_EKF_H
#define RBD_LOCALIZATION_EKF_H

#include <array>
#include <limits>
#include <ostream>
#include <string>

#include "rbd_localization/filter_common.h"

namespace rbd_localization {

/// One measurement (or one part of a message, e.g. an IMU's angular rates) for the filter.
struct Measurement {
  Measurement();

  /// Time of validity [s] (any monotonic clock; the node uses ROS time).
  double time;
  /// Measured values, stored at their state indices; only entries with update_vector true are used.
  StateVector values;
  /// Measurement covariance, same indexing; only the rows/columns of the used entries are read.
  StateMatrix covariance;
  /// Which state members this measurement observes.
  std::array<bool, STATE_SIZE> update_vector;
  /// Mahalanobis gate in standard deviations; the measurement is rejected if exceeded.
  double mahalanobis_threshold;
  /// Free text naming the source (for logs and diagnostics).
  std::string source;
};

/// Outcome of Ekf::correct / Ekf::processMeasurement.
enum class CorrectResult {
  kAccepted,  ///< fused (or used to initialise the filter)
  kRejected,  ///< failed the Mahalanobis gate
  kInvalid,   ///< NaN/inf values or nothing to update
};

/// Extended Kalman filter with robot_localization's omnidirectional motion model.
class Ekf {
 public:
  Ekf();

  /// Continuous process noise Q [unit²/s]; predict() adds Q * dt.
  void setProcessNoiseCovariance(const StateMatrix& q);
  /// Covariance the filter starts from (and returns to on reset()).
  void setInitialEstimateCovariance(const StateMatrix& p0);
  /// Values of the members the first measurement does not set (and after reset()); r_l's
  /// initial_state. The filter stays uninitialised until its first measurement.
  void setInitialState(const StateVector& x0);
  /// Planar mode: z, roll, pitch and their rates/acceleration are held at zero and never fused.
  void setTwoDMode(bool enabled);
  /// Debug output goes to stream when enabled (null stream disables output).
  void setDebug(bool enabled, std::ostream* stream);

  /// Forget everything: uninitialised, zero state, initial covariance.
  void reset();
  /// Set the state directly (marks the filter initialised at time).
  void setState(const StateVector& state, double time);
  /// Set the estimate covariance directly.
  void setCovariance(const StateMatrix& covariance);

  const StateVector& state() const { return state_; }
  const StateMatrix& processNoiseCovariance() const { return process_noise_; }
  const StateMatrix& initialEstimateCovariance() const { return initial_covariance_; }
  const StateMatrix& covariance() const { return covariance_; }
  bool initialized() const { return initialized_; }
  /// Time the state refers to [s].
  double lastUpdateTime() const { return last_update_time_; }
  /// Squared Mahalanobis distance of the last correct() call.
  double lastSquaredMahalanobis() const { return last_squared_mahalanobis_; }

  /// Propagate state and covariance by dt seconds (dt <= 0 does nothing).
  void predict(double dt);
  /// Propagate to an absolute time (no-op when time is not after lastUpdateTime()).
  void predictTo(double time);
  /// Fuse a measurement at the current state (no prediction). Joseph-form update on the
  /// configured subset, angle innovations wrapped, gated by the measurement's threshold.
  CorrectResult correct(const Measurement& measurement);
  /// Initialise from the first measurement, otherwise predict to its time and correct.
  CorrectResult processMeasurement(const Measurement& measurement);

  /// Analytic Jacobian of the motion model at the current state for a step dt (for tests).
  StateMatrix transferJacobian(double dt) const;

 private:
  template <int M>
  CorrectResult correctSubset(const Measurement& measurement, const std::array<int, STATE_SIZE>& idx,
                              int m = M);
  void enforceTwoD();
  void wrapStateAngles();
  bool debugOn() const { return debug_ && debug_stream_ != nullptr; }

  StateVector state_;
  StateVector initial_state_;
  StateMatrix covariance_;
  StateMatrix initial_covariance_;
  StateMatrix process_noise_;
  bool initialized_;
  bool two_d_mode_;
  bool debug_;
  std::ostream* debug_stream_;
  double last_update_time_;
  double last_squared_mahalanobis_;
};

}  // namespace rbd_localization

#endif  // RBD_LOCALIZATION_EKF_H
