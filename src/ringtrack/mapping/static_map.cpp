#include "ringtrack/mapping/static_map.hpp"

#include <algorithm>
#include <cmath>

namespace ringtrack::mapping {
namespace {

constexpr int kAxisBits = 21;
constexpr std::int64_t kAxisOffset = std::int64_t{1} << (kAxisBits - 1);
constexpr int kInitialBits = 10;

std::uint64_t pack(std::int64_t ix, std::int64_t iy, std::int64_t iz) {
  return (static_cast<std::uint64_t>(ix + kAxisOffset) << (2 * kAxisBits)) |
         (static_cast<std::uint64_t>(iy + kAxisOffset) << kAxisBits) |
         static_cast<std::uint64_t>(iz + kAxisOffset);
}

// floor() for |x| < 2^23 without a library call.
inline std::int64_t floor_to_int(float x) {
  const auto t = static_cast<std::int64_t>(x);
  return t - (static_cast<float>(t) > x ? 1 : 0);
}

// Voxel key of p scaled by 1 / voxel size; false for non-finite points and points beyond the
// +-2^20 voxel range (NaN fails every comparison, so it is rejected too).
inline bool voxel_key(const Eigen::Vector3f& p, float inverse_size, std::uint64_t& key) {
  const float x = p.x() * inverse_size, y = p.y() * inverse_size, z = p.z() * inverse_size;
  constexpr auto kLimit = static_cast<float>(kAxisOffset);
  if (!(std::abs(x) < kLimit && std::abs(y) < kLimit && std::abs(z) < kLimit)) return false;
  key = pack(floor_to_int(x), floor_to_int(y), floor_to_int(z));
  return true;
}

}  // namespace

StaticMap::StaticMap(double voxel_size_m)
    : voxel_size_m_(voxel_size_m), inverse_size_(static_cast<float>(1.0 / voxel_size_m)) {
  clear();
}

void StaticMap::clear() {
  bits_ = kInitialBits;
  slots_.assign(std::size_t{1} << bits_, Slot{});
  size_ = 0;
  last_key_ = kEmpty;
  ++generation_;
}

std::size_t StaticMap::home(std::uint64_t key) const {
  // Fibonacci hashing: the top bits of the product mix all three packed axes.
  return static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ull) >> (64 - bits_));
}

std::size_t StaticMap::find(std::uint64_t key) const {
  const std::size_t mask = slots_.size() - 1;
  for (std::size_t i = home(key);; i = (i + 1) & mask) {
    if (slots_[i].key == key) return i;
    if (slots_[i].key == kEmpty) return slots_.size();
  }
}

void StaticMap::grow() {
  std::vector<Slot> old = std::move(slots_);
  ++bits_;
  slots_.assign(std::size_t{1} << bits_, Slot{});
  const std::size_t mask = slots_.size() - 1;
  for (const auto& s : old) {
    if (s.key == kEmpty) continue;
    std::size_t i = home(s.key);
    while (slots_[i].key != kEmpty) i = (i + 1) & mask;
    slots_[i] = s;
  }
  last_key_ = kEmpty;
}

std::size_t StaticMap::find_or_claim(std::uint64_t key, std::size_t start) {
  const std::size_t mask = slots_.size() - 1;
  std::size_t i = start;
  while (slots_[i].key != key) {
    if (slots_[i].key == kEmpty) {
      slots_[i].key = key;
      slots_[i].point = MapPoint{};
      ++size_;
      break;
    }
    i = (i + 1) & mask;
  }
  return i;
}

void StaticMap::accumulate(std::size_t slot, const Eigen::Vector3f& p, float intensity) {
  MapPoint& m = slots_[slot].point;
  if (m.count >= kSettledCount) return;  // the mean is settled
  ++m.count;
  const float w = 1.0f / static_cast<float>(m.count);
  m.position += w * (p - m.position);
  m.intensity += w * (intensity - m.intensity);
}

void StaticMap::insert(const Eigen::Vector3f& p, float intensity) {
  std::uint64_t key = 0;
  if (!voxel_key(p, inverse_size_, key)) {
    ++dropped_;
    return;
  }
  if (key != last_key_) {
    if (2 * (size_ + 1) > slots_.size()) grow();  // keep the load at most 1/2
    last_slot_ = find_or_claim(key, home(key));
    last_key_ = key;
  }
  accumulate(last_slot_, p, intensity);
}

void StaticMap::insert(const std::vector<Eigen::Vector3f>& points,
                       const std::vector<float>& intensities,
                       const std::vector<std::uint8_t>& skip) {
  insert_batch(points, intensities, skip, nullptr, nullptr);
}

void StaticMap::insert(const std::vector<Eigen::Vector3f>& points,
                       const std::vector<float>& intensities, const std::vector<std::uint8_t>& skip,
                       const std::vector<std::uint32_t>& cells, SettledCells& settled) {
  std::uint32_t max_cell = 0;
  for (const auto c : cells) max_cell = std::max(max_cell, c);
  if (settled.generation != generation_ || settled.key.size() <= max_cell) {
    settled.key.assign(std::max<std::size_t>(settled.key.size(), std::size_t{max_cell} + 1),
                       kEmpty);
    settled.generation = generation_;
  }
  insert_batch(points, intensities, skip, &cells, &settled);
}

void StaticMap::insert_batch(const std::vector<Eigen::Vector3f>& points,
                             const std::vector<float>& intensities,
                             const std::vector<std::uint8_t>& skip,
                             const std::vector<std::uint32_t>* cells, SettledCells* settled) {
  // Chunks: room for a whole chunk is made first, so slots do not move inside one, and the
  // home slot of the point kPrefetch ahead is fetched while the current one is stored.
  constexpr std::size_t kChunk = 256;
  constexpr std::size_t kPrefetch = 8;
  std::uint64_t keys[kChunk];
  std::size_t homes[kChunk];
  std::uint32_t which[kChunk];
  for (std::size_t begin = 0; begin < points.size(); begin += kChunk) {
    const std::size_t end = std::min(points.size(), begin + kChunk);
    std::size_t n = 0;
    for (std::size_t i = begin; i < end; ++i) {
      if (!skip.empty() && skip[i]) continue;
      if (!voxel_key(points[i], inverse_size_, keys[n])) {
        ++dropped_;
        continue;
      }
      // A settled voxel ignores further points: nothing to do.
      if (settled != nullptr && settled->key[(*cells)[i]] == keys[n]) continue;
      which[n++] = static_cast<std::uint32_t>(i);
    }
    while (2 * (size_ + n) > slots_.size()) grow();
    for (std::size_t k = 0; k < n; ++k) homes[k] = home(keys[k]);
    for (std::size_t k = 0; k < n; ++k) {
      if (k + kPrefetch < n) __builtin_prefetch(&slots_[homes[k + kPrefetch]]);
      if (keys[k] != last_key_) {
        last_slot_ = find_or_claim(keys[k], homes[k]);
        last_key_ = keys[k];
      }
      accumulate(last_slot_, points[which[k]], intensities[which[k]]);
      if (settled != nullptr) {
        settled->key[(*cells)[which[k]]] =
            slots_[last_slot_].point.count >= kSettledCount ? keys[k] : kEmpty;
      }
    }
  }
}

void StaticMap::erase_slot(std::size_t i) {
  // Backward-shift deletion keeps every probe sequence unbroken without tombstones.
  const std::size_t mask = slots_.size() - 1;
  std::size_t hole = i;
  for (std::size_t j = (i + 1) & mask; slots_[j].key != kEmpty; j = (j + 1) & mask) {
    const std::size_t h = home(slots_[j].key);
    // Entry j may move into the hole when its home is not cyclically within (hole, j].
    const bool stays = hole <= j ? (hole < h && h <= j) : (hole < h || h <= j);
    if (!stays) {
      slots_[hole] = slots_[j];
      hole = j;
    }
  }
  slots_[hole] = Slot{};
  --size_;
  last_key_ = kEmpty;
  ++generation_;
}

std::size_t StaticMap::remove_inside(const core::Box3& box) {
  if (box.empty() || size_ == 0) return 0;
  std::vector<std::uint64_t> doomed;
  const Eigen::Vector3f lo = (box.min * inverse_size_).array().floor();
  const Eigen::Vector3f hi = (box.max * inverse_size_).array().floor();
  const Eigen::Vector3f span = (hi - lo).array() + 1.0f;
  const double cells = static_cast<double>(span.x()) * span.y() * span.z();
  const bool finite_range = lo.allFinite() && hi.allFinite() &&
                            (lo.array().abs() < static_cast<float>(kAxisOffset)).all() &&
                            (hi.array().abs() < static_cast<float>(kAxisOffset)).all();
  if (finite_range && cells <= static_cast<double>(slots_.size())) {
    // Small box: look up the voxels it covers.
    const auto x0 = static_cast<std::int64_t>(lo.x()), x1 = static_cast<std::int64_t>(hi.x());
    const auto y0 = static_cast<std::int64_t>(lo.y()), y1 = static_cast<std::int64_t>(hi.y());
    const auto z0 = static_cast<std::int64_t>(lo.z()), z1 = static_cast<std::int64_t>(hi.z());
    for (auto ix = x0; ix <= x1; ++ix) {
      for (auto iy = y0; iy <= y1; ++iy) {
        for (auto iz = z0; iz <= z1; ++iz) {
          const std::uint64_t key = pack(ix, iy, iz);
          const std::size_t i = find(key);
          if (i < slots_.size() && box.contains(slots_[i].point.position)) doomed.push_back(key);
        }
      }
    }
  } else {
    for (const auto& s : slots_) {
      if (s.key != kEmpty && box.contains(s.point.position)) doomed.push_back(s.key);
    }
  }
  for (const auto key : doomed) erase_slot(find(key));
  return doomed.size();
}

std::vector<MapPoint> StaticMap::points() const {
  std::vector<std::pair<std::uint64_t, MapPoint>> keyed;
  keyed.reserve(size_);
  for (const auto& s : slots_) {
    if (s.key != kEmpty) keyed.emplace_back(s.key, s.point);
  }
  std::sort(keyed.begin(), keyed.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<MapPoint> out;
  out.reserve(keyed.size());
  for (const auto& [key, point] : keyed) out.push_back(point);
  return out;
}

}  // namespace ringtrack::mapping
