// `ringtrack convert udp://...`: packets replayed to the live tool are recorded; Ctrl-C (SIGINT)
// ends the recording with a complete sequence folder holding the scans of the packets.

#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "ringtrack/io/sequence.hpp"
#include "ringtrack/io/velodyne_decoder.hpp"
#include "support/run_command.hpp"
#include "support/udp_replay.hpp"
#include "support/velodyne_encoder.hpp"

namespace ringtrack {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

const std::string kCli = RINGTRACK_CLI_PATH;

TEST(ConvertUdpCli, CtrlCEndsTheRecordingWithACompleteSequence) {
  const std::string dir = testing::make_temp_dir("ringtrack-convert-udp-");
  const std::uint16_t port = test::free_udp_port();
  const std::string err_path = dir + "/stderr.txt";
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    const int err = ::open(err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    ::dup2(err, 2);
    const std::string url = "udp://127.0.0.1:" + std::to_string(port);
    const std::string out = dir + "/seq";
    ::execl(kCli.c_str(), "ringtrack", "convert", url.c_str(), "--out", out.c_str(),
            static_cast<char*>(nullptr));
    ::_exit(127);
  }
  bool bound = false;
  for (int i = 0; i < 500 && !bound; ++i) {
    std::this_thread::sleep_for(10ms);
    bound = test::udp_port_bound(port);
  }
  ASSERT_TRUE(bound) << "the tool did not bind port " << port;

  test::VelodyneEncoderOptions eo;
  eo.start_azimuth_deg = 180.0;
  const test::VelodyneEncoder enc(eo);
  const auto packets = enc.encode(0, 250, [](long long s, int laser) {
    return test::VelodyneEchoPair{{static_cast<std::uint16_t>(700 + (s * 13 + laser) % 8000), 3},
                                  {}};
  });
  std::vector<std::vector<std::uint8_t>> payloads;
  for (const auto& p : packets) payloads.push_back(p.payload);
  ASSERT_NO_THROW(test::replay_to_loopback(payloads, port));  // never fills the receive buffer
  std::this_thread::sleep_for(300ms);                         // let the receiver drain the socket
  ::kill(pid, SIGINT);
  int status = 0;
  if (!testing::wait_or_kill(pid, status)) {
    FAIL() << "the tool did not stop on SIGINT";
  }
  std::stringstream err;
  err << std::ifstream(err_path).rdbuf();
  ASSERT_TRUE(WIFEXITED(status)) << err.str();
  ASSERT_EQ(WEXITSTATUS(status), 0) << err.str();

  io::VelodyneDecoder decoder;
  for (const auto& p : packets) decoder.add_packet(p.payload, p.host_stamp_ns);
  decoder.finish();
  std::vector<core::OrganizedScan> expected;
  while (auto s = decoder.pop_scan()) expected.push_back(std::move(*s));
  ASSERT_EQ(expected.size(), 2u);
  io::SequenceReader reader(dir + "/seq");  // sequence.yaml written: complete
  ASSERT_EQ(reader.size(), expected.size()) << err.str();
  io::SequenceScan s;
  for (const auto& e : expected) {
    ASSERT_TRUE(reader.next(s));
    ASSERT_EQ(s.scan.valid_count(), e.valid_count());
    for (std::size_t i = 0; i < e.size(); ++i) {
      if (e.valid(i)) {
        ASSERT_LT((s.scan.point(i) - e.point(i)).norm(), 1e-6f) << "cell " << i;
      }
    }
  }
  EXPECT_NE(err.str().find("wrote 2 scans"), std::string::npos) << err.str();
  fs::remove_all(dir);
}

}  // namespace
}  // namespace ringtrack
