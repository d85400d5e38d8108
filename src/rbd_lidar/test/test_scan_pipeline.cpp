// gtests of the per-scan pipeline on synthetic ouster-ros clouds (no ROS master needed).
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstring>
#include <set>

#include "rbd_lidar/scan_pipeline.h"
#include "rbd_lidar/synthetic_cloud.h"

using rbd_lidar::BeamModel;
using rbd_lidar::CloudError;
using rbd_lidar::ScanPipeline;
using rbd_lidar::SensorPose;

namespace {

const std::vector<double> kGAlt = {12.75, 10.03,  7.27,   4.47,   3.41,   2.35,   1.29,   0.23,
                                   -0.83, -1.89,  -2.95,  -4.01,  -5.07,  -6.13,  -7.19,  -8.25,
                                   -9.31, -10.37, -11.43, -12.49, -13.55, -14.61, -15.0,  -15.1,
                                   -15.2, -15.25, -15.3,  -15.31, -15.32, -15.33, -15.34, -15.35};

BeamModel u0(int columns) {
  return BeamModel::fromOuster(rbd_lidar::os1U0Altitudes(), rbd_lidar::os1U0Azimuths(),
                               std::vector<int>(32, 0), 512, columns, true, 15.806, 36.18);
}

ScanPipeline makePipeline(bool from_cloud = true) {
  ScanPipeline p;
  p.setNominalBeams(rbd_lidar::os1U0Altitudes(), rbd_lidar::os1U0Azimuths(), std::vector<int>(32, 0), 512,
                    true, 15.806, 36.18);
  rbd_lidar::PipelineParams params;
  params.beams_from_cloud = from_cloud;
  params.hysteresis_scans = 3;
  p.setParams(params);
  SensorPose pose;
  pose.height = 0.38;
  p.setPose(pose);
  return p;
}

SensorPose standing() {
  SensorPose pose;
  pose.height = 0.38;
  return pose;
}

}  // namespace

TEST(ScanPipeline, PersonInFrontIsCriticalAndPublished) {
  const BeamModel m = u0(1024);
  ScanPipeline p = makePipeline();
  ScanPipeline::Outputs out;
  std::string msg;
  // Empty room first: clear after the hysteresis (the latch starts in collision).
  const auto empty = rbd_lidar::makeOusterCloud(m, rbd_lidar::castScene(m, standing(), 3.0, false));
  for (int i = 0; i < 3; ++i) ASSERT_EQ(p.process(empty, &out, &msg), CloudError::NONE) << msg;
  EXPECT_FALSE(out.state.collision);
  EXPECT_EQ(out.zone.total(), 0u);
  EXPECT_FLOAT_EQ(out.state.speed_scale, 1.0f);
  const auto person = rbd_lidar::makeOusterCloud(m, rbd_lidar::castScene(m, standing(), 3.0, true, 0.5, 0.0));
  ASSERT_EQ(p.process(person, &out, &msg), CloudError::NONE) << msg;
  EXPECT_TRUE(out.state.collision);
  EXPECT_GT(out.state.points[0], 20u);
  EXPECT_EQ(out.state.points[2], 0u);
  EXPECT_NEAR(out.state.min_distance[0], 0.30, 0.01);  // person surface: 0.5 - 0.2
  EXPECT_FLOAT_EQ(out.state.speed_scale, 0.0f);
  // Critical cloud: pcl::PointXYZI layout, front points marked with intensity 1.
  ASSERT_EQ(out.critical.width, out.zone.total());
  ASSERT_EQ(out.critical.point_step, 32u);
  ASSERT_EQ(out.critical.data.size(), 32u * out.critical.width);
  for (size_t k = 0; k < out.critical.width; ++k) {
    float v[5];
    std::memcpy(v, &out.critical.data[k * 32], 12);
    std::memcpy(&v[4], &out.critical.data[k * 32 + 16], 4);
    EXPECT_GT(v[0], 0.29);  // on the near half of the cylinder (axis at 0.5 m, radius 0.2 m)
    EXPECT_LT(v[0], 0.51);
    EXPECT_LT(std::fabs(v[1]), 0.21);
    EXPECT_FLOAT_EQ(v[4], 1.0f);
  }
  // Removed: clear after exactly 3 clear scans.
  ASSERT_EQ(p.process(empty, &out, &msg), CloudError::NONE);
  EXPECT_TRUE(out.state.collision);
  ASSERT_EQ(p.process(empty, &out, &msg), CloudError::NONE);
  EXPECT_TRUE(out.state.collision);
  ASSERT_EQ(p.process(empty, &out, &msg), CloudError::NONE);
  EXPECT_FALSE(out.state.collision);
}

TEST(ScanPipeline, SliceAndLaserScan) {
  const BeamModel m = u0(1024);
  ScanPipeline p = makePipeline();
  ScanPipeline::Outputs out;
  std::string msg;
  ASSERT_EQ(
      p.process(rbd_lidar::makeOusterCloud(m, rbd_lidar::castScene(m, standing(), 2.0, false)), &out, &msg),
      CloudError::NONE)
      << msg;
  EXPECT_EQ(p.sliceRing(), 15);  // 0.18 deg: the beam nearest to horizontal
  EXPECT_EQ(out.slice.width, 1024u);
  ASSERT_EQ(out.scan.ranges.size(), 1024u);
  EXPECT_NEAR(out.scan.angle_min, -M_PI, 1e-6);
  EXPECT_NEAR(out.scan.angle_increment, 2 * M_PI / 1024, 1e-7);
  // Square room of half size 2 m: 2 m ahead and to the side, 2*sqrt(2) at the diagonal.
  const auto at = [&](double angle) {
    return out.scan.ranges[static_cast<size_t>((angle - out.scan.angle_min) / out.scan.angle_increment)];
  };
  EXPECT_NEAR(at(0.0), 2.0, 0.02);
  EXPECT_NEAR(at(M_PI / 2), 2.0, 0.02);
  EXPECT_NEAR(at(-M_PI / 4), 2.0 * std::sqrt(2.0), 0.03);
  size_t finite = 0;
  for (float r : out.scan.ranges) finite += std::isfinite(r);
  EXPECT_GT(finite, 1000u);
}

// Malformed clouds: every kind is rejected with its own error, the state is a collision, no crash.
TEST(ScanPipeline, MalformedCloudsFailSafe) {
  const BeamModel m = u0(512);
  const auto good = rbd_lidar::makeOusterCloud(m, rbd_lidar::castScene(m, standing(), 3.0, false));
  ScanPipeline p = makePipeline();
  ScanPipeline::Outputs out;
  std::string msg;
  for (int i = 0; i < 3; ++i) ASSERT_EQ(p.process(good, &out, &msg), CloudError::NONE);
  ASSERT_FALSE(out.state.collision);

  std::vector<std::pair<CloudError, sensor_msgs::PointCloud2>> cases;
  auto c = good;
  c.fields.pop_back();  // range
  cases.emplace_back(CloudError::NO_RANGE_FIELD, c);
  c = good;
  c.fields.back().datatype = sensor_msgs::PointField::FLOAT32;
  cases.emplace_back(CloudError::BAD_FIELD, c);
  c = good;
  c.point_step = 32;
  cases.emplace_back(CloudError::BAD_POINT_STEP, c);
  c = good;
  c.height = 16;
  c.row_step *= 2;
  cases.emplace_back(CloudError::BAD_HEIGHT, c);
  c = good;
  c.data.resize(c.data.size() - 100);
  cases.emplace_back(CloudError::BAD_SIZE, c);
  c = good;
  c.data.clear();
  cases.emplace_back(CloudError::EMPTY, c);
  c = good;
  c.width = 0;
  cases.emplace_back(CloudError::EMPTY, c);
  // All returns gone, all xyz NaN.
  cases.emplace_back(CloudError::NO_VALID_RETURNS,
                     rbd_lidar::makeOusterCloud(m, std::vector<uint32_t>(32 * 512, 0), true));
  std::set<std::string> messages;
  for (auto& kc : cases) {
    ASSERT_EQ(p.process(good, &out, &msg), CloudError::NONE);
    for (int i = 0; i < 3; ++i) p.process(good, &out, &msg);
    ASSERT_FALSE(out.state.collision);
    EXPECT_EQ(p.process(kc.second, &out, &msg), kc.first) << rbd_lidar::errorName(kc.first);
    EXPECT_TRUE(out.state.collision);
    EXPECT_FALSE(out.state.error.empty());
    EXPECT_FLOAT_EQ(out.state.speed_scale, 0.0f);
    EXPECT_EQ(out.critical.width, 0u);
    messages.insert(rbd_lidar::errorName(kc.first));
    // The next good cloud does not clear at once: the hysteresis starts again.
    ASSERT_EQ(p.process(good, &out, &msg), CloudError::NONE);
    EXPECT_TRUE(out.state.collision);
  }
  EXPECT_EQ(messages.size(), 7u);
}

// Padded rows (row_step > width * point_step) and another point layout (range first, point_step
// 20) give the same result as the ouster-ros layout.
TEST(ScanPipeline, OtherLayoutsSameResult) {
  const BeamModel m = u0(512);
  const auto ranges = rbd_lidar::castScene(m, standing(), 3.0, true, 0.5, 0.1);
  const auto cloud = rbd_lidar::makeOusterCloud(m, ranges);
  ScanPipeline a = makePipeline();
  ScanPipeline::Outputs ref, out;
  std::string msg;
  ASSERT_EQ(a.process(cloud, &ref, &msg), CloudError::NONE) << msg;
  ASSERT_GT(ref.zone.total(), 10u);

  auto padded = cloud;
  padded.row_step = cloud.row_step + 64;
  padded.data.assign(static_cast<size_t>(padded.row_step) * padded.height, 0xEE);
  for (size_t u = 0; u < cloud.height; ++u) {
    std::copy(cloud.data.begin() + u * cloud.row_step, cloud.data.begin() + (u + 1) * cloud.row_step,
              padded.data.begin() + u * padded.row_step);
  }
  ScanPipeline b = makePipeline();
  ASSERT_EQ(b.process(padded, &out, &msg), CloudError::NONE) << msg;
  EXPECT_EQ(out.zone.counts, ref.zone.counts);
  EXPECT_EQ(out.zone.critical, ref.zone.critical);
  EXPECT_EQ(out.critical.data, ref.critical.data);
  EXPECT_EQ(out.scan.ranges, ref.scan.ranges);

  sensor_msgs::PointCloud2 compact = cloud;
  compact.fields.clear();
  const char* names[] = {"range", "x", "y", "z"};
  for (int k = 0; k < 4; ++k) {
    sensor_msgs::PointField f;
    f.name = names[k];
    f.offset = 4 * k;
    f.datatype = k == 0 ? sensor_msgs::PointField::UINT32 : sensor_msgs::PointField::FLOAT32;
    f.count = 1;
    compact.fields.push_back(f);
  }
  compact.point_step = 20;
  compact.row_step = 20 * cloud.width;
  compact.data.assign(static_cast<size_t>(compact.row_step) * compact.height, 0);
  for (size_t i = 0; i < static_cast<size_t>(cloud.width) * cloud.height; ++i) {
    std::memcpy(&compact.data[i * 20], &cloud.data[i * 48 + 32], 4);
    std::memcpy(&compact.data[i * 20 + 4], &cloud.data[i * 48], 12);
  }
  ScanPipeline c = makePipeline();
  ASSERT_EQ(c.process(compact, &out, &msg), CloudError::NONE) << msg;
  EXPECT_EQ(out.zone.counts, ref.zone.counts);
  EXPECT_EQ(out.critical.data, ref.critical.data);
  EXPECT_EQ(out.scan.ranges, ref.scan.ranges);
}

// ouster-ros >= 0.13: NaN xyz but a valid range (its min_range filter) must not hide an obstacle.
TEST(ScanPipeline, NanCoordinatesDoNotHideReturns) {
  const BeamModel m = u0(512);
  ScanPipeline p = makePipeline(false);
  auto ranges = rbd_lidar::castScene(m, standing(), 3.0, true, 0.5, 0.0);
  auto cloud = rbd_lidar::makeOusterCloud(m, ranges);
  for (size_t i = 0; i < ranges.size(); ++i) {
    if (ranges[i] > 0 && ranges[i] < 1000) {
      const float nan = std::nanf("");
      std::memcpy(&cloud.data[i * 48], &nan, 4);
    }
  }
  ScanPipeline::Outputs out;
  std::string msg;
  ASSERT_EQ(p.process(cloud, &out, &msg), CloudError::NONE) << msg;
  EXPECT_GT(out.zone.counts[0], 10u);
  EXPECT_TRUE(out.state.collision);
  for (size_t k = 0; k < out.critical.width; ++k) {
    float x;
    std::memcpy(&x, &out.critical.data[k * 32], 4);
    EXPECT_GT(x, 0.29);  // filled from the beam model, on the cylinder
    EXPECT_LT(x, 0.51);
  }
}

// The beam table is measured from the cloud's own xyz: a different OS1-32 variant (gradient
// beams, column direction reversed) is picked up, and its floor still never triggers.
TEST(ScanPipeline, BeamAnglesMeasuredFromCloud) {
  BeamModel g = BeamModel::fromOuster(kGAlt, std::vector<double>(32, 1.4), std::vector<int>(32, 0), 1024,
                                      1024, true, 15.806, 36.18);
  g.direction = 1;
  const Eigen::Matrix3d pitch =
      Eigen::AngleAxisd(-15 * M_PI / 180, Eigen::Vector3d::UnitY()).toRotationMatrix();
  SensorPose pose;
  pose.level_from_sensor = pitch;
  pose.height = 0.35;
  const auto floor_only = rbd_lidar::castScene(g, pose, 4.0, false);
  ScanPipeline p = makePipeline(true);
  p.setPose(pose);
  ScanPipeline::Outputs out;
  std::string msg;
  ASSERT_EQ(p.process(rbd_lidar::makeOusterCloud(g, floor_only), &out, &msg), CloudError::NONE) << msg;
  EXPECT_EQ(p.model().direction, 1);
  for (size_t u = 0; u < 32; ++u) EXPECT_NEAR(p.model().altitude[u], g.altitude[u], 1e-4) << u;
  EXPECT_LT(p.modelResidual(), 0.003);
  EXPECT_EQ(out.zone.total(), 0u);
  // With the nominal (U0) table instead, the same cloud is misread.
  ScanPipeline nominal = makePipeline(false);
  nominal.setPose(pose);
  ASSERT_EQ(nominal.process(rbd_lidar::makeOusterCloud(g, floor_only), &out, &msg), CloudError::NONE);
  EXPECT_GT(nominal.modelResidual(), 0.05);
}

// Crouched attentive sitting: nose up 15 deg and the sensor 0.25 m above the floor, while the node
// believes the standing height (0.377 m). The measured floor height removes the floor; without it
// the rear floor is taken for an obstacle. A person is still found.
TEST(ScanPipeline, FloorHeightMeasuredFromCloud) {
  const BeamModel m = u0(1024);
  SensorPose truth;
  truth.level_from_sensor = Eigen::AngleAxisd(-15 * M_PI / 180, Eigen::Vector3d::UnitY()).toRotationMatrix();
  truth.height = 0.25;
  SensorPose believed = truth;
  believed.height = 0.377;
  const auto floor_cloud = rbd_lidar::makeOusterCloud(m, rbd_lidar::castScene(m, truth, 3.0, false));
  ScanPipeline::Outputs out;
  std::string msg;

  ScanPipeline fixed = makePipeline();
  rbd_lidar::PipelineParams params;
  params.floor_from_cloud = false;
  fixed.setParams(params);
  fixed.setPose(believed);
  ASSERT_EQ(fixed.process(floor_cloud, &out, &msg), CloudError::NONE) << msg;
  EXPECT_GT(out.zone.counts[rbd_lidar::BACK], 20u);
  EXPECT_FALSE(fixed.heightMeasured());

  ScanPipeline measured = makePipeline();
  measured.setPose(believed);
  ASSERT_EQ(measured.process(floor_cloud, &out, &msg), CloudError::NONE) << msg;
  EXPECT_TRUE(measured.heightMeasured());
  EXPECT_NEAR(measured.sensorHeight(), 0.25, 0.01);
  EXPECT_EQ(out.zone.total(), 0u);
  ASSERT_EQ(
      measured.process(rbd_lidar::makeOusterCloud(m, rbd_lidar::castScene(m, truth, 3.0, true, 0.5, 0.0)),
                       &out, &msg),
      CloudError::NONE);
  EXPECT_GT(out.zone.counts[rbd_lidar::FRONT], 20u);
  EXPECT_NEAR(measured.sensorHeight(), 0.25, 0.01);
  // The measurement is bounded: a nominal height far off is moved by at most the tolerance.
  believed.height = 0.80;
  measured.setPose(believed);
  ASSERT_EQ(measured.process(floor_cloud, &out, &msg), CloudError::NONE);
  EXPECT_NEAR(measured.sensorHeight(), 0.60, 1e-9);
}

// The attitude prior (IMU / odom) lags a body-pose transition: the real sensor is pitched or rolled
// while the pipeline still believes it level. The per-scan floor-plane fit must keep the floor out
// of the zone and still see a person 0.5 m in front.
TEST(ScanPipeline, FloorPlaneCorrectsLaggingAttitude) {
  const BeamModel m = u0(1024);
  struct Case {
    double roll, pitch, height;
  };
  const Case cases[] = {
      {0.0, -0.26, 0.33}, {0.0, 0.26, 0.40}, {0.3, 0.0, 0.36}, {-0.3, 0.0, 0.36}, {0.2, -0.2, 0.30}};
  for (const Case& k : cases) {
    SensorPose truth;
    truth.level_from_sensor = (Eigen::AngleAxisd(k.pitch, Eigen::Vector3d::UnitY()) *
                               Eigen::AngleAxisd(k.roll, Eigen::Vector3d::UnitX()))
                                  .toRotationMatrix();
    truth.height = k.height;
    SensorPose believed;  // level, nominal height
    believed.height = 0.38;
    const auto floor_cloud = rbd_lidar::makeOusterCloud(m, rbd_lidar::castScene(m, truth, 3.0, false));
    ScanPipeline::Outputs out;
    std::string msg;

    ScanPipeline prior_only = makePipeline();
    rbd_lidar::PipelineParams params;
    params.floor_from_cloud = false;
    prior_only.setParams(params);
    prior_only.setPose(believed);
    ASSERT_EQ(prior_only.process(floor_cloud, &out, &msg), CloudError::NONE) << msg;
    if (std::fabs(k.pitch) > 0.2) {
      EXPECT_GT(out.zone.total(), 5u) << "pitch " << k.pitch;  // the bug
    }

    ScanPipeline fitted = makePipeline();
    fitted.setPose(believed);
    ASSERT_EQ(fitted.process(floor_cloud, &out, &msg), CloudError::NONE) << msg;
    EXPECT_EQ(out.zone.total(), 0u) << "roll " << k.roll << " pitch " << k.pitch;
    EXPECT_NEAR(fitted.sensorHeight(), k.height, 0.01);
    ASSERT_EQ(
        fitted.process(rbd_lidar::makeOusterCloud(m, rbd_lidar::castScene(m, truth, 3.0, true, 0.5, 0.0)),
                       &out, &msg),
        CloudError::NONE);
    EXPECT_GT(out.zone.counts[rbd_lidar::FRONT], 20u) << "roll " << k.roll << " pitch " << k.pitch;
    EXPECT_EQ(out.zone.counts[rbd_lidar::BACK], 0u);
  }
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
