#pragma once
/// Voxel map of the static part of the world: one averaged point per occupied voxel.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "ringtrack/core/box3.hpp"

namespace ringtrack::mapping {

/// One voxel's content.
struct MapPoint {
  Eigen::Vector3f position{Eigen::Vector3f::Zero()};  ///< mean of the points (world, m)
  float intensity{0.0f};                              ///< mean intensity
  std::uint32_t count{0};                             ///< points averaged
};

/// Per-grid-cell memory of the settled voxel each cell's point last went to: a static sensor
/// sees the same voxels scan after scan, and these points then need no map lookup at all.
struct SettledCells {
  std::vector<std::uint64_t> key;               ///< per cell: voxel key, or all ones when unknown
  std::uint64_t generation{~std::uint64_t{0}};  ///< map generation the keys belong to
};

/// Voxel grid in the world frame, stored in an open-addressing hash table keyed by the voxel
/// index (21 bits per axis: +-2^20 voxels, e.g. +-104 km at 0.1 m). Each voxel keeps the
/// mean of its first kSettledCount points, so memory grows with the occupied space, not with
/// time, and a settled voxel needs no more writes.
class StaticMap {
 public:
  /// Points averaged per voxel; later points leave it unchanged.
  static constexpr std::uint32_t kSettledCount = 64;

  /// voxel_size_m > 0.
  explicit StaticMap(double voxel_size_m);

  /// Adds a point (world frame); non-finite points and points outside the index range are
  /// counted in dropped_points() and ignored.
  void insert(const Eigen::Vector3f& p, float intensity);
  /// Adds points[i] with intensities[i] for every i where skip is empty or skip[i] == 0; the
  /// same result as insert() one by one, with memory prefetching (the map's hot loop).
  void insert(const std::vector<Eigen::Vector3f>& points, const std::vector<float>& intensities,
              const std::vector<std::uint8_t>& skip);
  /// As above, where point i comes from grid cell cells[i]; settled remembers, per cell, a
  /// settled voxel so that the next scans skip the lookup. Same map contents as without it.
  void insert(const std::vector<Eigen::Vector3f>& points, const std::vector<float>& intensities,
              const std::vector<std::uint8_t>& skip, const std::vector<std::uint32_t>& cells,
              SettledCells& settled);
  /// Removes every voxel whose mean lies inside box; returns how many.
  std::size_t remove_inside(const core::Box3& box);
  /// Removes every voxel.
  void clear();

  /// Changes whenever voxels are removed (SettledCells of older generations are stale).
  [[nodiscard]] std::uint64_t generation() const { return generation_; }
  /// Number of occupied voxels.
  [[nodiscard]] std::size_t size() const { return size_; }
  /// Edge of a voxel (m).
  [[nodiscard]] double voxel_size_m() const { return voxel_size_m_; }
  /// Points that could not be stored.
  [[nodiscard]] std::size_t dropped_points() const { return dropped_; }
  /// Every voxel's point, ordered by voxel index (deterministic).
  [[nodiscard]] std::vector<MapPoint> points() const;
  /// Calls f(const MapPoint&) for every voxel in table order.
  template <class F>
  void for_each(F&& f) const {
    for (const auto& s : slots_) {
      if (s.key != kEmpty) f(s.point);
    }
  }

 private:
  static constexpr std::uint64_t kEmpty = ~std::uint64_t{0};
  struct Slot {
    std::uint64_t key{kEmpty};
    MapPoint point;
  };

  [[nodiscard]] std::size_t home(std::uint64_t key) const;
  [[nodiscard]] std::size_t find(std::uint64_t key) const;  // slots_.size() when absent
  void erase_slot(std::size_t i);
  void accumulate(std::size_t slot, const Eigen::Vector3f& p, float intensity);
  std::size_t find_or_claim(std::uint64_t key, std::size_t start);  // room must exist
  void insert_batch(const std::vector<Eigen::Vector3f>& points,
                    const std::vector<float>& intensities, const std::vector<std::uint8_t>& skip,
                    const std::vector<std::uint32_t>* cells, SettledCells* settled);
  void grow();

  double voxel_size_m_;
  float inverse_size_;
  std::vector<Slot> slots_;
  std::size_t size_{0};
  int bits_{0};
  std::size_t dropped_{0};
  std::uint64_t generation_{0};
  // The last voxel touched: consecutive points of a ring often share a voxel.
  std::uint64_t last_key_{kEmpty};
  std::size_t last_slot_{0};
};

}  // namespace ringtrack::mapping
