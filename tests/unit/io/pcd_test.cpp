#include "ringtrack/io/pcd.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <numbers>
#include <random>
#include <sstream>

#include "io_test_util.hpp"
#include "ringtrack/core/error.hpp"
#include "ringtrack/core/sensor_model.hpp"
#include "ringtrack/io/lzf.hpp"
#include "ringtrack/sim/simple_scene.hpp"
#include "support/peak_memory.hpp"

namespace ringtrack::io {
namespace {

using test::input_error;
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
std::span<const std::uint8_t> as_bytes(const std::string& s) {
  return {reinterpret_cast<const std::uint8_t*>(s.data()), s.size()};
}

// ---- an independent PCD builder: the oracle for the reader's type and layout handling

struct FieldSpec {
  std::string name;
  char type;
  int size;
  int count;
};

void store(std::string& out, char type, int size, double v) {
  char b[8];
  if (type == 'F' && size == 4) {
    const auto f = static_cast<float>(v);
    std::memcpy(b, &f, 4);
  } else if (type == 'F') {
    std::memcpy(b, &v, 8);
  } else if (type == 'U') {
    const auto u = static_cast<std::uint64_t>(v);
    std::memcpy(b, &u, 8);  // little-endian: the low `size` bytes come first
  } else {
    const auto s = static_cast<std::int64_t>(v);
    std::memcpy(b, &s, 8);
  }
  out.append(b, static_cast<std::size_t>(size));
}

// values[point] lists every element of every field in field order.
std::string build_pcd(const std::vector<FieldSpec>& fields, int width, int height,
                      const std::string& data, const std::vector<std::vector<double>>& values) {
  std::ostringstream h;
  h << "# built by the test\nVERSION 0.7\nFIELDS";
  for (const auto& f : fields) h << ' ' << f.name;
  h << "\nSIZE";
  for (const auto& f : fields) h << ' ' << f.size;
  h << "\nTYPE";
  for (const auto& f : fields) h << ' ' << f.type;
  h << "\nCOUNT";
  for (const auto& f : fields) h << ' ' << f.count;
  h << "\nWIDTH " << width << "\nHEIGHT " << height << "\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS "
    << width * height << "\nDATA " << data << "\n";
  std::string out = h.str();
  if (data == "ascii") {
    std::ostringstream a;
    a.precision(17);
    for (const auto& point : values) {
      for (std::size_t k = 0; k < point.size(); ++k) a << (k ? " " : "") << point[k];
      a << "\n";
    }
    return out + a.str();
  }
  if (data == "binary") {
    for (const auto& point : values) {
      std::size_t k = 0;
      for (const auto& f : fields) {
        for (int c = 0; c < f.count; ++c) store(out, f.type, f.size, point[k++]);
      }
    }
    return out;
  }
  std::string columns;  // binary_compressed: field-major
  std::size_t first = 0;
  for (const auto& f : fields) {
    for (const auto& point : values) {
      for (int c = 0; c < f.count; ++c) store(columns, f.type, f.size, point[first + c]);
    }
    first += static_cast<std::size_t>(f.count);
  }
  const auto packed = lzf_compress(as_bytes(columns));
  const auto compressed = static_cast<std::uint32_t>(packed.size());
  const auto raw = static_cast<std::uint32_t>(columns.size());
  out.append(reinterpret_cast<const char*>(&compressed), 4);
  out.append(reinterpret_cast<const char*>(&raw), 4);
  out.append(reinterpret_cast<const char*>(packed.data()), packed.size());
  return out;
}

// 2 rings x 2 columns with every supported type; extras (ring, t, s, c) must be skipped.
const std::vector<FieldSpec> kAllTypes{
    {"x", 'F', 8, 1},    {"y", 'F', 4, 1},  {"z", 'F', 4, 1},     {"intensity", 'U', 2, 1},
    {"ring", 'U', 1, 1}, {"t", 'I', 4, 2},  {"label", 'U', 4, 1}, {"s", 'I', 2, 1},
    {"c", 'I', 1, 1},    {"big", 'U', 8, 1}};
const std::vector<std::vector<double>> kAllTypesValues{
    {1.0, 0.0, -0.25, 100, 0, -5, 7, 3, -300, -7, 1e12},
    {0.0, 2.0, -0.5, 65535, 0, 1, 2, 0, 300, 7, 0},
    {1.0, 0.0, 0.25, 0, 1, 0, 0, 4294967295.0, 1, -128, 5},
    {NAN, NAN, NAN, 9, 1, 0, 0, 0, 0, 0, 0},
};

void expect_all_types_scan(const PcdScan& p) {
  ASSERT_EQ(p.scan.rings(), 2);
  ASSERT_EQ(p.scan.columns(), 2);
  EXPECT_FALSE(p.rows_flipped);
  EXPECT_EQ(p.scan.valid_count(), 3u);
  EXPECT_EQ(p.scan.point(1), Eigen::Vector3f(0.0f, 2.0f, -0.5f));
  EXPECT_FLOAT_EQ(p.scan.range_m(1), std::sqrt(4.25f));
  EXPECT_EQ(p.scan.intensity(0), 100.0f);
  EXPECT_EQ(p.scan.intensity(1), 65535.0f);
  EXPECT_FALSE(p.scan.valid(3));
  EXPECT_EQ(p.labels, (std::vector<std::uint32_t>{3, 0, 4294967295u, 0}));
}

TEST(Pcd, ReadsEveryTypeInEveryEncoding) {
  for (const char* data : {"ascii", "binary", "binary_compressed"}) {
    SCOPED_TRACE(data);
    const auto bytes = build_pcd(kAllTypes, 2, 2, data, kAllTypesValues);
    expect_all_types_scan(decode_pcd(as_bytes(bytes), "built.pcd"));
  }
}

TEST(Pcd, ReadsHandWrittenAsciiFixture) {
  const auto path = std::filesystem::path(RINGTRACK_SOURCE_DIR) /
                    "tests/unit/io/fixtures/organized_2x3_ascii.pcd";
  const PcdScan p = read_pcd(path);
  ASSERT_EQ(p.scan.rings(), 2);
  ASSERT_EQ(p.scan.columns(), 3);
  EXPECT_FALSE(p.rows_flipped);
  EXPECT_EQ(p.scan.valid_count(), 4u);  // one NaN cell, one all-zero cell
  EXPECT_EQ(p.scan.point(p.scan.index(0, 1)), Eigen::Vector3f(0.0f, 4.0f, -0.6f));
  EXPECT_FLOAT_EQ(p.scan.range_m(p.scan.index(0, 1)), std::sqrt(16.36f));
  EXPECT_EQ(p.scan.intensity(p.scan.index(0, 1)), 20.0f);
  EXPECT_FALSE(p.scan.valid(p.scan.index(0, 2)));
  EXPECT_FALSE(p.scan.valid(p.scan.index(1, 1)));
  EXPECT_EQ(p.scan.point(p.scan.index(1, 2)), Eigen::Vector3f(-2.0f, 0.0f, 0.25f));
  EXPECT_EQ(p.labels, (std::vector<std::uint32_t>{0, 7, 0, 0, 0, 7}));
  // Azimuths from the points: +x, +y, -x.
  EXPECT_NEAR(p.scan.column_azimuth_rad[0], 0.0, 1e-9);
  EXPECT_NEAR(p.scan.column_azimuth_rad[1], std::numbers::pi / 2, 1e-9);
  EXPECT_NEAR(p.scan.column_azimuth_rad[2], std::numbers::pi, 1e-9);
}

TEST(Pcd, RoundTripsAllEncodings) {
  const auto scan = test::make_scan(5, 12);
  const auto labels = test::make_labels(scan.size());
  for (auto encoding :
       {PcdEncoding::kAscii, PcdEncoding::kBinary, PcdEncoding::kBinaryCompressed}) {
    SCOPED_TRACE(std::string(to_string(encoding)));
    const auto bytes = encode_pcd(scan, labels, encoding);
    const PcdScan p = decode_pcd(as_bytes(bytes), "rt.pcd");
    test::expect_same_cells(scan, p.scan);
    EXPECT_EQ(p.labels, labels);
    const PcdScan unlabeled = decode_pcd(as_bytes(encode_pcd(scan, {}, encoding)), "rt.pcd");
    test::expect_same_cells(scan, unlabeled.scan);
    EXPECT_TRUE(unlabeled.labels.empty());
  }
  // Through a file, and the header says what the docs say.
  test::TempDir dir;
  write_pcd(dir / "a.pcd", scan, labels, PcdEncoding::kBinary);
  const std::string text = test::read_text(dir / "a.pcd");
  EXPECT_NE(
      text.find("FIELDS x y z intensity label\nSIZE 4 4 4 4 4\nTYPE F F F F U\nCOUNT 1 1 1 1 1\n"
                "WIDTH 12\nHEIGHT 5\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 60\nDATA binary\n"),
      std::string::npos);
  EXPECT_EQ(text.size(), text.find("DATA binary\n") + 12 + 60 * 20);
  test::expect_same_cells(scan, read_pcd(dir / "a.pcd").scan);
}

TEST(Pcd, CompressedIsSmallerForSparseScans) {
  const auto rendered = sim::render(core::SensorModel::vlp16(), sim::SimpleScene::open_field(10));
  const auto binary = encode_pcd(rendered.scan, rendered.labels, PcdEncoding::kBinary);
  const auto compressed =
      encode_pcd(rendered.scan, rendered.labels, PcdEncoding::kBinaryCompressed);
  EXPECT_LT(compressed.size(), binary.size());
  test::expect_same_cells(rendered.scan, decode_pcd(as_bytes(compressed), "c.pcd").scan);
}

TEST(Pcd, EstimatesColumnAzimuthsFromPoints) {
  const auto model = core::SensorModel::vlp16();
  const auto rendered = sim::render(model, sim::SimpleScene::demo());
  PcdScan p = decode_pcd(as_bytes(encode_pcd(rendered.scan, {}, PcdEncoding::kBinary)), "d.pcd");
  for (int c = 0; c < p.scan.columns(); c += 7) {
    const double d = std::remainder(
        p.scan.column_azimuth_rad[c] - rendered.scan.column_azimuth_rad[c], 2 * std::numbers::pi);
    EXPECT_NEAR(d, 0.0, 1e-5) << "column " << c;
  }
  // Empty columns (a gap of 100 and the wrap-around) are interpolated in uniform steps.
  core::OrganizedScan gappy = rendered.scan;
  for (int c = 0; c < gappy.columns(); ++c) {
    if ((c >= 200 && c < 300) || c < 5 || c >= gappy.columns() - 5) {
      for (int r = 0; r < gappy.rings(); ++r)
        gappy.set_invalid(r, c, core::ReturnStatus::kNoReturn);
    }
  }
  estimate_column_azimuths(gappy);
  for (int c : {0, 3, 200, 250, 299, gappy.columns() - 1}) {
    const double d = std::remainder(
        gappy.column_azimuth_rad[c] - rendered.scan.column_azimuth_rad[c], 2 * std::numbers::pi);
    // 1808 columns of 0.199 deg leave a 1.4-step seam that uniform interpolation smooths over.
    EXPECT_NEAR(d, 0.0, 1e-3) << "column " << c;
  }
  // No points at all: uniform.
  core::OrganizedScan empty(2, 8);
  estimate_column_azimuths(empty);
  EXPECT_NEAR(empty.column_azimuth_rad[2], std::numbers::pi / 2, 1e-12);
}

TEST(Pcd, FlipsTopFirstRows) {
  const auto scan = test::make_scan(4, 6);
  core::OrganizedScan top_first(4, 6);
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 6; ++c) {
      const auto i = scan.index(r, c);
      if (scan.valid(i))
        top_first.set_return(3 - r, c, scan.range_m(i), scan.intensity(i), scan.point(i));
    }
  }
  const auto bytes = encode_pcd(top_first, {}, PcdEncoding::kBinary);
  const PcdScan autod = decode_pcd(as_bytes(bytes), "t.pcd");
  EXPECT_TRUE(autod.rows_flipped);
  test::expect_same_cells(scan, autod.scan);
  PcdReadOptions keep;
  keep.row_order = PcdRowOrder::kBottomFirst;
  const PcdScan kept = decode_pcd(as_bytes(bytes), "t.pcd", keep);
  EXPECT_FALSE(kept.rows_flipped);
  test::expect_same_cells(top_first, kept.scan);
  // And a bottom-first file is left alone under kAuto.
  EXPECT_FALSE(
      decode_pcd(as_bytes(encode_pcd(scan, {}, PcdEncoding::kBinary)), "b.pcd").rows_flipped);
}

TEST(Pcd, OrganizesUnorganizedCloudByRing) {
  const std::vector<FieldSpec> fields{{"x", 'F', 4, 1},
                                      {"y", 'F', 4, 1},
                                      {"z", 'F', 4, 1},
                                      {"intensity", 'F', 4, 1},
                                      {"ring", 'U', 2, 1}};
  const std::vector<std::vector<double>> points{
      {1, 0.1, -0.2, 5, 0},    // ring 0, azimuth ~0.1 rad -> column 0 of 8
      {-0.01, 3, -0.3, 6, 0},  // ring 0, azimuth just past pi/2 -> column 2
      {-2, -0.1, 0.2, 7, 1},   // ring 1, azimuth just past pi -> column 4
      {-4, -0.2, 0.4, 8, 1},   // same cell, farther: dropped
      {NAN, NAN, NAN, 0, 1},   // no return: no cell
  };
  const auto bytes = build_pcd(fields, 5, 1, "binary", points);
  EXPECT_NE(input_error([&] { decode_pcd(as_bytes(bytes), "u.pcd"); }).find("unorganized"),
            std::string::npos);
  PcdReadOptions options;
  options.organize_columns = 8;
  const PcdScan p = decode_pcd(as_bytes(bytes), "u.pcd", options);
  ASSERT_EQ(p.scan.rings(), 2);
  ASSERT_EQ(p.scan.columns(), 8);
  EXPECT_EQ(p.scan.valid_count(), 3u);
  EXPECT_EQ(p.dropped_points, 1u);
  EXPECT_EQ(p.scan.intensity(p.scan.index(0, 0)), 5.0f);
  EXPECT_EQ(p.scan.intensity(p.scan.index(0, 2)), 6.0f);
  EXPECT_EQ(p.scan.intensity(p.scan.index(1, 4)), 7.0f);
  EXPECT_NEAR(p.scan.column_azimuth_rad[2], 2.5 * std::numbers::pi / 4, 1e-12);
  options.ring_field = "laser";
  EXPECT_NE(input_error([&] { decode_pcd(as_bytes(bytes), "u.pcd", options); }).find("'laser'"),
            std::string::npos);
}

TEST(Pcd, OrganizesRealVlp16ReferenceCloud) {
  std::filesystem::path data = std::getenv("RINGTRACK_TEST_DATA") != nullptr
                                   ? std::filesystem::path(std::getenv("RINGTRACK_TEST_DATA"))
                                   : std::filesystem::path(RINGTRACK_SOURCE_DIR) / "../shared/data";
  const auto path = data / "vlp16_indoor_nebula/reference_last_scan.pcd";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "test data not found: " << path;
  EXPECT_NE(input_error([&] { read_pcd(path); }).find("unorganized cloud (HEIGHT 1, WIDTH 14831)"),
            std::string::npos);
  PcdReadOptions options;
  options.organize_columns = 1808;
  options.ring_field = "channel";
  options.row_order = PcdRowOrder::kBottomFirst;
  const PcdScan p = read_pcd(path, options);
  EXPECT_EQ(p.scan.rings(), 16);
  // Every point either has its cell or lost it to a nearer one (dual returns share cells).
  EXPECT_EQ(p.scan.valid_count() + p.dropped_points, 14831u);
  EXPECT_GT(p.scan.valid_count(), 5000u);
}

// ---- bad input: every error names the file and what was expected

const std::string kGoodHeader =
    "VERSION 0.7\nFIELDS x y z intensity\nSIZE 4 4 4 4\nTYPE F F F F\nCOUNT 1 1 1 1\n"
    "WIDTH 2\nHEIGHT 2\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 4\nDATA ascii\n";

std::string error_of(const std::string& bytes) {
  return input_error([&] { decode_pcd(as_bytes(bytes), "bad.pcd"); });
}

TEST(Pcd, RejectsMalformedHeaders) {
  const std::string rows = "1 0 0 1\n0 1 0 1\n1 0 1 1\n0 1 1 1\n";
  ASSERT_NO_THROW(decode_pcd(as_bytes(kGoodHeader + rows), "good.pcd"));
  const auto replaced = [&](const std::string& from, const std::string& to) {
    std::string h = kGoodHeader;
    h.replace(h.find(from), from.size(), to);
    return h + rows;
  };
  std::string e = error_of(replaced("POINTS 4", "POINTS 5"));
  EXPECT_EQ(e.rfind("bad.pcd: ", 0), 0u) << e;
  EXPECT_NE(e.find("POINTS 5 does not equal WIDTH * HEIGHT = 2 * 2"), std::string::npos) << e;
  e = error_of(replaced("TYPE F F F F", "TYPE F F X F"));
  EXPECT_NE(e.find("field 'z': unknown TYPE 'X' (expected F, U or I)"), std::string::npos) << e;
  e = error_of(replaced("SIZE 4 4 4 4", "SIZE 4 4 2 4"));
  EXPECT_NE(e.find("unsupported SIZE '2' for TYPE F"), std::string::npos) << e;
  e = error_of(replaced("FIELDS x y z intensity", "FIELDS a y z intensity"));
  EXPECT_NE(e.find("missing field 'x'"), std::string::npos) << e;
  e = error_of(replaced("SIZE 4 4 4 4", "SIZE 4 4 4"));
  EXPECT_NE(e.find("SIZE lists 3 values for 4 FIELDS"), std::string::npos) << e;
  e = error_of(replaced("DATA ascii", "DATA zip"));
  EXPECT_NE(e.find("unknown DATA 'zip'"), std::string::npos) << e;
  e = error_of(replaced("WIDTH 2", "WIDTH -2"));
  EXPECT_NE(e.find("WIDTH expects an integer"), std::string::npos) << e;
  e = error_of(replaced("VERSION 0.7", "BOGUS 1"));
  EXPECT_NE(e.find("header line 1: unknown header keyword 'BOGUS'"), std::string::npos) << e;
  e = error_of("\x89PNG\r\n\x1a\n binary junk");
  EXPECT_NE(e.find("unknown header keyword"), std::string::npos) << e;
  e = error_of("");
  EXPECT_NE(e.find("no DATA line"), std::string::npos) << e;
  e = error_of(replaced("HEIGHT 2", "HEIGHT 1").replace(kGoodHeader.find("WIDTH 2"), 7, "WIDTH 4"));
  EXPECT_NE(
      e.find(
          "unorganized cloud (HEIGHT 1, WIDTH 4): expected an organized cloud with HEIGHT = rings"),
      std::string::npos)
      << e;
  e = error_of(replaced("FIELDS x y z intensity\nSIZE 4 4 4 4\nTYPE F F F F\nCOUNT 1 1 1 1",
                        "FIELDS x y z label\nSIZE 4 4 4 4\nTYPE F F F F\nCOUNT 1 1 1 1"));
  EXPECT_NE(e.find("'label' has TYPE F"), std::string::npos) << e;
  e = error_of(replaced("COUNT 1 1 1 1", "COUNT 1 2 1 1"));
  EXPECT_NE(e.find("'y' has COUNT 2, expected 1"), std::string::npos) << e;
}

TEST(Pcd, RejectsBadAsciiData) {
  std::string e = error_of(kGoodHeader + "1 0 0 1\n0 1 0 1\n1 0 1 1\n");
  EXPECT_NE(e.find("truncated ascii data: expected 4 point lines"), std::string::npos) << e;
  e = error_of(kGoodHeader + "1 0 0 1\n0 1 0 1\n1 0 1 1\n\n\n\n\n\n\n\n\n\n");
  EXPECT_NE(e.find("truncated ascii data: expected 4 point lines, found 3"), std::string::npos)
      << e;
  e = error_of(kGoodHeader + "1 0 0 1\n0 1 0\n1 0 1 1\n0 1 1 1\n");
  EXPECT_NE(e.find("line 12: expected 4 values, got 3"), std::string::npos) << e;
  e = error_of(kGoodHeader + "1 0 0 1\n0 1 zero 1\n1 0 1 1\n0 1 1 1\n");
  EXPECT_NE(e.find("line 12, field 'z': expected a number, got 'zero'"), std::string::npos) << e;
  e = error_of(kGoodHeader + "1 0 0 1\n0 1 0 1\n1 0 1 1\n0 1 1 1\n1 1 1 1\n");
  EXPECT_NE(e.find("more point lines"), std::string::npos) << e;
}

TEST(Pcd, RejectsNegativeAndFractionalLabels) {
  const std::vector<FieldSpec> fields{
      {"x", 'F', 4, 1}, {"y", 'F', 4, 1}, {"z", 'F', 4, 1}, {"label", 'I', 4, 1}};
  const auto bytes = build_pcd(fields, 1, 2, "binary", {{1, 0, 0, 1}, {1, 0, 1, -3}});
  const std::string e = error_of(bytes);
  EXPECT_NE(e.find("point 1: label value -3.000 is not an integer"), std::string::npos) << e;
}

TEST(Pcd, EveryTruncationIsAnErrorNotACrash) {
  const auto scan = test::make_scan(3, 5);
  const auto labels = test::make_labels(scan.size());
  for (auto encoding :
       {PcdEncoding::kBinary, PcdEncoding::kBinaryCompressed, PcdEncoding::kAscii}) {
    SCOPED_TRACE(std::string(to_string(encoding)));
    const auto bytes = encode_pcd(scan, labels, encoding);
    // A cut inside the last ascii value leaves a shorter, valid number: test cuts before it.
    const std::size_t full = encoding == PcdEncoding::kAscii ? bytes.rfind(' ') + 1 : bytes.size();
    for (std::size_t n = 0; n < full; ++n) {
      EXPECT_THROW(decode_pcd(as_bytes(bytes.substr(0, n)), "cut.pcd"), core::InputError) << n;
    }
  }
  const auto binary = encode_pcd(scan, labels, PcdEncoding::kBinary);
  const std::string e = error_of(binary.substr(0, binary.size() - 7));
  EXPECT_NE(e.find("truncated binary data: expected 15 points of 20 bytes (300 bytes)"),
            std::string::npos)
      << e;
}

TEST(Pcd, RejectsCorruptCompressedData) {
  const auto scan = test::make_scan(3, 5);
  auto bytes = encode_pcd(scan, {}, PcdEncoding::kBinaryCompressed);
  const std::size_t data = bytes.find("DATA binary_compressed\n") + 23;
  // Declared uncompressed size that does not match WIDTH * HEIGHT * record.
  std::string wrong = bytes;
  wrong[data + 4] = static_cast<char>(wrong[data + 4] + 1);
  EXPECT_NE(error_of(wrong).find("uncompressed bytes, expected 15 points x 16 bytes"),
            std::string::npos);
  // Corrupt stream bytes: an error, whichever check catches it first.
  std::mt19937 rng(5);
  for (int trial = 0; trial < 200; ++trial) {
    std::string corrupt = bytes;
    const std::size_t at = data + 8 + rng() % (bytes.size() - data - 8);
    corrupt[at] = static_cast<char>(rng());
    try {
      decode_pcd(as_bytes(corrupt), "corrupt.pcd");  // may decode to other valid floats
    } catch (const core::InputError& e) {
      EXPECT_EQ(std::string(e.what()).rfind("corrupt.pcd: ", 0), 0u) << e.what();
    }
  }
}

TEST(Pcd, RefusesADeclaredSizeNoStreamCanHoldBeforeAllocatingIt) {
  // Issue 16's memory bomb: a 200-byte file whose header (262,500 x 1,000 points of 16 bytes) and
  // size prefix agree on 4.2 GB, followed by a 2-byte stream (at most 176 bytes decoded).
  std::string bytes =
      "VERSION 0.7\nFIELDS x y z intensity\nSIZE 4 4 4 4\nTYPE F F F F\nCOUNT 1 1 1 1\n"
      "WIDTH 262500\nHEIGHT 1000\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 262500000\n"
      "DATA binary_compressed\n";
  const std::uint32_t sizes[2] = {2, 4'200'000'000u};
  bytes.append(reinterpret_cast<const char*>(sizes), sizeof sizes);
  bytes.append("\x00\x00", 2);
  const std::size_t peak_before = ringtrack::test::peak_rss_bytes();
  const std::string e = error_of(bytes);
  EXPECT_NE(e.find("bad.pcd: binary_compressed data declares 4200000000 uncompressed bytes, more "
                   "than 2 compressed bytes can hold (at most 88 times as many)"),
            std::string::npos)
      << e;
  EXPECT_LT(ringtrack::test::peak_rss_bytes() - peak_before, 64u << 20);
  // Genuine data at the limit still reads: an empty scan compresses to almost nothing.
  const core::OrganizedScan empty(16, 1800);
  const std::string compressed = encode_pcd(empty, {}, PcdEncoding::kBinaryCompressed);
  EXPECT_EQ(decode_pcd(as_bytes(compressed), "empty.pcd").scan.columns(), 1800);
}

TEST(Pcd, RandomByteDamageIsAnErrorOrAValidScan) {
  // Damage anywhere (header included) must end in core::InputError or a consistent scan.
  const auto scan = test::make_scan(4, 6);
  const auto labels = test::make_labels(scan.size());
  std::mt19937 rng(11);
  for (auto encoding :
       {PcdEncoding::kAscii, PcdEncoding::kBinary, PcdEncoding::kBinaryCompressed}) {
    const auto bytes = encode_pcd(scan, labels, encoding);
    for (int trial = 0; trial < 500; ++trial) {
      std::string damaged = bytes;
      for (int k = 0; k < 1 + trial % 3; ++k) {
        damaged[rng() % damaged.size()] = static_cast<char>("0123456789 \n.-x\xff"[rng() % 17]);
      }
      try {
        const PcdScan p = decode_pcd(as_bytes(damaged), "d.pcd");
        EXPECT_EQ(p.scan.size(), static_cast<std::size_t>(p.scan.rings()) * p.scan.columns());
        EXPECT_TRUE(p.labels.empty() || p.labels.size() == p.scan.size());
      } catch (const core::InputError& e) {
        EXPECT_EQ(std::string(e.what()).rfind("d.pcd: ", 0), 0u) << e.what();
      }
    }
  }
}

TEST(Pcd, ReadErrorsNameThePath) {
  test::TempDir dir;
  EXPECT_NE(input_error([&] { read_pcd(dir / "missing.pcd"); }).find("missing.pcd: cannot open"),
            std::string::npos);
  test::write_text(dir / "short.pcd", kGoodHeader + "1 0 0 1\n");
  EXPECT_NE(input_error([&] {
              read_pcd(dir / "short.pcd");
            }).find((dir / "short.pcd").string() + ": truncated"),
            std::string::npos);
  EXPECT_NE(input_error([&] { read_pcd(dir.path()); }).find("directory"), std::string::npos);
}

TEST(Pcd, WriteReportsDiskFull) {
  if (!std::filesystem::exists("/dev/full")) GTEST_SKIP() << "/dev/full not available";
  const auto scan = test::make_scan(2, 8);
  try {
    write_pcd("/dev/full", scan, {}, PcdEncoding::kBinary);
    ADD_FAILURE() << "no error";
  } catch (const core::Error& e) {
    EXPECT_NE(std::string(e.what()).find("/dev/full: write failed: No space left on device"),
              std::string::npos)
        << e.what();
  }
  EXPECT_TRUE(std::filesystem::exists("/dev/full"));  // a device is never removed
  test::TempDir dir;
  EXPECT_THROW(write_pcd(dir / "no/such/dir/a.pcd", scan, {}, PcdEncoding::kBinary), core::Error);
  EXPECT_THROW(encode_pcd(scan, std::vector<std::uint32_t>(3), PcdEncoding::kBinary), core::Error);
}

}  // namespace
}  // namespace ringtrack::io
