// EKF maths per IMU update: predict to the IMU stamp + the two corrections the node makes per
// IMU message (angular rates, linear accelerations), with a 15 Hz pose in between, as in the
// shipped configuration. Prints one JSON line.
#include <chrono>
#include <cstdio>
#include <ctime>
#include <random>

#include "rbd_localization/ekf.h"

using namespace rbd_localization;  // NOLINT

int main(int argc, char** argv) {
  const int n = argc > 1 ? std::atoi(argv[1]) : 200000;
  std::mt19937 rng(1);
  std::normal_distribution<double> noise(0.0, 0.01);
  Ekf ekf;
  StateMatrix q = StateMatrix::Identity() * 0.01;
  ekf.setProcessNoiseCovariance(q);
  ekf.setInitialEstimateCovariance(StateMatrix::Identity() * 1e-3);
  ekf.setState(StateVector::Zero(), 0.0);

  Measurement gyro, accel, pose;
  for (int i = StateMemberVroll; i <= StateMemberVyaw; ++i) gyro.update_vector[i] = true;
  for (int i = StateMemberAx; i <= StateMemberAz; ++i) accel.update_vector[i] = true;
  for (int i = StateMemberVx; i <= StateMemberVyaw; ++i) pose.update_vector[i] = true;
  gyro.covariance = StateMatrix::Identity() * 6e-4;
  accel.covariance = StateMatrix::Identity() * 1e-2;
  pose.covariance = StateMatrix::Identity() * 1e-2;
  gyro.mahalanobis_threshold = accel.mahalanobis_threshold = pose.mahalanobis_threshold = 8.0;
  // Pre-generate inputs so the RNG is not timed.
  std::vector<double> w(n), a(n);
  for (int k = 0; k < n; ++k) {
    w[k] = 0.2 + noise(rng);
    a[k] = noise(rng);
  }

  const auto run = [&](int count, bool with_pose) {
    double t = ekf.lastUpdateTime();
    for (int k = 0; k < count; ++k) {
      t += 0.002;
      gyro.time = accel.time = t;
      gyro.values(StateMemberVyaw) = w[k % n];
      accel.values(StateMemberAx) = a[k % n];
      ekf.processMeasurement(gyro);
      ekf.processMeasurement(accel);
      if (with_pose && k % 33 == 0) {
        pose.time = t;
        pose.values(StateMemberVx) = 0.3;
        ekf.processMeasurement(pose);
      }
    }
  };
  run(5000, true);  // warm-up

  const auto w0 = std::chrono::steady_clock::now();
  const std::clock_t c0 = std::clock();
  run(n, true);
  const std::clock_t c1 = std::clock();
  const auto w1 = std::chrono::steady_clock::now();
  const double wall_us = std::chrono::duration<double, std::micro>(w1 - w0).count() / n;
  const double cpu_us = 1e6 * static_cast<double>(c1 - c0) / CLOCKS_PER_SEC / n;

  const auto p0 = std::chrono::steady_clock::now();
  for (int k = 0; k < n; ++k) ekf.predict(0.002);
  const auto p1 = std::chrono::steady_clock::now();
  const double predict_us = std::chrono::duration<double, std::micro>(p1 - p0).count() / n;

  std::printf(
      "{\"bench\": \"ekf_update\", \"imu_updates\": %d, \"us_per_imu_update_wall\": %.3f, "
      "\"us_per_imu_update_cpu\": %.3f, \"us_per_predict\": %.3f, \"goal_us\": 5.0, \"finite\": %s}\n",
      n, wall_us, cpu_us, predict_us, ekf.state().allFinite() ? "true" : "false");
  return 0;
}
