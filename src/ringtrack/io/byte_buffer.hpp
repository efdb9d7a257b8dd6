#pragma once
/// A growable byte buffer whose appended space is not zero-filled first: the writers of large
/// messages (a scan's point cloud, an MCAP chunk) fill every byte they append, and a
/// std::vector's value-initialising resize would touch the several hundred kB twice.

#include <cstdint>
#include <cstring>
#include <memory>
#include <span>

namespace ringtrack::io {

/// Bytes with amortised O(1) append; moves keep the storage, clear() keeps the capacity.
class ByteBuffer {
 public:
  /// Number of bytes.
  [[nodiscard]] std::size_t size() const { return size_; }
  /// True when empty.
  [[nodiscard]] bool empty() const { return size_ == 0; }
  /// The first byte (nullptr before anything was appended).
  [[nodiscard]] std::uint8_t* data() { return data_.get(); }
  /// The first byte (nullptr before anything was appended).
  [[nodiscard]] const std::uint8_t* data() const { return data_.get(); }
  /// The bytes as a span.
  [[nodiscard]] std::span<const std::uint8_t> span() const { return {data_.get(), size_}; }
  /// Implicit view as a span, for the functions that read bytes.
  operator std::span<const std::uint8_t>() const { return span(); }  // NOLINT
  /// Empties the buffer, keeping its capacity.
  void clear() { size_ = 0; }
  /// Makes room for n more bytes without changing the size.
  void reserve_more(std::size_t n) {
    if (size_ + n > capacity_) reallocate(size_ + n);
  }
  /// Appends n bytes left for the caller to fill; returns where they start.
  std::uint8_t* grow(std::size_t n) {
    reserve_more(n);
    std::uint8_t* at = data_.get() + size_;
    size_ += n;
    return at;
  }
  /// Drops the last n bytes.
  void shrink(std::size_t n) { size_ -= n; }
  /// Appends bytes.
  void append(const void* bytes, std::size_t n) {
    if (n != 0) std::memcpy(grow(n), bytes, n);
  }
  /// Appends one byte.
  void push_back(std::uint8_t b) { *grow(1) = b; }

 private:
  void reallocate(std::size_t needed) {
    std::size_t capacity = capacity_ < 256 ? 256 : capacity_ * 2;
    while (capacity < needed) capacity *= 2;
    std::unique_ptr<std::uint8_t[]> bigger(new std::uint8_t[capacity]);
    if (size_ != 0) std::memcpy(bigger.get(), data_.get(), size_);
    data_ = std::move(bigger);
    capacity_ = capacity;
  }

  std::unique_ptr<std::uint8_t[]> data_;
  std::size_t size_{0};
  std::size_t capacity_{0};
};

}  // namespace ringtrack::io
