// The tracking and mapping sections of the configuration: keys, ranges and cross-checks.

#include <gtest/gtest.h>

#include <string>

#include "ringtrack/core/config.hpp"
#include "ringtrack/core/error.hpp"

namespace ringtrack::core {
namespace {

TEST(TrackingConfig, ReadsEveryKeyAndDumpsItBack) {
  Config c;
  apply_config_yaml(
      c,
      "tracking:\n  cost: mahalanobis\n  gate_mahalanobis: 3.5\n  process_noise: 0.4\n"
      "  delete_eigenvalue_m2: 2\n  rest_scans_to_static: 0\n"
      "mapping:\n  log_delay_scans: 20\n  voxel_size_m: 0.05\n  box_margin_m: 0\n",
      "t.yaml");
  EXPECT_EQ(c.tracking.cost, AssociationCost::kMahalanobis);
  EXPECT_DOUBLE_EQ(c.tracking.gate_mahalanobis, 3.5);
  EXPECT_DOUBLE_EQ(c.tracking.process_noise, 0.4);
  EXPECT_EQ(c.tracking.rest_scans_to_static, 0);
  EXPECT_EQ(c.mapping.log_delay_scans, 20);
  EXPECT_DOUBLE_EQ(c.mapping.voxel_size_m, 0.05);
  Config d;
  apply_config_yaml(d, dump_config(c), "dump");
  EXPECT_EQ(dump_config(d), dump_config(c));
  EXPECT_NE(dump_config(c).find("tracking:"), std::string::npos);
  EXPECT_NE(dump_config(c).find("mapping:"), std::string::npos);
}

void expect_error(const std::string& yaml, const std::string& fragment) {
  Config c;
  try {
    apply_config_yaml(c, yaml, "bad.yaml");
    FAIL() << "no error for: " << yaml;
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
  }
}

TEST(TrackingConfig, RejectsBadValuesByName) {
  expect_error("tracking:\n  cost: greedy\n", "tracking.cost");
  expect_error("tracking:\n  gate_bhattacharyya: 0\n", "tracking.gate_bhattacharyya");
  expect_error("tracking:\n  process_noise: -1\n", "tracking.process_noise");
  expect_error("tracking:\n  rest_scans_to_static: 1.5\n", "tracking.rest_scans_to_static");
  expect_error("tracking:\n  min_speed_kmh: 16\n", "min_speed_kmh");  // above max (15)
  expect_error("mapping:\n  voxel_size_m: 0\n", "mapping.voxel_size_m");
  expect_error("mapping:\n  log_delay_scans: -1\n", "mapping.log_delay_scans");
  expect_error("mapping:\n  nope: 1\n", "mapping.nope");
}

}  // namespace
}  // namespace ringtrack::core
