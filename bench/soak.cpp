// ringtrack_soak: the pipeline on a long simulated stream (issue 16, "Soak"), no disk output.
// Every --sample-every scans it prints one Markdown row: resident memory (VmRSS), the mean and
// max per-scan pipeline time of the block just ended, the static map's voxels and the filter
// log's scans; at the end a verdict line: RSS growth and time drift after the warm-up.
//
// Simulating a built-in scene costs several times the pipeline (the park: about 20 ms a scan),
// so by default a block of scans (two periods of the figure 8) is simulated once without range
// noise and replayed cyclically: stamps keep increasing, each pass draws fresh range noise (the
// map sees new measurements, as from a live sensor), the figure 8 continues almost seamlessly
// (the boundary's pose jump is printed) and the people jump back to where the block started.
// --block 0 simulates the whole stream live instead. Only Pipeline::process is timed.
//
// Usage: ringtrack_soak [--scans N] [--sensor static|moving|both] [--scenario NAME]
//                       [--sample-every K] [--warm-up W] [--block B] [--seed S]

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <fstream>
#include <limits>
#include <memory>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "ringtrack/core/config.hpp"
#include "ringtrack/experiment/benchmark_case.hpp"
#include "ringtrack/pipeline/pipeline.hpp"
#include "ringtrack/sim/scenario.hpp"
#include "ringtrack/sim/simulator.hpp"

namespace {

using namespace ringtrack;
using Clock = std::chrono::steady_clock;

struct Options {
  std::int64_t scans{100'000};
  std::string sensor{"both"};
  std::string scenario{"park"};
  std::int64_t sample_every{1'000};
  std::int64_t warm_up{-1};  // scans; -1: a tenth of the run, rounded up to a sample
  std::uint64_t seed{1};
  std::int64_t block{-1};  // replayed block in scans; -1: two figure-8 periods, 0: live
};

std::int64_t parse_count(std::string_view flag, std::string_view text) {
  std::int64_t value = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc() || end != text.data() + text.size() || value < 0)
    throw std::invalid_argument(std::string(flag) + " expects a whole number >= 0, got '" +
                                std::string(text) + "'");
  return value;
}

// Rejects values the run cannot honour and rounds the warm-up up to a whole sample.
void check_options(Options& o) {
  if (o.sensor != "static" && o.sensor != "moving" && o.sensor != "both")
    throw std::invalid_argument("--sensor expects static, moving or both, got '" + o.sensor + "'");
  if (o.sample_every < 1) throw std::invalid_argument("--sample-every must be >= 1");
  if (o.scans < 2 * o.sample_every)
    throw std::invalid_argument("--scans must be at least twice --sample-every");
  if (o.warm_up < 0)
    o.warm_up = (o.scans / 10 + o.sample_every - 1) / o.sample_every;
  else
    o.warm_up = (o.warm_up + o.sample_every - 1) / o.sample_every;
  o.warm_up *= o.sample_every;
  if (o.warm_up < o.sample_every || o.warm_up + o.sample_every > o.scans)
    throw std::invalid_argument("--warm-up must leave at least one sample on each side");
}

Options parse_options(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string_view flag = argv[i];
    if (i + 1 >= argc) throw std::invalid_argument(std::string(flag) + " needs a value");
    const std::string_view value = argv[++i];
    if (flag == "--scans") {
      o.scans = parse_count(flag, value);
    } else if (flag == "--sensor") {
      o.sensor = value;
    } else if (flag == "--scenario") {
      o.scenario = value;
    } else if (flag == "--sample-every") {
      o.sample_every = parse_count(flag, value);
    } else if (flag == "--warm-up") {
      o.warm_up = parse_count(flag, value);
    } else if (flag == "--block") {
      o.block = parse_count(flag, value);
    } else if (flag == "--seed") {
      o.seed = static_cast<std::uint64_t>(parse_count(flag, value));
    } else {
      throw std::invalid_argument("unknown option '" + std::string(flag) +
                                  "' (expected --scans, --sensor, --scenario, --sample-every, "
                                  "--warm-up, --block, --seed)");
    }
  }
  check_options(o);
  return o;
}

// Resident memory from /proc/self/status in MB (kB / 1024); -1 when it cannot be read.
double resident_mb() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind("VmRSS:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;
  }
  return -1.0;
}

// Bytes the filter log holds in its scans' buffers (capacities: what the allocator keeps).
double log_mb(const mapping::DynamicObjectFilter& filter) {
  std::size_t bytes = 0;
  for (const auto& s : filter.log()) {
    bytes += s.cells.capacity() * sizeof(std::uint32_t) +
             s.points.capacity() * sizeof(Eigen::Vector3f) +
             s.intensities.capacity() * sizeof(float) + s.removed.capacity() +
             s.candidates.capacity() * sizeof(std::uint32_t) +
             s.candidate_ranges.capacity() * sizeof(float) +
             s.block_bounds.capacity() * sizeof(core::Box3);
  }
  return static_cast<double>(bytes) / (1024.0 * 1024.0);
}

struct Sample {
  std::int64_t scans{0};
  double rss_mb{0};
  double mean_ms{0};
  double max_ms{0};
  double feed_ms{0};  // mean time to produce a scan (simulate or replay), not in mean_ms
  std::size_t voxels{0};
  std::size_t map_capacity{0};
  std::size_t log_scans{0};
  double log_mb{0};
  std::size_t hypotheses{0};
};

// Accumulates one block's per-scan times.
struct Block {
  double sum_ms{0}, max_ms{0}, feed_sum_ms{0};
  std::int64_t n{0};
  void add(double ms, double feed_ms) {
    sum_ms += ms;
    max_ms = std::max(max_ms, ms);
    feed_sum_ms += feed_ms;
    ++n;
  }
};

double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

Sample take_sample(std::int64_t scans, const Block& b, const pipeline::Pipeline& p,
                   std::size_t hypotheses) {
  const auto& filter = p.dynamic_filter();
  return {scans,
          resident_mb(),
          b.sum_ms / static_cast<double>(b.n),
          b.max_ms,
          b.feed_sum_ms / static_cast<double>(b.n),
          filter.map().size(),
          filter.map().capacity(),
          filter.log().size(),
          log_mb(filter),
          hypotheses};
}

void print_row(const Sample& s, bool warm_up_end) {
  std::printf("| %lld%s | %.1f | %.3f | %.2f | %.2f | %zu | %zu | %zu | %.1f | %zu |\n",
              static_cast<long long>(s.scans), warm_up_end ? " (warm-up end)" : "", s.rss_mb,
              s.mean_ms, s.max_ms, s.feed_ms, s.voxels, s.map_capacity, s.log_scans, s.log_mb,
              s.hypotheses);
  std::fflush(stdout);
}

void print_bound(const core::Config& config) {
  const auto& m = config.mapping;
  std::printf(
      "bound: filter log of mapping.log_delay_scans = %d scans (each a scan's valid points with "
      "cells, intensities and flags; it never holds more) + static map at "
      "mapping.voxel_size_m = %.2f m (one voxel per occupied cell of the scene the sensor sees: "
      "flat once the scene is covered, unbounded while a moving sensor explores)\n",
      m.log_delay_scans, m.voxel_size_m);
}

void print_verdict(const std::vector<Sample>& samples, std::size_t warm) {
  const Sample& w = samples[warm];
  const Sample& first = samples[warm + 1];
  const Sample& last = samples.back();
  const double peak =
      std::max_element(samples.begin() + static_cast<std::ptrdiff_t>(warm), samples.end(),
                       [](const Sample& a, const Sample& b) { return a.rss_mb < b.rss_mb; })
          ->rss_mb;
  std::printf(
      "verdict: RSS %.1f MB at scan %lld (warm-up end) -> %.1f MB at scan %lld: %+.1f MB "
      "(%+.2f %%), peak after warm-up %.1f MB; time %.3f ms/scan (block to scan %lld) -> %.3f "
      "ms/scan (last block): drift %+.1f %%; map voxels %zu -> %zu\n",
      w.rss_mb, static_cast<long long>(w.scans), last.rss_mb, static_cast<long long>(last.scans),
      last.rss_mb - w.rss_mb, 100.0 * (last.rss_mb - w.rss_mb) / w.rss_mb, peak, first.mean_ms,
      static_cast<long long>(first.scans), last.mean_ms, 100.0 * (last.mean_ms / first.mean_ms - 1),
      w.voxels, last.voxels);
}

// The scenario lasting long enough for the block (built-ins last about a minute), without range
// noise when the block is replayed: each pass draws its own (fresh_noise), as a live stream would.
sim::Scenario soak_scenario(const Options& o, bool moving, std::int64_t scans) {
  auto s = sim::builtin_scenario(o.scenario);
  s.sensor.motion = sim::SensorMotion::kStatic;
  if (moving) s = sim::with_moving_sensor(s);
  const double period_s = 1.0 / core::SensorModel::by_name(s.sensor.model).scan_rate_hz;
  s.duration_s = static_cast<double>(scans + 1) * period_s;
  return s;
}

// Scans in two periods of the figure 8 (its height and yaw repeat every 4 pi / w), so that the
// replayed poses continue almost seamlessly at the block boundary.
std::int64_t default_block(const sim::Scenario& s) {
  const double rate_hz = core::SensorModel::by_name(s.sensor.model).scan_rate_hz;
  return std::llround(2.0 * 4.0 * std::numbers::pi / sim::figure8_rate(s.sensor) * rate_hz);
}

struct Feed {
  core::OrganizedScan scan;
  core::Pose pose;  // deskewed to the scan's first column for a moving sensor
};

// Simulates the next scan into feed; a moving sensor's scan is motion-compensated as a pose
// source's would be (deskew), as `ringtrack benchmark` does.
void simulate_next(sim::Simulator& simulator, sim::SimulatedScan& buffer, bool moving, Feed& feed) {
  feed.pose = experiment::next_simulated_scan(simulator, buffer, moving);
  feed.scan = buffer.scan;
}

// Moves every stamp of feed by shift_ns (a later pass over the block).
void shift_stamps(Feed& feed, std::int64_t shift_ns) {
  feed.scan.stamp_ns += shift_ns;
  for (auto& t : feed.scan.column_stamp_ns) t += shift_ns;
  feed.pose.stamp_ns += shift_ns;
}

// Adds fresh Gaussian range noise to every valid return, moving its point along its ray, so
// that a replayed scan is not the same measurement again (the map sees new noise each pass).
void fresh_noise(core::OrganizedScan& scan, std::normal_distribution<float>& noise,
                 std::mt19937_64& rng) {
  for (int ring = 0; ring < scan.rings(); ++ring) {
    for (int col = 0; col < scan.columns(); ++col) {
      const std::size_t i = scan.index(ring, col);
      if (!scan.valid(i)) continue;
      const float r = scan.range_m(i);
      const float r_new = std::max(r + noise(rng), 0.01f);
      scan.set_return(ring, col, r_new, scan.intensity(i), scan.point(i) * (r_new / r));
    }
  }
}

// Approximate bytes of the replayed block (per-cell arrays), reported beside the RSS.
double block_mb(const std::vector<Feed>& block) {
  double bytes = 0;
  for (const auto& f : block) bytes += static_cast<double>(f.scan.size()) * (5 * 4 + 1);
  return bytes / (1024.0 * 1024.0);
}

// The scans fed to the pipeline: live from the simulator (block 0), or a simulated block
// replayed cyclically with stamps that keep increasing and fresh range noise per pass.
class Stream {
 public:
  Stream(const Options& o, bool moving) {
    const auto probe = soak_scenario(o, moving, 1);
    block_size_ = o.block >= 0 ? o.block : default_block(probe);
    const std::int64_t simulated = block_size_ > 0 ? block_size_ : o.scans;
    auto scenario = soak_scenario(o, moving, simulated);
    noise_ =
        std::normal_distribution<float>(0.0f, static_cast<float>(scenario.sensor.range_noise_m));
    if (block_size_ > 0) scenario.sensor.range_noise_m = 0.0;
    simulator_ = std::make_unique<sim::Simulator>(scenario, o.seed);
    rng_.seed(o.seed);
    moving_ = moving;
    block_.resize(static_cast<std::size_t>(block_size_));
    for (auto& feed : block_) simulate_next(*simulator_, buffer_, moving_, feed);
  }

  /// Scan k of the stream (valid until the next call).
  const Feed& next(std::int64_t k) {
    if (block_size_ == 0) {
      simulate_next(*simulator_, buffer_, moving_, current_);
      return current_;
    }
    const std::int64_t pass = k / block_size_;
    current_ = block_[static_cast<std::size_t>(k % block_size_)];  // reuses current_'s buffers
    shift_stamps(current_, pass * simulator_->scan_stamp_ns(block_size_));
    fresh_noise(current_.scan, noise_, rng_);
    return current_;
  }

  [[nodiscard]] const sim::Simulator& simulator() const { return *simulator_; }
  [[nodiscard]] std::int64_t block_size() const { return block_size_; }
  [[nodiscard]] const std::vector<Feed>& block() const { return block_; }

 private:
  std::unique_ptr<sim::Simulator> simulator_;
  sim::SimulatedScan buffer_;
  std::vector<Feed> block_;
  Feed current_;
  std::int64_t block_size_{0};
  bool moving_{false};
  std::normal_distribution<float> noise_;
  std::mt19937_64 rng_;
};

// How far the sensor pose jumps when the block starts over (0 for a static sensor).
void print_stream(const Stream& stream) {
  if (stream.block_size() == 0) {
    std::printf("stream: simulated live, scan after scan\n");
    return;
  }
  const auto& b = stream.block();
  const auto& sim = stream.simulator();
  const double gap_ns = static_cast<double>(sim.scan_stamp_ns(1));
  // Where the pose one scan after the block's last would be, against the block's first.
  const auto after_last = sim.sensor_pose_at(sim.scan_stamp_ns(stream.block_size()));
  const auto first = sim.sensor_pose_at(0);
  const double jump_m = (after_last.translation - first.translation).norm();
  const double jump_deg =
      after_last.rotation.angularDistance(first.rotation) * 180.0 / std::numbers::pi;
  std::printf(
      "stream: a block of %lld simulated scans (%.1f s, about %.0f MB held) replayed cyclically, "
      "stamps continuing (%.0f ms apart), fresh range noise each pass; at each block boundary the "
      "sensor pose differs from its continuation by %.3f m and %.2f deg, and the people jump back "
      "to where the block started\n",
      static_cast<long long>(stream.block_size()),
      static_cast<double>(stream.block_size()) * gap_ns * 1e-9, block_mb(b), gap_ns * 1e-6, jump_m,
      jump_deg);
}

void run(const Options& o, bool moving) {
  const auto t_sim = Clock::now();
  Stream stream(o, moving);
  const double block_s = ms_since(t_sim) * 1e-3;
  const core::Config config;
  pipeline::Pipeline pipeline(config, stream.simulator().model());
  std::printf("\n### %s sensor, scenario %s, %lld scans, seed %llu\n\n",
              moving ? "moving" : "static", o.scenario.c_str(), static_cast<long long>(o.scans),
              static_cast<unsigned long long>(o.seed));
  print_stream(stream);
  if (stream.block_size() > 0) std::printf("block simulated in %.1f s\n", block_s);
  print_bound(config);
  std::printf(
      "\n| scans | RSS MB | mean ms | max ms | feed ms | map voxels | map slots | log scans | "
      "log MB | hypotheses |\n|---|---|---|---|---|---|---|---|---|---|\n");
  std::vector<Sample> samples;
  Block block;
  for (std::int64_t k = 0; k < o.scans; ++k) {
    const auto t_feed = Clock::now();
    const Feed& feed = stream.next(k);
    const double feed_ms = ms_since(t_feed);
    const auto t0 = Clock::now();
    const auto& result = pipeline.process(feed.scan, feed.pose);
    block.add(ms_since(t0), feed_ms);
    if ((k + 1) % o.sample_every != 0) continue;
    samples.push_back(take_sample(k + 1, block, pipeline, result.hypotheses.size()));
    print_row(samples.back(), k + 1 == o.warm_up);
    block = {};
  }
  print_verdict(samples, static_cast<std::size_t>(o.warm_up / o.sample_every - 1));
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const Options o = parse_options(argc, argv);
    if (o.sensor != "moving") run(o, false);
    if (o.sensor != "static") run(o, true);
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "ringtrack_soak: %s\n", e.what());
    return 1;
  }
}
