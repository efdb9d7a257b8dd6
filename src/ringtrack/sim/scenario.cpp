#include "ringtrack/sim/scenario.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <functional>
#include <numbers>
#include <set>
#include <sstream>

#include "ringtrack/core/error.hpp"
#include "ringtrack/core/sensor_model.hpp"
#include "ringtrack/sim/random.hpp"

namespace ringtrack::sim {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;
constexpr double kGravity = 9.81;

std::string fmt_xy(const Eigen::Vector2d& p) {
  std::ostringstream s;
  s.precision(3);
  s << "(" << p.x() << ", " << p.y() << ")";
  return s.str();
}

[[noreturn]] void fail(const std::string& source, const std::string& entry,
                       const std::string& what) {
  throw core::ConfigError(source + ": " + entry + ": " + what);
}

void require_positive(const std::string& src, const std::string& entry, const char* key, double v) {
  if (!(v > 0.0) || !std::isfinite(v)) {
    fail(src, entry, std::string(key) + " must be > 0 (got " + std::to_string(v) + ")");
  }
}
// Positive and at most `max`: the upper bound keeps a typo from becoming an endless run.
void require_bounded(const std::string& src, const std::string& entry, const char* key, double v,
                     double max) {
  require_positive(src, entry, key, v);
  if (v > max) {
    std::ostringstream text;
    text << key << " must be at most " << max << " (got " << v << ")";
    fail(src, entry, text.str());
  }
}

void require_unit(const std::string& src, const std::string& entry, const char* key, double v) {
  if (!(v >= 0.0 && v <= 1.0)) {
    fail(src, entry, std::string(key) + " must be in [0, 1] (got " + std::to_string(v) + ")");
  }
}

std::string fmt_xyz(const Eigen::Vector3d& p) {
  std::ostringstream s;
  s.precision(3);
  s << "(" << p.x() << ", " << p.y() << ", " << p.z() << ")";
  return s.str();
}

std::string fmt_t(double t_s) {
  std::ostringstream s;
  s.precision(6);
  s << t_s;
  return s.str();
}

Eigen::Quaterniond rpy(const Eigen::Vector3d& rpy_rad) {
  return Eigen::AngleAxisd(rpy_rad.z(), Eigen::Vector3d::UnitZ()) *
         Eigen::AngleAxisd(rpy_rad.y(), Eigen::Vector3d::UnitY()) *
         Eigen::AngleAxisd(rpy_rad.x(), Eigen::Vector3d::UnitX());
}

// Entry ("boxes[2]", ...) of the first static solid within margin of the world point p, or "".
std::string solid_containing(const Scenario& s, const Eigen::Vector3d& p, double margin) {
  const Ground& g = s.ground;
  const auto ground_at = [&](const Eigen::Vector2d& c) {
    return g.enabled ? g.height_at(c.x(), c.y()) : 0.0;
  };
  // Upright yawed box: centre, half sizes, yaw, bottom z.
  const auto in_box = [&](const Eigen::Vector2d& c, const Eigen::Vector3d& half, double yaw,
                          double z0) {
    const Eigen::Vector2d r = p.head<2>() - c;
    const double cs = std::cos(yaw), sn = std::sin(yaw);
    return std::abs(cs * r.x() + sn * r.y()) <= half.x() + margin &&
           std::abs(-sn * r.x() + cs * r.y()) <= half.y() + margin && p.z() >= z0 - margin &&
           p.z() <= z0 + 2.0 * half.z() + margin;
  };
  for (std::size_t i = 0; i < s.boxes.size(); ++i) {
    const auto& b = s.boxes[i];
    if (in_box(b.center_m, 0.5 * b.size_m, b.yaw_deg * kDeg, ground_at(b.center_m) + b.base_z_m))
      return "boxes[" + std::to_string(i) + "]";
  }
  for (std::size_t i = 0; i < s.walls.size(); ++i) {
    const auto& w = s.walls[i];
    const Eigen::Vector2d d = w.to_m - w.from_m;
    const Eigen::Vector2d c = 0.5 * (w.from_m + w.to_m);
    if (in_box(c, {0.5 * d.norm(), 0.5 * w.thickness_m, 0.5 * w.height_m}, std::atan2(d.y(), d.x()),
               ground_at(c) + w.base_z_m))
      return "walls[" + std::to_string(i) + "]";
  }
  for (std::size_t i = 0; i < s.cylinders.size(); ++i) {
    const auto& c = s.cylinders[i];
    const double z0 = ground_at(c.center_m) + c.base_z_m;
    if ((p.head<2>() - c.center_m).norm() <= c.radius_m + margin && p.z() >= z0 - margin &&
        p.z() <= z0 + c.height_m + margin)
      return "cylinders[" + std::to_string(i) + "]";
  }
  for (std::size_t i = 0; i < s.ellipsoids.size(); ++i) {
    const auto& e = s.ellipsoids[i];
    Eigen::Vector3d c = e.center_m;
    c.z() += ground_at(e.center_m.head<2>());
    const Eigen::Vector3d local =
        Eigen::AngleAxisd(-e.yaw_deg * kDeg, Eigen::Vector3d::UnitZ()) * (p - c);
    const Eigen::Vector3d grown = e.radii_m + Eigen::Vector3d::Constant(margin);
    if (local.cwiseQuotient(grown).norm() <= 1.0) return "ellipsoids[" + std::to_string(i) + "]";
  }
  return {};
}

// A moving sensor must not fly through solids: its path is sampled every <= 5 cm.
void validate_sensor_path(const Scenario& s, const std::string& src) {
  const SensorSpec& z = s.sensor;
  if (z.motion == SensorMotion::kStatic) return;
  constexpr double kSensorRadiusM = 0.1;  // a VLP-16 is 10 cm wide; keep a little air around it
  const double speed = z.motion == SensorMotion::kFigure8 ? z.max_speed_mps * 1.1 : [&] {
    double v = 0.1;
    for (std::size_t i = 1; i < z.keyframes.size(); ++i) {
      v = std::max(v, (z.keyframes[i].xyz_m - z.keyframes[i - 1].xyz_m).norm() /
                          (z.keyframes[i].t_s - z.keyframes[i - 1].t_s));
    }
    return v;
  }();
  const double step_s = std::clamp(0.05 / speed, 1e-3, 0.05);
  const auto n = static_cast<std::int64_t>(std::ceil(s.duration_s / step_s));
  for (std::int64_t k = 0; k <= n; ++k) {
    const double t = std::min(static_cast<double>(k) * step_s, s.duration_s);
    const Eigen::Vector3d p =
        sensor_pose(z, static_cast<std::int64_t>(std::llround(t * 1e9))).translation;
    const std::string hit = solid_containing(s, p, kSensorRadiusM);
    if (!hit.empty()) {
      fail(src, "sensor",
           (z.motion == SensorMotion::kFigure8 ? std::string("figure8") : std::string("scripted")) +
               " path at t=" + fmt_t(t) + " s " + fmt_xyz(p) + " passes through " + hit);
    }
  }
}

// ---- built-in layouts -----------------------------------------------------------------------

// Places things by rejection sampling so that their bounding circles keep a gap, and keeps the
// sensor's surroundings (figure-8 flight) clear.
class Placer {
 public:
  Placer(std::uint64_t seed, Eigen::Vector2d half_extent, double keep_out_m)
      : rng_(seed), half_(std::move(half_extent)), keep_out_m_(keep_out_m) {}
  bool place(double radius_m, Eigen::Vector2d& out, double min_dist_m = 0.0) {
    for (int attempt = 0; attempt < 400; ++attempt) {
      const Eigen::Vector2d p{rng_.uniform(-half_.x(), half_.x()),
                              rng_.uniform(-half_.y(), half_.y())};
      if (p.norm() < keep_out_m_ + radius_m || p.norm() < min_dist_m) continue;
      bool free = true;
      for (const auto& [c, r] : taken_) {
        if ((c - p).norm() < r + radius_m + 1.0) {
          free = false;
          break;
        }
      }
      if (!free) continue;
      taken_.emplace_back(p, radius_m);
      out = p;
      return true;
    }
    return false;
  }
  void reserve(const Eigen::Vector2d& c, double r) { taken_.emplace_back(c, r); }
  Rng& rng() { return rng_; }

 private:
  Rng rng_;
  Eigen::Vector2d half_;
  double keep_out_m_;
  std::vector<std::pair<Eigen::Vector2d, double>> taken_;
};

void add_tree(Scenario& s, Placer& pl, double min_dist_m = 0.0) {
  Rng& r = pl.rng();
  const double crown = r.uniform(1.2, 3.2);
  Eigen::Vector2d c;
  if (!pl.place(0.3 * crown, c, min_dist_m)) return;
  const double trunk_h = r.uniform(1.9, 3.5);
  s.cylinders.push_back({c, r.uniform(0.1, 0.3), trunk_h + 0.5, 0.0, 0.35});
  const double rz = r.uniform(1.2, 2.8);
  s.ellipsoids.push_back({{c.x(), c.y(), trunk_h + 0.8 * rz},
                          {crown, crown * r.uniform(0.8, 1.0), rz},
                          r.uniform(0, 180),
                          0.3});
}

void add_box(Scenario& s, Placer& pl, Eigen::Vector3d size, double yaw_deg, double refl,
             double min_dist_m = 0.0, double base_z = 0.0) {
  Eigen::Vector2d c;
  if (pl.place(0.5 * size.head<2>().norm(), c, min_dist_m))
    s.boxes.push_back({c, size, base_z, yaw_deg, refl});
}

void add_distractors(Scenario& s, Placer& pl, int n, double min_m, double max_m) {
  for (int i = 0; i < n; ++i) {
    Eigen::Vector2d c;
    for (int k = 0; k < 50; ++k) {
      if (pl.place(0.4, c, min_m) && c.norm() <= max_m) {
        s.distractors.push_back(c);
        break;
      }
    }
  }
}

Scenario field(int number, std::string name, std::string description, double size_m, int people,
               double duration_s) {
  Scenario s;
  s.number = number;
  s.name = std::move(name);
  s.description = std::move(description);
  s.area_m = {size_m, size_m};
  s.people = people;
  s.duration_s = duration_s;
  return s;
}

Scenario industrial() {
  Scenario s = field(4, "industrial",
                     "industrial site, 100 x 100 m, 6 people, 9 static distractors", 100, 6, 54);
  Placer pl(4004, {48, 48}, 7.0);
  const std::vector<std::pair<Eigen::Vector2d, Eigen::Vector3d>> halls{{{-32, 30}, {24, 14, 9}},
                                                                       {{30, -32}, {30, 16, 10}},
                                                                       {{34, 30}, {18, 12, 7}},
                                                                       {{-30, -32}, {20, 20, 8}}};
  for (const auto& [c, size] : halls) {
    s.boxes.push_back({c, size, 0.0, 0.0, 0.5});
    pl.reserve(c, 0.5 * size.head<2>().norm());
  }
  for (int i = 0; i < 14; ++i) {
    const double yaw = pl.rng().chance(0.5) ? 0.0 : 90.0;
    add_box(s, pl, {12.2, 2.44, 2.6}, yaw, 0.45, 10.0);
    if (i % 4 == 0 && !s.boxes.empty()) {  // stacked container
      auto top = s.boxes.back();
      top.base_z_m = 2.6;
      s.boxes.push_back(top);
    }
  }
  for (int i = 0; i < 3; ++i) {
    Eigen::Vector2d c;
    if (pl.place(3.5, c, 15.0)) s.cylinders.push_back({c, 3.0, 8.0, 0.0, 0.5});  // tanks
  }
  for (int i = 0; i < 12; ++i) {
    Eigen::Vector2d c;
    if (pl.place(0.2, c, 8.0)) s.cylinders.push_back({c, 0.12, 6.0, 0.0, 0.6});  // lamp posts
  }
  s.walls.push_back({{-50, 50}, {50, 50}, 2.2, 0.1, 0.0, 0.3});  // fence on the north side
  s.walls.push_back({{50, -50}, {50, 50}, 2.2, 0.1, 0.0, 0.3});  // and on the east side
  add_distractors(s, pl, 9, 5.0, 40.0);
  return s;
}

Scenario town() {
  Scenario s = field(5, "town", "industry, shops and houses, 200 x 200 m, 6 people", 200, 6, 92);
  Placer pl(5005, {98, 98}, 8.0);
  Rng& r = pl.rng();
  for (int i = 0; i < 4; ++i)
    add_box(s, pl, {40, 25, 10}, r.uniform(0, 90), 0.5, 60.0);  // industry
  for (int i = 0; i < 8; ++i) add_box(s, pl, {20, 12, 4.5}, r.uniform(0, 90), 0.45, 20.0);  // shops
  for (int i = 0; i < 30; ++i) {
    add_box(s, pl, {r.uniform(8, 12), r.uniform(7, 10), r.uniform(5.5, 9)}, r.uniform(0, 90), 0.4,
            15.0);
  }
  for (int i = 0; i < 15; ++i)
    add_box(s, pl, {4.5, 1.8, 1.5}, r.uniform(0, 180), 0.6, 8.0);  // cars
  for (int i = 0; i < 25; ++i) add_tree(s, pl, 10.0);
  for (int i = 0; i < 20; ++i) {
    Eigen::Vector2d c;
    if (pl.place(0.2, c, 8.0)) s.cylinders.push_back({c, 0.1, 5.0, 0.0, 0.6});
  }
  return s;
}

Scenario park() {
  Scenario s =
      field(6, "park", "park with buildings, fountains and many trees, 100 x 150 m, 6 people", 100,
            6, 97);
  s.area_m = {100, 150};
  s.ground.amplitude_m = 0.3;
  s.ground.wavelength_m = 60.0;
  s.ground.phase_rad = 0.7;
  Placer pl(6006, {49, 74}, 6.0);
  Rng& r = pl.rng();
  // Buildings along the edges.
  const std::vector<std::pair<Eigen::Vector2d, Eigen::Vector3d>> buildings{
      {{-40, 65}, {16, 10, 12}}, {{-10, 68}, {22, 9, 15}},  {{25, 66}, {18, 12, 10}},
      {{-42, -64}, {14, 14, 9}}, {{38, -66}, {20, 10, 11}}, {{44, 10}, {10, 24, 8}}};
  for (const auto& [c, size] : buildings) {
    s.boxes.push_back({c, size, 0.0, 0.0, 0.45});
    pl.reserve(c, 0.5 * size.head<2>().norm());
  }
  // Fountains: a low basin and a central column.
  const std::vector<std::pair<Eigen::Vector2d, double>> fountains{
      {{14, 18}, 4.0}, {{-20, -25}, 3.0}, {{-18, 35}, 2.5}};
  for (const auto& [c, radius] : fountains) {
    s.cylinders.push_back({c, radius, 0.6, 0.0, 0.5});
    s.cylinders.push_back({c, 0.4, 2.5, 0.0, 0.5});
    pl.reserve(c, radius);
  }
  for (int i = 0; i < 150; ++i) add_tree(s, pl, 8.0);
  for (int i = 0; i < 40; ++i) {
    Eigen::Vector2d c;
    const double rad = r.uniform(0.6, 1.5);
    if (pl.place(rad, c, 7.0)) {
      s.ellipsoids.push_back({{c.x(), c.y(), 0.6 * rad},
                              {rad, rad * r.uniform(0.7, 1.0), 0.8 * rad},
                              r.uniform(0, 180),
                              0.3});
    }
  }
  for (int i = 0; i < 20; ++i)
    add_box(s, pl, {2.0, 0.6, 0.8}, r.uniform(0, 180), 0.4, 7.0);  // benches
  for (int i = 0; i < 15; ++i) {
    Eigen::Vector2d c;
    if (pl.place(0.2, c, 7.0)) s.cylinders.push_back({c, 0.08, 4.0, 0.0, 0.6});
  }
  return s;
}

Scenario hall() {
  Scenario s;
  s.number = 7;
  s.name = "hall";
  s.description = "indoor hall, walls 1-10 m from the sensor, 8 people and a small robot";
  s.duration_s = 60.0;
  s.area_center_m = {4.5, 1.0};
  s.area_m = {10.0, 9.0};
  s.people = 8;
  s.robots = 1;
  s.sensor.position_m = {0.0, 0.0, 1.2};
  s.sensor.figure8_radius_m = 0.5;
  s.sensor.max_speed_mps = 1.0;
  const double x0 = -1.0, x1 = 10.0, y0 = -4.0, y1 = 6.0, h = 4.0;
  s.walls = {{{x0, y0}, {x1, y0}, h, 0.3, 0.0, 0.5},
             {{x1, y0}, {x1, y1}, h, 0.3, 0.0, 0.5},
             {{x1, y1}, {x0, y1}, h, 0.3, 0.0, 0.5},
             {{x0, y1}, {x0, y0}, h, 0.3, 0.0, 0.5}};
  s.boxes.push_back({{4.5, 1.0}, {11.6, 10.6, 0.3}, h, 0.0, 0.4});  // ceiling
  s.boxes.push_back({{3.0, 3.5}, {0.5, 0.5, h}, 0.0, 0.0, 0.5});    // pillars
  s.boxes.push_back({{7.0, -1.5}, {0.5, 0.5, h}, 0.0, 0.0, 0.5});
  s.boxes.push_back({{8.8, 4.6}, {1.6, 0.8, 0.9}, 0.0, 0.0, 0.45});  // a table near a wall
  return s;
}

// Built-in layouts are rounded to centimetres (degrees for yaw) so that their YAML files in
// config/scenarios read back to exactly the same numbers.
double cm(double v) {
  return std::round(v * 100.0) / 100.0;
}
void tidy(Scenario& s) {
  for (auto& b : s.boxes) {
    b.center_m = b.center_m.unaryExpr(&cm);
    b.size_m = b.size_m.unaryExpr(&cm);
    b.base_z_m = cm(b.base_z_m);
    b.yaw_deg = std::round(b.yaw_deg);
  }
  for (auto& c : s.cylinders) {
    c.center_m = c.center_m.unaryExpr(&cm);
    c.radius_m = cm(c.radius_m);
    c.height_m = cm(c.height_m);
  }
  for (auto& e : s.ellipsoids) {
    e.center_m = e.center_m.unaryExpr(&cm);
    e.radii_m = e.radii_m.unaryExpr(&cm);
    e.yaw_deg = std::round(e.yaw_deg);
  }
  for (auto& d : s.distractors) d = d.unaryExpr(&cm);
}

}  // namespace

std::string_view class_name(ObjectClass c) {
  switch (c) {
    case ObjectClass::kPerson:
      return "person";
    case ObjectClass::kRobot:
      return "robot";
    case ObjectClass::kDrone:
      return "drone";
    case ObjectClass::kDistractor:
      return "distractor";
  }
  return "unknown";
}

ObjectClass class_from_name(std::string_view name) {
  for (const auto c :
       {ObjectClass::kPerson, ObjectClass::kRobot, ObjectClass::kDrone, ObjectClass::kDistractor}) {
    if (name == class_name(c)) return c;
  }
  throw core::InputError("unknown object class '" + std::string(name) +
                         "' (expected person, robot, drone or distractor)");
}

bool Footprint::contains(const Eigen::Vector2d& p, double margin) const {
  const Eigen::Vector2d r = p - center;
  if (circle) return r.norm() <= half.x() + margin;
  const double c = std::cos(yaw_rad), s = std::sin(yaw_rad);
  const Eigen::Vector2d l{c * r.x() + s * r.y(), -s * r.x() + c * r.y()};
  return std::abs(l.x()) <= half.x() + margin && std::abs(l.y()) <= half.y() + margin;
}

bool Footprint::crosses(const Eigen::Vector2d& a, const Eigen::Vector2d& b, double margin) const {
  const Eigen::Vector2d ab = b - a;
  if (circle) {
    const double len2 = ab.squaredNorm();
    const double t = len2 > 0 ? std::clamp((center - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
    return (a + t * ab - center).norm() <= half.x() + margin;
  }
  // Liang-Barsky clipping against the rectangle grown by margin, in its own frame.
  const double c = std::cos(yaw_rad), s = std::sin(yaw_rad);
  const Eigen::Vector2d ra = a - center;
  const double o[2] = {c * ra.x() + s * ra.y(), -s * ra.x() + c * ra.y()};
  const double d[2] = {c * ab.x() + s * ab.y(), -s * ab.x() + c * ab.y()};
  double t0 = 0.0, t1 = 1.0;
  for (int k = 0; k < 2; ++k) {
    const double h = half[k] + margin;
    if (std::abs(d[k]) < 1e-12) {
      if (std::abs(o[k]) > h) return false;
      continue;
    }
    double ta = (-h - o[k]) / d[k], tb = (h - o[k]) / d[k];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
    if (t0 > t1) return false;
  }
  return true;
}

std::vector<Footprint> ground_footprints(const Scenario& s) {
  std::vector<Footprint> out;
  for (std::size_t i = 0; i < s.boxes.size(); ++i) {
    const auto& b = s.boxes[i];
    if (b.base_z_m > 1.9) continue;  // ceilings, overhangs
    out.push_back({b.center_m, 0.5 * b.size_m.head<2>(), b.yaw_deg * kDeg, false,
                   "boxes[" + std::to_string(i) + "]"});
  }
  for (std::size_t i = 0; i < s.walls.size(); ++i) {
    const auto& w = s.walls[i];
    const Eigen::Vector2d d = w.to_m - w.from_m;
    out.push_back({0.5 * (w.from_m + w.to_m),
                   {0.5 * d.norm(), 0.5 * w.thickness_m},
                   std::atan2(d.y(), d.x()),
                   false,
                   "walls[" + std::to_string(i) + "]"});
  }
  for (std::size_t i = 0; i < s.cylinders.size(); ++i) {
    const auto& c = s.cylinders[i];
    if (c.base_z_m > 1.9) continue;
    out.push_back(
        {c.center_m, {c.radius_m, 0.0}, 0.0, true, "cylinders[" + std::to_string(i) + "]"});
  }
  for (std::size_t i = 0; i < s.ellipsoids.size(); ++i) {
    const auto& e = s.ellipsoids[i];
    if (e.center_m.z() - e.radii_m.z() > 1.9) continue;  // crowns high above
    out.push_back({e.center_m.head<2>(),
                   {std::max(e.radii_m.x(), e.radii_m.y()), 0.0},
                   0.0,
                   true,
                   "ellipsoids[" + std::to_string(i) + "]"});
  }
  for (std::size_t i = 0; i < s.distractors.size(); ++i) {
    out.push_back(
        {s.distractors[i], {0.3, 0.0}, 0.0, true, "distractors[" + std::to_string(i) + "]"});
  }
  return out;
}

namespace {

// The checks of validate, one function per part of the scenario in the file's own order, so that
// a reader sees every bound a scenario file must keep here, and the first broken one is reported.

void validate_world(const Scenario& s, const std::string& src) {
  require_bounded(src, "scenario", "duration_s", s.duration_s, kMaxDurationS);
  require_bounded(src, "scenario", "area_m[0]", s.area_m.x(), kMaxWorldExtentM);
  require_bounded(src, "scenario", "area_m[1]", s.area_m.y(), kMaxWorldExtentM);
  require_bounded(src, "scenario", "world_radius_m", s.world_radius_m, kMaxWorldExtentM);
  if (s.ground.amplitude_m < 0) fail(src, "ground", "amplitude_m must be >= 0");
  if (s.ground.amplitude_m > 0)
    require_positive(src, "ground", "wavelength_m", s.ground.wavelength_m);
  require_unit(src, "ground", "reflectivity", s.ground.reflectivity);
}

void validate_sensor(const SensorSpec& sensor, const std::string& src) {
  try {
    (void)core::SensorModel::by_name(sensor.model);
  } catch (const core::Error& e) {
    fail(src, "sensor", std::string("model: ") + e.what());
  }
  if (!(sensor.range_noise_m >= 0)) fail(src, "sensor", "range_noise_m must be >= 0");
  require_unit(src, "sensor", "dropout_probability", sensor.dropout_probability);
  require_unit(src, "sensor", "far_dropout_probability", sensor.far_dropout_probability);
  require_bounded(src, "sensor", "figure8_radius_m", sensor.figure8_radius_m, kMaxWorldExtentM);
  require_bounded(src, "sensor", "max_speed_mps", sensor.max_speed_mps, kMaxSensorSpeedMps);
  if (sensor.tilt_gain < 0) fail(src, "sensor", "tilt_gain must be >= 0");
  if (sensor.motion != SensorMotion::kScripted) return;
  if (sensor.keyframes.empty()) fail(src, "sensor", "motion scripted needs keyframes");
  for (std::size_t i = 1; i < sensor.keyframes.size(); ++i) {
    if (!(sensor.keyframes[i].t_s > sensor.keyframes[i - 1].t_s)) {
      fail(src, "sensor.keyframes[" + std::to_string(i) + "]", "times must increase");
    }
  }
}

void validate_actor_counts(const Scenario& s, const std::string& src) {
  for (const auto& [key, count] : {std::pair{"people", s.people}, std::pair{"robots", s.robots},
                                   std::pair{"drones", s.drones}}) {
    if (count < 0 || count > kMaxActorsPerKind) {
      fail(src, "actors",
           std::string(key) + " must be in [0, " + std::to_string(kMaxActorsPerKind) + "] (got " +
               std::to_string(count) + ")");
    }
  }
}

void validate_solids(const Scenario& s, const std::string& src) {
  for (std::size_t i = 0; i < s.boxes.size(); ++i) {
    const std::string e = "boxes[" + std::to_string(i) + "]";
    for (int a = 0; a < 3; ++a) require_positive(src, e, "size_m", s.boxes[i].size_m[a]);
    require_unit(src, e, "reflectivity", s.boxes[i].reflectivity);
  }
  for (std::size_t i = 0; i < s.cylinders.size(); ++i) {
    const std::string e = "cylinders[" + std::to_string(i) + "]";
    require_positive(src, e, "radius_m", s.cylinders[i].radius_m);
    require_positive(src, e, "height_m", s.cylinders[i].height_m);
    require_unit(src, e, "reflectivity", s.cylinders[i].reflectivity);
  }
  for (std::size_t i = 0; i < s.ellipsoids.size(); ++i) {
    const std::string e = "ellipsoids[" + std::to_string(i) + "]";
    for (int a = 0; a < 3; ++a) require_positive(src, e, "radii_m", s.ellipsoids[i].radii_m[a]);
    require_unit(src, e, "reflectivity", s.ellipsoids[i].reflectivity);
  }
  for (std::size_t i = 0; i < s.walls.size(); ++i) {
    const std::string e = "walls[" + std::to_string(i) + "]";
    require_positive(src, e, "height_m", s.walls[i].height_m);
    require_positive(src, e, "thickness_m", s.walls[i].thickness_m);
    require_positive(src, e, "length (from -> to)", (s.walls[i].to_m - s.walls[i].from_m).norm());
    require_unit(src, e, "reflectivity", s.walls[i].reflectivity);
  }
}

void validate_distractors(const Scenario& s, const std::vector<Footprint>& footprints,
                          const std::string& src) {
  for (std::size_t i = 0; i < s.distractors.size(); ++i) {
    for (const auto& f : footprints) {
      if (f.entry == "distractors[" + std::to_string(i) + "]") continue;
      if (f.entry.rfind("distractors", 0) == 0) continue;
      if (f.contains(s.distractors[i], 0.3)) {
        fail(src, "distractors[" + std::to_string(i) + "] at " + fmt_xy(s.distractors[i]),
             "inside " + f.entry);
      }
    }
  }
}

// What a scripted actor's path must stay clear of: the obstacles and the sensor's mast.
std::vector<Footprint> path_obstacles(const Scenario& s, std::vector<Footprint> footprints) {
  if (s.sensor.motion != SensorMotion::kScripted) {
    // The mast stands at position_m (the figure 8 flies about it); a scripted sensor has none.
    footprints.push_back({s.sensor.position_m.head<2>(),
                          {kSensorKeepOutM, 0.0},
                          0.0,
                          true,
                          "the sensor's keep-out zone (" + fmt_t(kSensorKeepOutM) + " m around " +
                              fmt_xy(s.sensor.position_m.head<2>()) + ")"});
  }
  return footprints;
}

void validate_actor_waypoints(const ScriptedActor& a, const std::string& e,
                              const std::string& src) {
  if (a.waypoints.empty()) fail(src, e, "no waypoints");
  if (a.waypoints.size() < 2) {
    fail(src, e,
         "a single waypoint (t=" + fmt_t(a.waypoints[0].t_s) +
             " s): an actor exists from its first to its last waypoint, give at least two "
             "(e.g. the same place at t=0 and at the end to stand all the time)");
  }
  for (std::size_t i = 1; i < a.waypoints.size(); ++i) {
    if (!(a.waypoints[i].t_s > a.waypoints[i - 1].t_s)) fail(src, e, "times must increase");
  }
}

void validate_actor_body(const ScriptedActor& a, const std::string& e, const std::string& src) {
  const bool has_body =
      a.object_class == ObjectClass::kPerson || a.object_class == ObjectClass::kDistractor;
  if ((a.height_m || a.width_m) && !has_body) {
    fail(src, e,
         "height_m/width_m apply to people and distractors only, not to a " +
             std::string(class_name(a.object_class)));
  }
  if (a.height_m && !(*a.height_m >= kMinBodyHeightM && *a.height_m <= kMaxBodyHeightM)) {
    fail(src, e,
         "height_m must be in [" + fmt_t(kMinBodyHeightM) + ", " + fmt_t(kMaxBodyHeightM) +
             "] (got " + fmt_t(*a.height_m) + ")");
  }
  if (a.width_m && !(*a.width_m >= kMinBodyWidthM && *a.width_m <= kMaxBodyWidthM)) {
    fail(src, e,
         "width_m must be in [" + fmt_t(kMinBodyWidthM) + ", " + fmt_t(kMaxBodyWidthM) + "] (got " +
             fmt_t(*a.width_m) + ")");
  }
  if (a.reflectivity) require_unit(src, e, "reflectivity", *a.reflectivity);
}

// Waypoints and the segments between them clear of the obstacles by half a body.
void validate_actor_path(const ScriptedActor& a, const std::vector<Footprint>& obstacles,
                         const std::string& e, const std::string& src) {
  constexpr double kPathMarginM = 0.2;
  for (const auto& w : a.waypoints) {
    for (const auto& f : obstacles) {
      if (f.contains(w.xyz_m.head<2>(), kPathMarginM)) {
        std::ostringstream t;
        t << "waypoint at t=" << w.t_s << " s " << fmt_xy(w.xyz_m.head<2>()) << " is inside "
          << f.entry;
        fail(src, e, t.str());
      }
    }
  }
  for (std::size_t i = 1; i < a.waypoints.size(); ++i) {
    const Waypoint& p = a.waypoints[i - 1];
    const Waypoint& q = a.waypoints[i];
    for (const auto& f : obstacles) {
      if (f.crosses(p.xyz_m.head<2>(), q.xyz_m.head<2>(), kPathMarginM)) {
        fail(src, e,
             "segment t=" + fmt_t(p.t_s) + "-" + fmt_t(q.t_s) + " s from " +
                 fmt_xy(p.xyz_m.head<2>()) + " to " + fmt_xy(q.xyz_m.head<2>()) + " crosses " +
                 f.entry);
      }
    }
  }
}

// Scripted actors: ids, times, bodies, and paths clear of obstacles and of the sensor's mast
// (drones fly over them).
void validate_scripted(const Scenario& s, const std::vector<Footprint>& obstacles,
                       const std::string& src) {
  std::set<std::uint32_t> ids;
  for (const auto& a : s.scripted) {
    const std::string e = "trajectory of id " + std::to_string(a.id);
    if (a.id == 0) fail(src, e, "ids must be >= 1 (0 is the background label)");
    if (!ids.insert(a.id).second) fail(src, e, "duplicate id");
    validate_actor_waypoints(a, e, src);
    validate_actor_body(a, e, src);
    if (a.object_class != ObjectClass::kDrone) validate_actor_path(a, obstacles, e, src);
  }
}

}  // namespace

void validate(const Scenario& s, const std::string& src) {
  validate_world(s, src);
  validate_sensor(s.sensor, src);
  validate_actor_counts(s, src);
  validate_solids(s, src);
  const std::vector<Footprint> footprints = ground_footprints(s);
  validate_distractors(s, footprints, src);
  validate_scripted(s, path_obstacles(s, footprints), src);
  validate_sensor_path(s, src);
}

double figure8_rate(const SensorSpec& s) {
  // Lemniscate of Gerono: peak speed R w sqrt(2).
  return s.max_speed_mps / (s.figure8_radius_m * std::sqrt(2.0));
}

core::Pose sensor_pose(const SensorSpec& s, std::int64_t t_ns) {
  core::Pose p;
  p.stamp_ns = t_ns;
  const double t = static_cast<double>(t_ns) * 1e-9;
  switch (s.motion) {
    case SensorMotion::kStatic:
      p.translation = s.position_m;
      break;
    case SensorMotion::kFigure8: {
      // Lemniscate of Gerono: x = R sin(wt), y = R sin(wt) cos(wt); peak speed R w sqrt(2).
      const double r = s.figure8_radius_m;
      const double w = figure8_rate(s);
      const double sw = std::sin(w * t);
      const double s2 = std::sin(2 * w * t);
      p.translation =
          s.position_m + Eigen::Vector3d(r * sw, 0.5 * r * s2, 0.15 * r * std::sin(0.5 * w * t));
      // A multirotor tilts its thrust towards its acceleration; tilt_gain scales that tilt.
      const Eigen::Vector3d acc{-r * w * w * sw, -2.0 * r * w * w * s2, 0.0};
      const Eigen::Vector3d up = (s.tilt_gain * acc + Eigen::Vector3d(0, 0, kGravity)).normalized();
      const double yaw = 0.35 * std::sin(0.5 * w * t);
      p.rotation = Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), up) *
                   Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ());
      break;
    }
    case SensorMotion::kScripted: {
      const auto& k = s.keyframes;
      const auto pose_of = [&](const SensorKeyframe& f) {
        core::Pose q;
        q.translation = f.xyz_m;
        q.rotation = rpy(f.rpy_deg * kDeg);
        return q;
      };
      if (t <= k.front().t_s) {
        p = pose_of(k.front());
      } else if (t >= k.back().t_s) {
        p = pose_of(k.back());
      } else {
        std::size_t i = 0;
        while (k[i + 1].t_s < t) ++i;
        const double u = (t - k[i].t_s) / (k[i + 1].t_s - k[i].t_s);
        p = core::Pose::interpolate(pose_of(k[i]), pose_of(k[i + 1]), u);
      }
      p.stamp_ns = t_ns;
      break;
    }
  }
  return p;
}

std::vector<ScenarioInfo> builtin_scenarios() {
  std::vector<ScenarioInfo> out;
  for (int i = 1; i <= 7; ++i) {
    const auto s = builtin_scenario(std::to_string(i));
    out.push_back({s.number, s.name, s.description});
  }
  return out;
}

Scenario builtin_scenario(std::string_view number_or_name) {
  std::string key(number_or_name);
  bool moving = false;
  for (const std::string suffix : {"-moving", "m"}) {
    if (key.size() > suffix.size() && key.ends_with(suffix) &&
        (suffix != "m" || std::isdigit(static_cast<unsigned char>(key[0])))) {
      key.resize(key.size() - suffix.size());
      moving = true;
      break;
    }
  }
  Scenario s;
  if (key == "1" || key == "empty-field") {
    s = field(1, "empty-field", "empty field, 100 x 100 m, 6 people", 100, 6, 98);
  } else if (key == "2" || key == "crowd") {
    s = field(2, "crowd", "empty field, 100 x 100 m, 50 people", 100, 50, 99);
  } else if (key == "3" || key == "large-field") {
    s = field(3, "large-field", "empty field, 200 x 200 m, 6 people", 200, 6, 97);
  } else if (key == "4" || key == "industrial") {
    s = industrial();
  } else if (key == "5" || key == "town") {
    s = town();
  } else if (key == "6" || key == "park") {
    s = park();
  } else if (key == "7" || key == "hall") {
    s = hall();
  } else {
    throw core::ConfigError("unknown scenario '" + std::string(number_or_name) +
                            "' (expected 1-7 or empty-field, crowd, large-field, industrial, town, "
                            "park, hall, optionally with -moving, or a .yaml file)");
  }
  tidy(s);
  return moving ? with_moving_sensor(std::move(s)) : s;
}

Scenario with_moving_sensor(Scenario s) {
  s.sensor.motion = SensorMotion::kFigure8;
  return s;
}

std::vector<Primitive> static_primitives(const Scenario& s) {
  std::vector<Primitive> out;
  const Ground& g = s.ground;
  // Solids standing on the ground reach down by the undulation so none floats on a slope.
  const auto base_of = [&](const Eigen::Vector2d& c, double base_z, double& extra) {
    extra = (base_z == 0.0 && g.enabled) ? g.amplitude_m : 0.0;
    return (g.enabled ? g.height_at(c.x(), c.y()) : 0.0) + base_z - extra;
  };
  for (const auto& b : s.boxes) {
    double extra = 0.0;
    const double z = base_of(b.center_m, b.base_z_m, extra);
    auto p =
        Primitive::box(b.center_m, z, b.size_m + Eigen::Vector3d(0, 0, extra), b.yaw_deg * kDeg);
    p.reflectivity = static_cast<float>(b.reflectivity);
    out.push_back(p);
  }
  for (const auto& w : s.walls) {
    const Eigen::Vector2d d = w.to_m - w.from_m;
    const Eigen::Vector2d c = 0.5 * (w.from_m + w.to_m);
    double extra = 0.0;
    const double z = base_of(c, w.base_z_m, extra);
    auto p = Primitive::box(c, z, {d.norm(), w.thickness_m, w.height_m + extra},
                            std::atan2(d.y(), d.x()));
    p.reflectivity = static_cast<float>(w.reflectivity);
    out.push_back(p);
  }
  for (const auto& c : s.cylinders) {
    double extra = 0.0;
    const double z = base_of(c.center_m, c.base_z_m, extra);
    auto p = Primitive::cylinder(c.center_m, z, c.radius_m, c.height_m + extra);
    p.reflectivity = static_cast<float>(c.reflectivity);
    out.push_back(p);
  }
  for (const auto& e : s.ellipsoids) {
    Eigen::Vector3d c = e.center_m;
    if (g.enabled) c.z() += g.height_at(c.x(), c.y());
    auto p = Primitive::ellipsoid(
        c, e.radii_m,
        Eigen::AngleAxisd(e.yaw_deg * kDeg, Eigen::Vector3d::UnitZ()).toRotationMatrix());
    p.reflectivity = static_cast<float>(e.reflectivity);
    out.push_back(p);
  }
  return out;
}

}  // namespace ringtrack::sim
