#pragma once
/// Voxel hashing for the odometry: a flat set of voxel keys (downsampling) and the local map
/// (a bounded number of points per voxel, cropped around the sensor).

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

namespace ringtrack::odometry {

/// Integer voxel coordinates packed into 63 bits (21 bits per axis, +-2^20 voxels).
using VoxelKey = std::uint64_t;

/// floor(v) as an int for finite |v| < 2^31; without SSE4.1 std::floor is a libm call, and the
/// downsampling takes three per point.
[[nodiscard]] inline int floor_to_int(float v) {
  const int i = static_cast<int>(v);  // truncates towards zero
  return i - static_cast<int>(v < static_cast<float>(i));
}
/// Key of integer voxel coordinates. Coordinates beyond +-2^20 voxels wrap: points that far
/// apart never meet in one scan's search. Inline: downsampling and the search call it per point.
[[nodiscard]] inline VoxelKey pack_voxel(int x, int y, int z) {
  constexpr int kAxisBits = 21;
  constexpr int kAxisOffset = 1 << (kAxisBits - 1);
  constexpr VoxelKey kAxisMask = (VoxelKey{1} << kAxisBits) - 1;
  const auto ux = static_cast<VoxelKey>(x + kAxisOffset) & kAxisMask;
  const auto uy = static_cast<VoxelKey>(y + kAxisOffset) & kAxisMask;
  const auto uz = static_cast<VoxelKey>(z + kAxisOffset) & kAxisMask;
  return ux | (uy << kAxisBits) | (uz << (2 * kAxisBits));
}
/// Key of the voxel of edge voxel_size_m holding p.
[[nodiscard]] inline VoxelKey voxel_key(const Eigen::Vector3f& p, float inv_voxel_size) {
  return pack_voxel(floor_to_int(p.x() * inv_voxel_size), floor_to_int(p.y() * inv_voxel_size),
                    floor_to_int(p.z() * inv_voxel_size));
}

/// Open-addressing set of voxel keys, reused across scans without reallocating (clear() keeps the
/// table): the voxel downsampling of a scan costs tens of nanoseconds per point.
class VoxelKeySet {
 public:
  /// Empties the set and makes room for at least n keys at load <= 1/2.
  void clear(std::size_t n);
  /// Inserts the key; true when it was not in the set. The table doubles past load 1/2.
  bool insert(VoxelKey key);
  /// Number of keys.
  [[nodiscard]] std::size_t size() const { return size_; }

 private:
  void grow();

  static constexpr VoxelKey kEmpty = ~VoxelKey{0};
  std::vector<VoxelKey> slots_;
  std::size_t mask_{0};
  std::size_t size_{0};
};

/// The local map: world-frame points in voxels of edge voxel_size_m, at most max_points each.
class VoxelMap {
 public:
  /// Points of one voxel, in insertion order, and the voxel's lowest corner. The coordinates
  /// are kept as three arrays: the neighbour search computes a voxel's distances in one loop
  /// the compiler vectorises (docs/odometry.md, "Speed").
  struct Voxel {
    Eigen::Vector3f corner{Eigen::Vector3f::Zero()};
    std::vector<float> x, y, z;
    VoxelKey key{0};  ///< its key (the table is rebuilt from the voxels after a crop)
    /// Number of points.
    [[nodiscard]] std::size_t size() const { return x.size(); }
    /// Point j.
    [[nodiscard]] Eigen::Vector3f point(std::size_t j) const { return {x[j], y[j], z[j]}; }
  };
  /// Squared distance from p to the voxel's cube (0 inside): a search skips voxels no nearer
  /// than the best point found so far.
  [[nodiscard]] float cube_distance2(const Voxel& v, const Eigen::Vector3f& p) const {
    const Eigen::Vector3f d = (v.corner - p).cwiseMax(p - v.corner - edge_).cwiseMax(0.0F);
    return d.squaredNorm();
  }

  VoxelMap(double voxel_size_m, int max_points_per_voxel);

  /// Adds world-frame points; a full voxel ignores further points (the first ones stay).
  void insert(const std::vector<Eigen::Vector3f>& points);
  /// Drops every voxel whose first point lies farther than radius_m from center.
  void crop(const Eigen::Vector3f& center, double radius_m);
  /// Removes every point.
  void clear();

  /// The voxels to search for the neighbour of p within max_distance_m (<= voxel size): the 2x2x2
  /// block around p when max_distance_m <= half a voxel, else the 3x3x3 block. Returns how many
  /// it wrote to out (only voxels that exist).
  int candidates(const Eigen::Vector3f& p, double max_distance_m,
                 std::array<const Voxel*, 27>& out) const;
  /// Key of the block candidates() searches for p (equal keys: equal candidate voxels). Inline:
  /// ICP asks it for every point in every iteration.
  [[nodiscard]] VoxelKey block_key(const Eigen::Vector3f& p, double max_distance_m) const {
    const Eigen::Vector3f q = p * inv_voxel_size_;
    const float shift = max_distance_m <= 0.5 * voxel_size_m_ ? 0.5F : 0.0F;
    return pack_voxel(floor_to_int(q.x() - shift), floor_to_int(q.y() - shift),
                      floor_to_int(q.z() - shift));
  }
  /// Nearest map point to p within max_distance_m; false when none.
  bool nearest(const Eigen::Vector3f& p, double max_distance_m, Eigen::Vector3f& out) const;

  [[nodiscard]] double voxel_size_m() const { return voxel_size_m_; }
  /// Points kept per voxel at most.
  [[nodiscard]] std::size_t max_points_per_voxel() const { return max_points_; }
  [[nodiscard]] std::size_t voxel_count() const { return voxels_.size(); }
  /// Number of points in the map.
  [[nodiscard]] std::size_t point_count() const;
  /// Every map point (tests, visualisation).
  [[nodiscard]] std::vector<Eigen::Vector3f> points() const;

 private:
  // One slot of the open-addressing table (linear probing, load <= 1/2): the key and the
  // voxel's index in voxels_. A std::unordered_map's node per voxel cost a pointer chase and a
  // cache miss per lookup, and the search looks up 8 voxels per query point (docs/odometry.md,
  // "Speed").
  struct Slot {
    VoxelKey key{kEmptyKey};
    std::uint32_t index{0};
  };
  static constexpr VoxelKey kEmptyKey = ~VoxelKey{0};  // pack_voxel never makes it (63 bits)
  static constexpr std::size_t kMinTableSlots = 64;
  [[nodiscard]] std::size_t home_slot(VoxelKey key) const {
    key ^= key >> 33U;  // splitmix-style finaliser: neighbouring voxels land far apart
    key *= 0xff51afd7ed558ccdULL;
    key ^= key >> 33U;
    return static_cast<std::size_t>(key) & (table_.size() - 1);
  }
  [[nodiscard]] const Voxel* find(VoxelKey key) const;
  const Voxel* find(int x, int y, int z) const { return find(pack_voxel(x, y, z)); }
  // The voxel of key, created (empty) when missing.
  Voxel& find_or_add(VoxelKey key);
  // Rebuilds table_ from voxels_ with room for at least `voxels` at load <= 1/2.
  void rebuild_table(std::size_t voxels);

  double voxel_size_m_;
  float inv_voxel_size_;
  Eigen::Vector3f edge_;
  std::size_t max_points_;
  std::vector<Voxel> voxels_;  // dense, in creation order (crop keeps the order)
  std::vector<Slot> table_;    // a power of two in size
};

/// Nearest map points of a fixed list of query points that move a little between calls (the
/// source points of one ICP run), against a map that does not change meanwhile. Answers exactly
/// as VoxelMap::nearest (up to ties), but searches only when needed: each slot remembers where it
/// last searched, the kKept nearest candidates found there and the distance b to the nearest
/// candidate it did not keep (or the search's reach). A query that moved by d from there, whose
/// nearest kept candidate lies closer than b - d, has that candidate as its answer: every other
/// point is at least b - d away (triangle inequality). While its candidate block stays the same,
/// only the kept candidates' distances are computed.
class NeighbourCache {
 public:
  /// Candidates a slot keeps from its last search: more keep answers valid over longer moves on
  /// dense surfaces (fewer searches), but a search prunes fewer voxels (docs/odometry.md, "Speed").
  static constexpr int kKept = 3;

  /// For `points` query slots, neighbours within max_distance_m (<= one voxel).
  NeighbourCache(const VoxelMap& map, double max_distance_m, std::size_t points);
  /// Forgets every answer and starts over for this map, distance and number of slots, keeping
  /// the memory (one cache serves scan after scan without allocating).
  void reset(const VoxelMap& map, double max_distance_m, std::size_t points);
  /// Nearest map point to q within the distance, for query slot i; false when none.
  bool nearest(std::size_t i, const Eigen::Vector3f& q, Eigen::Vector3f& out);
  /// The distance it answers for, and its number of query slots.
  [[nodiscard]] double max_distance_m() const { return max_distance_m_; }
  [[nodiscard]] std::size_t size() const { return slots_.size(); }
  /// Searches run so far (tests: they must be rarer than queries).
  [[nodiscard]] std::size_t searches() const { return searches_; }

 private:
  struct Slot {
    VoxelKey block{~VoxelKey{0}};
    int count{0};       // candidate voxels
    int kept{0};        // candidates kept, nearest first
    float bound{0.0F};  // distance from anchor to the nearest point not kept, less a margin
    Eigen::Vector3f anchor{Eigen::Vector3f::Zero()};  // where the last search ran
    std::array<Eigen::Vector3f, kKept> points{};      // the kept candidates
    std::array<const VoxelMap::Voxel*, 27> voxels{};
  };
  void search(Slot& slot, const Eigen::Vector3f& q);

  const VoxelMap* map_;
  std::vector<float> distance2_;  // scratch: squared distances to one voxel's points
  double max_distance_m_;
  float max2_, reach_;
  std::vector<Slot> slots_;
  std::size_t searches_{0};
};

}  // namespace ringtrack::odometry
