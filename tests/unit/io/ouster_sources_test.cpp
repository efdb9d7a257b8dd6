// Ouster captures through the CLI: a summary for `ringtrack run`, and one-line errors that leave
// no output behind (no metadata, metadata of another sensor, metadata without a needed key).
// Real data from ../shared/data/ouster_sdk; skips when it is absent.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "io_test_util.hpp"
#include "support/run_command.hpp"

namespace ringtrack::io {
namespace {

namespace fs = std::filesystem;
const std::string kCli = RINGTRACK_CLI_PATH;

fs::path ouster_dir() {
  if (const char* env = std::getenv("RINGTRACK_TEST_DATA")) return fs::path(env) / "ouster_sdk";
  return fs::path(RINGTRACK_SOURCE_DIR) / ".." / "shared" / "data" / "ouster_sdk";
}

TEST(OusterCli, RunAndOneLineErrors) {
  const fs::path d = ouster_dir();
  const fs::path pcap = d / "OS-0-32-U1_v2.2.0_1024x10.pcap";
  if (!fs::exists(pcap)) {
    GTEST_SKIP() << "real Ouster test data not found at " << d
                 << " (set RINGTRACK_TEST_DATA to the folder holding ouster_sdk/)";
  }
  test::TempDir tmp;
  auto r = testing::run_command(
      kCli + " run " + (d / "OS-1-128_v2.3.0_1024x10_lb_n3.pcap").string() + " --metadata " +
      (d / "OS-1-128_v2.3.0_1024x10.json").string() + " --out " + (tmp.path() / "run").string());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("192 Ouster lidar packets decoded (RNG15_RFL8_NIR8), 3 scans"),
            std::string::npos)
      << r.out;

  const auto one_line_error = [&](const std::string& args, const std::string& expected) {
    const fs::path out = tmp.path() / "x";
    const auto e = testing::run_command(kCli + " run " + args + " --out " + out.string());
    EXPECT_EQ(e.exit_code, 1) << e.err;
    EXPECT_NE(e.err.find(expected), std::string::npos) << e.err;
    EXPECT_EQ(std::count(e.err.begin(), e.err.end(), '\n'), 1) << e.err;
    EXPECT_FALSE(fs::exists(out)) << "an output was left behind";
  };
  one_line_error(pcap.string(),
                 "Ouster lidar packets (port 7502); give the sensor's metadata JSON with "
                 "--metadata FILE");
  one_line_error(pcap.string() + " --metadata " + (d / "OS-2-128-U1_v2.3.0_1024x10.json").string(),
                 "(frame 1): ouster packet 1: 8448 bytes, but the metadata");
  // Metadata without the beam angles.
  std::string json = test::read_text(d / "OS-0-32-U1_v2.2.0_1024x10.json");
  json.replace(json.find("\"beam_altitude_angles\""), 22, "\"beam_altitude_angle_\"");
  const fs::path cut = tmp.path() / "cut.json";
  std::ofstream(cut) << json;
  one_line_error(pcap.string() + " --metadata " + cut.string(),
                 cut.string() + ": metadata has no 'beam_altitude_angles'");
}

}  // namespace
}  // namespace ringtrack::io
