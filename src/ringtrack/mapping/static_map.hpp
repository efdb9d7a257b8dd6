#pragma once
/// Voxel map of the static part of the world: one averaged point per occupied voxel.

#include <Eigen/Core>
#include <cstdint>
#include <memory>
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
/// time, and a settled voxel needs no more writes. The table grows incrementally: a doubled
/// table is allocated and filled a little at each insert, in proportion to the voxels added and
/// the points inserted, so no single call rehashes the whole map (a moving sensor adds thousands
/// of voxels per scan).
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
  /// Completes a pending table resize now (otherwise spread over the next inserts).
  void finish_resize();

  /// True while the table is being grown (voxels may sit in the old or the new table).
  [[nodiscard]] bool resizing() const { return phase_ != Phase::kIdle; }
  /// Slots of the table new voxels go to.
  [[nodiscard]] std::size_t capacity() const { return table_.size; }

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
    for (std::size_t i = 0; i < table_.size; ++i) {
      if (is_key(table_[i].key)) f(table_[i].point);
    }
    for (std::size_t i = drained_; i < old_.size; ++i) {
      if (is_key(old_[i].key)) f(old_[i].point);
    }
  }

 private:
  static constexpr std::uint64_t kEmpty = ~std::uint64_t{0};
  // A voxel erased from the old table while it drains: probes continue past it.
  static constexpr std::uint64_t kGone = kEmpty - 1;
  // 32 bytes, aligned so that no slot straddles two cache lines (one miss per probe).
  struct alignas(32) Slot {
    std::uint64_t key{kEmpty};
    MapPoint point;
  };
  static_assert(sizeof(Slot) == 32);
  // One open-addressing table (linear probing) of 2^bits slots, stored in chunks of at most
  // 2^16 slots (2 MiB): a new table is allocated and an old one freed chunk by chunk, so no
  // call pays for a whole large table at once.
  struct Table {
    std::vector<std::unique_ptr<Slot[]>> chunks;
    std::size_t size{0};
    int bits{0};
    int chunk_bits{0};
    std::size_t ready{0};  // slots allocated so far while the table is prepared

    Slot& operator[](std::size_t i) {
      return chunks[i >> chunk_bits][i & ((std::size_t{1} << chunk_bits) - 1)];
    }
    const Slot& operator[](std::size_t i) const {
      return chunks[i >> chunk_bits][i & ((std::size_t{1} << chunk_bits) - 1)];
    }
  };
  // kPreparing: table_ takes the inserts while next_ (twice as large) is allocated.
  // kMoving: table_ (the new one) takes the inserts while old_ drains into it, front to back.
  enum class Phase { kIdle, kPreparing, kMoving };

  static bool is_key(std::uint64_t key) { return key < kGone; }
  static Table make_table(int bits);                         // no chunk allocated yet
  static void allocate_chunks(Table& t, std::size_t slots);  // up to slots allocated
  [[nodiscard]] static std::size_t home(std::uint64_t key, int bits);
  [[nodiscard]] std::size_t find(std::uint64_t key) const;      // in table_; its size if absent
  [[nodiscard]] std::size_t find_old(std::uint64_t key) const;  // in old_; its size if absent
  [[nodiscard]] std::size_t find_old(std::uint64_t key, std::size_t old_home) const;
  void erase_slot(std::size_t i);
  void erase(std::uint64_t key);
  static void accumulate(MapPoint& m, const Eigen::Vector3f& p, float intensity);
  std::size_t find_or_claim(std::uint64_t key, std::size_t start);  // in table_; room must exist
  // The voxel's point wherever it lives (old_ first while it drains), claimed in table_ if new;
  // home and old_home are the key's home slots in table_ and old_.
  MapPoint& locate(std::uint64_t key, std::size_t home, std::size_t old_home);
  void insert_batch(const std::vector<Eigen::Vector3f>& points,
                    const std::vector<float>& intensities, const std::vector<std::uint8_t>& skip,
                    const std::vector<std::uint32_t>* cells, SettledCells* settled);
  void make_room(std::size_t n);  // table_ can take n new voxels at load <= 1/2
  void start_resize();
  void advance_resize(std::size_t units);
  void prepare(std::size_t slots);
  void drain(std::size_t slots);

  double voxel_size_m_;
  float inverse_size_;
  Table table_;
  Table old_;
  Table next_;
  Phase phase_{Phase::kIdle};
  std::size_t drained_{0};  // old_ slots [0, drained_) are moved (their chunks freed)
  std::size_t size_{0};     // voxels in table_ and old_
  std::size_t dropped_{0};
  std::uint64_t generation_{0};
  // The last voxel touched: consecutive points of a ring often share a voxel. Forgotten
  // whenever a voxel may move (erase, table switch, drain).
  std::uint64_t last_key_{kEmpty};
  MapPoint* last_point_{nullptr};
};

}  // namespace ringtrack::mapping
