#pragma once
// A multiset of bucket keys (the values in a median window) with two tracked order statistics.
// Adding or removing a key is O(1); after a batch of changes, settle() moves each tracked rank's
// bucket pointer by as many non-empty buckets as the changes shifted it (found with a bitmap of
// non-empty buckets), so a window sliding by one cell costs O(1) whatever its size.

#include <bit>
#include <cstdint>
#include <utility>
#include <vector>

namespace ringtrack::segmentation::detail {

class OrderStatWindow {
 public:
  explicit OrderStatWindow(std::uint32_t buckets)
      : count_(buckets, 0), occupied_((buckets + 63) / 64, 0) {}

  /// Adds (kSign +1) or removes (kSign -1) the keys [first, last).
  template <int kSign>
  void update(const std::uint32_t* first, const std::uint32_t* last) {
    static_assert(kSign == 1 || kSign == -1);
    // Locals let the compiler keep the counters in registers across the loop.
    const std::uint32_t lo_bucket = lo_.bucket, hi_bucket = hi_.bucket;
    int lo_below = 0, hi_below = 0;
    for (const std::uint32_t* k = first; k != last; ++k) {
      const std::uint32_t key = *k;
      change<kSign>(key);
      lo_below += key < lo_bucket;
      hi_below += key < hi_bucket;
    }
    const int n = static_cast<int>(last - first);
    size_ += kSign * n;
    lo_.below += kSign * lo_below;
    hi_.below += kSign * hi_below;
  }
  /// Removes one key and adds another: the window slid by one cell.
  void slide(std::uint32_t out, std::uint32_t in) {
    change<-1>(out);
    change<1>(in);
    lo_.below += static_cast<int>(in < lo_.bucket) - static_cast<int>(out < lo_.bucket);
    hi_.below += static_cast<int>(in < hi_.bucket) - static_cast<int>(out < hi_.bucket);
  }
  /// Ranks (0-based, ascending) whose buckets settle() tracks; need 0 <= lo <= hi < size().
  void set_ranks(int lo, int hi) {
    lo_.rank = lo;
    hi_.rank = hi;
  }
  /// Moves both pointers to the buckets holding their ranks.
  void settle() {
    settle(lo_);
    settle(hi_);
  }
  /// Bucket holding `rank` and the number of keys below that bucket, found by walking from the
  /// lower tracked pointer (cheap when rank is near it).
  [[nodiscard]] std::pair<std::uint32_t, int> bucket_of_rank(int rank) const {
    Pointer p = lo_;
    p.rank = rank;
    settle(p);
    return {p.bucket, p.below};
  }
  [[nodiscard]] std::uint32_t lo_bucket() const { return lo_.bucket; }
  [[nodiscard]] std::uint32_t hi_bucket() const { return hi_.bucket; }
  [[nodiscard]] int size() const { return size_; }

 private:
  struct Pointer {
    std::uint32_t bucket{0};
    int below{0};  // keys in the window below `bucket`
    int rank{0};
  };

  template <int kSign>
  void change(std::uint32_t key) {
    const auto c = static_cast<std::uint16_t>(count_[key] + kSign);
    count_[key] = c;
    const std::uint64_t bit = std::uint64_t{1} << (key & 63);
    std::uint64_t& word = occupied_[key >> 6];
    word = c != 0 ? (word | bit) : (word & ~bit);
  }

  void settle(Pointer& p) const {
    while (p.below > p.rank) {
      p.bucket = previous_nonempty(p.bucket);
      p.below -= count_[p.bucket];
    }
    while (p.below + count_[p.bucket] <= p.rank) {
      p.below += count_[p.bucket];
      p.bucket = next_nonempty(p.bucket);
    }
  }
  // Callers guarantee that a non-empty bucket exists in the searched direction.
  [[nodiscard]] std::uint32_t next_nonempty(std::uint32_t b) const {
    ++b;
    std::uint32_t w = b >> 6;
    std::uint64_t bits = occupied_[w] & (~std::uint64_t{0} << (b & 63));
    while (bits == 0) bits = occupied_[++w];
    return (w << 6) + static_cast<std::uint32_t>(std::countr_zero(bits));
  }
  [[nodiscard]] std::uint32_t previous_nonempty(std::uint32_t b) const {
    --b;
    std::uint32_t w = b >> 6;
    std::uint64_t bits = occupied_[w] & (~std::uint64_t{0} >> (63 - (b & 63)));
    while (bits == 0) bits = occupied_[--w];
    return (w << 6) + 63 - static_cast<std::uint32_t>(std::countl_zero(bits));
  }

  std::vector<std::uint16_t> count_;
  std::vector<std::uint64_t> occupied_;  // bit per bucket: count_ != 0
  int size_{0};
  Pointer lo_, hi_;
};

}  // namespace ringtrack::segmentation::detail
