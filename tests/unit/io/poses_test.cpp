#include "ringtrack/io/poses.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "io_test_util.hpp"
#include "ringtrack/core/error.hpp"
#include "ringtrack/io/text.hpp"

namespace ringtrack::io {
namespace {

using test::input_error;

Eigen::Quaterniond yaw(double rad) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(rad, Eigen::Vector3d::UnitZ()));
}

TEST(Stamps, ParseAndFormatExactly) {
  EXPECT_EQ(parse_stamp_ns("1700000000.123456789"), 1700000000123456789LL);
  EXPECT_EQ(parse_stamp_ns("12.5"), 12500000000LL);
  EXPECT_EQ(parse_stamp_ns("7"), 7000000000LL);
  EXPECT_EQ(parse_stamp_ns("-0.25"), -250000000LL);
  EXPECT_EQ(parse_stamp_ns("0.0000000015"), 2LL);  // rounded half up at the tenth decimal
  EXPECT_EQ(parse_stamp_ns("1.5e3"), 1500000000000LL);
  EXPECT_FALSE(parse_stamp_ns("nan"));
  EXPECT_FALSE(parse_stamp_ns("1.2.3"));
  EXPECT_FALSE(parse_stamp_ns(""));
  EXPECT_EQ(format_stamp(1700000000123456789LL), "1700000000.123456789");
  EXPECT_EQ(format_stamp(12500000000LL), "12.500000000");
  EXPECT_EQ(format_stamp(-250000000LL), "-0.250000000");
  EXPECT_EQ(format_stamp(0), "0.000000000");
  for (std::int64_t ns : {0LL, 1LL, -1LL, 999999999LL, 1700000000123456789LL}) {
    EXPECT_EQ(parse_stamp_ns(format_stamp(ns)), ns);
  }
}

TEST(Poses, ReadsTumAndInterpolates) {
  test::TempDir dir;
  // Comment, blank line, tabs, commas and an unnormalized quaternion (0.999 norm) are accepted.
  test::write_text(dir / "poses.txt",
                   "# timestamp tx ty tz qx qy qz qw\n"
                   "\n"
                   "10.0 0 0 0 0 0 0 1\n"
                   "10.5\t1 2 3 0 0 0.7071067811865476 0.7071067811865476\n"
                   "11.0,2,4,6,0,0,0.999,0\n");
  const Trajectory t = read_tum(dir / "poses.txt");
  ASSERT_EQ(t.size(), 3u);
  EXPECT_EQ(t.start_ns(), 10'000'000'000LL);
  EXPECT_EQ(t.end_ns(), 11'000'000'000LL);
  EXPECT_NEAR(t.poses()[2].rotation.norm(), 1.0, 1e-12);
  // Exactly at a sample.
  const core::Pose at_sample = t.at(10'500'000'000LL);
  EXPECT_TRUE(at_sample.translation.isApprox(Eigen::Vector3d(1, 2, 3)));
  // A quarter of the way between the first two: translation linear, rotation slerp (90 deg yaw).
  const core::Pose q = t.at(10'125'000'000LL);
  EXPECT_EQ(q.stamp_ns, 10'125'000'000LL);
  EXPECT_TRUE(q.translation.isApprox(Eigen::Vector3d(0.25, 0.5, 0.75), 1e-12));
  EXPECT_NEAR(q.rotation.angularDistance(yaw(std::numbers::pi / 8)), 0.0, 1e-9);
  // Between the second (90 deg) and the third (180 deg): the short way, 135 deg at the middle.
  EXPECT_NEAR(t.at(10'750'000'000LL).rotation.angularDistance(yaw(3 * std::numbers::pi / 4)), 0.0,
              1e-6);
  // Endpoints are inside, anything beyond is an error naming the stamp and the range.
  EXPECT_NO_THROW((void)t.at(11'000'000'000LL));
  const std::string e = input_error([&] { (void)t.at(11'000'000'001LL); });
  EXPECT_NE(e.find("no pose for stamp 11.000000001 (poses cover 10.000000000 to 11.000000000)"),
            std::string::npos)
      << e;
  EXPECT_FALSE(t.covers(9'999'999'999LL));
}

TEST(Poses, InterpolationTakesTheShortRotation) {
  // q and -q are the same rotation; slerp must not swing the long way round.
  core::Pose a;
  a.stamp_ns = 0;
  a.rotation = yaw(0.1);
  core::Pose b;
  b.stamp_ns = 100;
  b.rotation = Eigen::Quaterniond(-yaw(0.3).coeffs());
  const Trajectory t({a, b});
  EXPECT_NEAR(t.at(50).rotation.angularDistance(yaw(0.2)), 0.0, 1e-9);
}

std::string tum_error(const std::string& body) {
  test::TempDir dir;
  test::write_text(dir / "p.txt", body);
  return input_error([&] { (void)read_tum(dir / "p.txt"); });
}

TEST(Poses, RejectsMalformedTum) {
  std::string e = tum_error("0 0 0 0 0 0 0 1\n1 0 0 0 0 0 1\n");
  EXPECT_NE(e.find("p.txt:2: expected 8 values (t x y z qx qy qz qw), got 7"), std::string::npos)
      << e;
  e = tum_error("# c\n0 0 0 0 0 0 0 1\n1 0 nan 0 0 0 0 1\n");
  EXPECT_NE(e.find("p.txt:3: y is nan, expected a finite number"), std::string::npos) << e;
  e = tum_error("0 0 0 0 0 0 0 1\n1 0 0 x 0 0 0 1\n");
  EXPECT_NE(e.find("p.txt:2: z is not a number: 'x'"), std::string::npos) << e;
  e = tum_error("0 0 0 0 0 0 0 1\n0 0 0 0 0 0 0 1\n");
  EXPECT_NE(e.find("p.txt:2: stamp 0.000000000 does not increase (previous 0.000000000)"),
            std::string::npos)
      << e;
  e = tum_error("1 0 0 0 0 0 0 1\n0.5 0 0 0 0 0 0 1\n");
  EXPECT_NE(e.find("does not increase"), std::string::npos) << e;
  e = tum_error("0 0 0 0 0 0 0 0\n");
  EXPECT_NE(e.find("p.txt:1: quaternion (qx qy qz qw) has norm 0"), std::string::npos) << e;
  e = tum_error("abc 0 0 0 0 0 0 1\n");
  EXPECT_NE(e.find("p.txt:1: t is not a stamp in seconds: 'abc'"), std::string::npos) << e;
  test::TempDir dir;
  EXPECT_NE(input_error([&] { (void)read_tum(dir / "none.txt"); }).find("none.txt: cannot open"),
            std::string::npos);
}

TEST(Poses, ReadsKittiWithStampsFromElsewhere) {
  test::TempDir dir;
  // Identity, then a 90 deg yaw with a translation.
  test::write_text(dir / "kitti.txt",
                   "1 0 0 0 0 1 0 0 0 0 1 0\n"
                   "0 -1 0 5 1 0 0 6 0 0 1 7\n");
  const std::vector<std::int64_t> stamps{100, 200};
  const Trajectory t = read_kitti(dir / "kitti.txt", stamps);
  ASSERT_EQ(t.size(), 2u);
  EXPECT_EQ(t.poses()[1].stamp_ns, 200);
  EXPECT_TRUE(t.poses()[1].translation.isApprox(Eigen::Vector3d(5, 6, 7)));
  EXPECT_NEAR(t.poses()[1].rotation.angularDistance(yaw(std::numbers::pi / 2)), 0.0, 1e-12);
  EXPECT_NEAR(t.at(150).rotation.angularDistance(yaw(std::numbers::pi / 4)), 0.0, 1e-12);
  // The 3x4 matrix maps a sensor point into the world.
  const Eigen::Vector3f p = t.poses()[1].to_world(Eigen::Vector3f(1, 0, 0));
  EXPECT_TRUE(p.isApprox(Eigen::Vector3f(5, 7, 7)));

  const std::vector<std::int64_t> three{1, 2, 3};
  EXPECT_NE(input_error([&] {
              (void)read_kitti(dir / "kitti.txt", three);
            }).find("2 KITTI poses for 3 stamps"),
            std::string::npos);
  test::write_text(dir / "bad.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n2 0 0 0 0 1 0 0 0 0 1 0\n");
  EXPECT_NE(input_error([&] {
              (void)read_kitti_poses(dir / "bad.txt");
            }).find("bad.txt:2: the 3x3 part is not a rotation matrix"),
            std::string::npos);
  test::write_text(dir / "mirror.txt", "-1 0 0 0 0 1 0 0 0 0 1 0\n");
  EXPECT_NE(input_error([&] { (void)read_kitti_poses(dir / "mirror.txt"); }).find("not a rotation"),
            std::string::npos);
  test::write_text(dir / "short.txt", "1 0 0 0 0 1 0 0 0 0 1\n");
  EXPECT_NE(input_error([&] {
              (void)read_kitti_poses(dir / "short.txt");
            }).find("short.txt:1: expected 12 values"),
            std::string::npos);
  test::write_text(dir / "nan.txt", "1 0 0 nan 0 1 0 0 0 0 1 0\n");
  EXPECT_NE(
      input_error([&] { (void)read_kitti_poses(dir / "nan.txt"); }).find("nan.txt:1: tx is nan"),
      std::string::npos);
  EXPECT_NE(input_error([&] {
              (void)read_kitti(dir / "kitti.txt", std::vector<std::int64_t>{5, 5});
            }).find("does not increase"),
            std::string::npos);
}

TEST(Poses, TumRoundTrip) {
  test::TempDir dir;
  std::vector<core::Pose> poses(3);
  for (int k = 0; k < 3; ++k) {
    poses[k].stamp_ns = 1700000000000000000LL + k * 100'000'001LL;
    poses[k].translation = Eigen::Vector3d(k * 1.25, -k * 0.5, 2.5);
    poses[k].rotation =
        Eigen::Quaterniond(Eigen::AngleAxisd(0.3 * k, Eigen::Vector3d(1, 2, 3).normalized()));
  }
  write_tum(dir / "p.txt", poses);
  const Trajectory t = read_tum(dir / "p.txt");
  ASSERT_EQ(t.size(), 3u);
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(t.poses()[k].stamp_ns, poses[k].stamp_ns);
    EXPECT_TRUE(t.poses()[k].translation.isApprox(poses[k].translation, 1e-9));
    EXPECT_NEAR(t.poses()[k].rotation.angularDistance(poses[k].rotation), 0.0, 1e-8);
  }
  EXPECT_EQ(format_tum_line(poses[0]),
            "1700000000.000000000 0.000000 0.000000 2.500000 0.000000000 0.000000000 0.000000000 "
            "1.000000000");
}

TEST(Poses, TrajectoryRejectsBadSamples) {
  core::Pose a;
  core::Pose b;
  b.stamp_ns = 5;
  b.translation.x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(input_error([&] {
              Trajectory({a, b}, "src");
            }).find("src: pose 1 at 0.000000005: translation or rotation is not finite"),
            std::string::npos);
  EXPECT_THROW(Trajectory({a, a}), core::InputError);
  EXPECT_NE(input_error([&] { (void)Trajectory().at(0); }).find("(no poses)"), std::string::npos);
}

}  // namespace
}  // namespace ringtrack::io
