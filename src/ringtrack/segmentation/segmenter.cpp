#include "ringtrack/segmentation/segmenter.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <tuple>

#include "ringtrack/core/error.hpp"
#include "ringtrack/segmentation/direct_median.hpp"
#include "ringtrack/segmentation/kernel.hpp"
#include "ringtrack/segmentation/order_stat_window.hpp"
#include "ringtrack/segmentation/radius_table.hpp"
#include "ringtrack/segmentation/range_buckets.hpp"

namespace ringtrack::segmentation {

using detail::direct_median;
using detail::kDirectRadius;
using detail::OrderStatWindow;
using detail::RadiusTable;
using detail::RangeBuckets;

// Per-column-count state: radius tables and scratch buffers reused across scans.
struct Segmenter::Tables {
  int columns{0};
  int pad{0};  // radius cap: the ring is extended by this many cells on both sides
  RadiusTable noise_radius, background_radius;
  float direct_noise_above{0};     // values above it have a noise radius <= kDirectRadius
  std::vector<float> value;        // extended ring: filter ranges
  std::vector<std::uint32_t> key;  // extended ring: their buckets
  std::vector<float> scratch;
  OrderStatWindow noise_window{RangeBuckets::kCount};
  OrderStatWindow background_window{RangeBuckets::kCount};
  // Exact windows of the points the brackets leave open; they follow those points along the ring.
  OrderStatWindow noise_exact_window{RangeBuckets::kCount};
  OrderStatWindow background_exact_window{RangeBuckets::kCount};
};

namespace {

// How far a point's radius and position may differ from the reference window's before the
// reference moves (see FilterState). Must not exceed the reference radius (the bracket needs ranks
// rho - D and rho + D in a window of 2 rho + 1). Larger means fewer bracket reads but looser
// brackets.
int allowed_drift(int rho) {
  return std::min(rho, 2 + rho / 6);
}

// One median filter's reference window over the extended ring: a histogram of the keys of
// [left, right] = [centre - rho, centre + rho] with tracked ranks rho - D and rho + D.
//
// The bracket: if a point j has radius r with |r - rho| <= D and |j - centre| <= D, its window
// [j - r, j + r] differs from the reference by at most max(|r - rho|, |j - centre|) cells on the
// side that matters for each bound, so its median lies in [os(rho - D), os(rho + D)] of the
// reference window. One reference position thus serves 2 D + 1 consecutive points; moving it costs
// two key updates per cell moved, the same as sliding cell by cell, but the tracked ranks are read
// once per position instead of once per point.
struct FilterState {
  OrderStatWindow* window;
  const std::uint32_t* key;
  const RadiusTable* radius;
  int rho{-1};
  int drift{0};  // D = allowed_drift(rho)
  int centre{0};
  int left{0};
  int right{-1};  // empty when right < left
  // The points the reference serves: extended index <= serve_end and value in (v_min, v_max],
  // which is |r - rho| <= D without computing r (the radius is monotone in the value).
  int serve_end{-1};
  float v_min{0}, v_max{-1};
  float lo{0}, hi{0};  // cached bounds, valid when lo_ready / hi_ready
  bool lo_ready{false}, hi_ready{false};

  [[nodiscard]] bool serves(int j, float v) const {
    return j <= serve_end && v > v_min && v <= v_max;
  }

  // Changes the window to [new_left, new_right]; returns the number of keys added or removed.
  std::size_t reshape(int new_left, int new_right) {
    std::size_t updates = 0;
    auto add = [&](int a, int b) {
      if (a > b) return;
      window->update<1>(key + a, key + b + 1);
      updates += static_cast<std::size_t>(b - a + 1);
    };
    auto remove = [&](int a, int b) {
      if (a > b) return;
      window->update<-1>(key + a, key + b + 1);
      updates += static_cast<std::size_t>(b - a + 1);
    };
    const int shift = new_left - left;
    if (right >= left && shift > 0 && new_right - right == shift && shift <= right - left + 1) {
      // The common move: same width, forward, overlapping or adjacent.
      window->replace(key + left, key + right + 1, shift);
      updates = 2 * static_cast<std::size_t>(shift);
    } else if (right < left || new_left > right || new_right < left) {
      add(new_left, new_right);
      remove(left, right);
    } else {
      add(new_left, left - 1);
      add(right + 1, new_right);
      remove(left, new_left - 1);
      remove(new_right + 1, right);
    }
    left = new_left;
    right = new_right;
    return updates;
  }

  // Makes the reference serve point j (extended index) with value v; `last` is the extended
  // index of the ring's last cell. Returns the number of key updates.
  std::size_t cover(int j, float v, int last) {
    const int r = radius->radius(v, key[j]);
    if (rho < 0 || std::abs(r - rho) > drift) {
      rho = r;
      drift = allowed_drift(rho);
      window->set_ranks(rho - drift, rho + drift);
      v_min = radius->radius_at_most_above(rho + drift);
      v_max = radius->radius_at_least_up_to(rho - drift);
    }
    centre = std::min(j + drift, last);  // ahead of j, so it also serves the next 2 D points
    serve_end = centre + drift;
    lo_ready = hi_ready = false;
    return reshape(centre - rho, centre + rho);
  }

  // Bounds of the medians of every point served (lazy, so possibly loose: see OrderStatWindow).
  // Read once per reference position; the window does not change in between.
  float lower() {
    if (!lo_ready) {
      lo = RangeBuckets::lower(window->lo_bound_bucket());
      lo_ready = true;
    }
    return lo;
  }
  float upper() {
    if (!hi_ready) {
      hi = RangeBuckets::upper(window->hi_bound_bucket());
      hi_ready = true;
    }
    return hi;
  }
  // Tight bounds for every point served: the lazy pointers moved to their tracked ranks.
  std::pair<float, float> tight_bounds() {
    window->tighten();
    lo_ready = hi_ready = false;
    return {lower(), upper()};
  }

  // For an exact window: becomes point j's own window (radius r), cheap when the previous query
  // was nearby, and returns the bucket of its median and the keys below that bucket.
  std::pair<std::uint32_t, int> median_bucket(int j, int r) {
    reshape(j - r, j + r);
    return window->track_rank(r);
  }

  void clear() {
    reshape(0, -1);
    rho = -1;
    serve_end = -1;
  }
};

// The exact median of the window of radius r around c, knowing its bucket and the keys below it:
// a selection among the few window values that share the bucket.
float median_in_bucket(const std::vector<float>& value, const std::vector<std::uint32_t>& key,
                       int c, int r, std::pair<std::uint32_t, int> bucket,
                       std::vector<float>& scratch) {
  scratch.clear();
  for (int j = c - r; j <= c + r; ++j) {
    if (key[static_cast<std::size_t>(j)] == bucket.first)
      scratch.push_back(value[static_cast<std::size_t>(j)]);
  }
  const auto nth = scratch.begin() + (r - bucket.second);
  std::nth_element(scratch.begin(), nth, scratch.end());
  return *nth;
}

// The decision from bounds of both medians: 1 segment, 0 background, -1 undecided. Float
// subtraction is monotone, so the differences of the bounds bound the true difference.
int decide(float noise_lo, float noise_hi, float background_lo, float background_hi,
           const DeltaRule& rule) {
  const float delta_hi = background_hi - noise_lo;
  const float delta_lo = background_lo - noise_hi;
  if (delta_hi < rule.background_below || delta_lo > rule.background_above) return 0;
  if (delta_lo >= rule.segment_from && delta_hi <= rule.segment_to) return 1;
  return -1;
}

// The four median windows of one ring: two references that jump along with the points, and two
// exact windows that follow the points the references leave open.
struct RingFilters {
  FilterState noise, background, noise_exact, background_exact;
  void clear() {
    for (auto* f : {&noise, &background, &noise_exact, &background_exact}) f->clear();
  }
};

// The label of point c (value at extended index c) that the references' cheap bounds left open.
int decide_open_point(RingFilters& f, const std::vector<float>& value,
                      const std::vector<std::uint32_t>& key, int c,
                      std::optional<float> noise_median, std::vector<float>& scratch,
                      const core::SegmentationConfig& config, const DeltaRule& rule,
                      SegmenterStats& stats) {
  ++stats.tight_decisions;
  // 1) The same reference windows' bounds, tightened (the lazy pointers lag after object edges).
  float noise_lo = 0, noise_hi = 0;
  if (noise_median) {
    noise_lo = noise_hi = *noise_median;
  } else {
    std::tie(noise_lo, noise_hi) = f.noise.tight_bounds();
  }
  const auto [background_lo, background_hi] = f.background.tight_bounds();
  int label = decide(noise_lo, noise_hi, background_lo, background_hi, rule);
  if (label >= 0) return label;
  // 2) The buckets (0.1 % wide) of the exact medians: first the noise median, whose window is the
  // narrow, cheap one, then if still needed the background median.
  ++stats.bucket_decisions;
  const auto i = static_cast<std::size_t>(c);
  const int rn = f.noise.radius->radius(value[i], key[i]);
  const int rb = f.background.radius->radius(value[i], key[i]);
  std::pair<std::uint32_t, int> nb{};
  if (!noise_median) {
    nb = f.noise_exact.median_bucket(c, rn);
    noise_lo = RangeBuckets::lower(nb.first);
    noise_hi = RangeBuckets::upper(nb.first);
    label = decide(noise_lo, noise_hi, background_lo, background_hi, rule);
    if (label >= 0) return label;
  }
  const auto bb = f.background_exact.median_bucket(c, rb);
  label = decide(noise_lo, noise_hi, RangeBuckets::lower(bb.first), RangeBuckets::upper(bb.first),
                 rule);
  if (label >= 0) return label;
  // 3) The exact medians, with the same arithmetic as the definition.
  ++stats.exact_decisions;
  if (!noise_median) noise_median = median_in_bucket(value, key, c, rn, nb, scratch);
  const float background_median = median_in_bucket(value, key, c, rb, bb, scratch);
  return is_segment(*noise_median, background_median, config) ? 1 : 0;
}

}  // namespace

Segmenter::Segmenter(const core::SegmentationConfig& config) : config_(config) {
  core::Config full;
  full.segmentation = config;
  core::validate_config(full);
  rule_ = delta_rule(config_);
}
Segmenter::~Segmenter() = default;
Segmenter::Segmenter(Segmenter&&) noexcept = default;
Segmenter& Segmenter::operator=(Segmenter&&) noexcept = default;

void Segmenter::segment(const core::OrganizedScan& scan, std::vector<std::uint8_t>& labels) {
  const int n = scan.columns();
  if (n >= 65535) throw core::Error("segmentation: at most 65534 columns per ring are supported");
  if (!tables_ || tables_->columns != n) {
    auto t = std::make_unique<Tables>();
    t->columns = n;
    t->pad = effective_radius_cap(config_, n);
    const double step = 2.0 * std::numbers::pi / n;
    t->noise_radius = RadiusTable(KernelRadius{config_.min_width_m, step, false, t->pad});
    t->background_radius = RadiusTable(KernelRadius{config_.max_width_m, step, true, t->pad});
    t->direct_noise_above = t->noise_radius.radius_at_most_above(kDirectRadius);
    t->value.resize(static_cast<std::size_t>(n) + 2 * static_cast<std::size_t>(t->pad));
    t->key.resize(t->value.size());
    tables_ = std::move(t);
  }
  Tables& t = *tables_;
  labels.assign(scan.size(), kBackground);
  stats_ = {};
  const auto invalid = static_cast<float>(config_.invalid_range_m);
  const auto& ranges = scan.ranges();
  const auto& status = scan.statuses();
  const int pad = t.pad;

  for (int ring = 0; ring < scan.rings(); ++ring) {
    const std::size_t base = scan.index(ring, 0);
    // The ring extended by `pad` cells on both sides so windows never wrap: [tail | ring | head].
    for (int col = 0; col < n; ++col) {
      const auto i = base + static_cast<std::size_t>(col);
      const float v = filter_range(ranges[i], status[i] == core::ReturnStatus::kValid, invalid);
      const std::size_t padded = static_cast<std::size_t>(col) + static_cast<std::size_t>(pad);
      t.value[padded] = v;
      t.key[padded] = RangeBuckets::key(v);
    }
    std::copy_n(t.value.begin() + n, pad, t.value.begin());
    std::copy_n(t.key.begin() + n, pad, t.key.begin());
    std::copy_n(t.value.begin() + pad, pad, t.value.begin() + n + pad);
    std::copy_n(t.key.begin() + pad, pad, t.key.begin() + n + pad);
    RingFilters f{{&t.noise_window, t.key.data(), &t.noise_radius},
                  {&t.background_window, t.key.data(), &t.background_radius},
                  {&t.noise_exact_window, t.key.data(), &t.noise_radius},
                  {&t.background_exact_window, t.key.data(), &t.background_radius}};
    const int last = pad + n - 1;
    for (int col = 0; col < n; ++col) {
      const int c = col + pad;
      const auto i = base + static_cast<std::size_t>(col);
      const float v = t.value[static_cast<std::size_t>(c)];
      if (!(v < invalid)) continue;  // invalid returns are background
      ++stats_.points;
      // A noise window of a few values (far points) gives its median directly; otherwise the
      // noise reference bounds it.
      std::optional<float> noise_median;
      if (v > t.direct_noise_above) {
        noise_median = direct_median(&t.value[static_cast<std::size_t>(c)],
                                     t.noise_radius.radius(v, t.key[static_cast<std::size_t>(c)]));
      } else if (!f.noise.serves(c, v)) {
        stats_.window_updates += f.noise.cover(c, v, last);
      }
      if (!f.background.serves(c, v)) stats_.window_updates += f.background.cover(c, v, last);
      // Bounds from the reference windows settle nearly every point. The background test needs
      // only two of the four bounds, so it goes first: it settles the common case, points on
      // surfaces wider than objects.
      const float noise_lo = noise_median ? *noise_median : f.noise.lower();
      const float background_hi = f.background.upper();
      if (background_hi - noise_lo < rule_.background_below) continue;
      const float noise_hi = noise_median ? *noise_median : f.noise.upper();
      int label = decide(noise_lo, noise_hi, f.background.lower(), background_hi, rule_);
      if (label < 0) {
        label = decide_open_point(f, t.value, t.key, c, noise_median, t.scratch, config_, rule_,
                                  stats_);
      }
      if (label == 1) labels[i] = kSegment;
    }
    f.clear();
  }
}

}  // namespace ringtrack::segmentation
