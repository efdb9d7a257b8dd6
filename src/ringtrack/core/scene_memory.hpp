#pragma once
/// What earlier scans saw of the space a point of the current scan now occupies: the evidence
/// that lets the detector keep clusters too small for its object model (docs/visibility.md).

#include <Eigen/Core>
#include <cstdint>

#include "ringtrack/core/organized_scan.hpp"

namespace ringtrack::core {

/// Memory of the scene: whether a point of the current scan stands where the scene was seen
/// free before (something new is there: a far person hit by one or two beams), as opposed to
/// where earlier scans saw structure or nothing at all.
class SceneMemory {
 public:
  SceneMemory() = default;
  SceneMemory(const SceneMemory&) = default;
  SceneMemory& operator=(const SceneMemory&) = default;
  SceneMemory(SceneMemory&&) = default;
  SceneMemory& operator=(SceneMemory&&) = default;
  virtual ~SceneMemory() = default;

  /// True when the valid cell of the current scan, at world_point, lies at least margin_m in
  /// front of what earlier scans saw through that space; false without evidence.
  [[nodiscard]] virtual bool seen_free_before(const OrganizedScan& scan, std::size_t cell,
                                              const Eigen::Vector3d& world_point,
                                              double margin_m) const = 0;
};

}  // namespace ringtrack::core
