// Detection benchmark: one VLP-16 scan with ten people (open field), segmented once outside the
// timing; only Detector::detect() is timed.

#include <benchmark/benchmark.h>

#include "ringtrack/detection/completion.hpp"
#include "ringtrack/detection/detector.hpp"
#include "ringtrack/segmentation/segmenter.hpp"
#include "ringtrack/sim/simple_scene.hpp"
#include "support/naive_detection.hpp"

namespace {

using namespace ringtrack;

struct SegmentedScan {
  sim::RenderedScan rendered;
  std::vector<std::uint8_t> labels;
};

const SegmentedScan& ten_people() {
  static const SegmentedScan scan = [] {
    SegmentedScan s{sim::render(core::SensorModel::vlp16(), sim::SimpleScene::open_field(10)), {}};
    segmentation::Segmenter segmenter{core::SegmentationConfig{}};
    segmenter.segment(s.rendered.scan, s.labels);
    return s;
  }();
  return scan;
}

void BM_Detect10People(benchmark::State& state) {
  const auto& s = ten_people();
  detection::Detector detector{core::DetectionConfig{}};
  const core::Pose pose;
  const std::vector<Eigen::Vector3f> predictions;
  detector.detect(s.rendered.scan, s.labels, pose, predictions);  // grows the buffers once
  for (auto _ : state) {
    const auto& detections = detector.detect(s.rendered.scan, s.labels, pose, predictions);
    benchmark::DoNotOptimize(detections.data());
  }
  state.counters["detections"] = static_cast<double>(detector.stats().detections);
  state.counters["segment_points"] = static_cast<double>(detector.stats().segment_points);
}

// The same with the split step off (split_min_width_m = 0), to show its cost.
void BM_Detect10PeopleNoSplit(benchmark::State& state) {
  const auto& s = ten_people();
  core::DetectionConfig config;
  config.split_min_width_m = 0.0;
  detection::Detector detector{config};
  const core::Pose pose;
  detector.detect(s.rendered.scan, s.labels, pose);
  for (auto _ : state) {
    const auto& detections = detector.detect(s.rendered.scan, s.labels, pose);
    benchmark::DoNotOptimize(detections.data());
  }
}

// The completion of the same scan's detections with the people's legs hidden from the detector
// (segment labels only 0.9 m above the ground and higher), so it has cells to add; only
// DetectionCompleter::complete() is timed.
void BM_CompleteDetections10People(benchmark::State& state) {
  const auto& s = ten_people();
  std::vector<std::uint8_t> upper = s.labels;
  const double ground_z = *sim::SimpleScene::open_field(10).ground_z_m;
  for (std::size_t i = 0; i < upper.size(); ++i) {
    if (s.rendered.scan.valid(i) && s.rendered.scan.point(i).z() < ground_z + 0.9) upper[i] = 0;
  }
  detection::Detector detector{core::DetectionConfig{}};
  const core::Pose pose;
  const auto detections = detector.detect(s.rendered.scan, upper, pose);
  detection::DetectionCompleter completer{core::DetectionConfig{}};
  completer.complete(s.rendered.scan, pose, detections);  // grows the buffers once
  std::size_t added = 0;
  for (auto _ : state) {
    const auto& out = completer.complete(s.rendered.scan, pose, detections);
    benchmark::DoNotOptimize(out.data());
    added = 0;
    for (const auto& d : out) added += d.completion.size();
  }
  state.counters["detections"] = static_cast<double>(detections.size());
  state.counters["added_cells"] = static_cast<double>(added);
}

// The O(n^2) union-find reference on the same scan, for scale.
void BM_Detect10PeopleNaive(benchmark::State& state) {
  const auto& s = ten_people();
  for (auto _ : state) {
    benchmark::DoNotOptimize(
        testing::naive_detect(s.rendered.scan, s.labels, core::DetectionConfig{}, core::Pose{}));
  }
}

}  // namespace

BENCHMARK(BM_Detect10People)
    ->Unit(benchmark::kMicrosecond)
    ->Repetitions(5)
    ->ReportAggregatesOnly(true);
BENCHMARK(BM_Detect10PeopleNoSplit)
    ->Unit(benchmark::kMicrosecond)
    ->Repetitions(5)
    ->ReportAggregatesOnly(true);
BENCHMARK(BM_CompleteDetections10People)
    ->Unit(benchmark::kMicrosecond)
    ->Repetitions(5)
    ->ReportAggregatesOnly(true);
BENCHMARK(BM_Detect10PeopleNaive)->Unit(benchmark::kMillisecond);
