#pragma once
/// Axis-aligned 3-D box.

#include <Eigen/Core>
#include <limits>

namespace ringtrack::core {

/// Axis-aligned box; default-constructed it is empty (min > max) and grows with extend().
struct Box3 {
  Eigen::Vector3f min{Eigen::Vector3f::Constant(std::numeric_limits<float>::infinity())};
  Eigen::Vector3f max{Eigen::Vector3f::Constant(-std::numeric_limits<float>::infinity())};

  /// True when no point has been added.
  [[nodiscard]] bool empty() const { return (min.array() > max.array()).any(); }
  /// Grows the box to contain p.
  void extend(const Eigen::Vector3f& p) {
    min = min.cwiseMin(p);
    max = max.cwiseMax(p);
  }
  /// Grows the box to contain another box.
  void extend(const Box3& b) {
    min = min.cwiseMin(b.min);
    max = max.cwiseMax(b.max);
  }
  /// Size along each axis (zero for an empty box).
  [[nodiscard]] Eigen::Vector3f size() const {
    return empty() ? Eigen::Vector3f::Zero() : Eigen::Vector3f(max - min);
  }
  /// Centre of the box.
  [[nodiscard]] Eigen::Vector3f center() const { return 0.5f * (min + max); }
  /// Diagonal of the box's footprint in the x-y plane.
  [[nodiscard]] float diagonal_xy() const { return size().head<2>().norm(); }
  /// True when p lies inside or on the boundary.
  [[nodiscard]] bool contains(const Eigen::Vector3f& p) const {
    return (p.array() >= min.array()).all() && (p.array() <= max.array()).all();
  }
  /// True when the two boxes share at least one point (touching counts).
  [[nodiscard]] bool intersects(const Box3& o) const {
    return !empty() && !o.empty() && (min.array() <= o.max.array()).all() &&
           (o.min.array() <= max.array()).all();
  }
  /// The box moved by t.
  [[nodiscard]] Box3 translated(const Eigen::Vector3f& t) const { return {min + t, max + t}; }
};

/// Axis-aligned box in double, for the world frame of the poses in outputs: UTM-scale
/// coordinates need more than float's 24 bits. Default-constructed it is empty (min > max).
struct Box3d {
  Eigen::Vector3d min{Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity())};
  Eigen::Vector3d max{Eigen::Vector3d::Constant(-std::numeric_limits<double>::infinity())};

  /// True when no point has been added.
  [[nodiscard]] bool empty() const { return (min.array() > max.array()).any(); }
  /// Grows the box to contain p (a float or double 3-vector).
  template <class Derived>
  void extend(const Eigen::MatrixBase<Derived>& p) {
    const Eigen::Vector3d q = p.template cast<double>();
    min = min.cwiseMin(q);
    max = max.cwiseMax(q);
  }
  /// A float box (e.g. the pipeline's local frame) shifted by offset; an empty box stays empty.
  [[nodiscard]] static Box3d shifted(const Box3& box, const Eigen::Vector3d& offset) {
    Box3d out;
    if (box.empty()) return out;
    out.min = box.min.cast<double>() + offset;
    out.max = box.max.cast<double>() + offset;
    return out;
  }
};

}  // namespace ringtrack::core
