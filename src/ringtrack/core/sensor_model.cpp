#include "ringtrack/core/sensor_model.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <numbers>
#include <numeric>

#include "ringtrack/core/error.hpp"

namespace ringtrack::core {
namespace {

constexpr double kDegToRad = std::numbers::pi / 180.0;

// Builds a model from per-laser tables in the sensor's own order, sorting rings bottom to top.
SensorModel from_laser_tables(std::string name, const std::vector<double>& elevation_deg,
                              const std::vector<double>& vertical_offset_mm,
                              const std::vector<double>& azimuth_offset_deg,
                              const std::vector<double>& firing_offset_us) {
  const auto n = elevation_deg.size();
  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](int a, int b) { return elevation_deg[a] < elevation_deg[b]; });
  SensorModel m;
  m.name = std::move(name);
  for (int laser : order) {
    m.elevation_rad.push_back(elevation_deg[laser] * kDegToRad);
    m.vertical_offset_m.push_back(vertical_offset_mm.empty() ? 0.0
                                                             : vertical_offset_mm[laser] / 1000.0);
    m.azimuth_offset_rad.push_back(
        azimuth_offset_deg.empty() ? 0.0 : azimuth_offset_deg[laser] * kDegToRad);
    m.firing_offset_us.push_back(firing_offset_us[laser]);
    m.laser_of_ring.push_back(laser);
  }
  return m;
}

std::string normalized(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (std::isalnum(static_cast<unsigned char>(c))) {
      out.push_back(static_cast<char>(std::tolower(static_cast<unsigned char>(c))));
    }
  }
  return out;
}

}  // namespace

double SensorModel::azimuth_step_rad() const {
  return 2.0 * std::numbers::pi * scan_rate_hz * firing_sequence_us * 1e-6;
}

int SensorModel::columns() const {
  return static_cast<int>(std::lround(2.0 * std::numbers::pi / azimuth_step_rad()));
}

int SensorModel::ring_of_laser(int laser) const {
  for (int r = 0; r < rings(); ++r) {
    if (laser_of_ring[r] == laser) return r;
  }
  throw Error("sensor model " + name + ": no ring for laser " + std::to_string(laser));
}

Eigen::Vector3f SensorModel::point(int ring, double azimuth_rad, double range_m) const {
  const double el = elevation_rad[ring];
  const double az = azimuth_rad + azimuth_offset_rad[ring];
  const double horizontal = range_m * std::cos(el);
  return {static_cast<float>(horizontal * std::cos(az)),
          static_cast<float>(horizontal * std::sin(az)),
          static_cast<float>(range_m * std::sin(el) + vertical_offset_m[ring])};
}

void SensorModel::validate() const {
  const auto n = elevation_rad.size();
  if (n == 0) throw Error("sensor model " + name + ": no rings");
  if (vertical_offset_m.size() != n || azimuth_offset_rad.size() != n ||
      laser_of_ring.size() != n || firing_offset_us.size() != n) {
    throw Error("sensor model " + name + ": per-ring tables differ in size from the elevations");
  }
  if (!std::is_sorted(elevation_rad.begin(), elevation_rad.end())) {
    throw Error("sensor model " + name + ": elevations must ascend from the bottom ring");
  }
  if (!(scan_rate_hz > 0) || !(firing_sequence_us > 0)) {
    throw Error("sensor model " + name + ": scan rate and firing sequence must be positive");
  }
  if (!(min_range_m >= 0) || !(max_range_m > min_range_m)) {
    throw Error("sensor model " + name + ": expected 0 <= min_range_m < max_range_m");
  }
}

SensorModel SensorModel::vlp16(double scan_rate_hz) {
  // VLP-16 user manual: laser ids 0..15 alternate -15,1,-13,3,...; vertical corrections in mm;
  // one laser fires every 2.304 us, a full sequence of 16 takes 55.296 us.
  const std::vector<double> elevation{-15, 1, -13, 3, -11, 5, -9, 7, -7, 9, -5, 11, -3, 13, -1, 15};
  const std::vector<double> offset_mm{11.2, -0.7, 9.7, -2.2, 8.1, -3.7, 6.6, -5.1,
                                      5.1,  -6.6, 3.7, -8.1, 2.2, -9.7, 0.7, -11.2};
  std::vector<double> firing(16);
  for (int i = 0; i < 16; ++i) firing[i] = 2.304 * i;
  SensorModel m = from_laser_tables("VLP-16", elevation, offset_mm, {}, firing);
  m.firing_sequence_us = 55.296;
  m.scan_rate_hz = scan_rate_hz;
  m.max_range_m = 100.0;
  return m;
}

SensorModel SensorModel::vlp32c(double scan_rate_hz) {
  // VLP-32C user manual: elevation and azimuth offset per laser id; lasers fire in pairs every
  // 2.304 us, a sequence of 16 firings takes 55.296 us. The manual's offsets are added to the
  // packet's clockwise azimuth; ringtrack azimuths turn counter-clockwise, hence the negation.
  // Ids 14-31 were checked against the VLP-32C User Manual (63-9325 Rev. C, sec. 9.3.2, p. 59);
  // ids 0-13 (the previous page) could not be checked here, nor any against a real VLP-32C capture.
  const std::vector<double> elevation{
      -25,    -1,     -1.667, -15.639, -11.31, 0,      -0.667, -8.843, -7.254, 0.333,  -0.333,
      -6.148, -5.333, 1.333,  0.667,   -4,     -4.667, 1.667,  1,      -3.667, -3.333, 3.333,
      2.333,  -2.667, -3,     7,       4.667,  -2.333, -2,     15,     10.333, -1.333};
  std::vector<double> azimuth{1.4,  -4.2, 1.4,  -1.4, 1.4,  -1.4, 4.2,  -1.4, 1.4,  -4.2, 1.4,
                              -1.4, 4.2,  -1.4, 4.2,  -1.4, 1.4,  -4.2, 1.4,  -4.2, 4.2,  -1.4,
                              1.4,  -1.4, 1.4,  -1.4, 1.4,  -4.2, 4.2,  -1.4, 1.4,  -1.4};
  for (double& a : azimuth) a = -a;
  std::vector<double> firing(32);
  for (int i = 0; i < 32; ++i) {
    const int pair = i / 2;  // the lasers fire in pairs, 2.304 us apart
    firing[i] = 2.304 * pair;
  }
  SensorModel m = from_laser_tables("VLP-32C", elevation, {}, azimuth, firing);
  m.firing_sequence_us = 55.296;
  m.scan_rate_hz = scan_rate_hz;
  m.max_range_m = 200.0;
  return m;
}

SensorModel SensorModel::hdl32e(double scan_rate_hz) {
  // HDL-32E user manual: laser ids alternate between the lower and upper block; one laser every
  // 1.152 us, a sequence of 32 takes 46.08 us.
  const std::vector<double> elevation{-30.67, -9.33, -29.33, -8.00, -28.00, -6.67, -26.67, -5.33,
                                      -25.33, -4.00, -24.00, -2.67, -22.67, -1.33, -21.33, 0.00,
                                      -20.00, 1.33,  -18.67, 2.67,  -17.33, 4.00,  -16.00, 5.33,
                                      -14.67, 6.67,  -13.33, 8.00,  -12.00, 9.33,  -10.67, 10.67};
  std::vector<double> firing(32);
  for (int i = 0; i < 32; ++i) firing[i] = 1.152 * i;
  SensorModel m = from_laser_tables("HDL-32E", elevation, {}, {}, firing);
  m.firing_sequence_us = 46.08;
  m.scan_rate_hz = scan_rate_hz;
  m.max_range_m = 100.0;
  return m;
}

SensorModel SensorModel::hdl64e(double scan_rate_hz) {
  // HDL-64E S2 user manual (nominal, no unit's calibration): the upper block's 32 lasers span
  // +2 .. -8.33 deg in 1/3 deg steps, the lower block's 32 lasers -8.83 .. -24.33 deg in 1/2 deg
  // steps; both blocks fire together, a firing cycle every 48 us (0.1728 deg at 10 Hz, the
  // manual's 0.0864 deg at 5 Hz). Beam origins: the blocks' lasers sit about 0.20 m (upper) and
  // 0.11 m (lower) above the sensor origin (vert_offset_correction of published S2.1 unit
  // calibrations: 0.19-0.21 m and 0.105-0.122 m). Laser ids here run top to bottom within each
  // block (the real ids interleave; they matter only to a packet decoder, which this sensor
  // does not have). A real unit's elevations differ from these by up to a few tenths of a
  // degree (docs/inputs.md).
  std::vector<double> elevation;
  std::vector<double> offset_mm;
  for (int i = 0; i < 32; ++i) {
    elevation.push_back(2.0 - i / 3.0);
    offset_mm.push_back(200.0);
  }
  for (int i = 0; i < 32; ++i) {
    elevation.push_back(-8.83 - 0.5 * i);
    offset_mm.push_back(110.0);
  }
  const std::vector<double> firing(64, 0.0);
  SensorModel m = from_laser_tables("HDL-64E", elevation, offset_mm, {}, firing);
  m.firing_sequence_us = 48.0;
  m.scan_rate_hz = scan_rate_hz;
  m.max_range_m = 120.0;
  return m;
}

SensorModel SensorModel::generic(const std::vector<double>& elevations_deg, int columns,
                                 double scan_rate_hz, double max_range_m) {
  if (elevations_deg.empty() || columns < 8) {
    throw Error("generic sensor model: expected at least one elevation and 8 columns");
  }
  std::vector<double> firing(elevations_deg.size(), 0.0);
  SensorModel m = from_laser_tables("generic", elevations_deg, {}, {}, firing);
  m.scan_rate_hz = scan_rate_hz;
  m.firing_sequence_us = 1e6 / (scan_rate_hz * columns);
  m.max_range_m = max_range_m;
  return m;
}

namespace {

constexpr const char* kHesaiNeeds =
    "its angle-correction file (--calibration FILE, with its packets; the library holds no "
    "nominal Hesai table, so its point clouds cannot be organized by name)";
constexpr const char* kOusterNeeds =
    "its metadata JSON (--metadata FILE, with its packets; beam angles differ per unit and the "
    "library holds no nominal Ouster table)";

// The one table of sensor names: --sensor, sequence.yaml and `ringtrack sensors` read it.
constexpr BuiltInSensor kBuiltIns[] = {
    {"vlp16", "Velodyne", "puck", &SensorModel::vlp16, ""},
    {"vlp32c", "Velodyne", "ultrapuck", &SensorModel::vlp32c, ""},
    {"hdl32e", "Velodyne", "hdl32", &SensorModel::hdl32e, ""},
    {"hdl64e", "Velodyne", "hdl64 hdl64es2 kitti", &SensorModel::hdl64e, ""},
    {"Pandar40P", "Hesai", "40p", nullptr, kHesaiNeeds},
    {"Pandar64", "Hesai", "p64", nullptr, kHesaiNeeds},
    {"PandarQT64", "Hesai", "qt64", nullptr, kHesaiNeeds},
    {"PandarXT16", "Hesai", "xt16", nullptr, kHesaiNeeds},
    {"PandarXT32", "Hesai", "xt32", nullptr, kHesaiNeeds},
    {"OS0/OS1/OS2", "Ouster", "os0* os1* os2* ouster*", nullptr, kOusterNeeds},
};

// True when the normalized key is the row's name or one of its space-separated aliases; an
// alias ending in '*' matches as a prefix ("os1*": os1-64, OS-1-128, ...).
bool matches(const BuiltInSensor& row, const std::string& key) {
  if (normalized(row.name) == key) return true;
  const std::string aliases = row.aliases;
  std::size_t start = 0;
  while (start < aliases.size()) {
    const std::size_t end = std::min(aliases.find(' ', start), aliases.size());
    std::string alias = aliases.substr(start, end - start);
    start = end + 1;
    if (!alias.empty() && alias.back() == '*') {
      alias.pop_back();
      if (!alias.empty() && key.rfind(alias, 0) == 0) return true;
    } else if (!alias.empty() && alias == key) {
      return true;
    }
  }
  return false;
}

}  // namespace

std::span<const BuiltInSensor> built_in_sensors() {
  return kBuiltIns;
}

std::string built_in_model_list() {
  std::vector<std::string> names;
  for (const auto& row : kBuiltIns) {
    if (row.make != nullptr) names.emplace_back(row.name);
  }
  std::string s;
  for (std::size_t i = 0; i < names.size(); ++i) {
    s += (i == 0 ? "" : (i + 1 == names.size() ? " or " : ", ")) + names[i];
  }
  return s;
}

SensorModel SensorModel::by_name(const std::string& name, double scan_rate_hz) {
  const std::string key = normalized(name);
  for (const auto& row : kBuiltIns) {
    if (!matches(row, key)) continue;
    if (row.make != nullptr) return row.make(scan_rate_hz);
    throw Error("sensor '" + name + "' (" + row.family + ") has no built-in geometry: it needs " +
                row.needs);
  }
  throw Error("unknown sensor model '" + name + "' (expected " + built_in_model_list() +
              "; `ringtrack sensors` lists every sensor)");
}

}  // namespace ringtrack::core
