#include "ringtrack/io/pointcloud2.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <numbers>
#include <optional>
#include <sstream>

#include "ringtrack/core/error.hpp"
#include "ringtrack/io/velodyne_packet.hpp"

namespace ringtrack::io {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

template <typename T>
T load(const std::uint8_t* p) {
  T v;
  std::memcpy(&v, p, sizeof v);  // little-endian host (checked at build: x86-64 / arm64)
  return v;
}

double wrap360(double deg) {
  double a = std::fmod(deg, 360.0);
  if (a < 0) a += 360.0;
  if (a >= 360.0) a = 0.0;
  return a;
}

// Names of per-point time fields in common drivers: velodyne_pointcloud "time" (float seconds
// after the header stamp), ouster "t" (uint32 ns after it), nebula "time_stamp" (ns after it),
// hesai "timestamp" (float64 seconds since the epoch).
const PointField* find_time_field(const PointCloud2& cloud) {
  for (const char* name : {"time", "t", "time_stamp", "timestamp"}) {
    if (const PointField* f = cloud.find(name)) return f;
  }
  return nullptr;
}

// Absolute point times beyond this (the years 1843 and 2096) are no recording's: rejected, as
// they would overflow the column stamp arithmetic (found by fuzz_ros_messages).
constexpr double kMaxAbsoluteTimeNs = 4e18;

// A point's time in ns since the epoch from its time field: floating fields are seconds,
// integer fields ns; small values are offsets from the header stamp, large ones absolute.
// Non-finite values give the header stamp; nullopt for an absolute time out of range.
std::optional<std::int64_t> point_time_ns(const PointField& field, double value,
                                          std::int64_t header_ns) {
  const bool floating = field.datatype == static_cast<std::uint8_t>(PointFieldType::kFloat32) ||
                        field.datatype == static_cast<std::uint8_t>(PointFieldType::kFloat64);
  const double ns = floating ? value * 1e9 : value;
  if (!std::isfinite(ns)) return header_ns;
  if (std::abs(ns) > kMaxAbsoluteTimeNs) return std::nullopt;
  if (std::abs(ns) > 1e15) return static_cast<std::int64_t>(std::llround(ns));  // absolute
  return header_ns + static_cast<std::int64_t>(std::llround(ns));
}

}  // namespace

std::size_t point_field_type_bytes(std::uint8_t datatype) {
  switch (static_cast<PointFieldType>(datatype)) {
    case PointFieldType::kInt8:
    case PointFieldType::kUint8:
      return 1;
    case PointFieldType::kInt16:
    case PointFieldType::kUint16:
      return 2;
    case PointFieldType::kInt32:
    case PointFieldType::kUint32:
    case PointFieldType::kFloat32:
      return 4;
    case PointFieldType::kFloat64:
      return 8;
  }
  return 0;
}

const PointField* PointCloud2::find(const std::string& name) const {
  for (const auto& f : fields) {
    if (f.name == name) return &f;
  }
  return nullptr;
}

double PointCloud2::value(const PointField& field, std::uint32_t row, std::uint32_t column) const {
  const std::uint8_t* p = data.data() + static_cast<std::size_t>(row) * row_step +
                          static_cast<std::size_t>(column) * point_step + field.offset;
  switch (static_cast<PointFieldType>(field.datatype)) {
    case PointFieldType::kInt8:
      return load<std::int8_t>(p);
    case PointFieldType::kUint8:
      return load<std::uint8_t>(p);
    case PointFieldType::kInt16:
      return load<std::int16_t>(p);
    case PointFieldType::kUint16:
      return load<std::uint16_t>(p);
    case PointFieldType::kInt32:
      return load<std::int32_t>(p);
    case PointFieldType::kUint32:
      return load<std::uint32_t>(p);
    case PointFieldType::kFloat32:
      return load<float>(p);
    case PointFieldType::kFloat64:
      return load<double>(p);
  }
  return std::numeric_limits<double>::quiet_NaN();
}

PointCloud2 parse_pointcloud2(std::span<const std::uint8_t> message, RosSerialization serialization,
                              const std::string& where) {
  RosMessageCursor in(message, serialization, where + ": PointCloud2");
  PointCloud2 c;
  c.stamp_ns = in.header_stamp_ns(&c.frame_id);
  c.height = in.u32();
  c.width = in.u32();
  // A field needs at least its name length, offset, datatype and count.
  const std::uint32_t fields = in.sequence_length(13, "fields");
  c.fields.resize(fields);
  for (auto& f : c.fields) {
    f.name = in.string();
    f.offset = in.u32();
    f.datatype = in.u8();
    f.count = in.u32();
  }
  c.is_bigendian = in.u8() != 0;
  c.point_step = in.u32();
  c.row_step = in.u32();
  const std::uint32_t bytes = in.sequence_length(1, "data");
  c.data = in.bytes(bytes);
  c.is_dense = in.u8() != 0;

  const auto fail = [&where](const std::string& what) {
    throw core::InputError(where + ": PointCloud2 " + what);
  };
  if (c.is_bigendian) fail("is big endian; only little-endian clouds are supported");
  for (const auto& f : c.fields) {
    const std::size_t size = point_field_type_bytes(f.datatype);
    if (size == 0) {
      fail("field '" + f.name + "' has unknown datatype " + std::to_string(f.datatype) +
           " (expected 1..8)");
    }
    if (f.count == 0 ||
        static_cast<std::uint64_t>(f.offset) + static_cast<std::uint64_t>(size) * f.count >
            c.point_step) {
      fail("field '" + f.name + "' (offset " + std::to_string(f.offset) + ", " +
           std::to_string(f.count) + " x " + std::to_string(size) +
           " bytes) does not fit in point_step " + std::to_string(c.point_step));
    }
  }
  const std::uint64_t points = static_cast<std::uint64_t>(c.width) * c.height;
  if (points > 0) {
    if (static_cast<std::uint64_t>(c.width) * c.point_step > c.row_step) {
      fail("row_step " + std::to_string(c.row_step) + " is less than width " +
           std::to_string(c.width) + " x point_step " + std::to_string(c.point_step));
    }
    const std::uint64_t needed = static_cast<std::uint64_t>(c.row_step) * (c.height - 1) +
                                 static_cast<std::uint64_t>(c.width) * c.point_step;
    if (c.data.size() < needed) {
      fail("data holds " + std::to_string(c.data.size()) + " bytes, expected " +
           std::to_string(needed) + " for " + std::to_string(c.height) + " x " +
           std::to_string(c.width) + " points");
    }
  }
  return c;
}

namespace {

// The scan rate and cut azimuth the grid is laid out with; throws core::ConfigError.
void check_grid_options(const PointCloud2Options& options) {
  if (!(options.scan_rate_hz >= 1.0 && options.scan_rate_hz <= 50.0)) {
    throw core::ConfigError("point cloud scan rate " + std::to_string(options.scan_rate_hz) +
                            " Hz: expected 1..50");
  }
  if (!std::isfinite(options.cut_azimuth_deg)) {
    throw core::ConfigError("point cloud cut azimuth: expected a finite number of degrees");
  }
}

// The packet decoder's grid for points whose ring is known: a point's cell is its ring and the
// column of its firing azimuth; a cell hit twice keeps the nearer point. Shared by clouds with a
// ring field (or organized rows) and by organize_points.
class RingGrid {
 public:
  RingGrid(const core::SensorModel& model, const PointCloud2Options& options,
           PointCloud2Stats& stats)
      : model_(model),
        options_(options),
        stats_(stats),
        columns_(model.columns()),
        step_deg_(360.0 / columns_),
        period_ns_(1e9 / (options.scan_rate_hz * columns_)),
        scan_(model.rings(), columns_),
        has_azimuth_(static_cast<std::size_t>(columns_), 0),
        first_ns_(static_cast<std::size_t>(columns_), core::kNoColumnTime),
        min_range_(static_cast<float>(model.min_range_m)),
        max_range_(static_cast<float>(model.max_range_m)) {}

  // A return of `ring` at x y z (sensor frame) with its measured range (finite, > 0) and, when
  // the cloud has one, its time.
  void place(int ring, double x, double y, double z, double range, float intensity,
             std::optional<std::int64_t> time_ns) {
    const auto r = static_cast<std::size_t>(ring);
    // The azimuth of the point's firing sequence: undo the laser's azimuth offset and the
    // rotation during its firing delay (ringtrack azimuths turn against the sensor).
    const double firing_rad = std::atan2(y, x) - model_.azimuth_offset_rad[r] +
                              kTwoPi * options_.scan_rate_hz * model_.firing_offset_us[r] * 1e-6;
    const double velodyne_deg = -firing_rad * 180.0 / std::numbers::pi;
    const double rel = wrap360(velodyne_deg - options_.cut_azimuth_deg);
    const int column = std::min(columns_ - 1, static_cast<int>(rel / step_deg_));
    const auto c = static_cast<std::size_t>(column);
    if (has_azimuth_[c] == 0) {
      has_azimuth_[c] = 1;
      scan_.column_azimuth_rad[c] = velodyne_to_ringtrack_azimuth_rad(velodyne_deg);
    }
    if (time_ns) first_ns_[c] = std::min(first_ns_[c], *time_ns);
    const std::size_t i = scan_.index(ring, column);
    const auto range_f = static_cast<float>(range);
    if (scan_.valid(i)) {
      ++stats_.dropped_points;
      if (range_f >= scan_.range_m(i)) return;
    }
    if (range_f < min_range_ || range_f > max_range_) {
      if (!scan_.valid(i)) {
        scan_.set_invalid(
            ring, column,
            range_f < min_range_ ? core::ReturnStatus::kTooClose : core::ReturnStatus::kTooFar);
      }
      return;
    }
    scan_.set_return(
        ring, column, range_f, intensity,
        Eigen::Vector3f(static_cast<float>(x), static_cast<float>(y), static_cast<float>(z)));
  }

  // The scan. Columns without points: nominal azimuths; stamps continued from the nearest timed
  // column at the nominal column period (or from the cloud's stamp without times).
  core::OrganizedScan finish(std::int64_t cloud_stamp_ns) {
    for (int c = 0; c < columns_; ++c) {
      const auto u = static_cast<std::size_t>(c);
      if (has_azimuth_[u] == 0) {
        scan_.column_azimuth_rad[u] =
            velodyne_to_ringtrack_azimuth_rad(options_.cut_azimuth_deg + (c + 0.5) * step_deg_);
      }
    }
    core::stamp_columns(scan_, first_ns_, cloud_stamp_ns, period_ns_);
    scan_.stamp_ns = scan_.column_stamp_ns[0];
    return std::move(scan_);
  }

 private:
  const core::SensorModel& model_;
  const PointCloud2Options& options_;
  PointCloud2Stats& stats_;
  int columns_;
  double step_deg_;
  double period_ns_;
  core::OrganizedScan scan_;
  std::vector<std::uint8_t> has_azimuth_;
  std::vector<std::int64_t> first_ns_;
  float min_range_, max_range_;
};

// Whether an organized cloud without a ring field holds its top ring in row 0: drivers differ
// (velodyne_pointcloud puts the bottom ring first, image-like drivers the top).
bool top_row_first(const PointCloud2& cloud, const PointField& fx, const PointField& fy,
                   const PointField& fz) {
  const auto row_elevation = [&](std::uint32_t r) {
    double sum = 0;
    int n = 0;
    for (std::uint32_t c = 0; c < cloud.width; ++c) {
      const double x = cloud.value(fx, r, c);
      const double y = cloud.value(fy, r, c);
      const double z = cloud.value(fz, r, c);
      if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z)) continue;
      if (x == 0 && y == 0 && z == 0) continue;
      sum += std::atan2(z, std::hypot(x, y));
      ++n;
    }
    return n > 0 ? std::optional<double>(sum / n) : std::nullopt;
  };
  std::optional<double> low;
  std::optional<double> high;
  for (std::uint32_t r = 0; r < cloud.height && !low; ++r) low = row_elevation(r);
  for (std::uint32_t r = cloud.height; r-- > 0 && !high;) high = row_elevation(r);
  return low && high && *low > *high;
}

// The time of an organized cloud's point; throws core::InputError naming the point when its time
// field holds no time.
std::int64_t cloud_point_time(const PointCloud2& cloud, const PointField& ftime, std::uint32_t row,
                              std::uint32_t col, const std::string& where) {
  const double value = cloud.value(ftime, row, col);
  const auto time = point_time_ns(ftime, value, cloud.stamp_ns);
  if (!time) {
    std::ostringstream what;
    what << where << ": point (row " << row << ", column " << col << ") has time field '"
         << ftime.name << "' = " << value
         << ", not a time (expected an offset from the header stamp or a stamp within +-4e18 ns "
            "of the epoch)";
    throw core::InputError(what.str());
  }
  return *time;
}

// Rings a cloud holds: one more than its largest ring value (below 1024), or its rows when it
// has no ring field (an organized cloud: one row per ring).
int count_rings(const PointCloud2& cloud, const PointField* fring, std::uint32_t point_rows) {
  if (fring == nullptr) return static_cast<int>(cloud.height);
  int rings = 0;
  for (std::uint32_t r = 0; r < point_rows; ++r) {
    for (std::uint32_t c = 0; c < cloud.width; ++c) {
      const double v = cloud.value(*fring, r, c);
      if (v >= 0 && v < 1024) rings = std::max(rings, static_cast<int>(v) + 1);
    }
  }
  return rings;
}

}  // namespace

core::OrganizedScan organize_points(const RingedPoints& points, const core::SensorModel& model,
                                    const PointCloud2Options& options, PointCloud2Stats* stats) {
  check_grid_options(options);
  const std::size_t n = points.xyz.size();
  const auto check_size = [n](std::size_t size, const char* what) {
    if (size != n) {
      throw core::InputError("organize_points: " + std::to_string(size) + " " + what + " for " +
                             std::to_string(n) + " points");
    }
  };
  check_size(points.ring.size(), "rings");
  if (!points.intensity.empty()) check_size(points.intensity.size(), "intensities");
  if (!points.time_ns.empty()) check_size(points.time_ns.size(), "times");
  PointCloud2Stats own;
  PointCloud2Stats& counts = stats != nullptr ? *stats : own;
  RingGrid grid(model, options, counts);
  ++counts.clouds;
  for (std::size_t k = 0; k < n; ++k) {
    ++counts.points;
    const double x = points.xyz[k].x(), y = points.xyz[k].y(), z = points.xyz[k].z();
    if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z) ||
        (x == 0 && y == 0 && z == 0)) {
      ++counts.empty_points;
      continue;
    }
    const int ring = points.ring[k];
    if (ring >= model.rings()) {
      ++counts.bad_ring_points;
      continue;
    }
    const double dz = z - model.vertical_offset_m[static_cast<std::size_t>(ring)];
    const double range = std::sqrt(x * x + y * y + dz * dz);
    const float intensity = points.intensity.empty() ? 0.0f : points.intensity[k];
    const auto time =
        points.time_ns.empty() ? std::nullopt : std::optional<std::int64_t>(points.time_ns[k]);
    grid.place(ring, x, y, z, range, intensity, time);
  }
  return grid.finish(points.stamp_ns);
}

PointCloud2Organizer::PointCloud2Organizer(PointCloud2Options options)
    : options_(std::move(options)) {
  check_grid_options(options_);
  if (!options_.model.empty()) {
    try {
      model_ = core::SensorModel::by_name(options_.model, options_.scan_rate_hz);
    } catch (const core::ConfigError&) {
      throw;
    } catch (const core::Error& e) {
      throw core::ConfigError(std::string("point cloud model: ") + e.what());
    }
  }
}

const core::SensorModel& PointCloud2Organizer::model() const {
  if (!model_) throw core::Error("point cloud organizer: the model is not known before a cloud");
  return *model_;
}

core::OrganizedScan PointCloud2Organizer::organize_ringless(const PointCloud2& cloud,
                                                            const std::string& where) {
  const PointField* fx = cloud.find("x");
  const PointField* fy = cloud.find("y");
  const PointField* fz = cloud.find("z");
  const PointField* fi = cloud.find("intensity");
  const PointField* ftime = find_time_field(cloud);
  core::UnorganizedCloud points;
  points.stamp_ns = cloud.stamp_ns;
  const std::uint32_t width = cloud.height == 0 ? 0 : cloud.width;
  points.xyz.reserve(width);
  if (fi != nullptr) points.intensity.reserve(width);
  if (ftime != nullptr) points.time_ns.reserve(width);
  for (std::uint32_t col = 0; col < width; ++col) {
    points.xyz.emplace_back(static_cast<float>(cloud.value(*fx, 0, col)),
                            static_cast<float>(cloud.value(*fy, 0, col)),
                            static_cast<float>(cloud.value(*fz, 0, col)));
    if (fi != nullptr) points.intensity.push_back(static_cast<float>(cloud.value(*fi, 0, col)));
    if (ftime != nullptr) {
      const double value = cloud.value(*ftime, 0, col);
      const auto t = point_time_ns(*ftime, value, cloud.stamp_ns);
      if (!t) {
        std::ostringstream what;
        what << where << ": point " << col << " has time field '" << ftime->name << "' = " << value
             << ", not a time (expected an offset from the header stamp or a stamp within +-4e18 "
                "ns of the epoch)";
        throw core::InputError(what.str());
      }
      points.time_ns.push_back(*t);
    }
  }
  if (!model_) {
    model_ = core::measure_cloud_sensor(
        points, where + ": PointCloud2 without a '" + options_.ring_field + "' field",
        options_.scan_rate_hz);
  }
  if (!ringless_) {
    // The packet decoder's grid: clockwise columns from the cut azimuth, firing delays undone.
    core::CloudOrganizerOptions grid;
    grid.clockwise = true;
    grid.undo_firing_rotation = true;
    grid.first_column_azimuth_rad = velodyne_to_ringtrack_azimuth_rad(
        options_.cut_azimuth_deg + 0.5 * 360.0 / model_->columns());
    ringless_.emplace(*model_, grid);
  }
  core::OrganizedCloud organized = ringless_->organize(points);
  const core::CloudOrganizeStats& s = organized.stats;
  ++stats_.clouds;
  stats_.points += s.points;
  stats_.empty_points += s.non_finite + s.at_origin;
  stats_.dropped_points += s.collided;
  stats_.ringless.add(s);
  return std::move(organized.scan);
}

namespace {

// A point's ring: its ring field, else its row (a cloud of one row per ring, the top ring first
// when flip_rows); -1 when the field holds no ring of the model.
int ring_of_point(const PointCloud2& cloud, const PointField* fring, bool flip_rows, int rings,
                  std::uint32_t row, std::uint32_t col) {
  if (fring == nullptr) {
    return flip_rows ? rings - 1 - static_cast<int>(row) : static_cast<int>(row);
  }
  const double v = cloud.value(*fring, row, col);
  return v >= 0 && v < rings ? static_cast<int>(v) : -1;
}

}  // namespace

core::OrganizedScan PointCloud2Organizer::organize(const PointCloud2& cloud,
                                                   const std::string& where) {
  const auto fail = [&where](const std::string& what) {
    throw core::InputError(where + ": PointCloud2 " + what);
  };
  const PointField* fx = cloud.find("x");
  const PointField* fy = cloud.find("y");
  const PointField* fz = cloud.find("z");
  if (fx == nullptr || fy == nullptr || fz == nullptr) fail("has no x, y and z fields");
  const PointField* fi = cloud.find("intensity");
  const PointField* fring = cloud.find(options_.ring_field);
  const PointField* ftime = find_time_field(cloud);
  const PointField* fdistance = cloud.find("distance");
  if (fring == nullptr && cloud.height <= 1) return organize_ringless(cloud, where);

  // Rows holding points: none when the width is 0, whatever the height says (fuzz_ros_messages
  // found a cloud of width 0 and 1.6 billion rows that took 11 s to walk doing nothing).
  const std::uint32_t point_rows = cloud.width == 0 ? 0 : cloud.height;

  const int cloud_rings = count_rings(cloud, fring, point_rows);
  if (!model_) {
    if (cloud_rings > 16) {
      fail("has " + std::to_string(cloud_rings) + " rings: name the sensor model (" +
           core::built_in_model_list() + ")");
    }
    model_ = core::SensorModel::vlp16(options_.scan_rate_hz);
  }
  const core::SensorModel& model = *model_;
  const int rings = model.rings();
  if (fring == nullptr && cloud_rings != rings) {
    fail("has " + std::to_string(cloud.height) + " rows, expected one per ring of the " +
         model.name + " (" + std::to_string(rings) + ") or a '" + options_.ring_field + "' field");
  }
  const bool flip_rows = fring == nullptr && top_row_first(cloud, *fx, *fy, *fz);

  RingGrid grid(model, options_, stats_);
  ++stats_.clouds;
  for (std::uint32_t row = 0; row < point_rows; ++row) {
    for (std::uint32_t col = 0; col < cloud.width; ++col) {
      ++stats_.points;
      const double x = cloud.value(*fx, row, col);
      const double y = cloud.value(*fy, row, col);
      const double z = cloud.value(*fz, row, col);
      if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z) ||
          (x == 0 && y == 0 && z == 0)) {
        ++stats_.empty_points;
        continue;
      }
      const int ring = ring_of_point(cloud, fring, flip_rows, rings, row, col);
      if (ring < 0) {
        ++stats_.bad_ring_points;
        continue;
      }
      // The measured distance: the driver's own, else from the beam origin (the point less the
      // ring's vertical offset), as the packet decoder reports it.
      const double dz = z - model.vertical_offset_m[static_cast<std::size_t>(ring)];
      const double range = fdistance != nullptr ? cloud.value(*fdistance, row, col)
                                                : std::sqrt(x * x + y * y + dz * dz);
      if (!std::isfinite(range) || range <= 0.0) {
        ++stats_.empty_points;
        continue;
      }
      const auto time = ftime != nullptr
                            ? std::optional(cloud_point_time(cloud, *ftime, row, col, where))
                            : std::nullopt;
      const float intensity = fi != nullptr ? static_cast<float>(cloud.value(*fi, row, col)) : 0.0f;
      grid.place(ring, x, y, z, range, intensity, time);
    }
  }
  return grid.finish(cloud.stamp_ns);
}

}  // namespace ringtrack::io
