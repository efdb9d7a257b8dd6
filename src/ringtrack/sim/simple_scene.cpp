#include "ringtrack/sim/simple_scene.hpp"

#include <cmath>
#include <limits>
#include <numbers>
#include <random>

namespace ringtrack::sim {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Nearest positive distance along a horizontal-unit-projected ray to a vertical cylinder's
// side, or +inf; dxy is the horizontal direction (unit), h the horizontal-per-range scale.
double hit_cylinder(const Cylinder& c, double ox, double oy, double oz, double dx, double dy,
                    double dz) {
  const double px = ox - c.x_m, py = oy - c.y_m;
  const double a = dx * dx + dy * dy;
  if (a < 1e-12) return kInf;
  const double b = 2.0 * (px * dx + py * dy);
  const double cc = px * px + py * py - c.radius_m * c.radius_m;
  const double disc = b * b - 4.0 * a * cc;
  if (disc < 0) return kInf;
  const double sq = std::sqrt(disc);
  for (double t : {(-b - sq) / (2 * a), (-b + sq) / (2 * a)}) {
    if (t <= 1e-6) continue;
    const double z = oz + t * dz;
    if (z >= c.z_min_m && z <= c.z_max_m) return t;
  }
  return kInf;
}

}  // namespace

Cylinder SimpleScene::person(double x_m, double y_m, double ground_z_m, std::uint32_t label) {
  return Cylinder{x_m, y_m, 0.25, ground_z_m, ground_z_m + 1.75, label};
}

SimpleScene SimpleScene::demo() {
  SimpleScene s;
  s.ground_z_m = -1.5;
  s.wall_radius_m = 12.0;
  s.range_noise_m = 0.02;
  s.cylinders = {
      person(4.0, 1.0, -1.5, 1),
      person(-3.0, 5.0, -1.5, 2),
      person(6.0, -6.0, -1.5, 3),
      person(-8.0, -2.0, -1.5, 4),
      person(5.0, 1.8, -1.5, 5),
      Cylinder{2.0, -3.0, 0.03, -1.5, 2.0, 0}};  // a 6 cm pole: narrower than min_width_m
  return s;
}

SimpleScene SimpleScene::hard_wall() {
  SimpleScene s;
  s.wall_radius_m = 1.0;
  s.range_noise_m = 0.03;
  // Close to the wall and the sensor, as in the paper's indoor hall.
  s.cylinders = {person(0.55, 0.1, -1.5, 1), person(-0.3, 0.5, -1.5, 2),
                 person(0.1, -0.6, -1.5, 3)};
  for (auto& c : s.cylinders) c.radius_m = 0.15;
  return s;
}

SimpleScene SimpleScene::open_field(int people) {
  SimpleScene s;
  s.ground_z_m = -2.5;
  s.range_noise_m = 0.03;
  for (int i = 0; i < people; ++i) {
    const double a = 2.0 * std::numbers::pi * i / std::max(people, 1) + 0.3;
    const double r = 5.0 + 35.0 * i / std::max(people - 1, 1);
    s.cylinders.push_back(
        person(r * std::cos(a), r * std::sin(a), -2.5, static_cast<std::uint32_t>(i + 1)));
  }
  return s;
}

RenderedScan render(const core::SensorModel& model, const SimpleScene& scene) {
  const int rings = model.rings();
  const int columns = model.columns();
  RenderedScan out{core::OrganizedScan(rings, columns), {}};
  out.labels.assign(out.scan.size(), 0);
  out.scan.set_uniform_columns(model, 0);
  std::mt19937_64 rng(scene.seed);
  std::normal_distribution<double> noise(0.0, scene.range_noise_m);
  for (int ring = 0; ring < rings; ++ring) {
    const double el = model.elevation_rad[ring];
    const double oz = model.vertical_offset_m[ring];
    for (int col = 0; col < columns; ++col) {
      const double az = out.scan.column_azimuth_rad[col] + model.azimuth_offset_rad[ring];
      const double dx = std::cos(el) * std::cos(az), dy = std::cos(el) * std::sin(az),
                   dz = std::sin(el);
      double best = kInf;
      std::uint32_t label = 0;
      if (scene.ground_z_m && dz < -1e-9) best = (*scene.ground_z_m - oz) / dz;
      if (scene.wall_radius_m) {
        // From inside a circle of radius R centred on the origin: t = R / |horizontal|.
        const double t = *scene.wall_radius_m / std::cos(el);
        if (t < best) best = t;
      }
      for (const auto& c : scene.cylinders) {
        const double t = hit_cylinder(c, 0.0, 0.0, oz, dx, dy, dz);
        if (t < best) {
          best = t;
          label = c.label;
        }
      }
      if (!std::isfinite(best)) continue;  // stays kNoReturn
      const double range = best + (scene.range_noise_m > 0 ? noise(rng) : 0.0);
      out.scan.set_range(model, ring, col, static_cast<float>(range), 50.0f);
      if (out.scan.valid(out.scan.index(ring, col))) out.labels[out.scan.index(ring, col)] = label;
    }
  }
  return out;
}

}  // namespace ringtrack::sim
