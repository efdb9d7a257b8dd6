#include "ringtrack/core/config.hpp"

#include <gtest/gtest.h>

#include "ringtrack/core/error.hpp"

namespace ringtrack::core {
namespace {

TEST(Config, DumpReadsBackUnchanged) {
  Config c;
  c.segmentation.max_width_m = 1.7;
  c.detection.join_rule = JoinRule::kEuclidean;
  Config d;
  apply_config_yaml(d, dump_config(c), "dump");
  EXPECT_EQ(dump_config(d), dump_config(c));
  EXPECT_EQ(d.detection.join_rule, JoinRule::kEuclidean);
  EXPECT_DOUBLE_EQ(d.segmentation.max_width_m, 1.7);
}

TEST(Config, PartialOverrideKeepsOtherDefaults) {
  Config c;
  apply_config_yaml(c, "segmentation:\n  min_width_m: 0.15\n", "test.yaml");
  EXPECT_DOUBLE_EQ(c.segmentation.min_width_m, 0.15);
  EXPECT_DOUBLE_EQ(c.segmentation.max_width_m, Config{}.segmentation.max_width_m);
}

void expect_config_error(const std::string& yaml, const std::string& fragment) {
  Config c;
  try {
    apply_config_yaml(c, yaml, "bad.yaml");
    FAIL() << "no error for: " << yaml;
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("bad.yaml"), std::string::npos) << e.what();
  }
}

TEST(Config, RejectsUnknownKeysAndSectionsByName) {
  expect_config_error("segmentation:\n  min_widht_m: 0.1\n", "segmentation.min_widht_m");
  expect_config_error("segmentatoin:\n  min_width_m: 0.1\n", "segmentatoin");
}

TEST(Config, RejectsOutOfRangeAndMalformedValuesByName) {
  expect_config_error("segmentation:\n  certainty_threshold: 0\n",
                      "segmentation.certainty_threshold");
  expect_config_error("detection:\n  neighbor_radius: 2.5\n", "detection.neighbor_radius");
  expect_config_error("detection:\n  join_distance_m: abc\n", "detection.join_distance_m");
  expect_config_error("detection:\n  join_rule: manhattan\n", "detection.join_rule");
  expect_config_error("segmentation:\n  min_width_m: 2\n  max_width_m: 1\n", "min_width_m");
  expect_config_error("segmentation: [1, 2]\n", "segmentation");
  expect_config_error("segmentation:\n  min_width_m: [1]\n", "segmentation.min_width_m");
}

TEST(Config, AListOrMapAsKeyIsAConfigError) {
  // Found while fixing fuzz_scenario's find: yaml-cpp threw its own exception (no ConfigError)
  // for a key that is a list or a map, at the top level and inside a section.
  expect_config_error("[segmentation]: 1\n",
                      "line 1: expected a key name, got a list or map as key");
  expect_config_error("segmentation:\n  {a: 1}: 2\n",
                      "line 2: expected a key name, got a list or map as key");
}

TEST(Config, FailedLoadLeavesConfigUntouched) {
  Config c;
  EXPECT_THROW(apply_config_yaml(c, "segmentation:\n  min_width_m: 0.2\n  nope: 1\n", "x"),
               ConfigError);
  EXPECT_DOUBLE_EQ(c.segmentation.min_width_m, Config{}.segmentation.min_width_m);
}

TEST(Config, CommandLineOverride) {
  Config c;
  apply_config_override(c, "detection.min_cluster_points=5");
  EXPECT_EQ(c.detection.min_cluster_points, 5);
  EXPECT_THROW(apply_config_override(c, "detection.bogus=5"), ConfigError);
  EXPECT_THROW(apply_config_override(c, "no_dot=5"), ConfigError);
  EXPECT_THROW(apply_config_override(c, "detection.min_cluster_points"), ConfigError);
}

TEST(Config, EveryKeyIsDescribed) {
  for (const auto& info : describe_config(Config{})) {
    EXPECT_FALSE(info.description.empty()) << info.key;
    EXPECT_NE(info.key.find('.'), std::string::npos);
  }
}

}  // namespace
}  // namespace ringtrack::core
