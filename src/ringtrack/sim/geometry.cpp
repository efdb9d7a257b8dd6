#include "ringtrack/sim/geometry.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace ringtrack::sim {
namespace {

double intersect_box(const Primitive& p, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                     double t_min, double t_max) {
  const Eigen::Vector3d r = o - p.center;
  const double ox = p.cos_yaw * r.x() + p.sin_yaw * r.y();
  const double oy = -p.sin_yaw * r.x() + p.cos_yaw * r.y();
  const double dx = p.cos_yaw * d.x() + p.sin_yaw * d.y();
  const double dy = -p.sin_yaw * d.x() + p.cos_yaw * d.y();
  double t_near = -kNoHit, t_far = kNoHit;
  const double os[3] = {ox, oy, r.z()};
  const double ds[3] = {dx, dy, d.z()};
  for (int a = 0; a < 3; ++a) {
    const double h = p.half[a];
    if (std::abs(ds[a]) < 1e-15) {
      if (std::abs(os[a]) > h) return kNoHit;  // parallel to and outside this slab
      continue;
    }
    const double inv = 1.0 / ds[a];
    double t0 = (-h - os[a]) * inv, t1 = (h - os[a]) * inv;
    if (t0 > t1) std::swap(t0, t1);
    t_near = std::max(t_near, t0);
    t_far = std::min(t_far, t1);
    if (t_near > t_far) return kNoHit;
  }
  const double t = t_near > t_min ? t_near : t_far;
  return (t > t_min && t < t_max) ? t : kNoHit;
}

double intersect_cylinder(const Primitive& p, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                          double t_min, double t_max) {
  const double px = o.x() - p.center.x(), py = o.y() - p.center.y(), pz = o.z() - p.center.z();
  const double r = p.half.x(), hz = p.half.z();
  double best = t_max;
  const double a = d.x() * d.x() + d.y() * d.y();
  if (a > 1e-15) {
    // Closest approach first, then the half chord: stable for small cylinders far away.
    const double t_ca = -(px * d.x() + py * d.y()) / a;
    const double qx = px + t_ca * d.x(), qy = py + t_ca * d.y();
    const double h2 = r * r - (qx * qx + qy * qy);
    if (h2 >= 0.0) {
      const double dt = std::sqrt(h2 / a);
      for (const double t : {t_ca - dt, t_ca + dt}) {
        if (t > t_min && t < best && std::abs(pz + t * d.z()) <= hz) {
          best = t;
          break;
        }
      }
    }
  }
  if (std::abs(d.z()) > 1e-15) {
    for (const double zc : {-hz, hz}) {
      const double t = (zc - pz) / d.z();
      if (t > t_min && t < best) {
        const double x = px + t * d.x(), y = py + t * d.y();
        if (x * x + y * y <= r * r) best = t;
      }
    }
  }
  return best < t_max ? best : kNoHit;
}

double intersect_ellipsoid(const Primitive& p, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                           double t_min, double t_max) {
  // In the unit-sphere frame the ray parameter t is unchanged (affine map).
  const Eigen::Vector3d ou = p.to_unit * (o - p.center);
  const Eigen::Vector3d du = p.to_unit * d;
  const double a = du.squaredNorm();
  const double t_ca = -ou.dot(du) / a;
  const double h2 = 1.0 - (ou + t_ca * du).squaredNorm();
  if (h2 < 0.0) return kNoHit;
  const double dt = std::sqrt(h2 / a);
  double t = t_ca - dt;
  if (t <= t_min) t = t_ca + dt;
  return (t > t_min && t < t_max) ? t : kNoHit;
}

}  // namespace

Primitive Primitive::box(const Eigen::Vector2d& center_xy, double base_z_m,
                         const Eigen::Vector3d& size_m, double yaw_rad) {
  Primitive p;
  p.kind = PrimitiveKind::kBox;
  p.center = {center_xy.x(), center_xy.y(), base_z_m + 0.5 * size_m.z()};
  p.half = 0.5 * size_m;
  p.cos_yaw = std::cos(yaw_rad);
  p.sin_yaw = std::sin(yaw_rad);
  p.bound_radius_xy = p.half.head<2>().norm();
  return p;
}

Primitive Primitive::cylinder(const Eigen::Vector2d& center_xy, double base_z_m, double radius_m,
                              double height_m) {
  Primitive p;
  p.kind = PrimitiveKind::kCylinder;
  p.center = {center_xy.x(), center_xy.y(), base_z_m + 0.5 * height_m};
  p.half = {radius_m, radius_m, 0.5 * height_m};
  p.bound_radius_xy = radius_m;
  return p;
}

Primitive Primitive::ellipsoid(const Eigen::Vector3d& center, const Eigen::Vector3d& radii_m,
                               const Eigen::Matrix3d& rotation) {
  Primitive p;
  p.kind = PrimitiveKind::kEllipsoid;
  p.center = center;
  p.half = radii_m;
  p.to_unit = radii_m.cwiseInverse().asDiagonal() * rotation.transpose();
  // Horizontal half extent of the rotated ellipsoid along x and y: sqrt(sum (R_ij r_j)^2).
  const Eigen::Matrix3d m = rotation * radii_m.asDiagonal();
  p.bound_radius_xy = std::hypot(m.row(0).norm(), m.row(1).norm());
  return p;
}

double intersect(const Primitive& p, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                 double t_min, double t_max) {
  switch (p.kind) {
    case PrimitiveKind::kBox:
      return intersect_box(p, o, d, t_min, t_max);
    case PrimitiveKind::kCylinder:
      return intersect_cylinder(p, o, d, t_min, t_max);
    case PrimitiveKind::kEllipsoid:
      return intersect_ellipsoid(p, o, d, t_min, t_max);
  }
  return kNoHit;
}

Eigen::Vector3d normal_at(const Primitive& p, const Eigen::Vector3d& x) {
  const Eigen::Vector3d r = x - p.center;
  switch (p.kind) {
    case PrimitiveKind::kBox: {
      const Eigen::Vector3d l{p.cos_yaw * r.x() + p.sin_yaw * r.y(),
                              -p.sin_yaw * r.x() + p.cos_yaw * r.y(), r.z()};
      int axis = 0;
      double best = -1.0;
      for (int a = 0; a < 3; ++a) {
        const double v = std::abs(l[a]) / p.half[a];
        if (v > best) {
          best = v;
          axis = a;
        }
      }
      const double s = l[axis] >= 0 ? 1.0 : -1.0;
      if (axis == 2) return {0.0, 0.0, s};
      if (axis == 0) return {s * p.cos_yaw, s * p.sin_yaw, 0.0};
      return {-s * p.sin_yaw, s * p.cos_yaw, 0.0};
    }
    case PrimitiveKind::kCylinder: {
      if (std::abs(r.z()) >= p.half.z() - 1e-6) return {0.0, 0.0, r.z() >= 0 ? 1.0 : -1.0};
      const double n = std::hypot(r.x(), r.y());
      return n > 0 ? Eigen::Vector3d(r.x() / n, r.y() / n, 0.0) : Eigen::Vector3d::UnitX();
    }
    case PrimitiveKind::kEllipsoid:
      return (p.to_unit.transpose() * (p.to_unit * r)).normalized();
  }
  return Eigen::Vector3d::UnitZ();
}

double Ground::height_at(double x, double y) const {
  if (amplitude_m == 0.0) return height_m;
  const double k = 2.0 * std::numbers::pi / wavelength_m;
  const double s = 0.6 * std::sin(k * x + phase_rad) * std::cos(0.8 * k * y + 0.7 * phase_rad) +
                   0.4 * std::sin(0.6 * k * (0.8 * x - 0.6 * y) + 1.3 * phase_rad);
  return height_m + amplitude_m * s;
}

double Ground::max_slope() const {
  const double k = 2.0 * std::numbers::pi / wavelength_m;
  return std::abs(amplitude_m) * k * (0.6 * 1.8 + 0.4 * 0.6);
}

Eigen::Vector3d Ground::normal_at(double x, double y) const {
  if (amplitude_m == 0.0) return Eigen::Vector3d::UnitZ();
  const double e = 1e-3;
  const double gx = (height_at(x + e, y) - height_at(x - e, y)) / (2 * e);
  const double gy = (height_at(x, y + e) - height_at(x, y - e)) / (2 * e);
  return Eigen::Vector3d(-gx, -gy, 1.0).normalized();
}

double Ground::intersect(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_min,
                         double t_max) const {
  if (!enabled) return kNoHit;
  const auto inside = [&](double t) {
    const double x = o.x() + t * d.x(), y = o.y() + t * d.y();
    return x * x + y * y <= radius_m * radius_m;
  };
  if (amplitude_m == 0.0) {
    if (std::abs(d.z()) < 1e-15) return kNoHit;
    const double t = (height_m - o.z()) / d.z();
    return (t > t_min && t < t_max && inside(t)) ? t : kNoHit;
  }
  // Height field: sphere tracing with a Lipschitz bound inside the slab |z - height| <= amplitude,
  // then bisection on the sign change.
  const double top = height_m + std::abs(amplitude_m), bottom = height_m - std::abs(amplitude_m);
  double t = t_min;
  double t_end = t_max;
  if (o.z() > top) {
    if (d.z() >= 0) return kNoHit;
    t = std::max(t, (top - o.z()) / d.z());
  }
  if (d.z() < 0) t_end = std::min(t_end, (bottom - o.z()) / d.z());
  const auto f = [&](double s) {
    return o.z() + s * d.z() - height_at(o.x() + s * d.x(), o.y() + s * d.y());
  };
  const double rate = std::abs(d.z()) + max_slope() * std::hypot(d.x(), d.y());
  double f_t = f(t);
  if (f_t <= 0) return kNoHit;  // origin below the ground
  while (t < t_end) {
    const double step = std::max(f_t / std::max(rate, 1e-9), 0.1);
    const double t_next = std::min(t + step, t_end);
    const double f_next = f(t_next);
    if (f_next <= 0) {
      double lo = t, hi = t_next;
      for (int i = 0; i < 40 && hi - lo > 1e-6; ++i) {
        const double mid = 0.5 * (lo + hi);
        (f(mid) > 0 ? lo : hi) = mid;
      }
      return (hi > t_min && hi < t_max && inside(hi)) ? hi : kNoHit;
    }
    if (t_next >= t_end) break;
    t = t_next;
    f_t = f_next;
  }
  return kNoHit;
}

double fast_atan2(double y, double x) {
  const double ax = std::abs(x), ay = std::abs(y);
  const double mx = std::max(ax, ay);
  if (mx == 0.0) return 0.0;
  const double a = std::min(ax, ay) / mx;
  const double s = a * a;
  double r = ((-0.0464964749 * s + 0.15931422) * s - 0.327622764) * s * a + a;
  if (ay > ax) r = 0.5 * std::numbers::pi - r;
  if (x < 0) r = std::numbers::pi - r;
  return y < 0 ? -r : r;
}

}  // namespace ringtrack::sim
