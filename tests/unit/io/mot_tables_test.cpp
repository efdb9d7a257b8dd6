// Readers of objects.csv, tracks.csv and MOTChallenge files: values, round trips with the writers,
// and the error messages (file, line, column).

#include "ringtrack/io/mot_tables.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <sstream>
#include <string>

#include "ringtrack/core/error.hpp"

namespace ringtrack::io {
namespace {

const std::string kObjectsHead = std::string(kObjectsCsvHeader) + "\n";
const std::string kTracksHead = std::string(kTracksCsvHeader) + "\n";
// tracks.csv as written before the person column (issue 10): still readable.
const std::string kOldTracksHead =
    "scan,stamp,id,x,y,z,vx,vy,vz,min_x,min_y,min_z,max_x,max_y,max_z,dynamic,ever_dynamic,age,"
    "points\n";

std::vector<ObjectRow> objects(const std::string& text) {
  std::istringstream in(text);
  return read_objects_csv(in, "objects.csv");
}

std::vector<TrackRow> tracks(const std::string& text, TracksCsvColumns* present = nullptr) {
  std::istringstream in(text);
  return read_tracks_csv(in, "tracks.csv", present);
}

// Expects an InputError whose message contains every fragment.
template <typename F>
void expect_error(F f, std::initializer_list<std::string> fragments) {
  try {
    f();
    ADD_FAILURE() << "no error thrown";
  } catch (const core::InputError& e) {
    for (const auto& fragment : fragments) {
      EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos)
          << "'" << e.what() << "' lacks '" << fragment << "'";
    }
  }
}

TEST(ObjectsCsv, ReadsRowsIncludingOnesWithoutPoints) {
  const auto rows =
      objects(kObjectsHead +
              "3,0.300000000,7,person,12,1.5,-2,0.9,1.3,-2.2,0,1.7,-1.8,1.8,1.5,-2,"
              "0.9,1\n"
              "\n"
              "3,0.300000000,8,robot,0,nan,nan,nan,nan,nan,nan,nan,nan,nan,4,4,0,0\n");
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0].scan, 3u);
  EXPECT_EQ(rows[0].stamp_ns, 300'000'000);
  EXPECT_EQ(rows[0].id, 7u);
  EXPECT_EQ(rows[0].class_name, "person");
  EXPECT_EQ(rows[0].points, 12u);
  EXPECT_EQ(rows[0].centroid, Eigen::Vector3d(1.5, -2.0, 0.9));
  EXPECT_DOUBLE_EQ(rows[0].box.max.z(), 1.8);  // read in double (UTM-scale boxes)
  EXPECT_TRUE(rows[0].moving);
  EXPECT_TRUE(std::isnan(rows[1].centroid.x()));
  EXPECT_TRUE(rows[1].box.empty());
  EXPECT_FALSE(rows[1].moving);
}

TEST(ObjectsCsv, ColumnsAreFoundByNameInAnyOrder) {
  const auto rows = objects(
      "moving,extra,true_z,true_y,true_x,max_z,max_y,max_x,min_z,min_y,min_x,z,y,x,points,class,id,"
      "stamp,scan\n"
      "0,hello,0,0,0,1,1,1,0,0,0,0.5,0.5,0.5,4,person,2,1.0,9\n");
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(rows[0].scan, 9u);
  EXPECT_EQ(rows[0].id, 2u);
  EXPECT_EQ(rows[0].stamp_ns, 1'000'000'000);
}

TEST(ObjectsCsv, RoundTripsTheWriterFormat) {
  ObjectRow row;
  row.scan = 42;
  row.stamp_ns = 1'700'000'000'123'456'789;
  row.id = 5;
  row.class_name = "drone";
  row.points = 3;
  row.centroid = {1.25, 2.5, -0.75};
  row.box.extend(Eigen::Vector3f(1.0f, 2.0f, -1.0f));
  row.box.extend(Eigen::Vector3f(1.5f, 3.0f, -0.5f));
  row.true_center = {1.2, 2.4, -0.7};
  row.moving = true;
  const auto rows = objects(kObjectsHead + format_object_row(row) + "\n");
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(rows[0].stamp_ns, row.stamp_ns);
  EXPECT_EQ(rows[0].class_name, "drone");
  EXPECT_EQ(rows[0].centroid, row.centroid);
  EXPECT_EQ(rows[0].box.min, row.box.min);
  EXPECT_NEAR(rows[0].true_center.z(), -0.7, 1e-12);
}

TEST(TracksCsv, RoundTripsTheWriterFormat) {
  TrackRow row;
  row.scan = 7;
  row.stamp_ns = 700'000'000;
  row.id = 123;
  row.position = {3.5, -1.25, 0.5};
  row.velocity = {1.0, 0.0, 0.0};
  row.dynamic = false;
  row.ever_dynamic = true;
  row.age = 17;
  row.points = 40;
  const auto rows = tracks(kTracksHead + format_track_row(row) + "\n");
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(rows[0].scan, 7u);
  EXPECT_EQ(rows[0].id, 123u);
  EXPECT_EQ(rows[0].position, row.position);
  EXPECT_TRUE(rows[0].box.empty());  // written as nan
  EXPECT_FALSE(rows[0].dynamic);
  EXPECT_TRUE(rows[0].ever_dynamic);
  EXPECT_EQ(rows[0].age, 17u);
  EXPECT_EQ(rows[0].points, 40u);
}

TEST(TracksCsv, PersonFlagRoundTripsAndOldFilesReadAsNotPerson) {
  TrackRow a;
  a.scan = 2;
  a.id = 5;
  a.position = {1.0, 2.0, 0.9};
  a.person = true;
  TrackRow b = a;
  b.id = 6;
  b.person = false;
  TracksCsvColumns present;
  const auto rows =
      tracks(kTracksHead + format_track_row(a) + "\n" + format_track_row(b) + "\n", &present);
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_TRUE(present.person);
  EXPECT_TRUE(rows[0].person);
  EXPECT_FALSE(rows[1].person);
  // The column is found by name, wherever it stands.
  const auto moved = tracks(
      "person,scan,stamp,id,x,y,z,vx,vy,vz,min_x,min_y,min_z,max_x,max_y,max_z,dynamic,"
      "ever_dynamic,age,points\n1,0,0.0,1,1,2,3,0,0,0,nan,nan,nan,nan,nan,nan,0,0,1,5\n");
  ASSERT_EQ(moved.size(), 1u);
  EXPECT_TRUE(moved[0].person);
  // A file from before the column: readable, every row not a person, and the caller is told.
  present.person = true;
  const auto old =
      tracks(kOldTracksHead + "0,0.0,1,1,2,3,0,0,0,nan,nan,nan,nan,nan,nan,1,1,1,5\n", &present);
  ASSERT_EQ(old.size(), 1u);
  EXPECT_FALSE(present.person);
  EXPECT_FALSE(old[0].person);
  EXPECT_TRUE(old[0].ever_dynamic);
  expect_error(
      [&] {
        (void)tracks(kTracksHead + "0,0.0,1,1,2,3,0,0,0,nan,nan,nan,nan,nan,nan,0,0,1,5,yes\n");
      },
      {"tracks.csv:2", "column 'person'", "0 or 1"});
}

TEST(TracksCsv, ErrorsNameFileLineAndColumn) {
  expect_error([] { (void)tracks("scan,stamp,id,x,y,z\n"); },
               {"tracks.csv:1", "missing column 'vx'"});
  expect_error([] { (void)tracks(""); }, {"tracks.csv", "empty file"});
  const std::string good = "0,0.0,1,1,2,3,0,0,0,nan,nan,nan,nan,nan,nan,0,0,1,5\n";
  expect_error(
      [&] {
        (void)tracks(kOldTracksHead + good +
                     "1,0.1,1,abc,2,3,0,0,0,nan,nan,nan,nan,"
                     "nan,nan,0,0,1,5\n");
      },
      {"tracks.csv:3", "column 'x'", "'abc'"});
  expect_error(
      [&] {
        (void)tracks(kOldTracksHead +
                     "0,0.0,1,nan,2,3,0,0,0,nan,nan,nan,nan,nan,nan,0,"
                     "0,1,5\n");
      },
      {"tracks.csv:2", "column 'x'", "finite"});
  expect_error(
      [&] {
        (void)tracks(kOldTracksHead +
                     "0,0.0,1,1,2,3,0,0,0,nan,nan,nan,nan,nan,nan,2,0,"
                     "1,5\n");
      },
      {"tracks.csv:2", "column 'dynamic'", "0 or 1"});
  expect_error([&] { (void)tracks(kOldTracksHead + "0,0.0,1,1,2\n"); },
               {"tracks.csv:2", "expected 19 comma-separated fields"});
  expect_error([&] { (void)tracks(kOldTracksHead + good + good); },
               {"tracks.csv:3", "id 1 appears twice in scan 0", "line 2"});
  expect_error(
      [&] {
        (void)tracks(kOldTracksHead + good +
                     "0,0.5,2,1,2,3,0,0,0,nan,nan,nan,nan,nan,"
                     "nan,0,0,1,5\n");
      },
      {"tracks.csv:3", "scan 0 has stamp 0.500000000"});
  expect_error(
      [&] {
        (void)tracks(kOldTracksHead +
                     "-1,0.0,1,1,2,3,0,0,0,nan,nan,nan,nan,nan,nan,0,0,"
                     "1,5\n");
      },
      {"tracks.csv:2", "column 'scan'"});
  expect_error([&] { (void)tracks(kOldTracksHead + "0,0.0,1,1,2,3,0,0,0,0,0,0,-1,0,0,0,0,1,5\n"); },
               {"tracks.csv:2", "min <= max"});
  expect_error(
      [&] {
        (void)tracks(kOldTracksHead +
                     "0,5.0,1,1,2,3,0,0,0,nan,nan,nan,nan,nan,nan,0,0,"
                     "1,5\n" +
                     "1,4.0,1,1,2,3,0,0,0,nan,nan,nan,nan,nan,nan,0,0,1,5\n");
      },
      {"scan 1 has stamp 4.000000000, earlier than 5.000000000"});
}

TEST(ObjectsCsv, Errors) {
  expect_error([] { (void)objects("scan,stamp,id,class,points,x,y,z\n"); },
               {"objects.csv:1", "missing column 'min_x'"});
  expect_error(
      [] { (void)objects(kObjectsHead + "0,0.0,1,person,3,nan,0,0,0,0,0,1,1,1,0,0,0,1\n"); },
      {"objects.csv:2", "column 'x'", "finite"});
  expect_error([] { (void)objects(kObjectsHead + "0,0.0,1,,3,0,0,0,0,0,0,1,1,1,0,0,0,1\n"); },
               {"objects.csv:2", "column 'class'"});
  expect_error(
      [] {
        (void)objects(kObjectsHead +
                      "0,0.0,1,person,3,0,0,0,nan,nan,nan,nan,nan,nan,0,"
                      "0,0,1\n");
      },
      {"objects.csv:2", "3 points but no box"});
  expect_error([] { (void)objects(kObjectsHead + "0,x1,1,person,0,0,0,0,0,0,0,1,1,1,0,0,0,1\n"); },
               {"objects.csv:2", "column 'stamp'"});
}

TEST(MotChallenge, ReadsAndDropsIgnoredGroundTruthRows) {
  std::istringstream gt(
      "1,1,10,20,30,40,1,1,1\n"
      "1,2,10,20,30,40,0,7,1\n"  // flag 0: ignored
      "2 1 11.5 20 30 40 1 1 0.5\n");
  const auto rows = read_motchallenge(gt, "gt.txt", true);
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[1].frame, 2);
  EXPECT_DOUBLE_EQ(rows[1].left, 11.5);
  std::istringstream res("1,5,0,0,10,10,0.3,-1,-1,-1\n1.000,6,0,0,10,10\n");
  const auto hyps = read_motchallenge(res, "res.txt", false);
  ASSERT_EQ(hyps.size(), 2u);  // confidence does not filter results
  EXPECT_DOUBLE_EQ(hyps[0].confidence, 0.3);
  EXPECT_EQ(hyps[1].frame, 1);
}

TEST(MotChallenge, Errors) {
  const auto read = [](const std::string& text) {
    std::istringstream in(text);
    return read_motchallenge(in, "res.txt", false);
  };
  expect_error([&] { (void)read("1,1,0,0,10\n"); }, {"res.txt:1", "at least 6 values"});
  expect_error([&] { (void)read("1,1,0,0,10,10\n1,x,0,0,1,1\n"); }, {"res.txt:2", "value 2"});
  expect_error([&] { (void)read("1.5,1,0,0,10,10\n"); }, {"res.txt:1", "value 1", "integer"});
  expect_error([&] { (void)read("1,1,0,0,-10,10\n"); }, {"res.txt:1", "non-negative width"});
  expect_error([&] { (void)read("1,1,0,0,10,10\n1,1,5,5,10,10\n"); },
               {"res.txt:2", "appears twice in frame 1"});
}

TEST(CheckScanStamps, DetectsShiftedScanIndices) {
  const auto gt = objects(kObjectsHead + "0,0.0,1,person,3,0,0,0,0,0,0,1,1,1,0,0,0,1\n" +
                          "1,0.1,1,person,3,0,0,0,0,0,0,1,1,1,0,0,0,1\n");
  const auto ok = tracks(kOldTracksHead + "1,0.1,4,1,2,3,0,0,0,nan,nan,nan,nan,nan,nan,0,0,1,5\n" +
                         "2,0.2,4,1,2,3,0,0,0,nan,nan,nan,nan,nan,nan,0,0,1,5\n");
  EXPECT_NO_THROW(check_scan_stamps(gt, "objects.csv", ok, "tracks.csv"));
  const auto shifted =
      tracks(kOldTracksHead + "0,0.1,4,1,2,3,0,0,0,nan,nan,nan,nan,nan,nan,0,0,1,5\n");
  expect_error([&] { check_scan_stamps(gt, "objects.csv", shifted, "tracks.csv"); },
               {"scan 0 has stamp 0.000000000 in objects.csv but 0.100000000 in tracks.csv"});
}

TEST(ReadFiles, MissingFileIsAnInputError) {
  EXPECT_THROW((void)read_objects_csv(std::filesystem::path("/nonexistent/objects.csv")),
               core::InputError);
}

}  // namespace
}  // namespace ringtrack::io
