#include "ringtrack/sensors/ouster/ouster_metadata.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <numeric>
#include <sstream>

#include "ringtrack/core/error.hpp"

namespace ringtrack::sensors::ouster {
namespace {

using nlohmann::json;

// A key at the top level or one level down (newer metadata nests it in sections such as
// "beam_intrinsics", "lidar_data_format", "config_params").
const json* find_key(const json& root, const char* key) {
  if (const auto it = root.find(key); it != root.end()) return &*it;
  for (const auto& [name, section] : root.items()) {
    if (!section.is_object()) continue;
    if (const auto it = section.find(key); it != section.end()) return &*it;
  }
  return nullptr;
}

[[noreturn]] void fail(const std::string& source, const std::string& what) {
  throw core::InputError(source + ": " + what);
}

const json& need(const json& root, const char* key, const std::string& source) {
  const json* v = find_key(root, key);
  if (v == nullptr) fail(source, std::string("metadata has no '") + key + "'");
  return *v;
}

std::vector<double> numbers(const json& v, const char* key, const std::string& source) {
  if (!v.is_array()) fail(source, std::string("'") + key + "' is not an array of numbers");
  std::vector<double> out;
  for (const auto& x : v) {
    if (!x.is_number()) fail(source, std::string("'") + key + "' is not an array of numbers");
    out.push_back(x.get<double>());
  }
  return out;
}

int integer(const json& v, const char* key, const std::string& source, int lo, int hi) {
  if (!v.is_number_integer() || v.get<long long>() < lo || v.get<long long>() > hi) {
    fail(source, std::string("'") + key + "' must be an integer in " + std::to_string(lo) + ".." +
                     std::to_string(hi));
  }
  return v.get<int>();
}

// The beam origin: newer metadata (firmware 3.x) gives beam_to_lidar_transform, a 4x4 row-major
// matrix whose translation is the beam origin (x out along the encoder direction, z up, mm);
// older metadata gives its distance alone (lidar_origin_to_beam_origin_mm, in the plane). The
// transform's rotation is the identity on every sensor and is not used.
void read_beam_origin(const json& root, const std::string& source, OusterMetadata& m) {
  if (const json* t = find_key(root, "beam_to_lidar_transform")) {
    const auto b = numbers(*t, "beam_to_lidar_transform", source);
    if (b.size() != 16) fail(source, "'beam_to_lidar_transform' must hold 16 numbers");
    m.beam_x_mm = b[3];
    m.beam_z_mm = b[11];
    m.origin_to_beam_mm = std::hypot(m.beam_x_mm, m.beam_z_mm);
    return;
  }
  const json& origin = need(root, "lidar_origin_to_beam_origin_mm", source);
  if (!origin.is_number()) fail(source, "'lidar_origin_to_beam_origin_mm' is not a number");
  m.origin_to_beam_mm = origin.get<double>();
  m.beam_x_mm = m.origin_to_beam_mm;
  m.beam_z_mm = 0.0;
}

}  // namespace

std::string to_string(OusterProfile profile) {
  switch (profile) {
    case OusterProfile::kLegacy:
      return "LEGACY";
    case OusterProfile::kRng19Rfl8Sig16Nir16:
      return "RNG19_RFL8_SIG16_NIR16";
    case OusterProfile::kRng19Rfl8Sig16Nir16Dual:
      return "RNG19_RFL8_SIG16_NIR16_DUAL";
    case OusterProfile::kRng15Rfl8Nir8:
      return "RNG15_RFL8_NIR8";
  }
  return "unknown";
}

std::size_t OusterMetadata::pixel_bytes() const {
  switch (profile) {
    case OusterProfile::kLegacy:
    case OusterProfile::kRng19Rfl8Sig16Nir16:
      return 12;
    case OusterProfile::kRng19Rfl8Sig16Nir16Dual:
      return 16;
    case OusterProfile::kRng15Rfl8Nir8:
      return 4;
  }
  return 12;
}

std::size_t OusterMetadata::packet_bytes() const {
  const auto cols = static_cast<std::size_t>(columns_per_packet);
  const auto pixels = static_cast<std::size_t>(pixels_per_column) * pixel_bytes();
  if (profile == OusterProfile::kLegacy) return cols * (16 + pixels + 4);
  return 32 + cols * (12 + pixels) + 32;
}

bool OusterMetadata::in_window(int m) const {
  const int a = column_window[0];
  const int b = column_window[1];
  return a <= b ? (m >= a && m <= b) : (m >= a || m <= b);
}

// Long because it reads the metadata JSON field by field (flat or nested in sections, and
// without udp_profile_lidar for firmware before 2.2; docs/ouster.md), each with its own message
// naming the key.
OusterMetadata parse_ouster_metadata(const std::string& text, const std::string& source) {
  json root;
  try {
    root = json::parse(text);
  } catch (const json::exception& e) {
    fail(source, std::string("not valid JSON (") + e.what() + ")");
  }
  if (!root.is_object()) fail(source, "metadata is not a JSON object");
  OusterMetadata m;
  m.source = source;
  if (const json* p = find_key(root, "prod_line"); p != nullptr && p->is_string()) {
    m.product = p->get<std::string>();
  }
  m.beam_altitude_deg =
      numbers(need(root, "beam_altitude_angles", source), "beam_altitude_angles", source);
  m.beam_azimuth_deg =
      numbers(need(root, "beam_azimuth_angles", source), "beam_azimuth_angles", source);
  read_beam_origin(root, source, m);
  const auto transform =
      numbers(need(root, "lidar_to_sensor_transform", source), "lidar_to_sensor_transform", source);
  if (transform.size() != 16) fail(source, "'lidar_to_sensor_transform' must hold 16 numbers");
  std::copy(transform.begin(), transform.end(), m.lidar_to_sensor.begin());
  const json& format = need(root, "data_format", source);
  if (!format.is_object()) fail(source, "'data_format' is not an object");
  m.pixels_per_column =
      integer(need(format, "pixels_per_column", source), "pixels_per_column", source, 1, 512);
  m.columns_per_packet =
      integer(need(format, "columns_per_packet", source), "columns_per_packet", source, 1, 64);
  m.columns_per_frame =
      integer(need(format, "columns_per_frame", source), "columns_per_frame", source, 64, 8192);
  const auto shifts =
      numbers(need(format, "pixel_shift_by_row", source), "pixel_shift_by_row", source);
  for (const double s : shifts) m.pixel_shift_by_row.push_back(static_cast<int>(s));
  if (const json* w = find_key(format, "column_window")) {
    const auto window = numbers(*w, "column_window", source);
    if (window.size() != 2 || window[0] < 0 || window[1] < 0 || window[0] >= m.columns_per_frame ||
        window[1] >= m.columns_per_frame) {
      fail(source, "'column_window' must be two measurement ids below columns_per_frame");
    }
    m.column_window = {static_cast<int>(window[0]), static_cast<int>(window[1])};
  } else {
    m.column_window = {0, m.columns_per_frame - 1};
  }
  // No udp_profile_lidar key: firmware before 2.2, LEGACY packets.
  if (const json* p = find_key(format, "udp_profile_lidar")) {
    const std::string name = p->is_string() ? p->get<std::string>() : "";
    if (name == "LEGACY") {
      m.profile = OusterProfile::kLegacy;
    } else if (name == "RNG19_RFL8_SIG16_NIR16") {
      m.profile = OusterProfile::kRng19Rfl8Sig16Nir16;
    } else if (name == "RNG19_RFL8_SIG16_NIR16_DUAL") {
      m.profile = OusterProfile::kRng19Rfl8Sig16Nir16Dual;
    } else if (name == "RNG15_RFL8_NIR8") {
      m.profile = OusterProfile::kRng15Rfl8Nir8;
    } else {
      fail(source, "udp_profile_lidar '" + name +
                       "' is not supported (LEGACY, RNG19_RFL8_SIG16_NIR16, its _DUAL variant, "
                       "RNG15_RFL8_NIR8)");
    }
  }
  if (const json* mode = find_key(root, "lidar_mode"); mode != nullptr && mode->is_string()) {
    const std::string s = mode->get<std::string>();  // "1024x10"
    const auto x = s.find('x');
    try {
      if (x == std::string::npos) throw std::invalid_argument(s);
      const int width = std::stoi(s.substr(0, x));
      m.scan_rate_hz = std::stod(s.substr(x + 1));
      if (width != m.columns_per_frame || !(m.scan_rate_hz >= 1 && m.scan_rate_hz <= 50)) {
        throw std::invalid_argument(s);
      }
    } catch (const std::exception&) {
      fail(source, "lidar_mode '" + s + "' does not match columns_per_frame " +
                       std::to_string(m.columns_per_frame) + " x a rate of 1..50 Hz");
    }
  }
  const auto beams = static_cast<std::size_t>(m.pixels_per_column);
  if (m.beam_altitude_deg.size() != beams || m.beam_azimuth_deg.size() != beams ||
      m.pixel_shift_by_row.size() != beams) {
    fail(source,
         "beam_altitude_angles, beam_azimuth_angles and pixel_shift_by_row must hold "
         "pixels_per_column (" +
             std::to_string(beams) + ") values each");
  }
  if (m.columns_per_frame % m.columns_per_packet != 0) {
    fail(source, "columns_per_frame is not a multiple of columns_per_packet");
  }
  return m;
}

OusterMetadata read_ouster_metadata(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw core::InputError(path.string() + ": cannot open the metadata file");
  std::stringstream text;
  text << in.rdbuf();
  return parse_ouster_metadata(text.str(), path.string());
}

core::SensorModel ouster_sensor_model(const OusterMetadata& metadata) {
  constexpr double kDegToRad = std::numbers::pi / 180.0;
  const auto n = static_cast<std::size_t>(metadata.pixels_per_column);
  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    return metadata.beam_altitude_deg[static_cast<std::size_t>(a)] <
           metadata.beam_altitude_deg[static_cast<std::size_t>(b)];
  });
  core::SensorModel m;
  m.name = metadata.product.empty() ? "Ouster-" + std::to_string(n) : metadata.product;
  for (const int beam : order) {
    const auto b = static_cast<std::size_t>(beam);
    m.elevation_rad.push_back(metadata.beam_altitude_deg[b] * kDegToRad);
    m.vertical_offset_m.push_back(0.0);
    // Ouster's beam azimuth angles are subtracted from the (counter-clockwise) encoder angle.
    m.azimuth_offset_rad.push_back(-metadata.beam_azimuth_deg[b] * kDegToRad);
    m.laser_of_ring.push_back(beam);
    m.firing_offset_us.push_back(0.0);  // all beams of a column fire together
  }
  m.scan_rate_hz = metadata.scan_rate_hz;
  m.firing_sequence_us = 1e6 / (metadata.scan_rate_hz * metadata.columns_per_frame);
  m.min_range_m = 0.3;
  m.max_range_m = 250.0;
  m.validate();
  return m;
}

}  // namespace ringtrack::sensors::ouster
