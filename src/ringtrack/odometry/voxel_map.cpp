#include "ringtrack/odometry/voxel_map.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace ringtrack::odometry {
void VoxelKeySet::clear(std::size_t n) {
  std::size_t capacity = 16;
  while (capacity < 2 * n) capacity *= 2;
  if (slots_.size() != capacity) {
    slots_.assign(capacity, kEmpty);
  } else {
    std::fill(slots_.begin(), slots_.end(), kEmpty);
  }
  mask_ = capacity - 1;
  size_ = 0;
}

bool VoxelKeySet::insert(VoxelKey key) {
  if (2 * (size_ + 1) > slots_.size()) grow();
  const VoxelKey h = key * 0x9e3779b97f4a7c15ULL;
  std::size_t i = static_cast<std::size_t>(h >> 20U) & mask_;
  while (true) {
    if (slots_[i] == key) return false;
    if (slots_[i] == kEmpty) {
      slots_[i] = key;
      ++size_;
      return true;
    }
    i = (i + 1) & mask_;
  }
}

void VoxelKeySet::grow() {
  std::vector<VoxelKey> old;
  old.swap(slots_);
  slots_.assign(std::max<std::size_t>(16, 2 * old.size()), kEmpty);
  mask_ = slots_.size() - 1;
  size_ = 0;
  for (const VoxelKey k : old) {
    if (k != kEmpty) insert(k);
  }
}

VoxelMap::VoxelMap(double voxel_size_m, int max_points_per_voxel)
    : voxel_size_m_(voxel_size_m),
      inv_voxel_size_(static_cast<float>(1.0 / voxel_size_m)),
      edge_(Eigen::Vector3f::Constant(static_cast<float>(voxel_size_m))),
      max_points_(static_cast<std::size_t>(max_points_per_voxel)),
      table_(kMinTableSlots) {}

void VoxelMap::insert(const std::vector<Eigen::Vector3f>& points) {
  const auto size = static_cast<float>(voxel_size_m_);
  // Consecutive points (neighbours on a ring) mostly share a voxel: its index is kept instead of
  // asking the table again (indices stay valid while voxels are only added).
  VoxelKey last_key = kEmptyKey;
  std::size_t last_index = 0;
  for (const auto& p : points) {
    const VoxelKey key = voxel_key(p, inv_voxel_size_);
    if (key != last_key) {
      last_index = static_cast<std::size_t>(&find_or_add(key) - voxels_.data());
      last_key = key;
    }
    auto& voxel = voxels_[last_index];
    if (voxel.size() >= max_points_) continue;
    if (voxel.size() == 0) {
      voxel.x.reserve(max_points_);
      voxel.y.reserve(max_points_);
      voxel.z.reserve(max_points_);
      const Eigen::Vector3f q = p * inv_voxel_size_;
      voxel.corner =
          Eigen::Vector3f(std::floor(q.x()), std::floor(q.y()), std::floor(q.z())) * size;
    }
    voxel.x.push_back(p.x());
    voxel.y.push_back(p.y());
    voxel.z.push_back(p.z());
  }
}

void VoxelMap::crop(const Eigen::Vector3f& center, double radius_m) {
  const float r2 = static_cast<float>(radius_m * radius_m);
  const std::size_t before = voxels_.size();
  std::erase_if(voxels_, [&](const Voxel& v) { return (v.point(0) - center).squaredNorm() > r2; });
  // Open addressing cannot simply drop a slot (later keys of its probe run would be lost), and
  // a crop runs only after the sensor moved 5 % of the map radius: rebuilding is the simple way.
  if (voxels_.size() != before) rebuild_table(voxels_.size());
}

void VoxelMap::clear() {
  voxels_.clear();
  rebuild_table(0);
}

const VoxelMap::Voxel* VoxelMap::find(VoxelKey key) const {
  const std::size_t mask = table_.size() - 1;
  for (std::size_t i = home_slot(key);; i = (i + 1) & mask) {
    const Slot& slot = table_[i];
    if (slot.key == key) return &voxels_[slot.index];
    if (slot.key == kEmptyKey) return nullptr;
  }
}

VoxelMap::Voxel& VoxelMap::find_or_add(VoxelKey key) {
  if (2 * (voxels_.size() + 1) > table_.size()) rebuild_table(voxels_.size() + 1);
  const std::size_t mask = table_.size() - 1;
  for (std::size_t i = home_slot(key);; i = (i + 1) & mask) {
    Slot& slot = table_[i];
    if (slot.key == key) return voxels_[slot.index];
    if (slot.key == kEmptyKey) {
      slot = {key, static_cast<std::uint32_t>(voxels_.size())};
      Voxel& voxel = voxels_.emplace_back();
      voxel.key = key;
      return voxel;
    }
  }
}

void VoxelMap::rebuild_table(std::size_t voxels) {
  std::size_t slots = kMinTableSlots;
  while (slots < 2 * voxels) slots *= 2;
  table_.assign(slots, Slot{});
  const std::size_t mask = slots - 1;
  for (std::size_t v = 0; v < voxels_.size(); ++v) {
    std::size_t i = home_slot(voxels_[v].key);
    while (table_[i].key != kEmptyKey) i = (i + 1) & mask;
    table_[i] = {voxels_[v].key, static_cast<std::uint32_t>(v)};
  }
}

int VoxelMap::candidates(const Eigen::Vector3f& p, double max_distance_m,
                         std::array<const Voxel*, 27>& out) const {
  const Eigen::Vector3f q = p * inv_voxel_size_;
  int n = 0;
  if (max_distance_m <= 0.5 * voxel_size_m_) {
    // The cube p +- half a voxel lies in the 2x2x2 block starting at floor(q - 0.5).
    const int x0 = floor_to_int(q.x() - 0.5F), y0 = floor_to_int(q.y() - 0.5F),
              z0 = floor_to_int(q.z() - 0.5F);
    for (int dx = 0; dx <= 1; ++dx)
      for (int dy = 0; dy <= 1; ++dy)
        for (int dz = 0; dz <= 1; ++dz)
          if (const Voxel* v = find(x0 + dx, y0 + dy, z0 + dz)) out[n++] = v;
    return n;
  }
  const int x0 = floor_to_int(q.x()), y0 = floor_to_int(q.y()), z0 = floor_to_int(q.z());
  for (int dx = -1; dx <= 1; ++dx)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dz = -1; dz <= 1; ++dz)
        if (const Voxel* v = find(x0 + dx, y0 + dy, z0 + dz)) out[n++] = v;
  return n;
}

bool VoxelMap::nearest(const Eigen::Vector3f& p, double max_distance_m,
                       Eigen::Vector3f& out) const {
  std::array<const Voxel*, 27> voxels{};
  const int n = candidates(p, max_distance_m, voxels);
  float best = static_cast<float>(max_distance_m * max_distance_m);
  bool found = false;
  for (int k = 0; k < n; ++k) {
    const Voxel& voxel = *voxels[static_cast<std::size_t>(k)];
    for (std::size_t j = 0; j < voxel.size(); ++j) {
      const Eigen::Vector3f q = voxel.point(j);
      const float d2 = (q - p).squaredNorm();
      if (d2 <= best) {
        best = d2;
        out = q;
        found = true;
      }
    }
  }
  return found;
}

std::size_t VoxelMap::point_count() const {
  std::size_t n = 0;
  for (const auto& voxel : voxels_) n += voxel.size();
  return n;
}

std::vector<Eigen::Vector3f> VoxelMap::points() const {
  std::vector<Eigen::Vector3f> out;
  out.reserve(point_count());
  for (const auto& voxel : voxels_) {
    for (std::size_t j = 0; j < voxel.size(); ++j) out.push_back(voxel.point(j));
  }
  return out;
}

namespace {
// A search also looks this far beyond the correspondence distance: a point with no neighbour
// then knows how far it may move before one could come within reach.
constexpr float kReachFactor = 1.2F;
// Float rounding of the distances (metres at most, relative error ~1e-7): the gap is trimmed by
// this so that a reused answer is the one a search would give.
constexpr float kSlackMarginM = 1e-5F;
}  // namespace

NeighbourCache::NeighbourCache(const VoxelMap& map, double max_distance_m, std::size_t points)
    : map_(&map), max_distance_m_(0.0), max2_(0.0F), reach_(0.0F) {
  reset(map, max_distance_m, points);
}

void NeighbourCache::reset(const VoxelMap& map, double max_distance_m, std::size_t points) {
  map_ = &map;
  distance2_.resize(map.max_points_per_voxel());
  max_distance_m_ = max_distance_m;
  max2_ = static_cast<float>(max_distance_m * max_distance_m);
  reach_ = kReachFactor * static_cast<float>(max_distance_m);
  slots_.resize(points);
  // An invalid block makes the first query of every slot search; nothing else is read before.
  for (auto& slot : slots_) slot.block = ~VoxelKey{0};
  searches_ = 0;
}

bool NeighbourCache::nearest(std::size_t i, const Eigen::Vector3f& q, Eigen::Vector3f& out) {
  Slot& slot = slots_[i];
  const VoxelKey block = map_->block_key(q, max_distance_m_);
  if (block != slot.block) {
    slot.block = block;
    slot.count = map_->candidates(q, max_distance_m_, slot.voxels);
    search(slot, q);
  } else {
    // The kept candidates' distances now (summed as VoxelMap::nearest sums them, so that the
    // answer is its answer bit for bit); ties go to the first, nearest at the search.
    float best2 = std::numeric_limits<float>::infinity();
    int best = -1;
    for (int k = 0; k < slot.kept; ++k) {
      const float d2 = (slot.points[static_cast<std::size_t>(k)] - q).squaredNorm();
      if (d2 < best2) {
        best2 = d2;
        best = k;
      }
    }
    // Every point not kept is at least this far from q now.
    const float others = slot.bound - (q - slot.anchor).norm();
    const bool settled = best >= 0 && others > 0 && best2 < others * others;
    const bool none = others > static_cast<float>(max_distance_m_) && !(best2 <= max2_);
    if (settled || none) {
      if (best < 0 || best2 > max2_) return false;
      out = slot.points[static_cast<std::size_t>(best)];
      return true;
    }
    search(slot, q);
  }
  // The kept candidates are sorted: the first is the nearest; it counts when within the distance.
  if (slot.kept == 0 || (slot.points[0] - q).squaredNorm() > max2_) return false;
  out = slot.points[0];
  return true;
}

void NeighbourCache::search(Slot& slot, const Eigen::Vector3f& q) {
  ++searches_;
  // The kKept + 1 nearest candidates within reach_ (ties go to the first). Voxels are visited
  // nearest first, so that the last kept distance soon skips the rest: no point in a voxel
  // farther than it can change what is kept or the bound.
  std::array<std::pair<float, const VoxelMap::Voxel*>, 27> order;
  const auto n = static_cast<std::size_t>(slot.count);
  for (std::size_t k = 0; k < n; ++k) {
    order[k] = {map_->cube_distance2(*slot.voxels[k], q), slot.voxels[k]};
  }
  std::sort(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(n),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  constexpr int kTop = kKept + 1;
  std::array<float, kTop> top2;
  std::array<Eigen::Vector3f, kTop> top;
  top2.fill(reach_ * reach_);
  int found = 0;
  float* __restrict dist2 = distance2_.data();
  const float qx = q.x(), qy = q.y(), qz = q.z();
  for (std::size_t k = 0; k < n && order[k].first <= top2[kTop - 1]; ++k) {
    const VoxelMap::Voxel& voxel = *order[k].second;
    const std::size_t m = voxel.size();
    const float* __restrict xs = voxel.x.data();
    const float* __restrict ys = voxel.y.data();
    const float* __restrict zs = voxel.z.data();
    // The distances first, in a loop without branches (vectorised), then the smallest.
    // Summed as Eigen's squaredNorm() of a 3-vector sums, x + (y + z), so that the answer is
    // bit for bit VoxelMap::nearest's.
    for (std::size_t j = 0; j < m; ++j) {
      const float dx = xs[j] - qx, dy = ys[j] - qy, dz = zs[j] - qz;
      dist2[j] = dx * dx + (dy * dy + dz * dz);
    }
    for (std::size_t j = 0; j < m; ++j) {
      const float d2 = dist2[j];
      if (!(d2 < top2[kTop - 1])) continue;
      // Insertion into the sorted list: a tie stays behind the earlier point.
      int pos = kTop - 1;
      while (pos > 0 && d2 < top2[static_cast<std::size_t>(pos - 1)]) {
        top2[static_cast<std::size_t>(pos)] = top2[static_cast<std::size_t>(pos - 1)];
        top[static_cast<std::size_t>(pos)] = top[static_cast<std::size_t>(pos - 1)];
        --pos;
      }
      top2[static_cast<std::size_t>(pos)] = d2;
      top[static_cast<std::size_t>(pos)] = voxel.point(j);
      found = std::min(found + 1, kTop);
    }
  }
  slot.kept = std::min(found, kKept);
  for (int k = 0; k < slot.kept; ++k) {
    slot.points[static_cast<std::size_t>(k)] = top[static_cast<std::size_t>(k)];
  }
  slot.anchor = q;
  // The nearest point not kept: the (kKept + 1)-th, or none within reach. Trimmed by the float
  // rounding of the distances, so that a reused answer is the one a search would give.
  slot.bound = std::sqrt(top2[kTop - 1]) - kSlackMarginM;
}

}  // namespace ringtrack::odometry
