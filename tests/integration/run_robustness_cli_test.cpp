// `ringtrack run` and `convert` on inputs between "works" and "fails" (issue 16): scans whose
// stamps go back, scans that cannot be read, SIGTERM and SIGINT, run.json, output that cannot be
// written, the decoder options both commands share.
#include <arpa/inet.h>
#include <fcntl.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "ringtrack/io/sequence.hpp"
#include "support/rosbag_writers.hpp"
#include "support/run_command.hpp"
#include "support/udp_replay.hpp"
#include "support/velodyne_encoder.hpp"

namespace ringtrack {
namespace {

namespace fs = std::filesystem;
using test::free_udp_port;
using test::udp_port_bound;
using testing::run_command;
using namespace std::chrono_literals;
const std::string kCli = RINGTRACK_CLI_PATH;

// A cloud of one ring of points around the sensor (16 rings, ring field, no time field: the
// scan's stamp is the header stamp).
std::vector<std::uint8_t> cloud_message(std::int64_t stamp_ns) {
  std::vector<test::TestPoint> points;
  for (int ring = 0; ring < 16; ++ring) {
    for (int k = 0; k < 36; ++k) {
      const double a = k * 10.0 * std::numbers::pi / 180.0;
      const double e = (-15.0 + 2.0 * ring) * std::numbers::pi / 180.0;
      points.push_back({static_cast<float>(8.0 * std::cos(e) * std::cos(a)),
                        static_cast<float>(8.0 * std::cos(e) * std::sin(a)),
                        static_cast<float>(8.0 * std::sin(e)), 20.0F,
                        static_cast<std::uint16_t>(ring), 0.0F});
    }
  }
  const auto cloud = test::make_xyzirt_cloud(points, 1, static_cast<std::uint32_t>(points.size()),
                                             stamp_ns, /*with_ring=*/true, /*with_time=*/false);
  return test::serialize_pointcloud2(cloud, test::RosEncoding::kCdr);
}

std::vector<std::string> lines_of(const fs::path& p) {
  std::ifstream in(p);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

TEST(RunRobustnessCli, ScanWhoseStampGoesBackIsSkippedWithAWarningNamingInputAndScan) {
  const std::string dir = testing::make_temp_dir("ringtrack-robust-");
  const fs::path bag = fs::path(dir) / "bag";
  // Header stamps 1.0, 1.1, 1.05 (a clock step back), 1.2 s; record stamps in order.
  const std::int64_t base = 1'700'000'001'000'000'000;
  const std::int64_t header_ns[] = {0, 100'000'000, 50'000'000, 200'000'000};
  std::vector<test::TestBagMessage> messages;
  for (int m = 0; m < 4; ++m) {
    messages.push_back({0, base + m * 100'000'000LL, cloud_message(base + header_ns[m])});
  }
  test::write_rosbag2(bag, {{"/points", "sensor_msgs/msg/PointCloud2"}}, messages);
  const std::string out = dir + "/out";
  // A static sensor (--odometry off): the odometry would add its own warning about these
  // featureless clouds, and the skip is the same with it (Pipeline::process_with_odometry).
  const auto r = run_command(kCli + " run " + bag.string() + " --odometry off --out " + out);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err, "ringtrack: warning: " + bag.string() +
                       ": scan 2: stamp 1700000001050000000 ns is 0.050000000 s older than the "
                       "previous scan's 1700000001100000000 ns (a clock step or a corrupt stamp); "
                       "skipped\n");
  EXPECT_NE(r.out.find("scans            3 (1 more skipped: stamp not after the scan before)"),
            std::string::npos)
      << r.out;
  // timing.csv: a header and the three processed scans, 0, 1 and 3.
  const auto timing = lines_of(fs::path(out) / "timing.csv");
  ASSERT_EQ(timing.size(), 4u);
  EXPECT_EQ(timing[1].substr(0, 2), "0,");
  EXPECT_EQ(timing[2].substr(0, 2), "1,");
  EXPECT_EQ(timing[3].substr(0, 2), "3,");
  fs::remove_all(dir);
}

std::string text_of(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

nlohmann::json run_json(const fs::path& folder) {
  return nlohmann::json::parse(text_of(folder / "run.json"));
}

// The scan numbers of timing.csv's rows.
std::set<int> timing_scans(const fs::path& folder) {
  std::set<int> scans;
  const auto lines = lines_of(folder / "timing.csv");
  for (std::size_t k = 1; k < lines.size(); ++k) scans.insert(std::stoi(lines[k]));
  return scans;
}

// A file whose last row was cut would not end with a newline.
bool ends_with_newline(const fs::path& p) {
  const std::string text = text_of(p);
  return !text.empty() && text.back() == '\n';
}

TEST(RunRobustnessCli, CorruptBagMessageIsSkippedAndCounted) {
  const std::string dir = testing::make_temp_dir("ringtrack-robust-");
  const fs::path bag = fs::path(dir) / "bag";
  const std::int64_t base = 1'700'000'001'000'000'000;
  std::vector<test::TestBagMessage> messages;
  for (int m = 0; m < 4; ++m) {
    auto data = cloud_message(base + m * 100'000'000LL);
    if (m == 1) data.resize(data.size() / 2);  // cut short: the cloud's data is incomplete
    messages.push_back({0, base + m * 100'000'000LL, std::move(data)});
  }
  test::write_rosbag2(bag, {{"/points", "sensor_msgs/msg/PointCloud2"}}, messages);
  const auto r = run_command(kCli + " run " + bag.string() + " --odometry off --no-plots --out " +
                             dir + "/out");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("ringtrack: warning: " + bag.string() + ": scan 1: unreadable, skipped: "),
            std::string::npos)
      << r.err;
  // Scans count from 0, a bag's messages from 1.
  EXPECT_NE(r.err.find("message 2"), std::string::npos) << r.err;
  EXPECT_NE(r.out.find("scans            3 (1 more skipped: unreadable)"), std::string::npos)
      << r.out;
  const auto j = run_json(dir + "/out");
  EXPECT_EQ(j["complete"], true);
  EXPECT_EQ(j["scans"]["read"], 4);
  EXPECT_EQ(j["scans"]["processed"], 3);
  EXPECT_EQ(j["scans"]["skipped_unreadable"], 1);
  EXPECT_EQ(timing_scans(dir + "/out"), (std::set<int>{0, 2, 3}));
  // --on-bad-scan stop: today's behaviour, an error naming the message.
  const auto stop =
      run_command(kCli + " run " + bag.string() +
                  " --odometry off --no-plots --on-bad-scan stop --out " + dir + "/stop");
  EXPECT_EQ(stop.exit_code, 1);
  EXPECT_NE(stop.err.find("message 2"), std::string::npos) << stop.err;
  EXPECT_EQ(run_json(dir + "/stop")["complete"], false);
  fs::remove_all(dir);
}

// convert writes sequences whose stamps increase: a scan whose stamp goes back is left out with
// a warning, a corrupt message is skipped; both are counted in the sequence's run.json.
TEST(RunRobustnessCli, ConvertSkipsStampsThatGoBackAndCorruptMessages) {
  const std::string dir = testing::make_temp_dir("ringtrack-robust-");
  const fs::path bag = fs::path(dir) / "bag";
  const std::int64_t base = 1'700'000'001'000'000'000;
  // Header stamps 1.0, 1.1, 1.05 (a clock step back), 1.2, (corrupt), 1.4 s.
  const std::int64_t header_ns[] = {0,           100'000'000, 50'000'000,
                                    200'000'000, 300'000'000, 400'000'000};
  std::vector<test::TestBagMessage> messages;
  for (int m = 0; m < 6; ++m) {
    auto data = cloud_message(base + header_ns[m]);
    if (m == 4) data.resize(data.size() / 2);
    messages.push_back({0, base + m * 100'000'000LL, std::move(data)});
  }
  test::write_rosbag2(bag, {{"/points", "sensor_msgs/msg/PointCloud2"}}, messages);
  const auto r = run_command(kCli + " convert " + bag.string() + " --out " + dir + "/seq");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("ringtrack: warning: " + bag.string() + ": scan 2: stamp "),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("ringtrack: warning: " + bag.string() + ": scan 4: unreadable, skipped: "),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("wrote 4 scans"), std::string::npos) << r.err;
  const io::SequenceReader reader(dir + "/seq");
  EXPECT_EQ(reader.size(), 4u);
  const auto j = run_json(dir + "/seq");
  EXPECT_EQ(j["complete"], true);
  EXPECT_EQ(j["command"], "convert");
  EXPECT_EQ(j["scans"]["read"], 6);
  EXPECT_EQ(j["scans"]["processed"], 4);
  EXPECT_EQ(j["scans"]["skipped_stamp"], 1);
  EXPECT_EQ(j["scans"]["skipped_unreadable"], 1);
  // A second convert into the folder is refused and leaves its run.json as it was.
  const auto again = run_command(kCli + " convert " + bag.string() + " --out " + dir + "/seq");
  EXPECT_EQ(again.exit_code, 1);
  EXPECT_EQ(run_json(dir + "/seq")["complete"], true);
  fs::remove_all(dir);
}

// A simulated sequence folder (15 scans) that each test copies and damages.
class RunSequenceRobustness : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = testing::make_temp_dir("ringtrack-robust-seq-");
    const auto r = run_command(kCli + " simulate 1 --duration 1.5 --seed 3 --out " + dir_ + "/seq");
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }
  // A fresh copy of the sequence named `name`.
  static fs::path copy(const std::string& name) {
    const fs::path to = fs::path(dir_) / name;
    fs::remove_all(to);
    fs::copy(fs::path(dir_) / "seq", to, fs::copy_options::recursive);
    return to;
  }
  // Cuts scans/NNNNNN.pcd of `seq` to half its size.
  static void truncate_scan(const fs::path& seq, std::size_t index) {
    const fs::path pcd = seq / "scans" / io::scan_file_name(index);
    fs::resize_file(pcd, fs::file_size(pcd) / 2);
  }
  static std::string dir_;
};
std::string RunSequenceRobustness::dir_;

TEST_F(RunSequenceRobustness, SimulateAndRunMarkTheirOutputsComplete) {
  const auto sim = run_json(fs::path(dir_) / "seq");
  EXPECT_EQ(sim["complete"], true);
  EXPECT_EQ(sim["command"], "simulate");
  EXPECT_EQ(sim["scans"]["processed"], 15);
  const std::string out = dir_ + "/plain-out";
  const auto r = run_command(kCli + " run " + dir_ + "/seq --no-plots --out " + out);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = run_json(out);
  EXPECT_EQ(j["complete"], true);
  EXPECT_EQ(j["state"], "finished");
  EXPECT_TRUE(j["error"].is_null());
  EXPECT_TRUE(j["interrupted"].is_null());
  EXPECT_EQ(j["command"], "run");
  EXPECT_EQ(j["input"], dir_ + "/seq");
  EXPECT_EQ(j["arguments"][1], "run");
  EXPECT_FALSE(j["version"].get<std::string>().empty());
  EXPECT_EQ(j["scans"]["read"], 15);
  EXPECT_EQ(j["scans"]["processed"], 15);
  EXPECT_EQ(j["scans"]["skipped"], 0);
  EXPECT_EQ(j["scans"]["failed"], 0);
  EXPECT_FALSE(fs::exists(fs::path(out) / "run.json.tmp"));
}

TEST_F(RunSequenceRobustness, TruncatedScanIsSkippedByDefault) {
  const fs::path seq = copy("truncated-skip");
  truncate_scan(seq, 5);
  const fs::path out = seq.string() + "-out";
  const auto r = run_command(kCli + " run " + seq.string() + " --no-plots --out " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("ringtrack: warning: " + seq.string() + ": scan 5: unreadable, skipped: "),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("000005.pcd"), std::string::npos) << r.err;
  EXPECT_NE(r.out.find("scans            14 (1 more skipped: unreadable)"), std::string::npos)
      << r.out;
  const auto j = run_json(out);
  EXPECT_EQ(j["complete"], true);
  EXPECT_EQ(j["state"], "finished");
  EXPECT_EQ(j["scans"]["read"], 15);
  EXPECT_EQ(j["scans"]["processed"], 14);
  EXPECT_EQ(j["scans"]["skipped"], 1);
  EXPECT_EQ(j["scans"]["skipped_unreadable"], 1);
  ASSERT_EQ(j["skipped_scans"].size(), 1u);
  EXPECT_EQ(j["skipped_scans"][0]["scan"], 5);
  // The outputs cover every other scan; the tracker saw a 0.2 s gap, no invented scan.
  std::set<int> expected;
  for (int k = 0; k < 15; ++k) {
    if (k != 5) expected.insert(k);
  }
  EXPECT_EQ(timing_scans(out), expected);
  EXPECT_TRUE(ends_with_newline(out / "tracks.csv"));
  for (const auto& line : lines_of(out / "tracks.csv")) {
    EXPECT_NE(line.substr(0, 2), "5,") << line;
  }
}

TEST_F(RunSequenceRobustness, TruncatedScanStopsTheRunWithStop) {
  const fs::path seq = copy("truncated-stop");
  truncate_scan(seq, 5);
  const fs::path out = seq.string() + "-out";
  const auto r = run_command(kCli + " run " + seq.string() +
                             " --no-plots --on-bad-scan stop --out " + out.string());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(r.err.rfind("ringtrack: error: ", 0), 0u) << r.err;
  EXPECT_NE(r.err.find("000005.pcd"), std::string::npos) << r.err;
  // The files written so far stay, but run.json says they are not whole.
  const auto j = run_json(out);
  EXPECT_EQ(j["complete"], false);
  EXPECT_EQ(j["state"], "failed");
  EXPECT_NE(j["error"].get<std::string>().find("000005.pcd"), std::string::npos) << j.dump();
  EXPECT_EQ(j["scans"]["read"], 6);
  EXPECT_EQ(j["scans"]["processed"], 5);
  EXPECT_EQ(j["scans"]["failed"], 1);
  EXPECT_TRUE(j["ended_utc"].is_string());
}

TEST_F(RunSequenceRobustness, StampThatGoesBackIsSkippedWithAWarning) {
  const fs::path seq = copy("clock-step");
  // Scan 3 is stamped 0.15 s before scan 2 (a host clock step), scan 4 on goes on as before.
  auto lines = lines_of(seq / "stamps.txt");
  std::vector<std::size_t> stamp_lines;  // line of each scan's stamp
  for (std::size_t n = 0; n < lines.size(); ++n) {
    if (!lines[n].empty() && lines[n][0] != '#') stamp_lines.push_back(n);
  }
  ASSERT_EQ(stamp_lines.size(), 15u);
  char text[64];
  std::snprintf(text, sizeof text, "%.9f", std::stod(lines[stamp_lines[2]]) - 0.15);
  lines[stamp_lines[3]] = text;
  {
    std::ofstream f(seq / "stamps.txt", std::ios::trunc);
    for (const auto& line : lines) f << line << "\n";
  }
  const fs::path out = seq.string() + "-out";
  const auto r = run_command(kCli + " run " + seq.string() + " --no-plots --out " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("ringtrack: warning: " + seq.string() + ": scan 3: stamp "),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("older than the previous scan's"), std::string::npos) << r.err;
  EXPECT_NE(r.out.find("scans            14 (1 more skipped: stamp not after the scan before)"),
            std::string::npos)
      << r.out;
  const auto j = run_json(out);
  EXPECT_EQ(j["complete"], true);
  EXPECT_EQ(j["scans"]["skipped_stamp"], 1);
  EXPECT_EQ(j["skipped_scans"][0]["scan"], 3);
  EXPECT_EQ(timing_scans(out).count(3), 0u);
  EXPECT_EQ(timing_scans(out).size(), 14u);
}

TEST_F(RunSequenceRobustness, FailedRunOverAnEarlierCompleteOneIsMarkedIncomplete) {
  // Outputs from a good run, then a failing run into the same folder: run.json must not keep
  // saying complete.
  const fs::path seq = copy("rerun");
  const fs::path out = seq.string() + "-out";
  ASSERT_EQ(
      run_command(kCli + " run " + seq.string() + " --no-plots --out " + out.string()).exit_code,
      0);
  EXPECT_EQ(run_json(out)["complete"], true);
  truncate_scan(seq, 2);
  const auto r = run_command(kCli + " run " + seq.string() +
                             " --no-plots --on-bad-scan stop --out " + out.string());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(run_json(out)["complete"], false);
}

struct Stopped {
  bool exited{false};
  int exit_code{-1};
  std::string err;
  std::string out;
};

// Starts `ringtrack args...` in the background with its standard output and error going to the
// given files (created or truncated); the child's pid, or -1.
pid_t start_cli(std::vector<std::string> args, const std::string& out_path = "/dev/null",
                const std::string& err_path = "/dev/null") {
  const pid_t pid = ::fork();
  if (pid == 0) {
    const int err = ::open(err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    const int so = ::open(out_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    ::dup2(err, 2);
    ::dup2(so, 1);
    args.insert(args.begin(), "ringtrack");
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    ::execv(kCli.c_str(), argv.data());
    ::_exit(127);
  }
  return pid;
}

// Waits until path exists, at most `polls` times 10 ms; whether it does.
bool wait_for_file(const fs::path& path, int polls) {
  for (int i = 0; i < polls; ++i) {
    std::error_code ec;
    if (fs::exists(path, ec)) return true;
    std::this_thread::sleep_for(10ms);
  }
  return false;
}

// Sends `signal` to the child and waits for it (killing it when it does not end): its exit
// code, or -1 when it did not end or did not exit normally.
int exit_code_after(pid_t pid, int signal) {
  ::kill(pid, signal);
  int status = 0;
  const bool ended = testing::wait_or_kill(pid, status);
  return ended && WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// Starts `ringtrack <command> udp://127.0.0.1:PORT --out OUT <extra>`, sends it about six
// revolutions of VLP-16 packets, waits for it to take them and sends `signal`.
Stopped stop_live_command(const std::string& command, const std::string& out,
                          const std::vector<std::string>& extra, int signal) {
  const std::uint16_t port = free_udp_port();
  const std::string err_path = out + ".stderr";
  const std::string out_path = out + ".stdout";
  std::vector<std::string> args{command, "udp://127.0.0.1:" + std::to_string(port), "--out", out};
  args.insert(args.end(), extra.begin(), extra.end());
  const pid_t pid = start_cli(args, out_path, err_path);
  Stopped result;
  if (pid < 0) return result;
  bool bound = false;
  for (int i = 0; i < 500 && !bound; ++i) {
    std::this_thread::sleep_for(10ms);
    bound = udp_port_bound(port);
  }
  if (bound) {
    test::VelodyneEncoderOptions eo;
    eo.start_azimuth_deg = 180.0;
    const test::VelodyneEncoder enc(eo);
    const auto packets = enc.encode(0, 560, [](long long s, int laser) {
      return test::VelodyneEchoPair{{static_cast<std::uint16_t>(700 + (s * 13 + laser) % 8000), 3},
                                    {}};
    });
    const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
    sockaddr_in to{};
    to.sin_family = AF_INET;
    to.sin_port = htons(port);
    to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    for (std::size_t i = 0; i < packets.size(); ++i) {
      ::sendto(fd, packets[i].payload.data(), packets[i].payload.size(), 0,
               reinterpret_cast<const sockaddr*>(&to), sizeof to);
      if (i % 20 == 19) std::this_thread::sleep_for(2ms);  // never fill the receive buffer
    }
    ::close(fd);
    std::this_thread::sleep_for(500ms);  // let the tool take the scans (a few ms each)
  }
  result.exit_code = exit_code_after(pid, signal);
  result.exited = result.exit_code >= 0;
  result.err = text_of(err_path);
  result.out = text_of(out_path);
  return result;
}

class RunStopSignal : public ::testing::TestWithParam<int> {};

// SIGTERM (kill, docker stop, systemd) ends a live run exactly as Ctrl-C does: exit 0, every
// output closed after the last scan processed, the summary printed and run.json complete,
// naming the signal.
TEST_P(RunStopSignal, LiveRunClosesEverythingAndSaysInterrupted) {
  const int signal = GetParam();
  const std::string name = signal == SIGTERM ? "SIGTERM" : "SIGINT";
  const std::string dir = testing::make_temp_dir("ringtrack-robust-signal-");
  const fs::path out = fs::path(dir) / "out";
  const auto r =
      stop_live_command("run", out.string(), {"--odometry", "off", "--no-plots"}, signal);
  ASSERT_TRUE(r.exited) << "the tool did not exit by itself on " << name << "\n" << r.err;
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("(interrupted by " + name + ": the outputs cover these scans only)"),
            std::string::npos)
      << r.out;
  const auto j = run_json(out);
  EXPECT_EQ(j["complete"], true);
  EXPECT_EQ(j["state"], "interrupted");
  EXPECT_EQ(j["interrupted"], name);
  EXPECT_GE(j["scans"]["processed"].get<int>(), 3);
  EXPECT_TRUE(ends_with_newline(out / "tracks.csv"));
  EXPECT_TRUE(ends_with_newline(out / "timing.csv"));
  EXPECT_EQ(lines_of(out / "timing.csv").size(), 1 + j["scans"]["processed"].get<std::size_t>());
  EXPECT_TRUE(fs::exists(out / "static_map.ply"));
  EXPECT_TRUE(fs::exists(out / "poses.txt"));
  fs::remove_all(dir);
}

INSTANTIATE_TEST_SUITE_P(Signals, RunStopSignal, ::testing::Values(SIGTERM, SIGINT),
                         [](const auto& param_info) {
                           return std::string(param_info.param == SIGTERM ? "SIGTERM" : "SIGINT");
                         });

TEST(ConvertStopSignal, SigtermEndsTheRecordingWithACompleteSequence) {
  const std::string dir = testing::make_temp_dir("ringtrack-robust-convert-signal-");
  const fs::path out = fs::path(dir) / "seq";
  const auto r = stop_live_command("convert", out.string(), {}, SIGTERM);
  ASSERT_TRUE(r.exited) << r.err;
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("stopped by SIGTERM"), std::string::npos) << r.err;
  const io::SequenceReader reader(out);  // sequence.yaml written: complete
  EXPECT_GE(reader.size(), 3u);
  const auto j = run_json(out);
  EXPECT_EQ(j["complete"], true);
  EXPECT_EQ(j["command"], "convert");
  EXPECT_EQ(j["interrupted"], "SIGTERM");
  EXPECT_EQ(j["scans"]["processed"].get<std::size_t>(), reader.size());
  fs::remove_all(dir);
}

// simulate honours SIGTERM like Ctrl-C too: a long simulation stopped early is a complete,
// shorter sequence whose run.json says it was interrupted.
TEST(SimulateStopSignal, SigtermEndsWithACompleteShorterSequence) {
  const std::string dir = testing::make_temp_dir("ringtrack-robust-simulate-signal-");
  const std::string out = dir + "/seq";
  const pid_t pid = start_cli({"simulate", "1", "--duration", "3600", "--out", out});
  ASSERT_GE(pid, 0);
  // Wait until the simulator has written a few scans, then stop it.
  wait_for_file(fs::path(out) / "scans" / io::scan_file_name(3), 500);
  ASSERT_EQ(exit_code_after(pid, SIGTERM), 0) << "simulate did not stop on SIGTERM with exit 0";
  const io::SequenceReader reader(out);  // sequence.yaml written: complete
  EXPECT_GE(reader.size(), 4u);
  EXPECT_LT(reader.size(), 36000u);
  const auto j = run_json(out);
  EXPECT_EQ(j["complete"], true);
  EXPECT_EQ(j["interrupted"], "SIGTERM");
  EXPECT_EQ(j["scans"]["processed"].get<std::size_t>(), reader.size());
  fs::remove_all(dir);
}

// benchmark honours SIGTERM like run: the run at hand is dropped (its tables deleted), the
// finished runs are reported, and run.json, results.json and report.md say it was interrupted.
TEST(BenchmarkStopSignal, SigtermReportsTheFinishedRunsOnly) {
  const std::string dir = testing::make_temp_dir("ringtrack-robust-benchmark-signal-");
  const fs::path out = fs::path(dir) / "bench";
  const pid_t pid = start_cli({"benchmark", "--scenarios", "1", "--sensors", "both", "--duration",
                               "60", "--save-tracks", "--no-plot", "--out", out.string()});
  ASSERT_GE(pid, 0);
  // The second run's table appears when the first run has finished.
  ASSERT_TRUE(wait_for_file(out / "tracks-1-moving.csv", 6000)) << "the first run never finished";
  ASSERT_EQ(exit_code_after(pid, SIGTERM), 0) << "benchmark did not stop on SIGTERM with exit 0";
  const auto j = run_json(out);
  EXPECT_EQ(j["complete"], true);
  EXPECT_EQ(j["interrupted"], "SIGTERM");
  const auto results = nlohmann::json::parse(text_of(out / "results.json"));
  EXPECT_EQ(results["interrupted"], "SIGTERM");
  EXPECT_EQ(results["runs_planned"], 2);
  ASSERT_EQ(results["cases"].size(), 1u);
  EXPECT_EQ(results["cases"][0]["sensor"], "static");
  EXPECT_EQ(results["cases"][0]["scans"], 600);
  EXPECT_TRUE(fs::exists(out / "tracks-1-static.csv"));
  EXPECT_FALSE(fs::exists(out / "tracks-1-moving.csv"));
  EXPECT_FALSE(fs::exists(out / "objects-1-moving.csv"));
  EXPECT_NE(text_of(out / "report.md").find("Interrupted by SIGTERM after 1 of 2 runs"),
            std::string::npos);
  fs::remove_all(dir);
}

// Every option `convert` takes to read and decode an input, `run` takes too (one shared set):
// a capture on port 2369 converts and runs alike.
TEST(RunRobustnessCli, RunTakesEveryDecoderOptionConvertTakes) {
  const auto options_of = [](const std::string& help) {
    std::set<std::string> names;
    std::istringstream in(help);
    for (std::string line; std::getline(in, line);) {
      const auto start = line.find_first_not_of(' ');
      if (start == std::string::npos || line.compare(start, 2, "--") != 0) continue;
      std::string name = line.substr(start);
      name = name.substr(0, name.find_first_of(" ,"));
      names.insert(name);
    }
    return names;
  };
  const auto convert = run_command(kCli + " convert --help");
  const auto run = run_command(kCli + " run --help");
  ASSERT_EQ(convert.exit_code, 0);
  ASSERT_EQ(run.exit_code, 0);
  const auto run_options = options_of(run.out);
  // Options about writing a sequence folder, not about reading the input.
  const std::set<std::string> convert_only{"--out",       "--encoding", "--max-scans",
                                           "--overwrite", "--quiet",    "--help"};
  for (const auto& name : options_of(convert.out)) {
    if (convert_only.count(name) != 0) continue;
    EXPECT_EQ(run_options.count(name), 1u) << "run lacks convert's " << name;
  }

  const std::string dir = testing::make_temp_dir("ringtrack-robust-port-");
  test::VelodyneEncoderOptions eo;
  eo.start_azimuth_deg = 30.0;
  const test::VelodyneEncoder enc(eo);
  const auto packets = enc.encode(0, 400, [](long long s, int laser) {
    return test::VelodyneEchoPair{{static_cast<std::uint16_t>(900 + (s * 3 + laser) % 4000), 9},
                                  {}};
  });
  const std::string pcap = dir + "/port2369.pcap";
  test::write_pcap(pcap, test::PcapLink::kEthernet,
                   test::frame_packets(test::PcapLink::kEthernet, packets, 2369));
  const auto converted =
      run_command(kCli + " convert " + pcap + " --port 2369 --out " + dir + "/seq");
  ASSERT_EQ(converted.exit_code, 0) << converted.err;
  const auto ran = run_command(kCli + " run " + pcap +
                               " --port 2369 --odometry off --no-plots --out " + dir + "/out");
  ASSERT_EQ(ran.exit_code, 0) << ran.err;
  EXPECT_EQ(run_json(dir + "/out")["scans"]["processed"], io::SequenceReader(dir + "/seq").size());
  // Without --port the capture holds no data packets on 2368: a clear error.
  const auto wrong =
      run_command(kCli + " run " + pcap + " --odometry off --no-plots --out " + dir + "/wrong");
  EXPECT_EQ(wrong.exit_code, 1);
  fs::remove_all(dir);
}

// Output that cannot be written (a full disk, /dev/full) is an error, not exit 0, for every
// command that prints: help and version included.
TEST(RunRobustnessCli, StandardOutputThatCannotBeWrittenIsAnError) {
  for (const std::string args : {"dump-config", "sensors", "--version", "--help", "run --help"}) {
    const auto r = run_command("{ " + kCli + " " + args + " > /dev/full; }");
    EXPECT_EQ(r.exit_code, 1) << args;
    EXPECT_EQ(r.err.rfind("ringtrack: error: cannot write to standard output", 0), 0u)
        << args << ": " << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << args << ": " << r.err;
  }
}

}  // namespace
}  // namespace ringtrack
