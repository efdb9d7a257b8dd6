#pragma once
/// A minimal protobuf (proto3 wire format) encoder for the few Foxglove messages ringtrack writes;
/// hand-written because Debian's libprotobuf would need protoc-generated code for a handful of
/// flat messages.

#include <cstdint>
#include <cstring>
#include <span>
#include <string_view>
#include <vector>

#include "ringtrack/io/byte_buffer.hpp"

namespace ringtrack::io {

/// Appends protobuf fields to a byte vector. Nested messages are written in place: begin()
/// reserves the length, end() fills it in (shifting the few bytes of a small message back when
/// the length varint is shorter than reserved), so no temporary buffers are needed.
class ProtoWriter {
 public:
  /// Wire types of the protobuf encoding.
  enum Wire : std::uint8_t { kVarint = 0, kFixed64 = 1, kLengthDelimited = 2, kFixed32 = 5 };

  /// The bytes written.
  [[nodiscard]] std::span<const std::uint8_t> bytes() const { return out_.span(); }
  /// Empties the buffer, keeping its capacity.
  void clear() { out_.clear(); }
  /// Reserves capacity for n more bytes.
  void reserve_more(std::size_t n) { out_.reserve_more(n); }

  /// A varint field (uint32, uint64, bool, enum; int64 as two's complement).
  void varint(std::uint32_t field, std::uint64_t v) {
    tag(field, kVarint);
    raw_varint(v);
  }
  /// A varint field, omitted when zero (proto3 default).
  void varint_nonzero(std::uint32_t field, std::uint64_t v) {
    if (v != 0) varint(field, v);
  }
  /// A double field, omitted when zero (proto3 default).
  void double_field(std::uint32_t field, double v) {
    if (v == 0.0) return;
    tag(field, kFixed64);
    put(v);
  }
  /// A fixed32 field.
  void fixed32(std::uint32_t field, std::uint32_t v) {
    tag(field, kFixed32);
    put(v);
  }
  /// A string field (also for bytes), omitted when empty.
  void string(std::uint32_t field, std::string_view s) {
    if (s.empty()) return;
    tag(field, kLengthDelimited);
    raw_varint(s.size());
    out_.append(s.data(), s.size());
  }
  /// The tag and length of a bytes field whose `size` bytes the caller appends next with
  /// append_raw() or grow(); returns nothing.
  void bytes_header(std::uint32_t field, std::size_t size) {
    tag(field, kLengthDelimited);
    raw_varint(size);
  }
  /// Appends n bytes uninitialised and returns where they start (for the caller to fill).
  std::uint8_t* grow(std::size_t n) { return out_.grow(n); }
  /// Appends bytes as they are.
  void append_raw(std::span<const std::uint8_t> data) { out_.append(data.data(), data.size()); }
  /// Starts a nested message field; returns the position end() needs.
  std::size_t begin(std::uint32_t field) {
    tag(field, kLengthDelimited);
    const std::size_t at = out_.size();
    out_.grow(kReserved);
    return at;
  }
  /// Ends the nested message begun at `at`.
  void end(std::size_t at) {
    const std::size_t length = out_.size() - at - kReserved;
    std::uint8_t len[10];
    std::size_t n = 0;
    for (std::uint64_t v = length;; v >>= 7) {
      len[n++] = static_cast<std::uint8_t>((v & 0x7F) | (v >= 0x80 ? 0x80 : 0));
      if (v < 0x80) break;
    }
    if (n < kReserved) {
      std::memmove(out_.data() + at + n, out_.data() + at + kReserved, length);
      out_.shrink(kReserved - n);
    }
    std::memcpy(out_.data() + at, len, n);
  }

 private:
  static constexpr std::size_t kReserved = 5;  // a varint of up to 2^35 - 1 bytes

  void tag(std::uint32_t field, Wire wire) { raw_varint((std::uint64_t{field} << 3) | wire); }
  void raw_varint(std::uint64_t v) {
    while (v >= 0x80) {
      out_.push_back(static_cast<std::uint8_t>(v | 0x80));
      v >>= 7;
    }
    out_.push_back(static_cast<std::uint8_t>(v));
  }
  template <typename T>
  void put(T v) {
    std::uint8_t* p = grow(sizeof(T));
    std::memcpy(p, &v, sizeof(T));  // little endian, as protobuf's fixed types
  }

  ByteBuffer out_;
};

}  // namespace ringtrack::io
