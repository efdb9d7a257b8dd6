#include "ringtrack/mapping/static_map.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <memory>
#include <new>
#include <stdexcept>
#include <type_traits>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace ringtrack::mapping {
namespace {

constexpr int kAxisBits = 21;
constexpr std::int64_t kAxisOffset = std::int64_t{1} << (kAxisBits - 1);
constexpr std::uint64_t kNoKey = ~std::uint64_t{0};  // no voxel (SettledCells, last_key_)
constexpr int kInitialBits = 10;
constexpr int kChunkBits = 18;  // table storage in chunks of 2^18 slots (2 MiB)
constexpr int kMaxBits = 32;    // fingerprints give the home slots of tables up to 2^32 slots
constexpr std::align_val_t kBlockAlign{64};
constexpr std::size_t kSpareBytes = std::size_t{2} << 20;  // table chunks and voxel blocks

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

#if defined(__SSE2__)
// voxel_key() for the three axes at once (the batch insert computes a key for every point):
// the same products, range test and floor, in 32-bit lanes (|x| < 2^20 fits), bit for bit
// (StaticMap.BatchKeysMatchTheScalarKeys).
struct KeyLanes {
  __m128 scale;
  __m128 sign = _mm_set1_ps(-0.0f);
  __m128 limit = _mm_set1_ps(static_cast<float>(kAxisOffset));
  __m128i offset = _mm_set1_epi32(static_cast<int>(kAxisOffset));
  explicit KeyLanes(float inverse_size) : scale(_mm_set1_ps(inverse_size)) {}
};
[[gnu::always_inline]] inline bool voxel_key(const Eigen::Vector3f& p, const KeyLanes& lanes,
                                             std::uint64_t& key) {
  const float* f = p.data();
  // x, y, z, 0 (no read past the point). x and y as one 8-byte load: memcpy, since the point
  // is only 4-byte aligned (a double* load of it is undefined; UBSan's misaligned load).
  double xy_pair = 0.0;
  std::memcpy(&xy_pair, f, sizeof(xy_pair));
  const __m128 xy = _mm_castpd_ps(_mm_set_sd(xy_pair));
  const __m128 v = _mm_mul_ps(_mm_movelh_ps(xy, _mm_load_ss(f + 2)), lanes.scale);
  const __m128 inside = _mm_cmplt_ps(_mm_andnot_ps(lanes.sign, v), lanes.limit);
  if ((_mm_movemask_ps(inside) & 7) != 7) return false;
  const __m128i t = _mm_cvttps_epi32(v);
  // floor: truncation, minus one where it rounded up (a negative fraction).
  const __m128i below = _mm_castps_si128(_mm_cmpgt_ps(_mm_cvtepi32_ps(t), v));
  const __m128i u = _mm_add_epi32(_mm_add_epi32(t, below), lanes.offset);
  const auto xy_bits = static_cast<std::uint64_t>(_mm_cvtsi128_si64(u));
  const auto z_bits = static_cast<std::uint32_t>(_mm_cvtsi128_si32(_mm_unpackhi_epi64(u, u)));
  key = ((xy_bits & 0xFFFFFFFFu) << (2 * kAxisBits)) | ((xy_bits >> 32) << kAxisBits) | z_bits;
  return true;
}
#else
struct KeyLanes {
  float scale;
  explicit KeyLanes(float inverse_size) : scale(inverse_size) {}
};
inline bool voxel_key(const Eigen::Vector3f& p, const KeyLanes& lanes, std::uint64_t& key) {
  return voxel_key(p, lanes.scale, key);
}
#endif

// Fibonacci hashing: the top bits of the product mix all three packed axes. Its top 32 bits are
// the fingerprint a slot keeps, and the top bits of those the home slot in a table of 2^bits.
inline std::uint32_t fingerprint(std::uint64_t key) {
  return static_cast<std::uint32_t>((key * 0x9E3779B97F4A7C15ull) >> 32);
}
inline std::size_t home(std::uint32_t fp, int bits) {
  return fp >> (32 - bits);
}

inline std::uint64_t make_slot(std::uint32_t fp, std::size_t index) {
  return (std::uint64_t{fp} << 32) | (index + 1);
}
inline std::uint32_t slot_fp(std::uint64_t s) {
  return static_cast<std::uint32_t>(s >> 32);
}
inline bool is_voxel(std::uint64_t s) {
  return (s & 0xFFFFFFFFu) != 0;
}
inline std::size_t slot_index(std::uint64_t s) {
  return (s & 0xFFFFFFFFu) - 1;
}

// Incremental resize. New voxels go to table_ at load <= 0.7 (the fingerprints keep the longer
// probes cheap: 8 slots per cache line, the voxel read only on a matching fingerprint). From
// load 0.52 on, a table twice as large is prepared, kPrepareSlotsPerUnit slots per unit of insert
// work (a new voxel, or kPointsPerUnit points inserted, whichever is more), so it is complete
// when table_ reaches load 0.52 + 2/20 = 0.62 < 0.7. Then it becomes table_ (load 0.31) and the
// old one drains into it, kDrainSlotsPerUnit slots per unit, done at load 0.31 + 1/64, long
// before the next resize starts. No call does more than a fixed multiple of its own work. The
// cost that dominates is the first touch of the new memory (page faults, 3-17 us per 4 KiB on
// the development VM; 160 bytes of new table per new voxel while preparing), so the rates trade
// the share of the growing scans that carry resize work (about a third of a doubling cycle)
// against the work each of them does: spread over every growing scan, the median scan pays it;
// packed into a few, the tail does. The voxels themselves mostly reuse drained tables' memory.
constexpr std::size_t kPrepareSlotsPerUnit = 20;
constexpr std::size_t kDrainSlotsPerUnit = 32;
constexpr std::size_t kPointsPerUnit = 32;
constexpr std::size_t kResizeLoadNum = 52;  // prepare from load 0.52 on
constexpr std::size_t kMaxLoadNum = 70;     // load <= 0.7
constexpr std::size_t kLoadDen = 100;
// 1 / n for the counts a voxel averages: the same correctly rounded quotients the division
// gives, read instead of computed (a division per point is the insert's longest latency).
constexpr auto kReciprocal = [] {
  std::array<float, StaticMap::kSettledCount + 1> r{};
  for (std::size_t n = 1; n < r.size(); ++n) r[n] = 1.0f / static_cast<float>(n);
  return r;
}();
constexpr std::size_t kChunk = 256;  // points per batch step (keys computed, slots prefetched)
constexpr std::size_t kPrefetch = 16;

}  // namespace

void StaticMap::RawDelete::operator()(void* p) const {
  ::operator delete(p, kBlockAlign);
}

template <class T>
StaticMap::Block<T> StaticMap::take_block(std::size_t n) {
  // Uninitialized: new memory is first written, and its pages faulted in, where it is used.
  static_assert(std::is_trivially_destructible_v<T>);
  if (n * sizeof(T) == kSpareBytes && !spares_.empty()) {
    Block<T> block(reinterpret_cast<T*>(spares_.back().release()));
    spares_.pop_back();
    return block;
  }
  return Block<T>(static_cast<T*>(::operator new(n * sizeof(T), kBlockAlign)));
}

template <class T>
void StaticMap::give_block(Block<T> block, std::size_t n) {
  if (n * sizeof(T) == kSpareBytes) {
    spares_.emplace_back(reinterpret_cast<std::byte*>(block.release()));
  }
}

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

void StaticMap::prepare_slots(Table& t, std::size_t slots) {
  const std::size_t target = std::min(t.size, slots);
  const std::size_t chunk = std::size_t{1} << t.chunk_bits;
  while (t.ready < target) {
    const std::size_t c = t.ready >> t.chunk_bits;
    if (!t.chunks[c]) t.chunks[c] = take_block<Slot>(chunk);
    const std::size_t stop = std::min(target, (c + 1) * chunk);
    Slot* first = &t[t.ready];
    std::uninitialized_fill(first, first + (stop - t.ready), kFree);
    t.ready = stop;
  }
}

void StaticMap::clear() {
  blocks_.clear();
  spares_.clear();
  table_ = make_table(kInitialBits);
  prepare_slots(table_, table_.size);
  old_ = Table{};
  next_ = Table{};
  phase_ = Phase::kIdle;
  drained_ = 0;
  size_ = 0;
  last_key_ = kNoKey;
  ++generation_;
}

// Inlined: these three run for every point the map takes (insert_batch).
[[gnu::always_inline]] inline bool StaticMap::holds(Slot s, std::uint32_t fp,
                                                    std::uint64_t key) const {
  return slot_fp(s) == fp && is_voxel(s) && voxel(slot_index(s)).key == key;
}

std::size_t StaticMap::find(std::uint64_t key) const {
  const std::uint32_t fp = fingerprint(key);
  const std::size_t mask = table_.size - 1;
  for (std::size_t i = home(fp, table_.bits);; i = (i + 1) & mask) {
    if (table_[i] == kFree) return table_.size;
    if (holds(table_[i], fp, key)) return i;
  }
}

std::size_t StaticMap::find_old(std::uint64_t key) const {
  if (phase_ != Phase::kMoving) return old_.size;
  return find_old(key, fingerprint(key));
}

std::size_t StaticMap::find_old(std::uint64_t key, std::uint32_t fp) const {
  // Slots below drained_ count as free (their chunks are freed): a probe whose home lies there
  // resumes at drained_ (an entry past it sits in an unbroken run from its home), and one that
  // wraps around past the last slot ends.
  const std::size_t mask = old_.size - 1;
  for (std::size_t i = std::max(home(fp, old_.bits), drained_); i >= drained_; i = (i + 1) & mask) {
    if (old_[i] == kFree) break;
    if (holds(old_[i], fp, key)) return i;
  }
  return old_.size;
}

void StaticMap::start_resize() {
  if (table_.bits >= kMaxBits) throw std::length_error("mapping: static map full (2^31 voxels)");
  next_ = make_table(table_.bits + 1);
  phase_ = Phase::kPreparing;
}

void StaticMap::prepare(std::size_t slots) {
  prepare_slots(next_, next_.ready + slots);
  if (next_.ready < next_.size) return;
  old_ = std::move(table_);
  table_ = std::move(next_);
  next_ = Table{};
  phase_ = Phase::kMoving;
  drained_ = 0;
}

void StaticMap::drain(std::size_t slots) {
  // Only slots move (the voxels stay where they are in the dense array), each to its home in
  // the doubled table, about twice its old position: the writes stream front to back too.
  const std::size_t end = std::min(old_.size, drained_ + slots);
  const std::size_t mask = table_.size - 1;
  const std::size_t chunk = std::size_t{1} << old_.chunk_bits;
  for (std::size_t i = drained_; i < end; ++i) {
    const Slot s = old_[i];
    if (!is_voxel(s)) continue;
    // Not in table_: a voxel has one slot.
    std::size_t j = home(slot_fp(s), table_.bits);
    while (table_[j] != kFree) j = (j + 1) & mask;
    table_[j] = s;
  }
  // Chunks wholly drained are freed now, a piece of the old table at a time.
  for (std::size_t c = drained_ / chunk; c < end / chunk; ++c) {
    give_block(std::move(old_.chunks[c]), chunk);
  }
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
  // The hard limit (load <= 0.7) is reached only when voxels come faster than the pacing above
  // assumes (or in the first, small tables); the pending resize is then completed at once.
  while (kLoadDen * (size_ + n) > kMaxLoadNum * table_.size) {
    if (phase_ == Phase::kIdle) start_resize();
    finish_resize();
  }
  if (phase_ == Phase::kIdle && kLoadDen * (size_ + n) > kResizeLoadNum * table_.size) {
    start_resize();
  }
}

std::size_t StaticMap::add_voxel(std::uint64_t key) {
  if ((size_ >> kBlockBits) >= blocks_.size()) {
    blocks_.push_back(take_block<Voxel>(std::size_t{1} << kBlockBits));
  }
  new (&voxel(size_)) Voxel{key, MapPoint{}};
  return size_++;
}

[[gnu::always_inline]] inline MapPoint& StaticMap::locate(std::uint64_t key, std::uint32_t fp) {
  // While the old table drains, a voxel whose slot is not drained yet is found there (one lookup
  // in one table, not a move per access); the drain moves the slot later. New voxels get a slot
  // in table_ only.
  if (phase_ == Phase::kMoving) {
    const std::size_t o = find_old(key, fp);
    if (o < old_.size) return voxel(slot_index(old_[o])).point;
  }
  const std::size_t mask = table_.size - 1;
  for (std::size_t i = home(fp, table_.bits);; i = (i + 1) & mask) {
    const Slot s = table_[i];
    if (s == kFree) {
      const std::size_t index = add_voxel(key);
      table_[i] = make_slot(fp, index);
      return voxel(index).point;
    }
    if (holds(s, fp, key)) return voxel(slot_index(s)).point;
  }
}

const MapPoint* StaticMap::voxel_at(const Eigen::Vector3f& p) const {
  std::uint64_t key = 0;
  if (size_ == 0 || !voxel_key(p, inverse_size_, key)) return nullptr;
  const std::uint32_t fp = fingerprint(key);
  if (phase_ == Phase::kMoving) {
    const std::size_t o = find_old(key, fp);
    if (o < old_.size) return &voxel(slot_index(old_[o])).point;
  }
  const std::size_t i = find(key);
  return i < table_.size ? &voxel(slot_index(table_[i])).point : nullptr;
}

std::optional<std::uint64_t> StaticMap::key_of(const Eigen::Vector3f& p) const {
  std::uint64_t key = 0;
  if (!voxel_key(p, inverse_size_, key)) return std::nullopt;
  return key;
}

[[gnu::always_inline]] inline void StaticMap::accumulate(MapPoint& m, const Eigen::Vector3f& p,
                                                         float intensity) {
  if (m.count >= kSettledCount) return;  // the mean is settled
  ++m.count;
  const float w = kReciprocal[m.count];
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
  last_point_ = &locate(key, fingerprint(key));
  last_key_ = key;
  accumulate(*last_point_, p, intensity);
  advance_resize(1 + size_ - before);
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
  const std::size_t needed = SettledCells::kKeysPerCell * (std::size_t{max_cell} + 1);
  if (settled.generation != generation_ || settled.key.size() < needed) {
    settled.key.assign(std::max(settled.key.size(), needed), kNoKey);
    settled.generation = generation_;
  }
  insert_batch(points, intensities, skip, &cells, &settled);
}

static_assert(SettledCells::kKeysPerCell == 4, "insert_batch compares four keys per cell");

// One piece on purpose: the chunk's arrays, the two-stage prefetch and the store loop share
// their indices, and with the prefetches in a lambda g++ 12 dropped all of them (below).
// NOLINTNEXTLINE(readability-function-cognitive-complexity)
void StaticMap::insert_batch(const std::vector<Eigen::Vector3f>& points,
                             const std::vector<float>& intensities,
                             const std::vector<std::uint8_t>& skip,
                             const std::vector<std::uint32_t>* cells, SettledCells* settled) {
  // Chunks: room for a whole chunk is made first, so the tables do not change inside one. The
  // home slot of the point kPrefetch ahead is fetched while the current one is stored, and the
  // voxel named by the home slot of the point kPrefetch / 2 ahead (the slot has arrived by then)
  // when its fingerprint matches.
  std::uint64_t keys[kChunk];
  std::uint32_t fps[kChunk];
  std::size_t homes[kChunk];
  std::size_t old_homes[kChunk];
  std::uint32_t which[kChunk];
  // The voxel the home slot named when it was read for the prefetch (nullptr: none with the
  // point's fingerprint). Inside a chunk a slot holding a voxel keeps it (new voxels take free
  // slots; nothing is erased or moved until the chunk's end), so a voxel found there whose key
  // matches is the point's voxel, and its lookup is not repeated.
  Voxel* found[kChunk];
  constexpr std::size_t kHalf = kPrefetch / 2;
  const KeyLanes lanes(inverse_size_);
  for (std::size_t begin = 0; begin < points.size(); begin += kChunk) {
    const std::size_t end = std::min(points.size(), begin + kChunk);
    std::size_t n = 0;
    for (std::size_t i = begin; i < end; ++i) {
      if (!skip.empty() && skip[i]) continue;
      if (!voxel_key(points[i], lanes, keys[n])) {
        ++dropped_;
        continue;
      }
      // A settled voxel ignores further points: nothing to do.
      if (settled != nullptr) {
        const std::uint64_t* known = &settled->key[SettledCells::kKeysPerCell * (*cells)[i]];
        const std::uint64_t k = keys[n];
        if (known[0] == k || known[1] == k || known[2] == k || known[3] == k) continue;
      }
      which[n++] = static_cast<std::uint32_t>(i);
    }
    make_room(n);
    const std::size_t before = size_;
    const bool moving = phase_ == Phase::kMoving;
    for (std::size_t k = 0; k < n; ++k) {
      fps[k] = fingerprint(keys[k]);
      homes[k] = home(fps[k], table_.bits);
      old_homes[k] = moving ? home(fps[k], old_.bits) : 0;
    }
    // While the old table drains, a voxel whose home there is not drained yet is most likely
    // still there (and a new one goes to table_): fetch both.
    // (Written out: with these prefetches in a lambda, g++ 12 dropped all of them.)
    for (std::size_t k = 0; k < n + kPrefetch; ++k) {
      if (k < n) {
        __builtin_prefetch(&table_[homes[k]]);
        if (moving && old_homes[k] >= drained_) __builtin_prefetch(&old_[old_homes[k]]);
      }
      if (k >= kHalf && k - kHalf < n) {
        const std::size_t m = k - kHalf;
        const Slot s = table_[homes[m]];
        found[m] = nullptr;
        if (slot_fp(s) == fps[m] && is_voxel(s)) {
          found[m] = &voxel(slot_index(s));
          __builtin_prefetch(found[m]);
        }
        if (moving && old_homes[m] >= drained_) {
          const Slot o = old_[old_homes[m]];
          if (slot_fp(o) == fps[m] && is_voxel(o)) __builtin_prefetch(&voxel(slot_index(o)));
        }
      }
      if (k < kPrefetch) continue;
      const std::size_t j = k - kPrefetch;  // the point stored now
      if (keys[j] != last_key_) {
        last_point_ = found[j] != nullptr && found[j]->key == keys[j] ? &found[j]->point
                                                                      : &locate(keys[j], fps[j]);
        last_key_ = keys[j];
      }
      accumulate(*last_point_, points[which[j]], intensities[which[j]]);
      if (settled != nullptr && last_point_->count >= kSettledCount) {
        // Newest first; the oldest of the cell's settled voxels is forgotten.
        std::uint64_t* known = &settled->key[SettledCells::kKeysPerCell * (*cells)[which[j]]];
        std::copy_backward(known, known + SettledCells::kKeysPerCell - 1,
                           known + SettledCells::kKeysPerCell);
        known[0] = keys[j];
      }
    }
    advance_resize(std::max(size_ - before, (end - begin) / kPointsPerUnit));
  }
}

void StaticMap::erase_slot(std::size_t i) {
  // Backward-shift deletion keeps every probe sequence unbroken without tombstones.
  const std::size_t mask = table_.size - 1;
  std::size_t hole = i;
  for (std::size_t j = (i + 1) & mask; table_[j] != kFree; j = (j + 1) & mask) {
    const std::size_t h = home(slot_fp(table_[j]), table_.bits);
    // Entry j may move into the hole when its home is not cyclically within (hole, j].
    const bool stays = hole <= j ? (hole < h && h <= j) : (hole < h || h <= j);
    if (!stays) {
      table_[hole] = table_[j];
      hole = j;
    }
  }
  table_[hole] = kFree;
}

void StaticMap::erase(std::uint64_t key) {
  std::size_t index = 0;
  if (const std::size_t i = find(key); i < table_.size) {
    index = slot_index(table_[i]);
    erase_slot(i);
  } else {
    // Still in the draining table: a tombstone keeps the probes past it unbroken.
    const std::size_t o = find_old(key);
    index = slot_index(old_[o]);
    old_[o] = kGone;
  }
  --size_;
  if (index != size_) {
    // The array stays dense: the last voxel moves into the hole and its slot follows.
    const std::uint64_t moved = voxel(size_).key;
    const std::size_t i = find(moved);
    Slot& s = i < table_.size ? table_[i] : old_[find_old(moved)];
    s = make_slot(slot_fp(s), index);
    voxel(index) = voxel(size_);
  }
  last_key_ = kNoKey;
  ++generation_;
}

std::size_t StaticMap::remove_outside(const Eigen::Vector2f& center, float radius_m,
                                      std::vector<MapPoint>& evicted) {
  std::size_t cursor = size_;
  return remove_outside(center, radius_m, evicted, cursor, size_);
}

std::size_t StaticMap::remove_outside(const Eigen::Vector2f& center, float radius_m,
                                      std::vector<MapPoint>& evicted, std::size_t& cursor,
                                      std::size_t visits) {
  const float r2 = radius_m * radius_m;
  std::size_t removed = 0;
  cursor = std::min(cursor, size_);
  // Top down: erase() moves the last voxel into the hole, one above the cursor (visited in this
  // sweep, or added since), never one still to come.
  for (; cursor > 0 && visits > 0; --visits) {
    const Voxel& v = voxel(--cursor);
    if ((v.point.position.head<2>() - center).squaredNorm() <= r2) continue;
    evicted.push_back(v.point);
    erase(v.key);
    ++removed;
  }
  return removed;
}

void StaticMap::collect_inside(const std::uint64_t* keys, std::size_t n, const core::Box3& box,
                               std::vector<std::uint64_t>& doomed) const {
  std::uint32_t fps[kChunk];
  std::size_t homes[kChunk];
  for (std::size_t k = 0; k < n; ++k) {
    fps[k] = fingerprint(keys[k]);
    homes[k] = home(fps[k], table_.bits);
  }
  for (std::size_t k = 0; k < std::min(n, kPrefetch); ++k) __builtin_prefetch(&table_[homes[k]]);
  const std::size_t mask = table_.size - 1;
  for (std::size_t k = 0; k < n; ++k) {
    if (k + kPrefetch < n) __builtin_prefetch(&table_[homes[k + kPrefetch]]);
    std::size_t i = homes[k];
    while (table_[i] != kFree && !holds(table_[i], fps[k], keys[k])) i = (i + 1) & mask;
    const MapPoint* p = nullptr;
    if (table_[i] != kFree) {
      p = &voxel(slot_index(table_[i])).point;
    } else if (phase_ == Phase::kMoving) {
      if (const std::size_t o = find_old(keys[k], fps[k]); o < old_.size) {
        p = &voxel(slot_index(old_[o])).point;
      }
    }
    if (p != nullptr && box.contains(p->position)) doomed.push_back(keys[k]);
  }
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
    // fetched ahead (a box of 10^5 voxels costs 10^5 lookups, mostly misses in a large table,
    // decided by the fingerprints alone).
    std::uint64_t keys[kChunk];
    std::size_t n = 0;
    const auto lookup = [&] {
      collect_inside(keys, n, box, doomed);
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
    for (std::size_t i = 0; i < size_; ++i) {
      if (box.contains(voxel(i).point.position)) doomed.push_back(voxel(i).key);
    }
  }
  for (const auto key : doomed) erase(key);
  return doomed.size();
}

std::vector<MapPoint> StaticMap::points() const {
  std::vector<std::pair<std::uint64_t, MapPoint>> keyed;
  keyed.reserve(size_);
  for (std::size_t i = 0; i < size_; ++i) keyed.emplace_back(voxel(i).key, voxel(i).point);
  std::sort(keyed.begin(), keyed.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<MapPoint> out;
  out.reserve(keyed.size());
  for (const auto& [key, point] : keyed) out.push_back(point);
  return out;
}

}  // namespace ringtrack::mapping
