#include "ringtrack/mapping/transient_grid.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>

#include "ringtrack/core/error.hpp"

namespace ringtrack::mapping {
namespace {

constexpr std::size_t kMinSlots = 1024;
constexpr std::uint64_t kFibonacci = 0x9E3779B97F4A7C15ULL;  // 2^64 / golden ratio
constexpr std::size_t kAhead = 8;       // keys between a slot's prefetch and its use
constexpr float kIndexLimit = 0x1p30f;  // cell indices within +-2^30 fit 32 bits with an offset

// Fibonacci hashing: the top `bits` bits of the product, which mix both halves of the key.
std::size_t top_bits_of_hash(std::uint64_t key, int bits) {
  return static_cast<std::size_t>((key * kFibonacci) >> (64 - bits));
}

// floor(v) for |v| < 2^30: truncation and a step down for negative fractions (std::floor is a
// library call without SSE4.1, and this runs for every candidate point of every scan).
std::int64_t floor_index(float v) {
  const auto t = static_cast<std::int64_t>(v);
  return static_cast<float>(t) > v ? t - 1 : t;
}

}  // namespace

TransientGrid::TransientGrid(double cell_m, std::uint64_t memory_scans)
    : inverse_cell_(static_cast<float>(1.0 / cell_m)), memory_scans_(memory_scans) {
  if (!(cell_m > 0.0) || !std::isfinite(cell_m)) {
    throw core::ConfigError("mapping: the transient grid's cell must be finite and > 0");
  }
  clear();
}

void TransientGrid::clear() {
  slots_.assign(kMinSlots, Slot{kNoCell, 0, 0});
  bits_ = std::countr_zero(kMinSlots);
  size_ = 0;
}

std::uint64_t TransientGrid::key(const Eigen::Vector3f& p) const {
  const float x = p.x() * inverse_cell_;
  const float y = p.y() * inverse_cell_;
  // NaN and infinity fail the comparison.
  if (!(std::abs(x) < kIndexLimit) || !(std::abs(y) < kIndexLimit)) return kNoCell;
  const auto ix = static_cast<std::uint64_t>(floor_index(x) + (1LL << 31));
  const auto iy = static_cast<std::uint64_t>(floor_index(y) + (1LL << 31));
  return (ix << 32) | iy;
}

std::size_t TransientGrid::home(std::uint64_t key) const {
  return top_bits_of_hash(key, bits_);
}

const TransientGrid::Slot* TransientGrid::find(std::uint64_t key) const {
  const std::size_t mask = slots_.size() - 1;
  for (std::size_t i = home(key);; i = (i + 1) & mask) {
    const Slot& s = slots_[i];
    if (s.key == key) return &s;
    if (s.key == kNoCell) return nullptr;
  }
}

void TransientGrid::insert(std::uint64_t key, std::uint64_t sequence) {
  const std::size_t mask = slots_.size() - 1;
  std::size_t i = home(key);
  while (slots_[i].key != kNoCell && slots_[i].key != key) i = (i + 1) & mask;
  Slot& s = slots_[i];
  if (s.key == kNoCell) {
    s = {key, sequence, sequence};
    ++size_;
  } else {
    s.last = sequence;
  }
}

void TransientGrid::note(const Eigen::Vector3f& p, std::uint64_t sequence) {
  const std::uint64_t key = this->key(p);
  if (key == kNoCell) return;
  newest_ = sequence;
  if (2 * (size_ + 1) > slots_.size()) rebuild(1);
  insert(key, sequence);
}

void TransientGrid::note(const std::vector<std::uint64_t>& keys, std::uint64_t sequence) {
  unique_.clear();
  // The points of one object fall in a few cells, ring after ring: a small direct-mapped filter
  // of the keys taken in this batch drops most repeats before they cost a table probe.
  constexpr int kTakenBits = 9;
  std::array<std::uint64_t, std::size_t{1} << kTakenBits> taken;
  taken.fill(kNoCell);
  for (const std::uint64_t key : keys) {
    if (key == kNoCell) continue;
    std::uint64_t& seen = taken[top_bits_of_hash(key, kTakenBits)];
    if (seen == key) continue;
    seen = key;
    unique_.push_back(key);
  }
  if (unique_.empty()) return;
  newest_ = sequence;
  // Room for every key first (the table stays at most half full), so that no rebuild moves the
  // slots prefetched below. Each insert is a cache miss in a large table: the home slots are
  // fetched kAhead keys early.
  if (2 * (size_ + unique_.size()) > slots_.size()) rebuild(unique_.size());
  const std::size_t n = unique_.size();
  for (std::size_t j = 0; j < n; ++j) {
    if (j + kAhead < n) __builtin_prefetch(&slots_[home(unique_[j + kAhead])]);
    insert(unique_[j], sequence);
  }
}

bool TransientGrid::confirmed(const Eigen::Vector3f& p, std::uint64_t sequence,
                              std::uint64_t k) const {
  return confirmed(key(p), sequence, k);
}

bool TransientGrid::confirmed(std::uint64_t key, std::uint64_t sequence, std::uint64_t k) const {
  if (key == kNoCell) return false;
  // The point's own cell first: what stands there is mostly confirmed by it. A neighbour's key
  // is the own key with its halves shifted (key() keeps indices within +-2^30, so no half
  // overflows into the other).
  for (const auto& [dx, dy] :
       {std::pair{0, 0}, {-1, -1}, {-1, 0}, {-1, 1}, {0, -1}, {0, 1}, {1, -1}, {1, 0}, {1, 1}}) {
    const std::uint64_t neighbour =
        key + (static_cast<std::uint64_t>(static_cast<std::int64_t>(dx)) << 32) +
        static_cast<std::uint64_t>(static_cast<std::int64_t>(dy));
    const Slot* s = find(neighbour);
    if (s == nullptr) continue;
    if (s->first + k <= sequence || s->last >= sequence + k) return true;
  }
  return false;
}

void TransientGrid::unconfirmed(const std::vector<std::uint64_t>& keys, std::uint64_t sequence,
                                std::uint64_t k, std::vector<std::uint32_t>& out) const {
  // As confirmed() key by key, with the own cells' slots fetched kAhead keys early.
  const std::size_t n = keys.size();
  for (std::size_t j = 0; j < n; ++j) {
    if (j + kAhead < n && keys[j + kAhead] != kNoCell) {
      __builtin_prefetch(&slots_[home(keys[j + kAhead])]);
    }
    if (!confirmed(keys[j], sequence, k)) out.push_back(static_cast<std::uint32_t>(j));
  }
}

void TransientGrid::rebuild(std::size_t extra) {
  std::vector<Slot> kept;
  kept.reserve(size_);
  for (const Slot& s : slots_) {
    if (s.key != kNoCell && s.last + memory_scans_ >= newest_) kept.push_back(s);
  }
  // At most a quarter full afterwards, so the next rebuild is at least as many inserts away.
  const std::size_t slots = std::max(kMinSlots, std::bit_ceil(4 * (kept.size() + extra)));
  slots_.assign(slots, Slot{kNoCell, 0, 0});
  bits_ = std::countr_zero(slots);
  const std::size_t mask = slots - 1;
  for (const Slot& s : kept) {
    std::size_t i = home(s.key);
    while (slots_[i].key != kNoCell) i = (i + 1) & mask;
    slots_[i] = s;
  }
  size_ = kept.size();
}

}  // namespace ringtrack::mapping
