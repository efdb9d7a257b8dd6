#include "support/ouster_encoder.hpp"

#include <sstream>

namespace ringtrack::test {
namespace {

void put(std::vector<std::uint8_t>& b, std::size_t at, std::uint64_t v, int bytes) {
  for (int i = 0; i < bytes; ++i) b[at + i] = static_cast<std::uint8_t>((v >> (8 * i)) & 0xFF);
}

}  // namespace

std::vector<std::uint8_t> encode_ouster_packet(
    const OusterEncoderOptions& o, int first_m, std::int64_t first_stamp_ns,
    const std::function<OusterEcho(int m, int beam)>& echo) {
  const bool legacy = o.profile == "LEGACY";
  std::size_t pixel = 12;
  if (o.profile == "RNG19_RFL8_SIG16_NIR16_DUAL") pixel = 16;
  if (o.profile == "RNG15_RFL8_NIR8") pixel = 4;
  const std::size_t pixels = static_cast<std::size_t>(o.pixels_per_column) * pixel;
  // LEGACY: per column 16-byte header (timestamp, measurement id, frame id, encoder count),
  // pixels, 4-byte status (all ones = valid). Others: 32-byte packet header (type, frame id,
  // init id, serial, ...), per column 12-byte header (timestamp, measurement id, status), pixels;
  // 32-byte footer.
  const std::size_t column = legacy ? 16 + pixels + 4 : 12 + pixels;
  std::vector<std::uint8_t> p((legacy ? 0 : 64) + column * o.columns_per_packet, 0);
  if (!legacy) {
    put(p, 0, 1, 2);
    put(p, 2, static_cast<std::uint64_t>(o.frame_id), 2);
  }
  for (int c = 0; c < o.columns_per_packet; ++c) {
    const int m = first_m + c;
    std::size_t at = (legacy ? 0 : 32) + c * column;
    put(p, at, static_cast<std::uint64_t>(first_stamp_ns + c * 97'656), 8);
    put(p, at + 8, static_cast<std::uint64_t>(m), 2);
    if (legacy) {
      put(p, at + 10, static_cast<std::uint64_t>(o.frame_id), 2);
      put(p, at + 12, static_cast<std::uint64_t>(m) * 88, 4);
      put(p, at + 16 + pixels, 0xFFFFFFFFu, 4);
      at += 16;
    } else {
      put(p, at + 10, 1, 2);  // status: valid
      at += 12;
    }
    for (int b = 0; b < o.pixels_per_column; ++b) {
      const OusterEcho e = echo(m, b);
      const std::size_t q = at + static_cast<std::size_t>(b) * pixel;
      if (legacy) {
        put(p, q, e.range_mm & 0xFFFFF, 4);
        put(p, q + 4, e.reflectivity, 2);
        put(p, q + 6, 100, 2);  // signal
        put(p, q + 8, 50, 2);   // near-infrared
      } else if (pixel == 12) {
        put(p, q, e.range_mm & 0x7FFFF, 4);
        p[q + 4] = e.reflectivity;
        put(p, q + 6, 100, 2);
        put(p, q + 8, 50, 2);
      } else if (pixel == 16) {
        put(p, q, (e.range_mm & 0x7FFFF) | (static_cast<std::uint32_t>(e.reflectivity) << 24), 4);
        put(p, q + 4, (e.range2_mm & 0x7FFFF) | (static_cast<std::uint32_t>(e.reflectivity2) << 24),
            4);
        put(p, q + 8, 100, 2);
        put(p, q + 10, 90, 2);
        put(p, q + 12, 50, 2);
      } else {
        put(p, q, (e.range_mm / 8) & 0x7FFF, 2);
        p[q + 2] = e.reflectivity;
        p[q + 3] = 50;
      }
    }
  }
  return p;
}

std::string ouster_metadata_json(const OusterEncoderOptions& o) {
  std::ostringstream s;
  const auto list = [&s](int n, const auto& f) {
    s << "[";
    for (int i = 0; i < n; ++i) s << (i ? ", " : "") << f(i);
    s << "]";
  };
  s << "{\"prod_line\": \"OS-TEST\", \"lidar_mode\": \"1024x10\", \"beam_altitude_angles\": ";
  list(o.pixels_per_column, [](int i) { return 15.0 - 2.0 * i; });
  s << ", \"beam_azimuth_angles\": ";
  list(o.pixels_per_column, [](int i) { return i % 2 == 0 ? 1.5 : -1.5; });
  s << ", \"lidar_origin_to_beam_origin_mm\": 15.0, \"lidar_to_sensor_transform\": "
       "[-1, 0, 0, 0, 0, -1, 0, 0, 0, 0, 1, 36.18, 0, 0, 0, 1], \"data_format\": "
       "{\"columns_per_frame\": 1024, \"columns_per_packet\": "
    << o.columns_per_packet << ", \"pixels_per_column\": " << o.pixels_per_column
    << ", \"column_window\": [0, 1023], \"pixel_shift_by_row\": ";
  list(o.pixels_per_column, [](int i) { return 4 * (i % 4); });
  if (o.profile != "LEGACY") s << ", \"udp_profile_lidar\": \"" << o.profile << "\"";
  s << "}}";
  return s.str();
}

}  // namespace ringtrack::test
