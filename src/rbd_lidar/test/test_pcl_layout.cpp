// The critical-point cloud reads back as pcl::PointXYZI (the thesis' point type).
#include <gtest/gtest.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl_conversions/pcl_conversions.h>

#include "rbd_lidar/scan_pipeline.h"
#include "rbd_lidar/synthetic_cloud.h"

TEST(PclLayout, CriticalCloudIsPointXYZI) {
  const rbd_lidar::BeamModel m =
      rbd_lidar::BeamModel::fromOuster(rbd_lidar::os1U0Altitudes(), rbd_lidar::os1U0Azimuths(),
                                       std::vector<int>(32, 0), 512, 512, true, 15.806, 36.18);
  rbd_lidar::SensorPose pose;
  pose.height = 0.38;
  rbd_lidar::ScanPipeline p;
  p.setNominalBeams(rbd_lidar::os1U0Altitudes(), rbd_lidar::os1U0Azimuths(), std::vector<int>(32, 0), 512,
                    true, 15.806, 36.18);
  p.setPose(pose);
  rbd_lidar::ScanPipeline::Outputs out;
  std::string msg;
  ASSERT_EQ(p.process(rbd_lidar::makeOusterCloud(m, rbd_lidar::castScene(m, pose, 3.0, true, -0.45, 0.0)),
                      &out, &msg),
            rbd_lidar::CloudError::NONE)
      << msg;
  ASSERT_GT(out.critical.width, 5u);
  pcl::PointCloud<pcl::PointXYZI> cloud;
  pcl::fromROSMsg(out.critical, cloud);
  ASSERT_EQ(cloud.size(), out.critical.width);
  for (const auto& pt : cloud.points) {
    EXPECT_LT(pt.x, -0.24);  // person behind: cylinder axis at -0.45 m, radius 0.2 m
    EXPECT_GT(pt.x, -0.46);
    EXPECT_FLOAT_EQ(pt.intensity, 1.0f + rbd_lidar::BACK);
  }
  pcl::PointCloud<pcl::PointXYZI> slice;
  pcl::fromROSMsg(out.slice, slice);
  EXPECT_EQ(slice.size(), out.slice.width);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
