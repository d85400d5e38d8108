// The EKF node's diagnostics: per sensor (received, rejected, stale, the last problem) and for
// the filter as a whole, through diagnostic_updater.
#include "rbd_localization/ekf_node.h"

namespace rbd_localization {

void EkfNode::diagnoseSensor(size_t idx, diagnostic_updater::DiagnosticStatusWrapper& stat) {
  SensorState& s = sensors_[idx];
  const ros::Time now = ros::Time::now();
  stat.add("topic", s.sub.getTopic());
  stat.add("type", sensorTypeName(s.cfg.type));
  stat.add("received", s.received);
  stat.add("accepted", s.accepted);
  stat.add("rejected", s.rejected);
  stat.add("invalid", s.invalid);
  stat.add("cycles with a full queue", s.full_queue_cycles);
  stat.add("last message age [s]", s.received ? (now - s.last_receive).toSec() : -1.0);
  if (sensorStale(s, now)) {
    stat.summaryf(diagnostic_msgs::DiagnosticStatus::ERROR, "stale: %s",
                  s.received ? "no message within sensor_stale_timeout" : "no message received yet");
  } else if (s.window_rejected > 0) {
    stat.summaryf(diagnostic_msgs::DiagnosticStatus::WARN,
                  "rejected %lu measurement(s) since last report: %s",
                  static_cast<unsigned long>(s.window_rejected), s.last_problem.c_str());
  } else if (s.window_invalid > 0) {
    stat.summaryf(diagnostic_msgs::DiagnosticStatus::WARN, "%lu invalid message(s) since last report: %s",
                  static_cast<unsigned long>(s.window_invalid), s.last_problem.c_str());
  } else {
    stat.summary(diagnostic_msgs::DiagnosticStatus::OK, "ok");
  }
  s.window_received = s.window_rejected = s.window_invalid = 0;
}

void EkfNode::diagnoseFilter(diagnostic_updater::DiagnosticStatusWrapper& stat) {
  stat.add("initialized", ekf_.initialized());
  stat.add("filter time", ekf_.lastUpdateTime());
  stat.add("world_frame", params_.world_frame);
  stat.add("TF listener", tf_listener_ ? "active" : "released");
  if (!enabled_) {
    stat.summary(diagnostic_msgs::DiagnosticStatus::WARN, "disabled: waiting for the enable service");
  } else if (!ekf_.initialized()) {
    stat.summary(diagnostic_msgs::DiagnosticStatus::WARN, "waiting for the first measurement");
  } else if (!publishing_) {
    stat.summary(diagnostic_msgs::DiagnosticStatus::ERROR, "all sensors stale: estimate not published");
  } else if (!ekf_.state().allFinite()) {
    stat.summary(diagnostic_msgs::DiagnosticStatus::ERROR, "state not finite");
  } else {
    stat.summary(diagnostic_msgs::DiagnosticStatus::OK, "publishing");
  }
}

}  // namespace rbd_localization
