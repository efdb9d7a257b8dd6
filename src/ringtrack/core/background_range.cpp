#include "ringtrack/core/background_range.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <numbers>
#include <string>

#include "ringtrack/core/error.hpp"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace ringtrack::core {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr int kMaxStreak = 60000;  // fits uint16

void require(bool ok, const char* key, const std::string& expected, double value) {
  if (!ok) {
    throw ConfigError(std::string("background range: ") + key + " must be " + expected + ", got " +
                      std::to_string(value));
  }
}

}  // namespace

BackgroundRangeModel::BackgroundRangeModel(const SensorModel& model,
                                           const BackgroundRangeConfig& config)
    : config_(config),
      rings_(model.rings()),
      bins_(model.columns()),
      bin_width_rad_(model.azimuth_step_rad()) {
  model.validate();
  require(config.tolerance_m >= 0.0 && std::isfinite(config.tolerance_m), "tolerance_m",
          "a finite number >= 0", config.tolerance_m);
  require(config.relative_tolerance >= 0.0 && config.relative_tolerance < 1.0, "relative_tolerance",
          "in [0, 1)", config.relative_tolerance);
  require(config.scans_to_learn >= 1 && config.scans_to_learn <= kMaxStreak, "scans_to_learn",
          "in [1, 60000]", config.scans_to_learn);
  require(config.scans_to_learn_behind >= 1 && config.scans_to_learn_behind <= kMaxStreak,
          "scans_to_learn_behind", "in [1, 60000]", config.scans_to_learn_behind);
  require(config.smoothing >= 0.0 && config.smoothing <= 1.0, "smoothing", "in [0, 1]",
          config.smoothing);
  reset();
}

void BackgroundRangeModel::reset() {
  const auto n = static_cast<std::size_t>(rings_) * static_cast<std::size_t>(bins_);
  background_.assign(n, kNaN);
  candidate_.assign(n, kNaN);
  streak_.assign(n, 0);
  column_bin_.clear();
  mapped_azimuths_.clear();
  scans_ = 0;
}

int BackgroundRangeModel::bin_of(double azimuth_rad) const {
  constexpr double kTwoPi = 2.0 * std::numbers::pi;
  double a = std::fmod(azimuth_rad, kTwoPi);
  if (a < 0.0) a += kTwoPi;
  const auto b = static_cast<long>(std::floor(a / bin_width_rad_ + 0.5));
  return static_cast<int>(b % bins_);
}

std::size_t BackgroundRangeModel::cell_of(const OrganizedScan& scan, std::size_t scan_index) const {
  const int ring = scan.ring_of(scan_index);
  const int column = scan.column_of(scan_index);
  const int bin = bin_of(scan.column_azimuth_rad[static_cast<std::size_t>(column)]);
  return static_cast<std::size_t>(ring) * static_cast<std::size_t>(bins_) +
         static_cast<std::size_t>(bin);
}

#if defined(__SSE2__)
namespace {
// Four cells of consecutive bins at once, when all four take the common case of update()'s
// per-cell step: a return on the learned surface, or open sky seen open again. The same
// arithmetic in float and double lanes, bit for bit (MatchesTheNaiveReferenceCellByCell);
// update() returns false for any other block, which then goes cell by cell.
class FourCells {
 public:
  FourCells(float smoothing, double tolerance, double relative, bool learn_open)
      : tolerance_(_mm_set1_pd(tolerance)),
        relative_(_mm_set1_pd(relative)),
        smoothing_(_mm_set1_ps(smoothing)),
        learn_open_(learn_open) {}

  bool update(const ReturnStatus* status, const float* range, float* background,
              std::uint16_t* streak) const {
    std::uint32_t st4 = 0;
    std::memcpy(&st4, status, sizeof(st4));
    if (st4 == 0x01010101u) return on_surface(range, background, streak);  // four kValid
    // All four kNoReturn (0) or kTooFar (3): open sky seen open again?
    if (learn_open_ && (st4 & 0xFCFCFCFCu) == 0 && ((st4 ^ (st4 >> 1)) & 0x01010101u) == 0) {
      const __m128 bg = _mm_loadu_ps(background);
      if (_mm_movemask_ps(_mm_cmpeq_ps(bg, _mm_set1_ps(kInf))) != 0xF) return false;
      std::memset(streak, 0, 4 * sizeof(std::uint16_t));
      return true;
    }
    return false;
  }

 private:
  bool on_surface(const float* range, float* background, std::uint16_t* streak) const {
    const __m128 x = _mm_loadu_ps(range);
    const __m128 bg = _mm_loadu_ps(background);
    const __m128 d = _mm_sub_ps(x, bg);
    const __m128 ad = _mm_andnot_ps(_mm_set1_ps(-0.0f), d);
    const __m128 mn = _mm_min_ps(bg, x);  // std::min(x, bg): bg when bg < x, else x
    const __m128d lo = _mm_cmple_pd(
        _mm_cvtps_pd(ad), _mm_add_pd(tolerance_, _mm_mul_pd(relative_, _mm_cvtps_pd(mn))));
    const __m128d hi = _mm_cmple_pd(
        _mm_cvtps_pd(_mm_movehl_ps(ad, ad)),
        _mm_add_pd(tolerance_, _mm_mul_pd(relative_, _mm_cvtps_pd(_mm_movehl_ps(mn, mn)))));
    if ((_mm_movemask_pd(lo) | (_mm_movemask_pd(hi) << 2)) != 0xF) return false;
    _mm_storeu_ps(background, _mm_add_ps(bg, _mm_mul_ps(smoothing_, d)));
    std::memset(streak, 0, 4 * sizeof(std::uint16_t));
    return true;
  }

  __m128d tolerance_;
  __m128d relative_;
  __m128 smoothing_;
  bool learn_open_;
};
}  // namespace
#endif

void BackgroundRangeModel::update(const OrganizedScan& scan) {
  if (scan.rings() != rings_) {
    throw InputError("background range: the scan has " + std::to_string(scan.rings()) +
                     " rings, the model " + std::to_string(rings_));
  }
  if (scan.column_azimuth_rad.size() != static_cast<std::size_t>(scan.columns())) {
    throw InputError("background range: the scan has " + std::to_string(scan.columns()) +
                     " columns but " + std::to_string(scan.column_azimuth_rad.size()) +
                     " column azimuths");
  }
  map_columns(scan);
  // The per-cell loop keeps everything it reads in locals: observe() is an out-of-line call,
  // after which the compiler would otherwise reload the configuration and the vectors' data.
  const float smoothing = static_cast<float>(config_.smoothing);
  const double tolerance = config_.tolerance_m;
  const double relative = config_.relative_tolerance;
  const bool learn_open = config_.learn_no_return;
  const int* column_bin = column_bin_.data();
  float* background = background_.data();
  std::uint16_t* streak = streak_.data();
  const int columns = scan.columns();
#if defined(__SSE2__)
  const FourCells four(smoothing, tolerance, relative, learn_open);
#endif
  for (int r = 0; r < rings_; ++r) {
    const std::size_t row = static_cast<std::size_t>(r) * static_cast<std::size_t>(bins_);
    const ReturnStatus* status = scan.statuses().data() + scan.index(r, 0);
    const float* range = scan.ranges().data() + scan.index(r, 0);
    const auto step = [&](int c) {
      const int bin = column_bin[c];
      if (bin < 0) return;
      const std::size_t cell = row + static_cast<std::size_t>(bin);
      const ReturnStatus st = status[c];
      if (st == ReturnStatus::kValid) {
        // Most returns agree with a learned finite background: that case inline (same_surface
        // and observe()'s arithmetic; false for an unlearned (NaN) or open (+inf) background),
        // everything else in observe().
        const float bg = background[cell];
        const float x = range[c];
        if (std::abs(x - bg) <= tolerance + relative * std::min(x, bg)) {
          background[cell] = bg + smoothing * (x - bg);
          streak[cell] = 0;
        } else {
          observe(cell, x);
        }
      } else if (st != ReturnStatus::kTooClose && learn_open) {  // no return, or too far
        if (background[cell] == kInf) {
          streak[cell] = 0;  // open background seen open again (observe()'s first case)
        } else {
          observe(cell, kInf);
        }
      }  // a too-close return is no evidence either way
    };
    int c = 0;
#if defined(__SSE2__)
    // Four neighbouring columns of consecutive bins at once where all four take the common
    // case (FourCells); any other block goes through step() cell by cell.
    for (; c + 4 <= columns; c += 4) {
      const int bin = column_bin[c];
      const bool consecutive = bin >= 0 && column_bin[c + 1] == bin + 1 &&
                               column_bin[c + 2] == bin + 2 && column_bin[c + 3] == bin + 3;
      const std::size_t cell = row + static_cast<std::size_t>(bin);
      if (consecutive && four.update(status + c, range + c, background + cell, streak + cell)) {
        continue;
      }
      step(c);
      step(c + 1);
      step(c + 2);
      step(c + 3);
    }
#endif
    for (; c < columns; ++c) step(c);
  }
  ++scans_;
}

void BackgroundRangeModel::map_columns(const OrganizedScan& scan) {
  // A sensor's column azimuths repeat from scan to scan (always in simulation, often in
  // captures): the last scan's bins are reused then.
  if (!column_bin_.empty() && scan.column_azimuth_rad == mapped_azimuths_) return;
  mapped_azimuths_ = scan.column_azimuth_rad;
  // Bin of each column; two columns of one scan in one bin (a revolution of 1809 firing
  // sequences): the first wins, the other is skipped (-1).
  std::vector<char> taken(static_cast<std::size_t>(bins_), 0);
  column_bin_.resize(static_cast<std::size_t>(scan.columns()));
  for (int c = 0; c < scan.columns(); ++c) {
    const double az = scan.column_azimuth_rad[static_cast<std::size_t>(c)];
    int bin = -1;
    if (std::isfinite(az)) {
      bin = bin_of(az);
      if (taken[static_cast<std::size_t>(bin)] != 0) {
        bin = -1;
      } else {
        taken[static_cast<std::size_t>(bin)] = 1;
      }
    }
    column_bin_[static_cast<std::size_t>(c)] = bin;
  }
}

void BackgroundRangeModel::observe(std::size_t cell, float range_m) {
  const auto same = [&](float a, float b) {
    if (std::isinf(a) || std::isinf(b)) return a == b;
    return same_surface(a, b);
  };
  float& bg = background_[cell];
  float& cand = candidate_[cell];
  std::uint16_t& streak = streak_[cell];
  const bool learned = !std::isnan(bg);
  if (learned && same(range_m, bg)) {
    if (std::isfinite(bg)) bg += static_cast<float>(config_.smoothing) * (range_m - bg);
    streak = 0;  // the background is back: a passing object's streak ends
    return;
  }
  if (streak > 0 && same(range_m, cand)) {
    if (std::isfinite(cand)) cand += (range_m - cand) / static_cast<float>(streak + 1);
    streak = static_cast<std::uint16_t>(std::min(streak + 1, kMaxStreak));
  } else {
    cand = range_m;
    streak = 1;
  }
  const int needed = learned && cand > bg ? config_.scans_to_learn_behind : config_.scans_to_learn;
  if (streak >= needed) {
    bg = cand;
    streak = 0;
  }
}

bool BackgroundRangeModel::is_in_front(std::size_t cell, double range_m, double margin_m) const {
  const float bg = background_[cell];
  if (std::isnan(bg) || !std::isfinite(range_m)) return false;
  return std::isinf(bg) || range_m < static_cast<double>(bg) - margin_m;
}

bool BackgroundRangeModel::is_in_front(const OrganizedScan& scan, std::size_t scan_index,
                                       double margin_m) const {
  if (!scan.valid(scan_index)) return false;
  return is_in_front(cell_of(scan, scan_index), scan.range_m(scan_index), margin_m);
}

std::size_t BackgroundRangeModel::learned_count() const {
  return static_cast<std::size_t>(std::count_if(background_.begin(), background_.end(),
                                                [](float b) { return !std::isnan(b); }));
}

}  // namespace ringtrack::core
