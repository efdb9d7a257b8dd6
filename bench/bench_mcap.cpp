// MCAP: what `run --mcap` adds per VLP-16 scan (io::FoxgloveSink::write_frame on the pipeline's
// results of a simulated open field with 10 people), on the caller's thread with the writer's
// worker thread (the default) and fully synchronous (all the CPU it costs: encoding, chunk
// compression, CRCs); and reading a ROS 2 MCAP bag of VelodyneScan messages (zstd chunks)
// through the bag source, in scans/s (real time is 10 scans/s). The file goes to /dev/null for
// the writer, so disk speed is not measured.
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <filesystem>
#include <memory>

#include "ringtrack/io/foxglove_sink.hpp"
#include "ringtrack/io/mcap_writer.hpp"
#include "ringtrack/io/rosbag_source.hpp"
#include "ringtrack/pipeline/pipeline.hpp"
#include "ringtrack/sim/scenario.hpp"
#include "ringtrack/sim/simulator.hpp"
#include "support/rosbag_writers.hpp"
#include "support/velodyne_encoder.hpp"

namespace {

using namespace ringtrack;

constexpr int kScans = 60;

// A scan and the pipeline's result on it, owned (FrameResult's spans point into these).
struct Frame {
  core::OrganizedScan scan;
  core::Pose pose;
  std::vector<std::uint8_t> labels;
  std::vector<core::Detection> detections;
  std::vector<tracking::Hypothesis> hypotheses;
  std::vector<std::uint32_t> removed;
  pipeline::FrameResult result() const {
    pipeline::FrameResult r;
    r.stamp_ns = scan.stamp_ns;
    r.segment_labels = labels;
    r.detections = detections;
    r.hypotheses = hypotheses;
    r.removed_cells = removed;
    return r;
  }
};

struct Run {
  std::vector<Frame> frames;
  std::unique_ptr<pipeline::Pipeline> pipeline;  // its static map is the one written
  std::size_t points{0};
};

const Run& run() {
  static const Run data = [] {
    auto scenario = sim::builtin_scenario("1");
    scenario.people = 10;
    sim::Simulator simulator(scenario, 7);
    Run r;
    r.pipeline = std::make_unique<pipeline::Pipeline>(core::Config{}, core::SensorModel::vlp16());
    sim::SimulatedScan s;
    for (int k = 0; k < kScans; ++k) {
      simulator.next(s);
      const auto& result = r.pipeline->process(s.scan, s.pose);
      Frame f{s.scan,
              s.pose,
              {result.segment_labels.begin(), result.segment_labels.end()},
              {result.detections.begin(), result.detections.end()},
              {result.hypotheses.begin(), result.hypotheses.end()},
              {result.removed_cells.begin(), result.removed_cells.end()}};
      r.points += s.scan.valid_count();
      r.frames.push_back(std::move(f));
    }
    r.points /= kScans;
    return r;
  }();
  return data;
}

// Arguments: compression (0 none, 1 lz4, 2 zstd), background (0/1).
void BM_McapSinkScan(benchmark::State& state) {
  const Run& data = run();
  io::FoxgloveSinkOptions options;
  options.mcap.compression = static_cast<io::McapCompression>(state.range(0));
  options.mcap.background = state.range(1) != 0;
  auto sink = std::make_unique<io::FoxgloveSink>("/dev/null", options);
  std::size_t next = 0;
  for (auto _ : state) {
    const Frame& f = data.frames[next];
    sink->write_frame(f.scan, f.pose, f.result(), data.pipeline->static_map());
    if (++next == data.frames.size()) next = 0;
  }
  // The last chunks and the summary are written after the timed loop (outside the timing).
  sink->finish(data.pipeline->static_map(), 0);
  state.counters["points/scan"] = static_cast<double>(data.points);
}
BENCHMARK(BM_McapSinkScan)
    ->ArgNames({"compression", "background"})
    ->Args({2, 1})
    ->Args({1, 1})
    ->Args({0, 1})
    ->Args({2, 0})
    ->Args({1, 0})
    ->Args({0, 0})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// A ROS 2 MCAP bag (our writer, profile ros2, zstd chunks) of 20 VLP-16 revolutions.
void BM_McapBagReadVelodyneScan(benchmark::State& state) {
  test::VelodyneEncoderOptions eo;
  const test::VelodyneEncoder enc(eo);
  const auto packets = enc.encode(0, 754 * 20, [](long long s, int laser) {
    return test::VelodyneEchoPair{{static_cast<std::uint16_t>(800 + (s * 7 + laser) % 5000), 9},
                                  {}};
  });
  const auto messages = test::velodyne_scan_messages(packets, 0, test::RosEncoding::kCdr);
  const auto path = std::filesystem::temp_directory_path() /
                    ("ringtrack_bench_" + std::to_string(::getpid()) + ".mcap");
  {
    io::McapWriterOptions o;
    o.profile = "ros2";
    io::McapWriter w(path, o);
    const auto schema = w.add_schema("velodyne_msgs/msg/VelodyneScan", "ros2msg", {});
    const auto channel = w.add_channel(schema, "/velodyne_packets", "cdr");
    for (const auto& m : messages) {
      w.write_message(channel, static_cast<std::uint64_t>(m.stamp_ns),
                      static_cast<std::uint64_t>(m.stamp_ns), m.data);
    }
    w.close();
  }
  std::int64_t scans = 0;
  for (auto _ : state) {
    io::RosbagScanSource source(path);
    while (auto scan = source.next()) ++scans;
  }
  std::filesystem::remove(path);
  state.counters["scans/s"] =
      benchmark::Counter(static_cast<double>(scans), benchmark::Counter::kIsRate);
  state.counters["x real time"] =
      benchmark::Counter(static_cast<double>(scans) / 10.0, benchmark::Counter::kIsRate);
}
BENCHMARK(BM_McapBagReadVelodyneScan)->Unit(benchmark::kMillisecond);

}  // namespace
