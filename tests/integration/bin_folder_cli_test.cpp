// `ringtrack run` and `ringtrack convert` on a folder of KITTI-style .bin files (issue 13):
// recognised as a folder, organized with --sensor or a measured sensor, the organizer's line in
// the summary, and a truncated file as one error line.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>

#include "ringtrack/core/cloud_organizer.hpp"
#include "ringtrack/io/kitti_bin.hpp"
#include "ringtrack/io/sequence.hpp"
#include "ringtrack/sim/simple_scene.hpp"
#include "support/run_command.hpp"

namespace ringtrack {
namespace {

namespace fs = std::filesystem;
using testing::run_command;
const std::string kCli = RINGTRACK_CLI_PATH;

fs::path write_bins(const std::string& dir) {
  const fs::path bins = fs::path(dir) / "velodyne";
  fs::create_directories(bins);
  const auto scan = sim::render(core::SensorModel::vlp16(), sim::SimpleScene::demo()).scan;
  for (int k = 0; k < 3; ++k) {
    io::write_kitti_bin(bins / ("00000" + std::to_string(k) + ".bin"), core::flatten_scan(scan));
  }
  return bins;
}

TEST(BinFolderCli, RunAndConvertReadAFolderOfBinFiles) {
  const std::string dir = testing::make_temp_dir("ringtrack-bins-");
  const fs::path bins = write_bins(dir);
  auto r = run_command(kCli + " run " + bins.string() + " --sensor vlp16 --out " + dir + "/run");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("input            organized 3 clouds: "), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("0 between rings"), std::string::npos) << r.out;

  r = run_command(kCli + " convert " + bins.string() + " --sensor vlp16 --quiet --out " + dir +
                  "/seq");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  io::SequenceReader seq(dir + "/seq");
  EXPECT_EQ(seq.size(), 3u);
  EXPECT_EQ(seq.meta().sensor, "vlp16");

  // Without --sensor: measured on the first file.
  r = run_command(kCli + " convert " + bins.string() + " --out " + dir + "/measured");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("3 scan files; sensor measured on 000000.bin: 16 rings ("),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find(" columns; organized 3 clouds"), std::string::npos) << r.err;
  EXPECT_EQ(io::SequenceReader(dir + "/measured").meta().sensor, "generic");
  fs::remove_all(dir);
}

// With --on-bad-scan stop the run ends on the file with one line; by default (skip) the file is
// skipped with a warning naming it, and the other scans are processed.
TEST(BinFolderCli, ATruncatedFileIsOneErrorLineOrSkipped) {
  const std::string dir = testing::make_temp_dir("ringtrack-bins-");
  const fs::path bins = write_bins(dir);
  fs::resize_file(bins / "000001.bin", fs::file_size(bins / "000001.bin") - 6);
  const auto stop =
      run_command(kCli + " run " + bins.string() +
                  " --sensor vlp16 --quiet --on-bad-scan stop --out " + dir + "/stop");
  EXPECT_NE(stop.exit_code, 0);
  EXPECT_NE(stop.err.find("000001.bin: "), std::string::npos) << stop.err;
  EXPECT_NE(stop.err.find("is not a multiple of 16"), std::string::npos) << stop.err;
  EXPECT_EQ(std::count(stop.err.begin(), stop.err.end(), '\n'), 1) << stop.err;
  const auto skip =
      run_command(kCli + " run " + bins.string() + " --sensor vlp16 --out " + dir + "/skip");
  EXPECT_EQ(skip.exit_code, 0) << skip.err;
  EXPECT_NE(skip.err.find("000001.bin"), std::string::npos) << skip.err;
  EXPECT_NE(skip.err.find("is not a multiple of 16"), std::string::npos) << skip.err;
  fs::remove_all(dir);
}

}  // namespace
}  // namespace ringtrack
