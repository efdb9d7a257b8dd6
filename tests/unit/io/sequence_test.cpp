#include "ringtrack/io/sequence.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "io_test_util.hpp"
#include "ringtrack/core/error.hpp"
#include "ringtrack/io/text.hpp"
#include "ringtrack/sim/simple_scene.hpp"

namespace ringtrack::io {
namespace {

using test::input_error;
namespace fs = std::filesystem;

constexpr std::int64_t kStart = 1'000'000'000;  // first scan at t = 1 s
constexpr std::int64_t kPeriod = 100'000'000;   // 10 Hz

// A three-scan VLP-16 sequence of the demo scene, the sensor moving along +x at 1 m/s and
// turning at 0.1 rad/s, with one ground-truth object per scan.
void write_demo_sequence(const fs::path& folder, int scans = 3, bool finish = true) {
  const auto model = core::SensorModel::vlp16();
  auto meta = SequenceMeta::for_sensor(model, model.columns());
  meta.name = "demo: \"quoted\"";
  meta.scenario = "6";
  meta.seed = 42;
  SequenceWriter writer(folder, meta);
  for (int k = 0; k < scans; ++k) {
    auto rendered = sim::render(model, sim::SimpleScene::demo());
    rendered.scan.set_uniform_columns(model, kStart + k * kPeriod);
    core::Pose pose;
    pose.stamp_ns = rendered.scan.stamp_ns;
    pose.translation = Eigen::Vector3d(0.1 * k, 0, 2.5);
    pose.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(0.01 * k, Eigen::Vector3d::UnitZ()));
    ObjectRow row;
    row.id = 1;
    row.class_name = "person";
    row.points = 10 + static_cast<std::uint32_t>(k);
    row.centroid = Eigen::Vector3d(4.0 + 0.1 * k, 0, 1);
    row.true_center = row.centroid;
    row.moving = k > 0;
    writer.add_scan(rendered.scan, rendered.labels, pose, std::vector<ObjectRow>{row});
  }
  if (finish) writer.finish();
}

TEST(Sequence, WritesAndReadsBack) {
  test::TempDir dir;
  const fs::path folder = dir / "seq";
  write_demo_sequence(folder);
  for (const char* f : {"sequence.yaml", "scans/000000.pcd", "scans/000002.pcd", "stamps.txt",
                        "poses.txt", "objects.csv"}) {
    EXPECT_TRUE(fs::exists(folder / f)) << f;
  }
  EXPECT_FALSE(fs::exists(folder / "sequence.yaml.tmp"));
  EXPECT_EQ(test::read_text(folder / "sequence.yaml"),
            "# ringtrack sequence folder, see docs/formats.md\n"
            "format_version: 1\n"
            "sensor: vlp16\n"
            "scan_rate_hz: 10\n"
            "columns: 1808\n"
            "scans: 3\n"
            "name: \"demo: \\\"quoted\\\"\"\n"
            "scenario: \"6\"\n"
            "seed: 42\n");
  const std::string objects = test::read_text(folder / "objects.csv");
  EXPECT_EQ(objects.substr(0, objects.find('\n')), kObjectsCsvHeader);
  EXPECT_NE(objects.find("\n2,1.200000000,1,person,12,4.2000,"), std::string::npos) << objects;

  SequenceReader reader(folder);
  EXPECT_TRUE(reader.is_sequence());
  EXPECT_TRUE(reader.has_poses());
  ASSERT_EQ(reader.size(), 3u);
  EXPECT_EQ(reader.meta().name, "demo: \"quoted\"");
  EXPECT_EQ(reader.meta().seed, 42u);
  EXPECT_EQ(reader.sensor().name, "VLP-16");
  ASSERT_TRUE(reader.objects_csv());
  const auto model = core::SensorModel::vlp16();
  const auto expected = sim::render(model, sim::SimpleScene::demo());
  SequenceScan s;
  std::size_t count = 0;
  while (reader.next(s)) {
    EXPECT_EQ(s.index, count);
    EXPECT_EQ(s.path.filename().string(), scan_file_name(count));
    EXPECT_EQ(s.scan.stamp_ns, kStart + static_cast<std::int64_t>(count) * kPeriod);
    // Column stamps spread uniformly over one revolution.
    EXPECT_EQ(s.scan.column_stamp_ns[1] - s.scan.column_stamp_ns[0], 55310);  // 1e8 / 1808
    EXPECT_EQ(s.scan.column_stamp_ns.back() - s.scan.stamp_ns, std::llround(1807 * 1e8 / 1808));
    test::expect_same_cells(expected.scan, s.scan);
    EXPECT_EQ(s.labels, expected.labels);
    EXPECT_TRUE(s.pose.translation.isApprox(
        Eigen::Vector3d(0.1 * static_cast<double>(count), 0, 2.5), 1e-9));
    ++count;
  }
  EXPECT_EQ(count, 3u);
}

TEST(Sequence, PosesAreInterpolatedToScanStamps) {
  test::TempDir dir;
  const fs::path folder = dir / "seq";
  write_demo_sequence(folder);
  // Replace the poses with a coarser trajectory: 0 m at 0.5 s, 4 m at 2.5 s, turning 0 -> 90 deg.
  test::write_text(dir / "coarse.txt",
                   "0.5 0 0 0 0 0 0 1\n"
                   "2.5 4 0 0 0 0 0.7071067811865476 0.7071067811865476\n");
  SequenceReadOptions options;
  options.poses = dir / "coarse.txt";
  SequenceReader reader(folder, options);
  // Scan 1 at 1.1 s: 0.3 of the way.
  EXPECT_TRUE(reader.pose(1).translation.isApprox(Eigen::Vector3d(1.2, 0, 0), 1e-9));
  const Eigen::Quaterniond expected(
      Eigen::AngleAxisd(0.3 * std::numbers::pi / 2, Eigen::Vector3d::UnitZ()));
  EXPECT_NEAR(reader.pose(1).rotation.angularDistance(expected), 0.0, 1e-9);
  // A trajectory ending before the last scan: an error naming the scan and its stamp.
  test::write_text(dir / "short.txt", "0.5 0 0 0 0 0 0 1\n1.15 1 0 0 0 0 0 1\n");
  options.poses = dir / "short.txt";
  const std::string e = input_error([&] { SequenceReader r(folder, options); });
  EXPECT_NE(e.find("short.txt: no pose for scan 000002.pcd at stamp 1.200000000 (poses cover "
                   "0.500000000 to 1.150000000)"),
            std::string::npos)
      << e;
  // KITTI poses: one line per scan, stamps from the scans.
  test::write_text(dir / "kitti.txt",
                   "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 1 0 1 0 0 0 0 1 0\n1 0 0 2 0 1 0 0 0 0 1 0\n");
  options.poses = dir / "kitti.txt";
  options.poses_format = PoseFileFormat::kKitti;
  SequenceReader kitti(folder, options);
  EXPECT_EQ(kitti.pose(2).translation.x(), 2.0);
  EXPECT_EQ(kitti.pose(2).stamp_ns, kStart + 2 * kPeriod);
}

// Issue 16: a stamps.txt that steps back (a host clock step while recording) is read as it is,
// so front ends can skip that scan instead of refusing the folder; poses still come per scan.
TEST(Sequence, StampsThatGoBackAreReadWithTheirPoses) {
  test::TempDir dir;
  const fs::path folder = dir / "seq";
  write_demo_sequence(folder, 4);
  test::write_text(folder / "stamps.txt", "# stepped back at scan 2\n1.0\n1.1\n1.05\n1.3\n");
  {
    SequenceReader reader(folder);  // poses.txt (TUM) interpolated at each stamp
    ASSERT_EQ(reader.size(), 4u);
    EXPECT_EQ(reader.stamp_ns(2), 1'050'000'000);
    EXPECT_EQ(reader.pose(2).stamp_ns, 1'050'000'000);
    EXPECT_TRUE(reader.pose(2).translation.isApprox(Eigen::Vector3d(0.05, 0, 2.5), 1e-9));
    SequenceScan s;
    for (int k = 0; k < 3; ++k) ASSERT_TRUE(reader.next(s));
    EXPECT_EQ(s.scan.stamp_ns, 1'050'000'000);
  }
  // KITTI poses: one per scan in order, given the scan's stamp.
  test::write_text(dir / "kitti.txt",
                   "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 1 0 1 0 0 0 0 1 0\n1 0 0 2 0 1 0 0 0 0 1 0\n"
                   "1 0 0 3 0 1 0 0 0 0 1 0\n");
  SequenceReadOptions options;
  options.poses = dir / "kitti.txt";
  options.poses_format = PoseFileFormat::kKitti;
  SequenceReader kitti(folder, options);
  EXPECT_EQ(kitti.pose(2).translation.x(), 2.0);
  EXPECT_EQ(kitti.pose(2).stamp_ns, 1'050'000'000);
  // Still one stamp per scan.
  test::write_text(folder / "stamps.txt", "1.0\n1.1\n1.05\n");
  EXPECT_NE(input_error([&] { SequenceReader r(folder); }).find("3 stamps for 4 scans"),
            std::string::npos);
}

TEST(Sequence, WithoutPosesTheSensorStaysAtTheOrigin) {
  test::TempDir dir;
  const auto model = core::SensorModel::vlp16();
  SequenceWriteOptions options;
  options.ground_truth = false;
  options.encoding = PcdEncoding::kBinary;
  {
    SequenceWriter writer(dir / "seq", SequenceMeta::for_sensor(model, 0), options);
    auto rendered = sim::render(model, sim::SimpleScene::open_field(2));
    writer.add_scan(rendered.scan, {});
    EXPECT_THROW(writer.add_scan(rendered.scan, {}), core::Error);  // stamp does not increase
    writer.finish();
  }
  EXPECT_FALSE(fs::exists(dir / "seq/poses.txt"));
  EXPECT_FALSE(fs::exists(dir / "seq/objects.csv"));
  SequenceReader reader(dir / "seq");
  EXPECT_FALSE(reader.has_poses());
  EXPECT_FALSE(reader.objects_csv());
  EXPECT_TRUE(reader.pose(0).isometry().isApprox(Eigen::Isometry3d::Identity()));
  EXPECT_EQ(reader.meta().columns, model.columns());
  EXPECT_TRUE(reader.read(0).labels.empty());
}

TEST(Sequence, StampsFromTheScanRateWithoutStampsFile) {
  test::TempDir dir;
  write_demo_sequence(dir / "seq");
  fs::remove(dir / "seq/stamps.txt");
  fs::remove(dir / "seq/poses.txt");
  SequenceReader reader(dir / "seq");
  EXPECT_EQ(reader.stamp_ns(0), 0);
  EXPECT_EQ(reader.stamp_ns(2), 200'000'000);
  test::write_text(dir / "seq/stamps.txt", "0\n1\n");
  EXPECT_NE(
      input_error([&] { SequenceReader r(dir / "seq"); }).find("stamps.txt: 2 stamps for 3 scans"),
      std::string::npos);
}

TEST(Sequence, GenericSensorRoundTrip) {
  test::TempDir dir;
  const auto model = core::SensorModel::generic({-10.0, -3.333, 0.0, 5.5}, 360, 5.0, 50.0);
  SequenceWriter writer(dir / "seq", SequenceMeta::for_sensor(model, 360));
  core::OrganizedScan scan(4, 360);
  scan.set_uniform_columns(model, 0);
  for (int c = 0; c < 360; ++c) scan.set_range(model, 1, c, 10.0f, 1.0f);
  writer.add_scan(scan, {});
  writer.finish();
  const std::string yaml = test::read_text(dir / "seq/sequence.yaml");
  EXPECT_NE(yaml.find("sensor: generic\nelevations_deg: [-10, -3.333, 0, 5.5]\nmax_range_m: 50\n"
                      "scan_rate_hz: 5\ncolumns: 360\n"),
            std::string::npos)
      << yaml;
  SequenceReader reader(dir / "seq");
  EXPECT_EQ(reader.sensor().rings(), 4);
  EXPECT_NEAR(reader.sensor().elevation_rad[1], -3.333 * std::numbers::pi / 180, 1e-12);
  EXPECT_EQ(reader.read(0).scan.valid_count(), 360u);
}

TEST(Sequence, RejectsIncompleteAndInconsistentFolders) {
  test::TempDir dir;
  const fs::path folder = dir / "seq";
  write_demo_sequence(folder, 2, false);  // writer never finished
  std::string e = input_error([&] { SequenceReader r(folder); });
  EXPECT_NE(e.find("has scans/ but no sequence.yaml: an incomplete sequence"), std::string::npos)
      << e;

  // An existing sequence is not overwritten by accident.
  EXPECT_THROW(write_demo_sequence(folder), core::Error);
  SequenceWriteOptions overwrite;
  overwrite.overwrite = true;
  {
    SequenceWriter w(folder, SequenceMeta::for_sensor(core::SensorModel::vlp16(), 0), overwrite);
    w.finish();
  }
  EXPECT_EQ(SequenceReader(folder).size(), 0u);

  write_demo_sequence(dir / "gap", 3);
  fs::remove(dir / "gap/scans/000001.pcd");
  e = input_error([&] { SequenceReader r(dir / "gap"); });
  EXPECT_NE(e.find("000001.pcd: missing (scans must be numbered from 000000 without gaps)"),
            std::string::npos)
      << e;

  write_demo_sequence(dir / "count", 2);
  fs::copy_file(dir / "count/scans/000001.pcd", dir / "count/scans/000002.pcd");
  e = input_error([&] { SequenceReader r(dir / "count"); });
  EXPECT_NE(e.find("sequence.yaml: says 2 scans, but scans/ holds 3"), std::string::npos) << e;

  write_demo_sequence(dir / "name", 1);
  fs::copy_file(dir / "name/scans/000000.pcd", dir / "name/scans/scan.pcd");
  e = input_error([&] { SequenceReader r(dir / "name"); });
  EXPECT_NE(e.find("scan.pcd: unexpected file name, expected NNNNNN.pcd"), std::string::npos) << e;

  // A scan with another ring count: an error naming the file, on reading it.
  write_demo_sequence(dir / "rings", 2);
  write_pcd(dir / "rings/scans/000001.pcd", test::make_scan(32, 1808), {}, PcdEncoding::kBinary);
  SequenceReader rings(dir / "rings");
  EXPECT_NO_THROW((void)rings.read(0));
  e = input_error([&] { (void)rings.read(1); });
  EXPECT_NE(
      e.find("000001.pcd: 32 rings (HEIGHT), expected 16 as the sensor vlp16 of sequence.yaml"),
      std::string::npos)
      << e;
  write_pcd(dir / "rings/scans/000001.pcd", test::make_scan(16, 900), {}, PcdEncoding::kBinary);
  e = input_error([&] { (void)rings.read(1); });
  EXPECT_NE(e.find("000001.pcd: 900 columns (WIDTH), expected 1808"), std::string::npos) << e;

  e = input_error([&] { SequenceReader r(dir / "nothing"); });
  EXPECT_NE(e.find("nothing: no such folder"), std::string::npos) << e;
  fs::create_directories(dir / "empty");
  e = input_error([&] { SequenceReader r(dir / "empty"); });
  EXPECT_NE(e.find("no sequence.yaml, no .pcd and no .bin files"), std::string::npos) << e;
}

std::string yaml_error(const std::string& yaml) {
  test::TempDir dir;
  test::write_text(dir / "sequence.yaml", yaml);
  return input_error([&] { (void)read_sequence_yaml(dir / "sequence.yaml"); });
}

TEST(Sequence, YamlIsStrict) {
  const std::string good = "format_version: 1\nsensor: vlp16\nscan_rate_hz: 10\ncolumns: 1800\n";
  test::TempDir dir;
  test::write_text(dir / "ok.yaml", good);
  const SequenceMeta meta = read_sequence_yaml(dir / "ok.yaml");
  EXPECT_EQ(meta.columns, 1800);
  EXPECT_FALSE(meta.scans);
  // A list as key (found while fixing fuzz_scenario's find): an InputError naming the line.
  std::string e = yaml_error(good + "[columns]: 3\n");
  EXPECT_NE(e.find("sequence.yaml:5: expected a key name, got a list or map as key"),
            std::string::npos)
      << e;
  e = yaml_error(good + "colour: red\n");
  EXPECT_NE(e.find("sequence.yaml:5: key 'colour': unknown key"), std::string::npos) << e;
  e = yaml_error("format_version: 2\nsensor: vlp16\nscan_rate_hz: 10\ncolumns: 1800\n");
  EXPECT_NE(e.find("key 'format_version': unsupported version 2 (this ringtrack reads 1)"),
            std::string::npos)
      << e;
  e = yaml_error("format_version: 1\nsensor: os1\nscan_rate_hz: 10\ncolumns: 1800\n");
  EXPECT_NE(e.find("unknown sensor 'os1'"), std::string::npos) << e;
  e = yaml_error("format_version: 1\nsensor: vlp16\nscan_rate_hz: fast\ncolumns: 1800\n");
  EXPECT_NE(e.find("key 'scan_rate_hz': expected a number, got 'fast'"), std::string::npos) << e;
  e = yaml_error("format_version: 1\nsensor: vlp16\nscan_rate_hz: 10\n");
  EXPECT_NE(e.find("missing key 'columns'"), std::string::npos) << e;
  e = yaml_error("format_version: 1\nsensor: generic\nscan_rate_hz: 10\ncolumns: 100\n");
  EXPECT_NE(e.find("sensor 'generic' needs the key 'elevations_deg'"), std::string::npos) << e;
  e = yaml_error(good + "elevations_deg: [1, 2]\n");
  EXPECT_NE(e.find("only allowed with sensor 'generic'"), std::string::npos) << e;
  e = yaml_error("format_version: 1\nsensor: [unclosed\n");
  EXPECT_NE(e.find("invalid YAML"), std::string::npos) << e;
  e = yaml_error("- a list\n");
  EXPECT_NE(e.find("expected a mapping"), std::string::npos) << e;
  e = yaml_error(good + "sensor_height_m: .nan\n");
  EXPECT_NE(e.find("key 'sensor_height_m': expected a height within +-1000 m"), std::string::npos)
      << e;
  EXPECT_FALSE(meta.sensor_height_m) << "optional: absent in sequences that do not know it";
  test::TempDir other;  // yaml_error's folder of the same name is gone by now
  test::write_text(other / "height.yaml", good + "sensor_height_m: 1.2\n");
  EXPECT_EQ(read_sequence_yaml(other / "height.yaml").sensor_height_m, 1.2);
}

TEST(Sequence, ReadsPlainFolderOfPcdFiles) {
  test::TempDir dir;
  const auto model = core::SensorModel::vlp16();
  auto rendered = sim::render(model, sim::SimpleScene::demo());
  // Names that sort wrongly as plain strings; intensities mark the intended order.
  const std::vector<std::string> names{"scan_2.pcd", "scan_10.pcd", "scan_1.pcd"};
  const std::vector<float> order{2, 10, 1};
  for (std::size_t k = 0; k < names.size(); ++k) {
    core::OrganizedScan s = rendered.scan;
    for (int c = 0; c < s.columns(); ++c) {
      const auto i = s.index(0, c);
      if (s.valid(i)) s.set_return(0, c, s.range_m(i), order[k], s.point(i));
    }
    write_pcd(dir / names[k], s, {}, PcdEncoding::kBinaryCompressed);
  }
  test::write_text(dir / "notes.txt", "ignored\n");
  SequenceReadOptions options;
  options.scan_rate_hz = 20.0;
  SequenceReader reader(dir.path(), options);
  EXPECT_FALSE(reader.is_sequence());
  ASSERT_EQ(reader.size(), 3u);
  EXPECT_EQ(reader.scan_path(0).filename(), "scan_1.pcd");
  EXPECT_EQ(reader.scan_path(2).filename(), "scan_10.pcd");
  EXPECT_EQ(reader.stamp_ns(2), 100'000'000);  // 2 / 20 Hz
  // The sensor is inferred from the first scan: VLP-16 elevations, give or take what the beams'
  // vertical offsets (up to 11 mm) add at the ground's 5-10 m ranges.
  EXPECT_EQ(reader.meta().sensor, "generic");
  ASSERT_EQ(reader.sensor().rings(), 16);
  for (int r = 0; r < 16; ++r) {
    EXPECT_NEAR(reader.sensor().elevation_rad[r], model.elevation_rad[r],
                0.2 * std::numbers::pi / 180)
        << r;
  }
  EXPECT_EQ(reader.read(0).scan.intensity(reader.read(0).scan.index(0, 5)), 1.0f);
  // An explicit sensor replaces the inference.
  options.sensor = core::SensorModel::vlp32c();
  SequenceReader explicit_sensor(dir.path(), options);
  EXPECT_EQ(explicit_sensor.meta().sensor, "vlp32c");
  EXPECT_NE(
      input_error([&] { (void)explicit_sensor.read(0); }).find("16 rings (HEIGHT), expected 32"),
      std::string::npos);
}

TEST(Sequence, MeasuresElevationsWithEmptyRings) {
  const auto model = core::SensorModel::vlp16();
  auto rendered = sim::render(model, sim::SimpleScene::demo());
  for (int c = 0; c < rendered.scan.columns(); ++c) {
    rendered.scan.set_invalid(0, c, core::ReturnStatus::kNoReturn);  // like the real VLP-16 data
    rendered.scan.set_invalid(7, c, core::ReturnStatus::kNoReturn);
  }
  const auto e = measure_elevations_deg(rendered.scan, "x.pcd");
  // Ring 0 extrapolated from rings 1 and 2, ring 7 interpolated (beam offsets add ~0.1 deg).
  EXPECT_NEAR(e[0], -15.0, 0.2);
  EXPECT_NEAR(e[7], -1.0, 0.2);
  core::OrganizedScan one(3, 10);
  one.set_return(1, 0, 1.0f, 0.0f, Eigen::Vector3f(1, 0, 0));
  EXPECT_NE(input_error([&] {
              (void)measure_elevations_deg(one, "one.pcd");
            }).find("one.pcd: cannot measure"),
            std::string::npos);
}

}  // namespace
}  // namespace ringtrack::io
