#include "ringtrack/io/velodyne_decoder.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "ringtrack/core/error.hpp"

namespace ringtrack::io {
namespace {

constexpr double kDegToRad = std::numbers::pi / 180.0;
constexpr double kHourUs = 3600e6;
constexpr std::int64_t kHourNs = 3'600'000'000'000;
constexpr double kStreamBreakUs = 1e6;  // sensor-time gap that ends a scan regardless of azimuth

double wrap360(double deg) {
  double a = std::fmod(deg, 360.0);
  if (a < 0) a += 360.0;
  if (a >= 360.0) a = 0.0;
  return a;
}

std::uint16_t read_u16(const std::uint8_t* p) {
  return static_cast<std::uint16_t>(p[0] | (p[1] << 8));
}

// cos and sin of a small angle (|a| <= 0.2 rad) by their Taylor series: error < 1e-9, and ~5x
// cheaper than the library calls in the per-return loop.
void small_angle_cos_sin(double a, double& c, double& s) {
  if (std::abs(a) > 0.2) {
    c = std::cos(a);
    s = std::sin(a);
    return;
  }
  const double a2 = a * a;
  c = 1.0 - a2 * (0.5 - a2 * (1.0 / 24.0 - a2 / 720.0));
  s = a * (1.0 - a2 * (1.0 / 6.0 - a2 * (1.0 / 120.0 - a2 / 5040.0)));
}

std::string packet_label(std::uint64_t index) {
  return "velodyne packet " + std::to_string(index);
}

}  // namespace

VelodyneReturnSelection parse_velodyne_return_selection(const std::string& name) {
  if (name == "auto") return VelodyneReturnSelection::kAuto;
  if (name == "strongest") return VelodyneReturnSelection::kStrongest;
  if (name == "last") return VelodyneReturnSelection::kLast;
  if (name == "second") return VelodyneReturnSelection::kSecond;
  throw core::ConfigError("velodyne return selection '" + name +
                          "': expected auto, strongest, last or second (Ouster _DUAL)");
}

VelodyneTimeSource parse_velodyne_time_source(const std::string& name) {
  if (name == "host") return VelodyneTimeSource::kHost;
  if (name == "sensor") return VelodyneTimeSource::kSensor;
  throw core::ConfigError("velodyne time source '" + name + "': expected host or sensor");
}

VelodyneDecoder::VelodyneDecoder(VelodyneDecoderOptions options) : options_(std::move(options)) {
  if (!(options_.scan_rate_hz >= 1.0 && options_.scan_rate_hz <= 50.0)) {
    throw core::ConfigError("velodyne scan_rate_hz " + std::to_string(options_.scan_rate_hz) +
                            ": expected 1..50");
  }
  if (!(options_.cut_azimuth_deg >= 0.0 && options_.cut_azimuth_deg < 360.0)) {
    throw core::ConfigError("velodyne cut_azimuth_deg " + std::to_string(options_.cut_azimuth_deg) +
                            ": expected [0, 360)");
  }
  if (!(options_.max_rate_deviation > 0.0 && options_.max_rate_deviation <= 1.0)) {
    throw core::ConfigError("velodyne max_rate_deviation: expected (0, 1]");
  }
  if (!options_.model.empty()) {
    try {
      set_model(core::SensorModel::by_name(options_.model, options_.scan_rate_hz));
    } catch (const core::ConfigError&) {
      throw;
    } catch (const core::Error& e) {
      throw core::ConfigError(std::string("velodyne model: ") + e.what());
    }
  }
}

const core::SensorModel& VelodyneDecoder::model() const {
  if (!model_)
    throw core::Error("velodyne decoder: the model is not known before the first packet");
  return *model_;
}

void VelodyneDecoder::set_model(core::SensorModel model) {
  model.validate();
  layout_ = VelodyneLayout::of(model);
  nominal_advance_deg_ = 360.0 * model.scan_rate_hz * model.firing_sequence_us * 1e-6;
  step_deg_ = 360.0 / model.columns();
  const auto lasers = static_cast<std::size_t>(model.rings());
  ring_of_laser_.assign(lasers, 0);
  cos_el_.assign(lasers, 0.0f);
  sin_el_.assign(lasers, 0.0f);
  z_offset_.assign(lasers, 0.0f);
  laser_delta_rad_.assign(lasers, 0.0);
  laser_fraction_.assign(lasers, 0.0);
  for (int ring = 0; ring < model.rings(); ++ring) {
    const auto r = static_cast<std::size_t>(ring);
    const auto laser = static_cast<std::size_t>(model.laser_of_ring[r]);
    if (laser >= lasers) throw core::Error("velodyne: model " + model.name + " has a bad laser id");
    ring_of_laser_[laser] = ring;
    cos_el_[laser] = static_cast<float>(std::cos(model.elevation_rad[r]));
    sin_el_[laser] = static_cast<float>(std::sin(model.elevation_rad[r]));
    z_offset_[laser] = static_cast<float>(model.vertical_offset_m[r]);
    laser_delta_rad_[laser] = model.azimuth_offset_rad[r];
    laser_fraction_[laser] = model.firing_offset_us[r] / model.firing_sequence_us;
  }
  model_ = std::move(model);
}

void VelodyneDecoder::check_stream(std::uint8_t product, std::uint8_t return_mode) {
  const std::string where = packet_label(stats_.packets);
  if (!model_) {
    if (product == static_cast<std::uint8_t>(VelodyneProduct::kUnknown)) {
      throw core::InputError(where +
                             ": product byte 0x00 does not identify the sensor; name the model "
                             "(vlp16, vlp32c or hdl32e)");
    }
    set_model(velodyne_model_for_product(product, options_.scan_rate_hz));
  } else if (product != static_cast<std::uint8_t>(VelodyneProduct::kUnknown)) {
    const auto expected = velodyne_product_of_model(*model_);
    if (product != static_cast<std::uint8_t>(expected)) {
      throw core::InputError(where + ": product byte says " + velodyne_product_name(product) +
                             ", which contradicts the named model " + model_->name);
    }
  }
  const auto mode = static_cast<VelodyneReturnMode>(return_mode);
  dual_ = mode == VelodyneReturnMode::kDual;
  const bool stream_last = mode == VelodyneReturnMode::kLast;
  switch (options_.return_selection) {
    case VelodyneReturnSelection::kAuto:
      use_last_ = false;
      break;
    case VelodyneReturnSelection::kStrongest:
      if (stream_last) {
        throw core::InputError(where +
                               ": the stream carries last returns only (return mode 0x38); "
                               "strongest returns need a strongest or dual stream");
      }
      use_last_ = false;
      break;
    case VelodyneReturnSelection::kLast:
      if (!dual_ && !stream_last) {
        throw core::InputError(where +
                               ": the stream carries strongest returns only; last returns need "
                               "a last (0x38) or dual (0x39) stream");
      }
      use_last_ = true;
      break;
    case VelodyneReturnSelection::kSecond:
      throw core::InputError(where +
                             ": Velodyne streams carry strongest and last returns; the second "
                             "strongest return is Ouster's (_DUAL profile)");
  }
  product_ = product;
  return_mode_ = return_mode;
  stream_known_ = true;
}

bool VelodyneDecoder::count_rejected(VelodynePacketStatus status) {
  switch (status) {
    case VelodynePacketStatus::kOk:
      return false;
    case VelodynePacketStatus::kWrongSize:
      ++stats_.wrong_size;
      break;
    case VelodynePacketStatus::kBadBlockFlag:
      ++stats_.bad_block_flag;
      break;
    case VelodynePacketStatus::kBadAzimuth:
    case VelodynePacketStatus::kDualPairMismatch:
      ++stats_.bad_azimuth;
      break;
    case VelodynePacketStatus::kUnknownReturnMode:
      ++stats_.unknown_return_mode;
      break;
    case VelodynePacketStatus::kProductChanged:
    case VelodynePacketStatus::kOutOfOrder:
      break;
  }
  return true;
}

bool VelodyneDecoder::stream_matches(std::span<const std::uint8_t> payload) {
  if (!stream_known_) {
    const bool had_model = model_.has_value();
    check_stream(parsed_.product, parsed_.return_mode);
    if (!had_model) {  // split again with the detected model's layout
      parse_velodyne_packet(payload, layout_, nominal_advance_deg_, parsed_);
    }
    return true;
  }
  if (parsed_.product != product_ || parsed_.return_mode != return_mode_) {
    ++stats_.product_changed;
    return false;
  }
  return true;
}

bool VelodyneDecoder::goes_back(double packet_start_us) const {
  if (!have_prev_) return false;
  double dt = packet_start_us - prev_sensor_us_;
  if (dt < -kHourUs / 2) dt += kHourUs;
  if (dt > kHourUs / 2) dt -= kHourUs;
  // A packet from before its predecessor (late or repeated) goes back in time and in azimuth;
  // a stuck clock alone (zero time stamps) is no reason to drop a packet.
  const double d_az = wrap360(parsed_.sequences[0].azimuth_deg - prev_azimuth_deg_);
  return dt < -0.5 * model_->firing_sequence_us && d_az > 180.0;
}

void VelodyneDecoder::update_spacing() {
  // Running estimate of the azimuth advance per sequence over the packet's span.
  const int per_block = layout_.sequences_per_block;
  if (parsed_.count > per_block) {
    const VelodyneSequence& a = parsed_.sequences[0];
    const VelodyneSequence& b =
        parsed_.sequences[static_cast<std::size_t>(parsed_.count - per_block)];
    const double spacing = wrap360(b.azimuth_deg - a.azimuth_deg) / (parsed_.count - per_block);
    if (spacing >= 0.25 * nominal_advance_deg_ && spacing <= 4.0 * nominal_advance_deg_) {
      ++spacing_samples_;
      const double weight = std::max(0.02, 1.0 / static_cast<double>(spacing_samples_));
      spacing_deg_ =
          spacing_samples_ == 1 ? spacing : spacing_deg_ + weight * (spacing - spacing_deg_);
    }
  }
  if (spacing_samples_ == 0) spacing_deg_ = nominal_advance_deg_;
  if (spacing_samples_ >= 50 &&
      std::abs(spacing_deg_ / nominal_advance_deg_ - 1.0) > options_.max_rate_deviation) {
    const double rpm = spacing_deg_ / 360.0 / (model_->firing_sequence_us * 1e-6) * 60.0;
    throw core::InputError(
        packet_label(stats_.packets) + ": the sensor spins at about " +
        std::to_string(static_cast<int>(std::lround(rpm))) + " rpm, but the scan rate is " +
        std::to_string(options_.scan_rate_hz) + " Hz (" +
        std::to_string(static_cast<int>(std::lround(options_.scan_rate_hz * 60))) +
        " rpm); set the scan rate to the sensor's");
  }
}

std::int64_t VelodyneDecoder::packet_start_ns(std::int64_t host_stamp_ns) const {
  if (options_.time_source == VelodyneTimeSource::kHost) {
    // The sensor sends a packet once its last firing sequence is over.
    return host_stamp_ns - std::llround(parsed_.packet_us * 1e3);
  }
  // The sensor's time is microseconds past the hour: the hour comes from the host's clock.
  std::int64_t hour = host_stamp_ns - host_stamp_ns % kHourNs;
  if (host_stamp_ns < 0) hour -= kHourNs;
  std::int64_t start_ns = hour + static_cast<std::int64_t>(parsed_.timestamp_us) * 1000;
  if (start_ns - host_stamp_ns > kHourNs / 2) start_ns -= kHourNs;
  if (host_stamp_ns - start_ns > kHourNs / 2) start_ns += kHourNs;
  return start_ns;
}

VelodynePacketStatus VelodyneDecoder::add_packet(std::span<const std::uint8_t> payload,
                                                 std::int64_t host_stamp_ns) {
  ++stats_.packets;
  const VelodyneLayout layout = model_ ? layout_ : VelodyneLayout{};
  const VelodynePacketStatus status = parse_velodyne_packet(
      payload, layout, nominal_advance_deg_ > 0 ? nominal_advance_deg_ : 0.2, parsed_);
  if (count_rejected(status)) return status;
  if (!stream_matches(payload)) return VelodynePacketStatus::kProductChanged;
  const double packet_start_us = parsed_.timestamp_us;
  if (goes_back(packet_start_us)) {
    ++stats_.out_of_order;
    return VelodynePacketStatus::kOutOfOrder;
  }
  update_spacing();
  const std::int64_t start_ns = packet_start_ns(host_stamp_ns);
  for (int i = 0; i < parsed_.count; ++i) {
    const VelodyneSequence& seq = parsed_.sequences[static_cast<std::size_t>(i)];
    add_sequence(seq, packet_start_us + seq.time_offset_us,
                 start_ns + std::llround(seq.time_offset_us * 1e3));
  }
  ++stats_.decoded_packets;
  return VelodynePacketStatus::kOk;
}

void VelodyneDecoder::add_sequence(const VelodyneSequence& seq, double sensor_us,
                                   std::int64_t stamp_ns) {
  const double rel = wrap360(seq.azimuth_deg - options_.cut_azimuth_deg);
  if (!scan_ || !have_prev_) {
    start_scan(rel, seq, stamp_ns);
    prev_azimuth_deg_ = seq.azimuth_deg;
    prev_rel_deg_ = rel;
    prev_sensor_us_ = sensor_us;
    have_prev_ = true;
    return;
  }
  const double sequence_us = model_->firing_sequence_us;
  const double d_az = wrap360(seq.azimuth_deg - prev_azimuth_deg_);
  double dt = sensor_us - prev_sensor_us_;
  if (dt < -kHourUs / 2) dt += kHourUs;
  if (dt > kHourUs / 2) dt -= kHourUs;
  if (dt > kStreamBreakUs) {
    // A paused recording: whatever the azimuth says, these returns are not of the same scan.
    ++stats_.stream_breaks;
    finish_scan(true);
    start_scan(rel, seq, stamp_ns);
    prev_azimuth_deg_ = seq.azimuth_deg;
    prev_rel_deg_ = rel;
    prev_sensor_us_ = sensor_us;
    return;
  }

  // Sequences elapsed since the previous one. The sensor clock counts them exactly (and across
  // whole lost revolutions); the azimuth confirms it. Without a usable clock the azimuth
  // advance, divided by the measured advance per sequence, gives the count.
  long long steps = 0;
  long long turns = 0;
  bool clock_ok = false;
  if (dt > 0.5 * sequence_us) {
    const long long steps_t = std::llround(dt / sequence_us);
    const double predicted = static_cast<double>(steps_t) * spacing_deg_;
    const long long k = std::llround((predicted - d_az) / 360.0);
    const double residual = predicted - d_az - 360.0 * static_cast<double>(k);
    if (std::abs(residual) <= std::max(3.0 * spacing_deg_, 0.02 * predicted)) {
      clock_ok = true;
      steps = steps_t;
      turns = k;
    }
  }
  if (!clock_ok) {
    ++stats_.clock_mismatches;
    steps = std::max(1LL, std::llround(d_az / spacing_deg_));
  }
  if (steps > 1) stats_.lost_sequences += static_cast<std::uint64_t>(steps - 1);

  const long long crossings = turns + (prev_rel_deg_ + d_az >= 360.0 ? 1 : 0);
  if (crossings == 0) {
    const long long column = prev_column_ + steps;
    if (column < scan_->columns()) {
      fill_column(static_cast<int>(column), seq, stamp_ns);
    } else {
      ++stats_.overflow_sequences;
    }
    prev_column_ = static_cast<int>(std::min<long long>(column, scan_->columns()));
  } else {
    finish_scan(true);
    start_scan(rel, seq, stamp_ns);
  }
  prev_azimuth_deg_ = seq.azimuth_deg;
  prev_rel_deg_ = rel;
  prev_sensor_us_ = sensor_us;
}

void VelodyneDecoder::start_scan(double rel_deg, const VelodyneSequence& seq,
                                 std::int64_t stamp_ns) {
  scan_.emplace(model_->rings(), model_->columns());
  filled_.assign(static_cast<std::size_t>(scan_->columns()), 0);
  int column = static_cast<int>(std::floor(rel_deg / step_deg_));
  column = std::clamp(column, 0, scan_->columns() - 1);
  first_column_ = column;
  fill_column(column, seq, stamp_ns);
  prev_column_ = column;
}

void VelodyneDecoder::fill_column(int column, const VelodyneSequence& seq, std::int64_t stamp_ns) {
  core::OrganizedScan& scan = *scan_;
  const auto c = static_cast<std::size_t>(column);
  filled_[c] = 1;
  ++stats_.sequences;
  const double base_rad = velodyne_to_ringtrack_azimuth_rad(seq.azimuth_deg);
  scan.column_azimuth_rad[c] = base_rad;
  scan.column_stamp_ns[c] = stamp_ns;
  const double cb = std::cos(base_rad);
  const double sb = std::sin(base_rad);
  const double advance_rad = seq.advance_deg * kDegToRad;
  const auto min_range = static_cast<float>(model_->min_range_m);
  const auto max_range = static_cast<float>(model_->max_range_m);
  const int lasers = layout_.lasers;
  for (int laser = 0; laser < lasers; ++laser) {
    const auto l = static_cast<std::size_t>(laser);
    const std::uint8_t* rec = seq.records[0] + 3 * l;
    if (dual_) {
      const std::uint8_t* other = seq.records[1] + 3 * l;
      const bool first_empty = read_u16(rec) == 0;
      const bool other_empty = read_u16(other) == 0;
      // Pair = (last, strongest); when the last return is also the strongest, the second block
      // holds the second strongest, recognisable by its lower reflectivity. Ties go to the
      // second block, the sensor's "strongest" block (as nebula decides them).
      if (use_last_) {
        if (first_empty) rec = other;
      } else if (!other_empty && (first_empty || other[2] >= rec[2])) {
        rec = other;
      }
    }
    const int raw = read_u16(rec);
    if (raw == 0) continue;  // a new scan's cells start as kNoReturn
    const int ring = ring_of_laser_[l];
    const auto range = static_cast<float>(raw * layout_.distance_unit_m);
    if (range < min_range) {
      scan.set_invalid(ring, column, core::ReturnStatus::kTooClose);
      continue;
    }
    if (range > max_range) {
      scan.set_invalid(ring, column, core::ReturnStatus::kTooFar);
      continue;
    }
    double cd = 0;
    double sd = 0;
    small_angle_cos_sin(laser_delta_rad_[l] - advance_rad * laser_fraction_[l], cd, sd);
    const float horizontal = range * cos_el_[l];
    const Eigen::Vector3f xyz(horizontal * static_cast<float>(cb * cd - sb * sd),
                              horizontal * static_cast<float>(sb * cd + cb * sd),
                              range * sin_el_[l] + z_offset_[l]);
    scan.set_return(ring, column, range, static_cast<float>(rec[2]), xyz);
  }
}

void VelodyneDecoder::finish_scan(bool complete) {
  if (!scan_) return;
  const bool partial = (scan_is_first_ && first_column_ != 0) || !complete;
  scan_is_first_ = false;
  if (partial && !options_.keep_partial_scans) {
    ++stats_.partial_scans_dropped;
    scan_.reset();
    return;
  }
  core::OrganizedScan& scan = *scan_;
  const int columns = scan.columns();
  // Columns without a sequence: azimuth and stamp continued from the nearest filled column.
  int anchor = -1;
  for (int c = 0; c < columns; ++c) {
    if (filled_[static_cast<std::size_t>(c)] != 0) {
      anchor = c;
      continue;
    }
    ++stats_.invalid_columns;
    const int from = anchor >= 0 ? anchor : first_column_;
    const auto f = static_cast<std::size_t>(from);
    const double steps = c - from;
    // Ringtrack azimuths decrease as the (clockwise) sensor turns.
    double az = scan.column_azimuth_rad[f] - steps * spacing_deg_ * kDegToRad;
    az = std::fmod(az, 2.0 * std::numbers::pi);
    if (az < 0) az += 2.0 * std::numbers::pi;
    scan.column_azimuth_rad[static_cast<std::size_t>(c)] = az;
    scan.column_stamp_ns[static_cast<std::size_t>(c)] =
        scan.column_stamp_ns[f] + std::llround(steps * model_->firing_sequence_us * 1e3);
  }
  scan.stamp_ns = scan.column_stamp_ns[0];
  ready_.push_back(std::move(scan));
  ++stats_.scans;
  scan_.reset();
}

void VelodyneDecoder::finish() {
  if (scan_) {
    const bool complete =
        prev_rel_deg_ >= 360.0 - 2.0 * step_deg_ || prev_column_ >= scan_->columns() - 1;
    finish_scan(complete);
  }
  have_prev_ = false;
  scan_is_first_ = true;
}

std::optional<core::OrganizedScan> VelodyneDecoder::pop_scan() {
  if (ready_.empty()) return std::nullopt;
  core::OrganizedScan scan = std::move(ready_.front());
  ready_.pop_front();
  return scan;
}

}  // namespace ringtrack::io
