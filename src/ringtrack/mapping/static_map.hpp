#pragma once
/// Voxel map of the static part of the world: one averaged point per occupied voxel.

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "ringtrack/core/box3.hpp"

namespace ringtrack::mapping {

/// One voxel's content.
struct MapPoint {
  Eigen::Vector3f position{Eigen::Vector3f::Zero()};  ///< mean of the points (world, m)
  float intensity{0.0f};                              ///< mean intensity
  std::uint32_t count{0};                             ///< points averaged
};

/// Per-grid-cell memory of the settled voxels each cell's points last went to: a static sensor
/// sees the same voxels scan after scan, and these points then need no map lookup at all. Range
/// noise spreads one cell's points over two to four neighbouring voxels (3 cm of noise against
/// 10 cm voxels moves most points into another voxel than the cell's previous one), so each cell
/// keeps its last four settled voxels, not one.
struct SettledCells {
  static constexpr std::size_t kKeysPerCell = 4;  ///< settled voxels remembered per cell
  /// kKeysPerCell keys per cell (cell c at c * kKeysPerCell), newest first; all ones: none
  std::vector<std::uint64_t> key;
  std::uint64_t generation{~std::uint64_t{0}};  ///< map generation the keys belong to
};

/// Voxel grid in the world frame: the voxels (index key and mean point) in a dense array, found
/// through an open-addressing hash table of 8-byte slots keyed by the voxel index (21 bits per
/// axis: +-2^20 voxels, e.g. +-104 km at 0.1 m). Each voxel keeps the mean of its first
/// kSettledCount points, so memory grows with the occupied space, not with time, and a settled
/// voxel needs no more writes. The table grows incrementally: a doubled table is prepared and
/// filled a little at each insert, in proportion to the voxels added and the points inserted, so
/// no single call rehashes the whole map (a moving sensor adds thousands of voxels per scan).
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
  /// The voxel p falls in, or nullptr (no such voxel, or p outside the index range).
  [[nodiscard]] const MapPoint* voxel_at(const Eigen::Vector3f& p) const;
  /// The key of the voxel p falls in (equal for two points exactly when they share a voxel), or
  /// nothing for a point the map would drop (non-finite, outside the index range).
  [[nodiscard]] std::optional<std::uint64_t> key_of(const Eigen::Vector3f& p) const;
  /// Removes every voxel whose mean lies inside box; returns how many.
  std::size_t remove_inside(const core::Box3& box);
  /// Removes every voxel whose mean lies farther than radius_m horizontally (x-y) from center,
  /// appending each to evicted before it goes; returns how many. One pass over the voxels.
  std::size_t remove_outside(const Eigen::Vector2f& center, float radius_m,
                             std::vector<MapPoint>& evicted);
  /// The same test for at most `visits` voxels of the dense array below `cursor` (clamped to
  /// size()), from the top down; cursor ends below the last voxel visited. Sweeping the map in
  /// slices from cursor = size() down to 0 visits every voxel that existed when the sweep began
  /// and was not moved by a removal meanwhile (removals move the last voxel down; voxels added
  /// meanwhile are left to the next sweep).
  std::size_t remove_outside(const Eigen::Vector2f& center, float radius_m,
                             std::vector<MapPoint>& evicted, std::size_t& cursor,
                             std::size_t visits);
  /// Removes every voxel.
  void clear();
  /// Completes a pending table resize now (otherwise spread over the next inserts).
  void finish_resize();

  /// True while the table is being grown (voxels may be found through the old or the new table).
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
  /// Calls f(const MapPoint&) for every voxel in storage order.
  template <class F>
  void for_each(F&& f) const {
    for (std::size_t i = 0; i < size_; ++i) f(voxel(i).point);
  }

 private:
  // A voxel: its packed index and its mean.
  struct alignas(32) Voxel {
    std::uint64_t key;
    MapPoint point;
  };
  static_assert(sizeof(Voxel) == 32);
  // A table slot: the upper 32 bits of the key's hash (its fingerprint, which also gives the
  // home slot in every table of up to 2^32 slots, so growing the table never reads the voxels)
  // and 1 + the voxel's index in the dense array; 0 = free. A quarter of the 32-byte slots that
  // held the voxels themselves: the memory a growing map first touches (page faults, the cost of
  // growth on the development VM) is the table's share of it.
  using Slot = std::uint64_t;
  static constexpr Slot kFree = 0;
  // A voxel erased from the old table while it drains: probes continue past it.
  static constexpr Slot kGone = Slot{1} << 32;
  // Storage in blocks of 2 MiB whose memory is obtained but not touched (written) until used:
  // the page faults come with the work that writes there, not with the allocation.
  struct RawDelete {
    void operator()(void* p) const;
  };
  template <class T>
  using Block = std::unique_ptr<T[], RawDelete>;
  // One open-addressing table (linear probing) of 2^bits slots, in chunks of at most 2^18
  // slots: a new table is prepared and an old one freed chunk by chunk.
  struct Table {
    std::vector<Block<Slot>> chunks;
    std::size_t size{0};
    int bits{0};
    int chunk_bits{0};
    std::size_t ready{0};  // slots [0, ready) are allocated and cleared

    Slot& operator[](std::size_t i) {
      return chunks[i >> chunk_bits][i & ((std::size_t{1} << chunk_bits) - 1)];
    }
    const Slot& operator[](std::size_t i) const {
      return chunks[i >> chunk_bits][i & ((std::size_t{1} << chunk_bits) - 1)];
    }
  };
  // kPreparing: table_ takes the inserts while next_ (twice as large) is cleared.
  // kMoving: table_ (the new one) takes the inserts while old_ drains into it, front to back.
  enum class Phase { kIdle, kPreparing, kMoving };

  // An uninitialized block of n T, a spare one when it has the size of the spares.
  template <class T>
  Block<T> take_block(std::size_t n);
  template <class T>
  void give_block(Block<T> block, std::size_t n);   // kept as a spare when it has their size
  static Table make_table(int bits);                // no chunk allocated yet
  void prepare_slots(Table& t, std::size_t slots);  // up to slots allocated and cleared
  [[nodiscard]] Voxel& voxel(std::size_t i) { return blocks_[i >> kBlockBits][i & kBlockMask]; }
  [[nodiscard]] const Voxel& voxel(std::size_t i) const {
    return blocks_[i >> kBlockBits][i & kBlockMask];
  }
  // Slot i holds voxel key (fingerprint fp), as opposed to another voxel, kFree or kGone.
  [[nodiscard]] bool holds(Slot s, std::uint32_t fp, std::uint64_t key) const;
  [[nodiscard]] std::size_t find(std::uint64_t key) const;      // in table_; its size if absent
  [[nodiscard]] std::size_t find_old(std::uint64_t key) const;  // in old_; its size if absent
  [[nodiscard]] std::size_t find_old(std::uint64_t key, std::uint32_t fp) const;
  void erase_slot(std::size_t i);
  void erase(std::uint64_t key);
  // Appends to doomed the keys[0, n) whose voxels exist and lie inside box; the home slots are
  // fetched kPrefetch keys ahead (remove_inside's small-box path).
  void collect_inside(const std::uint64_t* keys, std::size_t n, const core::Box3& box,
                      std::vector<std::uint64_t>& doomed) const;
  static void accumulate(MapPoint& m, const Eigen::Vector3f& p, float intensity);
  std::size_t add_voxel(std::uint64_t key);  // appended to the dense array; its index
  // The voxel's point wherever its slot is (old_ first while it drains), claimed in table_ if new.
  MapPoint& locate(std::uint64_t key, std::uint32_t fp);
  void insert_batch(const std::vector<Eigen::Vector3f>& points,
                    const std::vector<float>& intensities, const std::vector<std::uint8_t>& skip,
                    const std::vector<std::uint32_t>* cells, SettledCells* settled);
  void make_room(std::size_t n);  // table_ can take n new voxels at load <= 0.7
  void start_resize();
  void advance_resize(std::size_t units);
  void prepare(std::size_t slots);
  void drain(std::size_t slots);

  static constexpr int kBlockBits = 16;  // voxels per block of the dense array: 2 MiB
  static constexpr std::size_t kBlockMask = (std::size_t{1} << kBlockBits) - 1;

  double voxel_size_m_;
  float inverse_size_;
  std::vector<Block<Voxel>> blocks_;  // the voxels [0, size_), dense: removal moves the last
  // 2 MiB blocks of drained tables, for the next voxels and tables: memory already written is
  // cheap to reuse, new memory costs a page fault per 4 KiB.
  std::vector<Block<std::byte>> spares_;
  Table table_;
  Table old_;
  Table next_;
  Phase phase_{Phase::kIdle};
  std::size_t drained_{0};  // old_ slots [0, drained_) are moved (their chunks freed)
  std::size_t size_{0};     // voxels
  std::size_t dropped_{0};
  std::uint64_t generation_{0};
  // The last voxel touched: consecutive points of a ring often share a voxel. Forgotten
  // whenever a voxel may move (erase).
  std::uint64_t last_key_{~std::uint64_t{0}};
  MapPoint* last_point_{nullptr};
};

}  // namespace ringtrack::mapping
