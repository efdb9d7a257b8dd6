#pragma once
/// Where and when small objects were seen: the memory of the dynamic-object filter's transient
/// line (docs/tracking.md, "Transient line").

#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace ringtrack::mapping {

/// A hash grid of horizontal (x-y) cells that remembers, per cell, the first and the last scan
/// (by sequence number) in which a noted point fell in it. It answers whether the neighbourhood
/// of a point (its cell and the eight around it) held a noted point in a scan at least k scans
/// before or after a given one: something that stands there was seen again, whereas a walker's
/// points are seen once at each place.
///
/// Memory is bounded by the recent scans: a cell whose last point is more than memory_scans
/// older than the newest noted scan is forgotten when the table next grows (a forgotten cell
/// starts afresh when a point falls in it again).
class TransientGrid {
 public:
  /// The key of no cell: a point note() ignores.
  static constexpr std::uint64_t kNoCell = ~std::uint64_t{0};

  /// cell_m > 0; memory_scans: how long a cell is kept at least after its last point.
  TransientGrid(double cell_m, std::uint64_t memory_scans);

  /// The key of p's cell (world frame), or kNoCell for non-finite points and points beyond
  /// +-2^30 cells.
  [[nodiscard]] std::uint64_t key(const Eigen::Vector3f& p) const;
  /// Notes p as seen in scan `sequence`; sequences must not decrease from one call to the next.
  void note(const Eigen::Vector3f& p, std::uint64_t sequence);
  /// Notes the cells of keys (kNoCell skipped) as seen in scan `sequence`, as note() point by
  /// point would (the hot loop: the table's slots are prefetched).
  void note(const std::vector<std::uint64_t>& keys, std::uint64_t sequence);
  /// Whether p's cell or one of its eight neighbours held a noted point in a scan at least k
  /// scans before or after `sequence`. False for points note() would ignore.
  [[nodiscard]] bool confirmed(const Eigen::Vector3f& p, std::uint64_t sequence,
                               std::uint64_t k) const;
  /// The same for the cell of a key.
  [[nodiscard]] bool confirmed(std::uint64_t key, std::uint64_t sequence, std::uint64_t k) const;
  /// Appends to out every position j of keys whose cell is not confirmed (prefetched).
  void unconfirmed(const std::vector<std::uint64_t>& keys, std::uint64_t sequence, std::uint64_t k,
                   std::vector<std::uint32_t>& out) const;
  /// Cells remembered.
  [[nodiscard]] std::size_t size() const { return size_; }
  /// Slots of the table.
  [[nodiscard]] std::size_t capacity() const { return slots_.size(); }
  /// Forgets every cell.
  void clear();

 private:
  struct Slot {
    std::uint64_t key;  // kNoCell: free
    std::uint64_t first;
    std::uint64_t last;
  };

  [[nodiscard]] std::size_t home(std::uint64_t key) const;
  [[nodiscard]] const Slot* find(std::uint64_t key) const;
  // Adds or refreshes the cell; the table has room.
  void insert(std::uint64_t key, std::uint64_t sequence);
  // Rebuilds the table without the forgotten cells, at most a quarter full with `extra` more.
  void rebuild(std::size_t extra);

  float inverse_cell_;
  std::uint64_t memory_scans_;
  std::vector<Slot> slots_;  // open addressing, linear probing, a power of two
  int bits_{0};              // log2(slots_.size())
  std::size_t size_{0};
  std::uint64_t newest_{0};
  std::vector<std::uint64_t> unique_;  // note()'s batch without repeats
};

}  // namespace ringtrack::mapping
