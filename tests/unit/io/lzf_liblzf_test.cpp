// ringtrack's LZF (io/lzf.cpp) against liblzf, the reference implementation (Debian's
// liblzf-dev), as the independent oracle: each decompresses the other's streams to the same
// bytes, and both accept and reject the same damaged streams. The compressed streams themselves
// may differ (two compressors choose different matches, and liblzf's output is not even promised
// to be the same from run to run); only what they decode to must agree.

#include "ringtrack/io/lzf.hpp"

#include <gtest/gtest.h>
#include <lzf.h>

#include <cstdint>
#include <cstring>
#include <limits>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "ringtrack/core/error.hpp"

namespace ringtrack::io {
namespace {

using Bytes = std::vector<std::uint8_t>;

unsigned int length(const Bytes& b) {
  return static_cast<unsigned int>(b.size());
}

Bytes liblzf_compress(const Bytes& in) {
  if (in.empty()) return {};  // liblzf returns 0 ("does not fit") for empty input
  // liblzf's worst case is one control byte per 32 literals.
  Bytes out(in.size() + in.size() / 32 + 16);
  const unsigned int n = ::lzf_compress(in.data(), length(in), out.data(), length(out));
  EXPECT_NE(n, 0u) << "liblzf could not compress " << in.size() << " bytes";
  out.resize(n);
  return out;
}

// The bytes liblzf decodes the stream to when they are exactly `size`, else nothing.
std::optional<Bytes> liblzf_decompress(const Bytes& in, std::size_t size) {
  // liblzf reads a control byte before it looks at the length (a do-while): never hand it an
  // empty stream, which decodes to nothing.
  if (in.empty()) return size == 0 ? std::optional<Bytes>(Bytes{}) : std::nullopt;
  Bytes out(size + 1);  // one spare byte: a stream that decodes to more is caught as too long
  const unsigned int n = ::lzf_decompress(in.data(), length(in), out.data(), length(out));
  if (n != size) return std::nullopt;
  out.resize(size);
  return out;
}

// The bytes ours decodes the stream to, or nothing when it rejects it (with an InputError).
std::optional<Bytes> ours_decompress(const Bytes& in, std::size_t size) {
  Bytes out(size);
  try {
    lzf_decompress(in, out);
  } catch (const core::InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("lzf: ", 0), 0u) << e.what();
    return std::nullopt;
  }
  return out;
}

void expect_interchangeable(const Bytes& data, const std::string& what) {
  SCOPED_TRACE(what + ", " + std::to_string(data.size()) + " bytes");
  const Bytes ours = lzf_compress(data);
  const Bytes theirs = liblzf_compress(data);
  EXPECT_EQ(ours_decompress(ours, data.size()), data);
  EXPECT_EQ(liblzf_decompress(ours, data.size()), data);
  EXPECT_EQ(ours_decompress(theirs, data.size()), data);
  EXPECT_EQ(liblzf_decompress(theirs, data.size()), data);
}

Bytes random_bytes(std::mt19937& rng, std::size_t size, unsigned alphabet = 256) {
  Bytes b(size);
  for (auto& v : b) v = static_cast<std::uint8_t>(rng() % alphabet);
  return b;
}

TEST(LzfAgainstLiblzf, EachDecodesTheOthersStreams) {
  std::mt19937 rng(17);
  expect_interchangeable({}, "empty");
  expect_interchangeable({0x42}, "one byte");
  expect_interchangeable({0x00, 0x00}, "two bytes");
  expect_interchangeable({7, 7, 7}, "three equal bytes");
  for (std::size_t size : {4u, 31u, 32u, 33u, 64u, 255u, 1000u, 8191u, 8192u, 8193u, 70000u}) {
    expect_interchangeable(random_bytes(rng, size), "random");
    expect_interchangeable(random_bytes(rng, size, 3), "three-letter alphabet");
  }
  expect_interchangeable(Bytes(100000, 0), "zeros");
  expect_interchangeable(Bytes(265, 0xff), "one run one byte longer than the longest match");
  // Long runs of varying lengths between short random stretches.
  Bytes runs;
  for (int k = 0; k < 300; ++k) {
    runs.insert(runs.end(), 1 + rng() % 1000, static_cast<std::uint8_t>(rng()));
    const Bytes noise = random_bytes(rng, rng() % 40);
    runs.insert(runs.end(), noise.begin(), noise.end());
  }
  expect_interchangeable(runs, "long runs");
  Bytes pattern;
  for (int k = 0; k < 20000; ++k) pattern.push_back(static_cast<std::uint8_t>("abcdefg"[k % 7]));
  expect_interchangeable(pattern, "period 7");
  // Repeats just inside and just beyond the 8192-byte window.
  for (std::size_t gap : {8000u, 8192u, 8200u, 20000u}) {
    Bytes block = random_bytes(rng, 300);
    Bytes far = block;
    const Bytes middle = random_bytes(rng, gap - block.size());
    far.insert(far.end(), middle.begin(), middle.end());
    far.insert(far.end(), block.begin(), block.end());
    expect_interchangeable(far, "repeat " + std::to_string(gap) + " bytes back");
  }
  // The columns of a binary_compressed PCD file: floats with NaNs for empty cells.
  Bytes floats;
  for (int k = 0; k < 30000; ++k) {
    const float v = k % 10 == 0 ? std::numeric_limits<float>::quiet_NaN()
                                : 1.5f + 0.001f * static_cast<float>(k % 100);
    std::uint8_t b[4];
    std::memcpy(b, &v, 4);
    floats.insert(floats.end(), b, b + 4);
  }
  expect_interchangeable(floats, "float column");
}

// Damaged streams (bytes changed, cut short, declared one byte too short or too long): ours
// rejects exactly those liblzf rejects, and decodes the rest to the same bytes.
TEST(LzfAgainstLiblzf, BothRejectTheSameDamagedStreams) {
  std::mt19937 rng(1717);
  int rejected = 0;
  int accepted = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    const Bytes data = random_bytes(rng, 1 + rng() % 600, trial % 2 == 0 ? 4 : 256);
    Bytes stream = trial % 3 == 0 ? liblzf_compress(data) : lzf_compress(data);
    std::size_t size = data.size();
    switch (trial % 4) {
      case 0:  // a few bytes changed (control bytes, lengths, distances or literals)
        for (std::size_t k = 0, changes = 1 + rng() % 3; k < changes; ++k) {
          stream[rng() % stream.size()] = static_cast<std::uint8_t>(rng());
        }
        break;
      case 1:  // cut short
        stream.resize(rng() % stream.size());
        break;
      case 2:  // expected one byte more
        ++size;
        break;
      default:  // expected one byte less
        --size;
        break;
    }
    if (stream.empty()) continue;
    SCOPED_TRACE("trial " + std::to_string(trial));
    const std::optional<Bytes> ours = ours_decompress(stream, size);
    const std::optional<Bytes> theirs = liblzf_decompress(stream, size);
    EXPECT_EQ(ours.has_value(), theirs.has_value());
    if (ours && theirs) {
      EXPECT_EQ(*ours, *theirs);
    }
    ++(ours ? accepted : rejected);
  }
  // Both outcomes occur (a changed literal byte leaves a valid stream).
  EXPECT_GT(rejected, 1000);
  EXPECT_GT(accepted, 100);
}

}  // namespace
}  // namespace ringtrack::io
