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
      max_points_(static_cast<std::size_t>(max_points_per_voxel)) {}

void VoxelMap::insert(const std::vector<Eigen::Vector3f>& points) {
  const auto size = static_cast<float>(voxel_size_m_);
  for (const auto& p : points) {
    auto& voxel = voxels_[voxel_key(p, inv_voxel_size_)];
    if (voxel.points.size() >= max_points_) continue;
    if (voxel.points.empty()) {
      voxel.points.reserve(max_points_);
      const Eigen::Vector3f q = p * inv_voxel_size_;
      voxel.corner = Eigen::Vector3f(std::floor(q.x()), std::floor(q.y()), std::floor(q.z())) * size;
    }
    voxel.points.push_back(p);
  }
}

void VoxelMap::crop(const Eigen::Vector3f& center, double radius_m) {
  const float r2 = static_cast<float>(radius_m * radius_m);
  std::erase_if(voxels_,
                [&](const auto& kv) { return (kv.second.points.front() - center).squaredNorm() > r2; });
}

const VoxelMap::Voxel* VoxelMap::find(int x, int y, int z) const {
  const auto it = voxels_.find(pack_voxel(x, y, z));
  return it == voxels_.end() ? nullptr : &it->second;
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

VoxelKey VoxelMap::block_key(const Eigen::Vector3f& p, double max_distance_m) const {
  const Eigen::Vector3f q = p * inv_voxel_size_;
  const float shift = max_distance_m <= 0.5 * voxel_size_m_ ? 0.5F : 0.0F;
  return pack_voxel(floor_to_int(q.x() - shift), floor_to_int(q.y() - shift),
                    floor_to_int(q.z() - shift));
}

bool VoxelMap::nearest(const Eigen::Vector3f& p, double max_distance_m,
                       Eigen::Vector3f& out) const {
  std::array<const Voxel*, 27> voxels{};
  const int n = candidates(p, max_distance_m, voxels);
  float best = static_cast<float>(max_distance_m * max_distance_m);
  bool found = false;
  for (int k = 0; k < n; ++k) {
    for (const auto& q : voxels[static_cast<std::size_t>(k)]->points) {
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
  for (const auto& [key, voxel] : voxels_) n += voxel.points.size();
  return n;
}

std::vector<Eigen::Vector3f> VoxelMap::points() const {
  std::vector<Eigen::Vector3f> out;
  out.reserve(point_count());
  for (const auto& [key, voxel] : voxels_) {
    out.insert(out.end(), voxel.points.begin(), voxel.points.end());
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
    : map_(&map),
      max_distance_m_(max_distance_m),
      max2_(static_cast<float>(max_distance_m * max_distance_m)),
      reach_(kReachFactor * static_cast<float>(max_distance_m)),
      slots_(points) {}

bool NeighbourCache::nearest(std::size_t i, const Eigen::Vector3f& q, Eigen::Vector3f& out) {
  Slot& slot = slots_[i];
  const VoxelKey block = map_->block_key(q, max_distance_m_);
  if (block != slot.block) {
    slot.block = block;
    slot.count = map_->candidates(q, max_distance_m_, slot.voxels);
    search(slot, q);
  } else if (!((q - slot.anchor).squaredNorm() < slot.slack2)) {
    search(slot, q);
  }
  // The nearest candidate is still slot.nearest; it counts when within the distance.
  if (!slot.found || (slot.nearest - q).squaredNorm() > max2_) return false;
  out = slot.nearest;
  return true;
}

void NeighbourCache::search(Slot& slot, const Eigen::Vector3f& q) {
  ++searches_;
  // The two nearest candidates within reach_ (ties go to the first). Voxels are visited nearest
  // first, so that the runner-up bound soon skips the rest: no point in a voxel farther than it
  // can change the answer.
  std::array<std::pair<float, const VoxelMap::Voxel*>, 27> order;
  const auto n = static_cast<std::size_t>(slot.count);
  for (std::size_t k = 0; k < n; ++k) {
    order[k] = {map_->cube_distance2(*slot.voxels[k], q), slot.voxels[k]};
  }
  std::sort(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(n),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  float best = reach_ * reach_, second = best;
  bool found = false;
  for (std::size_t k = 0; k < n && order[k].first <= second; ++k) {
    for (const auto& m : order[k].second->points) {
      const float d2 = (m - q).squaredNorm();
      if (d2 < best) {
        second = best;
        best = d2;
        slot.nearest = m;
        found = true;
      } else if (d2 < second) {
        second = d2;
      }
    }
  }
  slot.anchor = q;
  const float d1 = std::sqrt(best), d2 = std::sqrt(second);
  // Found: the nearest stays nearest while q moves less than half the gap to the runner-up (or
  // to the reach, beyond which no candidate was looked at). None within reach: nothing comes
  // within the distance while q moves less than reach - distance.
  const float slack = found ? 0.5F * (d2 - d1) - kSlackMarginM
                            : d1 - static_cast<float>(max_distance_m_) - kSlackMarginM;
  slot.slack2 = slack > 0 ? slack * slack : -1.0F;
  slot.found = found;
}

}  // namespace ringtrack::odometry
