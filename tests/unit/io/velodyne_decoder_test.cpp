// Round trips through the test-support packet encoder: every decoded cell is checked against the
// echo that was encoded for it, and every column against the firing sequence it must hold.
#include "ringtrack/io/velodyne_decoder.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <map>
#include <numbers>
#include <ostream>
#include <set>
#include <utility>
#include <vector>

#include "ringtrack/core/error.hpp"
#include "ringtrack/core/sensor_model.hpp"
#include "ringtrack/io/velodyne_packet.hpp"
#include "support/velodyne_encoder.hpp"

namespace ringtrack::io {
namespace {

using test::VelodyneEcho;
using test::VelodyneEchoPair;
using test::VelodyneEncoder;
using test::VelodyneEncoderOptions;

constexpr double kDegToRad = std::numbers::pi / 180.0;
// Whole hours since the epoch, so that sensor time stamps (us past the hour) line up with it.
constexpr std::int64_t kEpochNs = 1'699'999'200LL * 1'000'000'000LL;

std::uint32_t mix(std::uint64_t x) {
  x ^= x >> 33;
  x *= 0xff51afd7ed558ccdULL;
  x ^= x >> 33;
  x *= 0xc4ceb9fe1a85ec53ULL;
  x ^= x >> 33;
  return static_cast<std::uint32_t>(x);
}

// What the sensor saw for one laser in one sequence: up to two echoes.
struct Truth {
  VelodyneEcho last;         // farthest echo (zero distance: nothing seen)
  VelodyneEcho strongest;    // highest reflectivity echo
  VelodyneEcho pair_second;  // what the dual packet's second block reports
};

// Deterministic scene: about 1/9 of the cells see nothing, 1/5 see two echoes, some are too
// close; the rest see one echo.
Truth truth(long long sequence, int laser) {
  const std::uint32_t h =
      mix(static_cast<std::uint64_t>(sequence) * 64 + static_cast<std::uint64_t>(laser));
  Truth t;
  if (h % 9 == 0) return t;
  const auto near_raw = static_cast<std::uint16_t>(h % 11 == 1 ? 100 : 500 + (h >> 8) % 20000);
  const auto near_refl = static_cast<std::uint8_t>((h >> 4) % 256);
  if (h % 5 != 0) {  // one echo: the dual packet reports it twice
    t.last = t.strongest = t.pair_second = VelodyneEcho{near_raw, near_refl};
    return t;
  }
  const VelodyneEcho near{near_raw, near_refl};
  const VelodyneEcho far{static_cast<std::uint16_t>(near_raw + 50 + (h >> 20) % 1000),
                         static_cast<std::uint8_t>((h >> 12) % 256)};
  t.last = far;
  if (far.reflectivity > near.reflectivity) {
    // The last echo is also the strongest: the second block holds the second strongest.
    t.strongest = far;
    t.pair_second = near;
  } else {
    t.strongest = near;
    t.pair_second = near;
  }
  return t;
}

VelodyneEchoPair encode_echo(long long sequence, int laser, std::uint8_t return_mode) {
  const Truth t = truth(sequence, laser);
  switch (return_mode) {
    case 0x38:
      return {t.last, {}};
    case 0x39:
      return {t.last, t.pair_second};
    default:
      return {t.strongest, {}};
  }
}

struct Decoded {
  std::vector<core::OrganizedScan> scans;
  VelodyneDecoderStats stats;
  core::SensorModel model;
};

Decoded decode(const std::vector<test::EncodedVelodynePacket>& packets,
               const VelodyneDecoderOptions& options) {
  VelodyneDecoder decoder(options);
  Decoded out;
  for (const auto& p : packets) {
    decoder.add_packet(p.payload, p.host_stamp_ns);
    while (auto scan = decoder.pop_scan()) out.scans.push_back(std::move(*scan));
  }
  decoder.finish();
  while (auto scan = decoder.pop_scan()) out.scans.push_back(std::move(*scan));
  out.stats = decoder.stats();
  out.model = decoder.model();
  return out;
}

double wrap360(double a) {
  a = std::fmod(a, 360.0);
  return a < 0 ? a + 360.0 : a;
}

double angle_diff_deg(double a, double b) {
  return std::abs(std::remainder(a - b, 360.0));
}

struct Case {
  std::uint8_t product;
  std::uint8_t return_mode;
  VelodyneReturnSelection selection;
  double start_azimuth_deg;
  double cut_deg;
  double rpm;
};

void PrintTo(const Case& c, std::ostream* os) {
  *os << velodyne_product_name(c.product) << " mode " << int{c.return_mode} << " selection "
      << int(c.selection) << " start " << c.start_azimuth_deg << " cut " << c.cut_deg << " rpm "
      << c.rpm;
}

// Checks every column and cell of every scan against the encoder. Returns the set of firing
// sequences found in the scans.
std::set<long long> check_scans(const Decoded& d, const VelodyneEncoder& enc, const Case& c,
                                const std::set<long long>& dropped, long long encoded) {
  const core::SensorModel& m = d.model;
  const double step_deg = 360.0 / m.columns();
  const double adv = enc.advance_deg();
  std::set<long long> seen;
  for (const auto& scan : d.scans) {
    EXPECT_EQ(scan.rings(), m.rings());
    EXPECT_EQ(scan.columns(), m.columns());
    long long first_seq = -1;
    int first_col = -1;
    double first_rel = 0;
    for (int col = 0; col < scan.columns(); ++col) {
      const auto cc = static_cast<std::size_t>(col);
      // Host time stamps: the encoder's host clock runs with the sensor clock.
      const double t_us =
          static_cast<double>(scan.column_stamp_ns[cc] - enc.options().host_epoch_ns) / 1e3;
      const long long k = std::llround((t_us - enc.options().start_time_us) / enc.sequence_us());
      EXPECT_NEAR(t_us, enc.sequence_time_us(k), 0.01) << "column " << col;
      if (first_seq < 0) {
        first_seq = k;
        first_col = col;
        first_rel = wrap360(enc.sequence_azimuth_deg(k) - c.cut_deg);
        if (first_rel > 180.0) first_rel -= 360.0;
      }
      // Columns count firing sequences: never shifted by lost packets.
      EXPECT_EQ(k - first_seq, col - first_col) << "column " << col;
      const double exact_az = enc.sequence_azimuth_deg(k);
      // A sequence past the cut belongs to the next scan; within the azimuth quantization of
      // the cut either scan may hold it.
      const double turned = first_rel + static_cast<double>(k - first_seq) * adv;
      if (std::abs(turned - 360.0) < 0.011) continue;
      const bool received = k >= 0 && k < encoded && dropped.count(k) == 0 && turned < 360.0;
      // Columns without data continue the azimuth with the measured advance per sequence.
      EXPECT_LT(angle_diff_deg(-scan.column_azimuth_rad[cc] / kDegToRad, exact_az),
                received ? 0.011 : 0.5)
          << "column " << col;
      if (received) seen.insert(k);
      for (int ring = 0; ring < m.rings(); ++ring) {
        const int laser = m.laser_of_ring[static_cast<std::size_t>(ring)];
        const std::size_t i = scan.index(ring, col);
        const Truth t = truth(k, laser);
        VelodyneEcho want = t.strongest;
        if (c.return_mode == 0x38 ||
            (c.return_mode == 0x39 && c.selection == VelodyneReturnSelection::kLast)) {
          want = t.last;
        }
        if (!received || want.distance_raw == 0) {
          EXPECT_EQ(scan.status(i), core::ReturnStatus::kNoReturn) << ring << "," << col;
          continue;
        }
        // Manuals: the VLP-32C counts distance in 4 mm units, the VLP-16 and HDL-32E in 2 mm.
        const double range = want.distance_raw * (m.name == "VLP-32C" ? 0.004 : 0.002);
        if (range < m.min_range_m) {
          EXPECT_EQ(scan.status(i), core::ReturnStatus::kTooClose) << ring << "," << col;
          continue;
        }
        if (!scan.valid(i)) {
          ADD_FAILURE() << "expected a valid return at " << ring << "," << col;
          continue;
        }
        EXPECT_FLOAT_EQ(scan.range_m(i), static_cast<float>(range));
        EXPECT_EQ(scan.intensity(i), want.reflectivity);
        // The naive geometry: the model's point at this laser's exact firing azimuth.
        const double firing_az = exact_az + adv *
                                                m.firing_offset_us[static_cast<std::size_t>(ring)] /
                                                m.firing_sequence_us;
        const Eigen::Vector3f p =
            m.point(ring, velodyne_to_ringtrack_azimuth_rad(firing_az), range);
        const double tol = 1e-4 + range * 0.012 * kDegToRad;  // 0.01 deg azimuth quantization
        EXPECT_NEAR(scan.point(i).x(), p.x(), tol) << ring << "," << col;
        EXPECT_NEAR(scan.point(i).y(), p.y(), tol) << ring << "," << col;
        EXPECT_NEAR(scan.point(i).z(), p.z(), 1e-4) << ring << "," << col;
      }
    }
    // The scan starts at the first sequence past the cut.
    if (first_col == 0) {
      EXPECT_GT(first_rel, -0.011);
      EXPECT_LT(first_rel, adv + 0.011);
    }
    EXPECT_EQ(scan.stamp_ns, scan.column_stamp_ns[0]);
    (void)step_deg;
  }
  return seen;
}

std::vector<test::EncodedVelodynePacket> encode_revolutions(const VelodyneEncoder& enc,
                                                            double revolutions) {
  const double packets_per_rev = 360.0 / (enc.advance_deg() * enc.sequences_per_packet());
  const auto n = static_cast<long long>(std::ceil(revolutions * packets_per_rev));
  return enc.encode(
      0, n, [&](long long s, int l) { return encode_echo(s, l, enc.options().return_mode); });
}

class VelodyneRoundTrip : public ::testing::TestWithParam<Case> {};

TEST_P(VelodyneRoundTrip, EveryCellMatchesTheEncodedEcho) {
  const Case c = GetParam();
  VelodyneEncoderOptions eo;
  eo.product = c.product;
  eo.return_mode = c.return_mode;
  eo.rpm = c.rpm;
  eo.start_azimuth_deg = c.start_azimuth_deg;
  eo.start_time_us = 1.5e9;
  eo.host_epoch_ns = kEpochNs;
  const VelodyneEncoder enc(eo);
  const auto packets = encode_revolutions(enc, 4.2);

  VelodyneDecoderOptions options;
  options.return_selection = c.selection;
  options.cut_azimuth_deg = c.cut_deg;
  options.scan_rate_hz = c.rpm / 60.0;
  const Decoded d = decode(packets, options);
  ASSERT_EQ(d.model.name, velodyne_product_name(c.product));
  // A partial first scan and a partial last one (both dropped), full ones between: one fewer
  // than the cut crossings of the encoded azimuths.
  const long long encoded = static_cast<long long>(packets.size()) * enc.sequences_per_packet();
  std::size_t crossings = 0;
  for (long long k = 1; k < encoded; ++k) {
    crossings += wrap360(enc.sequence_azimuth_deg(k) - c.cut_deg) <
                 wrap360(enc.sequence_azimuth_deg(k - 1) - c.cut_deg);
  }
  ASSERT_GE(crossings, 3u);
  ASSERT_EQ(d.scans.size(), crossings - 1) << "partial dropped " << d.stats.partial_scans_dropped;
  EXPECT_EQ(d.stats.partial_scans_dropped, 2u);
  EXPECT_EQ(d.stats.lost_sequences, 0u);
  EXPECT_EQ(d.stats.clock_mismatches, 0u);
  EXPECT_EQ(d.stats.skipped_packets(), 0u);
  const auto seen = check_scans(d, enc, c, {}, encoded);
  // Full revolutions: every column filled except at most one past the end (1808.4 sequences
  // per revolution at 600 rpm do not fill a whole number of columns).
  for (const auto& scan : d.scans) {
    int filled = 0;
    for (int col = 0; col < scan.columns(); ++col) {
      for (int r = 0; r < scan.rings(); ++r) {
        if (scan.status(scan.index(r, col)) != core::ReturnStatus::kNoReturn) {
          ++filled;
          break;
        }
      }
    }
    EXPECT_GE(filled, scan.columns() - 2);
  }
  EXPECT_LE(d.stats.invalid_columns, 3u);
  EXPECT_LE(d.stats.overflow_sequences, 3u);
  // Consecutive scans hold consecutive sequences (nothing lost at the seams but overflow).
  EXPECT_LE(static_cast<std::size_t>(*seen.rbegin() - *seen.begin() + 1) - seen.size(),
            d.stats.overflow_sequences);
}

INSTANTIATE_TEST_SUITE_P(
    Models, VelodyneRoundTrip,
    ::testing::Values(Case{0x22, 0x37, VelodyneReturnSelection::kAuto, 300.0, 0.0, 600.0},
                      Case{0x22, 0x38, VelodyneReturnSelection::kLast, 10.0, 90.0, 600.0},
                      Case{0x22, 0x39, VelodyneReturnSelection::kStrongest, 200.0, 0.0, 600.0},
                      Case{0x22, 0x39, VelodyneReturnSelection::kLast, 200.0, 359.9, 600.0},
                      Case{0x22, 0x37, VelodyneReturnSelection::kAuto, 100.0, 45.0, 1200.0},
                      Case{0x22, 0x37, VelodyneReturnSelection::kAuto, 100.0, 45.0, 300.0},
                      Case{0x28, 0x37, VelodyneReturnSelection::kStrongest, 300.0, 0.0, 600.0},
                      Case{0x28, 0x39, VelodyneReturnSelection::kLast, 123.4, 180.0, 600.0},
                      Case{0x28, 0x39, VelodyneReturnSelection::kAuto, 123.4, 180.0, 600.0},
                      Case{0x21, 0x37, VelodyneReturnSelection::kAuto, 50.0, 0.0, 600.0}));

TEST(VelodyneDecoder, LostPacketsGiveInvalidColumnsNotShiftedOnes) {
  VelodyneEncoderOptions eo;
  eo.start_azimuth_deg = 350.0;
  eo.start_time_us = 7e8;
  eo.host_epoch_ns = kEpochNs;
  const VelodyneEncoder enc(eo);
  auto packets = encode_revolutions(enc, 2.9);
  // Drop single packets, a run of five, and the packets around the second cut.
  std::set<std::size_t> drop{20, 21 + 10, 40, 41, 42, 43, 44, 300};
  const double packets_per_rev = 360.0 / (enc.advance_deg() * enc.sequences_per_packet());
  const auto seam =
      static_cast<std::size_t>(std::lround(10.0 / 360.0 * packets_per_rev + packets_per_rev));
  drop.insert(seam);
  drop.insert(seam + 1);
  std::vector<test::EncodedVelodynePacket> kept;
  std::set<long long> dropped_sequences;
  for (std::size_t i = 0; i < packets.size(); ++i) {
    if (drop.count(i) != 0) {
      for (int s = 0; s < enc.sequences_per_packet(); ++s) {
        dropped_sequences.insert(packets[i].first_sequence + s);
      }
    } else {
      kept.push_back(packets[i]);
    }
  }
  VelodyneDecoderOptions options;
  options.keep_partial_scans = true;
  const Decoded d = decode(kept, options);
  ASSERT_EQ(d.scans.size(), 4u);  // 350..360, two revolutions, the rest
  EXPECT_EQ(d.stats.lost_sequences, dropped_sequences.size());
  EXPECT_EQ(d.stats.clock_mismatches, 0u);
  const Case c{0x22, 0x37, VelodyneReturnSelection::kAuto, 350.0, 0.0, 600.0};
  check_scans(d, enc, c, dropped_sequences,
              static_cast<long long>(packets.size()) * enc.sequences_per_packet());
  EXPECT_GE(d.stats.invalid_columns, dropped_sequences.size());
}

TEST(VelodyneDecoder, LostPacketsAreFoundFromTheAzimuthWithoutAClock) {
  // Time stamps frozen at zero: the gap size must come from the azimuth advance.
  VelodyneEncoderOptions eo;
  eo.start_azimuth_deg = 10.0;
  const VelodyneEncoder enc(eo);
  auto packets = encode_revolutions(enc, 1.5);
  std::vector<test::EncodedVelodynePacket> kept;
  std::size_t lost = 0;
  for (std::size_t i = 0; i < packets.size(); ++i) {
    for (int b = 0; b < 4; ++b) packets[i].payload[1200 + static_cast<std::size_t>(b)] = 0;
    if (i == 50 || i == 51 || i == 52) {
      lost += static_cast<std::size_t>(enc.sequences_per_packet());
      continue;
    }
    kept.push_back(packets[i]);
  }
  VelodyneDecoderOptions options;
  options.keep_partial_scans = true;
  VelodyneDecoder decoder(options);
  for (const auto& p : kept) decoder.add_packet(p.payload, p.host_stamp_ns);
  decoder.finish();
  EXPECT_EQ(decoder.stats().lost_sequences, lost);
  EXPECT_GT(decoder.stats().clock_mismatches, 0u);
  const auto scan = decoder.pop_scan();
  ASSERT_TRUE(scan.has_value());
  // Sequence 51 * 24 sits 51 * 24 columns after sequence 0's column (10 deg past the cut).
  const int col0 = static_cast<int>(std::floor(10.0 / (360.0 / 1808)));
  for (int k : {50 * 24, 53 * 24}) {
    const int col = col0 + k;
    bool any_valid = false;
    for (int r = 0; r < scan->rings(); ++r) any_valid |= scan->valid(scan->index(r, col));
    EXPECT_EQ(any_valid, k == 53 * 24) << "column " << col;
    EXPECT_NEAR(-scan->column_azimuth_rad[static_cast<std::size_t>(col)] / kDegToRad + 360.0,
                enc.sequence_azimuth_deg(k), 0.02);
  }
}

TEST(VelodyneDecoder, PausedRecordingEndsTheScan) {
  VelodyneEncoderOptions eo;
  eo.start_azimuth_deg = 0.05;
  eo.host_epoch_ns = kEpochNs;
  const VelodyneEncoder enc(eo);
  auto packets = encode_revolutions(enc, 1.5);
  // After 40 packets (191 deg) the capture pauses for 5 s (sensor and host clocks) and goes on
  // where the sensor happens to be then: packet 70, 334 deg, shortly before the cut.
  std::vector<test::EncodedVelodynePacket> stream(packets.begin(), packets.begin() + 40);
  for (std::size_t i = 70; i < packets.size(); ++i) {
    auto p = packets[i];
    std::uint32_t t = 0;
    for (std::size_t b = 0; b < 4; ++b)
      t |= static_cast<std::uint32_t>(p.payload[1200 + b]) << (8 * b);
    t += 5'000'000;
    for (std::size_t b = 0; b < 4; ++b)
      p.payload[1200 + b] = static_cast<std::uint8_t>(t >> (8 * b));
    p.host_stamp_ns += 5'000'000'000;
    stream.push_back(p);
  }
  const Decoded d = decode(stream, {});
  EXPECT_EQ(d.stats.stream_breaks, 1u);
  EXPECT_EQ(d.stats.lost_sequences, 0u);
  // Scan 0 runs from the cut to the pause, the rest of its columns invalid; scan 1 holds the
  // 334..360 deg after the pause, its leading columns invalid (not shifted to the front); the
  // partial revolution after the next cut is dropped.
  ASSERT_EQ(d.scans.size(), 2u);
  const int columns = d.scans[0].columns();
  const int resume_column =
      static_cast<int>(std::floor(enc.sequence_azimuth_deg(70 * 24) / (360.0 / columns)));
  const auto has_data = [](const core::OrganizedScan& scan, int col) {
    for (int r = 0; r < scan.rings(); ++r) {
      if (scan.status(scan.index(r, col)) != core::ReturnStatus::kNoReturn) return true;
    }
    return false;
  };
  EXPECT_TRUE(has_data(d.scans[0], 40 * 24 - 1));
  EXPECT_FALSE(has_data(d.scans[0], 40 * 24));
  EXPECT_FALSE(has_data(d.scans[1], resume_column - 1));
  EXPECT_TRUE(has_data(d.scans[1], resume_column));
  EXPECT_NEAR(static_cast<double>(d.stats.invalid_columns), (columns - 40 * 24) + resume_column,
              2.0);
  EXPECT_GT(d.scans[1].column_stamp_ns[static_cast<std::size_t>(resume_column)] -
                d.scans[0].column_stamp_ns.front(),
            5'000'000'000);
}

TEST(VelodyneDecoder, SensorTimeSourceFollowsTheHourAcrossItsWrap) {
  VelodyneEncoderOptions eo;
  eo.start_time_us = 3600e6 - 0.15e6;  // the sensor clock wraps 150 ms into the stream
  eo.host_epoch_ns = kEpochNs;
  const VelodyneEncoder enc(eo);
  const auto packets = encode_revolutions(enc, 3.2);
  VelodyneDecoderOptions host_opts;
  VelodyneDecoderOptions sensor_opts;
  sensor_opts.time_source = VelodyneTimeSource::kSensor;
  const Decoded host = decode(packets, host_opts);
  const Decoded sensor = decode(packets, sensor_opts);
  ASSERT_EQ(host.scans.size(), 3u);
  ASSERT_EQ(sensor.scans.size(), 3u);
  EXPECT_EQ(sensor.stats.lost_sequences, 0u);
  for (std::size_t s = 0; s < host.scans.size(); ++s) {
    for (std::size_t c = 0; c < host.scans[s].column_stamp_ns.size(); ++c) {
      ASSERT_NEAR(static_cast<double>(host.scans[s].column_stamp_ns[c]),
                  static_cast<double>(sensor.scans[s].column_stamp_ns[c]), 1000.0);
    }
  }
}

TEST(VelodyneDecoder, ModelFromProductByteOrNamed) {
  VelodyneEncoderOptions eo;
  eo.product = 0x22;
  const auto packets =
      VelodyneEncoder(eo).encode(0, 2, [](long long, int) { return VelodyneEchoPair{}; });
  {
    VelodyneDecoder decoder;
    EXPECT_FALSE(decoder.has_model());
    EXPECT_THROW((void)decoder.model(), core::Error);
    decoder.add_packet(packets[0].payload, 0);
    EXPECT_EQ(decoder.model().name, "VLP-16");
  }
  {
    VelodyneDecoderOptions o;
    o.model = "vlp32c";
    VelodyneDecoder decoder(o);
    try {
      decoder.add_packet(packets[0].payload, 0);
      FAIL() << "expected a contradiction error";
    } catch (const core::InputError& e) {
      EXPECT_NE(std::string(e.what()).find("contradicts the named model VLP-32C"),
                std::string::npos)
          << e.what();
    }
  }
  auto zero = packets[0].payload;
  zero[1204] = 0;
  zero[1205] = 0;
  EXPECT_THROW(VelodyneDecoder().add_packet(zero, 0), core::InputError);
  VelodyneDecoderOptions named;
  named.model = "VLP-16";
  VelodyneDecoder decoder(named);
  EXPECT_EQ(decoder.add_packet(zero, 0), VelodynePacketStatus::kOk);
  auto hi_res = packets[0].payload;
  hi_res[1205] = 0x24;  // Puck Hi-Res: not supported
  EXPECT_THROW(VelodyneDecoder().add_packet(hi_res, 0), core::InputError);
  VelodyneDecoderOptions bad;
  bad.model = "os1";
  EXPECT_THROW(VelodyneDecoder{bad}, core::ConfigError);
  bad = {};
  bad.cut_azimuth_deg = 360.0;
  EXPECT_THROW(VelodyneDecoder{bad}, core::ConfigError);
  EXPECT_THROW(parse_velodyne_return_selection("first"), core::ConfigError);
  EXPECT_EQ(parse_velodyne_return_selection("last"), VelodyneReturnSelection::kLast);
}

TEST(VelodyneDecoder, RequestedReturnMustBeInTheStream) {
  VelodyneEncoderOptions eo;
  eo.return_mode = 0x37;
  const auto strongest =
      VelodyneEncoder(eo).encode(0, 1, [](long long, int) { return VelodyneEchoPair{}; });
  eo.return_mode = 0x38;
  const auto last =
      VelodyneEncoder(eo).encode(0, 1, [](long long, int) { return VelodyneEchoPair{}; });
  VelodyneDecoderOptions want_last;
  want_last.return_selection = VelodyneReturnSelection::kLast;
  EXPECT_THROW(VelodyneDecoder(want_last).add_packet(strongest[0].payload, 0), core::InputError);
  EXPECT_EQ(VelodyneDecoder(want_last).add_packet(last[0].payload, 0), VelodynePacketStatus::kOk);
  VelodyneDecoderOptions want_strongest;
  want_strongest.return_selection = VelodyneReturnSelection::kStrongest;
  EXPECT_THROW(VelodyneDecoder(want_strongest).add_packet(last[0].payload, 0), core::InputError);
}

TEST(VelodyneDecoder, SpinRateFarFromTheScanRateIsAnError) {
  VelodyneEncoderOptions eo;
  eo.rpm = 900.0;
  const VelodyneEncoder enc(eo);
  const auto packets = encode_revolutions(enc, 1.0);
  VelodyneDecoder decoder;  // 10 Hz = 600 rpm
  try {
    for (const auto& p : packets) decoder.add_packet(p.payload, p.host_stamp_ns);
    FAIL() << "expected a spin-rate error";
  } catch (const core::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("spins at about 900 rpm"), std::string::npos) << e.what();
  }
}

TEST(VelodyneDecoder, MalformedPacketsAreCountedAndSkipped) {
  VelodyneEncoderOptions eo;
  eo.start_azimuth_deg = 5.0;
  eo.host_epoch_ns = kEpochNs;
  const VelodyneEncoder enc(eo);
  auto packets = encode_revolutions(enc, 1.2);
  VelodyneDecoderOptions options;
  options.keep_partial_scans = true;
  VelodyneDecoder decoder(options);
  std::size_t fed = 0;
  for (std::size_t i = 0; i < packets.size(); ++i) {
    auto payload = packets[i].payload;
    if (i == 10) payload[500] = 0x00;  // block 5 flag byte
    if (i == 11) payload.push_back(0);
    if (i == 12) payload.pop_back();
    if (i == 13) payload[1204] = 0x3A;         // unknown return mode
    if (i == 14) payload[2 * 100 + 3] = 0xFF;  // block 2 azimuth 0xFF.. >= 36000
    if (i == 15) payload[1205] = 0x28;         // product changes mid-stream
    decoder.add_packet(payload, packets[i].host_stamp_ns);
    ++fed;
    if (i == 30) {  // a repeated packet
      decoder.add_packet(packets[25].payload, packets[25].host_stamp_ns);
      ++fed;
    }
  }
  decoder.finish();
  const auto& s = decoder.stats();
  EXPECT_EQ(s.packets, fed);
  EXPECT_EQ(s.bad_block_flag, 1u);
  EXPECT_EQ(s.wrong_size, 2u);
  EXPECT_EQ(s.unknown_return_mode, 1u);
  EXPECT_EQ(s.bad_azimuth, 1u);
  EXPECT_EQ(s.product_changed, 1u);
  EXPECT_EQ(s.out_of_order, 1u);
  EXPECT_EQ(s.skipped_packets(), 7u);
  EXPECT_EQ(s.decoded_packets, fed - 7);
  EXPECT_EQ(s.lost_sequences, 6u * 24u);
  EXPECT_EQ(decoder.pop_scan().has_value(), true);
}

TEST(VelodynePacket, DualPairsMustShareTheirAzimuth) {
  VelodyneEncoderOptions eo;
  eo.return_mode = 0x39;
  auto p = VelodyneEncoder(eo)
               .encode(0, 1, [](long long, int) { return VelodyneEchoPair{}; })[0]
               .payload;
  VelodyneParsedPacket parsed;
  const VelodyneLayout layout{};
  EXPECT_EQ(parse_velodyne_packet(p, layout, 0.2, parsed), VelodynePacketStatus::kOk);
  EXPECT_EQ(parsed.count, 12);
  p[3 * 100 + 2] ^= 0x01;
  EXPECT_EQ(parse_velodyne_packet(p, layout, 0.2, parsed), VelodynePacketStatus::kDualPairMismatch);
}

TEST(VelodynePacket, SequencesInterpolateAzimuthAndTime) {
  VelodyneEncoderOptions eo;
  eo.start_azimuth_deg = 359.0;
  const VelodyneEncoder enc(eo);
  const auto p = enc.encode(0, 1, [](long long s, int laser) {
    return VelodyneEchoPair{
        {static_cast<std::uint16_t>(1000 + s), static_cast<std::uint8_t>(laser)}, {}};
  })[0];
  VelodyneParsedPacket parsed;
  ASSERT_EQ(parse_velodyne_packet(p.payload, VelodyneLayout{}, 0.2, parsed),
            VelodynePacketStatus::kOk);
  ASSERT_EQ(parsed.count, 24);
  EXPECT_NEAR(parsed.packet_us, 24 * 55.296, 1e-9);
  for (int k = 0; k < 24; ++k) {
    const auto& seq = parsed.sequences[static_cast<std::size_t>(k)];
    EXPECT_NEAR(seq.time_offset_us, k * 55.296, 1e-9);
    EXPECT_LT(angle_diff_deg(seq.azimuth_deg, enc.sequence_azimuth_deg(k)), 0.011) << k;
    EXPECT_GE(seq.azimuth_deg, 0.0);
    EXPECT_LT(seq.azimuth_deg, 360.0);
  }
  std::vector<VelodynePoint> points;
  append_velodyne_points(parsed, core::SensorModel::vlp16(), points);
  ASSERT_EQ(points.size(), 24u * 16u);
  EXPECT_EQ(points[17].laser, 1);  // block 0, second sequence, laser 1
  EXPECT_EQ(points[17].sequence_in_block, 1);
  EXPECT_NEAR(points[17].distance_m, 1001 * 0.002, 1e-12);
  EXPECT_NEAR(points[17].time_offset_us, 55.296 + 2.304, 1e-9);
  EXPECT_EQ(points[17].ring, 8);
}

TEST(VelodyneDecoder, Vlp32cAzimuthOffsetsFollowTheManual) {
  // Laser 0 (-25 deg) has the manual's azimuth offset +1.4 deg, laser 1 (-1 deg) -4.2 deg,
  // added to the packet's clockwise azimuth.
  VelodyneEncoderOptions eo;
  eo.product = 0x28;
  eo.start_azimuth_deg = 100.0;
  const VelodyneEncoder enc(eo);
  const auto packets = enc.encode(0, 3, [](long long, int laser) {
    return VelodyneEchoPair{{static_cast<std::uint16_t>(laser < 2 ? 5000 : 0), 50}, {}};
  });
  VelodyneDecoderOptions options;
  options.keep_partial_scans = true;
  const Decoded d = decode(packets, options);
  ASSERT_EQ(d.scans.size(), 1u);
  const auto& scan = d.scans[0];
  const int column = static_cast<int>(std::floor(100.0 / (360.0 / scan.columns())));
  for (const auto& [laser, offset_deg] : {std::pair{0, 1.4}, std::pair{1, -4.2}}) {
    const std::size_t i = scan.index(d.model.ring_of_laser(laser), column);
    ASSERT_TRUE(scan.valid(i));
    const double velodyne_az = -std::atan2(scan.point(i).y(), scan.point(i).x()) / kDegToRad;
    EXPECT_NEAR(velodyne_az, 100.0 + offset_deg, 0.01) << "laser " << laser;
  }
}

TEST(VelodynePacket, AzimuthConvention) {
  EXPECT_NEAR(velodyne_to_ringtrack_azimuth_rad(0.0), 0.0, 1e-12);
  EXPECT_NEAR(velodyne_to_ringtrack_azimuth_rad(90.0), 1.5 * std::numbers::pi, 1e-12);   // right
  EXPECT_NEAR(velodyne_to_ringtrack_azimuth_rad(270.0), 0.5 * std::numbers::pi, 1e-12);  // left
}

}  // namespace
}  // namespace ringtrack::io
