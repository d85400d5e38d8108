// Differential pose handling (measurement_conversions): the RoboDog increment covariance and the
// gate it gives to a jumping tracker such as the ZED2; the IMU orientation as a base pose.
#include <gtest/gtest.h>

#include <cmath>

#include "rbd_localization/ekf.h"
#include "rbd_localization/filter_params.h"
#include "rbd_localization/measurement_conversions.h"

using namespace rbd_localization;  // NOLINT: StateMember* enumerators

namespace {

const double kDt = 1.0 / 15.0;

SensorConfig zedConfig(bool with_noise) {
  SensorConfig c;
  c.name = "pose0";
  c.update_vector[StateMemberX] = c.update_vector[StateMemberY] = true;
  c.differential = true;
  c.pose_rejection_threshold = 5.0;
  if (with_noise) {
    c.has_differential_noise = true;
    c.differential_noise = {0.008, 0.008, 0.008, 0.003, 0.003, 0.003};
  }
  return c;
}

PoseWithCov pose(double x, double y, double yaw, double variance) {
  PoseWithCov p;
  p.pose.translation() = Eigen::Vector3d(x, y, 0.0);
  p.pose.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  p.covariance = Matrix6d::Identity() * variance;
  return p;
}

// A filter moving at 0.3 m/s along x, settled.
Ekf movingFilter() {
  Ekf ekf;
  StateVector s = StateVector::Zero();
  s(StateMemberVx) = 0.3;
  ekf.setState(s, 0.0);
  StateMatrix p = StateMatrix::Identity() * 1e-4;
  ekf.setCovariance(p);
  StateMatrix q = StateMatrix::Zero();
  q.diagonal().setConstant(0.005);
  ekf.setProcessNoiseCovariance(q);
  return ekf;
}

}  // namespace

TEST(Differential, CovarianceIsNoisePlusGrowthNotSum) {
  Measurement m;
  // A tracker that reports 5 cm of accumulated drift (variance 0.0025) growing by 1e-5.
  ASSERT_TRUE(differentialMeasurement(pose(0, 0, 0, 0.0025), pose(0.02, 0, 0, 0.00251), kDt, zedConfig(true),
                                      1.0, &m));
  const double expected = (2 * 0.008 * 0.008 + 1e-5) / (kDt * kDt);
  EXPECT_NEAR(m.covariance(StateMemberVx, StateMemberVx), expected, 1e-9);
  EXPECT_NEAR(m.values(StateMemberVx), 0.3, 1e-9);
  EXPECT_TRUE(m.update_vector[StateMemberVx]);
  EXPECT_FALSE(m.update_vector[StateMemberX]);
  // A relocalisation (covariance shrinks) adds nothing beyond the white noise.
  ASSERT_TRUE(
      differentialMeasurement(pose(0, 0, 0, 0.0025), pose(0.02, 0, 0, 1e-5), kDt, zedConfig(true), 1.0, &m));
  EXPECT_NEAR(m.covariance(StateMemberVx, StateMemberVx), 2 * 0.008 * 0.008 / (kDt * kDt), 1e-9);
  // robot_localization's behaviour without the extension: the sum of both covariances.
  ASSERT_TRUE(differentialMeasurement(pose(0, 0, 0, 0.0025), pose(0.02, 0, 0, 0.00251), kDt, zedConfig(false),
                                      1.0, &m));
  EXPECT_NEAR(m.covariance(StateMemberVx, StateMemberVx), (0.0025 + 0.00251) / (kDt * kDt), 1e-9);
}

TEST(Differential, VelocityIsInThePreviousBodyFrame) {
  Measurement m;
  // Facing +y, moving 0.02 m along +y: forward body velocity.
  ASSERT_TRUE(differentialMeasurement(pose(1, 1, M_PI / 2, 1e-4), pose(1, 1.02, M_PI / 2, 1e-4), kDt,
                                      zedConfig(true), 1.0, &m));
  EXPECT_NEAR(m.values(StateMemberVx), 0.3, 1e-9);
  EXPECT_NEAR(m.values(StateMemberVy), 0.0, 1e-9);
}

TEST(Differential, JumpIsGatedNormalMotionIsFused) {
  const SensorConfig cfg = zedConfig(true);
  Ekf ekf = movingFilter();
  double t = 0.0;
  double x = 0.0;
  const double variance = 0.0025;  // the ZED reports several cm of accumulated drift
  PoseWithCov previous = pose(x, 0, 0, variance);
  Measurement m;
  for (int i = 0; i < 30; ++i) {  // normal motion: accepted
    t += kDt;
    x += 0.3 * kDt;
    const PoseWithCov current = pose(x, 0, 0, variance);
    ASSERT_TRUE(differentialMeasurement(previous, current, kDt, cfg, t, &m));
    EXPECT_EQ(ekf.processMeasurement(m), CorrectResult::kAccepted) << "sample " << i;
    previous = current;
  }
  const double before = ekf.state()(StateMemberY);
  for (double jump : {1.0, 0.1}) {  // a 1 m and a 10 cm sideways jump: rejected
    t += kDt;
    x += 0.3 * kDt;
    const PoseWithCov current = pose(x, jump, 0, variance);
    ASSERT_TRUE(differentialMeasurement(previous, current, kDt, cfg, t, &m));
    EXPECT_EQ(ekf.processMeasurement(m), CorrectResult::kRejected) << jump << " m";
    // the tracker stays shifted: the next increments are consistent again and accepted
    previous = current;
    for (int i = 0; i < 5; ++i) {
      t += kDt;
      x += 0.3 * kDt;
      const PoseWithCov next = pose(x, jump, 0, variance);
      ASSERT_TRUE(differentialMeasurement(previous, next, kDt, cfg, t, &m));
      EXPECT_EQ(ekf.processMeasurement(m), CorrectResult::kAccepted);
      previous = next;
    }
    // back to the unshifted pose for the next case (also a jump, also rejected)
    t += kDt;
    x += 0.3 * kDt;
    const PoseWithCov back = pose(x, 0, 0, variance);
    ASSERT_TRUE(differentialMeasurement(previous, back, kDt, cfg, t, &m));
    EXPECT_EQ(ekf.processMeasurement(m), CorrectResult::kRejected);
    previous = back;
  }
  EXPECT_NEAR(ekf.state()(StateMemberY), before, 0.01);  // the estimate never followed
  EXPECT_NEAR(ekf.state()(StateMemberX), x, 0.03);

  // Without the extension (r_l's summed covariance) the 10 cm jump passes the same gate.
  const SensorConfig rl = zedConfig(false);
  Ekf ekf2 = movingFilter();
  ASSERT_TRUE(
      differentialMeasurement(pose(0, 0, 0, variance), pose(0.02, 0.1, 0, variance), kDt, rl, kDt, &m));
  EXPECT_EQ(ekf2.processMeasurement(m), CorrectResult::kAccepted);
}

TEST(ImuOrientation, BaseOrientationThroughTheMountAndUnusableOrientationRefused) {
  // IMU mounted yawed +90 deg on base_link; it reports its own orientation: yaw 120 deg, so the
  // body is at 30 deg. Orientation covariance: 0.01 about the IMU's x, 0.04 about its y.
  const Eigen::Matrix3d base_from_imu =
      Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  sensor_msgs::Imu msg;
  const Eigen::Quaterniond q(Eigen::AngleAxisd(M_PI * 2 / 3, Eigen::Vector3d::UnitZ()));
  msg.orientation.w = q.w();
  msg.orientation.z = q.z();
  msg.orientation_covariance[0] = 0.01;
  msg.orientation_covariance[4] = 0.04;
  msg.orientation_covariance[8] = 0.09;
  PoseWithCov out;
  ASSERT_TRUE(imuOrientationPose(msg, base_from_imu, &out));
  const Eigen::Matrix3d r = out.pose.linear();
  EXPECT_NEAR(std::atan2(r(1, 0), r(0, 0)), M_PI / 6, 1e-12);
  EXPECT_NEAR(out.pose.translation().norm(), 0.0, 1e-12);
  // The IMU's x axis is the body's y axis: 0.01 about body y, 0.04 about body x.
  EXPECT_NEAR(out.covariance(3, 3), 0.04, 1e-12);
  EXPECT_NEAR(out.covariance(4, 4), 0.01, 1e-12);
  EXPECT_NEAR(out.covariance(5, 5), 0.09, 1e-12);
  msg.orientation_covariance[0] = -1.0;  // "no orientation" (ouster-ros)
  EXPECT_FALSE(imuOrientationPose(msg, base_from_imu, &out));
  msg.orientation_covariance[0] = 0.01;
  msg.orientation.w = msg.orientation.z = 0.0;
  EXPECT_FALSE(imuOrientationPose(msg, base_from_imu, &out));
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
