#include "ringtrack/io/csv_writers.hpp"

#include <gtest/gtest.h>

#include "io_test_util.hpp"
#include "ringtrack/core/error.hpp"

namespace ringtrack::io {
namespace {

TEST(CsvWriters, TracksCsvHasTheDocumentedSchema) {
  test::TempDir dir;
  TrackRow a;
  a.scan = 3;
  a.stamp_ns = 300'000'000;
  a.id = 17;
  a.position = {1.23456, -2.0, 0.9};
  a.velocity = {1.0, -0.00001, 0.0};  // a tiny negative prints as 0.0000, not -0.0000
  a.box.extend(Eigen::Vector3f(1.0f, -2.25f, 0.0f));
  a.box.extend(Eigen::Vector3f(1.5f, -1.75f, 1.75f));
  a.dynamic = true;
  a.ever_dynamic = true;
  a.age = 12;
  a.points = 40;
  a.person = true;
  TrackRow b;  // a hypothesis without a detection in this scan: empty box
  b.scan = 3;
  b.stamp_ns = 300'000'000;
  b.id = 18;
  {
    TracksCsvWriter w(dir / "tracks.csv");
    w.write(std::vector<TrackRow>{a, b});
    w.close();
  }
  EXPECT_EQ(
      test::read_text(dir / "tracks.csv"),
      "scan,stamp,id,x,y,z,vx,vy,vz,min_x,min_y,min_z,max_x,max_y,max_z,dynamic,ever_dynamic,"
      "age,points,person\n"
      "3,0.300000000,17,1.2346,-2.0000,0.9000,1.0000,0.0000,0.0000,1.0000,-2.2500,0.0000,"
      "1.5000,-1.7500,1.7500,1,1,12,40,1\n"
      "3,0.300000000,18,0.0000,0.0000,0.0000,0.0000,0.0000,0.0000,nan,nan,nan,nan,nan,nan,0,0,"
      "0,0,0\n");
}

TEST(CsvWriters, ObjectsCsvHasTheDocumentedSchema) {
  ObjectRow r;
  r.scan = 0;
  r.stamp_ns = 1'700'000'000'050'000'000LL;
  r.id = 4;
  r.class_name = "person";
  r.points = 23;
  r.centroid = {10.0, 5.5, -1.5};
  r.box.extend(Eigen::Vector3f(9.75f, 5.25f, -2.5f));
  r.box.extend(Eigen::Vector3f(10.25f, 5.75f, -0.75f));
  r.true_center = {10.1, 5.5, -1.625};
  r.moving = true;
  EXPECT_EQ(format_object_row(r),
            "0,1700000000.050000000,4,person,23,10.0000,5.5000,-1.5000,9.7500,5.2500,-2.5000,"
            "10.2500,5.7500,-0.7500,10.1000,5.5000,-1.6250,1");
  EXPECT_EQ(kObjectsCsvHeader,
            "scan,stamp,id,class,points,x,y,z,min_x,min_y,min_z,max_x,max_y,max_z,true_x,true_y,"
            "true_z,moving");
  r.class_name = "per,son";
  EXPECT_THROW((void)format_object_row(r), core::Error);
  r.class_name = "";
  EXPECT_THROW((void)format_object_row(r), core::Error);
}

TEST(CsvWriters, TimingCsvTakesItsColumnsFromTheStages) {
  test::TempDir dir;
  TimingCsvWriter w(dir / "timing.csv");
  TimingRow row;
  row.scan = 0;
  row.stamp_ns = 0;
  row.stages = {{"segmentation", 0.12345}, {"detection", 0.05}};
  row.total_ms = 0.2;
  w.write(row);
  row.scan = 1;
  row.stamp_ns = 100'000'000;
  w.write(row);
  TimingRow other = row;
  other.stages = {{"segmentation", 1.0}};
  EXPECT_THROW(w.write(other), core::Error);
  w.close();
  EXPECT_EQ(test::read_text(dir / "timing.csv"),
            "scan,stamp,segmentation_ms,detection_ms,total_ms\n"
            "0,0.000000000,0.1235,0.0500,0.2000\n"
            "1,0.100000000,0.1235,0.0500,0.2000\n");
  TimingCsvWriter bad(dir / "bad.csv");
  TimingRow named;
  named.stages = {{"Has Space", 1.0}};
  EXPECT_THROW(bad.write(named), core::Error);
  TimingCsvWriter none(dir / "none.csv");
  none.close();
  EXPECT_EQ(test::read_text(dir / "none.csv"), "scan,stamp,total_ms\n");
}

TEST(CsvWriters, ReportDiskFull) {
  if (!std::filesystem::exists("/dev/full")) GTEST_SKIP() << "/dev/full not available";
  TracksCsvWriter w("/dev/full");
  TrackRow row;
  w.write(row);
  try {
    w.close();
    ADD_FAILURE() << "no error";
  } catch (const core::Error& e) {
    EXPECT_NE(std::string(e.what()).find("/dev/full: write failed: No space left on device"),
              std::string::npos)
        << e.what();
  }
  // Large outputs fail while writing, before close.
  ObjectsCsvWriter objects("/dev/full");
  ObjectRow o;
  EXPECT_THROW(
      {
        for (int k = 0; k < 100000; ++k) objects.write(o);
      },
      core::Error);
  test::TempDir dir;
  EXPECT_THROW(TracksCsvWriter(dir / "missing/tracks.csv"), core::Error);
}

}  // namespace
}  // namespace ringtrack::io
