#pragma once
/// A detected object, the interface between detection and tracking.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "ringtrack/core/box3.hpp"

namespace ringtrack::core {

/// One object found in one scan, in the world frame.
struct Detection {
  Eigen::Vector3f centroid{Eigen::Vector3f::Zero()};        ///< mean of its points, world frame
  Eigen::Matrix3f covariance{Eigen::Matrix3f::Identity()};  ///< of its points, with a floor
  Box3 box;                                                 ///< axis-aligned, world frame
  std::vector<std::uint32_t> indices;  ///< grid cells (ring * columns + column)
  bool relaxed{false};  ///< accepted only by the relaxed model near a predicted track
  bool sparse{false};   ///< fewer points than a detection needs, accepted for lying in front of
                        ///< the learned background (docs/detection.md)
};

}  // namespace ringtrack::core
