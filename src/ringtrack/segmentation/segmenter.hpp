#pragma once
/// Width-range segmentation (paper III.B), exact and fast.

#include <cstdint>
#include <memory>
#include <vector>

#include "ringtrack/core/config.hpp"
#include "ringtrack/core/organized_scan.hpp"
#include "ringtrack/segmentation/kernel.hpp"

namespace ringtrack::segmentation {

/// Counters of the last segment() call, for benchmarks and diagnostics.
struct SegmenterStats {
  std::size_t points{0};            ///< valid points labelled
  std::size_t tight_decisions{0};   ///< points the references' lazy bounds left open
  std::size_t bucket_decisions{0};  ///< of those, points the tight bounds left open
  std::size_t exact_decisions{0};   ///< of those, points whose exact median values were needed
  std::size_t window_updates{0};    ///< keys added to or removed from the median windows
};

/// Labels each cell of a scan as segment or background. Per ring, for every point, a noise
/// median over a window spanning min_width_m and a background median over one spanning
/// max_width_m at the point's own range; windows wrap across the 0/360 degree seam.
///
/// Why it is fast (docs/segmentation.md): each filter keeps a bucket histogram of a reference
/// window that moves along with the points (O(1) per point); the reference radius only changes
/// when the point's own radius drifts too far from it. The medians of the point's true window are
/// bounded by order statistics of the reference window, and the certainty rule is an interval of
/// the median difference, which settles the decision for nearly every point; the rest get tighter
/// bounds, then exact medians. The labels equal the naive nth_element result bit for bit.
class Segmenter {
 public:
  explicit Segmenter(const core::SegmentationConfig& config);
  ~Segmenter();
  Segmenter(Segmenter&&) noexcept;
  Segmenter& operator=(Segmenter&&) noexcept;

  /// Writes one label per cell (kSegment or kBackground) into labels, resized to scan.size().
  void segment(const core::OrganizedScan& scan, std::vector<std::uint8_t>& labels);
  /// Counters of the last call.
  [[nodiscard]] const SegmenterStats& stats() const { return stats_; }

 private:
  struct Tables;
  core::SegmentationConfig config_;
  DeltaRule rule_;                  // the certainty rule as intervals of the median difference
  std::unique_ptr<Tables> tables_;  // rebuilt when the column count changes
  SegmenterStats stats_;
};

}  // namespace ringtrack::segmentation
