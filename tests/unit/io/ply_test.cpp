#include "ringtrack/io/ply.hpp"

#include <gtest/gtest.h>

#include <cstring>

#include "io_test_util.hpp"
#include "ringtrack/core/error.hpp"
#include "ringtrack/io/pcd.hpp"

namespace ringtrack::io {
namespace {

const std::vector<Eigen::Vector3f> kPoints{{1.0f, -2.0f, 0.5f}, {1e-3f, 3e4f, -7.25f}};
const std::vector<float> kIntensity{10.0f, 255.0f};

const char* const kHeader =
    "ply\n"
    "format binary_little_endian 1.0\n"
    "comment ringtrack\n"
    "element vertex 2\n"
    "property float x\n"
    "property float y\n"
    "property float z\n"
    "property float intensity\n"
    "end_header\n";

float le_float(const std::string& bytes, std::size_t at) {
  std::uint32_t bits = 0;
  for (int k = 3; k >= 0; --k) bits = (bits << 8) | static_cast<unsigned char>(bytes[at + k]);
  float v;
  std::memcpy(&v, &bits, 4);
  return v;
}

TEST(Ply, WritesBinaryLittleEndian) {
  test::TempDir dir;
  write_ply(dir / "map.ply", kPoints, kIntensity);
  const std::string bytes = test::read_text(dir / "map.ply");
  const std::string header = kHeader;
  ASSERT_EQ(bytes.substr(0, header.size()), header);
  ASSERT_EQ(bytes.size(), header.size() + 2 * 16);
  const float expected[] = {1.0f, -2.0f, 0.5f, 10.0f, 1e-3f, 3e4f, -7.25f, 255.0f};
  for (int k = 0; k < 8; ++k) EXPECT_EQ(le_float(bytes, header.size() + 4 * k), expected[k]) << k;
  // Byte order spelled out for one value: 1.0f = 0x3F800000, least significant byte first.
  EXPECT_EQ(bytes.substr(header.size(), 4), std::string("\x00\x00\x80\x3f", 4));
}

TEST(Ply, WritesAscii) {
  const std::string text = encode_ply(kPoints, {}, PlyEncoding::kAscii);
  std::string header = kHeader;
  header.replace(header.find("binary_little_endian"), 20, "ascii");
  EXPECT_EQ(text, header + "1 -2 0.5 0\n0.001 30000 -7.25 0\n");
}

TEST(Ply, EmptyCloudAndErrors) {
  const std::string empty = encode_ply({}, {});
  EXPECT_NE(empty.find("element vertex 0\n"), std::string::npos);
  EXPECT_EQ(empty.substr(empty.size() - 11), "end_header\n");
  EXPECT_THROW(encode_ply(kPoints, std::vector<float>{1.0f}), core::Error);
  if (std::filesystem::exists("/dev/full")) {
    EXPECT_THROW(write_ply("/dev/full", kPoints, kIntensity), core::Error);
  }
}

// Issue 16: the maps stay in the pipeline's local frame (float32) and say where it lies, in a
// header comment that PLY and PCD readers skip.
TEST(Ply, CommentLineStatesTheFrameAndPcdReadersSkipIt) {
  const std::string comment = "origin_m 500000.000 5000000.000 100.000 (world = point + origin)";
  std::string header = kHeader;
  header.insert(header.find("element"), "comment " + comment + "\n");
  EXPECT_EQ(encode_ply(kPoints, kIntensity, PlyEncoding::kBinaryLittleEndian, comment)
                .substr(0, header.size()),
            header);
  EXPECT_THROW(encode_ply(kPoints, kIntensity, PlyEncoding::kAscii, "two\nlines"), core::Error);

  const std::string pcd = encode_pcd_points(kPoints, kIntensity, PcdEncoding::kAscii, comment);
  EXPECT_EQ(pcd.substr(0, pcd.find("VERSION")),
            "# .PCD v0.7 - Point Cloud Data file format\n# " + comment + "\n");
  const auto cloud = decode_pcd_cloud(
      std::span(reinterpret_cast<const std::uint8_t*>(pcd.data()), pcd.size()), "map.pcd");
  ASSERT_EQ(cloud.size(), 2u);
  EXPECT_EQ(cloud.xyz[1], kPoints[1]);
}

}  // namespace
}  // namespace ringtrack::io
