// PointSpill: points spilled to a scratch file and points still in memory come out as one PLY and
// one PCD, checked against the in-memory encoders (encode_ply, encode_pcd_points) of the same
// points; failures name the file and leave no partial output.

#include "ringtrack/io/point_spill.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "ringtrack/core/error.hpp"
#include "ringtrack/io/pcd.hpp"
#include "ringtrack/io/ply.hpp"
#include "ringtrack/io/text.hpp"
#include "support/temp_dir.hpp"

namespace ringtrack::io {
namespace {

namespace fs = std::filesystem;

std::string bytes_of(const fs::path& p) {
  const auto b = read_file_bytes(p);
  return {b.begin(), b.end()};
}

TEST(PointSpill, SpilledThenInMemoryPointsEqualTheInMemoryEncoders) {
  const test::TempDir dir;
  std::mt19937 rng(4);
  std::uniform_real_distribution<float> u(-50.0f, 50.0f);
  std::vector<Eigen::Vector3f> all;
  std::vector<float> intensities;
  // More than one copy block (16,384 points) spilled, then a tail in memory.
  for (int i = 0; i < 40000; ++i) {
    all.emplace_back(u(rng), u(rng), u(rng));
    intensities.push_back(u(rng) + 50.0f);
  }
  constexpr std::size_t kSpilled = 37000;
  const std::string comment = "origin_m 1.000 2.000 3.000 (world = point + origin)";
  PointSpill spill(dir / "map.spill");
  for (std::size_t i = 0; i < kSpilled; ++i) spill.append(all[i], intensities[i]);
  EXPECT_EQ(spill.size(), kSpilled);
  const std::span<const Eigen::Vector3f> tail(all.data() + kSpilled, all.size() - kSpilled);
  const std::span<const float> tail_i(intensities.data() + kSpilled, all.size() - kSpilled);
  spill.write(dir / "map.ply", dir / "map.pcd", tail, tail_i, comment);
  EXPECT_FALSE(fs::exists(dir / "map.spill"));
  EXPECT_EQ(bytes_of(dir / "map.ply"),
            encode_ply(all, intensities, PlyEncoding::kBinaryLittleEndian, comment));
  EXPECT_EQ(bytes_of(dir / "map.pcd"),
            encode_pcd_points(all, intensities, PcdEncoding::kBinary, comment));
  const auto cloud = decode_pcd_cloud(read_file_bytes(dir / "map.pcd"), "map.pcd");
  ASSERT_EQ(cloud.size(), all.size());
  EXPECT_EQ(cloud.xyz.back(), all.back());
}

TEST(PointSpill, NothingSpilledAndNoPcd) {
  const test::TempDir dir;
  PointSpill spill(dir / "s");
  const std::vector<Eigen::Vector3f> points{{1, 2, 3}};
  spill.write(dir / "map.ply", {}, points, {}, {});
  EXPECT_EQ(bytes_of(dir / "map.ply"), encode_ply(points, {}));
  EXPECT_FALSE(fs::exists(dir / "map.pcd"));
}

TEST(PointSpill, FailuresNameTheFileAndLeaveNoOutput) {
  const test::TempDir dir;
  try {
    PointSpill spill(dir / "missing" / "s");
    FAIL() << "a scratch file in a missing folder was created";
  } catch (const core::Error& e) {
    EXPECT_NE(std::string(e.what()).find("missing/s"), std::string::npos) << e.what();
  }
  {
    PointSpill spill(dir / "s");
    spill.append({1, 2, 3}, 4);
    EXPECT_THROW(spill.write(dir / "missing" / "map.ply", {}, {}, {}, {}), core::Error);
    const std::vector<Eigen::Vector3f> one{{0, 0, 0}};
    const std::vector<float> two{1, 2};
    EXPECT_THROW(spill.write(dir / "map.ply", {}, one, two, {}), core::Error);
    EXPECT_FALSE(fs::exists(dir / "map.ply"));
  }
  EXPECT_FALSE(fs::exists(dir / "s"));  // the destructor removes the scratch file
}

}  // namespace
}  // namespace ringtrack::io
