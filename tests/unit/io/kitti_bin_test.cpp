#include "ringtrack/io/kitti_bin.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <map>
#include <numbers>
#include <tuple>

#include "io_test_util.hpp"
#include "ringtrack/io/pcd.hpp"
#include "ringtrack/io/pointcloud2.hpp"
#include "ringtrack/io/scan_source.hpp"
#include "ringtrack/io/sequence.hpp"
#include "ringtrack/io/text.hpp"
#include "ringtrack/sim/simple_scene.hpp"
#include "support/rosbag_writers.hpp"

namespace ringtrack::io {
namespace {

// Default options, named: a braced temporary trips g++ 12's -Wmaybe-uninitialized.
const ScanSourceOptions kDefaults;

using test::input_error;
namespace fs = std::filesystem;

std::span<const std::uint8_t> as_bytes(const std::string& s) {
  return {reinterpret_cast<const std::uint8_t*>(s.data()), s.size()};
}

// Cell for cell, ranges measured from the beam origins (close to, not bit-equal with, the
// simulator's).
void expect_recovered(const core::OrganizedScan& expected, const core::OrganizedScan& actual) {
  ASSERT_EQ(actual.rings(), expected.rings());
  ASSERT_EQ(actual.columns(), expected.columns());
  for (std::size_t i = 0; i < expected.size(); ++i) {
    ASSERT_EQ(actual.valid(i), expected.valid(i)) << "cell " << i;
    if (!expected.valid(i)) continue;
    ASSERT_EQ(actual.point(i), expected.point(i)) << "cell " << i;
    ASSERT_EQ(actual.intensity(i), expected.intensity(i)) << "cell " << i;
    ASSERT_NEAR(actual.range_m(i), expected.range_m(i), 1e-4f) << "cell " << i;
  }
}

TEST(KittiBin, EncodesAndDecodesExactly) {
  core::UnorganizedCloud cloud;
  cloud.xyz = {{1.5f, -2.25f, 0.125f}, {-0.0f, 1e-30f, 3e7f}};
  cloud.intensity = {0.25f, 1.0f};
  const std::string bytes = encode_kitti_bin(cloud);
  ASSERT_EQ(bytes.size(), 32u);
  float first[4];
  std::memcpy(first, bytes.data(), 16);
  EXPECT_EQ(first[0], 1.5f);
  EXPECT_EQ(first[3], 0.25f);
  const auto back = decode_kitti_bin(as_bytes(bytes), "a.bin");
  EXPECT_EQ(back.xyz, cloud.xyz);
  EXPECT_EQ(back.intensity, cloud.intensity);
  EXPECT_TRUE(back.time_ns.empty());
  EXPECT_EQ(decode_kitti_bin({}, "empty.bin").size(), 0u);
}

TEST(KittiBin, ASizeThatIsNotAMultipleOf16IsOneClearError) {
  const std::string bytes(40, '\0');
  const std::string e = input_error([&] { (void)decode_kitti_bin(as_bytes(bytes), "cut.bin"); });
  EXPECT_NE(e.find("cut.bin: 40 bytes is not a multiple of 16"), std::string::npos) << e;
  EXPECT_NE(e.find("the point at offset 32 is truncated (8 of 16 bytes)"), std::string::npos) << e;
  test::TempDir dir;
  test::write_text(dir / "000000.bin", std::string(17, '\0'));
  const std::string f = input_error([&] { SequenceReader r(dir.path()); });
  EXPECT_NE(f.find("000000.bin: 17 bytes"), std::string::npos) << f;
  EXPECT_NE(f.find("offset 16"), std::string::npos) << f;
}

TEST(KittiBin, NaNPointsAreSkippedAndCounted) {
  core::UnorganizedCloud cloud;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  cloud.xyz = {{nan, nan, nan}, {10, 0, 0.17455f}, {0, 0, 0}};  // the middle one on ring +1 deg
  cloud.intensity = {1, 2, 3};
  const auto back = decode_kitti_bin(as_bytes(encode_kitti_bin(cloud)), "n.bin");
  const auto o = core::CloudOrganizer(core::SensorModel::vlp16()).organize(back);
  EXPECT_EQ(o.stats.non_finite, 1u);
  EXPECT_EQ(o.stats.at_origin, 1u);
  EXPECT_EQ(o.stats.organized, 1u);
}

// A folder of .bin files of three simulated VLP-16 scans.
std::vector<core::OrganizedScan> write_bin_folder(const fs::path& folder) {
  const auto model = core::SensorModel::vlp16();
  std::vector<core::OrganizedScan> scans;
  for (const auto& scene :
       {sim::SimpleScene::demo(), sim::SimpleScene::hard_wall(), sim::SimpleScene::open_field()}) {
    scans.push_back(sim::render(model, scene).scan);
  }
  fs::create_directories(folder);
  for (std::size_t k = 0; k < scans.size(); ++k) {
    write_kitti_bin(folder / (std::to_string(k) + ".bin"), core::flatten_scan(scans[k]));
  }
  return scans;
}

// Reading options for the simulator's flattened scans: its columns turn counter-clockwise and all
// its lasers fire at the column.
SequenceReadOptions simulated_cloud_options(const core::SensorModel& model) {
  SequenceReadOptions options;
  options.sensor = model;
  options.organizer.clockwise = false;
  options.organizer.undo_firing_rotation = false;
  return options;
}

TEST(KittiBin, FolderRoundTripRecoversTheScans) {
  test::TempDir dir;
  const auto scans = write_bin_folder(dir / "bins");
  SequenceReader reader(dir / "bins", simulated_cloud_options(core::SensorModel::vlp16()));
  EXPECT_FALSE(reader.is_sequence());
  EXPECT_EQ(reader.meta().sensor, "vlp16");
  ASSERT_EQ(reader.size(), 3u);
  SequenceScan item;
  std::size_t k = 0;
  while (reader.next(item)) {
    SCOPED_TRACE(k);
    expect_recovered(scans[k], item.scan);
    EXPECT_EQ(item.scan.stamp_ns, static_cast<std::int64_t>(k) * 100'000'000);
    ++k;
  }
  EXPECT_EQ(reader.organize_totals().clouds, 3u);
  EXPECT_EQ(reader.organize_totals().sum.dropped(), 0u);
  EXPECT_NE(reader.summary().find("organized 3 clouds"), std::string::npos) << reader.summary();

  // The default grid turns clockwise: column c of the simulator is column (columns - c) % columns.
  SequenceReadOptions clockwise;
  clockwise.sensor = core::SensorModel::vlp16();
  clockwise.organizer.undo_firing_rotation = false;
  SequenceReader cw(dir / "bins", clockwise);
  const auto first = cw.read(0).scan;
  const int columns = first.columns();
  for (int r = 0; r < first.rings(); ++r) {
    for (int c = 0; c < columns; ++c) {
      ASSERT_EQ(first.valid(first.index(r, (columns - c) % columns)),
                scans[0].valid(scans[0].index(r, c)));
    }
  }
}

TEST(KittiBin, Hdl64eFolderIsOrganizedByTheBuiltInModel) {
  // KITTI's clouds are of an HDL-64E: a simulated one (beam origins 0.11 / 0.20 m up, two ring
  // spacings), flattened into .bin files, comes back cell for cell with --sensor hdl64e.
  test::TempDir dir;
  const auto model = core::SensorModel::by_name("hdl64e");
  std::vector<core::OrganizedScan> scans;
  for (const auto& scene : {sim::SimpleScene::demo(), sim::SimpleScene::open_field()}) {
    scans.push_back(sim::render(model, scene).scan);
  }
  fs::create_directories(dir / "velodyne");
  for (std::size_t k = 0; k < scans.size(); ++k) {
    write_kitti_bin(dir / "velodyne" / ("00000" + std::to_string(k) + ".bin"),
                    core::flatten_scan(scans[k]));
  }
  SequenceReader reader(dir / "velodyne", simulated_cloud_options(model));
  EXPECT_EQ(reader.meta().sensor, "hdl64e");
  ASSERT_EQ(reader.size(), 2u);
  SequenceScan item;
  std::size_t k = 0;
  while (reader.next(item)) {
    SCOPED_TRACE(k);
    ASSERT_EQ(item.scan.rings(), 64);
    expect_recovered(scans[k], item.scan);
    ++k;
  }
  EXPECT_EQ(reader.organize_totals().sum.dropped(), 0u);
  // Without the model the rings are measured from the sensor origin, where beam origins 0.11 and
  // 0.20 m up smear them: the count is not 64 (the reason for the built-in model).
  SequenceReader measured(dir / "velodyne");
  EXPECT_NE(measured.sensor().rings(), 64);
  std::printf("hdl64e folder measured without --sensor: %d rings\n", measured.sensor().rings());
}

TEST(KittiBin, FolderWithoutASensorMeasuresOne) {
  test::TempDir dir;
  const auto scans = write_bin_folder(dir / "bins");
  SequenceReader reader(dir / "bins");
  EXPECT_EQ(reader.meta().sensor, "generic");
  ASSERT_EQ(reader.sensor().rings(), 16);
  EXPECT_EQ(reader.sensor().columns(), core::SensorModel::vlp16().columns());
  std::size_t organized = 0;
  std::size_t total = 0;
  for (std::size_t k = 0; k < reader.size(); ++k) {
    organized += reader.read(k).scan.valid_count();
    total += scans[k].valid_count();
  }
  // A measured sensor has no beam offsets: the VLP-16's outer rings, 11 mm off the axis, put
  // returns nearer than ~1.5 m outside the ring window (the hard-wall scene's wall is 1 m away).
  std::printf("measured sensor: %zu of %zu points kept\n", organized, total);
  EXPECT_GT(static_cast<double>(organized), 0.85 * static_cast<double>(total));
  EXPECT_GT(static_cast<double>(reader.read(0).scan.valid_count()),
            0.99 * static_cast<double>(scans[0].valid_count()));  // the demo scene: 6-12 m
}

TEST(KittiBin, FoldersAreRecognisedAndOpenedAsSources) {
  test::TempDir dir;
  const auto scans = write_bin_folder(dir / "bins");
  EXPECT_EQ(guess_scan_input_format((dir / "bins").string()), ScanInputFormat::kFolder);
  EXPECT_EQ(parse_scan_input_format("bin"), ScanInputFormat::kFolder);
  fs::create_directories(dir / "empty");
  EXPECT_NE(input_error([&] {
              (void)open_source((dir / "empty").string(), kDefaults);
            }).find("a folder of KITTI-style .bin files"),
            std::string::npos);
  ScanSourceOptions options;
  options.velodyne.decoder.model = "vlp16";
  auto source = open_source((dir / "bins").string(), options);
  EXPECT_EQ(source->model().name, "VLP-16");
  std::size_t n = 0;
  while (auto scan = source->next()) {
    // Firing delays undone on the simulator's points (which have none): some share a cell.
    EXPECT_GT(scan->valid_count(), scans[n].valid_count() * 9 / 10);
    ++n;
  }
  EXPECT_EQ(n, 3u);
  EXPECT_NE(source->summary().find("3 scan files; organized 3 clouds"), std::string::npos)
      << source->summary();
  // Both kinds of files: which ones are the scans?
  write_pcd(dir / "bins" / "x.pcd", test::make_scan(16, 100), {});
  const std::string e = input_error([&] { SequenceReader r(dir / "bins"); });
  EXPECT_NE(e.find("holds both .pcd (1) and .bin (3) files"), std::string::npos) << e;
}

TEST(KittiBin, UnorganizedPcdWithoutRingsIsOrganized) {
  test::TempDir dir;
  const auto model = core::SensorModel::vlp16();
  const auto scan = sim::render(model, sim::SimpleScene::demo()).scan;
  const auto cloud = core::flatten_scan(scan);
  std::string pcd =
      "VERSION 0.7\nFIELDS x y z intensity\nSIZE 4 4 4 4\nTYPE F F F F\nCOUNT 1 1 1 1\n";
  pcd += "WIDTH " + std::to_string(cloud.size()) + "\nHEIGHT 1\nPOINTS " +
         std::to_string(cloud.size()) + "\nDATA binary\n";
  pcd += encode_kitti_bin(cloud);  // the same 16-byte records
  fs::create_directories(dir / "pcd");
  test::write_text(dir / "pcd" / "a.pcd", pcd);
  const auto header = parse_pcd_header(as_bytes(pcd), "a.pcd");
  EXPECT_TRUE(pcd_needs_organizer(header, "ring"));
  SequenceReadOptions options;
  options.sensor = model;
  options.organizer.clockwise = false;
  options.organizer.undo_firing_rotation = false;
  SequenceReader reader(dir / "pcd", options);
  expect_recovered(scan, reader.read(0).scan);
  EXPECT_EQ(reader.organize_totals().sum.organized, cloud.size());
}

TEST(KittiBin, PointCloud2WithoutRingFieldIsOrganized) {
  // Points where a Velodyne decode puts them: column c fires at Velodyne azimuth (c + 0.5) steps
  // (clockwise from +x), each laser later by its firing offset.
  const auto model = core::SensorModel::vlp16();
  const int columns = model.columns();
  const double step = 2 * std::numbers::pi / columns;
  const double turn_per_us = 2 * std::numbers::pi * model.scan_rate_hz * 1e-6;
  core::OrganizedScan expected(model.rings(), columns);
  std::vector<::ringtrack::test::TestPoint> points;
  for (int c = 0; c < columns; c += 2) {
    for (int r = 0; r < model.rings(); ++r) {
      const double az = -(c + 0.5) * step - turn_per_us * model.firing_offset_us[r];
      const auto range = static_cast<float>(4.0 + 0.002 * c + 0.1 * r);
      const Eigen::Vector3f p = model.point(r, az, range);
      expected.set_return(r, c, range, static_cast<float>(r), p);
      points.push_back({p.x(), p.y(), p.z(), static_cast<float>(r), 0, 0.0f});
    }
  }
  const auto cloud = ::ringtrack::test::make_xyzirt_cloud(
      points, 1, static_cast<std::uint32_t>(points.size()), 5'000'000'000, /*with_ring=*/false);
  const auto bytes =
      ::ringtrack::test::serialize_pointcloud2(cloud, ::ringtrack::test::RosEncoding::kCdr);
  const PointCloud2 parsed = parse_pointcloud2(bytes, RosSerialization::kCdr, "t");
  PointCloud2Options options;
  options.model = "vlp16";
  PointCloud2Organizer organizer(options);
  const auto scan = organizer.organize(parsed, "t");
  expect_recovered(expected, scan);
  EXPECT_EQ(organizer.stats().ringless.clouds, 1u);
  EXPECT_EQ(organizer.stats().ringless.sum.organized, points.size());
  EXPECT_EQ(scan.column_stamp_ns[0], 5'000'000'000);

  // Without a model: measured on the first cloud (16 rings, the VLP-16's columns).
  PointCloud2Organizer measured;
  const auto m = measured.organize(parsed, "t");
  EXPECT_EQ(m.rings(), 16);
  EXPECT_EQ(measured.model().name, "generic");
}

TEST(KittiBin, RealVlp16CloudWithoutItsChannelFieldGetsTheChannelsRings) {
  // nebula's decode of a real dual-return VLP-16 revolution, as an unorganized PCD whose ring
  // field is called `channel` (so: no ring field). Oracle: every point the organizer keeps sits in
  // the ring its channel names.
  const fs::path data = std::getenv("RINGTRACK_TEST_DATA") != nullptr
                            ? fs::path(std::getenv("RINGTRACK_TEST_DATA"))
                            : fs::path(RINGTRACK_SOURCE_DIR) / "../shared/data";
  const auto path = data / "vlp16_indoor_nebula/reference_last_scan.pcd";
  if (!fs::exists(path)) GTEST_SKIP() << "real VLP-16 test data not found: " << path;
  const auto bytes = read_file_bytes(path);
  const PcdHeader header = parse_pcd_header(bytes, path.string());
  ASSERT_TRUE(pcd_needs_organizer(header, "ring"));
  const core::UnorganizedCloud cloud = decode_pcd_cloud(bytes, path.string());
  ASSERT_EQ(cloud.size(), 14831u);
  PcdReadOptions by_channel;
  by_channel.organize_columns = 1808;
  by_channel.ring_field = "channel";
  by_channel.row_order = PcdRowOrder::kBottomFirst;
  const auto truth = decode_pcd(bytes, path.string(), by_channel).scan;  // ring = channel
  std::map<std::tuple<float, float, float>, int> ring_of_point;
  for (std::size_t i = 0; i < truth.size(); ++i) {
    if (!truth.valid(i)) continue;
    const auto p = truth.point(i);
    ring_of_point[{p.x(), p.y(), p.z()}] = truth.ring_of(i);
  }
  core::CloudOrganizerOptions options;
  options.clockwise = true;
  options.undo_firing_rotation = true;
  const auto o = core::CloudOrganizer(core::SensorModel::vlp16(), options).organize(cloud);
  std::size_t checked = 0;
  for (std::size_t i = 0; i < o.scan.size(); ++i) {
    if (!o.scan.valid(i)) continue;
    const auto p = o.scan.point(i);
    const auto it = ring_of_point.find({p.x(), p.y(), p.z()});
    if (it == ring_of_point.end()) continue;  // lost its cell in the channel-based scan
    ASSERT_EQ(o.scan.ring_of(i), it->second) << "point " << p.transpose();
    ++checked;
  }
  std::printf(
      "real VLP-16 (dual return): %llu points, %llu in cells, %llu collided, %llu between rings, "
      "%llu out of range; elevation error median %.3f p95 %.3f max %.3f deg; %zu checked\n",
      static_cast<unsigned long long>(o.stats.points),
      static_cast<unsigned long long>(o.stats.organized),
      static_cast<unsigned long long>(o.stats.collided),
      static_cast<unsigned long long>(o.stats.between_rings),
      static_cast<unsigned long long>(o.stats.out_of_range), o.stats.median_elevation_error_deg,
      o.stats.p95_elevation_error_deg, o.stats.max_elevation_error_deg, checked);
  // nebula places every beam at the sensor origin: the organizer sees it and drops nothing.
  EXPECT_FALSE(o.stats.beam_offsets);
  EXPECT_EQ(o.stats.between_rings, 0u);
  EXPECT_GT(checked, o.stats.organized * 9 / 10);
  core::CloudOrganizerOptions forced = options;
  forced.beam_origins = core::BeamOrigins::kModel;
  const auto f = core::CloudOrganizer(core::SensorModel::vlp16(), forced).organize(cloud);
  std::printf("with the model's beam offsets forced: %llu between rings, median error %.3f deg\n",
              static_cast<unsigned long long>(f.stats.between_rings),
              f.stats.median_elevation_error_deg);
  EXPECT_GT(f.stats.between_rings, 0u);
  // Dual returns: about half the points are the second return of a cell.
  EXPECT_GT(o.stats.organized, 6000u);
  // Measured without a model: ring 0 (-15 deg) returns nothing indoors, so 15 rings.
  const auto measured = core::measure_cloud_sensor(cloud, path.string());
  std::printf("measured: %d rings, %d columns, lowest %.3f deg, highest %.3f deg\n",
              measured.rings(), measured.columns(),
              measured.elevation_rad.front() * 180 / std::numbers::pi,
              measured.elevation_rad.back() * 180 / std::numbers::pi);
  EXPECT_GE(measured.rings(), 14);
}

}  // namespace
}  // namespace ringtrack::io
