#include "rbd_localization/measurement_conversions.h"

#include <algorithm>
#include <cmath>

#include "rbd_localization/geometry.h"

namespace rbd_localization {

namespace {

Eigen::Matrix3d cov3(const boost::array<double, 9>& c) {
  Eigen::Matrix3d m;
  for (int r = 0; r < 3; ++r) {
    for (int k = 0; k < 3; ++k) m(r, k) = c[r * 3 + k];
  }
  return m;
}

bool anyOf(const std::array<bool, STATE_SIZE>& v, int first, int count) {
  for (int i = first; i < first + count; ++i) {
    if (v[i]) return true;
  }
  return false;
}

void setBlock(Measurement* m, int offset, const Eigen::Vector3d& value, const Eigen::Matrix3d& cov,
              const std::array<bool, STATE_SIZE>& cfg, int cfg_offset) {
  m->values.segment<3>(offset) = value;
  m->covariance.block<3, 3>(offset, offset) = cov;
  for (int i = 0; i < 3; ++i) m->update_vector[offset + i] = cfg[cfg_offset + i];
}

}  // namespace

bool fromMsg(const geometry_msgs::PoseWithCovariance& msg, PoseWithCov* out) {
  const auto& p = msg.pose.position;
  const auto& q = msg.pose.orientation;
  Eigen::Quaterniond quat(q.w, q.x, q.y, q.z);
  if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z) || !quat.coeffs().allFinite() ||
      quat.norm() < 1e-6) {
    return false;
  }
  out->pose = Eigen::Isometry3d::Identity();
  out->pose.linear() = quat.normalized().toRotationMatrix();
  out->pose.translation() = Eigen::Vector3d(p.x, p.y, p.z);
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) out->covariance(r, c) = msg.covariance[r * 6 + c];
  }
  return out->covariance.allFinite();
}

Matrix6d rotateCovariance(const Matrix6d& c, const Eigen::Matrix3d& r) {
  Matrix6d rot = Matrix6d::Zero();
  rot.topLeftCorner<3, 3>() = r;
  rot.bottomRightCorner<3, 3>() = r;
  return rot * c * rot.transpose();
}

Measurement poseMeasurement(const PoseWithCov& world_pose, const SensorConfig& cfg, double time) {
  Measurement m;
  m.time = time;
  m.source = cfg.name;
  m.mahalanobis_threshold = cfg.pose_rejection_threshold;
  m.values.segment<3>(POSITION_OFFSET) = world_pose.pose.translation();
  m.values.segment<3>(ORIENTATION_OFFSET) = rpyFromRotation(world_pose.pose.linear());
  m.covariance.topLeftCorner<6, 6>() = world_pose.covariance;
  for (int i = 0; i < 6; ++i) m.update_vector[i] = cfg.update_vector[i];
  return m;
}

bool differentialMeasurement(const PoseWithCov& previous, const PoseWithCov& current, double dt,
                             const SensorConfig& cfg, double time, Measurement* out) {
  if (!(dt > 0.0) || !anyOf(cfg.update_vector, 0, 6)) return false;
  const Eigen::Isometry3d delta = previous.pose.inverse() * current.pose;
  Measurement m;
  m.time = time;
  m.source = cfg.name;
  m.mahalanobis_threshold = cfg.pose_rejection_threshold;
  m.values.segment<3>(POSITION_V_OFFSET) = delta.translation() / dt;
  m.values.segment<3>(ORIENTATION_V_OFFSET) = rpyFromRotation(delta.linear()) / dt;
  Matrix6d world_cov;
  if (cfg.has_differential_noise) {
    // RoboDog: the increment's own uncertainty, i.e. twice the per-sample white noise plus what
    // the reported covariance grew by (the drift added between the samples); a relocalisation
    // shrinks the covariance and adds nothing.
    world_cov.setZero();
    for (int i = 0; i < 6; ++i) {
      const double n = cfg.differential_noise[static_cast<size_t>(i)];
      world_cov(i, i) = 2.0 * n * n + std::max(0.0, current.covariance(i, i) - previous.covariance(i, i));
    }
  } else {
    // r_l: both poses' uncertainty.
    world_cov = previous.covariance + current.covariance;
  }
  // Expressed in the previous body frame, over dt^2.
  const Matrix6d cov = rotateCovariance(world_cov, previous.pose.linear().transpose()) / (dt * dt);
  m.covariance.block<6, 6>(POSITION_V_OFFSET, POSITION_V_OFFSET) = cov;
  for (int i = 0; i < 6; ++i) m.update_vector[POSITION_V_OFFSET + i] = cfg.update_vector[i];
  *out = m;
  return true;
}

bool twistMeasurement(const geometry_msgs::TwistWithCovariance& msg, const Eigen::Matrix3d& base_from_frame,
                      const SensorConfig& cfg, double time, Measurement* out) {
  const Eigen::Vector3d v(msg.twist.linear.x, msg.twist.linear.y, msg.twist.linear.z);
  const Eigen::Vector3d w(msg.twist.angular.x, msg.twist.angular.y, msg.twist.angular.z);
  if (!v.allFinite() || !w.allFinite() || !anyOf(cfg.update_vector, POSITION_V_OFFSET, 6)) return false;
  Matrix6d c;
  for (int r = 0; r < 6; ++r) {
    for (int k = 0; k < 6; ++k) c(r, k) = msg.covariance[r * 6 + k];
  }
  if (!c.allFinite()) return false;
  Measurement m;
  m.time = time;
  m.source = cfg.name;
  m.mahalanobis_threshold = cfg.twist_rejection_threshold;
  m.values.segment<3>(POSITION_V_OFFSET) = base_from_frame * v;
  m.values.segment<3>(ORIENTATION_V_OFFSET) = base_from_frame * w;
  m.covariance.block<6, 6>(POSITION_V_OFFSET, POSITION_V_OFFSET) = rotateCovariance(c, base_from_frame);
  for (int i = POSITION_V_OFFSET; i < POSITION_V_OFFSET + 6; ++i) m.update_vector[i] = cfg.update_vector[i];
  *out = m;
  return true;
}

bool imuOrientationPose(const sensor_msgs::Imu& msg, const Eigen::Matrix3d& base_from_imu, PoseWithCov* out) {
  const auto& q = msg.orientation;
  const Eigen::Quaterniond quat(q.w, q.x, q.y, q.z);
  if (msg.orientation_covariance[0] == -1.0 || !quat.coeffs().allFinite() || quat.norm() < 1e-6) return false;
  const Eigen::Matrix3d c = cov3(msg.orientation_covariance);
  if (!c.allFinite()) return false;
  out->pose = Eigen::Isometry3d::Identity();
  out->pose.linear() = quat.normalized().toRotationMatrix() * base_from_imu.transpose();
  out->covariance.setIdentity();
  out->covariance.bottomRightCorner<3, 3>() = base_from_imu * c * base_from_imu.transpose();
  return true;
}

bool imuMeasurements(const sensor_msgs::Imu& msg, const Eigen::Matrix3d& base_from_imu,
                     const SensorConfig& cfg, const StateVector& state, double gravity, double time,
                     std::vector<Measurement>* out, std::string* reason) {
  const size_t first = out->size();
  const auto& q = msg.orientation;
  Eigen::Quaterniond quat(q.w, q.x, q.y, q.z);
  const bool orientation_valid =
      msg.orientation_covariance[0] != -1.0 && quat.coeffs().allFinite() && quat.norm() > 1e-6;
  Eigen::Matrix3d world_from_base;
  if (orientation_valid) {
    world_from_base = quat.normalized().toRotationMatrix() * base_from_imu.transpose();
  } else {
    world_from_base = rotationFromRpy(state(StateMemberRoll), state(StateMemberPitch), 0.0);
  }

  if (anyOf(cfg.update_vector, ORIENTATION_OFFSET, 3) && orientation_valid) {
    const Eigen::Matrix3d c = cov3(msg.orientation_covariance);
    if (!c.allFinite()) {
      *reason = "non-finite orientation covariance";
      out->resize(first);
      return false;
    }
    out->emplace_back();
    Measurement& m = out->back();
    m.time = time;
    m.source = cfg.name + "/rpy";
    m.mahalanobis_threshold = cfg.pose_rejection_threshold;
    setBlock(&m, ORIENTATION_OFFSET, rpyFromRotation(world_from_base),
             base_from_imu * c * base_from_imu.transpose(), cfg.update_vector, ORIENTATION_OFFSET);
  }

  if (anyOf(cfg.update_vector, ORIENTATION_V_OFFSET, 3) && msg.angular_velocity_covariance[0] != -1.0) {
    const Eigen::Vector3d w(msg.angular_velocity.x, msg.angular_velocity.y, msg.angular_velocity.z);
    const Eigen::Matrix3d c = cov3(msg.angular_velocity_covariance);
    if (!w.allFinite() || !c.allFinite()) {
      *reason = "non-finite angular velocity";
      out->resize(first);
      return false;
    }
    out->emplace_back();
    Measurement& m = out->back();
    m.time = time;
    m.source = cfg.name + "/w";
    m.mahalanobis_threshold = cfg.twist_rejection_threshold;
    setBlock(&m, ORIENTATION_V_OFFSET, base_from_imu * w, base_from_imu * c * base_from_imu.transpose(),
             cfg.update_vector, ORIENTATION_V_OFFSET);
  }

  if (anyOf(cfg.update_vector, POSITION_A_OFFSET, 3) && msg.linear_acceleration_covariance[0] != -1.0) {
    const Eigen::Vector3d a(msg.linear_acceleration.x, msg.linear_acceleration.y, msg.linear_acceleration.z);
    const Eigen::Matrix3d c = cov3(msg.linear_acceleration_covariance);
    if (!a.allFinite() || !c.allFinite()) {
      *reason = "non-finite linear acceleration";
      out->resize(first);
      return false;
    }
    Eigen::Vector3d a_base = base_from_imu * a;
    // The accelerometer measures specific force (+g upwards at rest): remove gravity in base_link.
    if (cfg.remove_gravitational_acceleration) {
      a_base -= world_from_base.transpose() * Eigen::Vector3d(0.0, 0.0, gravity);
    }
    out->emplace_back();
    Measurement& m = out->back();
    m.time = time;
    m.source = cfg.name + "/a";
    m.mahalanobis_threshold = cfg.linear_acceleration_rejection_threshold;
    setBlock(&m, POSITION_A_OFFSET, a_base, base_from_imu * c * base_from_imu.transpose(), cfg.update_vector,
             POSITION_A_OFFSET);
  }
  return true;
}

}  // namespace rbd_localization
