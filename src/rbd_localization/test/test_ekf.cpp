// Analytic cases for the ROS-free Ekf core.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <random>
#include <sstream>
#include <vector>

#include "rbd_localization/ekf.h"

using rbd_localization::CorrectResult;
using rbd_localization::Ekf;
using rbd_localization::Measurement;
using rbd_localization::STATE_SIZE;
using rbd_localization::StateMatrix;
using rbd_localization::StateVector;
using namespace rbd_localization;  // NOLINT: StateMember* enumerators

namespace {

Measurement poseMeasurement(double t, double x, double y, double yaw, double var) {
  Measurement m;
  m.time = t;
  m.values(StateMemberX) = x;
  m.values(StateMemberY) = y;
  m.values(StateMemberYaw) = yaw;
  m.covariance = StateMatrix::Identity() * var;
  m.update_vector[StateMemberX] = m.update_vector[StateMemberY] = m.update_vector[StateMemberYaw] = true;
  m.source = "pose";
  return m;
}

bool symmetricPsd(const StateMatrix& p) {
  if ((p - p.transpose()).cwiseAbs().maxCoeff() > 1e-9) return false;
  Eigen::SelfAdjointEigenSolver<StateMatrix> es(p);
  return es.eigenvalues().minCoeff() > -1e-9;
}

}  // namespace

TEST(Ekf, WrapAngle) {
  EXPECT_NEAR(wrapAngle(3 * M_PI / 2), -M_PI / 2, 1e-12);
  EXPECT_NEAR(wrapAngle(-3 * M_PI / 2), M_PI / 2, 1e-12);
  EXPECT_NEAR(wrapAngle(7 * M_PI + 0.1), -M_PI + 0.1, 1e-9);
  EXPECT_NEAR(wrapAngle(0.3), 0.3, 1e-15);
}

TEST(Ekf, ConstantVelocityPropagatesInWorldFrame) {
  Ekf ekf;
  StateVector x = StateVector::Zero();
  x(StateMemberYaw) = M_PI / 2;  // facing +y
  x(StateMemberVx) = 1.0;        // body-forward 1 m/s
  x(StateMemberVyaw) = 0.0;
  ekf.setState(x, 0.0);
  for (int i = 0; i < 100; ++i) ekf.predict(0.02);
  EXPECT_NEAR(ekf.state()(StateMemberX), 0.0, 1e-9);
  EXPECT_NEAR(ekf.state()(StateMemberY), 2.0, 1e-9);
  EXPECT_NEAR(ekf.state()(StateMemberVx), 1.0, 1e-12);
  EXPECT_NEAR(ekf.lastUpdateTime(), 2.0, 1e-9);
}

TEST(Ekf, CircleAtConstantBodyVelocityNeedsOnlyTheCentripetalAcceleration) {
  // On a circle the body-frame velocity is constant while the accelerometer sees V*W sideways;
  // the model's a - w x v keeps v_body constant and the robot on the circle.
  const double v = 0.3, w = 0.25;
  Ekf ekf;
  StateVector x = StateVector::Zero();
  x(StateMemberVx) = v;
  x(StateMemberVyaw) = w;
  x(StateMemberAy) = v * w;
  ekf.setState(x, 0.0);
  for (int i = 0; i < 2000; ++i) ekf.predict(0.005);  // 10 s
  const double yaw = w * 10.0;
  EXPECT_NEAR(ekf.state()(StateMemberVx), v, 1e-6);
  EXPECT_NEAR(ekf.state()(StateMemberVy), 0.0, 1e-6);
  EXPECT_NEAR(ekf.state()(StateMemberX), v / w * std::sin(yaw), 5e-3);  // Euler steps: ~1 mm
  EXPECT_NEAR(ekf.state()(StateMemberY), v / w * (1 - std::cos(yaw)), 5e-3);
}

TEST(Ekf, ConstantAccelerationAndTurnRate) {
  Ekf ekf;
  StateVector x = StateVector::Zero();
  x(StateMemberAx) = 0.5;
  ekf.setState(x, 0.0);
  for (int i = 0; i < 1000; ++i) ekf.predict(0.002);
  EXPECT_NEAR(ekf.state()(StateMemberVx), 1.0, 1e-9);
  EXPECT_NEAR(ekf.state()(StateMemberX), 0.5 * 0.5 * 4.0, 1e-9);

  Ekf turn;
  StateVector y = StateVector::Zero();
  y(StateMemberVyaw) = 0.5;
  turn.setState(y, 0.0);
  for (int i = 0; i < 100; ++i) turn.predict(0.1);  // 5 rad: wraps past pi
  EXPECT_NEAR(turn.state()(StateMemberYaw), wrapAngle(5.0), 1e-9);
  EXPECT_LT(std::fabs(turn.state()(StateMemberYaw)), M_PI + 1e-12);
}

TEST(Ekf, AnalyticJacobianMatchesFiniteDifferences) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  StateVector x0;
  for (int i = 0; i < STATE_SIZE; ++i) x0(i) = u(rng);
  const double dt = 0.05;
  Ekf ekf;
  ekf.setState(x0, 0.0);
  const StateMatrix f = ekf.transferJacobian(dt);
  const double h = 1e-6;
  for (int j = 0; j < STATE_SIZE; ++j) {
    Ekf plus, minus;
    StateVector xp = x0, xm = x0;
    xp(j) += h;
    xm(j) -= h;
    plus.setState(xp, 0.0);
    minus.setState(xm, 0.0);
    plus.predict(dt);
    minus.predict(dt);
    StateVector diff = plus.state() - minus.state();
    for (int i = 3; i < 6; ++i) diff(i) = wrapAngle(diff(i));
    const StateVector numeric = diff / (2 * h);
    for (int i = 0; i < STATE_SIZE; ++i)
      EXPECT_NEAR(f(i, j), numeric(i), 1e-6) << "F(" << i << "," << j << ")";
  }
}

TEST(Ekf, FullCovarianceUpdateEqualsMeasurementWhenPriorIsVague) {
  Ekf ekf;
  ekf.setState(StateVector::Zero(), 0.0);
  ekf.setCovariance(StateMatrix::Identity() * 1e6);
  Measurement m;
  m.time = 0.0;
  for (int i = 0; i < STATE_SIZE; ++i) {
    m.update_vector[i] = true;
    m.values(i) = 0.1 * (i + 1) * (i % 2 ? -1 : 1);
  }
  // Off-diagonal terms too: a full covariance.
  Eigen::Matrix<double, STATE_SIZE, STATE_SIZE> l =
      Eigen::Matrix<double, STATE_SIZE, STATE_SIZE>::Identity() * 0.01;
  l(4, 1) = 0.003;
  l(10, 7) = -0.002;
  m.covariance = l * l.transpose();
  ASSERT_EQ(ekf.correct(m), CorrectResult::kAccepted);
  for (int i = 0; i < STATE_SIZE; ++i) EXPECT_NEAR(ekf.state()(i), wrapAngle(m.values(i)), 1e-6) << i;
  // Posterior covariance ~ the measurement's.
  EXPECT_LT((ekf.covariance() - m.covariance).cwiseAbs().maxCoeff(), 1e-7);
}

TEST(Ekf, PartialUpdateTouchesOnlyCorrelatedMembers) {
  Ekf ekf;
  ekf.setState(StateVector::Zero(), 0.0);
  ekf.setCovariance(StateMatrix::Identity());
  ASSERT_EQ(ekf.correct(poseMeasurement(0.0, 1.0, 0.0, 0.0, 1.0)), CorrectResult::kAccepted);
  EXPECT_NEAR(ekf.state()(StateMemberX), 0.5, 1e-12);  // equal weights
  EXPECT_NEAR(ekf.covariance()(StateMemberX, StateMemberX), 0.5, 1e-12);
  EXPECT_NEAR(ekf.state()(StateMemberZ), 0.0, 1e-15);
  EXPECT_NEAR(ekf.covariance()(StateMemberZ, StateMemberZ), 1.0, 1e-15);
}

TEST(Ekf, GatingRejectsTenSigmaJump) {
  Ekf ekf;
  ekf.setState(StateVector::Zero(), 0.0);
  ekf.setCovariance(StateMatrix::Identity() * 0.01);  // prior sigma 0.1
  // Innovation covariance 0.01 + 0.01 = 0.02 -> sigma 0.1414; a 1.414 m jump is 10 sigma.
  Measurement jump = poseMeasurement(0.0, 10.0 * std::sqrt(0.02), 0.0, 0.0, 0.01);
  jump.mahalanobis_threshold = 5.0;
  const StateVector before = ekf.state();
  const StateMatrix cov_before = ekf.covariance();
  EXPECT_EQ(ekf.correct(jump), CorrectResult::kRejected);
  EXPECT_NEAR(ekf.lastSquaredMahalanobis(), 100.0, 1e-6);
  EXPECT_EQ(ekf.state(), before);
  EXPECT_EQ(ekf.covariance(), cov_before);
  // A 2 sigma measurement passes the same gate.
  Measurement near = poseMeasurement(0.0, 2.0 * std::sqrt(0.02), 0.0, 0.0, 0.01);
  near.mahalanobis_threshold = 5.0;
  EXPECT_EQ(ekf.correct(near), CorrectResult::kAccepted);
  EXPECT_GT(ekf.state()(StateMemberX), 0.1);
  // Without a gate (r_l default: max double) the jump is fused.
  Measurement ungated = poseMeasurement(0.0, 2.0, 0.0, 0.0, 0.01);
  EXPECT_EQ(ekf.correct(ungated), CorrectResult::kAccepted);
}

TEST(Ekf, AngleInnovationWrapsAcrossPi) {
  Ekf ekf;
  StateVector x = StateVector::Zero();
  x(StateMemberYaw) = M_PI - 0.05;
  ekf.setState(x, 0.0);
  ekf.setCovariance(StateMatrix::Identity() * 0.01);
  // Measured just across the seam: the true difference is +0.1 rad, not -2pi + 0.1.
  Measurement m = poseMeasurement(0.0, 0.0, 0.0, -M_PI + 0.05, 0.01);
  m.mahalanobis_threshold = 3.0;  // a 2pi innovation would be rejected
  ASSERT_EQ(ekf.correct(m), CorrectResult::kAccepted);
  const double yaw = ekf.state()(StateMemberYaw);
  EXPECT_GT(std::fabs(yaw), M_PI - 0.01);  // near the seam, between the two values
  EXPECT_NEAR(wrapAngle(yaw - (M_PI - 0.05)), 0.05, 1e-9);
  EXPECT_GE(yaw, -M_PI);
  EXPECT_LT(yaw, M_PI);
}

TEST(Ekf, TwoDModeHoldsOutOfPlaneMembersAtZero) {
  Ekf ekf;
  ekf.setTwoDMode(true);
  StateVector x = StateVector::Zero();
  x(StateMemberZ) = 1.0;
  x(StateMemberPitch) = 0.3;
  x(StateMemberVx) = 1.0;
  x(StateMemberVz) = 1.0;
  x(StateMemberVpitch) = 0.2;
  ekf.setState(x, 0.0);
  EXPECT_EQ(ekf.state()(StateMemberZ), 0.0);
  EXPECT_EQ(ekf.state()(StateMemberPitch), 0.0);
  ekf.setCovariance(StateMatrix::Identity());
  for (int i = 0; i < 10; ++i) ekf.predict(0.1);
  EXPECT_NEAR(ekf.state()(StateMemberX), 1.0, 1e-9);
  EXPECT_EQ(ekf.state()(StateMemberZ), 0.0);
  // z / roll measurements are ignored; x is still fused.
  Measurement m;
  m.update_vector[StateMemberZ] = m.update_vector[StateMemberRoll] = true;
  m.values(StateMemberZ) = 3.0;
  m.values(StateMemberRoll) = 0.5;
  EXPECT_EQ(ekf.correct(m), CorrectResult::kInvalid);
  m.update_vector[StateMemberX] = true;
  m.values(StateMemberX) = 1.5;
  EXPECT_EQ(ekf.correct(m), CorrectResult::kAccepted);
  EXPECT_EQ(ekf.state()(StateMemberZ), 0.0);
  EXPECT_EQ(ekf.state()(StateMemberRoll), 0.0);
  EXPECT_GT(ekf.state()(StateMemberX), 1.0);
  // Without planar mode, z moves.
  Ekf full;
  full.setState(x, 0.0);
  full.predict(1.0);
  // Body displacement u = v + (a - w x v)/2 = (0.9, 0, 1.1) for w = (0, 0.2, 0), v = (1, 0, 1).
  EXPECT_NEAR(full.state()(StateMemberZ), 1.0 - std::sin(0.3) * 0.9 + std::cos(0.3) * 1.1, 1e-9);
}

TEST(Ekf, CovarianceStaysSymmetricPsdOverLongRandomRun) {
  std::mt19937 rng(42);
  std::normal_distribution<double> n(0.0, 1.0);
  Ekf ekf;
  StateMatrix q = StateMatrix::Identity() * 0.01;
  ekf.setProcessNoiseCovariance(q);
  ekf.setInitialEstimateCovariance(StateMatrix::Identity() * 1e-3);
  ekf.setState(StateVector::Zero(), 0.0);
  double t = 0.0;
  for (int k = 0; k < 3000; ++k) {
    t += 0.002;
    Measurement imu;
    imu.time = t;
    for (int i = StateMemberVroll; i <= StateMemberAz; ++i) {
      imu.update_vector[i] = true;
      imu.values(i) = 0.3 * n(rng);
    }
    imu.covariance = StateMatrix::Identity() * 1e-4;
    ASSERT_NE(ekf.processMeasurement(imu), CorrectResult::kInvalid);
    if (k % 33 == 0) {
      Measurement pose = poseMeasurement(t, n(rng), n(rng), M_PI * n(rng), 1e-6);
      pose.covariance(StateMemberX, StateMemberY) = pose.covariance(StateMemberY, StateMemberX) = 5e-7;
      ekf.processMeasurement(pose);
    }
    if (k % 500 == 0) {
      ASSERT_TRUE(symmetricPsd(ekf.covariance())) << "step " << k;
    }
  }
  EXPECT_TRUE(symmetricPsd(ekf.covariance()));
  EXPECT_TRUE(ekf.state().allFinite());
}

TEST(Ekf, ProcessNoiseScalesWithDt) {
  Ekf a, b;
  StateMatrix q = StateMatrix::Zero();
  q(StateMemberVx, StateMemberVx) = 0.5;
  for (Ekf* e : {&a, &b}) {
    e->setProcessNoiseCovariance(q);
    e->setState(StateVector::Zero(), 0.0);
    e->setCovariance(StateMatrix::Zero());
  }
  a.predict(0.1);
  b.predict(0.2);
  EXPECT_NEAR(a.covariance()(StateMemberVx, StateMemberVx), 0.05, 1e-12);
  EXPECT_NEAR(b.covariance()(StateMemberVx, StateMemberVx), 0.10, 1e-12);
}

TEST(Ekf, FirstMeasurementInitialisesAndInvalidInputIsRefused) {
  Ekf ekf;
  std::ostringstream log;
  ekf.setDebug(true, &log);
  EXPECT_FALSE(ekf.initialized());
  Measurement bad = poseMeasurement(1.0, NAN, 0.0, 0.0, 0.1);
  EXPECT_EQ(ekf.processMeasurement(bad), CorrectResult::kInvalid);
  EXPECT_FALSE(ekf.initialized());
  EXPECT_EQ(ekf.processMeasurement(poseMeasurement(1.0, 2.0, 3.0, 0.5, 0.1)), CorrectResult::kAccepted);
  EXPECT_TRUE(ekf.initialized());
  EXPECT_DOUBLE_EQ(ekf.state()(StateMemberX), 2.0);
  EXPECT_DOUBLE_EQ(ekf.covariance()(StateMemberX, StateMemberX), 0.1);
  Measurement inf = poseMeasurement(2.0, INFINITY, 0.0, 0.0, 0.1);
  EXPECT_EQ(ekf.processMeasurement(inf), CorrectResult::kInvalid);
  EXPECT_TRUE(ekf.state().allFinite());
  EXPECT_NE(log.str().find("non-finite"), std::string::npos);
  ekf.reset();
  EXPECT_FALSE(ekf.initialized());
}

TEST(Ekf, ImuRatesAndPoseFuseToTruth) {
  // Robot turning on a circle; the filter hears noisy yaw rate + forward accel (zero) and
  // a 15 Hz pose. The estimate must follow the truth.
  std::mt19937 rng(3);
  std::normal_distribution<double> n(0.0, 1.0);
  Ekf ekf;
  StateMatrix q = StateMatrix::Identity() * 1e-3;
  ekf.setProcessNoiseCovariance(q);
  ekf.setInitialEstimateCovariance(StateMatrix::Identity() * 1e-2);
  ekf.setTwoDMode(true);
  const double v = 0.3, w = 0.3;
  double t = 0.0;
  int accepted = 0;
  for (int k = 1; k <= 5000; ++k) {  // 10 s at 500 Hz
    t = k * 0.002;
    Measurement imu;
    imu.time = t;
    imu.update_vector[StateMemberVyaw] = true;
    imu.values(StateMemberVyaw) = w + 0.01 * n(rng);
    imu.covariance = StateMatrix::Identity() * 1e-4;
    ekf.processMeasurement(imu);
    if (k % 33 == 0) {
      const double yaw = w * t;
      Measurement p = poseMeasurement(t, v / w * std::sin(yaw) + 0.01 * n(rng),
                                      v / w * (1 - std::cos(yaw)) + 0.01 * n(rng), wrapAngle(yaw), 1e-4);
      p.update_vector[StateMemberVx] = p.update_vector[StateMemberVy] = true;
      p.values(StateMemberVx) = v;
      p.values(StateMemberVy) = 0.0;
      p.mahalanobis_threshold = 5.0;
      if (ekf.processMeasurement(p) == CorrectResult::kAccepted) ++accepted;
    }
  }
  const double yaw = w * t;
  EXPECT_NEAR(ekf.state()(StateMemberX), v / w * std::sin(yaw), 0.03);
  EXPECT_NEAR(ekf.state()(StateMemberY), v / w * (1 - std::cos(yaw)), 0.03);
  EXPECT_NEAR(wrapAngle(ekf.state()(StateMemberYaw) - yaw), 0.0, 0.02);
  EXPECT_GT(accepted, 140);
}

TEST(Ekf, UpdateMatchesTheTextbookKalmanFormForEveryMeasurementSize) {
  // x' = x + K (z - H x), P' = (I - K H) P (I - K H)^T + K R K^T with K = P H^T (H P H^T + R)^-1,
  // computed here with dense H; sizes 3 and 6 take the fixed-size path, 4 and 9 the dynamic one.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (const std::vector<int>& members : std::vector<std::vector<int>>{
           {9, 10, 11}, {0, 1, 2, 3, 4, 5}, {0, 1, 6, 11}, {3, 4, 5, 9, 10, 11, 12, 13, 14}}) {
    const int m = static_cast<int>(members.size());
    Eigen::Matrix<double, STATE_SIZE, STATE_SIZE> a;
    for (int i = 0; i < STATE_SIZE * STATE_SIZE; ++i) a(i) = u(rng);
    const StateMatrix p = a * a.transpose() + StateMatrix::Identity() * 0.1;
    StateVector x;
    for (int i = 0; i < STATE_SIZE; ++i) x(i) = 0.1 * u(rng);  // angles far from the wrap
    Ekf ekf;
    ekf.setState(x, 0.0);
    ekf.setCovariance(p);
    Measurement meas;
    meas.time = 0.0;
    Eigen::MatrixXd b(m, m);
    for (int i = 0; i < m * m; ++i) b(i) = u(rng);
    const Eigen::MatrixXd r = b * b.transpose() + Eigen::MatrixXd::Identity(m, m) * 0.05;
    Eigen::MatrixXd h = Eigen::MatrixXd::Zero(m, STATE_SIZE);
    Eigen::VectorXd z(m);
    for (int k = 0; k < m; ++k) {
      h(k, members[k]) = 1.0;
      z(k) = x(members[k]) + 0.2 * u(rng);
      meas.values(members[k]) = z(k);
      meas.update_vector[members[k]] = true;
      for (int c = 0; c < m; ++c) meas.covariance(members[k], members[c]) = r(k, c);
    }
    ASSERT_EQ(ekf.correct(meas), CorrectResult::kAccepted) << m;
    const Eigen::MatrixXd pd = p;
    const Eigen::MatrixXd k = pd * h.transpose() * (h * pd * h.transpose() + r).inverse();
    const Eigen::VectorXd x_expected = Eigen::VectorXd(x) + k * (z - h * Eigen::VectorXd(x));
    const Eigen::MatrixXd i_kh = Eigen::MatrixXd::Identity(STATE_SIZE, STATE_SIZE) - k * h;
    const Eigen::MatrixXd p_expected = i_kh * pd * i_kh.transpose() + k * r * k.transpose();
    EXPECT_LT((Eigen::VectorXd(ekf.state()) - x_expected).cwiseAbs().maxCoeff(), 1e-9) << m;
    EXPECT_LT((Eigen::MatrixXd(ekf.covariance()) - p_expected).cwiseAbs().maxCoeff(), 1e-9) << m;
  }
}

TEST(Ekf, InitialStateFillsWhatTheFirstMeasurementDoesNotSet) {
  Ekf ekf;
  StateVector x0 = StateVector::Zero();
  x0(StateMemberZ) = 0.3;
  x0(StateMemberYaw) = 1.0;
  x0(StateMemberVx) = 0.2;
  ekf.setInitialState(x0);
  EXPECT_FALSE(ekf.initialized());
  EXPECT_EQ(ekf.processMeasurement(poseMeasurement(1.0, 2.0, 3.0, -0.5, 0.01)), CorrectResult::kAccepted);
  EXPECT_EQ(ekf.state()(StateMemberX), 2.0);
  EXPECT_EQ(ekf.state()(StateMemberYaw), -0.5);  // measured
  EXPECT_EQ(ekf.state()(StateMemberZ), 0.3);     // from initial_state
  EXPECT_EQ(ekf.state()(StateMemberVx), 0.2);
  ekf.reset();
  EXPECT_EQ(ekf.state(), x0);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
