// MCAP: what `run --mcap` adds per VLP-16 scan (io::FoxgloveSink::write_frame on the pipeline's
// results of a simulated open field with 10 people): back to back (throughput; with the writer's
// worker thread, the default, and fully synchronous) and paced as at the sensor's rate (the
// caller's time and the total CPU per scan), per compression and zstd level; and reading a ROS 2
// MCAP bag of VelodyneScan messages (zstd chunks) through the bag source, in scans/s (real time is
// 10 scans/s). The file goes to /dev/null for the writer, so disk speed is not measured.
#include <benchmark/benchmark.h>
#include <time.h>
#include <unistd.h>

#include <chrono>
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

io::FoxgloveSinkOptions sink_options(const benchmark::State& state, bool background) {
  io::FoxgloveSinkOptions options;
  options.mcap.compression = static_cast<io::McapCompression>(state.range(0));
  options.mcap.zstd_level = static_cast<int>(state.range(1));
  options.mcap.background = background;
  return options;
}

double process_cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

void report(benchmark::State& state, const io::FoxgloveSink& sink, const Run& data) {
  state.counters["points/scan"] = static_cast<double>(data.points);
  state.counters["ratio"] = static_cast<double>(sink.mcap_stats().uncompressed_bytes) /
                            static_cast<double>(sink.mcap_stats().file_bytes);
}

// Throughput: scans written back to back. Arguments: compression (0 none, 1 lz4, 2 zstd), zstd
// level, background (0/1). Real time is bounded by the worker (compression, CRCs) when
// background; CPU time is the caller's thread only.
void BM_McapSinkScan(benchmark::State& state) {
  const Run& data = run();
  auto sink =
      std::make_unique<io::FoxgloveSink>("/dev/null", sink_options(state, state.range(2) != 0));
  std::size_t next = 0;
  for (auto _ : state) {
    const Frame& f = data.frames[next];
    sink->write_frame(f.scan, f.pose, f.result(), data.pipeline->static_map());
    if (++next == data.frames.size()) next = 0;
  }
  // The last chunks and the summary are written after the timed loop (outside the timing).
  sink->finish(data.pipeline->static_map(), 0);
  report(state, *sink, data);
}
BENCHMARK(BM_McapSinkScan)
    ->ArgNames({"compression", "level", "background"})
    ->Args({2, 1, 1})
    ->Args({2, -3, 1})
    ->Args({1, 0, 1})
    ->Args({0, 0, 1})
    ->Args({2, 1, 0})
    ->Args({2, -1, 0})
    ->Args({2, -3, 0})
    ->Args({2, -5, 0})
    ->Args({1, 0, 0})
    ->Args({0, 0, 0})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// What `run --mcap` adds per scan at the sensor's rate (10 scans/s leave the worker idle when the
// next scan comes): the time is the caller's wall time in write_frame with the worker idle at its
// start (the worker is waited for outside the timing); "total CPU ms" is the process's CPU time
// per scan over the loop (caller + worker: encoding, copies, compression, CRCs, writing).
void BM_McapSinkScanPaced(benchmark::State& state) {
  const Run& data = run();
  auto sink = std::make_unique<io::FoxgloveSink>("/dev/null", sink_options(state, true));
  std::size_t next = 0;
  const double cpu_start = process_cpu_seconds();
  for (auto _ : state) {
    const Frame& f = data.frames[next];
    const auto start = std::chrono::steady_clock::now();
    sink->write_frame(f.scan, f.pose, f.result(), data.pipeline->static_map());
    state.SetIterationTime(
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    sink->wait_idle();
    if (++next == data.frames.size()) next = 0;
  }
  const double cpu = process_cpu_seconds() - cpu_start;
  sink->finish(data.pipeline->static_map(), 0);
  report(state, *sink, data);
  state.counters["total CPU ms"] = 1e3 * cpu / static_cast<double>(state.iterations());
}
BENCHMARK(BM_McapSinkScanPaced)
    ->ArgNames({"compression", "level"})
    ->Args({2, 1})
    ->Args({2, -1})
    ->Args({2, -3})
    ->Args({2, -5})
    ->Args({1, 0})
    ->Args({0, 0})
    ->Unit(benchmark::kMillisecond)
    ->UseManualTime();

// A ROS 2 MCAP bag (our writer, profile ros2, zstd chunks) of 20 s of VLP-16 packets: 200 scans.
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
