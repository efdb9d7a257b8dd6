#include "ringtrack/pipeline/pipeline.hpp"

#include <chrono>
#include <utility>

#include "ringtrack/core/error.hpp"

namespace ringtrack::pipeline {
namespace {

using Clock = std::chrono::steady_clock;

double elapsed_ms(Clock::time_point from, Clock::time_point to) {
  return std::chrono::duration<double, std::milli>(to - from).count();
}

}  // namespace

Pipeline::Pipeline(const core::Config& config, core::SensorModel model)
    : config_(config),
      model_(std::move(model)),
      segmenter_(config.segmentation),
      detector_(config.detection),
      tracker_(config.tracking),
      filter_(config.mapping) {
  core::validate_config(config);
  model_.validate();
}

const FrameResult& Pipeline::process(const core::OrganizedScan& scan, const core::Pose& pose) {
  if (tracker_.stamp_ns() != 0 && scan.stamp_ns < tracker_.stamp_ns()) {
    throw core::InputError("pipeline: scan stamp " + std::to_string(scan.stamp_ns) +
                           " ns is older than the previous scan's " +
                           std::to_string(tracker_.stamp_ns()) +
                           " ns; scans must come in time order");
  }
  if (scan.rings() != model_.rings()) {
    throw core::InputError("pipeline: the scan at " + std::to_string(scan.stamp_ns) + " ns has " +
                           std::to_string(scan.rings()) + " rings, the sensor model " +
                           model_.name + " has " + std::to_string(model_.rings()));
  }
  const auto t0 = Clock::now();
  segmenter_.segment(scan, labels_);
  const auto t1 = Clock::now();
  // The tracker's predictions for this scan let the detector relax its model near known objects.
  const auto predictions = tracker_.predicted_positions(scan.stamp_ns);
  const auto& detections = detector_.detect(scan, labels_, pose, predictions);
  const auto t2 = Clock::now();
  // What this scan sees of the space hypotheses occupied (free-space tests; docs/visibility.md).
  const core::VisibilityQuery visibility(scan, model_, pose);
  const auto& hypotheses = tracker_.update(detections, scan.stamp_ns, &visibility);
  const auto t3 = Clock::now();
  const auto& filtered = filter_.process(scan, pose, detections, hypotheses);
  const auto t4 = Clock::now();

  result_.stamp_ns = scan.stamp_ns;
  result_.segment_labels = labels_;
  result_.detections = detections;
  result_.hypotheses = hypotheses;
  result_.removed_cells = filtered.removed_cells;
  result_.retroactive_points = filtered.retroactive_points;
  result_.times = {elapsed_ms(t0, t1), elapsed_ms(t1, t2), elapsed_ms(t2, t3), elapsed_ms(t3, t4),
                   elapsed_ms(t0, t4)};
  return result_;
}

void Pipeline::finish() {
  filter_.flush();
  result_ = {};
}

}  // namespace ringtrack::pipeline
