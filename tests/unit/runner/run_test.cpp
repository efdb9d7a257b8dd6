// runner::Run in-process: the outputs of a run are what pipeline::Pipeline gives scan by scan.
// Oracle: the same scans (runner::RunInput) through a Pipeline of our own, its reported
// hypotheses made rows with track_row and formatted as tracks.csv formats them; a stop request
// must leave every output complete for the scans done. Input: a short simulated sequence
// (scenario 1, people walking past a static sensor) written to a temp folder.
#include "ringtrack/runner/run.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "ringtrack/core/error.hpp"
#include "ringtrack/io/csv_writers.hpp"
#include "ringtrack/io/sequence.hpp"
#include "ringtrack/sim/scenario.hpp"
#include "ringtrack/sim/scenario_file.hpp"
#include "ringtrack/sim/simulator.hpp"
#include "support/temp_dir.hpp"

namespace ringtrack::runner {
namespace {

namespace fs = std::filesystem;

constexpr int kScans = 12;
// Default options, named: a braced temporary trips g++ 12's -Wmaybe-uninitialized.
const RunInputOptions kDefaults;

// Scenario 1 for kScans scans (static sensor, people walking), as `ringtrack simulate` writes it.
void write_sequence(const fs::path& folder) {
  sim::Scenario scenario = sim::resolve_scenario("1");
  sim::Simulator simulator(scenario, 3);
  io::SequenceMeta meta =
      io::SequenceMeta::for_sensor(simulator.model(), simulator.model().columns());
  meta.sensor_height_m =
      sim::sensor_pose(scenario.sensor, 0).translation.z() - scenario.ground.height_m;
  io::SequenceWriter writer(folder, meta);
  sim::SimulatedScan scan;
  for (int k = 0; k < kScans; ++k) {
    simulator.next(scan);
    writer.add_scan(scan.scan, scan.labels, scan.pose);
  }
  writer.finish();
}

std::string read_text(const fs::path& path) {
  std::ifstream f(path, std::ios::binary);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

// The run's config: the sequence's sensor height, as `ringtrack run` takes it.
core::Config config_for(const RunInput& input) {
  core::Config config;
  config.detection.sensor_height_m = *input.stated_sensor_height();
  return config;
}

// tracks.csv's lines after its header for the reported hypotheses of each scan, from a Pipeline
// fed scan by scan.
std::vector<std::string> pipeline_rows(const fs::path& sequence) {
  RunInput input(sequence.string(), kDefaults);
  const core::Config config = config_for(input);
  std::unique_ptr<pipeline::Pipeline> pipeline;
  std::vector<std::string> lines;
  std::size_t index = 0;
  core::OrganizedScan scan;
  core::Pose pose;
  while (input.next(index, scan, pose)) {
    if (!pipeline) pipeline = std::make_unique<pipeline::Pipeline>(config, input.sensor_model());
    const auto& result = pipeline->process(scan, pose);
    for (const auto& h : result.hypotheses) {
      if (h.reported) {
        lines.push_back(io::format_track_row(track_row(index, scan.stamp_ns, h, result.origin)));
      }
    }
  }
  return lines;
}

std::vector<std::string> lines_after_header(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, io::kTracksCsvHeader);
  while (std::getline(in, line)) lines.push_back(line);
  return lines;
}

class RunTest : public ::testing::Test {
 protected:
  void SetUp() override { write_sequence(dir_ / "seq"); }
  [[nodiscard]] std::string sequence() const { return (dir_ / "seq").string(); }
  [[nodiscard]] fs::path out(const std::string& name) const {
    fs::create_directories(dir_ / name);
    return dir_ / name;
  }
  test::TempDir dir_;
};

TEST_F(RunTest, TrackRowsAreWhatThePipelineGivesScanByScan) {
  RunInput input(sequence(), kDefaults);
  RunOptions options;
  options.out = out("run");
  std::vector<std::string> reported;  // what on_scan hands over, formatted
  std::size_t calls = 0;
  options.on_scan = [&](std::size_t index, const pipeline::FrameResult&,
                        const std::vector<io::TrackRow>& rows) {
    EXPECT_EQ(index, calls++);
    for (const auto& row : rows) reported.push_back(io::format_track_row(row));
  };
  const RunSummary summary = run(input, config_for(input), options);

  const std::vector<std::string> expected = pipeline_rows(sequence());
  ASSERT_FALSE(expected.empty()) << "the scenario should give tracks within " << kScans << " scans";
  EXPECT_EQ(lines_after_header(read_text(options.out / "tracks.csv")), expected);
  EXPECT_EQ(reported, expected);
  EXPECT_EQ(calls, static_cast<std::size_t>(kScans));
  EXPECT_EQ(summary.scans, static_cast<std::size_t>(kScans));
  EXPECT_EQ(summary.total_ms.size(), static_cast<std::size_t>(kScans));
  EXPECT_GT(summary.tracks, 0u);
  EXPECT_GT(summary.map_voxels, 0u);
  EXPECT_FALSE(summary.stopped);
  EXPECT_FALSE(summary.raw_map);
  EXPECT_FALSE(fs::exists(options.out / "raw_map.ply"));
  EXPECT_FALSE(fs::exists(options.out / "odometry.csv"));
  for (const char* name :
       {"timing.csv", "poses.txt", "static_map.ply", "static_map.pcd", "config.yaml"}) {
    EXPECT_TRUE(fs::exists(options.out / name)) << name;
  }
}

TEST_F(RunTest, AStopRequestEndsWithCompleteOutputsForTheScansDone) {
  RunInput input(sequence(), kDefaults);
  std::atomic<bool> stop{false};
  RunOptions options;
  options.out = out("stopped");
  options.filtered_scans = true;
  options.raw_map = true;
  options.stop = &stop;
  options.on_scan = [&stop](std::size_t index, const pipeline::FrameResult&,
                            const std::vector<io::TrackRow>&) {
    if (index == 4) stop = true;
  };
  io::RunStatus status;
  const RunSummary summary = run(input, config_for(input), options, &status);
  EXPECT_TRUE(summary.stopped);
  EXPECT_EQ(summary.scans, 5u);
  EXPECT_EQ(status.scans_read, 5u);
  EXPECT_EQ(status.scans_processed, 5u);
  // Every processed scan, once the filter decided on all of them at finish().
  for (int k = 0; k < 5; ++k) {
    char name[32];
    std::snprintf(name, sizeof name, "%06d.pcd", k);
    EXPECT_TRUE(fs::exists(options.out / "filtered" / name)) << name;
  }
  EXPECT_FALSE(fs::exists(options.out / "filtered" / "000005.pcd"));
  // poses.txt: its header comment and one pose per scan done.
  const std::string poses = read_text(options.out / "poses.txt");
  EXPECT_EQ(poses[0], '#');
  EXPECT_EQ(std::count(poses.begin(), poses.end(), '\n'), 1 + 5);
  // The rows of the scans done, nothing after them.
  std::vector<std::string> expected = pipeline_rows(sequence());
  std::erase_if(expected, [](const std::string& line) { return std::stoi(line) >= 5; });
  ASSERT_FALSE(expected.empty());
  EXPECT_EQ(lines_after_header(read_text(options.out / "tracks.csv")), expected);
  EXPECT_TRUE(summary.raw_map);
  EXPECT_TRUE(fs::exists(options.out / "raw_map.ply"));
}

TEST_F(RunTest, NoScanIsAnErrorNamingTheInput) {
  RunInput input(sequence(), kDefaults);
  std::atomic<bool> stop{true};
  RunOptions options;
  options.out = out("none");
  options.stop = &stop;
  runner::Run r(input, config_for(input), options);  // qualified: gtest has its own Run
  EXPECT_FALSE(r.step());
  EXPECT_EQ(r.scans(), 0u);
  try {
    (void)r.finish();
    FAIL() << "expected core::InputError";
  } catch (const core::InputError& e) {
    EXPECT_EQ(std::string(e.what()), sequence() + ": no scans found");
  }
}

TEST(UseOdometry, AutoIsOnForRecordingsWithoutPoses) {
  EXPECT_TRUE(use_odometry("auto", false, ""));
  EXPECT_FALSE(use_odometry("auto", true, ""));
  EXPECT_FALSE(use_odometry("auto", false, "poses.tum"));
  EXPECT_TRUE(use_odometry("on", true, ""));
  EXPECT_FALSE(use_odometry("off", false, ""));
  EXPECT_THROW((void)use_odometry("on", false, "poses.tum"), core::InputError);
}

}  // namespace
}  // namespace ringtrack::runner
