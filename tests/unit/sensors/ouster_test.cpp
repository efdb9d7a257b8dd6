// Ouster decoder: hand-encoded packets of every profile decoded exactly (tests/support/
// ouster_encoder, from the manual's layouts; XYZ against the manual's formula written out here),
// the real captures of ../shared/data/ouster_sdk decoded to full scans with geometry that must
// hold (a planar ground seen by many rings, destaggered columns of one direction each, the
// OS1-128's consecutive scans agreeing), and hostile input (metadata without a needed key,
// packets of another format than the metadata).
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <numbers>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "ringtrack/core/error.hpp"
#include "ringtrack/io/ouster_pcap_source.hpp"
#include "ringtrack/sensors/ouster/ouster_decoder.hpp"
#include "ringtrack/sensors/ouster/ouster_metadata.hpp"
#include "support/nearest_distances.hpp"
#include "support/ouster_encoder.hpp"

namespace ringtrack::sensors::ouster {
namespace {

namespace fs = std::filesystem;
constexpr double kPi = std::numbers::pi;

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const core::Error& e) {
    return e.what();
  }
  return "no error";
}

test::OusterEcho echo_of(int m, int beam) {
  if ((m + beam) % 9 == 0) return {};
  const auto r = static_cast<std::uint32_t>(1000 + 8 * ((m * 7 + beam * 13) % 5000));
  return {r, r + 800, static_cast<std::uint8_t>((m + beam) % 256)};
}

class OusterRoundTrip : public ::testing::TestWithParam<const char*> {};

TEST_P(OusterRoundTrip, EveryPixelAsEncoded) {
  test::OusterEncoderOptions eo;
  eo.profile = GetParam();
  const OusterMetadata meta = parse_ouster_metadata(test::ouster_metadata_json(eo), "test.json");
  OusterDecoder decoder(meta);
  const std::int64_t t0 = 1'700'000'000'000'000'000;
  for (int k = 0; k < 1024 / eo.columns_per_packet; ++k) {
    const int m = k * eo.columns_per_packet;
    decoder.add_packet(test::encode_ouster_packet(eo, m, t0 + m * 97'656LL, echo_of), 0);
  }
  eo.frame_id = 8;  // the next frame's first packet ends this one
  decoder.add_packet(test::encode_ouster_packet(eo, 0, t0 + 100'000'000, echo_of), 0);
  auto scan = decoder.pop_scan();
  ASSERT_TRUE(scan.has_value());
  EXPECT_EQ(decoder.stats().lost_columns, 0u);
  ASSERT_EQ(scan->rings(), 16);
  ASSERT_EQ(scan->columns(), 1024);
  std::size_t checked = 0;
  for (int m = 0; m < 1024; ++m) {
    for (int b = 0; b < 16; ++b) {
      // Altitudes fall with the beam index: ring 0 (bottom) is beam 15. Destaggered column.
      const int ring = 15 - b;
      const int col = (m + 4 * (b % 4)) % 1024;
      const std::size_t i = scan->index(ring, col);
      const auto e = echo_of(m, b);
      if (e.range_mm == 0) {
        EXPECT_EQ(scan->status(i), core::ReturnStatus::kNoReturn);
        continue;
      }
      ASSERT_TRUE(scan->valid(i)) << m << "," << b;
      EXPECT_FLOAT_EQ(scan->range_m(i), static_cast<float>(e.range_mm * 1e-3));
      EXPECT_EQ(scan->intensity(i), static_cast<float>(e.reflectivity));
      // The manual's formula: encoder angle 2 pi (1 - m / W), beam azimuth subtracted, the beam
      // origin 15 mm out along the encoder direction; then the lidar-to-sensor transform.
      const double enc = 2 * kPi * (1.0 - m / 1024.0);
      const double az = -2 * kPi * (b % 2 == 0 ? 1.5 : -1.5) / 360.0;
      const double alt = 2 * kPi * (15.0 - 2.0 * b) / 360.0;
      const double r = e.range_mm - 15.0;
      const double x = r * std::cos(enc + az) * std::cos(alt) + 15.0 * std::cos(enc);
      const double y = r * std::sin(enc + az) * std::cos(alt) + 15.0 * std::sin(enc);
      const double z = r * std::sin(alt);
      const Eigen::Vector3d want(-x / 1000.0, -y / 1000.0, (z + 36.18) / 1000.0);
      EXPECT_LT((scan->point(i).cast<double>() - want).norm(), 1e-5) << m << "," << b;
      ++checked;
    }
    EXPECT_EQ(scan->column_stamp_ns[static_cast<std::size_t>(m)], t0 + m * 97'656LL);
  }
  EXPECT_GT(checked, 14000u);
}

INSTANTIATE_TEST_SUITE_P(Profiles, OusterRoundTrip,
                         ::testing::Values("LEGACY", "RNG19_RFL8_SIG16_NIR16",
                                           "RNG19_RFL8_SIG16_NIR16_DUAL", "RNG15_RFL8_NIR8"));

TEST(OusterMetadata, MissingOrBadKeysAreOneClearError) {
  test::OusterEncoderOptions eo;
  const std::string json = test::ouster_metadata_json(eo);
  const auto without = [&](const std::string& key) {
    std::string s = json;
    const auto at = s.find("\"" + key + "\"");
    s.replace(at, key.size() + 2, "\"x_" + key + "\"");
    return s;
  };
  EXPECT_EQ(error_of([&] { parse_ouster_metadata(without("beam_altitude_angles"), "os.json"); }),
            "os.json: metadata has no 'beam_altitude_angles'");
  EXPECT_EQ(error_of([&] { parse_ouster_metadata(without("pixel_shift_by_row"), "os.json"); }),
            "os.json: metadata has no 'pixel_shift_by_row'");
  EXPECT_EQ(error_of([&] {
              parse_ouster_metadata(without("lidar_origin_to_beam_origin_mm"), "os.json");
            }),
            "os.json: metadata has no 'lidar_origin_to_beam_origin_mm'");
  EXPECT_EQ(error_of([] {
              parse_ouster_metadata("{nope", "os.json");
            }).rfind("os.json: not valid JSON", 0),
            0u);
  std::string bad_profile = json;
  bad_profile.replace(bad_profile.find("RNG19_RFL8_SIG16_NIR16"), 22, "FUSA_RNG15_RFL8_NIR8_DUAL");
  EXPECT_EQ(error_of([&] { parse_ouster_metadata(bad_profile, "os.json"); }),
            "os.json: udp_profile_lidar 'FUSA_RNG15_RFL8_NIR8_DUAL' is not supported (LEGACY, "
            "RNG19_RFL8_SIG16_NIR16, its _DUAL variant, RNG15_RFL8_NIR8)");
  EXPECT_EQ(error_of([] { read_ouster_metadata("/nonexistent/os.json"); }),
            "/nonexistent/os.json: cannot open the metadata file");
}

TEST(OusterDecoder, PacketsOfAnotherFormatThanTheMetadataAreAnError) {
  test::OusterEncoderOptions eo;
  const OusterMetadata meta = parse_ouster_metadata(test::ouster_metadata_json(eo), "os.json");
  OusterDecoder decoder(meta);
  test::OusterEncoderOptions other = eo;
  other.profile = "RNG15_RFL8_NIR8";
  EXPECT_EQ(
      error_of([&] { decoder.add_packet(test::encode_ouster_packet(other, 0, 0, echo_of), 0); }),
      "ouster packet 1: 1280 bytes, but the metadata (os.json) describes "
      "RNG19_RFL8_SIG16_NIR16 packets of 16 columns x 16 pixels = 3328 bytes (metadata of "
      "another sensor?)");
  // After good packets, a truncated one is counted and skipped.
  OusterDecoder d2(meta);
  d2.add_packet(test::encode_ouster_packet(eo, 0, 0, echo_of), 0);
  auto cut = test::encode_ouster_packet(eo, 16, 0, echo_of);
  cut.resize(cut.size() - 10);
  d2.add_packet(cut, 0);
  EXPECT_EQ(d2.stats().wrong_size, 1u);
  d2.finish();
  EXPECT_FALSE(d2.pop_scan().has_value());  // incomplete frame dropped
  EXPECT_EQ(d2.stats().partial_scans_dropped, 1u);
}

// The _DUAL profile's returns (Ouster's manual: return 1 the strongest, return 2 the second
// strongest). A hand-made frame holds every case: both returns with the second nearer or
// farther, equal ranges, no second return, no return at all, and a second return without a
// first. Each selection must put exactly the expected range and reflectivity in every cell.
test::OusterEcho dual_echo(int m, int beam) {
  const auto r1 = static_cast<std::uint32_t>(2000 + 8 * ((m * 7 + beam * 13) % 3000));
  const auto r2 = static_cast<std::uint32_t>(1000 + 8 * ((m * 11 + beam * 5) % 5000));
  const auto f1 = static_cast<std::uint8_t>(100 + (m + beam) % 100);
  const auto f2 = static_cast<std::uint8_t>((m * 3 + beam) % 100);
  switch ((m + 3 * beam) % 6) {
    case 0:
      return {r1, 0, f1, 0};  // one return only
    case 1:
      return {};  // nothing
    case 2:
      return {r1, r1, f1, f2};  // the same range twice
    case 3:
      return {0, r2, 0, f2};  // a second return without a first (not expected, but possible)
    default:
      return {r1, r2, f1, f2};  // the second nearer or farther
  }
}

// The (range mm, reflectivity) a selection must give for a pixel; range 0 = no return.
std::pair<std::uint32_t, std::uint8_t> expected_return(OusterReturn selection,
                                                       const test::OusterEcho& e) {
  const bool second = selection == OusterReturn::kSecond ||
                      (selection == OusterReturn::kLast && e.range2_mm > e.range_mm);
  return second ? std::pair{e.range2_mm, e.reflectivity2} : std::pair{e.range_mm, e.reflectivity};
}

std::optional<core::OrganizedScan> decode_dual_frame(OusterDecoderOptions options) {
  test::OusterEncoderOptions eo;
  eo.profile = "RNG19_RFL8_SIG16_NIR16_DUAL";
  OusterDecoder decoder(parse_ouster_metadata(test::ouster_metadata_json(eo), "dual.json"),
                        options);
  for (int m = 0; m < 1024; m += eo.columns_per_packet) {
    decoder.add_packet(test::encode_ouster_packet(eo, m, m * 97'656LL, dual_echo), 0);
  }
  decoder.finish();
  return decoder.pop_scan();
}

TEST(OusterDualReturns, EachSelectionPicksTheExpectedReturnPerPixel) {
  const auto by_default = decode_dual_frame({});
  ASSERT_TRUE(by_default.has_value());
  for (const OusterReturn selection :
       {OusterReturn::kStrongest, OusterReturn::kSecond, OusterReturn::kLast}) {
    OusterDecoderOptions o;
    o.return_selection = selection;
    const auto scan = decode_dual_frame(o);
    ASSERT_TRUE(scan.has_value());
    std::map<std::string, int> cases;
    for (int m = 0; m < 1024; ++m) {
      for (int b = 0; b < 16; ++b) {
        const std::size_t i = scan->index(15 - b, (m + 4 * (b % 4)) % 1024);
        const test::OusterEcho e = dual_echo(m, b);
        const auto [range_mm, reflectivity] = expected_return(selection, e);
        const std::string where =
            to_string(selection) + " m " + std::to_string(m) + " beam " + std::to_string(b);
        if (range_mm == 0) {
          ASSERT_EQ(scan->status(i), core::ReturnStatus::kNoReturn) << where;
          ++cases["empty"];
          continue;
        }
        ASSERT_TRUE(scan->valid(i)) << where;
        ASSERT_EQ(scan->range_m(i), static_cast<float>(range_mm) * 1e-3f) << where;
        ASSERT_EQ(scan->intensity(i), static_cast<float>(reflectivity)) << where;
        ++cases[range_mm == e.range_mm ? "return 1" : "return 2"];
      }
    }
    // Every selection meets both kinds of cell; strongest never takes return 2.
    EXPECT_GT(cases["empty"], 1000) << to_string(selection);
    EXPECT_GT(cases["return 1"], selection == OusterReturn::kSecond ? 0 : 5000);
    EXPECT_EQ(cases["return 2"] > 0, selection != OusterReturn::kStrongest);
  }
  // The default is the strongest return, bit for bit as before the selection existed.
  OusterDecoderOptions strongest;
  strongest.return_selection = OusterReturn::kStrongest;
  const auto explicit_strongest = decode_dual_frame(strongest);
  EXPECT_EQ(by_default->statuses(), explicit_strongest->statuses());
  for (std::size_t i = 0; i < by_default->size(); ++i) {
    if (by_default->valid(i)) {
      ASSERT_EQ(by_default->point(i), explicit_strongest->point(i));
    }
  }
}

TEST(OusterDualReturns, ASelectionTheProfileCannotGiveIsOneError) {
  for (const char* profile : {"LEGACY", "RNG19_RFL8_SIG16_NIR16", "RNG15_RFL8_NIR8"}) {
    test::OusterEncoderOptions eo;
    eo.profile = profile;
    const OusterMetadata meta = parse_ouster_metadata(test::ouster_metadata_json(eo), "os.json");
    for (const OusterReturn selection : {OusterReturn::kSecond, OusterReturn::kLast}) {
      OusterDecoderOptions o;
      o.return_selection = selection;
      EXPECT_EQ(error_of([&] { OusterDecoder decoder(meta, o); }),
                "os.json: the " + to_string(selection) +
                    " return needs the RNG19_RFL8_SIG16_NIR16_DUAL profile, but the sensor "
                    "sends " +
                    profile + " (one return per pixel: the strongest)");
    }
    EXPECT_NO_THROW(OusterDecoder(meta, {}));
  }
}

// Newer metadata (firmware 3.x) gives the beam origin as beam_to_lidar_transform (nested in
// beam_intrinsics); its translation replaces lidar_origin_to_beam_origin_mm: the range is measured
// from the beam origin, n = |(x, z)| away, which sits x mm out along the encoder direction and z
// mm up. The points of a decoded frame against that formula written out here.
TEST(OusterMetadata, BeamToLidarTransformGivesTheBeamOrigin) {
  test::OusterEncoderOptions eo;
  std::string json = test::ouster_metadata_json(eo);
  json.insert(json.rfind('}'),
              ", \"beam_intrinsics\": {\"beam_to_lidar_transform\": [1, 0, 0, "
              "27.116, 0, 1, 0, 0, 0, 0, 1, 5.5, 0, 0, 0, 1]}");
  const OusterMetadata meta = parse_ouster_metadata(json, "new.json");
  EXPECT_EQ(meta.beam_x_mm, 27.116);
  EXPECT_EQ(meta.beam_z_mm, 5.5);
  EXPECT_DOUBLE_EQ(meta.origin_to_beam_mm, std::sqrt(27.116 * 27.116 + 5.5 * 5.5));
  OusterDecoder decoder(meta);
  for (int m = 0; m < 1024; m += eo.columns_per_packet) {
    decoder.add_packet(test::encode_ouster_packet(eo, m, m * 97'656LL, echo_of), 0);
  }
  decoder.finish();
  const auto scan = decoder.pop_scan();
  ASSERT_TRUE(scan.has_value());
  const double n = std::sqrt(27.116 * 27.116 + 5.5 * 5.5);
  std::size_t checked = 0;
  for (int m = 0; m < 1024; m += 7) {
    for (int b = 0; b < 16; ++b) {
      const auto e = echo_of(m, b);
      if (e.range_mm == 0) continue;
      const std::size_t i = scan->index(15 - b, (m + 4 * (b % 4)) % 1024);
      ASSERT_TRUE(scan->valid(i));
      const double enc = 2 * kPi * (1.0 - m / 1024.0);
      const double az = -2 * kPi * (b % 2 == 0 ? 1.5 : -1.5) / 360.0;
      const double alt = 2 * kPi * (15.0 - 2.0 * b) / 360.0;
      const double r = e.range_mm - n;
      const double x = r * std::cos(enc + az) * std::cos(alt) + 27.116 * std::cos(enc);
      const double y = r * std::sin(enc + az) * std::cos(alt) + 27.116 * std::sin(enc);
      const double z = r * std::sin(alt) + 5.5;
      const Eigen::Vector3d want(-x / 1000.0, -y / 1000.0, (z + 36.18) / 1000.0);
      EXPECT_LT((scan->point(i).cast<double>() - want).norm(), 1e-5) << m << "," << b;
      EXPECT_LT((decoder.point(b, m, e.range_mm) - want).norm(), 1e-9) << m << "," << b;
      ++checked;
    }
  }
  EXPECT_GT(checked, 2000u);
  // Without the transform: lidar_origin_to_beam_origin_mm, in the plane, as before.
  const OusterMetadata old = parse_ouster_metadata(test::ouster_metadata_json(eo), "old.json");
  EXPECT_EQ(old.origin_to_beam_mm, 15.0);
  EXPECT_EQ(old.beam_x_mm, 15.0);
  EXPECT_EQ(old.beam_z_mm, 0.0);
  json.replace(json.find("27.116"), 6, "\"x\"");
  EXPECT_EQ(error_of([&] { parse_ouster_metadata(json, "new.json"); }),
            "new.json: 'beam_to_lidar_transform' is not an array of numbers");
}

// ---- The fast kernel against the per-pixel reference ----

// The fast kernel (the point from per-beam factors and the column's encoder angle, every cell
// written, no reset of a recycled scan) against the per-pixel reference kernel (set_return and
// the per (measurement id, beam) point table): an OS1-128-sized stream of four frames with a
// lost packet, a repeated one and two swapped ones, scans recycled, a tilted mount, a lifted beam
// origin and pixel shifts outside 0..1023. Statuses, ranges, intensities, azimuths and stamps
// identical; points within 0.1 mm (float sums in another order).
struct KernelCase {
  const char* profile;
  OusterReturn selection;
};

class OusterKernels : public ::testing::TestWithParam<KernelCase> {};

TEST_P(OusterKernels, FastKernelMatchesThePerPixelReference) {
  test::OusterEncoderOptions eo;
  eo.profile = GetParam().profile;
  eo.pixels_per_column = 128;
  std::string json = test::ouster_metadata_json(eo);
  const std::string mount = "[-1, 0, 0, 0, 0, -1, 0, 0, 0, 0, 1, 36.18, 0, 0, 0, 1]";
  ASSERT_NE(json.find(mount), std::string::npos);
  // Rotated 180 deg about z, then tilted by 10 deg about x, and moved.
  const double c = std::cos(10 * kPi / 180);
  const double s = std::sin(10 * kPi / 180);
  json.replace(json.find(mount), mount.size(),
               "[-1, 0, 0, 12.5, 0, " + std::to_string(-c) + ", " + std::to_string(-s) +
                   ", -40, 0, " + std::to_string(-s) + ", " + std::to_string(c) +
                   ", 36.18, 0, 0, 0, 1]");
  const std::string shifts = "\"pixel_shift_by_row\": [0, 4, 8, 12";
  ASSERT_NE(json.find(shifts), std::string::npos);
  json.replace(json.find(shifts), shifts.size(), "\"pixel_shift_by_row\": [-3, 1030, 8, 12");
  json.insert(json.rfind('}'),
              ", \"beam_intrinsics\": {\"beam_to_lidar_transform\": [1, 0, 0, "
              "27.116, 0, 1, 0, 0, 0, 0, 1, 5.5, 0, 0, 0, 1]}");
  const OusterMetadata meta = parse_ouster_metadata(json, "kernels.json");
  const bool rng15 = eo.profile == std::string("RNG15_RFL8_NIR8");
  const auto echo = [rng15](int m, int beam) {
    const auto h = static_cast<std::uint32_t>((m * 2654435761LL + beam * 40503) & 0xFFFFFFFF);
    std::uint32_t r = 0;
    switch (h % 10) {
      case 0:
        break;  // no return
      case 1:
        r = 8 * (h % 37);  // too close (below 0.3 m)
        break;
      case 2:
        r = 250'000 + 8 * ((h >> 8) % 1500);  // too far for some profiles (RNG15 tops at 262 m)
        break;
      default:
        r = 800 + 8 * ((h >> 8) % 30000);
    }
    const std::uint32_t r2 = (h >> 4) % 3 == 0 ? 0 : r + 8 * ((h >> 12) % 500);
    return test::OusterEcho{rng15 ? std::min<std::uint32_t>(r, 32767 * 8) : r, r2,
                            static_cast<std::uint8_t>(h >> 24), static_cast<std::uint8_t>(h >> 16)};
  };
  std::vector<std::vector<std::uint8_t>> packets;
  for (int frame = 0; frame < 4; ++frame) {
    eo.frame_id = frame;
    std::vector<std::vector<std::uint8_t>> frame_packets;
    for (int m = 0; m < 1024; m += eo.columns_per_packet) {
      frame_packets.push_back(test::encode_ouster_packet(
          eo, m, frame * 100'000'000LL + m * 97'656LL, [&](int mm, int b) {
            auto e = echo(mm + 7 * frame, b);  // another scene each frame
            return e;
          }));
    }
    if (frame == 1) frame_packets.erase(frame_packets.begin() + 5);  // lost
    if (frame == 2) {
      frame_packets.insert(frame_packets.begin() + 11, frame_packets[10]);  // repeated
      std::swap(frame_packets[20], frame_packets[21]);                      // out of order
    }
    if (frame == 3) frame_packets.erase(frame_packets.begin());  // lost, first of the frame
    for (auto& p : frame_packets) packets.push_back(std::move(p));
  }
  for (const bool keep_partial : {true, false}) {
    OusterDecoderOptions fast_options;
    fast_options.return_selection = GetParam().selection;
    fast_options.keep_partial_scans = keep_partial;
    OusterDecoderOptions reference_options = fast_options;
    reference_options.reference_kernel = true;
    OusterDecoder fast(meta, fast_options);
    OusterDecoder reference(meta, reference_options);
    std::vector<std::pair<core::OrganizedScan, core::OrganizedScan>> pairs;
    const auto collect = [&] {
      while (true) {
        auto a = fast.pop_scan();
        auto b = reference.pop_scan();
        ASSERT_EQ(a.has_value(), b.has_value());
        if (!a) return;
        pairs.emplace_back(*a, *b);
        fast.recycle(std::move(*a));  // the next frame is written over this one
        reference.recycle(std::move(*b));
      }
    };
    for (const auto& p : packets) {
      fast.add_packet(p, 0);
      reference.add_packet(p, 0);
      collect();
    }
    fast.finish();
    reference.finish();
    collect();
    ASSERT_EQ(pairs.size(), keep_partial ? 4u : 2u);
    EXPECT_EQ(fast.stats().lost_columns, reference.stats().lost_columns);
    double worst_m = 0;
    double worst_exact_m = 0;
    std::size_t valid = 0;
    for (const auto& [a, b] : pairs) {
      ASSERT_EQ(a.size(), b.size());
      EXPECT_EQ(a.stamp_ns, b.stamp_ns);
      EXPECT_EQ(a.column_azimuth_rad, b.column_azimuth_rad);
      EXPECT_EQ(a.column_stamp_ns, b.column_stamp_ns);
      for (std::size_t i = 0; i < a.size(); ++i) {
        ASSERT_EQ(a.status(i), b.status(i)) << i;
        ASSERT_EQ(std::bit_cast<std::uint32_t>(a.range_m(i)),
                  std::bit_cast<std::uint32_t>(b.range_m(i)))
            << i;
        ASSERT_EQ(a.intensity(i), b.intensity(i)) << i;
        if (!a.valid(i)) {
          ASSERT_TRUE(std::isnan(a.xs()[i]) && std::isnan(a.ys()[i]) && std::isnan(a.zs()[i]));
          continue;
        }
        ++valid;
        worst_m = std::max(worst_m, (a.point(i) - b.point(i)).cast<double>().norm());
        // Against the manual's formula in double (OusterDecoder::point) too.
        const int ring = a.ring_of(i);
        const int beam = fast.model().laser_of_ring[static_cast<std::size_t>(ring)];
        const int shift = meta.pixel_shift_by_row[static_cast<std::size_t>(beam)];
        const int m = (((a.column_of(i) - shift) % 1024) + 1024) % 1024;
        const double range_mm = std::round(static_cast<double>(a.range_m(i)) * 1e3);
        const Eigen::Vector3d exact = fast.point(beam, m, range_mm);
        worst_exact_m = std::max(worst_exact_m, (a.point(i).cast<double>() - exact).norm());
      }
    }
    EXPECT_GT(valid, 100'000u);
    EXPECT_LT(worst_m, 1e-4);
    EXPECT_LT(worst_exact_m, 1e-4);
    std::printf(
        "%s %s: %zu valid cells, worst point difference %.1f um (%.1f um from the "
        "formula in double)\n",
        GetParam().profile, to_string(GetParam().selection).c_str(), valid, worst_m * 1e6,
        worst_exact_m * 1e6);
  }
}

INSTANTIATE_TEST_SUITE_P(
    Profiles, OusterKernels,
    ::testing::Values(KernelCase{"LEGACY", OusterReturn::kStrongest},
                      KernelCase{"RNG19_RFL8_SIG16_NIR16", OusterReturn::kStrongest},
                      KernelCase{"RNG19_RFL8_SIG16_NIR16_DUAL", OusterReturn::kStrongest},
                      KernelCase{"RNG19_RFL8_SIG16_NIR16_DUAL", OusterReturn::kSecond},
                      KernelCase{"RNG19_RFL8_SIG16_NIR16_DUAL", OusterReturn::kLast},
                      KernelCase{"RNG15_RFL8_NIR8", OusterReturn::kStrongest}));

// ---- Real captures ----

fs::path data_dir() {
  if (const char* env = std::getenv("RINGTRACK_TEST_DATA")) return fs::path(env) / "ouster_sdk";
  return fs::path(RINGTRACK_SOURCE_DIR) / ".." / "shared" / "data" / "ouster_sdk";
}

struct Capture {
  const char* pcap;
  const char* json;
  int beams;
  std::size_t scans;
};

class OusterCapture : public ::testing::TestWithParam<Capture> {};

// The dominant plane below the sensor (RANSAC, then least squares on its inliers).
struct Plane {
  Eigen::Vector3d normal{0, 0, 1};
  double d{0};  // normal . p + d = 0
  std::size_t inliers{0};
};

Plane ground_plane(const std::vector<Eigen::Vector3d>& pts) {
  Plane best;
  std::uint64_t state = 12345;
  const auto next = [&state](std::size_t n) {
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    return static_cast<std::size_t>((state >> 33) % n);
  };
  for (int it = 0; it < 400 && pts.size() >= 3; ++it) {
    const auto& a = pts[next(pts.size())];
    const auto& b = pts[next(pts.size())];
    const auto& c = pts[next(pts.size())];
    Eigen::Vector3d n = (b - a).cross(c - a);
    if (n.norm() < 1e-6) continue;
    n.normalize();
    if (std::abs(n.z()) < 0.9) continue;  // about horizontal
    const double d = -n.dot(a);
    std::size_t count = 0;
    for (const auto& p : pts) count += std::abs(n.dot(p) + d) < 0.03;
    if (count > best.inliers) best = {n, d, count};
  }
  // Least squares on the inliers: z = a x + b y + c.
  std::vector<Eigen::Vector3d> in;
  for (const auto& p : pts) {
    if (std::abs(best.normal.dot(p) + best.d) < 0.03) in.push_back(p);
  }
  Eigen::MatrixXd A(in.size(), 3);
  Eigen::VectorXd z(in.size());
  for (std::size_t i = 0; i < in.size(); ++i) {
    A.row(static_cast<Eigen::Index>(i)) << in[i].x(), in[i].y(), 1.0;
    z(static_cast<Eigen::Index>(i)) = in[i].z();
  }
  const Eigen::Vector3d s = A.colPivHouseholderQr().solve(z);
  Eigen::Vector3d n(-s.x(), -s.y(), 1.0);
  const double norm = n.norm();
  best.normal = n / norm;
  best.d = -s.z() / norm;
  best.inliers = in.size();
  return best;
}

TEST_P(OusterCapture, FullScansWithConsistentGeometry) {
  const Capture c = GetParam();
  const fs::path pcap = data_dir() / c.pcap;
  const fs::path json = data_dir() / c.json;
  if (!fs::exists(pcap) || !fs::exists(json)) {
    GTEST_SKIP() << "real Ouster test data not found at " << data_dir()
                 << " (set RINGTRACK_TEST_DATA to the folder holding ouster_sdk/)";
  }
  io::OusterPcapSource source(pcap, read_ouster_metadata(json));
  std::vector<core::OrganizedScan> scans;
  while (auto s = source.next()) scans.push_back(std::move(*s));
  ASSERT_EQ(scans.size(), c.scans) << source.summary();
  const auto& stats = source.decoder().stats();
  EXPECT_EQ(stats.lost_columns, 0u);
  EXPECT_EQ(stats.partial_scans_dropped, 0u);
  EXPECT_EQ(stats.wrong_size, 0u);
  EXPECT_EQ(stats.invalid_columns, 0u);
  const core::OrganizedScan& scan = scans.front();
  EXPECT_EQ(scan.columns(), 1024);
  EXPECT_EQ(scan.rings(), c.beams);

  // Destaggered: a column holds one direction. Every valid point lies within a column step of
  // its column's azimuth (staggered, beams would spread over up to 64 columns).
  const double step = 2 * kPi / scan.columns();
  std::vector<double> off;
  std::vector<Eigen::Vector3d> ground;
  std::vector<Eigen::Vector3d> all;
  for (std::size_t i = 0; i < scan.size(); ++i) {
    if (!scan.valid(i)) continue;
    const Eigen::Vector3d p = scan.point(i).cast<double>();
    all.push_back(p);
    const double h = std::hypot(p.x(), p.y());
    if (h > 1.0) {
      const double az = std::atan2(p.y(), p.x());
      off.push_back(std::abs(std::remainder(
          az - scan.column_azimuth_rad[static_cast<std::size_t>(scan.column_of(i))], 2 * kPi)));
    }
    if (h > 1.5 && h < 25.0 && p.z() < -0.3) ground.push_back(p);
  }
  const double off_median = test::quantile(off, 0.5) / step;
  const double off_p95 = test::quantile(off, 0.95) / step;
  // The ground: a plane through many rings, fit within centimetres.
  const Plane g = ground_plane(ground);
  std::vector<double> residual;
  std::map<int, std::pair<double, int>> by_ring;  // mean residual per ring
  for (std::size_t i = 0; i < scan.size(); ++i) {
    if (!scan.valid(i)) continue;
    const Eigen::Vector3d p = scan.point(i).cast<double>();
    const double r = g.normal.dot(p) + g.d;
    if (std::abs(r) >= 0.03 || std::hypot(p.x(), p.y()) < 1.5) continue;
    residual.push_back(std::abs(r));
    auto& [sum, n] = by_ring[scan.ring_of(i)];
    sum += r;
    ++n;
  }
  int rings_on_ground = 0;
  double lo = 1e9;
  double hi = -1e9;
  for (const auto& [ring, sn] : by_ring) {
    if (sn.second < 50) continue;
    ++rings_on_ground;
    lo = std::min(lo, sn.first / sn.second);
    hi = std::max(hi, sn.first / sn.second);
  }
  std::printf(
      "%s: %zu scans, %zu valid points; column offset median %.2f / p95 %.2f steps; "
      "ground %zu points on %d rings, height %.3f m, |residual| median %.1f mm, per-ring "
      "mean spread %.1f mm\n",
      c.pcap, scans.size(), all.size(), off_median, off_p95, g.inliers, rings_on_ground, g.d,
      test::quantile(residual, 0.5) * 1e3, (hi - lo) * 1e3);
  // Thresholds from the captures (docs/ouster.md): staggered, points would lie up to 64
  // columns off; a wrong elevation, beam origin or range scale would tilt or bend the ground
  // ring by ring by far more than the few centimetres that real ground and ranging noise give.
  EXPECT_LT(off_median, 0.75);
  EXPECT_LT(off_p95, 1.0);
  EXPECT_GE(rings_on_ground, c.beams / 8);
  EXPECT_LT(test::quantile(residual, 0.5), 0.02);
  EXPECT_LT(hi - lo, 0.04);
  EXPECT_GT(g.d, 0.2);  // the ground lies below the sensor ...
  EXPECT_LT(g.d, 3.0);  // ... at a mounting height, so the range scale is right

  // Consecutive scans show the same scene: the sensor moves between them (the OS1-128 capture
  // is taken in motion), so each is aligned to the first by a rigid point-to-point ICP on every
  // 8th point; then their points lie on the first scan's, within the beam spacing.
  for (std::size_t k = 1; k < scans.size(); ++k) {
    std::vector<Eigen::Vector3d> other;
    for (std::size_t i = 0; i < scans[k].size(); ++i) {
      if (scans[k].valid(i) && i % 8 == 0) other.push_back(scans[k].point(i).cast<double>());
    }
    const auto before = test::nearest_distances(all, other, 0.5);
    Eigen::Matrix4d pose = Eigen::Matrix4d::Identity();
    for (int it = 0; it < 15; ++it) {
      std::vector<Eigen::Vector3d> moved(other.size());
      for (std::size_t i = 0; i < other.size(); ++i) {
        moved[i] = pose.topLeftCorner<3, 3>() * other[i] + pose.topRightCorner<3, 1>();
      }
      std::vector<std::size_t> nn;
      const auto d = test::nearest_distances(all, moved, 0.5, &nn);
      std::vector<std::size_t> pairs;
      for (std::size_t i = 0; i < d.size(); ++i) {
        if (d[i] < 0.5) pairs.push_back(i);
      }
      Eigen::Matrix3Xd src(3, pairs.size());
      Eigen::Matrix3Xd dst(3, pairs.size());
      for (std::size_t j = 0; j < pairs.size(); ++j) {
        src.col(static_cast<Eigen::Index>(j)) = moved[pairs[j]];
        dst.col(static_cast<Eigen::Index>(j)) = all[nn[pairs[j]]];
      }
      pose = Eigen::umeyama(src, dst, false) * pose;
    }
    std::vector<Eigen::Vector3d> aligned(other.size());
    for (std::size_t i = 0; i < other.size(); ++i) {
      aligned[i] = pose.topLeftCorner<3, 3>() * other[i] + pose.topRightCorner<3, 1>();
    }
    const auto after = test::nearest_distances(all, aligned, 0.5);
    // A moving sensor samples other spots of the scene each scan: the distance to the nearest
    // point of the first scan is bounded by the beam spacing at that range (0.35 deg, 6 mrad,
    // for the OS1-128's 1024 columns and 128 beams over 45 deg), so it is compared per metre of
    // range.
    std::vector<double> relative(after.size());
    for (std::size_t i = 0; i < after.size(); ++i) {
      relative[i] = after[i] / std::max(1.0, other[i].norm());
    }
    std::printf(
        "  scan %zu against scan 0: median %.1f mm before, %.1f mm (p95 %.1f mm) after "
        "aligning by %.3f m; median %.2f mrad of range\n",
        k, test::quantile(before, 0.5) * 1e3, test::quantile(after, 0.5) * 1e3,
        test::quantile(after, 0.95) * 1e3, pose.topRightCorner<3, 1>().norm(),
        test::quantile(relative, 0.5) * 1e3);
    EXPECT_LT(test::quantile(relative, 0.5), 0.006);  // measured: 3.6 and 4.2 mrad
    EXPECT_LT(test::quantile(after, 0.5), 0.1);
  }
}

INSTANTIATE_TEST_SUITE_P(
    RealCaptures, OusterCapture,
    ::testing::Values(
        Capture{"OS-1-32-G_v2.1.1_1024x10.pcap", "OS-1-32-G_v2.1.1_1024x10.json", 32, 1},
        Capture{"OS-2-32-U0_v2.0.0_1024x10.pcap", "OS-2-32-U0_v2.0.0_1024x10.json", 32, 1},
        Capture{"OS-0-32-U1_v2.2.0_1024x10.pcap", "OS-0-32-U1_v2.2.0_1024x10.json", 32, 1},
        Capture{"OS-2-128-U1_v2.3.0_1024x10.pcap", "OS-2-128-U1_v2.3.0_1024x10.json", 128, 1},
        Capture{"OS-0-128-U1_v2.3.0_1024x10.pcap", "OS-0-128-U1_v2.3.0_1024x10.json", 128, 1},
        Capture{"OS-1-128_v2.3.0_1024x10_lb_n3.pcap", "OS-1-128_v2.3.0_1024x10.json", 128, 3}),
    [](const auto& param_info) {
      std::string name = param_info.param.pcap;
      name = name.substr(0, name.find('_'));
      for (char& ch : name) {
        if (ch == '-') ch = '_';
      }
      return name + (param_info.param.scans > 1 ? "_n3" : "");
    });

}  // namespace
}  // namespace ringtrack::sensors::ouster
