#pragma once
// Shared helpers of the io unit tests: temporary folders and small hand-made scans.

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <string>
#include <thread>
#include <vector>

#include "ringtrack/core/error.hpp"
#include "ringtrack/core/organized_scan.hpp"
#include "ringtrack/io/text.hpp"
#include "ringtrack/io/udp_packet_source.hpp"
#include "support/temp_dir.hpp"
#include "support/udp_replay.hpp"

namespace ringtrack::io::test {

/// A fresh folder per test (tests/support/temp_dir.hpp).
using TempDir = ::ringtrack::test::TempDir;

/// Options of a live UDP source on 127.0.0.1 at a free port (source.port() says which).
inline UdpOptions loopback_udp(std::size_t max_queued_scans) {
  UdpOptions o;
  o.host = "127.0.0.1";
  o.port = 0;
  o.max_queued_scans = max_queued_scans;
  return o;
}

/// The same decoded cells (status, range, intensity, point) at the same column azimuths; stamps
/// are not compared (a live source stamps by receive time).
inline void expect_same_decoded_cells(const core::OrganizedScan& got,
                                      const core::OrganizedScan& want) {
  ASSERT_EQ(got.rings(), want.rings());
  ASSERT_EQ(got.columns(), want.columns());
  ASSERT_EQ(got.statuses(), want.statuses());
  for (std::size_t i = 0; i < want.size(); ++i) {
    if (!want.valid(i)) continue;
    ASSERT_EQ(got.range_m(i), want.range_m(i)) << "cell " << i;
    ASSERT_EQ(got.intensity(i), want.intensity(i)) << "cell " << i;
    ASSERT_EQ(got.point(i), want.point(i)) << "cell " << i;
  }
  EXPECT_EQ(got.column_azimuth_rad, want.column_azimuth_rad);
}

/// Sends the packets to a live UDP source on the loopback interface, waits until all arrived,
/// stops it (completing the scan in progress when whole) and drains its queue.
inline std::vector<core::OrganizedScan> receive_replayed(
    UdpPacketSource& source, const std::vector<std::vector<std::uint8_t>>& packets) {
  ::ringtrack::test::replay_to_loopback(packets, source.port());
  for (int i = 0; i < 500 && source.stats().datagrams < packets.size(); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  source.stop();
  std::vector<core::OrganizedScan> scans;
  while (auto s = source.next(std::chrono::milliseconds(0))) scans.push_back(std::move(*s));
  return scans;
}

inline std::string read_text(const std::filesystem::path& path) {
  const auto bytes = read_file_bytes(path);
  return {bytes.begin(), bytes.end()};
}

inline void write_text(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

/// A rings x columns scan with distinct points (ring r, column c at azimuth c*step, range
/// 2 + r + c/10, intensity r*10+c), every fifth cell invalid.
inline core::OrganizedScan make_scan(int rings, int columns) {
  core::OrganizedScan scan(rings, columns);
  for (int r = 0; r < rings; ++r) {
    for (int c = 0; c < columns; ++c) {
      const auto i = scan.index(r, c);
      if (i % 5 == 3) continue;
      const double az = 2.0 * std::numbers::pi * c / columns;
      const double el = (-15.0 + 2.0 * r) * std::numbers::pi / 180.0;
      const double range = 2.0 + r + c / 10.0;
      const Eigen::Vector3f p(static_cast<float>(range * std::cos(el) * std::cos(az)),
                              static_cast<float>(range * std::cos(el) * std::sin(az)),
                              static_cast<float>(range * std::sin(el)));
      scan.set_return(r, c, p.norm(), static_cast<float>(r * 10 + c) + 0.25f, p);
    }
  }
  return scan;
}

/// Labels 0..6 cycling over the cells, with a large id mixed in.
inline std::vector<std::uint32_t> make_labels(std::size_t n) {
  std::vector<std::uint32_t> labels(n);
  for (std::size_t i = 0; i < n; ++i)
    labels[i] = i % 11 == 0 ? 4000000000u : static_cast<std::uint32_t>(i % 7);
  return labels;
}

/// Expects two scans to hold the same cells (same validity, identical coordinates/intensity).
inline void expect_same_cells(const core::OrganizedScan& a, const core::OrganizedScan& b) {
  ASSERT_EQ(a.rings(), b.rings());
  ASSERT_EQ(a.columns(), b.columns());
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a.valid(i), b.valid(i)) << "cell " << i;
    if (!a.valid(i)) continue;
    EXPECT_EQ(a.point(i), b.point(i)) << "cell " << i;
    EXPECT_EQ(a.intensity(i), b.intensity(i)) << "cell " << i;
    EXPECT_FLOAT_EQ(b.range_m(i), b.point(i).norm()) << "cell " << i;
  }
}

/// Runs f and returns the message of the core::InputError it throws (fails the test otherwise).
template <typename F>
std::string input_error(F&& f) {
  try {
    f();
  } catch (const core::InputError& e) {
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "expected core::InputError, got: " << e.what();
    return {};
  }
  ADD_FAILURE() << "expected core::InputError, nothing thrown";
  return {};
}

}  // namespace ringtrack::io::test
