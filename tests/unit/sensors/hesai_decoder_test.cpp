// Hesai decoder against packets written by tests/support/hesai_encoder (from the manuals'
// layouts): recognition, round trips for every model in single and dual mode, lost packets,
// and hostile input (truncated packets, bad headers, calibration files with a missing or extra
// channel, a model other than the named one).
#include "ringtrack/sensors/hesai/hesai_decoder.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <set>
#include <string>
#include <vector>

#include "ringtrack/core/error.hpp"
#include "ringtrack/sensors/hesai/hesai_calibration.hpp"
#include "ringtrack/sensors/hesai/hesai_format.hpp"
#include "support/hesai_encoder.hpp"

namespace ringtrack::sensors::hesai {
namespace {

using test::HesaiEcho;
using test::HesaiEncoder;
using test::HesaiEncoderOptions;
constexpr double kDegToRad = std::numbers::pi / 180.0;
const char* const kModels[] = {"Pandar40P", "Pandar64", "PandarQT64", "PandarXT16", "PandarXT32"};

// Echoes as a function of firing and channel: some empty, some too close, the rest spread out.
std::pair<HesaiEcho, HesaiEcho> echo_of(long long firing, int channel) {
  const auto v = static_cast<unsigned>(firing * 7 + channel * 13);
  if (v % 11 == 3) return {{}, {}};
  HesaiEcho last{static_cast<std::uint16_t>(500 + v % 9000), static_cast<std::uint8_t>(v % 200)};
  HesaiEcho second = last;  // the sensor saw one echo: both blocks report it
  if (v % 5 == 1) {         // two echoes: the second block holds a nearer one
    second.distance_raw = static_cast<std::uint16_t>(last.distance_raw - 100);
    second.reflectivity = static_cast<std::uint8_t>((v * 3) % 250);
  }
  if (v % 37 == 5) last.distance_raw = 2;  // 8 mm: too close for every model
  return {last, second};
}

HesaiCalibration calibration_for(int channels, const std::string& name = "test.csv") {
  return parse_hesai_calibration(test::hesai_calibration_csv(channels), name);
}

struct Decoded {
  std::vector<core::OrganizedScan> scans;
  HesaiDecoderStats stats;
  core::SensorModel model;
};

// Packets arrive every packet_ns (the duration of their firings).
Decoded decode(const std::vector<std::vector<std::uint8_t>>& packets, HesaiDecoderOptions options,
               double packet_ns, const std::set<std::size_t>& drop = {}) {
  HesaiDecoder decoder(std::move(options));
  Decoded d;
  for (std::size_t i = 0; i < packets.size(); ++i) {
    const std::int64_t stamp =
        1'700'000'000'000'000'000 + std::llround(static_cast<double>(i + 1) * packet_ns);
    if (drop.count(i) != 0) continue;
    decoder.add_packet(packets[i], stamp);
    while (auto s = decoder.pop_scan()) d.scans.push_back(std::move(*s));
  }
  decoder.finish();
  while (auto s = decoder.pop_scan()) d.scans.push_back(std::move(*s));
  d.stats = decoder.stats();
  d.model = decoder.model();
  return d;
}

TEST(HesaiFormat, RecognisesEveryModelAndNotVelodyne) {
  for (const char* model : kModels) {
    for (const bool seq : {true, false}) {
      HesaiEncoderOptions o;
      o.model = model;
      o.udp_sequence = seq;
      const auto packets = HesaiEncoder(o).encode(0, 1, echo_of);
      const HesaiFormat* f = identify_hesai_packet(packets[0]);
      ASSERT_NE(f, nullptr) << model;
      EXPECT_STREQ(f->name, model);
      HesaiParsedPacket parsed;
      EXPECT_EQ(parse_hesai_packet(packets[0], *f, parsed), HesaiPacketStatus::kOk) << model;
      EXPECT_EQ(parsed.motor_rpm, 600);
      EXPECT_DOUBLE_EQ(parsed.distance_unit_m, 0.004);
    }
  }
  std::vector<std::uint8_t> velodyne(1206, 0);
  velodyne[0] = 0xFF;
  velodyne[1] = 0xEE;
  EXPECT_EQ(identify_hesai_packet(velodyne), nullptr);
  EXPECT_EQ(hesai_format_by_name("xt-32")->channels, 32);
  EXPECT_EQ(hesai_format_by_name("Hesai Pandar40P")->channels, 40);
  EXPECT_EQ(hesai_format_by_name("vlp16"), nullptr);
}

struct RoundTrip {
  const char* model;
  std::uint8_t mode;
  HesaiReturnSelection selection;
};

// The sensor-name table of core (`--sensor`, `ringtrack sensors`) and this format table name
// the same Hesai models; without a nominal table a name given for a cloud says what it needs.
TEST(HesaiFormat, TheSensorNameTableListsEveryFormat) {
  std::vector<std::string> named;
  for (const auto& row : core::built_in_sensors()) {
    if (std::string(row.family) != "Hesai") continue;
    named.emplace_back(row.name);
    EXPECT_EQ(row.make, nullptr);
    ASSERT_NE(hesai_format_by_name(row.name), nullptr) << row.name;
    try {
      (void)core::SensorModel::by_name(row.name);
      ADD_FAILURE() << row.name << " built a model";
    } catch (const core::Error& e) {
      EXPECT_NE(std::string(e.what()).find("--calibration"), std::string::npos) << e.what();
    }
  }
  std::vector<std::string> formats;
  for (const auto& f : hesai_formats()) formats.emplace_back(f.name);
  EXPECT_EQ(named, formats);
}

class HesaiRoundTrip : public ::testing::TestWithParam<RoundTrip> {};

TEST_P(HesaiRoundTrip, EveryCellAndPointAsEncoded) {
  const RoundTrip c = GetParam();
  HesaiEncoderOptions eo;
  eo.model = c.model;
  eo.return_mode = c.mode;
  eo.start_azimuth_deg = 350.0;
  const HesaiEncoder enc(eo);
  const int per_rev = enc.firings_per_revolution();
  const int packets_n = (per_rev * 5 / 2) / enc.firings_per_packet();
  const auto packets = enc.encode(0, packets_n, echo_of);
  HesaiDecoderOptions options;
  options.calibration = calibration_for(enc.channels());
  options.return_selection = c.selection;
  const Decoded d = decode(packets, options, enc.firings_per_packet() * 1e9 / (10.0 * per_rev));
  ASSERT_EQ(d.model.name, c.model);
  EXPECT_EQ(d.stats.skipped_packets(), 0u);
  EXPECT_EQ(d.stats.lost_blocks, 0u);
  ASSERT_EQ(d.scans.size(), 2u);  // partial first (from 350 deg) and last dropped
  EXPECT_EQ(d.stats.partial_scans_dropped, 2u);
  const double step_deg = 360.0 / per_rev;
  const long long first_firing = std::llround(10.0 / step_deg);  // azimuth 0
  for (std::size_t s = 0; s < d.scans.size(); ++s) {
    const auto& scan = d.scans[s];
    ASSERT_EQ(scan.columns(), per_rev);
    ASSERT_EQ(scan.rings(), enc.channels());
    for (int col = 0; col < scan.columns(); ++col) {
      const long long firing = first_firing + static_cast<long long>(s) * per_rev + col;
      const double az_deg = enc.azimuth_of(firing) * 0.01;
      const double col_az = scan.column_azimuth_rad[static_cast<std::size_t>(col)] / kDegToRad;
      EXPECT_NEAR(std::remainder(col_az + az_deg, 360.0), 0.0, 1e-6) << "column " << col;
      if (col > 0) {
        const auto dt = scan.column_stamp_ns[static_cast<std::size_t>(col)] -
                        scan.column_stamp_ns[static_cast<std::size_t>(col - 1)];
        EXPECT_NEAR(static_cast<double>(dt), 1e9 / (10.0 * per_rev), 2.0);
      }
      for (int ch = 0; ch < enc.channels(); ++ch) {
        // Calibration: channel 1 on top (elevation 15 - (ch)); rings bottom up.
        const int ring = enc.channels() - 1 - ch;
        const std::size_t i = scan.index(ring, col);
        const auto [last, second] = echo_of(firing, ch);
        HesaiEcho want = last;
        if (c.mode == 0x39 && c.selection != HesaiReturnSelection::kLast) {
          if (second.distance_raw != 0 &&
              (last.distance_raw == 0 || second.reflectivity >= last.reflectivity)) {
            want = second;
          }
        }
        if (want.distance_raw == 0) {
          EXPECT_EQ(scan.status(i), core::ReturnStatus::kNoReturn);
          continue;
        }
        const double range = want.distance_raw * 0.004;
        if (range < d.model.min_range_m) {
          EXPECT_EQ(scan.status(i), core::ReturnStatus::kTooClose);
          continue;
        }
        ASSERT_TRUE(scan.valid(i)) << ring << "," << col;
        EXPECT_FLOAT_EQ(scan.range_m(i), static_cast<float>(range));
        EXPECT_EQ(scan.intensity(i), want.reflectivity);
        // The naive geometry: azimuth clockwise (block + offset), +x at 0, counter-clockwise y.
        const double el = (15.0 - ch) * kDegToRad;
        const double az = (az_deg + ((ch + 1) % 2 == 0 ? 1.5 : -1.5)) * kDegToRad;
        const Eigen::Vector3d want_xyz(range * std::cos(el) * std::cos(az),
                                       -range * std::cos(el) * std::sin(az), range * std::sin(el));
        EXPECT_LT((scan.point(i).cast<double>() - want_xyz).norm(), 1e-4) << ring << "," << col;
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(
    Models, HesaiRoundTrip,
    ::testing::Values(RoundTrip{"Pandar40P", 0x37, HesaiReturnSelection::kAuto},
                      RoundTrip{"Pandar40P", 0x39, HesaiReturnSelection::kStrongest},
                      RoundTrip{"Pandar64", 0x39, HesaiReturnSelection::kLast},
                      RoundTrip{"Pandar64", 0x38, HesaiReturnSelection::kAuto},
                      RoundTrip{"PandarQT64", 0x39, HesaiReturnSelection::kAuto},
                      RoundTrip{"PandarXT16", 0x37, HesaiReturnSelection::kAuto},
                      RoundTrip{"PandarXT32", 0x39, HesaiReturnSelection::kLast},
                      RoundTrip{"PandarXT32", 0x39, HesaiReturnSelection::kStrongest}),
    [](const auto& param_info) {
      return std::string(param_info.param.model) + "_" + std::to_string(param_info.param.mode) +
             "_" + std::to_string(static_cast<int>(param_info.param.selection));
    });

TEST(HesaiDecoder, FlatPointsSkipIdenticalSecondReturns) {
  HesaiEncoderOptions eo;
  eo.model = "PandarXT32";
  eo.return_mode = 0x39;
  const HesaiEncoder enc(eo);
  const auto packets = enc.encode(0, 1, echo_of);
  HesaiParsedPacket parsed;
  ASSERT_EQ(parse_hesai_packet(packets[0], *hesai_format_by_name("XT32"), parsed),
            HesaiPacketStatus::kOk);
  std::vector<HesaiPoint> points;
  append_hesai_points(parsed, calibration_for(32), points);
  std::size_t expected = 0;
  for (int f = 0; f < 4; ++f) {
    for (int ch = 0; ch < 32; ++ch) {
      const auto [a, b] = echo_of(f, ch);
      expected += a.distance_raw != 0;
      expected += b.distance_raw != 0 && b.distance_raw != a.distance_raw;
    }
  }
  EXPECT_EQ(points.size(), expected);
  for (const auto& p : points) {
    EXPECT_NEAR(p.xyz().norm(), p.distance_m, 1e-9);
  }
}

TEST(HesaiDecoder, LostPacketsLeaveExactlyTheirColumnsInvalid) {
  HesaiEncoderOptions eo;
  eo.model = "PandarXT32";
  eo.start_azimuth_deg = 0.0;
  const HesaiEncoder enc(eo);
  const auto packets = enc.encode(0, 2000 / 8 + 10, [](long long, int) {
    return std::pair{HesaiEcho{2500, 10}, HesaiEcho{}};
  });
  HesaiDecoderOptions options;
  options.calibration = calibration_for(32);
  const Decoded d = decode(packets, options, 400'000.0, {5, 6, 100});
  ASSERT_GE(d.scans.size(), 1u);
  EXPECT_EQ(d.stats.lost_blocks, 3u * 8u);
  const auto& scan = d.scans[0];
  for (int col = 0; col < scan.columns(); ++col) {
    const bool lost = (col >= 40 && col < 56) || (col >= 800 && col < 808);
    EXPECT_EQ(scan.valid(scan.index(0, col)), !lost) << col;
  }
}

TEST(HesaiDecoder, MalformedPacketsAreCountedAndSkipped) {
  HesaiEncoderOptions eo;
  eo.model = "Pandar40P";
  const HesaiEncoder enc(eo);
  auto packets = enc.encode(0, 6, echo_of);
  packets[1].resize(packets[1].size() - 1);    // truncated
  packets[2][124] = 0x00;                      // second block's flag
  packets[3][2] = 0xA0, packets[3][3] = 0x8C;  // azimuth 360.00 deg
  packets[4][1240 + 14] = 0x35;                // unknown return mode
  HesaiDecoderOptions options;
  options.calibration = calibration_for(40);
  options.keep_partial_scans = true;
  const Decoded d = decode(packets, options, 555'556.0);
  EXPECT_EQ(d.stats.wrong_size, 1u);
  EXPECT_EQ(d.stats.bad_header, 1u);
  EXPECT_EQ(d.stats.bad_azimuth, 1u);
  EXPECT_EQ(d.stats.unknown_return_mode, 1u);
  EXPECT_EQ(d.stats.decoded_packets, 2u);
  // Packets of no known format at all.
  HesaiDecoder decoder(options);
  EXPECT_EQ(decoder.add_packet(std::vector<std::uint8_t>(7, 0xEE), 0),
            HesaiPacketStatus::kWrongSize);
  EXPECT_EQ(decoder.add_packet(std::vector<std::uint8_t>{}, 0), HesaiPacketStatus::kWrongSize);
}

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const core::Error& e) {
    return e.what();
  }
  return "no error";
}

TEST(HesaiCalibration, MissingOrExtraChannelIsOneClearError) {
  std::string csv = test::hesai_calibration_csv(32);
  // Missing: drop the row of channel 7.
  const auto at = csv.find("\n7,");
  std::string missing = csv;
  missing.erase(at + 1, missing.find('\n', at + 1) - at);
  EXPECT_EQ(error_of([&] { parse_hesai_calibration(missing, "xt32.csv"); }),
            "xt32.csv: channel 32 but only 31 rows (channels must run 1..31; one missing?)");
  // Extra: a calibration of 33 channels for XT32 packets, found at the first packet.
  HesaiDecoderOptions options;
  options.calibration = parse_hesai_calibration(test::hesai_calibration_csv(33), "big.csv");
  HesaiDecoder decoder(options);
  HesaiEncoderOptions eo;
  const auto packets = HesaiEncoder(eo).encode(0, 1, echo_of);
  EXPECT_EQ(error_of([&] { decoder.add_packet(packets[0], 0); }),
            "hesai packet 1 (PandarXT32): big.csv: 33 channels, but PandarXT32 packets have 32 "
            "(wrong calibration file for this sensor?)");
  // Named model and calibration disagree before any packet.
  options.model = "XT32";
  EXPECT_EQ(error_of([&] { HesaiDecoder named(options); }),
            "big.csv: 33 channels, but PandarXT32 packets have 32 (wrong calibration file for "
            "this sensor?)");
  // Repeated channels, text, out-of-range angles.
  EXPECT_EQ(error_of([] {
              parse_hesai_calibration("Channel,Elevation,Azimuth\n1,2,3\n1,2,3\n", "a.csv");
            }),
            "a.csv:3: channel 1 appears twice");
  EXPECT_EQ(
      error_of([] { parse_hesai_calibration("Channel,Elevation,Azimuth\n1,abc,3\n", "a.csv"); }),
      "a.csv:2: expected 'channel,elevation,azimuth' numbers, got '1,abc,3'");
  EXPECT_EQ(
      error_of([] { parse_hesai_calibration("Channel,Elevation,Azimuth\n1,95,3\n", "a.csv"); }),
      "a.csv:2: angles out of range (elevation within +-90, azimuth within +-180 degrees)");
  EXPECT_EQ(error_of([] { parse_hesai_calibration("", "a.csv"); }),
            "a.csv: no channels (expected CSV rows)");
  EXPECT_EQ(error_of([] { read_hesai_calibration("/nonexistent/x.csv"); }),
            "/nonexistent/x.csv: cannot open the calibration file");
}

TEST(HesaiDecoder, AnotherModelThanTheNamedOneIsAnError) {
  HesaiDecoderOptions options;
  options.model = "PandarXT32";
  options.calibration = calibration_for(32);
  HesaiDecoder decoder(options);
  HesaiEncoderOptions eo;
  eo.model = "PandarXT16";
  const auto packets = HesaiEncoder(eo).encode(0, 1, echo_of);
  EXPECT_EQ(error_of([&] { decoder.add_packet(packets[0], 0); }),
            "hesai packet 1: a PandarXT16 packet, but the stream is PandarXT32 (named)");
  options.model = "PandarXT99";
  EXPECT_EQ(error_of([&] { HesaiDecoder bad(options); }),
            "hesai model 'PandarXT99': expected one of Pandar40P, Pandar64, PandarQT64, "
            "PandarXT16, PandarXT32");
  options.model.clear();
  options.calibration = {};
  EXPECT_EQ(error_of([&] { HesaiDecoder bad(options); }),
            "hesai: the sensor's angle-correction file is required (--calibration FILE)");
}

TEST(HesaiDecoder, AbsentReturnIsAnError) {
  HesaiDecoderOptions options;
  options.calibration = calibration_for(32);
  options.return_selection = HesaiReturnSelection::kLast;
  HesaiDecoder decoder(options);
  HesaiEncoderOptions eo;  // strongest only
  const auto packets = HesaiEncoder(eo).encode(0, 1, echo_of);
  EXPECT_EQ(error_of([&] { decoder.add_packet(packets[0], 0); }),
            "hesai packet 1: the stream carries no last return (return mode 55)");
}

}  // namespace
}  // namespace ringtrack::sensors::hesai

namespace ringtrack::sensors::hesai {
namespace {

TEST(HesaiDecoder, RecycledScansEqualFreshOnes) {
  HesaiEncoderOptions eo;
  eo.model = "PandarXT32";
  eo.return_mode = 0x39;
  eo.start_azimuth_deg = 200.0;
  const HesaiEncoder enc(eo);
  const auto packets = enc.encode(0, 2000, echo_of);  // 4 revolutions
  HesaiDecoderOptions options;
  options.calibration = calibration_for(32);
  HesaiDecoder fresh(options);
  HesaiDecoder recycling(options);
  std::vector<core::OrganizedScan> a;
  std::vector<core::OrganizedScan> b;
  for (std::size_t i = 0; i < packets.size(); ++i) {
    const auto stamp = static_cast<std::int64_t>(i) * 200'000;
    fresh.add_packet(packets[i], stamp);
    recycling.add_packet(packets[i], stamp);
    while (auto s = fresh.pop_scan()) a.push_back(std::move(*s));
    while (auto s = recycling.pop_scan()) {
      b.push_back(*s);  // a copy; the scan itself goes back to the decoder
      recycling.recycle(std::move(*s));
    }
  }
  ASSERT_EQ(a.size(), 3u);
  ASSERT_EQ(b.size(), a.size());
  for (std::size_t k = 0; k < a.size(); ++k) {
    EXPECT_EQ(a[k].column_azimuth_rad, b[k].column_azimuth_rad);
    EXPECT_EQ(a[k].column_stamp_ns, b[k].column_stamp_ns);
    EXPECT_EQ(a[k].stamp_ns, b[k].stamp_ns);
    for (std::size_t i = 0; i < a[k].size(); ++i) {
      ASSERT_EQ(a[k].status(i), b[k].status(i)) << i;
      if (!a[k].valid(i)) continue;
      EXPECT_EQ(a[k].point(i), b[k].point(i));
      EXPECT_EQ(a[k].intensity(i), b[k].intensity(i));
    }
  }
}

}  // namespace
}  // namespace ringtrack::sensors::hesai
