// Randomised fuzzing (fixed seeds) of the exact parsing + zone code the node runs
// (ScanPipeline::process -> validate, beam measurement, floor fit, CriticalZone, outputs) with
// malformed and random clouds, random beam tables, zone parameters and sensor poses.
// Invariants: no crash / out-of-bounds access (this test is also built with ASan + UBSan),
// process() returns, a cloud whose layout is inconsistent is always rejected, a rejected cloud
// yields collision + an error text, accepted outputs are well formed (sizes, finite speed scale).
// RBD_LIDAR_FUZZ_ITER=N runs N inputs per test instead of the default.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <random>
#include <string>

#include "rbd_lidar/scan_pipeline.h"
#include "rbd_lidar/synthetic_cloud.h"

using rbd_lidar::BeamModel;
using rbd_lidar::CloudError;
using rbd_lidar::ScanPipeline;
using rbd_lidar::SensorPose;
using sensor_msgs::PointCloud2;
using sensor_msgs::PointField;

#if defined(__SANITIZE_ADDRESS__)
// The LeakSanitizer needs ptrace, which CI containers may forbid; leaks are not the point here.
extern "C" const char* __asan_default_options() { return "detect_leaks=0"; }
#endif

namespace {

int iterations(int fallback) {
  const char* env = std::getenv("RBD_LIDAR_FUZZ_ITER");
  return env ? std::max(1, std::atoi(env)) : fallback;
}

// Independent layout check: is every byte the pipeline may read inside the data buffer?
bool layoutConsistent(const PointCloud2& c, size_t beams) {
  if (c.width == 0 || c.height == 0 || c.data.empty() || c.height != beams || c.is_bigendian) return false;
  uint64_t end = 0;
  for (const char* name : {"range", "x", "y", "z"}) {
    const PointField* found = nullptr;
    for (const auto& f : c.fields) {
      if (f.name == name) {
        found = &f;
        break;
      }
    }
    if (!found || found->count != 1) return false;
    const uint8_t want = std::string(name) == "range" ? PointField::UINT32 : PointField::FLOAT32;
    if (found->datatype != want) return false;
    end = std::max<uint64_t>(end, static_cast<uint64_t>(found->offset) + 4);
  }
  return end <= c.point_step &&
         static_cast<uint64_t>(c.row_step) >= static_cast<uint64_t>(c.width) * c.point_step &&
         c.data.size() == static_cast<uint64_t>(c.row_step) * c.height;
}

float specialFloat(std::mt19937* rng) {
  const float v[] = {std::numeric_limits<float>::quiet_NaN(),
                     std::numeric_limits<float>::infinity(),
                     -std::numeric_limits<float>::infinity(),
                     1e30f,
                     -1e30f,
                     0.0f,
                     -0.0f,
                     1e-40f};
  return v[(*rng)() % 8];
}

// One random input: a valid synthetic cloud of random width, then random mutations.
PointCloud2 randomCloud(std::mt19937* rng, size_t beams, const std::vector<double>& alt,
                        const std::vector<double>& az) {
  std::uniform_int_distribution<int> widths(1, 300);
  const int width = (*rng)() % 4 == 0 ? 512 : widths(*rng);
  BeamModel m = BeamModel::fromOuster(alt, az, std::vector<int>(beams, 0), 512, width, true, 15.806, 36.18);
  SensorPose pose;
  pose.height = 0.38;
  std::vector<uint32_t> range;
  if (m.valid(nullptr)) {
    range = rbd_lidar::castScene(m, pose, 0.5 + 5.0 * ((*rng)() % 100) / 100.0, (*rng)() % 2 == 0,
                                 0.2 + ((*rng)() % 100) / 100.0, 0.0, 0.2);
  } else {
    range.assign(beams * width, 0);
    for (auto& r : range) r = (*rng)() % 5000;
  }
  PointCloud2 c = rbd_lidar::makeOusterCloud(m, range, (*rng)() % 2 == 0);
  const int mutations = static_cast<int>((*rng)() % 4);
  for (int k = 0; k < mutations; ++k) {
    switch ((*rng)() % 14) {
      case 0:  // field datatype
        if (!c.fields.empty())
          c.fields[(*rng)() % c.fields.size()].datatype = static_cast<uint8_t>((*rng)() % 10);
        break;
      case 1:  // field offset (possibly beyond the point)
        if (!c.fields.empty()) c.fields[(*rng)() % c.fields.size()].offset = (*rng)() % 80;
        break;
      case 2:  // field removed or renamed
        if (!c.fields.empty()) {
          if ((*rng)() % 2)
            c.fields.erase(c.fields.begin() + (*rng)() % c.fields.size());
          else
            c.fields[(*rng)() % c.fields.size()].name = "range";
        }
        break;
      case 3:
        c.point_step = (*rng)() % 64;
        break;
      case 4:
        c.row_step = (*rng)() % 2 ? (*rng)() % 100000 : c.width * c.point_step + (*rng)() % 64;
        break;
      case 5:
        c.width = (*rng)() % 3 ? (*rng)() % 1024 : (*rng)();
        break;
      case 6:
        c.height = (*rng)() % 3 ? (*rng)() % 70 : (*rng)();
        break;
      case 7:  // truncated or extended data
        c.data.resize((*rng)() % 2 ? c.data.size() / (1 + (*rng)() % 8) : c.data.size() + (*rng)() % 100);
        break;
      case 8:  // NaN / Inf / huge xyz
        for (int i = 0; i < 200 && !c.data.empty(); ++i) {
          const float f = specialFloat(rng);
          const size_t at = (*rng)() % c.data.size();
          if (at + 4 <= c.data.size()) std::memcpy(&c.data[at & ~size_t(3)], &f, 4);
        }
        break;
      case 9:  // huge / random ranges at the range offset
        for (int i = 0; i < 500 && c.point_step >= 36 && c.data.size() >= 48; ++i) {
          const size_t p = (*rng)() % (c.data.size() / 48);
          const uint32_t r = (*rng)() % 2 ? 0xFFFFFFFFu : (*rng)();
          std::memcpy(&c.data[p * 48 + 32], &r, 4);
        }
        break;
      case 10:  // random bytes
        for (auto& b : c.data) b = static_cast<uint8_t>((*rng)());
        break;
      case 11:
        c.is_bigendian = true;
        break;
      case 12:  // field count
        if (!c.fields.empty()) c.fields[(*rng)() % c.fields.size()].count = (*rng)() % 4;
        break;
      default:  // all ranges zero (blinded)
        for (size_t p = 0; c.point_step >= 36 && p + 48 <= c.data.size(); p += 48)
          std::memset(&c.data[p + 32], 0, 4);
        break;
    }
  }
  return c;
}

void checkOutputs(const PointCloud2& cloud, bool consistent, CloudError err, const ScanPipeline::Outputs& out,
                  const std::string& msg, int i) {
  if (!consistent) {
    ASSERT_NE(err, CloudError::NONE) << "inconsistent layout accepted, input " << i;
  }
  if (err != CloudError::NONE) {
    EXPECT_TRUE(out.state.collision) << i;
    EXPECT_FALSE(out.state.error.empty()) << i;
    EXPECT_FALSE(msg.empty()) << i;
    EXPECT_EQ(out.critical.width, 0u) << i;
    EXPECT_EQ(out.state.speed_scale, 0.0f) << i;
    return;
  }
  EXPECT_EQ(out.critical.data.size(), static_cast<size_t>(out.critical.width) * 32u) << i;
  EXPECT_EQ(out.critical.width, out.zone.critical.size()) << i;
  EXPECT_EQ(out.slice.data.size(), static_cast<size_t>(out.slice.width) * 16u) << i;
  EXPECT_LE(out.slice.width, cloud.width) << i;
  EXPECT_EQ(out.scan.ranges.size(), cloud.width) << i;
  EXPECT_TRUE(out.state.speed_scale >= 0.0f && out.state.speed_scale <= 1.0f) << i;
  for (size_t k = 0; k < out.zone.critical.size(); ++k) {
    ASSERT_LT(out.zone.critical[k], static_cast<size_t>(cloud.width) * cloud.height) << i;
    ASSERT_LT(out.zone.critical_side[k], 4u) << i;
  }
  if (out.zone.total() >= 5) {
    EXPECT_TRUE(out.state.collision) << i;
  }
}

}  // namespace

// Malformed and random clouds against the OS1-32 beam table, one pipeline reused across inputs
// (as the node does), with random poses and zones in between.
TEST(FuzzCloud, MalformedAndRandomClouds) {
  std::mt19937 rng(20261123);
  ScanPipeline p;
  p.setNominalBeams(rbd_lidar::os1U0Altitudes(), rbd_lidar::os1U0Azimuths(), std::vector<int>(32, 0), 512,
                    true, 15.806, 36.18);
  ScanPipeline::Outputs out;
  const int n = iterations(3000);
  int rejected = 0;
  for (int i = 0; i < n; ++i) {
    if (rng() % 8 == 0) {
      SensorPose pose;
      pose.height = 0.1 + (rng() % 100) / 100.0;
      pose.level_from_sensor =
          Eigen::AngleAxisd(((rng() % 200) / 100.0 - 1.0) * 0.5, Eigen::Vector3d::UnitY()).toRotationMatrix();
      p.setPose(pose);
      rbd_lidar::PipelineParams params;
      params.beams_from_cloud = rng() % 2;
      params.floor_from_cloud = rng() % 4 != 0;
      params.slice_ring = static_cast<int>(rng() % 40) - 2;
      p.setParams(params);
    }
    const PointCloud2 c = randomCloud(&rng, 32, rbd_lidar::os1U0Altitudes(), rbd_lidar::os1U0Azimuths());
    std::string msg;
    const CloudError err = p.process(c, &out, &msg);
    if (err != CloudError::NONE) ++rejected;
    checkOutputs(c, layoutConsistent(c, 32), err, out, msg, i);
    if (HasFatalFailure()) return;
  }
  // Both paths were exercised.
  EXPECT_GT(rejected, n / 10);
  EXPECT_LT(rejected, n);
}

// Random beam tables (row counts, NaN / +-90 deg altitudes, azimuths, pixel shifts) and random
// zone parameters, including values configure() must refuse.
TEST(FuzzCloud, RandomBeamTablesAndZones) {
  std::mt19937 rng(7);
  const int n = iterations(1000);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (int i = 0; i < n; ++i) {
    const size_t beams = 1 + rng() % 64;
    std::vector<double> alt(beams), az(beams);
    std::vector<int> shift(beams);
    for (size_t u = 0; u < beams; ++u) {
      alt[u] = rng() % 50 == 0 ? (rng() % 2 ? nan : 90.0) : 45.0 - (rng() % 9000) / 100.0;
      az[u] = rng() % 50 == 0 ? std::numeric_limits<double>::infinity() : (rng() % 2000) / 100.0 - 10.0;
      shift[u] = static_cast<int>(rng() % 64) - 32;
    }
    ScanPipeline p;
    p.setNominalBeams(alt, az, shift, static_cast<int>(rng() % 1024) - 4, rng() % 2, (rng() % 3000) / 100.0,
                      (rng() % 5000) / 100.0);
    rbd_lidar::PipelineParams params;
    params.beams_from_cloud = rng() % 2;
    p.setParams(params);
    rbd_lidar::ZoneParams z;
    z.front = rng() % 20 == 0 ? nan : (rng() % 300) / 100.0;
    z.back = rng() % 20 == 0 ? -1.0 : (rng() % 300) / 100.0;
    z.left = (rng() % 300) / 100.0;
    z.right = rng() % 40 == 0 ? 1e9 : (rng() % 300) / 100.0;
    z.blind_zone = (rng() % 100) / 100.0;
    z.point_threshold = rng() % 10;
    p.setZone(z);
    ScanPipeline::Outputs out;
    for (int scan = 0; scan < 2; ++scan) {
      const PointCloud2 c = randomCloud(&rng, beams, alt, az);
      std::string msg;
      const CloudError err = p.process(c, &out, &msg);
      checkOutputs(c, layoutConsistent(c, beams), err, out, msg, i);
      if (HasFatalFailure()) return;
    }
  }
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
