// run.json, the completeness marker of every command that writes outputs (issue 16).
#include "ringtrack/io/run_status.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "ringtrack/core/error.hpp"
#include "support/temp_dir.hpp"

namespace ringtrack::io {
namespace {

nlohmann::json read_json(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return nlohmann::json::parse(text.str());
}

RunStatus example() {
  RunStatus s;
  s.command = "run";
  s.arguments = {"ringtrack", "run", "in", "--out", "out"};
  s.version = "1.2.3";
  s.input = "in";
  return s;
}

TEST(RunStatus, RunningThenFinishedWithCountsAndSkippedScans) {
  test::TempDir dir;
  RunStatusFile file(dir / "run.json", example());
  file.start();
  auto j = read_json(dir / "run.json");
  EXPECT_EQ(j["complete"], false);
  EXPECT_EQ(j["state"], "running");
  EXPECT_TRUE(j["error"].is_null());
  EXPECT_TRUE(j["interrupted"].is_null());
  EXPECT_TRUE(j["ended_utc"].is_null());
  EXPECT_EQ(j["command"], "run");
  EXPECT_EQ(j["version"], "1.2.3");
  EXPECT_EQ(j["arguments"].size(), 5u);
  EXPECT_EQ(j["started_utc"].get<std::string>().size(), 20u);  // 2026-11-26T07:15:13Z
  EXPECT_FALSE(j.contains("origin_m")) << "no scan processed yet: no frame";

  file.status().scans_read = 10;
  file.status().scans_processed = 8;
  file.status().scans_skipped_unreadable = 1;
  file.status().scans_skipped_stamp = 1;
  file.status().add_skipped(3, "unreadable: x.pcd: truncated");
  file.status().add_skipped(7, "stamp goes back");
  file.status().origin_m = {{500000.0, 5000000.0, 100.0}};
  file.finish();
  j = read_json(dir / "run.json");
  EXPECT_EQ(j["complete"], true);
  EXPECT_EQ(j["state"], "finished");
  EXPECT_EQ(j["scans"]["read"], 10);
  EXPECT_EQ(j["scans"]["processed"], 8);
  EXPECT_EQ(j["scans"]["skipped"], 2);
  EXPECT_EQ(j["scans"]["skipped_unreadable"], 1);
  EXPECT_EQ(j["scans"]["skipped_stamp"], 1);
  EXPECT_EQ(j["scans"]["failed"], 0);
  ASSERT_EQ(j["skipped_scans"].size(), 2u);
  EXPECT_EQ(j["skipped_scans"][0]["scan"], 3);
  EXPECT_EQ(j["skipped_scans"][0]["reason"], "unreadable: x.pcd: truncated");
  EXPECT_FALSE(j["ended_utc"].is_null());
  EXPECT_EQ(j["origin_m"], nlohmann::json::array({500000.0, 5000000.0, 100.0}));
  // Written through a temporary file that is renamed: nothing is left beside it.
  EXPECT_FALSE(std::filesystem::exists(dir / "run.json.tmp"));
}

TEST(RunStatus, InterruptedIsCompleteAndNamesTheSignal) {
  test::TempDir dir;
  RunStatusFile file(dir / "run.json", example());
  file.start();
  file.finish("SIGTERM");
  const auto j = read_json(dir / "run.json");
  EXPECT_EQ(j["complete"], true);
  EXPECT_EQ(j["state"], "interrupted");
  EXPECT_EQ(j["interrupted"], "SIGTERM");
}

TEST(RunStatus, FailedIsIncompleteWithTheErrorAndFailNeverThrows) {
  test::TempDir dir;
  RunStatusFile file(dir / "run.json", example());
  file.start();
  file.status().scans_failed = 1;
  file.fail("in/scans/000010.pcd: truncated \xff binary data");  // invalid UTF-8 is replaced
  const auto j = read_json(dir / "run.json");
  EXPECT_EQ(j["complete"], false);
  EXPECT_EQ(j["state"], "failed");
  EXPECT_NE(j["error"].get<std::string>().find("000010.pcd: truncated"), std::string::npos);
  EXPECT_EQ(j["scans"]["failed"], 1);
  // A folder that cannot be written: fail() swallows the error (another is on its way),
  // start() reports it naming the file.
  RunStatusFile nowhere(dir / "missing" / "run.json", example());
  EXPECT_NO_THROW(nowhere.fail("boom"));
  try {
    nowhere.start();
    FAIL() << "no error for a run.json in a missing folder";
  } catch (const core::Error& e) {
    EXPECT_NE(std::string(e.what()).find("run.json"), std::string::npos) << e.what();
  }
}

TEST(RunStatus, SkippedListIsBoundedButCountsAreNot) {
  RunStatus s = example();
  for (std::uint64_t k = 0; k < kMaxListedSkippedScans + 5; ++k) s.add_skipped(k, "bad");
  EXPECT_EQ(s.skipped.size(), kMaxListedSkippedScans);
}

TEST(RunStatus, AtomicWriteReplacesAnExistingFile) {
  test::TempDir dir;
  write_file_atomically(dir / "a.txt", "old");
  write_file_atomically(dir / "a.txt", "new text");
  std::ifstream in(dir / "a.txt");
  std::string text;
  std::getline(in, text);
  EXPECT_EQ(text, "new text");
  EXPECT_FALSE(std::filesystem::exists(dir / "a.txt.tmp"));
}

}  // namespace
}  // namespace ringtrack::io
