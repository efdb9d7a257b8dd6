// `ringtrack run` motion-compensates the scans of a moving sensor whenever poses give its motion.
// Oracles: the simulator's exact geometry (a noise-free walled yard seen from a sensor flying a
// figure 8: every wall and pole point, mapped with the poses, must lie on its surface), and for
// recordings a pure-translation trajectory, under which deskewing shifts column c's points by
// exactly v * (t_c - t_first).

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "ringtrack/core/organized_scan.hpp"
#include "ringtrack/core/pose.hpp"
#include "ringtrack/io/pcd.hpp"
#include "ringtrack/io/poses.hpp"
#include "ringtrack/io/scan_source.hpp"
#include "ringtrack/io/sequence.hpp"
#include "support/run_command.hpp"
#include "support/velodyne_encoder.hpp"

namespace ringtrack {
namespace {

namespace fs = std::filesystem;
using testing::run_command;

const std::string kCli = RINGTRACK_CLI_PATH;

// A 20 m x 20 m yard (walls 0.2 m thick centred on x, y = +-10 m, 3 m high) with one pole, no
// actors and no measurement noise: any distance of a mapped point from the surface it was
// measured on is an error of the pose/motion handling.
constexpr const char* kYard = R"(name: walled-yard
duration_s: 4
world_radius_m: 40
ground: {enabled: true, height_m: 0, amplitude_m: 0}
sensor:
  motion: figure8
  range_noise_m: 0
  dropout_probability: 0
  far_dropout_probability: 0
actors:
  people: 0
walls:
  - {from_m: [10, -10], to_m: [10, 10], height_m: 3, thickness_m: 0.2}
  - {from_m: [-10, -10], to_m: [-10, 10], height_m: 3, thickness_m: 0.2}
  - {from_m: [-10, 10], to_m: [10, 10], height_m: 3, thickness_m: 0.2}
  - {from_m: [-10, -10], to_m: [10, -10], height_m: 3, thickness_m: 0.2}
cylinders:
  - {center_m: [6, -6], radius_m: 0.3, height_m: 3}
)";
constexpr double kWallFace = 9.9;  // inner faces of the walls
const Eigen::Vector2d kPole{6.0, -6.0};
constexpr double kPoleRadius = 0.3;

// Distance of a world point to the nearest wall face or the pole's surface.
double yard_distance(const Eigen::Vector3d& p) {
  double d = std::abs(std::hypot(p.x() - kPole.x(), p.y() - kPole.y()) - kPoleRadius);
  for (const double c : {p.x(), p.y()}) d = std::min(d, std::abs(std::abs(c) - kWallFace));
  return d;
}

// Root mean square of yard_distance over the points between 0.3 m and 2.7 m high: above the
// (flat) ground and below the tops of the walls and the pole, so on a wall or the pole.
struct Spread {
  double rms_m{0.0};
  std::size_t points{0};
  void add(const Eigen::Vector3d& p) {
    if (p.z() < 0.3 || p.z() > 2.7) return;
    const double d = yard_distance(p);
    sum_sq_ += d * d;
    ++points;
    rms_m = std::sqrt(sum_sq_ / static_cast<double>(points));
  }

 private:
  double sum_sq_{0.0};
};

// Vertices of a static_map.ply as `run` writes it (binary little endian, x y z intensity).
std::vector<Eigen::Vector3d> read_map(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  const std::string bytes = text.str();
  const std::string end = "end_header\n";
  const auto at = bytes.find(end);
  EXPECT_NE(bytes.find("format binary_little_endian 1.0"), std::string::npos) << path;
  EXPECT_NE(at, std::string::npos) << path;
  std::vector<Eigen::Vector3d> out;
  if (at == std::string::npos) return out;
  for (std::size_t i = at + end.size(); i + 16 <= bytes.size(); i += 16) {
    float v[3];
    std::memcpy(v, bytes.data() + i, sizeof v);
    out.emplace_back(v[0], v[1], v[2]);
  }
  return out;
}

double map_spread(const fs::path& run) {
  Spread s;
  for (const auto& p : read_map(run / "static_map.ply")) s.add(p);
  EXPECT_GT(s.points, 1000u) << run;
  return s.rms_m;
}

// Spread of the filtered scans (sensor frame), mapped with the sequence's scan poses.
double filtered_spread(const fs::path& seq, const fs::path& run) {
  const io::SequenceReader reader(seq);
  Spread s;
  for (std::size_t i = 0; i < reader.size(); ++i) {
    const auto filtered = io::read_pcd(run / "filtered" / io::scan_file_name(i));
    const core::Pose& pose = reader.pose(i);
    for (std::size_t c = 0; c < filtered.scan.size(); ++c) {
      if (filtered.scan.valid(c)) s.add(pose.to_world(filtered.scan.point(c)).cast<double>());
    }
  }
  EXPECT_GT(s.points, 10000u) << run;
  return s.rms_m;
}

// The summary line that starts with key (paths in other lines may contain the word).
std::string summary_line(const std::string& out, const std::string& key) {
  std::size_t at = out.rfind(key + " ", 0) == 0 ? 0 : out.find("\n" + key + " ");
  if (at == std::string::npos) return {};
  if (out[at] == '\n') ++at;
  return out.substr(at, out.find('\n', at) - at);
}

class RunDeskewCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new fs::path(testing::make_temp_dir("ringtrack-run-deskew-"));
    std::ofstream(*dir_ / "yard.yaml") << kYard;
    const auto r = run_command(kCli + " simulate " + (*dir_ / "yard.yaml").string() +
                               " --seed 1 --out " + (*dir_ / "seq").string());
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  static void TearDownTestSuite() {
    std::error_code ec;
    fs::remove_all(*dir_, ec);
    delete dir_;
  }
  static fs::path* dir_;
};
fs::path* RunDeskewCli::dir_ = nullptr;

TEST_F(RunDeskewCli, MovingSensorWallsComeOutSharpAndFilteredScansAreTheDeskewedOnes) {
  const fs::path seq = *dir_ / "seq";
  const fs::path on = *dir_ / "on", off = *dir_ / "off";
  const auto a =
      run_command(kCli + " run " + seq.string() + " --quiet --filtered-scans --out " + on.string());
  ASSERT_EQ(a.exit_code, 0) << a.err;
  EXPECT_EQ(summary_line(a.out, "deskew"),
            "deskew           40 of 40 scans (poses of this and the next scan)")
      << a.out;
  const auto b = run_command(kCli + " run " + seq.string() +
                             " --quiet --filtered-scans --no-deskew --out " + off.string());
  ASSERT_EQ(b.exit_code, 0) << b.err;
  EXPECT_EQ(summary_line(b.out, "deskew"), "deskew           off (--no-deskew)") << b.out;

  // Deskewed, the only error left is the linear pose interpolation within a revolution: the
  // figure 8 accelerates at most ~6 m/s^2, a * T^2 / 8 = 8 mm at T = 0.1 s, and far less on
  // average. Skewed, the sensor moves up to 0.5 m and turns during a revolution.
  const double map_on = map_spread(on), map_off = map_spread(off);
  EXPECT_LT(map_on, 0.01);
  EXPECT_GT(map_off, 0.1);
  // The filtered scans are the scans the map was built from: deskewed in the first run.
  const double filtered_on = filtered_spread(seq, on), filtered_off = filtered_spread(seq, off);
  EXPECT_LT(filtered_on, 0.01);
  EXPECT_GT(filtered_off, 0.1);
  // A smeared wall also fills more voxels of the static map.
  EXPECT_LT(read_map(on / "static_map.ply").size(), read_map(off / "static_map.ply").size());
}

TEST_F(RunDeskewCli, PlainPcdFolderIsNotDeskewed) {
  // The same scans, poses and stamps without sequence.yaml: the files carry no column times.
  const fs::path plain = *dir_ / "plain";
  fs::create_directories(plain);
  for (const char* f : {"stamps.txt", "poses.txt"}) fs::copy_file(*dir_ / "seq" / f, plain / f);
  for (const auto& e : fs::directory_iterator(*dir_ / "seq" / "scans")) {
    fs::copy_file(e.path(), plain / e.path().filename());
  }
  const auto r = run_command(kCli + " run " + plain.string() + " --quiet --out " +
                             (*dir_ / "plain-out").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(summary_line(r.out, "deskew"),
            "deskew           off (plain PCD folder: its columns carry no times)")
      << r.out;
}

TEST_F(RunDeskewCli, KittiPosesDeskewToo) {
  // The scan poses as a KITTI file (one per scan, the scans' stamps): the same motion is known.
  const io::SequenceReader reader(*dir_ / "seq");
  const fs::path kitti = *dir_ / "kitti.txt";
  {
    std::ofstream f(kitti);
    f.precision(12);
    for (std::size_t i = 0; i < reader.size(); ++i) {
      const Eigen::Matrix3d r = reader.pose(i).rotation.toRotationMatrix();
      const Eigen::Vector3d t = reader.pose(i).translation;
      for (int row = 0; row < 3; ++row) {
        f << r(row, 0) << ' ' << r(row, 1) << ' ' << r(row, 2) << ' ' << t(row)
          << (row == 2 ? '\n' : ' ');
      }
    }
  }
  const fs::path out = *dir_ / "kitti-out";
  const auto r =
      run_command(kCli + " run " + (*dir_ / "seq").string() + " --poses " + kitti.string() +
                  " --poses-format kitti --quiet --out " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(summary_line(r.out, "deskew"),
            "deskew           40 of 40 scans (poses of this and the next scan)")
      << r.out;
  EXPECT_LT(map_spread(out), 0.01);
}

// A synthetic VLP-16 capture (four revolutions of a fixed range pattern) and its scans as `run`
// reads them.
struct Capture {
  std::string pcap;
  std::vector<core::OrganizedScan> scans;
};

Capture write_capture(const fs::path& dir) {
  Capture c;
  const test::VelodyneEncoder enc(test::VelodyneEncoderOptions{});
  const auto packets = enc.encode(0, 320, [](long long s, int laser) {
    const auto mm2 = static_cast<std::uint16_t>(1500 + ((s / 7) * 37 + laser * 211) % 2500);
    return test::VelodyneEchoPair{{mm2, 40}, {}};
  });
  c.pcap = (dir / "drive.pcap").string();
  test::write_pcap(c.pcap, test::PcapLink::kEthernet,
                   test::frame_packets(test::PcapLink::kEthernet, packets));
  const io::ScanSourceOptions options;  // run's defaults
  const auto source = io::open_source(c.pcap, options);
  while (auto scan = source->next()) c.scans.push_back(std::move(*scan));
  return c;
}

// Writes a TUM trajectory moving at velocity v (m/s) without turning, from `from_ns` to `to_ns`.
void write_straight_line(const fs::path& path, std::int64_t from_ns, std::int64_t to_ns,
                         const Eigen::Vector3d& v) {
  std::vector<core::Pose> poses;
  for (const std::int64_t t : {from_ns, to_ns}) {
    core::Pose p;
    p.stamp_ns = t;
    p.translation = v * (static_cast<double>(t - from_ns) * 1e-9);
    poses.push_back(p);
  }
  io::write_tum(path, poses);
}

TEST(RunDeskewRecording, PosesAtTheFirstAndLastColumnShiftEachColumnByTheMotion) {
  const fs::path dir = testing::make_temp_dir("ringtrack-run-deskew-pcap-");
  const Capture capture = write_capture(dir);
  ASSERT_GE(capture.scans.size(), 3u);
  const Eigen::Vector3d v{1.0, -0.5, 0.25};
  const std::int64_t from = capture.scans.front().stamp_ns - 1'000'000'000;
  const std::int64_t to = capture.scans.back().column_stamp_ns.back() + 1'000'000'000;
  write_straight_line(dir / "line.txt", from, to, v);
  const std::string common = kCli + " run " + capture.pcap + " --quiet --filtered-scans --poses " +
                             (dir / "line.txt").string();
  const auto a = run_command(common + " --out " + (dir / "on").string());
  ASSERT_EQ(a.exit_code, 0) << a.err;
  const std::string n = std::to_string(capture.scans.size());
  EXPECT_EQ(summary_line(a.out, "deskew"),
            "deskew           " + n + " of " + n +
                " scans (--poses at each scan's first and last column)")
      << a.out;
  const auto b = run_command(common + " --no-deskew --out " + (dir / "off").string());
  ASSERT_EQ(b.exit_code, 0) << b.err;
  EXPECT_EQ(summary_line(b.out, "deskew"), "deskew           off (--no-deskew)") << b.out;

  // Sensor frame at the scan's stamp (its first column): a point measured at t_c from a sensor
  // that moved by v (t_c - t_0) without turning is that far ahead of the skewed one.
  std::size_t compared = 0;
  for (std::size_t k = 0; k < capture.scans.size(); ++k) {
    const core::OrganizedScan& raw = capture.scans[k];
    const auto on = io::read_pcd(dir / "on" / "filtered" / io::scan_file_name(k)).scan;
    const auto off = io::read_pcd(dir / "off" / "filtered" / io::scan_file_name(k)).scan;
    ASSERT_EQ(on.size(), raw.size());
    for (std::size_t i = 0; i < raw.size(); ++i) {
      if (!raw.valid(i) || !on.valid(i) || !off.valid(i)) continue;
      const std::int64_t dt_ns =
          raw.column_stamp_ns[static_cast<std::size_t>(raw.column_of(i))] - raw.stamp_ns;
      const Eigen::Vector3f shift = (v * (static_cast<double>(dt_ns) * 1e-9)).cast<float>();
      ASSERT_LT((off.point(i) - raw.point(i)).norm(), 1e-5f) << "scan " << k << " cell " << i;
      ASSERT_LT((on.point(i) - (raw.point(i) + shift)).norm(), 1e-4f)
          << "scan " << k << " cell " << i << " dt " << dt_ns;
      ++compared;
    }
  }
  EXPECT_GT(compared, capture.scans.size() * 20000);
  fs::remove_all(dir);
}

TEST(RunDeskewRecording, TrajectoryEndingInsideTheLastScanIsOneLineError) {
  const fs::path dir = testing::make_temp_dir("ringtrack-run-deskew-short-");
  const Capture capture = write_capture(dir);
  ASSERT_GE(capture.scans.size(), 2u);
  const auto& last = capture.scans.back();
  const std::size_t last_index = capture.scans.size() - 1;
  // Covers every scan's stamp, but not the last scan's later columns.
  write_straight_line(dir / "short.txt", capture.scans.front().stamp_ns - 1'000'000,
                      last.stamp_ns + 50'000'000, {1.0, 0.0, 0.0});
  const std::string common =
      kCli + " run " + capture.pcap + " --quiet --poses " + (dir / "short.txt").string();
  const auto bad = run_command(common + " --out " + (dir / "on").string());
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_EQ(std::count(bad.err.begin(), bad.err.end(), '\n'), 1) << bad.err;
  EXPECT_NE(bad.err.find("no pose around scan " + std::to_string(last_index)), std::string::npos)
      << bad.err;
  EXPECT_NE(bad.err.find("--no-deskew"), std::string::npos) << bad.err;
  // Without motion compensation only the scan stamps need poses.
  const auto ok = run_command(common + " --no-deskew --out " + (dir / "off").string());
  EXPECT_EQ(ok.exit_code, 0) << ok.err;
  EXPECT_EQ(summary_line(ok.out, "deskew"), "deskew           off (--no-deskew)") << ok.out;
  // A trajectory ending before a scan's stamp stays an error either way.
  write_straight_line(dir / "shorter.txt", capture.scans.front().stamp_ns - 1'000'000,
                      last.stamp_ns - 1'000'000, {1.0, 0.0, 0.0});
  const auto worse =
      run_command(kCli + " run " + capture.pcap + " --quiet --no-deskew --poses " +
                  (dir / "shorter.txt").string() + " --out " + (dir / "off2").string());
  EXPECT_EQ(worse.exit_code, 1);
  EXPECT_NE(worse.err.find("no pose around scan " + std::to_string(last_index)), std::string::npos)
      << worse.err;
  fs::remove_all(dir);
}

TEST(RunDeskewRecording, WithoutPosesAndOdometryOffNothingIsDeskewed) {
  const fs::path dir = testing::make_temp_dir("ringtrack-run-deskew-none-");
  const Capture capture = write_capture(dir);
  const auto r = run_command(kCli + " run " + capture.pcap + " --odometry off --quiet --out " +
                             (dir / "out").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(summary_line(r.out, "deskew"), "deskew           off (no --poses: static sensor)")
      << r.out;
  EXPECT_EQ(summary_line(r.out, "poses"),
            "poses            none: static sensor at the origin (--odometry on estimates them)")
      << r.out;
  fs::remove_all(dir);
}

// A recording without --poses: the odometry estimates them (--odometry auto) and says so.
TEST(RunDeskewRecording, WithoutPosesTheOdometryEstimatesThem) {
  const fs::path dir = testing::make_temp_dir("ringtrack-run-odometry-auto-");
  const Capture capture = write_capture(dir);
  const auto r =
      run_command(kCli + " run " + capture.pcap + " --quiet --out " + (dir / "out").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(summary_line(r.out, "poses"),
            "poses            odometry (--odometry auto: a recording without --poses)")
      << r.out;
  EXPECT_EQ(summary_line(r.out, "deskew"),
            "deskew           by the odometry (estimated velocity, from the second scan)")
      << r.out;
  EXPECT_TRUE(fs::exists(dir / "out" / "odometry.csv"));
  write_straight_line(dir / "line.txt", capture.scans.front().stamp_ns - 1'000'000'000,
                      capture.scans.back().column_stamp_ns.back() + 1'000'000'000, {1, 0, 0});
  const auto both =
      run_command(kCli + " run " + capture.pcap + " --odometry on --poses " +
                  (dir / "line.txt").string() + " --quiet --out " + (dir / "o2").string());
  EXPECT_NE(both.exit_code, 0);
  EXPECT_NE(both.err.find("--odometry on and --poses exclude each other"), std::string::npos)
      << both.err;
  fs::remove_all(dir);
}

}  // namespace
}  // namespace ringtrack
