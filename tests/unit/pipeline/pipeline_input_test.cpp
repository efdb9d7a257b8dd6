#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include "ringtrack/core/error.hpp"
#include "ringtrack/pipeline/pipeline.hpp"
#include "ringtrack/sim/simple_scene.hpp"

namespace ringtrack::pipeline {
namespace {

core::OrganizedScan flat_scan(const core::SensorModel& model) {
  core::OrganizedScan scan(model.rings(), model.columns());
  scan.set_uniform_columns(model, 0);
  for (int r = 0; r < model.rings(); ++r) {
    for (int c = 0; c < model.columns(); ++c) scan.set_range(model, r, c, 10.0f, 1.0f);
  }
  return scan;
}

// The pipeline follows the sensor's beams (free-space tests), so a scan that does not match the
// sensor model, or a pose that is not a pose, is a clear error rather than a silent wrong answer.
TEST(PipelineInput, ScanOfTheWrongSizeAndNanPoseAreClearErrors) {
  Pipeline pipeline(core::Config{}, core::SensorModel::vlp16());
  const auto wrong = flat_scan(core::SensorModel::hdl32e());
  try {
    pipeline.process(wrong, core::Pose{});
    FAIL() << "no error for a 32-ring scan given to a VLP-16 pipeline";
  } catch (const core::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("32"), std::string::npos) << e.what();
  }
  const auto scan = flat_scan(core::SensorModel::vlp16());
  core::Pose nan_pose;
  nan_pose.translation.x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(pipeline.process(scan, nan_pose), core::InputError);
  core::Pose ok;
  ok.stamp_ns = scan.stamp_ns;
  EXPECT_NO_THROW(pipeline.process(scan, ok));
}

TEST(PipelineInput, RejectsAnInconsistentSensorModel) {
  auto model = core::SensorModel::vlp16();
  model.elevation_rad.pop_back();  // tables of different sizes
  EXPECT_THROW(Pipeline(core::Config{}, model), core::Error);
}

// Issue 16: a scan whose stamp goes back (a host clock step, a corrupt bag stamp) or repeats
// aborted the whole run. It is skipped and counted instead, and the run goes on exactly as if the
// scan had never been there (oracle: a second pipeline that never saw it).
TEST(PipelineInput, ScanOlderThanThePreviousIsSkippedAndCounted) {
  const auto model = core::SensorModel::vlp16();
  const auto people = sim::render(model, sim::SimpleScene::open_field(4)).scan;
  const auto at = [&](std::int64_t stamp_ns) {
    core::OrganizedScan scan = people;
    scan.set_uniform_columns(model, stamp_ns);
    return scan;
  };
  const auto pose = [](std::int64_t stamp_ns) {
    core::Pose p;
    p.stamp_ns = stamp_ns;
    return p;
  };
  Pipeline with_step(core::Config{}, model);
  Pipeline without(core::Config{}, model);
  const std::int64_t second = 1'000'000'000;
  for (const std::int64_t t : {1 * second, 2 * second, 3 * second}) {
    EXPECT_FALSE(with_step.process(at(t), pose(t)).skipped);
    without.process(at(t), pose(t));
  }
  const auto& skipped = with_step.process(at(2'500'000'000), pose(2'500'000'000));
  EXPECT_TRUE(skipped.skipped);
  EXPECT_EQ(skipped.skip_reason,
            "stamp 2500000000 ns is 0.500000000 s older than the previous scan's 3000000000 ns (a "
            "clock step or a corrupt stamp); skipped");
  EXPECT_TRUE(skipped.hypotheses.empty());
  EXPECT_EQ(with_step.skipped_scans(), 1u);
  // A scan with the previous scan's stamp (a repeated message) would count as a second
  // observation at the same instant: skipped too.
  const auto& repeated = with_step.process(at(3 * second), pose(3 * second));
  EXPECT_TRUE(repeated.skipped);
  EXPECT_EQ(repeated.skip_reason,
            "stamp 3000000000 ns repeats the previous scan's (a repeated message or a clock that "
            "stood still); skipped");
  EXPECT_EQ(with_step.skipped_scans(), 2u);
  const auto& after = with_step.process(at(4 * second), pose(4 * second));
  EXPECT_FALSE(after.skipped);
  EXPECT_TRUE(after.skip_reason.empty());
  const auto& oracle = without.process(at(4 * second), pose(4 * second));
  ASSERT_EQ(after.hypotheses.size(), oracle.hypotheses.size());
  ASSERT_GE(after.hypotheses.size(), 4u);  // the four people, tracked across the skipped scan
  for (std::size_t k = 0; k < after.hypotheses.size(); ++k) {
    EXPECT_EQ(after.hypotheses[k].id, oracle.hypotheses[k].id);
    EXPECT_EQ(after.hypotheses[k].reported, oracle.hypotheses[k].reported);
  }
  EXPECT_EQ(without.skipped_scans(), 0u);
}

}  // namespace
}  // namespace ringtrack::pipeline
