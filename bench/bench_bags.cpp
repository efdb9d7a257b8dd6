// ROS bag inputs: organizing a full VLP-16 PointCloud2 and reading + decoding a ROS 1 bag of
// VelodyneScan messages (lz4 chunks). Real time is 10 scans/s.
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <filesystem>

#include "ringtrack/io/pointcloud2.hpp"
#include "ringtrack/io/rosbag_source.hpp"
#include "support/rosbag_writers.hpp"
#include "support/velodyne_encoder.hpp"

namespace {

using namespace ringtrack;

// One revolution as velodyne_pointcloud publishes it: every return, with ring and time fields.
std::vector<std::uint8_t> full_cloud_cdr(std::size_t& points) {
  const auto model = core::SensorModel::vlp16();
  std::vector<test::TestPoint> pts;
  const int columns = model.columns();
  for (int c = 0; c < columns; ++c) {
    for (int r = 0; r < 16; ++r) {
      if ((c + r) % 13 == 0) continue;  // some missing returns
      const double az = 6.283185307179586 * c / columns;
      const Eigen::Vector3f p = model.point(r, az, 2.0 + 0.01 * ((c * 7 + r) % 800));
      pts.push_back({p.x(), p.y(), p.z(), 10.0f, static_cast<std::uint16_t>(r),
                     static_cast<float>(c) * 55.296e-6f});
    }
  }
  points = pts.size();
  const auto cloud = test::make_xyzirt_cloud(pts, 1, static_cast<std::uint32_t>(pts.size()), 0);
  return test::serialize_pointcloud2(cloud, test::RosEncoding::kCdr);
}

void BM_PointCloud2OrganizeVlp16(benchmark::State& state) {
  std::size_t points = 0;
  const auto message = full_cloud_cdr(points);
  io::PointCloud2Organizer organizer;
  for (auto _ : state) {
    const auto cloud = io::parse_pointcloud2(message, io::RosSerialization::kCdr, "bench");
    auto scan = organizer.organize(cloud, "bench");
    benchmark::DoNotOptimize(scan);
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(points));
  state.counters["scans/s"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_PointCloud2OrganizeVlp16)->Unit(benchmark::kMillisecond);

void BM_Rosbag1VelodyneScanLz4(benchmark::State& state) {
  test::VelodyneEncoderOptions eo;
  const test::VelodyneEncoder enc(eo);
  const auto packets = enc.encode(0, 754 * 2, [](long long s, int laser) {
    return test::VelodyneEchoPair{{static_cast<std::uint16_t>(800 + (s * 7 + laser) % 5000), 9},
                                  {}};
  });
  std::vector<test::TestBagMessage> messages;
  for (std::size_t i = 0; i < packets.size(); i += 75) {
    test::TestVelodyneScan scan;
    for (std::size_t k = i; k < std::min(packets.size(), i + 75); ++k) {
      scan.packets.push_back({packets[k].host_stamp_ns, packets[k].payload});
    }
    messages.push_back({0, scan.packets.back().stamp_ns,
                        test::serialize_velodyne_scan(scan, test::RosEncoding::kRos1)});
  }
  const auto path = std::filesystem::temp_directory_path() /
                    ("ringtrack_bench_" + std::to_string(::getpid()) + ".bag");
  test::write_rosbag1(path, {{"/velodyne_packets", "velodyne_msgs/VelodyneScan"}}, messages,
                      {"lz4", 768 * 1024, true});
  std::int64_t scans = 0;
  for (auto _ : state) {
    io::RosbagScanSource source(path);
    while (auto scan = source.next()) ++scans;
  }
  std::filesystem::remove(path);
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(packets.size()));
  state.counters["scans/s"] =
      benchmark::Counter(static_cast<double>(scans), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_Rosbag1VelodyneScanLz4)->Unit(benchmark::kMillisecond);

}  // namespace
