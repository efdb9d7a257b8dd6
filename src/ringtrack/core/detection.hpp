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
  /// Cells of the object the segmentation missed, added by detection::DetectionCompleter (the
  /// legs below a torso): part of the object, but not of its shape above (association and the
  /// static/dynamic tests use the cells the detector found, which do not change with the ground
  /// behind the object).
  std::vector<std::uint32_t> completion;
  /// Mean of indices and completion cells, world frame; meaningful only when completion is not
  /// empty (see object_centroid()).
  Eigen::Vector3f completed_centroid{Eigen::Vector3f::Zero()};
  bool relaxed{false};  ///< accepted only by the relaxed model near a predicted track
  bool sparse{false};   ///< fewer points than a detection needs, accepted for lying in front of
                        ///< the learned background (docs/detection.md)

  /// Where the object is: the centroid of all its cells, the completion included.
  [[nodiscard]] Eigen::Vector3f object_centroid() const {
    return completion.empty() ? centroid : completed_centroid;
  }
};

}  // namespace ringtrack::core
