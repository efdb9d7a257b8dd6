// runner::RunInput in-process: which scans are motion-compensated and with which poses. Oracle:
// a sensor translating at a constant velocity v without turning sees a point at column time t in
// its frame at the scan's stamp t0 shifted by v (t - t0), so a compensated cell is the read cell
// plus that shift, exactly (the interpolation is linear in time); a scan left alone is the read
// scan cell for cell. Inputs are hand-made in a temp folder: a sequence folder with poses, a VLP-16
// capture with a TUM trajectory.
#include "ringtrack/runner/run_input.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "ringtrack/core/error.hpp"
#include "ringtrack/io/poses.hpp"
#include "ringtrack/io/sequence.hpp"
#include "ringtrack/sim/simple_scene.hpp"
#include "support/temp_dir.hpp"
#include "support/velodyne_encoder.hpp"

namespace ringtrack::runner {
namespace {

namespace fs = std::filesystem;

constexpr std::int64_t kStart = 1'700'000'000'000'000'000;
constexpr std::int64_t kPeriod = 100'000'000;     // 10 Hz
const Eigen::Vector3d kVelocity(2.0, -1.0, 0.5);  // m/s, no turning
// Default options, named: a braced temporary trips g++ 12's -Wmaybe-uninitialized.
const RunInputOptions kDefaults;

// The sensor's pose at t: moving at kVelocity from the origin at kStart.
core::Pose pose_at(std::int64_t t_ns) {
  core::Pose p;
  p.stamp_ns = t_ns;
  p.translation = kVelocity * (static_cast<double>(t_ns - kStart) * 1e-9);
  return p;
}

// A three-scan VLP-16 sequence of the demo scene with per-column stamps and moving poses.
void write_sequence(const fs::path& folder, int scans = 3) {
  const auto model = core::SensorModel::vlp16();
  io::SequenceWriter writer(folder, io::SequenceMeta::for_sensor(model, model.columns()));
  for (int k = 0; k < scans; ++k) {
    auto rendered = sim::render(model, sim::SimpleScene::demo());
    rendered.scan.set_uniform_columns(model, kStart + k * kPeriod);
    writer.add_scan(rendered.scan, rendered.labels, pose_at(rendered.scan.stamp_ns));
  }
  writer.finish();
}

// Expects `compensated` to be `read` with every valid cell shifted by the sensor's motion from
// the scan's stamp to its column's stamp.
void expect_shifted_by_motion(const core::OrganizedScan& read,
                              const core::OrganizedScan& compensated) {
  ASSERT_EQ(read.size(), compensated.size());
  std::size_t checked = 0;
  for (int r = 0; r < read.rings(); ++r) {
    for (int c = 0; c < read.columns(); ++c) {
      const std::size_t i = read.index(r, c);
      ASSERT_EQ(read.valid(i), compensated.valid(i));
      if (!read.valid(i)) continue;
      const double dt =
          static_cast<double>(read.column_stamp_ns[static_cast<std::size_t>(c)] - read.stamp_ns) *
          1e-9;
      const Eigen::Vector3d expected = read.point(i).cast<double>() + kVelocity * dt;
      EXPECT_NEAR((compensated.point(i).cast<double>() - expected).norm(), 0.0, 1e-4)
          << "ring " << r << " column " << c;
      ++checked;
    }
  }
  EXPECT_GT(checked, 1000u);
}

TEST(RunInput, ASequenceIsCompensatedByItsOwnPoses) {
  test::TempDir dir;
  write_sequence(dir / "seq");
  io::SequenceReader reader(dir / "seq");
  RunInput input((dir / "seq").string(), kDefaults);
  EXPECT_TRUE(input.folder());
  EXPECT_EQ(input.size(), 3u);
  std::size_t index = 0;
  core::OrganizedScan scan;
  core::Pose pose;
  for (std::size_t k = 0; k < 3; ++k) {
    ASSERT_TRUE(input.next(index, scan, pose));
    EXPECT_EQ(index, k);
    // The last scan extrapolates the motion of the pair before it: the same motion here.
    expect_shifted_by_motion(reader.read(k).scan, scan);
    EXPECT_EQ(pose.stamp_ns, scan.stamp_ns);
    EXPECT_NEAR((pose.translation - pose_at(scan.stamp_ns).translation).norm(), 0.0, 1e-9);
  }
  EXPECT_FALSE(input.next(index, scan, pose));
  EXPECT_EQ(input.deskew_summary(), "3 of 3 scans (poses of this and the next scan)");
  EXPECT_EQ(input.pose_summary("auto"), "the sequence's poses.txt");
  EXPECT_EQ(input.read(), 3u);
  EXPECT_EQ(input.unreadable(), 0u);
}

TEST(RunInput, NoDeskewOdometryAndOneScanLeaveTheScansAsRead) {
  test::TempDir dir;
  write_sequence(dir / "seq");
  io::SequenceReader reader(dir / "seq");
  const auto expect_as_read = [&](RunInput& input, const std::string& summary) {
    std::size_t index = 0;
    core::OrganizedScan scan;
    core::Pose pose;
    while (input.next(index, scan, pose)) {
      const core::OrganizedScan read = reader.read(index).scan;
      ASSERT_EQ(scan.size(), read.size());
      std::size_t moved = 0;
      for (std::size_t i = 0; i < read.size(); ++i) {
        if (read.valid(i) && scan.point(i) != read.point(i)) ++moved;
      }
      EXPECT_EQ(moved, 0u) << "scan " << index;
      EXPECT_EQ(pose.stamp_ns, read.stamp_ns);
    }
    EXPECT_EQ(input.deskew_summary(), summary);
  };
  RunInputOptions off;
  off.no_deskew = true;
  RunInput no_deskew((dir / "seq").string(), off);
  expect_as_read(no_deskew, "off (--no-deskew)");

  RunInput odometry((dir / "seq").string(), kDefaults);
  odometry.use_odometry(true);
  expect_as_read(odometry, "by the odometry (estimated velocity, from the second scan)");
  EXPECT_EQ(odometry.pose_summary("on"), "odometry (--odometry on)");

  write_sequence(dir / "one", 1);
  RunInput one((dir / "one").string(), kDefaults);
  expect_as_read(one, "off (one scan: its motion is unknown)");
}

// A VLP-16 capture of about three revolutions, and its scans as read.
struct Capture {
  std::string pcap;
  std::vector<core::OrganizedScan> scans;
};

Capture write_capture(const fs::path& dir) {
  ::ringtrack::test::VelodyneEncoderOptions eo;
  eo.host_epoch_ns = kStart;
  const ::ringtrack::test::VelodyneEncoder enc(eo);
  const double per_rev = 360.0 / (enc.advance_deg() * enc.sequences_per_packet());
  const auto packets =
      enc.encode(0, static_cast<long long>(3.5 * per_rev), [](long long s, int laser) {
        const auto d = static_cast<std::uint16_t>((s * 7 + laser * 131) % 4000 + 1000);
        return ::ringtrack::test::VelodyneEchoPair{{d, 10}, {d, 1}};
      });
  Capture c;
  c.pcap = (dir / "capture.pcap").string();
  ::ringtrack::test::write_pcap(
      c.pcap, ::ringtrack::test::PcapLink::kEthernet,
      ::ringtrack::test::frame_packets(::ringtrack::test::PcapLink::kEthernet, packets));
  const auto source = io::open_source(c.pcap, io::ScanSourceOptions());
  while (auto scan = source->next()) c.scans.push_back(std::move(*scan));
  return c;
}

TEST(RunInput, ARecordingIsCompensatedByATrajectoryAtItsColumns) {
  test::TempDir dir;
  const Capture capture = write_capture(dir.path());
  ASSERT_GE(capture.scans.size(), 2u);
  const std::int64_t from = capture.scans.front().stamp_ns - 1'000'000'000;
  const std::int64_t to = capture.scans.back().column_stamp_ns.back() + 1'000'000'000;
  const std::vector<core::Pose> line{pose_at(from), pose_at(to)};
  io::write_tum(dir / "line.txt", line);
  RunInputOptions options;
  options.poses = (dir / "line.txt").string();
  RunInput input(capture.pcap, options);
  EXPECT_FALSE(input.folder());
  std::size_t index = 0;
  core::OrganizedScan scan;
  core::Pose pose;
  std::size_t n = 0;
  while (input.next(index, scan, pose)) {
    ASSERT_LT(index, capture.scans.size());
    // Column times from the first to the last column, so the shift is about 0.1 s of motion.
    expect_shifted_by_motion(capture.scans[index], scan);
    EXPECT_NEAR((pose.translation - pose_at(scan.stamp_ns).translation).norm(), 0.0, 1e-6);
    ++n;
  }
  EXPECT_EQ(n, capture.scans.size());
  EXPECT_EQ(input.deskew_summary(), std::to_string(n) + " of " + std::to_string(n) +
                                        " scans (--poses at each scan's first and last column)");
  EXPECT_EQ(input.pose_summary("auto"), options.poses + " (--poses)");
}

TEST(RunInput, PosesThatDoNotFitARecordingAreOneLine) {
  test::TempDir dir;
  const Capture capture = write_capture(dir.path());
  ASSERT_GE(capture.scans.size(), 1u);
  const auto error_of = [&](const RunInputOptions& options) -> std::string {
    try {
      RunInput input(capture.pcap, options);
      std::size_t index = 0;
      core::OrganizedScan scan;
      core::Pose pose;
      while (input.next(index, scan, pose)) {
      }
    } catch (const core::InputError& e) {
      return e.what();
    }
    return "no error";
  };
  // Poses up to the first scan's stamp only: not over its revolution.
  const core::OrganizedScan& first = capture.scans.front();
  const std::vector<core::Pose> short_line{pose_at(first.stamp_ns - 1'000'000),
                                           pose_at(first.stamp_ns)};
  io::write_tum(dir / "short.txt", short_line);
  RunInputOptions options;
  options.poses = (dir / "short.txt").string();
  const std::string e = error_of(options);
  EXPECT_EQ(e.rfind("--poses: no pose around scan 0's columns (", 0), 0u) << e;
  EXPECT_NE(e.find("motion compensation needs poses over the whole revolution (or give "
                   "--no-deskew)"),
            std::string::npos)
      << e;
  // Without compensation the scan's own stamp is enough for the first scan, not the next one.
  options.no_deskew = true;
  EXPECT_EQ(error_of(options).rfind("--poses: no pose around scan 1 at stamp ", 0), 0u);
  options.poses_format = "kitti";
  EXPECT_EQ(error_of(options),
            options.poses + ": only TUM poses (with stamps) can be matched to a sensor recording");
}

}  // namespace
}  // namespace ringtrack::runner
