#include "support/hesai_encoder.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace ringtrack::test {
namespace {

void put16(std::vector<std::uint8_t>& b, std::size_t at, unsigned v) {
  b[at] = static_cast<std::uint8_t>(v & 0xFF);
  b[at + 1] = static_cast<std::uint8_t>((v >> 8) & 0xFF);
}

void put32(std::vector<std::uint8_t>& b, std::size_t at, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) b[at + i] = static_cast<std::uint8_t>((v >> (8 * i)) & 0xFF);
}

}  // namespace

HesaiEncoder::HesaiEncoder(HesaiEncoderOptions options) : o_(std::move(options)) {
  if (o_.model == "Pandar40P") {
    channels_ = 40, blocks_ = 10, columns_10hz_ = 1800;
  } else if (o_.model == "Pandar64") {
    channels_ = 64, blocks_ = 6, columns_10hz_ = 1800;
  } else if (o_.model == "PandarQT64") {
    channels_ = 64, blocks_ = 4, columns_10hz_ = 600;
  } else if (o_.model == "PandarXT16") {
    channels_ = 16, blocks_ = 8, columns_10hz_ = 2000;
  } else if (o_.model == "PandarXT32") {
    channels_ = 32, blocks_ = 8, columns_10hz_ = 2000;
  } else {
    throw std::invalid_argument("hesai encoder: unknown model " + o_.model);
  }
}

int HesaiEncoder::firings_per_packet() const {
  return o_.return_mode == 0x39 ? blocks_ / 2 : blocks_;
}

int HesaiEncoder::firings_per_revolution() const {
  return static_cast<int>(std::lround(columns_10hz_ * 10.0 / o_.scan_rate_hz));
}

std::uint16_t HesaiEncoder::azimuth_of(long long firing) const {
  const double step = 36000.0 / firings_per_revolution();
  const double az =
      std::fmod(o_.start_azimuth_deg * 100.0 + static_cast<double>(firing) * step, 36000.0);
  return static_cast<std::uint16_t>(std::lround(az) % 36000);
}

std::vector<std::vector<std::uint8_t>> HesaiEncoder::encode(
    long long first, int count,
    const std::function<std::pair<HesaiEcho, HesaiEcho>(long long, int)>& echo) const {
  const bool dual = o_.return_mode == 0x39;
  std::vector<std::vector<std::uint8_t>> out;
  for (long long k = first; k < first + count; ++k) {
    std::size_t header = 0;
    std::size_t record = 4;
    std::size_t tail = 24;
    bool flag = false;
    // Layouts as the manuals draw them (chapter "Data Structure").
    if (o_.model == "Pandar40P") {
      header = 0, record = 3, tail = 22, flag = true;
    } else if (o_.model == "Pandar64") {
      header = 8, record = 3, tail = 22;
    } else {
      header = 12, record = 4, tail = 24;
    }
    const std::size_t block_bytes = (flag ? 2 : 0) + 2 + channels_ * record;
    const std::size_t body_end = header + blocks_ * block_bytes;
    std::vector<std::uint8_t> p(body_end + tail + (o_.udp_sequence ? 4 : 0), 0);
    if (o_.model == "Pandar64") {
      p[0] = 0xEE, p[1] = 0xFF, p[2] = 64, p[3] = 6, p[4] = 0, p[5] = 4, p[6] = dual ? 2 : 1;
      p[7] = o_.udp_sequence ? 1 : 0;
    } else if (header == 12) {
      p[0] = 0xEE, p[1] = 0xFF;
      p[2] = o_.model == "PandarQT64" ? 3 : 6;
      p[3] = 1;
      p[6] = static_cast<std::uint8_t>(channels_), p[7] = static_cast<std::uint8_t>(blocks_);
      p[8] = dual ? 1 : 0, p[9] = 4, p[10] = dual ? 2 : 1, p[11] = o_.udp_sequence ? 1 : 0;
    }
    for (int b = 0; b < blocks_; ++b) {
      const long long firing = k * firings_per_packet() + (dual ? b / 2 : b);
      std::size_t at = header + b * block_bytes;
      if (flag) {
        p[at] = 0xFF, p[at + 1] = 0xEE;
        at += 2;
      }
      put16(p, at, azimuth_of(firing));
      at += 2;
      for (int ch = 0; ch < channels_; ++ch) {
        const auto [a, second] = echo(firing, ch);
        const HesaiEcho e = dual && b % 2 == 1 ? second : a;
        put16(p, at + ch * record, e.distance_raw);
        p[at + ch * record + 2] = e.reflectivity;
      }
    }
    const std::uint32_t micros = static_cast<std::uint32_t>((k * 100) % 1000000);
    if (o_.model == "Pandar40P" || o_.model == "Pandar64") {
      // reserved 5, shutdown flag, reserved 2, motor speed, timestamp, return mode, factory, UTC
      put16(p, body_end + 8, 600);
      put32(p, body_end + 10, micros);
      p[body_end + 14] = o_.return_mode;
      p[body_end + 15] = 0x42;
    } else if (o_.model == "PandarQT64") {
      // reserved 10, motor speed, timestamp, return mode, factory, date and time
      put16(p, body_end + 10, 600);
      put32(p, body_end + 12, micros);
      p[body_end + 16] = o_.return_mode;
      p[body_end + 17] = 0x42;
    } else {
      // reserved 9, shutdown flag, return mode, motor speed, date and time, timestamp, factory
      p[body_end + 10] = o_.return_mode;
      put16(p, body_end + 11, 600);
      put32(p, body_end + 19, micros);
      p[body_end + 23] = 0x42;
    }
    if (o_.udp_sequence) put32(p, body_end + tail, static_cast<std::uint32_t>(k + 1));
    out.push_back(std::move(p));
  }
  return out;
}

std::string hesai_calibration_csv(int channels) {
  std::ostringstream s;
  s << "Channel,Elevation,Azimuth\n";
  for (int ch = 1; ch <= channels; ++ch) {
    s << ch << "," << 15.0 - (ch - 1) << "," << (ch % 2 == 0 ? 1.5 : -1.5) << "\n";
  }
  return s.str();
}

}  // namespace ringtrack::test
