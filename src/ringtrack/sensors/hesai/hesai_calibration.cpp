#include "ringtrack/sensors/hesai/hesai_calibration.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <numbers>
#include <numeric>
#include <sstream>

#include "ringtrack/core/error.hpp"

namespace ringtrack::sensors::hesai {
namespace {

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r\n");
  if (b == std::string::npos) return {};
  const auto e = s.find_last_not_of(" \t\r\n");
  return s.substr(b, e - b + 1);
}

bool parse_number(const std::string& text, double& value) {
  const std::string t = trim(text);
  if (t.empty()) return false;
  std::size_t used = 0;
  try {
    value = std::stod(t, &used);
  } catch (const std::exception&) {
    return false;
  }
  return used == t.size() && std::isfinite(value);
}

}  // namespace

void HesaiCalibration::check(const HesaiFormat& format) const {
  if (channels() != format.channels) {
    throw core::InputError(source + ": " + std::to_string(channels()) + " channels, but " +
                           format.name + " packets have " + std::to_string(format.channels) +
                           " (wrong calibration file for this sensor?)");
  }
}

HesaiCalibration parse_hesai_calibration(const std::string& text, const std::string& source) {
  HesaiCalibration cal;
  cal.source = source;
  std::istringstream in(text);
  std::string line;
  int line_no = 0;
  std::vector<int> ids;
  std::vector<double> elevation;
  std::vector<double> azimuth;
  bool header_seen = false;
  while (std::getline(in, line)) {
    ++line_no;
    const std::string t = trim(line);
    if (t.empty() || t[0] == '#') continue;
    std::vector<std::string> cells;
    std::stringstream ls(t);
    for (std::string cell; std::getline(ls, cell, ',');) cells.push_back(cell);
    double id = 0;
    if (!header_seen && !parse_number(cells[0], id)) {  // "Channel,Elevation,Azimuth"
      header_seen = true;
      continue;
    }
    header_seen = true;
    const std::string where = source + ":" + std::to_string(line_no);
    double el = 0;
    double az = 0;
    if (cells.size() < 3 || !parse_number(cells[0], id) || !parse_number(cells[1], el) ||
        !parse_number(cells[2], az)) {
      throw core::InputError(where + ": expected 'channel,elevation,azimuth' numbers, got '" + t +
                             "'");
    }
    if (id != std::floor(id) || id < 1 || id > 512) {
      throw core::InputError(where + ": channel " + trim(cells[0]) + " (expected 1..512)");
    }
    if (std::abs(el) > 90.0 || std::abs(az) > 180.0) {
      throw core::InputError(where +
                             ": angles out of range (elevation within +-90, azimuth "
                             "within +-180 degrees)");
    }
    const int channel = static_cast<int>(id);
    if (std::find(ids.begin(), ids.end(), channel) != ids.end()) {
      throw core::InputError(where + ": channel " + std::to_string(channel) + " appears twice");
    }
    ids.push_back(channel);
    elevation.push_back(el);
    azimuth.push_back(az);
  }
  if (ids.empty()) throw core::InputError(source + ": no channels (expected CSV rows)");
  const int n = static_cast<int>(ids.size());
  cal.elevation_deg.assign(static_cast<std::size_t>(n), 0.0);
  cal.azimuth_deg.assign(static_cast<std::size_t>(n), 0.0);
  for (int i = 0; i < n; ++i) {
    const int channel = ids[static_cast<std::size_t>(i)];
    if (channel > n) {
      throw core::InputError(source + ": channel " + std::to_string(channel) + " but only " +
                             std::to_string(n) + " rows (channels must run 1.." +
                             std::to_string(n) + "; one missing?)");
    }
    cal.elevation_deg[static_cast<std::size_t>(channel - 1)] =
        elevation[static_cast<std::size_t>(i)];
    cal.azimuth_deg[static_cast<std::size_t>(channel - 1)] = azimuth[static_cast<std::size_t>(i)];
  }
  return cal;
}

HesaiCalibration read_hesai_calibration(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw core::InputError(path.string() + ": cannot open the calibration file");
  std::stringstream text;
  text << in.rdbuf();
  return parse_hesai_calibration(text.str(), path.string());
}

core::SensorModel hesai_sensor_model(const HesaiFormat& format, const HesaiCalibration& calibration,
                                     double scan_rate_hz) {
  calibration.check(format);
  constexpr double kDegToRad = std::numbers::pi / 180.0;
  const auto n = static_cast<std::size_t>(format.channels);
  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    return calibration.elevation_deg[static_cast<std::size_t>(a)] <
           calibration.elevation_deg[static_cast<std::size_t>(b)];
  });
  core::SensorModel m;
  m.name = format.name;
  for (const int channel : order) {
    const auto c = static_cast<std::size_t>(channel);
    m.elevation_rad.push_back(calibration.elevation_deg[c] * kDegToRad);
    m.vertical_offset_m.push_back(0.0);
    // Hesai azimuths turn clockwise; ringtrack's counter-clockwise (docs/hesai.md).
    m.azimuth_offset_rad.push_back(-calibration.azimuth_deg[c] * kDegToRad);
    m.laser_of_ring.push_back(channel);
    m.firing_offset_us.push_back(0.0);  // per-channel firing times are not modelled
  }
  m.scan_rate_hz = scan_rate_hz;
  // One column per block; columns_at_10hz blocks per revolution at 10 Hz.
  m.firing_sequence_us = 1e6 / (10.0 * format.columns_at_10hz);
  m.min_range_m = format.default_min_range_m;
  m.max_range_m = format.default_max_range_m;
  m.validate();
  return m;
}

}  // namespace ringtrack::sensors::hesai
