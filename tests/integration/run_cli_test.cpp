// `ringtrack run` end to end: outputs and their schemas, and bad input as one-line errors.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "ringtrack/core/config.hpp"
#include "ringtrack/io/csv_writers.hpp"
#include "ringtrack/io/pcd.hpp"
#include "ringtrack/io/sequence.hpp"
#include "ringtrack/io/text.hpp"
#include "support/run_command.hpp"

namespace ringtrack {
namespace {

namespace fs = std::filesystem;
using testing::run_command;

const std::string kCli = RINGTRACK_CLI_PATH;

std::string first_line(const fs::path& p) {
  std::ifstream in(p);
  std::string line;
  std::getline(in, line);
  return line;
}

std::size_t line_count(const fs::path& p) {
  std::ifstream in(p);
  std::size_t n = 0;
  for (std::string line; std::getline(in, line);) ++n;
  return n;
}

// A run's static map: the PCD's points, checked to be the PLY's points in the same order
// (binary PLY: 16 bytes per point after the header).
core::UnorganizedCloud map_of_run(const std::string& out) {
  auto map = io::decode_pcd_cloud(io::read_file_bytes(out + "/static_map.pcd"), "static_map.pcd");
  const auto ply = io::read_file_bytes(out + "/static_map.ply");
  const std::string end_header = "end_header\n";
  const auto body = std::search(ply.begin(), ply.end(), end_header.begin(), end_header.end()) -
                    ply.begin() + static_cast<std::ptrdiff_t>(end_header.size());
  EXPECT_EQ(ply.size() - static_cast<std::size_t>(body), 16 * map.size()) << out;
  if (ply.size() - static_cast<std::size_t>(body) != 16 * map.size()) return {};
  for (std::size_t i = 0; i < map.size(); ++i) {
    float v[4];
    std::memcpy(v, ply.data() + body + static_cast<std::ptrdiff_t>(16 * i), sizeof v);
    EXPECT_EQ(map.xyz[i], Eigen::Vector3f(v[0], v[1], v[2])) << out << ", point " << i;
    EXPECT_EQ(map.intensity[i], v[3]) << out << ", point " << i;
    if (map.xyz[i] != Eigen::Vector3f(v[0], v[1], v[2])) return {};
  }
  return map;
}

class RunCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = testing::make_temp_dir("ringtrack-run-");
    const auto r = run_command(kCli + " simulate 1 --duration 3 --seed 3 --out " + dir_ + "/seq");
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }
  static std::string dir_;
};
std::string RunCli::dir_;

TEST_F(RunCli, WritesEveryOutputWithItsSchema) {
  const std::string out = dir_ + "/out";
  const auto r = run_command(kCli + " run " + dir_ + "/seq --out " + out +
                             " --filtered-scans --set mapping.voxel_size_m=0.2");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("scans            30"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("ms per scan"), std::string::npos);
  EXPECT_EQ(first_line(out + "/tracks.csv"), io::kTracksCsvHeader);
  EXPECT_GT(line_count(out + "/tracks.csv"), 30u);
  EXPECT_EQ(first_line(out + "/timing.csv")
                .rfind("scan,stamp,segmentation_ms,detection_ms,tracking_ms,mapping_ms", 0),
            0u)
      << first_line(out + "/timing.csv");
  EXPECT_EQ(line_count(out + "/timing.csv"), 31u);
  EXPECT_EQ(first_line(out + "/static_map.ply"), "ply");
  EXPECT_GT(map_of_run(out).size(), 100u);
  EXPECT_TRUE(fs::exists(out + "/filtered/000029.pcd"));
  std::ifstream config(out + "/config.yaml");
  std::stringstream text;
  text << config.rdbuf();
  EXPECT_NE(text.str().find("voxel_size_m: 0.2"), std::string::npos);
}

// Width and height from a PNG's IHDR chunk; {0, 0} when the file is not a PNG.
std::pair<std::uint32_t, std::uint32_t> png_size(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  unsigned char h[24] = {};
  in.read(reinterpret_cast<char*>(h), sizeof h);
  if (!in || h[1] != 'P' || h[2] != 'N' || h[3] != 'G' || h[12] != 'I' || h[15] != 'R')
    return {0, 0};
  const auto be32 = [&](int i) {
    return (std::uint32_t{h[i]} << 24) | (std::uint32_t{h[i + 1]} << 16) |
           (std::uint32_t{h[i + 2]} << 8) | std::uint32_t{h[i + 3]};
  };
  return {be32(16), be32(20)};
}

bool have_matplotlib() {
  return run_command("/usr/bin/python3 -c 'import matplotlib, numpy'").exit_code == 0;
}

TEST_F(RunCli, DrawsTheRawPointsBesideTheStaticMap) {
  if (!have_matplotlib()) GTEST_SKIP() << "python3-matplotlib is not installed";
  const std::string out = dir_ + "/plots";
  const auto r = run_command(kCli + " run " + dir_ + "/seq --out " + out);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("maps.png"), std::string::npos) << r.out;
  // Fig. 7: one figure of 14 x 6.6 inches at 110 dpi, two panels.
  EXPECT_EQ(png_size(out + "/maps.png"), std::make_pair(1540u, 726u));
  // Not blank: the pixels vary (a blank or single-colour figure has a tiny spread), read back by
  // matplotlib's own PNG reader.
  const auto spread =
      run_command("/usr/bin/python3 -c \"import matplotlib.image as m; a = m.imread('" + out +
                  "/maps.png'); print(int(1000 * a[..., :3].std()), int((a[..., :3].sum(axis=2) < "
                  "2.9).mean() * 1000))\"");
  ASSERT_EQ(spread.exit_code, 0) << spread.err;
  int std_milli = 0, ink_permille = 0;
  std::istringstream(spread.out) >> std_milli >> ink_permille;
  EXPECT_GT(std_milli, 50) << spread.out;
  EXPECT_GT(ink_permille, 20) << "share of non-white pixels, per mille: " << spread.out;
  // The raw map holds every point, so at least as many voxels as the static map; one pose per
  // scan.
  EXPECT_EQ(first_line(out + "/raw_map.ply"), "ply");
  EXPECT_GE(fs::file_size(out + "/raw_map.ply"), fs::file_size(out + "/static_map.ply"));
  EXPECT_EQ(line_count(out + "/poses.txt"), 31u);  // a comment header, then one line per scan
}

TEST_F(RunCli, NoPlotsWritesNoPictures) {
  const std::string out = dir_ + "/no-plots";
  const auto r = run_command(kCli + " run " + dir_ + "/seq --out " + out + " --no-plots");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_FALSE(fs::exists(out + "/maps.png"));
  EXPECT_FALSE(fs::exists(out + "/raw_map.ply"));
  EXPECT_TRUE(fs::exists(out + "/static_map.ply"));
}

TEST_F(RunCli, FilteredScansGiveMapMetricsInEval) {
  const std::string out = dir_ + "/out-map";
  ASSERT_EQ(run_command(kCli + " run " + dir_ + "/seq --out " + out + " --filtered-scans --quiet")
                .exit_code,
            0);
  const auto r = run_command(kCli + " eval --json --gt " + dir_ + "/seq --tracks " + out +
                             "/tracks.csv --filtered " + out + "/filtered");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const char* key : {"\"overall_map\"", "\"preservation_rate\"", "\"rejection_rate\"",
                          "\"static_points\"", "\"dynamic_points\""}) {
    EXPECT_NE(r.out.find(key), std::string::npos) << key << "\n" << r.out;
  }
  // Most static points survive the filter (people walk in an empty field).
  const auto at = r.out.find("\"preservation_rate\": ");
  ASSERT_NE(at, std::string::npos);
  EXPECT_GT(std::stod(r.out.substr(at + 21)), 0.99);
  // A missing filtered scan is an error naming the file.
  fs::remove(out + "/filtered/000005.pcd");
  const auto bad = run_command(kCli + " eval --gt " + dir_ + "/seq --tracks " + out +
                               "/tracks.csv --filtered " + out + "/filtered");
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.err.find("000005.pcd"), std::string::npos) << bad.err;
}

// The fourth property (intensity) of every vertex of a binary PLY written by ringtrack.
std::vector<float> ply_intensities(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::size_t n = 0;
  for (std::string line; std::getline(in, line) && line != "end_header";) {
    if (line.rfind("element vertex ", 0) == 0) n = std::stoul(line.substr(15));
  }
  std::vector<float> xyzi(4 * n);
  in.read(reinterpret_cast<char*>(xyzi.data()), static_cast<std::streamsize>(4 * xyzi.size()));
  std::vector<float> out;
  for (std::size_t i = 0; i < n; ++i) out.push_back(xyzi[4 * i + 3]);
  return out;
}

long long json_count(const std::string& json, const std::string& key) {
  const auto at = json.find("\"" + key + "\": ");
  return at == std::string::npos ? -1 : std::stoll(json.substr(at + key.size() + 4));
}

TEST_F(RunCli, MapErrorPictureHoldsExactlyTheFiltersErrors) {
  if (!have_matplotlib()) GTEST_SKIP() << "python3-matplotlib is not installed";
  const std::string out = dir_ + "/out-errors";
  ASSERT_EQ(run_command(kCli + " run " + dir_ + "/seq --out " + out +
                        " --filtered-scans --quiet --no-plots")
                .exit_code,
            0);
  const auto r = run_command(kCli + " eval --json --gt " + dir_ + "/seq --tracks " + out +
                             "/tracks.csv --filtered " + out + "/filtered --map-errors-png " + out +
                             "/errors.png");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(png_size(out + "/errors.png"), std::make_pair(880u, 825u));
  // The points beside the picture: kind 1 = dynamic kept, 2 = static removed; as many as the
  // map metrics count.
  const auto kinds = ply_intensities(out + "/errors.ply");
  const auto count = [&](float k) {
    return static_cast<long long>(std::count(kinds.begin(), kinds.end(), k));
  };
  const auto m = r.out.substr(r.out.find("\"overall_map\""));
  EXPECT_EQ(count(1.0f), json_count(m, "dynamic_points") - json_count(m, "dynamic_removed"));
  EXPECT_EQ(count(2.0f), json_count(m, "static_points") - json_count(m, "static_kept"));
  EXPECT_GT(count(0.0f), 1000);  // the scene
  // One picture per run: two sequences are refused.
  const auto two =
      run_command(kCli + " eval --gt " + dir_ + "/seq --gt " + dir_ + "/seq --tracks " + out +
                  "/tracks.csv --tracks " + out + "/tracks.csv --filtered " + out +
                  "/filtered --filtered " + out + "/filtered --map-errors-png " + out + "/e2.png");
  EXPECT_EQ(two.exit_code, 1);
  EXPECT_NE(two.err.find("--map-errors-png"), std::string::npos) << two.err;
}

TEST_F(RunCli, MissingInputIsOneLineError) {
  const auto r = run_command(kCli + " run " + dir_ + "/nothing-here --out " + dir_ + "/o2");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("nothing-here"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
}

TEST_F(RunCli, MalformedPosesFileIsOneLineErrorNamingTheLine) {
  { std::ofstream(dir_ + "/bad_poses.txt") << "0 0 0 0 0 0 0 1\n0.1 1 2 nan 0 0 0 1\n"; }
  const auto r = run_command(kCli + " run " + dir_ + "/seq --out " + dir_ + "/o3 --poses " + dir_ +
                             "/bad_poses.txt");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("bad_poses.txt"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
}

TEST_F(RunCli, UnorganizedPcdFolderIsRejected) {
  const std::string folder = dir_ + "/plain";
  fs::create_directories(folder);
  {
    std::ofstream(folder + "/a.pcd")
        << "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
           "WIDTH 2\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\nDATA ascii\n"
           "1 2 3\n4 5 6\n";
  }
  const auto r = run_command(kCli + " run " + folder + " --out " + dir_ + "/o4");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("a.pcd"), std::string::npos) << r.err;
}

TEST_F(RunCli, UnknownConfigKeyFailsBeforeAnyOutput) {
  const auto r =
      run_command(kCli + " run " + dir_ + "/seq --out " + dir_ + "/o5 --set tracking.nope=1");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("tracking.nope"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ + "/o5/tracks.csv"));
}

// The hall's sensor stands 1.2 m above its floor, not the default 2.5 m: the simulated sequence
// says so and `run` takes it (the altitude test counts from the floor), unless the user's
// configuration sets the key, in a file or with --set.
TEST_F(RunCli, ASimulatedSequenceGivesItsSensorHeight) {
  const std::string hall = dir_ + "/hall";
  ASSERT_EQ(run_command(kCli + " simulate 7 --duration 0.5 --out " + hall).exit_code, 0);
  const auto meta = io::read_sequence_yaml(hall + "/sequence.yaml");
  ASSERT_TRUE(meta.sensor_height_m);
  EXPECT_NEAR(*meta.sensor_height_m, 1.2, 1e-9);
  const auto height_used = [&](const std::string& out, const std::string& options) {
    const auto r =
        run_command(kCli + " run " + hall + " --no-plots --quiet --out " + out + " " + options);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    core::Config used;
    core::apply_config_file(used, out + "/config.yaml");
    return used.detection.sensor_height_m;
  };
  EXPECT_NEAR(height_used(dir_ + "/h1", ""), 1.2, 1e-9);
  EXPECT_NEAR(height_used(dir_ + "/h2", "--set detection.sensor_height_m=2.5"), 2.5, 1e-9);
  std::ofstream(dir_ + "/height.yaml") << "detection:\n  sensor_height_m: 3.0\n";
  EXPECT_NEAR(height_used(dir_ + "/h3", "--config " + dir_ + "/height.yaml"), 3.0, 1e-9);
  // Another key in the file leaves the sequence's height in force.
  std::ofstream(dir_ + "/other.yaml") << "detection:\n  min_height_m: 0.7\n";
  EXPECT_NEAR(height_used(dir_ + "/h4", "--config " + dir_ + "/other.yaml"), 1.2, 1e-9);
}

// mapping.map_radius_m: voxels farther from the moving sensor leave memory during the run and
// are written out; the maps hold them and what stayed (PLY and PCD alike, the scratch file
// gone), every voxel of the unbounded run's map among them.
TEST_F(RunCli, ABoundedMapWritesOutWhatLeftMemory) {
  const std::string seq = dir_ + "/flight";
  ASSERT_EQ(run_command(kCli + " simulate 1 --duration 3 --seed 3 --moving-sensor --out " + seq)
                .exit_code,
            0);
  const std::string common = " --no-plots --quiet --set mapping.log_delay_scans=5 --out ";
  const auto all = run_command(kCli + " run " + seq + common + dir_ + "/all");
  ASSERT_EQ(all.exit_code, 0) << all.err;
  const auto near =
      run_command(kCli + " run " + seq + common + dir_ + "/near --set mapping.map_radius_m=5");
  ASSERT_EQ(near.exit_code, 0) << near.err;
  unsigned long long voxels = 0, spilled = 0;
  const auto at = near.out.find("static map ");
  ASSERT_NE(at, std::string::npos) << near.out;
  ASSERT_EQ(std::sscanf(near.out.c_str() + at, "static map %llu voxels (%llu written out", &voxels,
                        &spilled),
            2)
      << near.out;
  EXPECT_GT(spilled, 1000u);
  EXPECT_FALSE(fs::exists(dir_ + "/near/static_map.spill"));
  EXPECT_FALSE(fs::exists(dir_ + "/near/raw_map.ply"));
  const auto bounded = map_of_run(dir_ + "/near");
  const auto unbounded = map_of_run(dir_ + "/all");
  ASSERT_EQ(bounded.size(), voxels);
  const auto key = [](const Eigen::Vector3f& p) {
    return std::array<long, 3>{std::lround(std::floor(p.x() / 0.1f)),
                               std::lround(std::floor(p.y() / 0.1f)),
                               std::lround(std::floor(p.z() / 0.1f))};
  };
  std::set<std::array<long, 3>> bounded_keys;
  for (const auto& p : bounded.xyz) bounded_keys.insert(key(p));
  std::size_t missing = 0;
  for (const auto& p : unbounded.xyz) missing += bounded_keys.count(key(p)) == 0 ? 1 : 0;
  EXPECT_EQ(missing, 0u) << "of " << unbounded.size();
}

}  // namespace
}  // namespace ringtrack
