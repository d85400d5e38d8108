// zone_benchmark: times, in one run on the same synthetic OS1-32 cloud,
//   memcpy of the cloud's data buffer,
//   the zone core alone (range image -> per-side counts + critical indices),
//   the full per-scan pipeline (validation, range extraction, zone, critical cloud, slice cloud,
//   LaserScan, CollisionState; message building without serialisation),
//   a PCL baseline (pcl::fromROSMsg to PointXYZI + pcl::CropBox of the zone),
// for 512, 1024 and 2048 columns, under two cache conditions that every stage meets alike:
//   hot:     each stage runs back to back on the same cloud in short blocks, so its working set
//            stays in the caches (the condition of the reference figures: a 3 MB memcpy
//            in ~0.07 ms);
//   arrival: before each timed stage the cloud's buffer is rewritten from a pristine copy, as the
//            subscriber's deserialisation leaves it just before the callback runs (the node's case);
//   cold:    before each timed stage 48 MiB are written, so the cloud comes from DRAM (worst case).
// The last line is one JSON object for 2048 columns (hot; arrival and cold nested).
#include <pcl/filters/crop_box.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl_conversions/pcl_conversions.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <string>
#include <vector>

#include "rbd_lidar/scan_pipeline.h"
#include "rbd_lidar/synthetic_cloud.h"

namespace {

using Clock = std::chrono::steady_clock;

double ms(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

double percentile(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  return v[static_cast<size_t>(q * (v.size() - 1))];
}

struct Row {
  int columns;
  double memcpy_ms, zone_ms, pipeline_ms, pcl_ms, pipeline_p90, pcl_p90, table_ms;
  uint32_t critical, pcl_points;
};

enum class Cache { HOT, ARRIVAL, COLD };

Row benchColumns(int columns, int iterations, double person_x, Cache cache) {
  using namespace rbd_lidar;
  const BeamModel model = BeamModel::fromOuster(os1U0Altitudes(), os1U0Azimuths(), std::vector<int>(32, 0),
                                                512, columns, true, 15.806, 36.18);
  SensorPose pose;
  pose.height = 0.38;
  // A 6 m x 6 m room with a person 0.5 m ahead of the LiDAR.
  sensor_msgs::PointCloud2 cloud =
      makeOusterCloud(model, castScene(model, pose, 3.0, person_x > 0, person_x, 0.1));
  const std::vector<uint8_t> wire = cloud.data;  // what deserialisation writes into cloud.data
  std::vector<uint8_t> evict(cache == Cache::COLD ? (48u << 20) : 0);
  unsigned evict_value = 0;
  auto prepare = [&]() {
    if (cache == Cache::COLD) {
      std::memset(evict.data(), static_cast<int>(++evict_value & 0xFF), evict.size());
    } else {
      std::memcpy(cloud.data.data(), wire.data(), wire.size());
    }
  };
  ScanPipeline pipeline;
  pipeline.setNominalBeams(os1U0Altitudes(), os1U0Azimuths(), std::vector<int>(32, 0), 512, true, 15.806,
                           36.18);
  pipeline.setPose(pose);
  ScanPipeline::Outputs out;
  std::string msg;
  if (pipeline.process(cloud, &out, &msg) != CloudError::NONE) {
    std::fprintf(stderr, "pipeline rejected the benchmark cloud: %s\n", msg.c_str());
    std::exit(1);
  }
  ZoneResult zres;
  std::vector<uint32_t> range_image;
  ScanPipeline::extractRange(cloud, &range_image);
  std::vector<uint8_t> copy(cloud.data.size());
  pcl::PointCloud<pcl::PointXYZI> pcl_cloud, cropped;
  pcl::CropBox<pcl::PointXYZI> crop;
  const ZoneParams z;
  crop.setMin(Eigen::Vector4f(-z.back, -z.right, -1e3f, 1.0f));
  crop.setMax(Eigen::Vector4f(z.front, z.left, 1e3f, 1.0f));

  std::function<void()> stages[4] = {
      [&]() { std::memcpy(copy.data(), cloud.data.data(), cloud.data.size()); },
      [&]() { pipeline.evaluateOnly(range_image, &zres); }, [&]() { pipeline.process(cloud, &out, &msg); },
      [&]() {
        pcl::fromROSMsg(cloud, pcl_cloud);
        crop.setInputCloud(pcl_cloud.makeShared());
        crop.filter(cropped);
      }};
  std::vector<double> times[4];
  auto timed = [&](int s, bool keep) {
    const auto t0 = Clock::now();
    stages[s]();
    const auto t1 = Clock::now();
    if (keep) times[s].push_back(ms(t0, t1));
  };
  if (cache == Cache::HOT) {
    // Rounds of short blocks: within a block a stage runs back to back (its working set stays in
    // the caches; the block's first run is not timed), and the stages alternate block by block,
    // so that the machine's load varies alike for all of them.
    const int rounds = 10, block = std::max(1, iterations / rounds);
    for (int round = 0; round < rounds; ++round) {
      for (int s = 0; s < 4; ++s) {
        for (int j = 0; j <= block; ++j) timed(s, j > 0);
      }
    }
  } else {
    for (int i = 0; i < iterations + 5; ++i) {
      for (int s = 0; s < 4; ++s) {
        prepare();
        timed(s, i >= 5);  // the first 5 rounds warm up
      }
    }
  }
  const std::vector<double>&t_copy = times[0], &t_zone = times[1], &t_pipe = times[2], &t_pcl = times[3];
  // Rebuild of the candidate table after an attitude change (not per scan: only when the body
  // tilts by more than 0.25 deg or the zone outgrows the table).
  std::vector<double> t_table;
  CriticalZone zone;
  for (int i = 0; i < 10; ++i) {
    SensorPose p = pose;
    p.level_from_sensor = Eigen::AngleAxisd((i % 2) * 0.1, Eigen::Vector3d::UnitY()).toRotationMatrix();
    auto a = Clock::now();
    zone.configure(pipeline.model(), z, p, nullptr);
    t_table.push_back(ms(a, Clock::now()));
  }
  if (copy[100] == 0xAB && zres.total() == 12345) std::puts("");  // keep the work observable
  return Row{columns,
             percentile(t_copy, 0.5),
             percentile(t_zone, 0.5),
             percentile(t_pipe, 0.5),
             percentile(t_pcl, 0.5),
             percentile(t_pipe, 0.9),
             percentile(t_pcl, 0.9),
             percentile(t_table, 0.5),
             zres.total(),
             static_cast<uint32_t>(cropped.size())};
}

void printJsonScenes(const Row& person, const Row& empty) {
  std::printf(
      "\"columns\": %d, \"memcpy_ms_p50\": %.4f, \"zone_ms_p50\": %.4f, \"pipeline_ms_p50\": %.4f, "
      "\"pcl_baseline_ms_p50\": %.4f, \"zone_over_memcpy\": %.3f, \"pcl_over_pipeline\": %.3f, "
      "\"pipeline_ms_p90\": %.4f, \"table_rebuild_ms_p50\": %.3f, \"scene\": \"person 0.5 m ahead\", "
      "\"empty_room\": {\"memcpy_ms_p50\": %.4f, \"zone_ms_p50\": %.4f, \"pipeline_ms_p50\": %.4f, "
      "\"pcl_baseline_ms_p50\": %.4f}",
      person.columns, person.memcpy_ms, person.zone_ms, person.pipeline_ms, person.pcl_ms,
      person.zone_ms / person.memcpy_ms, person.pcl_ms / person.pipeline_ms, person.pipeline_p90,
      person.table_ms, empty.memcpy_ms, empty.zone_ms, empty.pipeline_ms, empty.pcl_ms);
}

}  // namespace

int main(int argc, char** argv) {
  int iterations = 300;
  if (argc > 1) iterations = std::max(10, std::atoi(argv[1]));
  // Optional second argument: only this cache condition (hot, arrival or cold), e.g. under perf.
  const std::string only = argc > 2 ? argv[2] : "";
  Row person[3] = {}, empty[3] = {};
  bool ran[3] = {false, false, false};
  const char* names[3] = {"hot (each stage back to back in blocks of iterations/10, cloud cached)",
                          "arrival (cloud rewritten before each stage, as deserialisation leaves it)",
                          "cold (48 MiB written before each stage: cloud from DRAM)"};
  for (Cache cache : {Cache::HOT, Cache::ARRIVAL, Cache::COLD}) {
    const int k = static_cast<int>(cache);
    if (!only.empty() && std::strncmp(names[k], only.c_str(), only.size()) != 0) continue;
    ran[k] = true;
    // The cold condition costs a 48 MiB write per stage: a third of the iterations.
    const int n = cache == Cache::COLD ? std::max(10, iterations / 3) : iterations;
    std::printf(
        "zone_benchmark: synthetic OS1-32 clouds (6 m x 6 m room), %d iterations, p50 [ms], cache: %s\n", n,
        names[k]);
    // Scene 1: a person (0.4 m cylinder) 0.5 m ahead: ~13 % of all pixels are critical (worst case).
    // Scene 2: the empty room: nothing near the robot (the common case).
    for (double person_x : {0.5, 0.0}) {
      std::printf("scene: %s\n", person_x > 0 ? "person 0.5 m ahead" : "empty room");
      std::printf("%8s %10s %10s %12s %12s %14s %12s %12s %10s\n", "columns", "memcpy", "zone", "pipeline",
                  "pcl_base", "zone/memcpy", "pcl/pipe", "pipe_p90", "table");
      for (int columns : {512, 1024, 2048}) {
        const Row r = benchColumns(columns, n, person_x, cache);
        std::printf("%8d %10.4f %10.4f %12.4f %12.4f %14.2f %12.2f %12.4f %10.3f  (critical %u, crop %u)\n",
                    r.columns, r.memcpy_ms, r.zone_ms, r.pipeline_ms, r.pcl_ms, r.zone_ms / r.memcpy_ms,
                    r.pcl_ms / r.pipeline_ms, r.pipeline_p90, r.table_ms, r.critical, r.pcl_points);
        (person_x > 0 ? person[k] : empty[k]) = r;
      }
    }
  }
  // One JSON object: the first condition that ran at the top level, the others nested.
  const char* keys[3] = {"hot", "arrival", "cold"};
  int top = -1;
  for (int k = 0; k < 3; ++k) {
    if (!ran[k]) continue;
    if (top < 0) {
      top = k;
      std::printf("{\"cache\": \"%s\", ", keys[k]);
      printJsonScenes(person[k], empty[k]);
    } else {
      std::printf(", \"%s\": {", keys[k]);
      printJsonScenes(person[k], empty[k]);
      std::printf("}");
    }
  }
  if (top < 0) {
    std::fprintf(stderr, "unknown cache condition '%s' (hot, arrival or cold)\n", only.c_str());
    return 2;
  }
  std::printf("}\n");
  return 0;
}
