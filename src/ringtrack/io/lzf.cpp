#include "ringtrack/io/lzf.hpp"

#include <algorithm>
#include <cstring>
#include <string>

#include "ringtrack/core/error.hpp"

namespace ringtrack::io {
namespace {

constexpr std::size_t kMaxLiteral = 32;   // control byte 0..31 means 1..32 literals
constexpr std::size_t kMaxOffset = 8192;  // 13 bits of distance, stored minus one
constexpr std::size_t kMinMatch = 3;      // shorter matches cost more than literals
constexpr std::size_t kMaxMatch = 264;    // 7 + 255 in the length fields, plus 2
constexpr int kHashBits = 14;

std::uint32_t hash3(const std::uint8_t* p) {
  const std::uint32_t v = (std::uint32_t{p[0]} << 16) | (std::uint32_t{p[1]} << 8) | p[2];
  return (v * 2654435761u) >> (32 - kHashBits);
}

void flush_literals(std::vector<std::uint8_t>& out, const std::uint8_t* begin,
                    const std::uint8_t* end) {
  while (begin < end) {
    const auto n = std::min<std::size_t>(kMaxLiteral, static_cast<std::size_t>(end - begin));
    out.push_back(static_cast<std::uint8_t>(n - 1));
    out.insert(out.end(), begin, begin + n);
    begin += n;
  }
}

[[noreturn]] void corrupt(const std::string& what, std::size_t offset) {
  throw core::InputError("lzf: " + what + " at stream offset " + std::to_string(offset));
}

}  // namespace

std::vector<std::uint8_t> lzf_compress(std::span<const std::uint8_t> in) {
  std::vector<std::uint8_t> out;
  out.reserve(in.size() + in.size() / kMaxLiteral + 16);
  const std::size_t n = in.size();
  const std::uint8_t* data = in.data();
  // Last position + 1 of each 3-byte hash (0 = empty), so a zero-filled table is valid.
  std::vector<std::size_t> table(std::size_t{1} << kHashBits, 0);
  std::size_t literal_start = 0;
  std::size_t ip = 0;
  while (ip + kMinMatch <= n) {
    const std::uint32_t h = hash3(data + ip);
    const std::size_t candidate = table[h];
    table[h] = ip + 1;
    if (candidate != 0) {
      const std::size_t ref = candidate - 1;
      const std::size_t distance = ip - ref;
      if (distance <= kMaxOffset && std::memcmp(data + ref, data + ip, kMinMatch) == 0) {
        const std::size_t limit = std::min(kMaxMatch, n - ip);
        std::size_t len = kMinMatch;
        while (len < limit && data[ref + len] == data[ip + len]) ++len;
        flush_literals(out, data + literal_start, data + ip);
        const std::size_t code_len = len - 2;  // 1..262
        const std::size_t off = distance - 1;  // 0..8191
        if (code_len < 7) {
          out.push_back(static_cast<std::uint8_t>((code_len << 5) | (off >> 8)));
        } else {
          out.push_back(static_cast<std::uint8_t>((7u << 5) | (off >> 8)));
          out.push_back(static_cast<std::uint8_t>(code_len - 7));
        }
        out.push_back(static_cast<std::uint8_t>(off & 0xffu));
        // Index the positions inside the match so repeated data keeps finding long matches.
        const std::size_t end = ip + len;
        for (std::size_t k = ip + 1; k < end && k + kMinMatch <= n; ++k) {
          table[hash3(data + k)] = k + 1;
        }
        ip = end;
        literal_start = ip;
        continue;
      }
    }
    ++ip;
  }
  flush_literals(out, data + literal_start, data + n);
  return out;
}

void lzf_decompress(std::span<const std::uint8_t> in, std::span<std::uint8_t> out) {
  std::size_t ip = 0;
  std::size_t op = 0;
  while (ip < in.size()) {
    const std::size_t at = ip;
    const std::size_t ctrl = in[ip++];
    if (ctrl < kMaxLiteral) {
      const std::size_t len = ctrl + 1;
      if (len > in.size() - ip)
        corrupt("literal run of " + std::to_string(len) + " bytes is truncated", at);
      if (len > out.size() - op)
        corrupt("output overflows the expected " + std::to_string(out.size()) + " bytes", at);
      std::memcpy(out.data() + op, in.data() + ip, len);
      ip += len;
      op += len;
      continue;
    }
    std::size_t len = ctrl >> 5;
    if (len == 7) {
      if (ip >= in.size()) corrupt("back reference is truncated", at);
      len += in[ip++];
    }
    if (ip >= in.size()) corrupt("back reference is truncated", at);
    const std::size_t distance = ((ctrl & 0x1fu) << 8) + in[ip++] + 1;
    len += 2;
    if (distance > op) {
      corrupt("back reference " + std::to_string(distance) + " bytes back reaches before the start",
              at);
    }
    if (len > out.size() - op)
      corrupt("output overflows the expected " + std::to_string(out.size()) + " bytes", at);
    // Byte by byte: source and destination overlap when distance < len (run-length repeats).
    for (std::size_t k = 0; k < len; ++k, ++op) out[op] = out[op - distance];
  }
  if (op != out.size()) {
    corrupt("stream ends after " + std::to_string(op) + " of " + std::to_string(out.size()) +
                " decoded bytes",
            ip);
  }
}

}  // namespace ringtrack::io
