// Hesai inputs through io: the real bags written into a pcap give the same scans as the bags;
// input recognition (pcap by its packets, bags by their topic type) and the CLI's one-line
// errors (no calibration, a calibration for another model, a truncated capture). Real data from
// ../shared/data/hesai_nebula; skips when it is absent.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "io_test_util.hpp"
#include "ringtrack/core/error.hpp"
#include "ringtrack/io/hesai_pcap_source.hpp"
#include "ringtrack/io/rosbag_reader.hpp"
#include "ringtrack/io/rosbag_source.hpp"
#include "ringtrack/io/scan_source.hpp"
#include "support/run_command.hpp"
#include "support/velodyne_encoder.hpp"

namespace ringtrack::io {
namespace {

namespace fs = std::filesystem;
const std::string kCli = RINGTRACK_CLI_PATH;

fs::path model_dir(const std::string& model) {
  if (const char* env = std::getenv("RINGTRACK_TEST_DATA")) {
    return fs::path(env) / "hesai_nebula" / model;
  }
  return fs::path(RINGTRACK_SOURCE_DIR) / ".." / "shared" / "data" / "hesai_nebula" / model;
}

#define REQUIRE_HESAI(dir)                                                            \
  if (!fs::exists((dir) / "ros2_bag")) {                                              \
    GTEST_SKIP() << "real Hesai test data not found at " << (dir)                     \
                 << " (set RINGTRACK_TEST_DATA to the folder holding hesai_nebula/)"; \
  }

// The bag's packets as Ethernet/IPv4/UDP frames to port 2368, stamped as in the bag.
std::vector<::ringtrack::test::PcapFrame> frames_of(const fs::path& bag) {
  auto reader = open_rosbag(bag);
  reader->select_topic(reader->topics().front().name);
  std::vector<::ringtrack::test::PcapFrame> frames;
  RosbagMessage m;
  while (reader->next(m)) {
    for (const auto& p : parse_pandar_scan(m.data, reader->serialization(), "bag")) {
      frames.push_back(::ringtrack::test::udp_frame(
          ::ringtrack::test::PcapLink::kEthernet,
          std::vector<std::uint8_t>(p.data.begin(), p.data.end()), 2368, p.stamp_ns));
    }
  }
  return frames;
}

TEST(HesaiSources, PcapGivesTheBagsScans) {
  for (const std::string model : {"PandarXT32", "Pandar40P"}) {
    const fs::path dir = model_dir(model);
    REQUIRE_HESAI(dir);
    test::TempDir tmp;
    const fs::path pcap = tmp.path() / "hesai.pcap";
    ::ringtrack::test::write_pcap(pcap, ::ringtrack::test::PcapLink::kEthernet,
                                  frames_of(dir / "ros2_bag"), true);
    EXPECT_TRUE(pcap_holds_hesai(pcap, 2368));
    ScanSourceOptions options;
    options.calibration = (dir / (model + ".csv")).string();
    auto from_pcap = open_source(pcap.string(), options);
    auto from_bag = open_source((dir / "ros2_bag").string(), options);
    std::size_t scans = 0;
    while (auto a = from_pcap->next()) {
      auto b = from_bag->next();
      ASSERT_TRUE(b.has_value());
      test::expect_same_cells(*a, *b);
      EXPECT_EQ(a->column_stamp_ns, b->column_stamp_ns);
      ++scans;
    }
    EXPECT_FALSE(from_bag->next().has_value());
    EXPECT_GE(scans, 2u) << from_pcap->summary();
    EXPECT_EQ(from_pcap->model().name, model);
  }
}

TEST(HesaiSources, NoCalibrationIsOneClearError) {
  const fs::path dir = model_dir("PandarXT16");
  REQUIRE_HESAI(dir);
  ScanSourceOptions options;
  EXPECT_EQ(test::input_error([&] { open_source((dir / "ros2_bag").string(), options); }),
            (dir / "ros2_bag").string() +
                ": topic /pandar_packets holds Hesai packets; give the sensor's angle-correction "
                "file with --calibration FILE");
}

TEST(HesaiSources, CliErrorsAreOneLine) {
  const fs::path dir = model_dir("PandarXT16");
  REQUIRE_HESAI(dir);
  test::TempDir tmp;
  // A calibration of another model (XT32's 32 channels for XT16 packets).
  const std::string wrong = (model_dir("PandarXT32") / "PandarXT32.csv").string();
  auto r = testing::run_command(kCli + " convert " + (dir / "ros2_bag").string() + " --out " +
                                (tmp.path() / "out").string() + " --calibration " + wrong);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find(wrong + ": 32 channels, but PandarXT16 packets have 16"), std::string::npos)
      << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_FALSE(fs::exists(tmp.path() / "out"));
  r = testing::run_command(kCli + " run " + (dir / "ros2_bag").string() + " --quiet --out " +
                           (tmp.path() / "run0").string() + " --calibration " + wrong);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_FALSE(fs::exists(tmp.path() / "run0")) << "an output was left behind";
  // A calibration file with a channel missing.
  const fs::path cut = tmp.path() / "cut.csv";
  {
    std::ifstream in(dir / "PandarXT16.csv");
    std::ofstream out(cut);
    std::string line;
    for (int i = 0; std::getline(in, line); ++i) {
      if (i != 3) out << line << "\n";
    }
  }
  r = testing::run_command(kCli + " run " + (dir / "ros2_bag").string() + " --quiet --out " +
                           (tmp.path() / "run").string() + " --calibration " + cut.string());
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find(cut.string() + ": channel 16 but only 15 rows"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  // A truncated capture: the file ends inside a packet record; the decoded part is used and
  // the summary says so.
  const fs::path pcap = tmp.path() / "t.pcap";
  ::ringtrack::test::write_pcap(pcap, ::ringtrack::test::PcapLink::kEthernet,
                                frames_of(dir / "ros2_bag"), true);
  fs::resize_file(pcap, fs::file_size(pcap) - 100);
  r = testing::run_command(kCli + " convert " + pcap.string() + " --out " +
                           (tmp.path() / "conv").string() + " --calibration " +
                           (dir / "PandarXT16.csv").string());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("file truncated"), std::string::npos) << r.err;
  // Packets of another model than the named one.
  r = testing::run_command(kCli + " convert " + pcap.string() + " --out " +
                           (tmp.path() / "conv2").string() + " --sensor PandarXT32 --calibration " +
                           wrong);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("a PandarXT16 packet, but the stream is PandarXT32 (named)"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
}

}  // namespace
}  // namespace ringtrack::io
