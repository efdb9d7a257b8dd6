// Ray-primitive intersections against closed forms.

#include "ringtrack/sim/geometry.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>

#include "ringtrack/sim/random.hpp"

namespace ringtrack::sim {
namespace {

TEST(Geometry, BoxFacesAndYaw) {
  const auto box = Primitive::box({10.0, 0.0}, 0.0, {2.0, 4.0, 3.0}, 0.0);
  const Eigen::Vector3d o{0, 0, 1};
  EXPECT_NEAR(intersect(box, o, Eigen::Vector3d::UnitX(), 0, 100), 9.0, 1e-12);
  EXPECT_EQ(intersect(box, o, Eigen::Vector3d::UnitY(), 0, 100), kNoHit);
  EXPECT_EQ(intersect(box, o, Eigen::Vector3d::UnitX(), 0, 8.5), kNoHit);  // beyond t_max
  EXPECT_TRUE(normal_at(box, {9.0, 0.0, 1.0}).isApprox(-Eigen::Vector3d::UnitX()));
  // Rotated by 45 deg: the near corner at distance 10 - sqrt(2) along the diagonal direction...
  const auto rotated = Primitive::box({10.0, 0.0}, 0.0, {2.0, 2.0, 3.0}, std::numbers::pi / 4);
  EXPECT_NEAR(intersect(rotated, o, Eigen::Vector3d::UnitX(), 0, 100), 10.0 - std::sqrt(2.0),
              1e-12);
  // From above onto the top face at z = 3.
  EXPECT_NEAR(intersect(box, {10, 0, 10}, -Eigen::Vector3d::UnitZ(), 0, 100), 7.0, 1e-12);
}

TEST(Geometry, CylinderSideAndCap) {
  const auto cyl = Primitive::cylinder({5.0, 0.0}, 0.0, 0.5, 2.0);
  EXPECT_NEAR(intersect(cyl, {0, 0, 1}, Eigen::Vector3d::UnitX(), 0, 100), 4.5, 1e-12);
  // Offset by y = 0.3: chord half length sqrt(0.25 - 0.09) = 0.4.
  EXPECT_NEAR(intersect(cyl, {0, 0.3, 1}, Eigen::Vector3d::UnitX(), 0, 100), 4.6, 1e-12);
  EXPECT_EQ(intersect(cyl, {0, 0.6, 1}, Eigen::Vector3d::UnitX(), 0, 100), kNoHit);
  EXPECT_EQ(intersect(cyl, {0, 0, 2.5}, Eigen::Vector3d::UnitX(), 0, 100), kNoHit);  // above it
  // Down onto the cap.
  EXPECT_NEAR(intersect(cyl, {5.2, 0, 5}, -Eigen::Vector3d::UnitZ(), 0, 100), 3.0, 1e-12);
  EXPECT_TRUE(normal_at(cyl, {5.2, 0, 2}).isApprox(Eigen::Vector3d::UnitZ()));
  // Slanted ray through the side: the closed form of the quadratic.
  const Eigen::Vector3d d = Eigen::Vector3d(1, 0.1, -0.05).normalized();
  const Eigen::Vector3d o{0, 0, 1.5};
  const double a = d.x() * d.x() + d.y() * d.y();
  const double b = 2 * (-5.0 * d.x());
  const double c = 25.0 - 0.25;
  const double t = (-b - std::sqrt(b * b - 4 * a * c)) / (2 * a);
  EXPECT_NEAR(intersect(cyl, o, d, 0, 100), t, 1e-9);
}

TEST(Geometry, EllipsoidMatchesSphereAndScaledForms) {
  const auto sphere = Primitive::ellipsoid({20, 0, 0}, {1, 1, 1}, Eigen::Matrix3d::Identity());
  EXPECT_NEAR(intersect(sphere, {0, 0, 0}, Eigen::Vector3d::UnitX(), 0, 100), 19.0, 1e-12);
  EXPECT_NEAR(intersect(sphere, {0, 0.6, 0}, Eigen::Vector3d::UnitX(), 0, 100), 20.0 - 0.8, 1e-12);
  // Far away and small: the closest-approach form stays accurate.
  const auto small =
      Primitive::ellipsoid({90, 0, 0}, {0.05, 0.05, 0.05}, Eigen::Matrix3d::Identity());
  EXPECT_NEAR(intersect(small, {0, 0.03, 0}, Eigen::Vector3d::UnitX(), 0, 100), 90.0 - 0.04, 1e-9);
  // Rotated ellipsoid with semi-axes (3, 1, 1) along (cos 30, sin 30): a ray along its long axis
  // through the centre hits at distance |c| - 3.
  const Eigen::Matrix3d rot =
      Eigen::AngleAxisd(std::numbers::pi / 6, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Eigen::Vector3d c = 10.0 * rot.col(0);
  const auto ell = Primitive::ellipsoid(c, {3, 1, 1}, rot);
  EXPECT_NEAR(intersect(ell, {0, 0, 0}, rot.col(0), 0, 100), 7.0, 1e-12);
  // Across it (perpendicular to the long axis through the centre): 1 m semi-axis.
  const Eigen::Vector3d o = c - 5.0 * rot.col(1);
  EXPECT_NEAR(intersect(ell, o, rot.col(1), 0, 100), 4.0, 1e-12);
  EXPECT_TRUE(normal_at(ell, c - rot.col(1)).isApprox(-rot.col(1)));
  // Horizontal bound of the rotated ellipsoid contains the far tip.
  EXPECT_GE(ell.bound_radius_xy + 1e-9, 3.0);
}

TEST(Geometry, FlatAndUndulatingGround) {
  Ground g;
  g.height_m = 0.0;
  const Eigen::Vector3d o{0, 0, 2.5};
  const double el = -15.0 * std::numbers::pi / 180.0;
  const Eigen::Vector3d d{std::cos(el), 0, std::sin(el)};
  EXPECT_NEAR(g.intersect(o, d, 0, 200), 2.5 / std::sin(-el), 1e-12);
  EXPECT_EQ(g.intersect(o, Eigen::Vector3d::UnitX(), 0, 200), kNoHit);
  // Height field: the hit lies on the surface and no earlier sample along the ray is below it.
  g.amplitude_m = 0.4;
  g.wavelength_m = 30.0;
  g.phase_rad = 0.3;
  Rng rng(3);
  for (int i = 0; i < 200; ++i) {
    const double e = rng.uniform(-15, -1) * std::numbers::pi / 180.0;
    const double az = rng.uniform(-3.14, 3.14);
    const Eigen::Vector3d dir{std::cos(e) * std::cos(az), std::cos(e) * std::sin(az), std::sin(e)};
    const double t = g.intersect(o, dir, 0, 100);
    if (t == kNoHit) continue;
    const Eigen::Vector3d x = o + t * dir;
    EXPECT_NEAR(x.z(), g.height_at(x.x(), x.y()), 1e-5);
    for (double s = 0; s < t - 1e-3; s += 0.01) {
      const Eigen::Vector3d y = o + s * dir;
      ASSERT_GT(y.z() - g.height_at(y.x(), y.y()), -1e-6) << "missed an earlier crossing at " << s;
    }
  }
}

TEST(Geometry, FastAtan2IsAccurate) {
  Rng rng(5);
  for (int i = 0; i < 10000; ++i) {
    const double y = rng.uniform(-1, 1), x = rng.uniform(-1, 1);
    // Far below the simulator's one-bin margin (2 pi / 1024 = 6e-3 rad).
    EXPECT_NEAR(fast_atan2(y, x), std::atan2(y, x), 2.5e-4);
  }
}

}  // namespace
}  // namespace ringtrack::sim
