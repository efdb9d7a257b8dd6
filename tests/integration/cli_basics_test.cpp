// The CLI's basic contract: version, dump-config, config errors naming the key, demo output.

#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <sstream>

#include "ringtrack/core/config.hpp"
#include "support/run_command.hpp"

namespace ringtrack {
namespace {

using testing::run_command;

const std::string kCli = RINGTRACK_CLI_PATH;

TEST(CliBasics, Version) {
  const auto r = run_command(kCli + " --version");
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.out.find("ringtrack "), std::string::npos);
}

TEST(CliBasics, DumpConfigPrintsEveryKeyAndReadsBack) {
  const auto r = run_command(kCli + " dump-config --set detection.min_cluster_points=7");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const auto& info : core::describe_config(core::Config{})) {
    const auto name = info.key.substr(info.key.find('.') + 1);
    EXPECT_NE(r.out.find("  " + name + ": "), std::string::npos) << info.key;
  }
  EXPECT_NE(r.out.find("min_cluster_points: 7"), std::string::npos);
  core::Config c;
  core::apply_config_yaml(c, r.out, "dump");
  EXPECT_EQ(c.detection.min_cluster_points, 7);
}

TEST(CliBasics, ShippedDefaultConfigMatchesDumpConfig) {
  std::ifstream in(std::string(RINGTRACK_SOURCE_DIR) + "/config/default.yaml");
  ASSERT_TRUE(in) << "config/default.yaml missing";
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_EQ(text.str(), core::dump_config(core::Config{}))
      << "regenerate with: ringtrack dump-config > config/default.yaml";
}

TEST(CliBasics, UnknownKeyFailsNamingTheKey) {
  const std::string dir = testing::make_temp_dir("ringtrack-cli-");
  { std::ofstream(dir + "/bad.yaml") << "segmentation:\n  max_widht_m: 1.0\n"; }
  const auto r = run_command(kCli + " dump-config --config " + dir + "/bad.yaml");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_TRUE(r.out.empty());
  EXPECT_NE(r.err.find("segmentation.max_widht_m"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("bad.yaml"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << "one line: " << r.err;
}

TEST(CliBasics, OutOfRangeOverrideFailsNamingTheKey) {
  const auto r = run_command(kCli + " dump-config --set segmentation.certainty_threshold=2");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("segmentation.certainty_threshold"), std::string::npos) << r.err;
}

TEST(CliBasics, OutOfRangeLogDelayFailsNamingTheKey) {
  // Issue 16: every logged scan stays in memory; the bound keeps the log below 1 GB.
  const auto r = run_command(kCli + " dump-config --set mapping.log_delay_scans=5000");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("mapping.log_delay_scans"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("expected"), std::string::npos) << r.err;
  EXPECT_EQ(run_command(kCli + " dump-config --set mapping.log_delay_scans=1000").exit_code, 0);
}

TEST(CliBasics, OutputThatCannotBeWrittenIsAnError) {
  // Issue 16: `dump-config > /dev/full` exited 0. The braces redirect the tool's own output.
  const auto r = run_command("{ " + kCli + " dump-config > /dev/full; }");
  EXPECT_EQ(r.exit_code, 1);
  // (The cause is named when the last flush reports it; an earlier failed write leaves only the
  // stream's error flag.)
  EXPECT_EQ(r.err.rfind("ringtrack: error: cannot write to standard output", 0), 0u) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
}

TEST(CliBasics, DemoFindsTheFivePeople) {
  const auto r = run_command(kCli + " demo --runs 1");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (int id = 1; id <= 5; ++id) {
    EXPECT_NE(r.out.find("person " + std::to_string(id)), std::string::npos) << r.out;
  }
  EXPECT_EQ(r.out.find("false positive"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("segmentation"), std::string::npos);
}

}  // namespace
}  // namespace ringtrack
