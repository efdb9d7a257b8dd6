#include "ringtrack/io/lzf.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <string>

#include "io_test_util.hpp"
#include "ringtrack/core/error.hpp"

namespace ringtrack::io {
namespace {

using Bytes = std::vector<std::uint8_t>;

// Straightforward reference decoder written from the format description (no bounds shortcuts):
// the oracle for the compressor, independent of lzf_decompress.
Bytes reference_decode(const Bytes& in) {
  Bytes out;
  std::size_t ip = 0;
  while (ip < in.size()) {
    const unsigned ctrl = in.at(ip++);
    if (ctrl < 32) {
      for (unsigned k = 0; k <= ctrl; ++k) out.push_back(in.at(ip++));
    } else {
      unsigned len = ctrl >> 5;
      if (len == 7) len += in.at(ip++);
      const std::size_t back = ((ctrl & 31u) << 8) + in.at(ip++) + 1;
      EXPECT_LE(back, out.size());
      EXPECT_LE(back, 8192u);
      for (unsigned k = 0; k < len + 2; ++k) out.push_back(out.at(out.size() - back));
    }
  }
  return out;
}

Bytes decode(const Bytes& in, std::size_t size) {
  Bytes out(size);
  lzf_decompress(in, out);
  return out;
}

Bytes text(const std::string& s) {
  return {s.begin(), s.end()};
}

TEST(Lzf, NoStreamDecodesToMoreThanTheDeclaredMaximumExpansion) {
  // The longest token, a 3-byte back reference of length 264 (control 0xE0, length byte 255,
  // distance 1), is the densest: a stream of them after a 1-byte literal reaches the maximum.
  Bytes stream{0x00, 'z'};
  for (int k = 0; k < 100; ++k) stream.insert(stream.end(), {0xE0, 0xFF, 0x00});
  const std::size_t size = 1 + 100 * 264;
  EXPECT_EQ(decode(stream, size), Bytes(size, 'z'));
  EXPECT_LE(size, stream.size() * kLzfMaxExpansion);
  EXPECT_GT(size, (stream.size() - 2) * (kLzfMaxExpansion - 1));  // the bound is tight
  // Our compressor approaches it on uniform data.
  const Bytes zeros(1u << 20, 0);
  const Bytes packed = lzf_compress(zeros);
  EXPECT_LE(zeros.size(), packed.size() * kLzfMaxExpansion);
  EXPECT_GT(zeros.size(), packed.size() * 80);
}

TEST(Lzf, DecodesHandMadeStream) {
  // literal run "abc" (control 2), then a 5-byte back reference 3 bytes back:
  // length field 5-2 = 3 in the top bits (0x60), distance-1 = 2 -> overlapping copy.
  const Bytes stream{0x02, 'a', 'b', 'c', 0x60, 0x02};
  EXPECT_EQ(decode(stream, 8), text("abcabcab"));
  // literal "x", then the long form: top bits 7 (0xE0), extra length 10 -> 7+10+2 = 19 bytes,
  // distance 1: a run of 20 'x'.
  const Bytes run{0x00, 'x', 0xE0, 0x0A, 0x00};
  EXPECT_EQ(decode(run, 20), Bytes(20, 'x'));
  // A back reference with the high distance bits: 300 literals, then copy 4 bytes from 300 back.
  Bytes far;
  Bytes expected;
  for (int chunk = 0; chunk < 10; ++chunk) {
    far.push_back(29);  // 30 literals
    for (int k = 0; k < 30; ++k) {
      const auto b = static_cast<std::uint8_t>(chunk * 30 + k);
      far.push_back(b);
      expected.push_back(b);
    }
  }
  // distance 300 -> stored 299 = 0x12B: high bits 0x01 in the control byte, low byte 0x2B.
  far.push_back(0x40 | 0x01);  // length 4-2 = 2
  far.push_back(0x2B);
  for (int k = 0; k < 4; ++k) expected.push_back(expected[static_cast<std::size_t>(k)]);
  EXPECT_EQ(decode(far, expected.size()), expected);
}

TEST(Lzf, RejectsCorruptStreams) {
  // Reference before the start of the output.
  EXPECT_NE(test::input_error([] {
              decode({0x20, 0x00}, 3);
            }).find("before the start"),
            std::string::npos);
  // Literal run longer than the remaining stream.
  EXPECT_NE(test::input_error([] { decode({0x05, 'a'}, 6); }).find("truncated"), std::string::npos);
  // Back reference missing its distance byte.
  EXPECT_NE(test::input_error([] {
              decode({0x00, 'a', 0x20}, 4);
            }).find("truncated"),
            std::string::npos);
  // Stream decodes to fewer or more bytes than expected.
  EXPECT_NE(test::input_error([] {
              decode({0x02, 'a', 'b', 'c'}, 4);
            }).find("3 of 4"),
            std::string::npos);
  EXPECT_NE(test::input_error([] {
              decode({0x02, 'a', 'b', 'c'}, 2);
            }).find("overflows"),
            std::string::npos);
}

void expect_round_trip(const Bytes& data) {
  const Bytes packed = lzf_compress(data);
  EXPECT_EQ(reference_decode(packed), data);
  EXPECT_EQ(decode(packed, data.size()), data);
  // Worst case: one control byte per 32 literals.
  EXPECT_LE(packed.size(), data.size() + (data.size() + 31) / 32);
}

TEST(Lzf, RoundTripsRandomData) {
  std::mt19937 rng(7);
  for (std::size_t size : {0u, 1u, 2u, 3u, 4u, 31u, 32u, 33u, 1000u, 100000u}) {
    Bytes data(size);
    for (auto& b : data) b = static_cast<std::uint8_t>(rng());
    expect_round_trip(data);
  }
  // Few distinct bytes: many short matches at every distance.
  Bytes small_alphabet(50000);
  for (auto& b : small_alphabet) b = static_cast<std::uint8_t>('a' + rng() % 3);
  expect_round_trip(small_alphabet);
}

TEST(Lzf, CompressesRepetitiveData) {
  const Bytes zeros(100000, 0);
  expect_round_trip(zeros);
  EXPECT_LT(lzf_compress(zeros).size(), 1500u);  // 264-byte matches: 3 bytes per 264

  Bytes pattern;
  for (int k = 0; k < 20000; ++k) pattern.push_back(static_cast<std::uint8_t>("abcdefg"[k % 7]));
  expect_round_trip(pattern);
  EXPECT_LT(lzf_compress(pattern).size(), pattern.size() / 20);

  // Repeats farther apart than the 8192-byte window must still round-trip.
  std::mt19937 rng(3);
  Bytes block(10000);
  for (auto& b : block) b = static_cast<std::uint8_t>(rng());
  Bytes twice = block;
  twice.insert(twice.end(), block.begin(), block.end());
  expect_round_trip(twice);

  // A float column like those of binary_compressed PCD files.
  Bytes floats;
  for (int k = 0; k < 5000; ++k) {
    const float v = k % 10 == 0 ? std::numeric_limits<float>::quiet_NaN()
                                : 1.5f + 0.001f * static_cast<float>(k % 100);
    std::uint8_t b[4];
    std::memcpy(b, &v, 4);
    floats.insert(floats.end(), b, b + 4);
  }
  expect_round_trip(floats);
}

}  // namespace
}  // namespace ringtrack::io
