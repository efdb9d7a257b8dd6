#pragma once
/// Ray casting primitives of the simulator: ground (flat or a gentle height field), yawed boxes,
/// capped vertical cylinders and arbitrarily oriented ellipsoids, with closed-form intersections.

#include <Eigen/Core>
#include <cstdint>
#include <limits>

namespace ringtrack::sim {

/// "No hit" distance.
inline constexpr double kNoHit = std::numeric_limits<double>::infinity();

/// Kinds of solid primitives.
enum class PrimitiveKind : std::uint8_t { kBox, kCylinder, kEllipsoid };

/// A solid in the world frame. Boxes rotate about z by yaw; cylinders are upright and capped;
/// ellipsoids are the image of the unit sphere under to_unit^-1 about center.
struct Primitive {
  PrimitiveKind kind{PrimitiveKind::kBox};
  std::uint32_t label{0};    ///< object id written to the label image, 0 = background
  float reflectivity{0.3f};  ///< 0..1, drives the return intensity
  std::int32_t mover{-1};    ///< index of the moving actor carrying it, -1 = static
  Eigen::Vector3d center{Eigen::Vector3d::Zero()};       ///< centre of the solid
  Eigen::Vector3d half{Eigen::Vector3d::Zero()};         ///< box half extents; cylinder (r, r, h/2)
  double cos_yaw{1.0}, sin_yaw{0.0};                     ///< box orientation about z
  Eigen::Matrix3d to_unit{Eigen::Matrix3d::Identity()};  ///< ellipsoid: world offset -> unit sphere
  double bound_radius_xy{0.0};  ///< radius of a circle about center.xy containing the footprint

  /// Upright box with its bottom face at base_z.
  static Primitive box(const Eigen::Vector2d& center_xy, double base_z_m,
                       const Eigen::Vector3d& size_m, double yaw_rad);
  /// Upright capped cylinder with its bottom at base_z.
  static Primitive cylinder(const Eigen::Vector2d& center_xy, double base_z_m, double radius_m,
                            double height_m);
  /// Ellipsoid with semi-axes radii along the columns of rotation (world from body).
  static Primitive ellipsoid(const Eigen::Vector3d& center, const Eigen::Vector3d& radii_m,
                             const Eigen::Matrix3d& rotation);
};

/// Distance t > t_min along o + t d (d unit) to the first surface point of p before t_max, or
/// kNoHit.
double intersect(const Primitive& p, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                 double t_min, double t_max);
/// Outward unit normal of p at a surface point x.
Eigen::Vector3d normal_at(const Primitive& p, const Eigen::Vector3d& x);

/// Ground surface: z = height_m + amplitude_m * s(x, y) with s a fixed sum of two sinusoids of the
/// given wavelength (|s| <= 1), limited to radius_m from the world origin.
struct Ground {
  bool enabled{true};         ///< false: no ground at all (indoor scenes with floors as boxes)
  double height_m{0.0};       ///< mean ground height
  double amplitude_m{0.0};    ///< 0 = flat plane
  double wavelength_m{40.0};  ///< of the undulation; keep >> amplitude for gentle slopes
  double phase_rad{0.0};      ///< shifts the undulation (seeded in scenarios)
  double radius_m{140.0};     ///< no ground beyond this horizontal distance from the origin
  float reflectivity{0.25f};  ///< of the ground material

  /// Ground height at (x, y).
  [[nodiscard]] double height_at(double x, double y) const;
  /// Upper bound of |grad height| (for safe ray marching).
  [[nodiscard]] double max_slope() const;
  /// First hit of the ray with the ground in (t_min, t_max), or kNoHit.
  [[nodiscard]] double intersect(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_min,
                                 double t_max) const;
  /// Upward unit normal at (x, y).
  [[nodiscard]] Eigen::Vector3d normal_at(double x, double y) const;
};

/// Polynomial atan2 (max error about 2e-4 rad), used to pick a ray's azimuth bin.
double fast_atan2(double y, double x);

}  // namespace ringtrack::sim
