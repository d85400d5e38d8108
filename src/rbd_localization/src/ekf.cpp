#include "rbd_localization/ekf.h"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <cmath>

namespace rbd_localization {

namespace {

using Mat3 = Eigen::Matrix3d;
using Vec3 = Eigen::Vector3d;
using Rows3 = Eigen::Matrix<double, 3, STATE_SIZE>;

constexpr double kMinVariance = 1e-9;
constexpr double kMinCosPitch = 1e-6;

// The members planar mode holds at zero.
constexpr std::array<int, 7> kTwoDMembers = {{StateMemberZ, StateMemberRoll, StateMemberPitch, StateMemberVz,
                                              StateMemberVroll, StateMemberVpitch, StateMemberAz}};

bool isTwoDMember(int index) {
  for (int m : kTwoDMembers) {
    if (m == index) return true;
  }
  return false;
}

// Blocks of the motion model's Jacobian F at one state for one step dt. Row blocks that
// differ from identity are position (0-2), orientation (3-5) and linear velocity (6-8):
//   c = a - w x v  (body-frame velocity change: the accelerometer also sees the centripetal
//                   term of a rotating body, e.g. V*W sideways on a circle at constant v)
//   p' = p + R(e) (v dt + c dt^2 / 2)   e' = e + T(e) w dt   v' = v + c dt
// (r_l uses v' = v + a dt, which drifts sideways on every turn between pose updates.)
struct ModelBlocks {
  Mat3 rot;         // R(e) body -> world, R = Rz(yaw) Ry(pitch) Rx(roll)
  Mat3 d_pos_d_e;   // d p' / d e
  Mat3 d_u_d_v;     // d u / d v with u = v dt + c dt^2/2 (body-frame displacement)
  Mat3 d_u_d_w;     // d u / d w
  Mat3 d_v_d_v;     // d v' / d v = I - [w]x dt
  Mat3 d_v_d_w;     // d v' / d w = [v]x dt
  Vec3 vel_step;    // c dt
  Mat3 euler_rate;  // T(e): body rates -> Euler angle rates
  Mat3 d_e_d_e;     // d e' / d e (identity + dT/de w dt)
  Vec3 pos_step;    // R (v dt + a dt^2/2)
  Vec3 euler_step;  // T w dt
};

ModelBlocks modelBlocks(const StateVector& x, double dt) {
  const double cr = std::cos(x(StateMemberRoll)), sr = std::sin(x(StateMemberRoll));
  const double cp = std::cos(x(StateMemberPitch)), sp = std::sin(x(StateMemberPitch));
  const double cy = std::cos(x(StateMemberYaw)), sy = std::sin(x(StateMemberYaw));
  Mat3 rx, ry, rz, drx, dry, drz;
  rx << 1, 0, 0, 0, cr, -sr, 0, sr, cr;
  ry << cp, 0, sp, 0, 1, 0, -sp, 0, cp;
  rz << cy, -sy, 0, sy, cy, 0, 0, 0, 1;
  drx << 0, 0, 0, 0, -sr, -cr, 0, cr, -sr;
  dry << -sp, 0, cp, 0, 0, 0, -cp, 0, -sp;
  drz << -sy, -cy, 0, cy, -sy, 0, 0, 0, 0;

  ModelBlocks b;
  const Mat3 rzy = rz * ry;
  b.rot = rzy * rx;
  const Vec3 v = x.segment<3>(POSITION_V_OFFSET);
  const Vec3 a = x.segment<3>(POSITION_A_OFFSET);
  const Vec3 w = x.segment<3>(ORIENTATION_V_OFFSET);
  const Vec3 c = a - w.cross(v);
  const Vec3 u = v * dt + c * (0.5 * dt * dt);
  Mat3 wx, vx;  // skew-symmetric cross-product matrices
  wx << 0, -w(2), w(1), w(2), 0, -w(0), -w(1), w(0), 0;
  vx << 0, -v(2), v(1), v(2), 0, -v(0), -v(1), v(0), 0;
  b.d_v_d_v = Mat3::Identity() - wx * dt;
  b.d_v_d_w = vx * dt;
  b.d_u_d_v = Mat3::Identity() * dt - wx * (0.5 * dt * dt);
  b.d_u_d_w = vx * (0.5 * dt * dt);
  b.vel_step = c * dt;
  b.pos_step = b.rot * u;
  b.d_pos_d_e.col(0) = rzy * (drx * u);
  b.d_pos_d_e.col(1) = rz * (dry * (rx * u));
  b.d_pos_d_e.col(2) = drz * (ry * (rx * u));

  // Keep T finite near +-90 deg pitch (gimbal lock): clamp cos(pitch) away from zero.
  const double cpc = std::fabs(cp) < kMinCosPitch ? std::copysign(kMinCosPitch, cp) : cp;
  const double tp = sp / cpc;
  const double sec = 1.0 / cpc;
  b.euler_rate << 1, sr * tp, cr * tp, 0, cr, -sr, 0, sr * sec, cr * sec;
  b.euler_step = b.euler_rate * w * dt;
  Mat3 dt_droll, dt_dpitch;
  dt_droll << 0, cr * tp, -sr * tp, 0, -sr, -cr, 0, cr * sec, -sr * sec;
  dt_dpitch << 0, sr * sec * sec, cr * sec * sec, 0, 0, 0, 0, sr * tp * sec, cr * tp * sec;
  b.d_e_d_e.setIdentity();
  b.d_e_d_e.col(0) += dt_droll * w * dt;
  b.d_e_d_e.col(1) += dt_dpitch * w * dt;
  return b;
}

// Rows of F * M for the three non-identity row blocks, M given with STATE_SIZE rows.
void applyTransfer(const ModelBlocks& b, double dt, const StateMatrix& m, StateMatrix* out) {
  *out = m;
  // Small fixed-size products: lazyProduct keeps them coefficient-based (no GEMM set-up).
  const Mat3 rot_duv = b.rot * b.d_u_d_v;
  const Mat3 rot_duw = b.rot * b.d_u_d_w;
  const Mat3 rot_hdt2 = b.rot * (0.5 * dt * dt);
  const Mat3 euler_dt = b.euler_rate * dt;
  const Rows3 pos = m.middleRows<3>(POSITION_OFFSET) +
                    b.d_pos_d_e.lazyProduct(m.middleRows<3>(ORIENTATION_OFFSET)) +
                    rot_duv.lazyProduct(m.middleRows<3>(POSITION_V_OFFSET)) +
                    rot_duw.lazyProduct(m.middleRows<3>(ORIENTATION_V_OFFSET)) +
                    rot_hdt2.lazyProduct(m.middleRows<3>(POSITION_A_OFFSET));
  const Rows3 ori = b.d_e_d_e.lazyProduct(m.middleRows<3>(ORIENTATION_OFFSET)) +
                    euler_dt.lazyProduct(m.middleRows<3>(ORIENTATION_V_OFFSET));
  const Rows3 vel = b.d_v_d_v.lazyProduct(m.middleRows<3>(POSITION_V_OFFSET)) +
                    b.d_v_d_w.lazyProduct(m.middleRows<3>(ORIENTATION_V_OFFSET)) +
                    dt * m.middleRows<3>(POSITION_A_OFFSET);
  out->middleRows<3>(POSITION_V_OFFSET) = vel;
  out->middleRows<3>(POSITION_OFFSET) = pos;
  out->middleRows<3>(ORIENTATION_OFFSET) = ori;
}

}  // namespace

double wrapAngle(double angle) {
  if (angle >= -M_PI && angle < M_PI) return angle;
  angle = std::fmod(angle + M_PI, 2.0 * M_PI);
  if (angle < 0.0) angle += 2.0 * M_PI;
  return angle - M_PI;
}

Measurement::Measurement()
    : time(0.0),
      values(StateVector::Zero()),
      covariance(StateMatrix::Identity()),
      mahalanobis_threshold(std::numeric_limits<double>::max()) {
  update_vector.fill(false);
}

Ekf::Ekf()
    : state_(StateVector::Zero()),
      initial_state_(StateVector::Zero()),
      covariance_(StateMatrix::Identity() * 1e-9),
      initial_covariance_(StateMatrix::Identity() * 1e-9),
      process_noise_(StateMatrix::Identity() * 0.01),
      initialized_(false),
      two_d_mode_(false),
      debug_(false),
      debug_stream_(nullptr),
      last_update_time_(0.0),
      last_squared_mahalanobis_(0.0) {}

void Ekf::setProcessNoiseCovariance(const StateMatrix& q) { process_noise_ = q; }

void Ekf::setInitialEstimateCovariance(const StateMatrix& p0) {
  initial_covariance_ = p0;
  if (!initialized_) covariance_ = p0;
}

void Ekf::setInitialState(const StateVector& x0) {
  initial_state_ = x0;
  if (!initialized_) {
    state_ = x0;
    wrapStateAngles();
    if (two_d_mode_) enforceTwoD();
  }
}

void Ekf::setTwoDMode(bool enabled) {
  two_d_mode_ = enabled;
  if (two_d_mode_) enforceTwoD();
}

void Ekf::setDebug(bool enabled, std::ostream* stream) {
  debug_ = enabled;
  debug_stream_ = stream;
}

void Ekf::reset() {
  state_ = initial_state_;
  covariance_ = initial_covariance_;
  initialized_ = false;
  last_update_time_ = 0.0;
  last_squared_mahalanobis_ = 0.0;
}

void Ekf::setState(const StateVector& state, double time) {
  state_ = state;
  wrapStateAngles();
  if (two_d_mode_) enforceTwoD();
  initialized_ = true;
  last_update_time_ = time;
}

void Ekf::setCovariance(const StateMatrix& covariance) {
  covariance_ = covariance;
  if (two_d_mode_) enforceTwoD();
}

StateMatrix Ekf::transferJacobian(double dt) const {
  const ModelBlocks b = modelBlocks(state_, dt);
  StateMatrix f;
  applyTransfer(b, dt, StateMatrix::Identity(), &f);
  return f;
}

void Ekf::predict(double dt) {
  if (!(dt > 0.0)) return;
  const ModelBlocks b = modelBlocks(state_, dt);

  // P' = F P F^T + Q dt, using F's block structure: (F (F P)^T)^T.
  StateMatrix fp, fpft;
  applyTransfer(b, dt, covariance_, &fp);
  applyTransfer(b, dt, fp.transpose(), &fpft);
  covariance_ = fpft.transpose();
  covariance_.noalias() += process_noise_ * dt;
  for (int i = 0; i < STATE_SIZE; ++i) {
    for (int j = i + 1; j < STATE_SIZE; ++j) {
      const double v = 0.5 * (covariance_(i, j) + covariance_(j, i));
      covariance_(i, j) = covariance_(j, i) = v;
    }
  }

  // State after the Jacobian was taken at the prior state.
  state_.segment<3>(POSITION_OFFSET) += b.pos_step;
  state_.segment<3>(ORIENTATION_OFFSET) += b.euler_step;
  state_.segment<3>(POSITION_V_OFFSET) += b.vel_step;
  wrapStateAngles();
  if (two_d_mode_) enforceTwoD();
  last_update_time_ += dt;

  if (debugOn()) {
    *debug_stream_ << "predict dt=" << dt << " state=" << state_.transpose() << "\n";
  }
}

void Ekf::predictTo(double time) {
  if (!initialized_) {
    last_update_time_ = time;
    return;
  }
  predict(time - last_update_time_);
}

CorrectResult Ekf::correct(const Measurement& meas) {
  // Indices this update uses (planar mode drops the members it holds at zero).
  std::array<int, STATE_SIZE> idx;
  int m = 0;
  for (int i = 0; i < STATE_SIZE; ++i) {
    if (!meas.update_vector[i] || (two_d_mode_ && isTwoDMember(i))) continue;
    if (!std::isfinite(meas.values(i))) {
      if (debugOn())
        *debug_stream_ << "reject " << meas.source << ": non-finite value at index " << i << "\n";
      return CorrectResult::kInvalid;
    }
    idx[m++] = i;
  }
  // Fixed sizes for the common cases (IMU rates / accelerations: 3, planar pose: 3, 6-D pose: 6)
  // let Eigen unroll the small products; anything else goes through the bounded dynamic path.
  switch (m) {
    case 0:
      return CorrectResult::kInvalid;
    case 3:
      return correctSubset<3>(meas, idx);
    case 6:
      return correctSubset<6>(meas, idx);
    default:
      return correctSubset<Eigen::Dynamic>(meas, idx, m);
  }
}

template <int M>
CorrectResult Ekf::correctSubset(const Measurement& meas, const std::array<int, STATE_SIZE>& idx, int m_dyn) {
  constexpr int kMax = M == Eigen::Dynamic ? STATE_SIZE : M;
  using VecM = Eigen::Matrix<double, M, 1, 0, kMax, 1>;
  using MatM = Eigen::Matrix<double, M, M, 0, kMax, kMax>;
  using MatNM = Eigen::Matrix<double, STATE_SIZE, M, 0, STATE_SIZE, kMax>;
  const int m = M == Eigen::Dynamic ? m_dyn : M;

  VecM innovation(m);
  MatM r(m, m);
  MatM s(m, m);
  MatNM pht(STATE_SIZE, m);  // P H^T: the measured columns of P
  for (int a = 0; a < m; ++a) {
    const int i = idx[a];
    double d = meas.values(i) - state_(i);
    if (isAngleMember(i)) d = wrapAngle(d);
    innovation(a) = d;
    pht.col(a) = covariance_.col(i);
    for (int c = 0; c < m; ++c) {
      const double rv = meas.covariance(i, idx[c]);
      if (!std::isfinite(rv)) return CorrectResult::kInvalid;
      r(a, c) = rv;
      s(a, c) = covariance_(i, idx[c]);
    }
    // A zero or negative variance would make the update singular: floor it.
    if (r(a, a) < kMinVariance) r(a, a) = kMinVariance;
  }
  s += r;

  const Eigen::LLT<MatM> llt(s);
  if (llt.info() != Eigen::Success) {
    if (debugOn()) *debug_stream_ << "reject " << meas.source << ": innovation covariance not PD\n";
    return CorrectResult::kInvalid;
  }
  // S^-1 explicitly: a fixed 3x3/6x6 inverse is a short unrolled computation, while solving for
  // a matrix right-hand side (K = P H^T S^-1) goes through Eigen's general blocked
  // triangular solver (its packing and blocking set-up cost more than the whole update).
  MatM s_inv(m, m);
  if (M == Eigen::Dynamic) {
    s_inv = llt.solve(MatM::Identity(m, m));
  } else {
    s_inv = s.inverse();
  }
  s_inv = (0.5 * (s_inv + s_inv.transpose())).eval();
  const VecM s_inv_innov = s_inv * innovation;
  last_squared_mahalanobis_ = innovation.dot(s_inv_innov);
  const double gate = meas.mahalanobis_threshold;
  if (gate < std::sqrt(std::numeric_limits<double>::max()) && last_squared_mahalanobis_ > gate * gate) {
    if (debugOn()) {
      *debug_stream_ << "reject " << meas.source << ": squared Mahalanobis " << last_squared_mahalanobis_
                     << " > " << gate * gate << "\n";
    }
    return CorrectResult::kRejected;
  }

  // K = P H^T S^-1.
  const MatNM k = pht.lazyProduct(s_inv);
  state_.noalias() += k * innovation;

  // Joseph form P' = (I - K H) P (I - K H)^T + K R K^T with H = rows idx of the identity:
  //   A = (I - K H) P = P - K (P H^T)^T
  //   P' = A (I - K H)^T + K R K^T = A + (K R - A H^T) K^T
  StateMatrix a_mat = covariance_;
  a_mat.noalias() -= k.lazyProduct(pht.transpose());
  MatNM b = k * r;
  for (int c = 0; c < m; ++c) b.col(c) -= a_mat.col(idx[c]);
  covariance_ = a_mat;
  covariance_.noalias() += b.lazyProduct(k.transpose());
  // Keep exact symmetry against round-off.
  for (int i = 0; i < STATE_SIZE; ++i) {
    for (int j = i + 1; j < STATE_SIZE; ++j) {
      const double v = 0.5 * (covariance_(i, j) + covariance_(j, i));
      covariance_(i, j) = covariance_(j, i) = v;
    }
  }

  wrapStateAngles();
  if (two_d_mode_) enforceTwoD();
  if (debugOn()) {
    *debug_stream_ << "correct " << meas.source << " m=" << m << " state=" << state_.transpose() << "\n";
  }
  return CorrectResult::kAccepted;
}

CorrectResult Ekf::processMeasurement(const Measurement& meas) {
  if (!initialized_) {
    // Take the measured members as they are; keep the initial covariance elsewhere.
    bool any = false;
    for (int i = 0; i < STATE_SIZE; ++i) {
      if (!meas.update_vector[i]) continue;
      if (!std::isfinite(meas.values(i))) return CorrectResult::kInvalid;
      any = true;
    }
    if (!any) return CorrectResult::kInvalid;
    covariance_ = initial_covariance_;
    for (int i = 0; i < STATE_SIZE; ++i) {
      if (!meas.update_vector[i]) continue;
      state_(i) = meas.values(i);
      for (int j = 0; j < STATE_SIZE; ++j) {
        if (meas.update_vector[j]) covariance_(i, j) = meas.covariance(i, j);
      }
      if (covariance_(i, i) < kMinVariance) covariance_(i, i) = kMinVariance;
    }
    initialized_ = true;
    last_update_time_ = meas.time;
    wrapStateAngles();
    if (two_d_mode_) enforceTwoD();
    if (debugOn()) *debug_stream_ << "initialised from " << meas.source << "\n";
    return CorrectResult::kAccepted;
  }
  // Measurements older than the state are fused without predicting backwards.
  if (meas.time > last_update_time_) predict(meas.time - last_update_time_);
  return correct(meas);
}

void Ekf::enforceTwoD() {
  for (int i : kTwoDMembers) {
    state_(i) = 0.0;
    covariance_.row(i).setZero();
    covariance_.col(i).setZero();
    covariance_(i, i) = kMinVariance;
  }
}

void Ekf::wrapStateAngles() {
  for (int i = ORIENTATION_OFFSET; i < ORIENTATION_OFFSET + 3; ++i) state_(i) = wrapAngle(state_(i));
}

}  // namespace rbd_localization
