#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include "ringtrack/core/error.hpp"
#include "ringtrack/pipeline/pipeline.hpp"

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

}  // namespace
}  // namespace ringtrack::pipeline
