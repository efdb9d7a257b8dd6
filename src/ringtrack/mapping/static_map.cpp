#include "ringtrack/mapping/static_map.hpp"

#include <algorithm>
#include <cmath>
#include <memory>

namespace ringtrack::mapping {
namespace {

constexpr int kAxisBits = 21;
constexpr std::int64_t kAxisOffset = std::int64_t{1} << (kAxisBits - 1);
constexpr int kInitialBits = 10;
constexpr int kChunkBits = 16;  // table storage in chunks of 2^16 slots (2 MiB)

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

// Incremental resize. New voxels go to table_ at load <= 1/2. From load 0.42 on, a table twice
// as large is allocated, kPrepareSlotsPerUnit slots per unit of insert work (a new voxel, or
// kPointsPerUnit points inserted, whichever is more), so it is complete before table_ reaches load
// 0.42 + 2/32 < 1/2. Then it becomes table_ (load < 1/4) and the old one drains into it,
// kDrainSlotsPerUnit slots per unit, done before the load grows by 1/64, long before the next
// resize starts. No call does more than a fixed multiple of its own work: the whole-table
// rehash that used to happen in one insert (hundreds of ms at millions of voxels) is spread
// over the scans that add the next few percent of the voxels. The cost that dominates is the
// first touch of the new memory (page faults, ~2 us per 4 KiB on the development VM), so the
// rates trade the share of scans that carry resize work (about a fifth while the map grows)
// against the work each of them does (32 slots, 1 KiB, per new voxel).
constexpr std::size_t kPrepareSlotsPerUnit = 32;
constexpr std::size_t kDrainSlotsPerUnit = 32;
constexpr std::size_t kPointsPerUnit = 4;
constexpr std::size_t kResizeLoadNum = 42;  // prepare from load 0.42 on
constexpr std::size_t kResizeLoadDen = 100;
constexpr std::size_t kChunk = 256;  // points per batch step (keys computed, slots prefetched)
constexpr std::size_t kPrefetch = 16;

}  // namespace

StaticMap::StaticMap(double voxel_size_m)
    : voxel_size_m_(voxel_size_m), inverse_size_(static_cast<float>(1.0 / voxel_size_m)) {
  clear();
}

StaticMap::Table StaticMap::make_table(int bits) {
  Table t;
  t.bits = bits;
  t.size = std::size_t{1} << bits;
  t.chunk_bits = std::min(bits, kChunkBits);
  t.chunks.resize(t.size >> t.chunk_bits);
  return t;
}

void StaticMap::allocate_chunks(Table& t, std::size_t slots) {
  t.ready = std::min(t.size, slots);
  const std::size_t chunk = std::size_t{1} << t.chunk_bits;
  const std::size_t needed = (t.ready + chunk - 1) / chunk;
  for (std::size_t c = 0; c < needed; ++c) {
    if (!t.chunks[c]) t.chunks[c] = std::make_unique<Slot[]>(chunk);  // all kEmpty
  }
}

void StaticMap::clear() {
  table_ = make_table(kInitialBits);
  allocate_chunks(table_, table_.size);
  old_ = Table{};
  next_ = Table{};
  phase_ = Phase::kIdle;
  drained_ = 0;
  size_ = 0;
  last_key_ = kEmpty;
  ++generation_;
}

std::size_t StaticMap::home(std::uint64_t key, int bits) {
  // Fibonacci hashing: the top bits of the product mix all three packed axes.
  return static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ull) >> (64 - bits));
}

std::size_t StaticMap::find(std::uint64_t key) const {
  const std::size_t mask = table_.size - 1;
  for (std::size_t i = home(key, table_.bits);; i = (i + 1) & mask) {
    if (table_[i].key == key) return i;
    if (table_[i].key == kEmpty) return table_.size;
  }
}

std::size_t StaticMap::find_old(std::uint64_t key) const {
  if (phase_ != Phase::kMoving) return old_.size;
  return find_old(key, home(key, old_.bits));
}

std::size_t StaticMap::find_old(std::uint64_t key, std::size_t old_home) const {
  // Slots below drained_ count as empty (their chunks are freed): a probe whose home lies there
  // resumes at drained_ (an entry past it sits in an unbroken run from its home), and one that
  // wraps around past the last slot ends.
  const std::size_t mask = old_.size - 1;
  for (std::size_t i = std::max(old_home, drained_); i >= drained_; i = (i + 1) & mask) {
    if (old_[i].key == key) return i;
    if (old_[i].key == kEmpty) break;
  }
  return old_.size;
}

void StaticMap::start_resize() {
  next_ = make_table(table_.bits + 1);
  phase_ = Phase::kPreparing;
}

void StaticMap::prepare(std::size_t slots) {
  allocate_chunks(next_, next_.ready + slots);
  if (next_.ready < next_.size) return;
  old_ = std::move(table_);
  table_ = std::move(next_);
  next_ = Table{};
  phase_ = Phase::kMoving;
  drained_ = 0;
  last_key_ = kEmpty;
}

void StaticMap::drain(std::size_t slots) {
  const std::size_t end = std::min(old_.size, drained_ + slots);
  last_key_ = kEmpty;  // its point may move
  const std::size_t mask = table_.size - 1;
  const std::size_t chunk = std::size_t{1} << old_.chunk_bits;
  // Blocks of old slots: the new homes of a block's voxels are fetched before they are stored.
  constexpr std::size_t kBlock = 64;
  std::size_t homes[kBlock] = {};
  for (std::size_t begin = drained_; begin < end; begin += kBlock) {
    const std::size_t stop = std::min(end, begin + kBlock);
    for (std::size_t i = begin; i < stop; ++i) {
      const std::uint64_t key = old_[i].key;
      if (!is_key(key)) continue;
      homes[i - begin] = home(key, table_.bits);
      __builtin_prefetch(&table_[homes[i - begin]]);
    }
    for (std::size_t i = begin; i < stop; ++i) {
      const Slot& s = old_[i];
      if (!is_key(s.key)) continue;
      // Not in table_: a voxel lives in one table only.
      std::size_t j = homes[i - begin];
      while (table_[j].key != kEmpty) j = (j + 1) & mask;
      table_[j] = s;
    }
  }
  // Chunks wholly drained are freed now, a piece of the old table at a time.
  for (std::size_t c = drained_ / chunk; c < end / chunk; ++c) old_.chunks[c].reset();
  drained_ = end;
  if (drained_ == old_.size) {
    old_ = Table{};
    drained_ = 0;
    phase_ = Phase::kIdle;
  }
}

void StaticMap::advance_resize(std::size_t units) {
  if (phase_ == Phase::kPreparing) {
    prepare(units * kPrepareSlotsPerUnit);
  } else if (phase_ == Phase::kMoving) {
    drain(units * kDrainSlotsPerUnit);
  }
}

void StaticMap::finish_resize() {
  if (phase_ == Phase::kPreparing) prepare(next_.size);
  if (phase_ == Phase::kMoving) drain(old_.size);
}

void StaticMap::make_room(std::size_t n) {
  // The hard limit (load <= 1/2) is reached only when voxels come faster than the pacing above
  // assumes (or in the first, small tables); the pending resize is then completed at once.
  while (2 * (size_ + n) > table_.size) {
    if (phase_ == Phase::kIdle) start_resize();
    finish_resize();
  }
  if (phase_ == Phase::kIdle && kResizeLoadDen * (size_ + n) > kResizeLoadNum * table_.size) {
    start_resize();
  }
}

std::size_t StaticMap::find_or_claim(std::uint64_t key, std::size_t start) {
  const std::size_t mask = table_.size - 1;
  std::size_t i = start;
  while (table_[i].key != key) {
    if (table_[i].key == kEmpty) {
      table_[i].key = key;
      table_[i].point = MapPoint{};
      ++size_;
      break;
    }
    i = (i + 1) & mask;
  }
  return i;
}

MapPoint& StaticMap::locate(std::uint64_t key, std::size_t home, std::size_t old_home) {
  // While the old table drains, a voxel not drained yet is updated where it is (one lookup in
  // one table, not a move per access); the drain moves it later. New voxels go to table_ only.
  if (phase_ == Phase::kMoving) {
    const std::size_t o = find_old(key, old_home);
    if (o < old_.size) return old_[o].point;
  }
  return table_[find_or_claim(key, home)].point;
}

void StaticMap::accumulate(MapPoint& m, const Eigen::Vector3f& p, float intensity) {
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
  if (key == last_key_) {
    accumulate(*last_point_, p, intensity);
    return;
  }
  make_room(1);
  const std::size_t before = size_;
  last_point_ =
      &locate(key, home(key, table_.bits), phase_ == Phase::kMoving ? home(key, old_.bits) : 0);
  last_key_ = key;
  accumulate(*last_point_, p, intensity);
  advance_resize(1 + size_ - before);  // may move voxels (and forget last_key_)
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
  std::uint64_t keys[kChunk];
  std::size_t homes[kChunk];
  std::size_t old_homes[kChunk];
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
    make_room(n);
    const std::size_t before = size_;
    const bool moving = phase_ == Phase::kMoving;
    for (std::size_t k = 0; k < n; ++k) {
      homes[k] = home(keys[k], table_.bits);
      old_homes[k] = moving ? home(keys[k], old_.bits) : 0;
    }
    // While the old table drains, a voxel whose home there is not drained yet is most likely
    // still there (and a new one goes to table_): fetch both.
    // (Written out: with these two prefetches in a lambda, g++ 12 dropped all of them.)
    for (std::size_t k = 0; k < n + kPrefetch; ++k) {
      if (k < n) {
        __builtin_prefetch(&table_[homes[k]]);
        if (moving && old_homes[k] >= drained_) __builtin_prefetch(&old_[old_homes[k]]);
      }
      if (k < kPrefetch) continue;
      const std::size_t j = k - kPrefetch;  // the point stored now
      if (keys[j] != last_key_) {
        last_point_ = &locate(keys[j], homes[j], old_homes[j]);
        last_key_ = keys[j];
      }
      accumulate(*last_point_, points[which[j]], intensities[which[j]]);
      if (settled != nullptr) {
        settled->key[(*cells)[which[j]]] = last_point_->count >= kSettledCount ? keys[j] : kEmpty;
      }
    }
    advance_resize(std::max(size_ - before, (end - begin) / kPointsPerUnit));
  }
}

void StaticMap::erase_slot(std::size_t i) {
  // Backward-shift deletion keeps every probe sequence unbroken without tombstones.
  const std::size_t mask = table_.size - 1;
  std::size_t hole = i;
  for (std::size_t j = (i + 1) & mask; table_[j].key != kEmpty; j = (j + 1) & mask) {
    const std::size_t h = home(table_[j].key, table_.bits);
    // Entry j may move into the hole when its home is not cyclically within (hole, j].
    const bool stays = hole <= j ? (hole < h && h <= j) : (hole < h || h <= j);
    if (!stays) {
      table_[hole] = table_[j];
      hole = j;
    }
  }
  table_[hole] = Slot{};
}

void StaticMap::erase(std::uint64_t key) {
  const std::size_t i = find(key);
  if (i < table_.size) {
    erase_slot(i);
  } else {
    // Still in the draining table: a tombstone keeps the probes past it unbroken.
    old_[find_old(key)].key = kGone;
  }
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
  if (finite_range && cells <= static_cast<double>(table_.size)) {
    // Small box: look up the voxels it covers, a chunk of keys at a time with the home slots
    // fetched ahead (a box of 10^5 voxels costs 10^5 lookups, mostly misses in a large table).
    std::uint64_t keys[kChunk];
    std::size_t homes[kChunk];
    std::size_t n = 0;
    const auto lookup = [&] {
      for (std::size_t k = 0; k < n; ++k) homes[k] = home(keys[k], table_.bits);
      for (std::size_t k = 0; k < std::min(n, kPrefetch); ++k)
        __builtin_prefetch(&table_[homes[k]]);
      const std::size_t mask = table_.size - 1;
      for (std::size_t k = 0; k < n; ++k) {
        if (k + kPrefetch < n) __builtin_prefetch(&table_[homes[k + kPrefetch]]);
        std::size_t i = homes[k];
        while (table_[i].key != keys[k] && table_[i].key != kEmpty) i = (i + 1) & mask;
        const MapPoint* p = nullptr;
        if (table_[i].key == keys[k]) {
          p = &table_[i].point;
        } else if (const std::size_t o = find_old(keys[k]); o < old_.size) {
          p = &old_[o].point;
        }
        if (p != nullptr && box.contains(p->position)) doomed.push_back(keys[k]);
      }
      n = 0;
    };
    const auto x0 = static_cast<std::int64_t>(lo.x()), x1 = static_cast<std::int64_t>(hi.x());
    const auto y0 = static_cast<std::int64_t>(lo.y()), y1 = static_cast<std::int64_t>(hi.y());
    const auto z0 = static_cast<std::int64_t>(lo.z()), z1 = static_cast<std::int64_t>(hi.z());
    for (auto ix = x0; ix <= x1; ++ix) {
      for (auto iy = y0; iy <= y1; ++iy) {
        for (auto iz = z0; iz <= z1; ++iz) {
          keys[n++] = pack(ix, iy, iz);
          if (n == kChunk) lookup();
        }
      }
    }
    lookup();
  } else {
    const auto check = [&](const Slot& s) {
      if (is_key(s.key) && box.contains(s.point.position)) doomed.push_back(s.key);
    };
    for (std::size_t i = 0; i < table_.size; ++i) check(table_[i]);
    for (std::size_t i = drained_; i < old_.size; ++i) check(old_[i]);
  }
  for (const auto key : doomed) erase(key);
  return doomed.size();
}

std::vector<MapPoint> StaticMap::points() const {
  std::vector<std::pair<std::uint64_t, MapPoint>> keyed;
  keyed.reserve(size_);
  const auto take = [&](const Slot& s) {
    if (is_key(s.key)) keyed.emplace_back(s.key, s.point);
  };
  for (std::size_t i = 0; i < table_.size; ++i) take(table_[i]);
  for (std::size_t i = drained_; i < old_.size; ++i) take(old_[i]);
  std::sort(keyed.begin(), keyed.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<MapPoint> out;
  out.reserve(keyed.size());
  for (const auto& [key, point] : keyed) out.push_back(point);
  return out;
}

}  // namespace ringtrack::mapping
