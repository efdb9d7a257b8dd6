#include "ringtrack/core/cloud_organizer.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <utility>

#include "ringtrack/core/error.hpp"

namespace ringtrack::core {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;
constexpr double kRadToDeg = 180.0 / std::numbers::pi;
constexpr double kDegToRad = std::numbers::pi / 180.0;

double wrap_two_pi(double a) {
  a -= kTwoPi * std::floor(a / kTwoPi);
  return a >= kTwoPi ? 0.0 : a;
}

// atan2 within 1e-5 rad (the polynomial of sim::fast_atan2): enough to pick a ring (windows of
// 1.4e-3 rad and more) and a column (half a VLP-16 column is 1.7e-3 rad); libm's atan2 took 40 %
// of the organizer's time.
double fast_atan2(double y, double x) {
  const double ax = std::abs(x);
  const double ay = std::abs(y);
  const double mx = std::max(ax, ay);
  if (mx == 0.0) return 0.0;
  const double a = std::min(ax, ay) / mx;
  const double s = a * a;
  double r = ((-0.0464964749 * s + 0.15931422) * s - 0.327622764) * s * a + a;
  if (ay > ax) r = 0.5 * std::numbers::pi - r;
  if (x < 0) r = std::numbers::pi - r;
  return y < 0 ? -r : r;
}

// The exact angle between the direction (h, z) and elevation `el` (cos_el, sin_el): the direction
// turned by -el has a small slope t, whose atan is its series to t^7 (error below 1e-8 rad for
// |t| < 0.2, i.e. residuals under 11 degrees; libm beyond).
double residual_rad(double h, double z, double cos_el, double sin_el) {
  const double u = h * cos_el + z * sin_el;
  const double v = z * cos_el - h * sin_el;
  if (!(u > 0.0) || std::abs(v) > 0.2 * u) return std::atan2(v, u);
  const double t = v / u;
  const double t2 = t * t;
  return t * (1.0 - t2 * (1.0 / 3.0 - t2 * (1.0 / 5.0 - t2 / 7.0)));
}

// The ring nearest to a point (h horizontal distance, z height) seen from each ring's own beam
// origin, and the signed residual (within 1e-5 rad); ring -1 when none is finite. Beam origins
// between min_off and max_off metres above the sensor shift the elevation seen from the sensor
// origin by at most off / h: only the rings inside that span (and one beyond) are candidates,
// which is two for models without offsets and a few for the VLP-16 (11 mm), more near a sensor
// whose beams start 0.2 m up.
std::pair<int, double> nearest_ring(double h, double z, const std::vector<double>& el,
                                    const std::vector<double>& voff, double min_off,
                                    double max_off) {
  const int rings = static_cast<int>(el.size());
  const double lo_e = fast_atan2(z - max_off, h);
  const double hi_e = max_off == min_off ? lo_e : fast_atan2(z - min_off, h);
  const int lo = static_cast<int>(std::upper_bound(el.begin(), el.end(), lo_e) - el.begin()) - 1;
  const int hi = static_cast<int>(std::upper_bound(el.begin(), el.end(), hi_e) - el.begin());
  int ring = -1;
  double residual = std::numeric_limits<double>::infinity();
  for (int r = std::max(0, lo); r <= std::min(rings - 1, hi); ++r) {
    const auto u = static_cast<std::size_t>(r);
    const double e = voff[u] == max_off   ? lo_e
                     : voff[u] == min_off ? hi_e
                                          : fast_atan2(z - voff[u], h);
    const double d = e - el[u];
    if (std::abs(d) < std::abs(residual)) {
      residual = d;
      ring = r;
    }
  }
  return {ring, residual};
}

bool is_return(const Eigen::Vector3f& p) {
  return p.x() != 0.0f || p.y() != 0.0f || p.z() != 0.0f;
}

// f applied to each value.
template <typename F>
std::vector<double> each(const std::vector<double>& values, F f) {
  std::vector<double> out(values.size());
  std::transform(values.begin(), values.end(), out.begin(), f);
  return out;
}

// A point into its cell: out of range marks an empty cell too close or too far; a cell hit
// twice keeps the nearer point (both counted).
void place_return(OrganizedScan& scan, CloudOrganizeStats& stats, int ring, int column,
                  double range, double min_range, double max_range, float intensity,
                  const Eigen::Vector3f& p) {
  const std::size_t cell = scan.index(ring, column);
  if (range < min_range || range > max_range) {
    ++stats.out_of_range;
    if (!scan.valid(cell)) {
      scan.set_invalid(ring, column,
                       range < min_range ? ReturnStatus::kTooClose : ReturnStatus::kTooFar);
    }
    return;
  }
  if (scan.valid(cell)) {
    ++stats.collided;
    if (static_cast<float>(range) >= scan.range_m(cell)) return;
  }
  scan.set_return(ring, column, static_cast<float>(range),
                  std::isfinite(intensity) ? intensity : 0.0f, p);
}

// Intensities and times, when given, must be one per point.
void check_sizes(const UnorganizedCloud& cloud) {
  const std::size_t n = cloud.size();
  if (!cloud.intensity.empty() && cloud.intensity.size() != n) {
    throw InputError("cloud organizer: " + std::to_string(cloud.intensity.size()) +
                     " intensities for " + std::to_string(n) + " points");
  }
  if (!cloud.time_ns.empty() && cloud.time_ns.size() != n) {
    throw InputError("cloud organizer: " + std::to_string(cloud.time_ns.size()) + " times for " +
                     std::to_string(n) + " points");
  }
}

// Median, 95th percentile and largest of the kept points' elevation residuals (reorders them).
void summarise_residuals(std::vector<float>& residual_deg, CloudOrganizeStats& stats) {
  if (residual_deg.empty()) return;
  const auto mid = residual_deg.begin() + static_cast<std::ptrdiff_t>(residual_deg.size() / 2);
  std::nth_element(residual_deg.begin(), mid, residual_deg.end());
  stats.median_elevation_error_deg = *mid;
  const auto p95 = residual_deg.begin() +
                   static_cast<std::ptrdiff_t>(0.95 * static_cast<double>(residual_deg.size() - 1));
  std::nth_element(residual_deg.begin(), p95, residual_deg.end());
  stats.p95_elevation_error_deg = *p95;
  stats.max_elevation_error_deg = *std::max_element(residual_deg.begin(), residual_deg.end());
}

}  // namespace

void CloudOrganizeTotals::add(const CloudOrganizeStats& s) {
  ++clouds;
  sum.points += s.points;
  sum.organized += s.organized;
  sum.non_finite += s.non_finite;
  sum.at_origin += s.at_origin;
  sum.between_rings += s.between_rings;
  sum.collided += s.collided;
  sum.out_of_range += s.out_of_range;
  sum.median_elevation_error_deg =
      std::max(sum.median_elevation_error_deg, s.median_elevation_error_deg);
  sum.p95_elevation_error_deg = std::max(sum.p95_elevation_error_deg, s.p95_elevation_error_deg);
  sum.max_elevation_error_deg = std::max(sum.max_elevation_error_deg, s.max_elevation_error_deg);
}

std::string CloudOrganizeTotals::summary() const {
  const auto share = [this](std::uint64_t n) {
    return sum.points > 0 ? 100.0 * static_cast<double>(n) / static_cast<double>(sum.points) : 0.0;
  };
  char line[512];
  std::snprintf(line, sizeof line,
                "organized %llu cloud%s: %llu of %llu points in cells (%.2f %%); dropped: %llu "
                "between rings (%.2f %%), %llu collided (%.2f %%), %llu out of range; skipped: "
                "%llu NaN, %llu at the origin; elevation error (deg, worst cloud): median %.3f, "
                "p95 %.3f, max %.3f",
                static_cast<unsigned long long>(clouds), clouds == 1 ? "" : "s",
                static_cast<unsigned long long>(sum.organized),
                static_cast<unsigned long long>(sum.points), share(sum.organized),
                static_cast<unsigned long long>(sum.between_rings), share(sum.between_rings),
                static_cast<unsigned long long>(sum.collided), share(sum.collided),
                static_cast<unsigned long long>(sum.out_of_range),
                static_cast<unsigned long long>(sum.non_finite),
                static_cast<unsigned long long>(sum.at_origin), sum.median_elevation_error_deg,
                sum.p95_elevation_error_deg, sum.max_elevation_error_deg);
  return line;
}

CloudOrganizer::CloudOrganizer(SensorModel model, CloudOrganizerOptions options)
    : model_(std::move(model)), options_(options) {
  try {
    model_.validate();
  } catch (const ConfigError&) {
    throw;
  } catch (const Error& e) {
    throw ConfigError(std::string("cloud organizer: ") + e.what());
  }
  if (!(options_.ring_window > 0.0 && options_.ring_window <= 0.5)) {
    throw ConfigError("cloud organizer: ring_window " + std::to_string(options_.ring_window) +
                      ": expected a fraction of the ring gap in (0, 0.5]");
  }
  if (!std::isfinite(options_.first_column_azimuth_rad)) {
    throw ConfigError("cloud organizer: first_column_azimuth_rad must be finite");
  }
  columns_ = model_.columns();
  if (columns_ < 1 || columns_ > 1'000'000) {
    throw ConfigError("cloud organizer: the model " + model_.name + " has " +
                      std::to_string(columns_) + " columns, expected 1..1000000");
  }
  step_rad_ = kTwoPi / columns_;
  const int rings = model_.rings();
  const auto& el = model_.elevation_rad;
  below_rad_.resize(static_cast<std::size_t>(rings));
  above_rad_.resize(static_cast<std::size_t>(rings));
  column_shift_rad_.resize(static_cast<std::size_t>(rings));
  // The sensor turns by this much per microsecond (clockwise sensors towards smaller azimuths).
  const double turn_per_us = kTwoPi * model_.scan_rate_hz * 1e-6;
  for (int r = 0; r < rings; ++r) {
    const auto u = static_cast<std::size_t>(r);
    // One ring: a window of the VLP-16's 2 degree gap; outer rings mirror their inner gap.
    double below = r > 0 ? el[u] - el[u - 1] : (rings > 1 ? el[1] - el[0] : 2.0 * kDegToRad);
    double above = r + 1 < rings ? el[u + 1] - el[u] : below;
    if (r == 0) below = above;
    below_rad_[u] = options_.ring_window * below;
    above_rad_[u] = options_.ring_window * above;
    double shift = -model_.azimuth_offset_rad[u];
    if (options_.undo_firing_rotation) {
      const double turn = turn_per_us * model_.firing_offset_us[u];
      shift += options_.clockwise ? turn : -turn;
    }
    column_shift_rad_[u] = shift;
    if (model_.vertical_offset_m[u] != 0.0) has_offsets_ = true;
  }
}

bool CloudOrganizer::offsets_fit_better(const UnorganizedCloud& cloud) const {
  const auto& el = model_.elevation_rad;
  const auto& voff = model_.vertical_offset_m;
  const std::vector<double> zeros(voff.size(), 0.0);
  const double min_off = std::min(0.0, *std::min_element(voff.begin(), voff.end()));
  const double max_off = std::max(0.0, *std::max_element(voff.begin(), voff.end()));
  const std::size_t n = cloud.size();
  const std::size_t stride = std::max<std::size_t>(1, n / 4096);
  double with = 0.0;
  double without = 0.0;
  for (std::size_t i = 0; i < n; i += stride) {
    const Eigen::Vector3f& p = cloud.xyz[i];
    if (!p.allFinite() || !is_return(p)) continue;
    const double x = p.x();
    const double y = p.y();
    const double z = p.z();
    const double h = std::sqrt(x * x + y * y);
    const double best_with = std::abs(nearest_ring(h, z, el, voff, min_off, max_off).second);
    const double best_without = std::abs(nearest_ring(h, z, el, zeros, 0.0, 0.0).second);
    with += best_with;
    without += best_without;
  }
  return with <= without;
}

void stamp_columns(OrganizedScan& scan, const std::vector<std::int64_t>& first_ns,
                   std::int64_t stamp_ns, double period_ns) {
  const int columns = scan.columns();
  const auto timed = [&](int c) {
    return !first_ns.empty() && first_ns[static_cast<std::size_t>(c)] != kNoColumnTime;
  };
  int anchor = -1;  // the last timed column, or the first one for the columns before it
  for (int c = 0; c < columns && anchor < 0; ++c) {
    if (timed(c)) anchor = c;
  }
  for (int c = 0; c < columns; ++c) {
    const auto u = static_cast<std::size_t>(c);
    if (timed(c)) {
      anchor = c;
      scan.column_stamp_ns[u] = first_ns[u];
    } else if (anchor < 0) {
      scan.column_stamp_ns[u] = stamp_ns + std::llround(c * period_ns);
    } else {
      scan.column_stamp_ns[u] =
          first_ns[static_cast<std::size_t>(anchor)] + std::llround((c - anchor) * period_ns);
    }
  }
}

void CloudOrganizer::set_columns(OrganizedScan& scan, const std::vector<std::int64_t>& first_ns,
                                 std::int64_t stamp_ns) const {
  const double first = options_.first_column_azimuth_rad;
  for (int c = 0; c < columns_; ++c) {
    scan.column_azimuth_rad[static_cast<std::size_t>(c)] =
        wrap_two_pi(first + (options_.clockwise ? -c : c) * step_rad_);
  }
  stamp_columns(scan, first_ns, stamp_ns, 1e9 / (model_.scan_rate_hz * columns_));
}

OrganizedCloud CloudOrganizer::organize(const UnorganizedCloud& cloud) const {
  check_sizes(cloud);
  const std::size_t n = cloud.size();
  const int rings = model_.rings();
  const auto& el = model_.elevation_rad;
  bool offsets = has_offsets_;
  if (offsets && options_.beam_origins != BeamOrigins::kModel) {
    offsets = options_.beam_origins == BeamOrigins::kAuto && offsets_fit_better(cloud);
  }
  const std::vector<double> no_offsets(offsets ? 0 : el.size(), 0.0);
  const auto& voff = offsets ? model_.vertical_offset_m : no_offsets;
  const std::vector<double> cos_el = each(el, [](double e) { return std::cos(e); });
  const std::vector<double> sin_el = each(el, [](double e) { return std::sin(e); });
  OrganizedCloud out;
  out.scan = OrganizedScan(rings, columns_);
  OrganizedScan& scan = out.scan;
  CloudOrganizeStats& stats = out.stats;
  stats.points = n;
  stats.beam_offsets = offsets;
  const bool timed = !cloud.time_ns.empty();
  std::vector<std::int64_t> first_ns(timed ? static_cast<std::size_t>(columns_) : 0, kNoColumnTime);
  std::vector<float> residual_deg;
  residual_deg.reserve(n);
  const double min_range = model_.min_range_m;
  const double max_range = model_.max_range_m;
  const double first = options_.first_column_azimuth_rad;
  const bool clockwise = options_.clockwise;
  // The span of the beam origins (the sensor origin included) bounds nearest_ring's candidates.
  const double min_off = std::min(0.0, *std::min_element(voff.begin(), voff.end()));
  const double max_off = std::max(0.0, *std::max_element(voff.begin(), voff.end()));
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3f& p = cloud.xyz[i];
    if (!p.allFinite()) {
      ++stats.non_finite;
      continue;
    }
    if (!is_return(p)) {
      ++stats.at_origin;
      continue;
    }
    const double x = p.x();
    const double y = p.y();
    const double z = p.z();
    const double h = std::sqrt(x * x + y * y);
    auto [ring, residual] = nearest_ring(h, z, el, voff, min_off, max_off);
    if (ring < 0) {  // no finite residual (not reachable from finite coordinates)
      ++stats.between_rings;
      continue;
    }
    const auto ru = static_cast<std::size_t>(ring);
    residual = residual_rad(h, z - voff[ru], cos_el[ru], sin_el[ru]);
    if (residual > above_rad_[ru] || -residual > below_rad_[ru]) {
      ++stats.between_rings;
      continue;
    }
    residual_deg.push_back(static_cast<float>(std::abs(residual) * kRadToDeg));
    const double dz = z - voff[ru];
    const double range = std::sqrt(h * h + dz * dz);
    const double az = fast_atan2(y, x) + column_shift_rad_[ru];
    const double rel = wrap_two_pi(clockwise ? first - az : az - first);
    // The nearest column, halves up: rel is in [0, 2 pi) (at worst a hair below 0), where this
    // is what + 0.5 and truncation gave, but for 0.49999999999999994, which that rounded up.
    int column = static_cast<int>(std::lround(rel / step_rad_));
    if (column >= columns_) column -= columns_;
    if (timed) {
      auto& t = first_ns[static_cast<std::size_t>(column)];
      t = std::min(t, cloud.time_ns[i]);
    }
    const float intensity = cloud.intensity.empty() ? 0.0f : cloud.intensity[i];
    place_return(scan, stats, ring, column, range, min_range, max_range, intensity, p);
  }
  stats.organized = scan.valid_count();
  summarise_residuals(residual_deg, stats);
  set_columns(scan, first_ns, cloud.stamp_ns);
  scan.stamp_ns = timed ? scan.column_stamp_ns[0] : cloud.stamp_ns;
  return out;
}

UnorganizedCloud flatten_scan(const OrganizedScan& scan) {
  UnorganizedCloud cloud;
  cloud.stamp_ns = scan.stamp_ns;
  const std::size_t n = scan.valid_count();
  cloud.xyz.reserve(n);
  cloud.intensity.reserve(n);
  const bool timed = scan.column_stamp_ns.size() == static_cast<std::size_t>(scan.columns());
  if (timed) cloud.time_ns.reserve(n);
  for (std::size_t i = 0; i < scan.size(); ++i) {
    if (!scan.valid(i)) continue;
    cloud.xyz.push_back(scan.point(i));
    cloud.intensity.push_back(scan.intensity(i));
    if (timed)
      cloud.time_ns.push_back(scan.column_stamp_ns[static_cast<std::size_t>(scan.column_of(i))]);
  }
  return cloud;
}

std::vector<double> measure_elevations_deg(const OrganizedScan& scan, const std::string& name) {
  const auto rings = static_cast<std::size_t>(scan.rings());
  std::vector<double> sum(rings, 0.0);
  std::vector<std::size_t> count(rings, 0);
  for (std::size_t i = 0; i < scan.size(); ++i) {
    if (!scan.valid(i)) continue;
    const Eigen::Vector3f p = scan.point(i);
    const auto r = static_cast<std::size_t>(scan.ring_of(i));
    sum[r] += std::atan2(double{p.z()}, std::hypot(double{p.x()}, double{p.y()})) * kRadToDeg;
    ++count[r];
  }
  std::vector<std::size_t> known;
  std::vector<double> out(rings, 0.0);
  for (std::size_t r = 0; r < rings; ++r) {
    if (count[r] > 0) {
      out[r] = sum[r] / static_cast<double>(count[r]);
      known.push_back(r);
    }
  }
  if (known.size() < 2) {
    throw InputError(name +
                     ": cannot measure the ring elevations (fewer than two rings have "
                     "points); give the sensor model explicitly");
  }
  // Rings without points: linear through the nearest measured rings (extrapolated at the ends).
  for (std::size_t r = 0; r < rings; ++r) {
    if (count[r] > 0) continue;
    auto hi = std::upper_bound(known.begin(), known.end(), r);
    if (hi == known.begin()) ++hi;
    if (hi == known.end()) --hi;
    const std::size_t a = *(hi - 1);
    const std::size_t b = *hi;
    const double t = (static_cast<double>(r) - static_cast<double>(a)) /
                     (static_cast<double>(b) - static_cast<double>(a));
    out[r] = out[a] + t * (out[b] - out[a]);
  }
  for (std::size_t r = 1; r < rings; ++r) {
    if (!(out[r] > out[r - 1])) {
      throw InputError(name + ": rows are not ordered by elevation (row " + std::to_string(r) +
                       " is not above row " + std::to_string(r - 1) +
                       "); give the sensor model explicitly");
    }
  }
  return out;
}

namespace {

// Histogram of the points' elevations in bins this wide, over -90..90 degrees.
constexpr double kBinDeg = 0.05;
constexpr int kBins = static_cast<int>(180.0 / kBinDeg);

// Elevations seen from the sensor origin. Near points are left out when there are enough far
// ones: beam origins a centimetre off the axis smear a ring by a degree at half a metre.
std::vector<double> ring_finding_elevations_deg(const UnorganizedCloud& cloud) {
  std::vector<double> near_deg;
  std::vector<double> far_deg;
  for (const auto& p : cloud.xyz) {
    if (!p.allFinite() || !is_return(p)) continue;
    const double h = std::hypot(double{p.x()}, double{p.y()});
    const double e = std::atan2(double{p.z()}, h) * kRadToDeg;
    (std::hypot(h, double{p.z()}) >= 2.0 ? far_deg : near_deg).push_back(e);
  }
  if (far_deg.size() >= 200) return far_deg;
  near_deg.insert(near_deg.end(), far_deg.begin(), far_deg.end());
  return near_deg;
}

// Rings are the histogram's peaks that stand above a fiftieth of the highest, separated by a
// valley below half the lower one; of two peaks without such a valley the higher one is kept.
std::vector<int> elevation_peaks(const std::vector<double>& hist) {
  const double highest = *std::max_element(hist.begin(), hist.end());
  const double threshold = std::max(3.0, 0.02 * highest);
  std::vector<int> peaks;
  for (int b = 0; b < kBins; ++b) {
    const double v = hist[static_cast<std::size_t>(b)];
    if (v < threshold) continue;
    const double left = b > 0 ? hist[static_cast<std::size_t>(b - 1)] : 0.0;
    const double right = b + 1 < kBins ? hist[static_cast<std::size_t>(b) + 1] : 0.0;
    if (!(v >= left && v > right)) continue;
    if (!peaks.empty()) {
      const int a = peaks.back();
      double valley = v;
      for (int m = a; m <= b; ++m) valley = std::min(valley, hist[static_cast<std::size_t>(m)]);
      if (valley > 0.5 * std::min(v, hist[static_cast<std::size_t>(a)])) {
        if (v > hist[static_cast<std::size_t>(a)]) peaks.back() = b;
        continue;
      }
    }
    peaks.push_back(b);
  }
  return peaks;
}

// First guess of the rings' elevations: the centroids of the elevation histogram's peaks.
std::vector<double> histogram_ring_elevations_deg(const UnorganizedCloud& cloud,
                                                  const std::string& name) {
  std::vector<double> hist(kBins, 0.0);
  for (double e : ring_finding_elevations_deg(cloud)) {
    const int b = std::clamp(static_cast<int>((e + 90.0) / kBinDeg), 0, kBins - 1);
    hist[static_cast<std::size_t>(b)] += 1.0;
  }
  const std::vector<int> peaks = elevation_peaks(hist);
  if (peaks.size() < 2) {
    throw InputError(name + ": cannot measure the ring elevations (" +
                     std::to_string(peaks.size()) +
                     " ring(s) stand out in the points' elevations, expected at least two); "
                     "name the sensor with --sensor");
  }
  // No spinning LiDAR has more rings; more peaks are a cloud of something else (and a grid that
  // could not be allocated).
  constexpr std::size_t kMaxMeasuredRings = 256;
  if (peaks.size() > kMaxMeasuredRings) {
    throw InputError(name + ": cannot measure the ring elevations (" +
                     std::to_string(peaks.size()) + " stand out, expected at most " +
                     std::to_string(kMaxMeasuredRings) + "); name the sensor with --sensor");
  }
  std::vector<double> elevations_deg;
  for (int b : peaks) {
    double w = 0.0;
    double s = 0.0;
    for (int m = std::max(0, b - 2); m <= std::min(kBins - 1, b + 2); ++m) {
      const double v = hist[static_cast<std::size_t>(m)];
      w += v;
      s += v * ((m + 0.5) * kBinDeg - 90.0);
    }
    elevations_deg.push_back(s / w);
  }
  return elevations_deg;
}

// Neighbouring points of one ring are one column apart unless returns are missing between
// them: the median spacing is the column width.
int measure_columns(const UnorganizedCloud& cloud, const std::vector<double>& elevations_deg,
                    double scan_rate_hz, const std::string& name) {
  SensorModel rings_only = SensorModel::generic(elevations_deg, 8, scan_rate_hz);
  const auto& el = rings_only.elevation_rad;
  std::vector<std::vector<double>> azimuths(el.size());
  for (const auto& p : cloud.xyz) {
    if (!p.allFinite() || !is_return(p)) continue;
    const double e = std::atan2(double{p.z()}, std::hypot(double{p.x()}, double{p.y()}));
    const auto k = static_cast<std::size_t>(std::lower_bound(el.begin(), el.end(), e) - el.begin());
    std::size_t r = k;
    if (k == el.size() || (k > 0 && e - el[k - 1] < el[k] - e)) r = k - 1;
    if (std::abs(e - el[r]) > 0.1 * kDegToRad) continue;
    azimuths[r].push_back(std::atan2(double{p.y()}, double{p.x()}));
  }
  std::vector<double> gaps;
  for (auto& a : azimuths) {
    std::sort(a.begin(), a.end());
    for (std::size_t j = 1; j < a.size(); ++j) {
      if (a[j] - a[j - 1] > 1e-6) gaps.push_back(a[j] - a[j - 1]);
    }
  }
  if (gaps.size() < 16) {
    throw InputError(name +
                     ": cannot measure the column width (too few points per ring); name the "
                     "sensor with --sensor");
  }
  const auto mid = gaps.begin() + static_cast<std::ptrdiff_t>(gaps.size() / 2);
  std::nth_element(gaps.begin(), mid, gaps.end());
  const long measured = std::lround(kTwoPi / *mid);
  if (measured > 16'384) {
    throw InputError(name + ": cannot measure the column width (neighbouring points " +
                     std::to_string(*mid * kRadToDeg) +
                     " degrees apart, finer than any spinning LiDAR); name the sensor with "
                     "--sensor");
  }
  return static_cast<int>(std::max(measured, 8L));
}

}  // namespace

SensorModel measure_cloud_sensor(const UnorganizedCloud& cloud, const std::string& name,
                                 double scan_rate_hz, int columns) {
  if (!(scan_rate_hz > 0.0 && scan_rate_hz <= 100.0)) {
    throw ConfigError(name + ": scan rate " + std::to_string(scan_rate_hz) +
                      " Hz: expected 0..100");
  }
  const std::vector<double> elevations_deg = histogram_ring_elevations_deg(cloud, name);
  if (columns <= 0) columns = measure_columns(cloud, elevations_deg, scan_rate_hz, name);
  // Refine each ring to the mean elevation of the points it gathers.
  constexpr double kMeasuredMaxRangeM = 200.0;
  SensorModel first_guess =
      SensorModel::generic(elevations_deg, columns, scan_rate_hz, kMeasuredMaxRangeM);
  const CloudOrganizer organizer(first_guess);
  const OrganizedCloud organized = organizer.organize(cloud);
  return SensorModel::generic(measure_elevations_deg(organized.scan, name), columns, scan_rate_hz,
                              kMeasuredMaxRangeM);
}

}  // namespace ringtrack::core
