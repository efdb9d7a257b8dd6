// `ringtrack run --mcap`: the MCAP file is checked by the reference TypeScript library
// (@mcap/core, tests/mcap/validate_mcap.cjs: CRCs, summary, indexes, statistics), and what it
// decodes is compared with tracks.csv and config.yaml of the same run.

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "ringtrack/io/mot_tables.hpp"
#include "support/mcap_check.hpp"
#include "support/run_command.hpp"

namespace ringtrack {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using testing::run_command;

const std::string kCli = RINGTRACK_CLI_PATH;

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

class RunMcapCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = testing::make_temp_dir("ringtrack-mcap-");
    // An open field with people walking: tracks, dynamic ones among them.
    const auto r = run_command(kCli + " simulate 1 --duration 3 --seed 3 --out " + dir_ + "/seq");
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }

  void SetUp() override {
    const std::string why = testing::mcap_check_unavailable();
    if (!why.empty()) GTEST_SKIP() << "skipped: " << why;
  }

  // Runs the pipeline with --mcap and the given options, then the validator; returns its JSON.
  static json run_and_validate(const std::string& name, const std::string& options) {
    const std::string out = dir_ + "/" + name;
    const auto r = run_command(kCli + " run " + dir_ + "/seq --quiet --out " + out + " --mcap " +
                               out + ".mcap " + options);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.out.find("mcap             " + out + ".mcap"), std::string::npos) << r.out;
    const auto v = run_command(testing::mcap_script("validate_mcap.cjs") + " " + out + ".mcap");
    EXPECT_EQ(v.exit_code, 0) << v.err;
    if (v.exit_code != 0) return json::object();
    return json::parse(v.out);
  }

  static std::string dir_;
};
std::string RunMcapCli::dir_;

std::map<std::string, json> channels_by_topic(const json& j) {
  std::map<std::string, json> out;
  for (const auto& c : j["channels"]) out[c["topic"].get<std::string>()] = c;
  return out;
}

TEST_F(RunMcapCli, ReferenceLibraryReadsEveryTopicWithTheExpectedCounts) {
  const json j = run_and_validate("zstd", "");
  ASSERT_FALSE(j.empty());
  EXPECT_EQ(j["compression"], json::array({"zstd"}));
  EXPECT_EQ(j["library"].get<std::string>().rfind("ringtrack ", 0), 0u);
  const auto channels = channels_by_topic(j);
  const std::map<std::string, std::pair<std::string, int>> expected = {
      {"/ringtrack/scan", {"foxglove.PointCloud", 30}},
      {"/tf", {"foxglove.FrameTransform", 30}},
      {"/ringtrack/detections", {"foxglove.SceneUpdate", 30}},
      {"/ringtrack/tracks", {"foxglove.SceneUpdate", 30}},
      {"/ringtrack/static_map", {"foxglove.PointCloud", 1}},
  };
  ASSERT_EQ(channels.size(), expected.size());
  for (const auto& [topic, schema_count] : expected) {
    ASSERT_TRUE(channels.count(topic)) << topic;
    EXPECT_EQ(channels.at(topic)["schema"], schema_count.first) << topic;
    EXPECT_EQ(channels.at(topic)["encoding"], "protobuf") << topic;
    EXPECT_EQ(channels.at(topic)["messages"], schema_count.second) << topic;
  }
  EXPECT_EQ(j["messages"], 30 * 4 + 1);
  EXPECT_EQ(j["schemas"].size(), 3u);
  for (const auto& s : j["schemas"]) EXPECT_EQ(s["encoding"], "protobuf");
}

TEST_F(RunMcapCli, MetadataHoldsTheEffectiveConfigVersionAndInput) {
  const json j = run_and_validate("meta", "--set mapping.voxel_size_m=0.2");
  ASSERT_FALSE(j.empty());
  EXPECT_EQ(j["metadata"]["config"]["config.yaml"].get<std::string>(),
            slurp(dir_ + "/meta/config.yaml"));
  EXPECT_EQ(j["metadata"]["ringtrack"]["input"], dir_ + "/seq");
  EXPECT_FALSE(j["metadata"]["ringtrack"]["version"].get<std::string>().empty());
}

TEST_F(RunMcapCli, TrackEntitiesAndLabelledPointsMatchTracksCsv) {
  const json j = run_and_validate("tracks", "");
  ASSERT_FALSE(j.empty());
  const auto rows = io::read_tracks_csv(dir_ + "/tracks/tracks.csv");
  ASSERT_FALSE(rows.empty());
  std::map<std::uint64_t, std::vector<io::TrackRow>> by_scan;
  for (const auto& r : rows) by_scan[r.scan].push_back(r);

  const auto& updates = j["decoded"]["/ringtrack/tracks"];
  const auto& clouds = j["decoded"]["/ringtrack/scan"];
  ASSERT_EQ(updates.size(), 30u);
  ASSERT_EQ(clouds.size(), 30u);
  bool saw_dynamic = false;
  std::size_t compared = 0;
  for (std::size_t k = 0; k < updates.size(); ++k) {
    const auto& u = updates[k];
    EXPECT_EQ(u["deletions"], json::array({"ALL"}));  // the scene is exactly this scan's tracks
    std::map<std::string, json> entities;
    for (const auto& e : u["entities"]) entities[e["id"].get<std::string>()] = e;
    const auto& expected = by_scan[k];
    ASSERT_EQ(entities.size(), expected.size()) << "scan " << k;
    std::map<std::string, std::size_t> cloud_tracks;
    for (const auto& [id, n] : clouds[k]["track_points"].items()) cloud_tracks[id] = n;
    for (const auto& row : expected) {
      const std::string id = "track/" + std::to_string(row.id);
      ASSERT_TRUE(entities.count(id)) << id << " in scan " << k;
      const auto& e = entities[id];
      EXPECT_EQ(e["stamp"], std::to_string(row.stamp_ns));
      EXPECT_EQ(e["frame_id"], "world");
      EXPECT_EQ(e["metadata"]["dynamic"], row.dynamic ? "1" : "0");
      EXPECT_EQ(e["metadata"]["person"], row.person ? "1" : "0");
      saw_dynamic = saw_dynamic || row.dynamic;
      ASSERT_EQ(e["cubes"].size(), 1u);
      const auto& c = e["cubes"][0];
      for (int a = 0; a < 3; ++a) {
        // tracks.csv has 4 decimals.
        EXPECT_NEAR(c["center"][a].get<double>(), 0.5 * (row.box.min[a] + row.box.max[a]), 1e-4);
        EXPECT_NEAR(c["size"][a].get<double>(),
                    std::max(0.01, static_cast<double>(row.box.max[a] - row.box.min[a])), 1e-4);
      }
      EXPECT_EQ(e["texts"][0].get<std::string>().rfind(std::to_string(row.id), 0), 0u);
      if (row.velocity.norm() >= 0.05) {
        ASSERT_EQ(e["arrows"].size(), 1u);
        for (int a = 0; a < 3; ++a) {
          EXPECT_NEAR(e["arrows"][0]["position"][a].get<double>(), row.position[a], 1e-4);
        }
        EXPECT_NEAR(e["arrows"][0]["length"].get<double>(), row.velocity.norm(), 1e-3);
      }
      // Every cell of the track's detection is labelled with its id (completion cells too).
      const std::string key = std::to_string(row.id);
      if (row.points > 0) {
        ASSERT_TRUE(cloud_tracks.count(key)) << id << " has no labelled points in scan " << k;
        EXPECT_GE(cloud_tracks[key], row.points);
      }
      cloud_tracks.erase(key);
      ++compared;
    }
    EXPECT_TRUE(cloud_tracks.empty())
        << "points labelled with a track tracks.csv lacks, scan " << k;
  }
  EXPECT_GT(compared, 30u);
  EXPECT_TRUE(saw_dynamic);
}

TEST_F(RunMcapCli, CloudsAndTransformsAreWellFormed) {
  const json j = run_and_validate("clouds", "");
  ASSERT_FALSE(j.empty());
  for (const auto& c : j["decoded"]["/ringtrack/scan"]) {
    EXPECT_EQ(c["frame_id"], "sensor");
    EXPECT_EQ(c["stride"], 24);
    EXPECT_TRUE(c["whole_points"].get<bool>());
    EXPECT_GT(c["points"].get<double>(), 1000);
    std::vector<std::string> names;
    for (const auto& f : c["fields"]) names.push_back(f["name"]);
    EXPECT_EQ(names, (std::vector<std::string>{"x", "y", "z", "intensity", "track_id", "detection",
                                               "segment", "removed"}));
    EXPECT_EQ(c["stamp"], c["log_time"]);
  }
  for (const auto& t : j["decoded"]["/tf"]) {
    EXPECT_EQ(t["parent"], "world");
    EXPECT_EQ(t["child"], "sensor");
    EXPECT_NEAR(t["rotation"][3].get<double>(), 1.0, 1e-9);  // a static sensor at the origin
  }
  const auto& map = j["decoded"]["/ringtrack/static_map"];
  ASSERT_EQ(map.size(), 1u);
  EXPECT_EQ(map[0]["frame_id"], "world");
  EXPECT_EQ(map[0]["stride"], 16);
  // The map cloud holds exactly the voxels of static_map.ply.
  const std::string ply = slurp(dir_ + "/clouds/static_map.ply");
  const auto at = ply.find("element vertex ");
  ASSERT_NE(at, std::string::npos);
  EXPECT_EQ(map[0]["points"].get<double>(), std::stod(ply.substr(at + 15)));
}

TEST_F(RunMcapCli, Lz4UncompressedAndPeriodicMapsValidateToo) {
  const json lz4 = run_and_validate("lz4", "--mcap-compression lz4 --mcap-map-every 10");
  ASSERT_FALSE(lz4.empty());
  EXPECT_EQ(lz4["compression"], json::array({"lz4"}));
  EXPECT_EQ(channels_by_topic(lz4)["/ringtrack/static_map"]["messages"], 3 + 1);
  const json none = run_and_validate("none", "--mcap-compression none");
  ASSERT_FALSE(none.empty());
  EXPECT_EQ(none["compression"], json::array({""}));
  EXPECT_EQ(none["messages"], lz4["messages"].get<int>() - 3);
}

}  // namespace
}  // namespace ringtrack
