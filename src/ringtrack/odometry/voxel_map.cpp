#include "ringtrack/odometry/voxel_map.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace ringtrack::odometry {
namespace {

constexpr int kAxisBits = 21;
constexpr int kAxisOffset = 1 << (kAxisBits - 1);
constexpr VoxelKey kAxisMask = (VoxelKey{1} << kAxisBits) - 1;

int floor_int(float v) {
  return static_cast<int>(std::floor(v));
}

}  // namespace

VoxelKey pack_voxel(int x, int y, int z) {
  // Coordinates beyond +-2^20 voxels wrap: points that far apart never meet in one scan's search.
  const auto ux = static_cast<VoxelKey>(x + kAxisOffset) & kAxisMask;
  const auto uy = static_cast<VoxelKey>(y + kAxisOffset) & kAxisMask;
  const auto uz = static_cast<VoxelKey>(z + kAxisOffset) & kAxisMask;
  return ux | (uy << kAxisBits) | (uz << (2 * kAxisBits));
}

VoxelKey voxel_key(const Eigen::Vector3f& p, float inv_voxel_size) {
  return pack_voxel(floor_int(p.x() * inv_voxel_size), floor_int(p.y() * inv_voxel_size),
                    floor_int(p.z() * inv_voxel_size));
}

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
    const int x0 = floor_int(q.x() - 0.5F), y0 = floor_int(q.y() - 0.5F),
              z0 = floor_int(q.z() - 0.5F);
    for (int dx = 0; dx <= 1; ++dx)
      for (int dy = 0; dy <= 1; ++dy)
        for (int dz = 0; dz <= 1; ++dz)
          if (const Voxel* v = find(x0 + dx, y0 + dy, z0 + dz)) out[n++] = v;
    return n;
  }
  const int x0 = floor_int(q.x()), y0 = floor_int(q.y()), z0 = floor_int(q.z());
  for (int dx = -1; dx <= 1; ++dx)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dz = -1; dz <= 1; ++dz)
        if (const Voxel* v = find(x0 + dx, y0 + dy, z0 + dz)) out[n++] = v;
  return n;
}

VoxelKey VoxelMap::block_key(const Eigen::Vector3f& p, double max_distance_m) const {
  const Eigen::Vector3f q = p * inv_voxel_size_;
  const float shift = max_distance_m <= 0.5 * voxel_size_m_ ? 0.5F : 0.0F;
  return pack_voxel(floor_int(q.x() - shift), floor_int(q.y() - shift), floor_int(q.z() - shift));
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

}  // namespace ringtrack::odometry
