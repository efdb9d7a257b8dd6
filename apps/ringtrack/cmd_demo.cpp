// `ringtrack demo`: segmentation and detection on a built-in synthetic VLP-16 scene, with timing.
// It does exactly that and nothing more: no tracking, no map (see README for what exists).

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <map>
#include <memory>

#include "commands.hpp"
#include "ringtrack/detection/detector.hpp"
#include "ringtrack/segmentation/segmenter.hpp"
#include "ringtrack/sim/simple_scene.hpp"

namespace ringtrack::cli {
namespace {

// Median wall time of `runs` calls, in milliseconds.
template <class F>
double median_ms(int runs, F&& f) {
  std::vector<double> ms;
  for (int i = 0; i < runs; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    f();
    ms.push_back(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  }
  std::nth_element(ms.begin(), ms.begin() + runs / 2, ms.end());
  return ms[static_cast<std::size_t>(runs / 2)];
}

// The ground-truth object most of a detection's points hit (0 = background).
std::uint32_t majority_label(const core::Detection& d, const std::vector<std::uint32_t>& labels) {
  std::map<std::uint32_t, int> votes;
  for (auto i : d.indices) ++votes[labels[i]];
  return std::max_element(votes.begin(), votes.end(),
                          [](auto& a, auto& b) { return a.second < b.second; })
      ->first;
}

void run_demo(const core::Config& config, int runs) {
  const auto model = core::SensorModel::vlp16();
  const auto scene = sim::SimpleScene::demo();
  const auto rendered = sim::render(model, scene);
  const auto& scan = rendered.scan;
  std::printf("Synthetic VLP-16 scan: %d rings x %d columns, %zu valid returns\n", scan.rings(),
              scan.columns(), scan.valid_count());
  std::printf(
      "Scene: ground 1.5 m below the sensor, a wall at 12 m, a 6 cm pole, 5 people (ids 1-5)\n\n");

  segmentation::Segmenter segmenter(config.segmentation);
  detection::Detector detector(config.detection);
  std::vector<std::uint8_t> labels;
  const core::Pose pose;  // sensor at the world origin
  segmenter.segment(scan, labels);
  const double segment_ms = median_ms(runs, [&] { segmenter.segment(scan, labels); });
  const double detect_ms = median_ms(runs, [&] { detector.detect(scan, labels, pose); });
  const auto& detections = detector.detect(scan, labels, pose);
  const auto segment_points = static_cast<std::size_t>(std::count(labels.begin(), labels.end(), 1));

  std::printf("%zu segment points, %zu detections:\n", segment_points, detections.size());
  std::printf("  %-3s %8s %8s %8s %7s %7s %6s  %s\n", "#", "x_m", "y_m", "z_m", "width", "height",
              "points", "true object");
  int k = 0;
  for (const auto& d : detections) {
    const auto size = d.box.size();
    const auto label = majority_label(d, rendered.labels);
    std::printf("  %-3d %8.2f %8.2f %8.2f %7.2f %7.2f %6zu  %s%s\n", ++k, d.centroid.x(),
                d.centroid.y(), d.centroid.z(), d.box.diagonal_xy(), size.z(), d.indices.size(),
                label ? ("person " + std::to_string(label)).c_str() : "background (false positive)",
                d.relaxed ? " [relaxed]" : "");
  }
  std::printf("\nTime per scan (median of %d runs, one core):\n", runs);
  std::printf("  segmentation %8.3f ms\n  detection    %8.3f ms\n  total        %8.3f ms\n",
              segment_ms, detect_ms, segment_ms + detect_ms);
  std::printf("\nThis demo covers segmentation and detection only.\n");
}

}  // namespace

void register_demo(CLI::App& app) {
  auto* cmd =
      app.add_subcommand("demo", "segment and detect people in a built-in synthetic VLP-16 scan");
  auto options = std::make_shared<ConfigOptions>();
  auto runs = std::make_shared<int>(50);
  options->add_to(*cmd);
  cmd->add_option("--runs", *runs, "repetitions for the timing median")
      ->check(CLI::Range(1, 100000));
  cmd->callback([options, runs] { run_demo(options->load(), *runs); });
}

}  // namespace ringtrack::cli
