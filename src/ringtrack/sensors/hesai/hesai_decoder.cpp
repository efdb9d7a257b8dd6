#include "ringtrack/sensors/hesai/hesai_decoder.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "ringtrack/core/error.hpp"

namespace ringtrack::sensors::hesai {
namespace {

constexpr double kDegToRad = std::numbers::pi / 180.0;

double wrap360(double deg) {
  double a = std::fmod(deg, 360.0);
  if (a < 0) a += 360.0;
  if (a >= 360.0) a = 0.0;
  return a;
}

// Hesai azimuths turn clockwise seen from above; ringtrack's counter-clockwise from +x.
double to_ringtrack_rad(double hesai_deg) {
  double a = std::fmod(-hesai_deg * kDegToRad, 2.0 * std::numbers::pi);
  if (a < 0) a += 2.0 * std::numbers::pi;
  if (a >= 2.0 * std::numbers::pi) a = 0.0;
  return a;
}

std::uint16_t le16(const std::uint8_t* p) {
  return static_cast<std::uint16_t>(p[0] | (p[1] << 8));
}

std::string packet_label(std::uint64_t index) {
  return "hesai packet " + std::to_string(index);
}

}  // namespace

HesaiReturnSelection parse_hesai_return_selection(const std::string& name) {
  if (name == "auto") return HesaiReturnSelection::kAuto;
  if (name == "strongest") return HesaiReturnSelection::kStrongest;
  if (name == "last") return HesaiReturnSelection::kLast;
  throw core::ConfigError("hesai return selection '" + name +
                          "': expected auto, strongest or last");
}

Eigen::Vector3d HesaiPoint::xyz() const {
  const double el = elevation_deg * kDegToRad;
  const double az = to_ringtrack_rad(azimuth_deg);
  const double h = distance_m * std::cos(el);
  return {h * std::cos(az), h * std::sin(az), distance_m * std::sin(el)};
}

void append_hesai_points(const HesaiParsedPacket& packet, const HesaiCalibration& calibration,
                         std::vector<HesaiPoint>& out) {
  const HesaiFormat& f = *packet.format;
  calibration.check(f);
  for (int b = 0; b < packet.blocks; ++b) {
    const bool second = packet.dual && b % 2 == 1;
    const std::uint8_t* records = packet.records[static_cast<std::size_t>(b)];
    const std::uint8_t* first = second ? packet.records[static_cast<std::size_t>(b - 1)] : nullptr;
    for (int ch = 0; ch < f.channels; ++ch) {
      const std::uint8_t* rec = records + static_cast<std::size_t>(ch) * f.unit_bytes;
      const int raw = le16(rec);
      if (raw == 0) continue;
      if (second && le16(first + static_cast<std::size_t>(ch) * f.unit_bytes) == raw) continue;
      HesaiPoint p;
      p.channel = ch;
      p.block = b;
      p.second_of_pair = second;
      p.azimuth_deg = wrap360(packet.azimuth[static_cast<std::size_t>(b)] * 0.01 +
                              calibration.azimuth_deg[static_cast<std::size_t>(ch)]);
      p.elevation_deg = calibration.elevation_deg[static_cast<std::size_t>(ch)];
      p.distance_m = raw * packet.distance_unit_m;
      p.reflectivity = rec[2];
      out.push_back(p);
    }
  }
}

HesaiDecoder::HesaiDecoder(HesaiDecoderOptions options) : options_(std::move(options)) {
  if (!(options_.scan_rate_hz >= 1.0 && options_.scan_rate_hz <= 50.0)) {
    throw core::ConfigError("hesai scan_rate_hz " + std::to_string(options_.scan_rate_hz) +
                            ": expected 1..50");
  }
  if (!(options_.cut_azimuth_deg >= 0.0 && options_.cut_azimuth_deg < 360.0)) {
    throw core::ConfigError("hesai cut_azimuth_deg: expected [0, 360)");
  }
  if (options_.calibration.channels() == 0) {
    throw core::ConfigError(
        "hesai: the sensor's angle-correction file is required (--calibration FILE)");
  }
  if (!options_.model.empty()) {
    const HesaiFormat* f = hesai_format_by_name(options_.model);
    if (f == nullptr) {
      throw core::ConfigError("hesai model '" + options_.model + "': expected one of " +
                              hesai_model_list());
    }
    set_format(*f);
  }
}

const core::SensorModel& HesaiDecoder::model() const {
  if (!model_) throw core::Error("hesai decoder: the model is not known before the first packet");
  return *model_;
}

void HesaiDecoder::set_format(const HesaiFormat& format) {
  model_ = hesai_sensor_model(format, options_.calibration, options_.scan_rate_hz);  // checks
  if (options_.min_range_m >= 0) model_->min_range_m = options_.min_range_m;
  if (options_.max_range_m >= 0) model_->max_range_m = options_.max_range_m;
  model_->validate();
  format_ = &format;
  step_deg_ = 360.0 / model_->columns();
  spacing_deg_ = step_deg_;
  firing_us_ = model_->firing_sequence_us;
  min_range_ = static_cast<float>(model_->min_range_m);
  max_range_ = static_cast<float>(model_->max_range_m);
  const auto n = static_cast<std::size_t>(format.channels);
  cos_el_.resize(n);
  sin_el_.resize(n);
  cos_offset_.resize(n);
  sin_offset_.resize(n);
  ring_of_channel_.resize(n);
  for (std::size_t c = 0; c < n; ++c) {
    const double el = options_.calibration.elevation_deg[c] * kDegToRad;
    cos_el_[c] = static_cast<float>(std::cos(el));
    sin_el_[c] = static_cast<float>(std::sin(el));
    cos_offset_[c] = std::cos(options_.calibration.azimuth_deg[c] * kDegToRad);
    sin_offset_[c] = std::sin(options_.calibration.azimuth_deg[c] * kDegToRad);
    ring_of_channel_[c] = model_->ring_of_laser(static_cast<int>(c));
  }
}

void HesaiDecoder::check_same_format(std::span<const std::uint8_t> payload) const {
  // A packet that does not parse as the stream's format may be another model's: say so.
  const HesaiFormat* other = identify_hesai_packet(payload);
  if (other != nullptr && other != format_) {
    throw core::InputError(packet_label(stats_.packets) + ": a " + other->name +
                           " packet, but the stream is " + format_->name +
                           (options_.model.empty() ? "" : " (named)"));
  }
}

bool HesaiDecoder::count_rejected(HesaiPacketStatus status) {
  switch (status) {
    case HesaiPacketStatus::kOk:
      return false;
    case HesaiPacketStatus::kWrongSize:
      ++stats_.wrong_size;
      break;
    case HesaiPacketStatus::kBadHeader:
    case HesaiPacketStatus::kBadDistanceUnit:
      ++stats_.bad_header;
      break;
    case HesaiPacketStatus::kBadAzimuth:
      ++stats_.bad_azimuth;
      break;
    case HesaiPacketStatus::kUnknownReturnMode:
      ++stats_.unknown_return_mode;
      break;
  }
  return true;
}

void HesaiDecoder::choose_return(std::uint8_t mode, bool dual) {
  switch (options_.return_selection) {
    case HesaiReturnSelection::kAuto:
      use_last_ = dual && mode == 0x3B;  // last + first: no strongest in the pair
      break;
    case HesaiReturnSelection::kStrongest:
      if (mode == 0x38 || mode == 0x33 || mode == 0x3B) {
        throw core::InputError(packet_label(stats_.packets) +
                               ": the stream carries no strongest return (return mode " +
                               std::to_string(mode) + ")");
      }
      use_last_ = false;
      break;
    case HesaiReturnSelection::kLast:
      if (mode != 0x38 && mode != 0x39 && mode != 0x3B) {
        throw core::InputError(packet_label(stats_.packets) +
                               ": the stream carries no last return (return mode " +
                               std::to_string(mode) + ")");
      }
      use_last_ = true;
      break;
  }
}

bool HesaiDecoder::stream_matches(const HesaiFormat& format) {
  if (format_ == nullptr) {
    try {
      set_format(format);
    } catch (const core::InputError& e) {
      throw core::InputError(packet_label(stats_.packets) + " (" + format.name + "): " + e.what());
    }
  }
  if (!stream_known_) {
    choose_return(parsed_.return_mode, parsed_.dual);
    return_mode_ = parsed_.return_mode;
    stream_known_ = true;
    return true;
  }
  if (parsed_.return_mode != return_mode_) {
    ++stats_.mode_changed;
    return false;
  }
  return true;
}

HesaiPacketStatus HesaiDecoder::add_packet(std::span<const std::uint8_t> payload,
                                           std::int64_t host_stamp_ns) {
  ++stats_.packets;
  const HesaiFormat* format = format_ != nullptr ? format_ : identify_hesai_packet(payload);
  if (format == nullptr) {
    ++stats_.wrong_size;
    return HesaiPacketStatus::kWrongSize;
  }
  const HesaiPacketStatus status = parse_hesai_packet(payload, *format, parsed_);
  if (status != HesaiPacketStatus::kOk && format_ != nullptr) check_same_format(payload);
  if (count_rejected(status)) return status;
  if (!stream_matches(*format)) return HesaiPacketStatus::kUnknownReturnMode;
  const int firings = parsed_.dual ? parsed_.blocks / 2 : parsed_.blocks;
  // The packet leaves the sensor after its last firing.
  const std::int64_t start_ns = host_stamp_ns - std::llround(firings * firing_us_ * 1e3);
  for (int k = 0; k < firings; ++k) {
    add_firing(parsed_.dual ? 2 * k : k, start_ns + std::llround(k * firing_us_ * 1e3));
  }
  ++stats_.decoded_packets;
  return HesaiPacketStatus::kOk;
}

void HesaiDecoder::add_firing(int block, std::int64_t stamp_ns) {
  const double az = parsed_.azimuth[static_cast<std::size_t>(block)] * 0.01;
  const double rel = wrap360(az - options_.cut_azimuth_deg);
  if (scan_ && have_prev_) {
    const double d_az = wrap360(az - prev_azimuth_deg_);
    const std::int64_t dt_ns = stamp_ns - scan_->column_stamp_ns[static_cast<std::size_t>(
                                              std::min(prev_column_, scan_->columns() - 1))];
    const bool paused = dt_ns > static_cast<std::int64_t>(0.5e9 / options_.scan_rate_hz);
    if (!paused && (d_az == 0.0 || d_az > 180.0)) {
      ++stats_.repeated_blocks;  // a repeated or late block
      return;
    }
    if (paused || prev_rel_deg_ + d_az >= 360.0) {
      finish_scan(true);
      start_scan(rel, block, stamp_ns);
    } else {
      const long long steps = std::max(1LL, std::llround(d_az / spacing_deg_));
      if (steps == 1 && d_az > 0.5 * step_deg_ && d_az < 1.5 * step_deg_) {
        spacing_deg_ += 0.02 * (d_az - spacing_deg_);
      }
      stats_.lost_blocks += static_cast<std::uint64_t>(steps - 1);
      const long long column = prev_column_ + steps;
      if (column < scan_->columns()) {
        fill_column(static_cast<int>(column), block, stamp_ns);
      } else {
        ++stats_.overflow_blocks;
      }
      prev_column_ = static_cast<int>(std::min<long long>(column, scan_->columns()));
    }
  } else {
    start_scan(rel, block, stamp_ns);
    have_prev_ = true;
  }
  prev_azimuth_deg_ = az;
  prev_rel_deg_ = rel;
}

void HesaiDecoder::start_scan(double rel_deg, int block, std::int64_t stamp_ns) {
  if (spare_ && spare_->rings() == model_->rings() && spare_->columns() == model_->columns()) {
    scan_ = std::move(spare_);
    spare_.reset();
    scan_->reset();
  } else {
    scan_.emplace(model_->rings(), model_->columns());
  }
  filled_.assign(static_cast<std::size_t>(scan_->columns()), 0);
  const int column =
      std::clamp(static_cast<int>(std::floor(rel_deg / step_deg_)), 0, scan_->columns() - 1);
  first_column_ = column;
  fill_column(column, block, stamp_ns);
  prev_column_ = column;
}

void HesaiDecoder::fill_column(int column, int block, std::int64_t stamp_ns) {
  core::OrganizedScan& scan = *scan_;
  const auto c = static_cast<std::size_t>(column);
  filled_[c] = 1;
  const double base_deg = parsed_.azimuth[static_cast<std::size_t>(block)] * 0.01;
  scan.column_azimuth_rad[c] = to_ringtrack_rad(base_deg);
  scan.column_stamp_ns[c] = stamp_ns;
  const HesaiFormat& f = *format_;
  const std::uint8_t* first = parsed_.records[static_cast<std::size_t>(block)];
  const std::uint8_t* second =
      parsed_.dual ? parsed_.records[static_cast<std::size_t>(block) + 1] : nullptr;
  const double unit = parsed_.distance_unit_m;
  // Point azimuth = block azimuth + channel offset (clockwise); ringtrack's is its negative, so
  // x = h cos(block + offset), y = -h sin(block + offset), by the angle-addition formulas.
  const double cb = std::cos(base_deg * kDegToRad);
  const double sb = std::sin(base_deg * kDegToRad);
  for (int ch = 0; ch < f.channels; ++ch) {
    const auto k = static_cast<std::size_t>(ch);
    const std::uint8_t* rec = first + k * f.unit_bytes;
    if (second != nullptr) {
      const std::uint8_t* other = second + k * f.unit_bytes;
      const bool first_empty = le16(rec) == 0;
      const bool other_empty = le16(other) == 0;
      if (use_last_) {
        if (first_empty) rec = other;
      } else if (!other_empty && (first_empty || other[2] >= rec[2])) {
        rec = other;  // the stronger of the pair; ties go to the second ("strongest") block
      }
    }
    const int raw = le16(rec);
    if (raw == 0) continue;
    const int ring = ring_of_channel_[k];
    const auto range = static_cast<float>(raw * unit);
    if (range < min_range_) {
      scan.set_invalid(ring, column, core::ReturnStatus::kTooClose);
      continue;
    }
    if (range > max_range_) {
      scan.set_invalid(ring, column, core::ReturnStatus::kTooFar);
      continue;
    }
    const float h = range * cos_el_[k];
    const double cos_az = cb * cos_offset_[k] - sb * sin_offset_[k];
    const double sin_az = sb * cos_offset_[k] + cb * sin_offset_[k];
    const Eigen::Vector3f xyz(h * static_cast<float>(cos_az), -h * static_cast<float>(sin_az),
                              range * sin_el_[k]);
    scan.set_return(ring, column, range, static_cast<float>(rec[2]), xyz);
  }
}

void HesaiDecoder::finish_scan(bool complete) {
  if (!scan_) return;
  const bool partial = (scan_is_first_ && first_column_ != 0) || !complete;
  scan_is_first_ = false;
  if (partial && !options_.keep_partial_scans) {
    ++stats_.partial_scans_dropped;
    spare_ = std::move(scan_);  // its memory serves the next scan
    scan_.reset();
    return;
  }
  core::OrganizedScan& scan = *scan_;
  int anchor = -1;
  for (int c = 0; c < scan.columns(); ++c) {
    if (filled_[static_cast<std::size_t>(c)] != 0) {
      anchor = c;
      continue;
    }
    ++stats_.invalid_columns;
    const int from = anchor >= 0 ? anchor : first_column_;
    const auto f = static_cast<std::size_t>(from);
    const double steps = c - from;
    double az = scan.column_azimuth_rad[f] - steps * spacing_deg_ * kDegToRad;
    az = std::fmod(az, 2.0 * std::numbers::pi);
    if (az < 0) az += 2.0 * std::numbers::pi;
    scan.column_azimuth_rad[static_cast<std::size_t>(c)] = az;
    scan.column_stamp_ns[static_cast<std::size_t>(c)] =
        scan.column_stamp_ns[f] + std::llround(steps * firing_us_ * 1e3);
  }
  scan.stamp_ns = scan.column_stamp_ns[0];
  ready_.push_back(std::move(scan));
  ++stats_.scans;
  scan_.reset();
}

void HesaiDecoder::finish() {
  if (scan_) {
    const bool complete =
        prev_rel_deg_ >= 360.0 - 2.0 * step_deg_ || prev_column_ >= scan_->columns() - 1;
    finish_scan(complete);
  }
  have_prev_ = false;
  scan_is_first_ = true;
}

std::optional<core::OrganizedScan> HesaiDecoder::pop_scan() {
  if (ready_.empty()) return std::nullopt;
  core::OrganizedScan scan = std::move(ready_.front());
  ready_.pop_front();
  return scan;
}

}  // namespace ringtrack::sensors::hesai
