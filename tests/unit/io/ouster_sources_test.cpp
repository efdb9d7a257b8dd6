// Ouster inputs through the CLI: a summary for `ringtrack run`, and one-line errors that leave
// no output behind (no metadata, metadata of another sensor, metadata without a needed key, a
// return the profile cannot give); real data from ../shared/data/ouster_sdk, skipped when it is
// absent. Live: `ringtrack run udp://... --metadata` on hand-encoded packets, ended by Ctrl-C.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "io_test_util.hpp"
#include "support/ouster_encoder.hpp"
#include "support/run_command.hpp"
#include "support/udp_replay.hpp"
#include "support/velodyne_encoder.hpp"

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

// `frames` frames of 1024 columns of the encoder's default sensor (16 beams, RNG19).
std::vector<std::vector<std::uint8_t>> encoded_frames(
    const ringtrack::test::OusterEncoderOptions& o, double frames) {
  std::vector<std::vector<std::uint8_t>> ps;
  const int per_frame = 1024 / o.columns_per_packet;
  for (int k = 0; k < static_cast<int>(frames * per_frame); ++k) {
    ringtrack::test::OusterEncoderOptions eo = o;
    eo.frame_id = o.frame_id + k / per_frame;
    ps.push_back(ringtrack::test::encode_ouster_packet(
        eo, (k % per_frame) * o.columns_per_packet,
        1'000'000'000LL * 1'700'000'000 + k * 1'562'500LL, [](int m, int beam) {
          return ringtrack::test::OusterEcho{
              static_cast<std::uint32_t>(2000 + 8 * ((m + beam) % 900)), 0, 30};
        }));
  }
  return ps;
}

TEST(OusterCli, ASelectionTheProfileCannotGiveIsOneLine) {
  test::TempDir tmp;
  const ringtrack::test::OusterEncoderOptions eo;
  const fs::path json = tmp.path() / "os.json";
  test::write_text(json, ringtrack::test::ouster_metadata_json(eo));
  std::vector<ringtrack::test::PcapFrame> frames;
  for (const auto& p : encoded_frames(eo, 1.0)) {
    frames.push_back(ringtrack::test::udp_frame(ringtrack::test::PcapLink::kEthernet, p, 7502,
                                                1'000'000'000, 7502));
  }
  const fs::path pcap = tmp.path() / "o.pcap";
  ringtrack::test::write_pcap(pcap, ringtrack::test::PcapLink::kEthernet, frames);
  const fs::path out = tmp.path() / "x";
  for (const auto& [args, expected] :
       {std::pair{" --metadata " + json.string() + " --return second",
                  json.string() + ": the second return needs the RNG19_RFL8_SIG16_NIR16_DUAL "
                                  "profile, but the sensor sends RNG19_RFL8_SIG16_NIR16"},
        std::pair{std::string(" --return second"),
                  std::string("return 'second': only Ouster's RNG19_RFL8_SIG16_NIR16_DUAL "
                              "profile reports a second strongest return")}}) {
    const auto e =
        testing::run_command(kCli + " run " + pcap.string() + args + " --out " + out.string());
    EXPECT_EQ(e.exit_code, 1) << e.err;
    EXPECT_NE(e.err.find(expected), std::string::npos) << e.err;
    EXPECT_EQ(std::count(e.err.begin(), e.err.end(), '\n'), 1) << e.err;
    EXPECT_FALSE(fs::exists(out)) << "an output was left behind";
  }
}

// `ringtrack run udp://127.0.0.1:PORT --metadata FILE`: 2.5 frames of packets, then SIGINT; the
// run ends normally with the two whole frames and says it was interrupted.
TEST(OusterCli, LiveRunEndsOnCtrlC) {
  test::TempDir tmp;
  const ringtrack::test::OusterEncoderOptions eo;
  const fs::path json = tmp.path() / "os.json";
  test::write_text(json, ringtrack::test::ouster_metadata_json(eo));
  const std::uint16_t port = ringtrack::test::free_udp_port();
  const std::string out_path = (tmp.path() / "stdout.txt").string();
  const std::string err_path = (tmp.path() / "stderr.txt").string();
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    ::dup2(::open(out_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644), 1);
    ::dup2(::open(err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644), 2);
    const std::string url = "udp://127.0.0.1:" + std::to_string(port);
    const std::string out = (tmp.path() / "run").string();
    ::execl(kCli.c_str(), "ringtrack", "run", url.c_str(), "--metadata", json.c_str(), "--out",
            out.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  using namespace std::chrono_literals;
  bool bound = false;
  for (int i = 0; i < 500 && !bound; ++i) {
    std::this_thread::sleep_for(10ms);
    bound = ringtrack::test::udp_port_bound(port);
  }
  if (!bound) ::kill(pid, SIGKILL);
  ASSERT_TRUE(bound) << "the tool did not bind port " << port;
  ASSERT_NO_THROW(ringtrack::test::replay_to_loopback(encoded_frames(eo, 2.5), port));
  std::this_thread::sleep_for(500ms);  // let the receiver drain the socket
  ::kill(pid, SIGINT);
  int status = 0;
  ASSERT_TRUE(testing::wait_or_kill(pid, status)) << "the tool did not stop on SIGINT";
  const std::string out = test::read_text(out_path);
  const std::string err = test::read_text(err_path);
  ASSERT_TRUE(WIFEXITED(status)) << err;
  EXPECT_EQ(WEXITSTATUS(status), 0) << err;
  EXPECT_NE(out.find("160 datagrams, 160 Ouster lidar packets decoded (RNG19_RFL8_SIG16_NIR16), "
                     "2 scans"),
            std::string::npos)
      << out;
  EXPECT_NE(out.find("scans            2 (interrupted by SIGINT"), std::string::npos) << out;
}

}  // namespace
}  // namespace ringtrack::io
