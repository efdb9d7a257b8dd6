#pragma once
// A multiset of bucket keys (the values in a median window) with two rank pointers. Adding or
// removing a key is O(1) and keeps each pointer's count of keys below it. Reading a bound moves a
// pointer only if the changes made its bound invalid, by as many non-empty buckets as needed
// (found with a bitmap of non-empty buckets); exact reads (tighten, track_rank) move it to the
// rank. A window moving by one cell per point thus costs O(1) per point whatever its size.

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
    for (const std::uint32_t* k = first; k != last; ++k) change<kSign>(*k);
    // A separate loop: without the scattered stores the comparisons vectorise.
    const std::uint32_t lo_bucket = lo_.bucket, hi_bucket = hi_.bucket;
    int lo_below = 0, hi_below = 0;
    for (const std::uint32_t* k = first; k != last; ++k) {
      lo_below += static_cast<int>(*k < lo_bucket);
      hi_below += static_cast<int>(*k < hi_bucket);
    }
    const int n = static_cast<int>(last - first);
    size_ += kSign * n;
    lo_.below += kSign * lo_below;
    hi_.below += kSign * hi_below;
  }
  /// Removes the keys [out, out + n) and adds [in, in + n): a window moved by n cells. One pass
  /// instead of an add and a remove.
  void replace(const std::uint32_t* out, const std::uint32_t* in, int n) {
    for (int k = 0; k < n; ++k) {
      change<-1>(out[k]);
      change<1>(in[k]);
    }
    const std::uint32_t lo_bucket = lo_.bucket, hi_bucket = hi_.bucket;
    int lo_delta = 0, hi_delta = 0;
    for (int k = 0; k < n; ++k) {
      lo_delta += static_cast<int>(in[k] < lo_bucket) - static_cast<int>(out[k] < lo_bucket);
      hi_delta += static_cast<int>(in[k] < hi_bucket) - static_cast<int>(out[k] < hi_bucket);
    }
    lo_.below += lo_delta;
    hi_.below += hi_delta;
  }
  /// Ranks (0-based, ascending) whose buckets settle() tracks; need 0 <= lo <= hi < size().
  void set_ranks(int lo, int hi) {
    lo_.rank = lo;
    hi_.rank = hi;
  }
  /// Makes the lower tracked pointer follow `rank` and returns its bucket and the keys below it:
  /// for a window that moves with the queried point, so the pointer only walks a little.
  [[nodiscard]] std::pair<std::uint32_t, int> track_rank(int rank) {
    lo_.rank = rank;
    settle(lo_);
    return {lo_.bucket, lo_.below};
  }
  /// A bucket whose smallest value is a lower bound of the lower tracked rank's value: the
  /// pointer moves down only when the window's changes made it invalid, never up, so it is
  /// usually where it was (no walk) but may lag below the rank.
  [[nodiscard]] std::uint32_t lo_bound_bucket() {
    while (lo_.below > lo_.rank) step_down(lo_);
    return lo_.bucket;
  }
  /// A bucket whose values bound the upper tracked rank's value from above, lazily as above.
  [[nodiscard]] std::uint32_t hi_bound_bucket() {
    while (hi_.below + count_[hi_.bucket] <= hi_.rank) step_up(hi_);
    return hi_.bucket;
  }
  /// Moves both pointers to the buckets holding their ranks exactly: the tightest bounds.
  void tighten() {
    settle(lo_);
    settle(hi_);
  }
  [[nodiscard]] int size() const { return size_; }

 private:
  struct Pointer {
    std::uint32_t bucket{0};
    int below{0};  // keys in the window below `bucket`
    int rank{0};
  };

  // The bitmap is maintained lazily: adding sets the bucket's bit, removing leaves it, and the
  // searches clear bits they find stale. A set bit thus means "maybe non-empty", a clear bit
  // "empty", which is all the searches need; it keeps the hot update to two stores.
  template <int kSign>
  void change(std::uint32_t key) {
    count_[key] = static_cast<std::uint16_t>(count_[key] + kSign);
    if constexpr (kSign > 0) occupied_[key >> 6] |= std::uint64_t{1} << (key & 63);
  }

  void step_down(Pointer& p) {
    p.bucket = previous_nonempty(p.bucket);
    p.below -= count_[p.bucket];
  }
  void step_up(Pointer& p) {
    p.below += count_[p.bucket];
    p.bucket = next_nonempty(p.bucket);
  }
  // Inlined: in the common case neither loop runs.
  [[gnu::always_inline]] void settle(Pointer& p) {
    while (p.below > p.rank) step_down(p);
    while (p.below + count_[p.bucket] <= p.rank) step_up(p);
  }
  // Callers guarantee that a non-empty bucket exists in the searched direction.
  [[gnu::noinline]] std::uint32_t next_nonempty(std::uint32_t b) {
    ++b;
    std::uint32_t w = b >> 6;
    std::uint64_t bits = occupied_[w] & (~std::uint64_t{0} << (b & 63));
    for (;;) {
      while (bits == 0) bits = occupied_[++w];
      const std::uint32_t found = (w << 6) + static_cast<std::uint32_t>(std::countr_zero(bits));
      if (count_[found] != 0) return found;
      occupied_[w] &= ~(std::uint64_t{1} << (found & 63));  // stale: the bucket emptied
      bits &= bits - 1;
    }
  }
  [[gnu::noinline]] std::uint32_t previous_nonempty(std::uint32_t b) {
    --b;
    std::uint32_t w = b >> 6;
    std::uint64_t bits = occupied_[w] & (~std::uint64_t{0} >> (63 - (b & 63)));
    for (;;) {
      while (bits == 0) bits = occupied_[--w];
      const int top = 63 - std::countl_zero(bits);
      const std::uint32_t found = (w << 6) + static_cast<std::uint32_t>(top);
      if (count_[found] != 0) return found;
      occupied_[w] &= ~(std::uint64_t{1} << top);
      bits &= ~(std::uint64_t{1} << top);
    }
  }

  std::vector<std::uint16_t> count_;
  std::vector<std::uint64_t> occupied_;  // bit per bucket: count_ != 0
  int size_{0};
  Pointer lo_, hi_;
};

}  // namespace ringtrack::segmentation::detail
