// Runs the installed library's pipeline on a few seconds of a simulated VLP-16 in an empty field
// with six walkers, and says how many reported tracks lie on a true person. Exit code 1 when none
// does: the package linked, but the pipeline it gives does not work.

#include <cstdio>

#include "ringtrack/pipeline/pipeline.hpp"
#include "ringtrack/sim/scenario.hpp"
#include "ringtrack/sim/simulator.hpp"
#include "ringtrack/version.hpp"

int main() {
  using namespace ringtrack;
  sim::Scenario scenario = sim::builtin_scenario("empty-field");
  scenario.duration_s = 4.0;  // enough scans to confirm tracks, short enough for a test
  sim::Simulator simulator(scenario, /*seed=*/1);
  pipeline::Pipeline pipeline(core::Config{}, simulator.model());

  int scans = 0;
  int reported = 0;
  int on_person = 0;
  while (simulator.next_index() < simulator.scan_count()) {
    const sim::SimulatedScan s = simulator.next();
    const pipeline::FrameResult& frame = pipeline.process(s.scan, s.pose);
    ++scans;
    if (simulator.next_index() < simulator.scan_count()) continue;
    // The last scan: compare each reported track with the walkers' true positions.
    for (const tracking::Hypothesis& h : frame.hypotheses) {
      if (!h.reported) continue;
      ++reported;
      const Eigen::Vector3d world = h.reported_position + frame.origin;
      for (const sim::ObjectTruth& truth : s.objects) {
        if ((world.head<2>() - truth.body_center_m.head<2>().cast<double>()).norm() < 1.0) {
          ++on_person;
          break;
        }
      }
    }
  }
  std::printf("ringtrack %s: %d scans, %d reported tracks, %d on a true person\n", kVersion, scans,
              reported, on_person);
  return on_person > 0 ? 0 : 1;
}
