// The MCAP container: CRC-32 against its published check value, writer/reader round trips for
// every compression (with and without the worker thread), files without summary or chunks built
// record by record, cut-off files (every complete message and a warning), and bad input (magic,
// CRCs, lengths): one-line errors naming the offset and what was expected.
// The writer's output is also checked by the reference library in
// tests/integration/run_mcap_cli_test.cpp.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "io_test_util.hpp"
#include "ringtrack/core/error.hpp"
#include "ringtrack/io/mcap_format.hpp"
#include "ringtrack/io/mcap_reader.hpp"
#include "ringtrack/io/mcap_writer.hpp"

namespace ringtrack::io {
namespace {

namespace fs = std::filesystem;
using test::TempDir;

std::vector<std::uint8_t> read_all(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// Message k of the test files: its channel and payload (sizes vary, some empty).
struct Sent {
  std::uint16_t channel;
  std::uint64_t time;
  std::vector<std::uint8_t> data;
};

std::vector<Sent> sample_messages(int n) {
  std::vector<Sent> out;
  for (int k = 0; k < n; ++k) {
    Sent s{static_cast<std::uint16_t>(k % 3 == 0 ? 1 : 0),
           1000 + 10 * static_cast<std::uint64_t>(k),
           {}};
    s.data.resize(static_cast<std::size_t>((k * 37) % 300));
    for (std::size_t i = 0; i < s.data.size(); ++i) {
      s.data[i] = static_cast<std::uint8_t>((i * 7 + static_cast<std::size_t>(k)) % 251);
    }
    out.push_back(std::move(s));
  }
  return out;
}

void write_sample(const fs::path& p, const std::vector<Sent>& messages, McapWriterOptions o) {
  McapWriter w(p, o);
  const std::vector<std::uint8_t> text = {'i', 'n', 't', '3', '2', ' ', 'x'};
  const auto s = w.add_schema("pkg/msg/A", "ros2msg", text);
  EXPECT_EQ(s, 1);
  EXPECT_EQ(w.add_channel(s, "/a", "cdr", {{"k", "v"}}), 0);
  EXPECT_EQ(w.add_channel(s, "/b", "cdr"), 1);
  for (const auto& m : messages) w.write_message(m.channel, m.time, m.time + 1, m.data);
  w.write_metadata("info", {{"x", "1"}});
  w.close();
}

std::vector<McapMessage> read_messages(McapReader& r,
                                       std::vector<std::vector<std::uint8_t>>* data) {
  std::vector<McapMessage> out;
  McapMessage m;
  while (r.next(m)) {
    out.push_back(m);
    if (data) data->emplace_back(m.data.begin(), m.data.end());
  }
  return out;
}

TEST(McapFormat, Crc32HasTheIeeeCheckValue) {
  const std::string s = "123456789";
  const auto* p = reinterpret_cast<const std::uint8_t*>(s.data());
  EXPECT_EQ(mcap::crc32({p, s.size()}), 0xCBF43926U);
  // Continued over pieces (the writer's running data section CRC) equals the whole.
  EXPECT_EQ(mcap::crc32({p + 4, 5}, mcap::crc32({p, 4})), 0xCBF43926U);
  std::vector<std::uint8_t> zeros(1000, 0);
  EXPECT_EQ(mcap::crc32(zeros),
            mcap::crc32({zeros.data() + 3, 997}, mcap::crc32({zeros.data(), 3})));
}

struct RoundTripCase {
  McapCompression compression;
  bool background;
  std::size_t chunk_bytes;
};

class McapRoundTrip : public ::testing::TestWithParam<RoundTripCase> {};

TEST_P(McapRoundTrip, ReaderGetsEveryMessageChannelAndCount) {
  TempDir dir;
  const auto messages = sample_messages(200);
  McapWriterOptions o;
  o.compression = GetParam().compression;
  o.background = GetParam().background;
  o.chunk_bytes = GetParam().chunk_bytes;
  write_sample(dir / "a.mcap", messages, o);
  ASSERT_TRUE(is_mcap_file(dir / "a.mcap"));

  for (const bool use_summary : {true, false}) {
    McapReaderOptions ro;
    ro.use_summary = use_summary;
    McapReader r(dir / "a.mcap", ro);
    EXPECT_EQ(r.used_summary(), use_summary);
    ASSERT_EQ(r.channels().size(), 2u);
    EXPECT_EQ(r.channels()[0].topic, "/a");
    EXPECT_EQ(r.channels()[0].metadata, (McapStringMap{{"k", "v"}}));
    ASSERT_NE(r.schema(1), nullptr);
    EXPECT_EQ(r.schema(1)->name, "pkg/msg/A");
    EXPECT_EQ(r.message_count(0), 133u);
    EXPECT_EQ(r.message_count(1), 67u);
    std::vector<std::vector<std::uint8_t>> data;
    const auto got = read_messages(r, &data);
    ASSERT_EQ(got.size(), messages.size());
    for (std::size_t k = 0; k < got.size(); ++k) {
      EXPECT_EQ(got[k].channel_id, messages[k].channel);
      EXPECT_EQ(got[k].log_time_ns, messages[k].time);
      EXPECT_EQ(got[k].publish_time_ns, messages[k].time + 1);
      EXPECT_EQ(data[k], messages[k].data) << "message " << k;
    }
    EXPECT_TRUE(r.warning().empty());
  }
}

INSTANTIATE_TEST_SUITE_P(Compressions, McapRoundTrip,
                         ::testing::Values(RoundTripCase{McapCompression::kNone, false, 1000},
                                           RoundTripCase{McapCompression::kLz4, true, 1000},
                                           RoundTripCase{McapCompression::kZstd, true, 1000},
                                           RoundTripCase{McapCompression::kZstd, false, 1 << 20}));

TEST(McapWriter, DestroyedWithoutCloseLeavesNoFile) {
  TempDir dir;
  {
    McapWriter w(dir / "a.mcap");
    w.add_channel(0, "/a", "json");
    w.write_message(0, 1, 1, std::vector<std::uint8_t>{1, 2, 3});
  }
  EXPECT_FALSE(fs::exists(dir / "a.mcap"));
  EXPECT_THROW(parse_mcap_compression("brotli"), core::ConfigError);
}

// A file without chunks, index or summary, built record by record: a Header, a Schema, a
// Channel and Messages in the data section, a Data End without CRC and an empty Footer.
std::vector<std::uint8_t> unchunked_file(int messages) {
  mcap::Buffer b;
  b.raw(mcap::kMagic);
  auto r = b.begin_record(mcap::Op::kHeader);
  b.string("ros2");
  b.string("hand");
  b.end_record(r);
  r = b.begin_record(mcap::Op::kSchema);
  b.u16(1);
  b.string("pkg/msg/A");
  b.string("ros2msg");
  b.u32(0);
  b.end_record(r);
  r = b.begin_record(mcap::Op::kChannel);
  b.u16(7);
  b.u16(1);
  b.string("/a");
  b.string("cdr");
  b.u32(0);
  b.end_record(r);
  for (int k = 0; k < messages; ++k) {
    r = b.begin_record(mcap::Op::kMessage);
    b.u16(7);
    b.u32(static_cast<std::uint32_t>(k));
    b.u64(static_cast<std::uint64_t>(k));
    b.u64(static_cast<std::uint64_t>(k));
    b.u8(static_cast<std::uint8_t>(k));
    b.end_record(r);
  }
  r = b.begin_record(mcap::Op::kDataEnd);
  b.u32(0);
  b.end_record(r);
  r = b.begin_record(mcap::Op::kFooter);
  b.u64(0);
  b.u64(0);
  b.u32(0);
  b.end_record(r);
  b.raw(mcap::kMagic);
  return {b.bytes().begin(), b.bytes().end()};
}

TEST(McapReader, ReadsFilesWithoutChunksOrSummary) {
  const auto bytes = unchunked_file(5);
  McapReader r(bytes, "hand.mcap");
  EXPECT_FALSE(r.used_summary());
  EXPECT_EQ(r.profile(), "ros2");
  ASSERT_EQ(r.channels().size(), 1u);
  EXPECT_EQ(r.message_count(7), 5u);
  std::vector<std::vector<std::uint8_t>> data;
  const auto got = read_messages(r, &data);
  ASSERT_EQ(got.size(), 5u);
  for (int k = 0; k < 5; ++k)
    EXPECT_EQ(data[static_cast<std::size_t>(k)],
              std::vector<std::uint8_t>{static_cast<std::uint8_t>(k)});
}

TEST(McapReader, ACutOffFileYieldsEveryCompleteMessageAndAWarning) {
  TempDir dir;
  const auto messages = sample_messages(120);
  McapWriterOptions o;
  o.compression = McapCompression::kZstd;
  o.chunk_bytes = 2000;  // many chunks
  write_sample(dir / "full.mcap", messages, o);
  const auto full = read_all(dir / "full.mcap");
  McapReader whole(dir / "full.mcap");
  const auto all = read_messages(whole, nullptr);
  std::size_t previous = 0;
  for (std::size_t cut = 100; cut < full.size() - 1; cut += 997) {
    const std::vector<std::uint8_t> part(full.begin(),
                                         full.begin() + static_cast<std::ptrdiff_t>(cut));
    McapReader r(part, "cut.mcap");
    std::vector<std::vector<std::uint8_t>> data;
    const auto got = read_messages(r, &data);
    // A prefix of the messages: those of the chunks completed before the cut.
    ASSERT_LE(got.size(), all.size());
    EXPECT_GE(got.size(), previous);
    previous = got.size();
    for (std::size_t k = 0; k < got.size(); ++k) EXPECT_EQ(data[k], messages[k].data);
    for (const auto& m : got) EXPECT_LT(m.offset, cut);
    if (got.size() < all.size()) {  // messages lost: the cut is reported
      EXPECT_NE(r.warning().find("cut.mcap: file cut off at offset "), std::string::npos)
          << r.warning();
    }
  }
  EXPECT_GT(previous, 100u);
}

TEST(McapReader, BadInputIsAOneLineErrorNamingTheOffset) {
  TempDir dir;
  const auto messages = sample_messages(50);
  McapWriterOptions o;
  o.compression = McapCompression::kNone;
  write_sample(dir / "a.mcap", messages, o);
  const auto good = read_all(dir / "a.mcap");

  const auto error_of = [](const std::vector<std::uint8_t>& bytes) -> std::string {
    try {
      McapReader r(bytes, "x.mcap");
      McapMessage m;
      while (r.next(m)) {
      }
    } catch (const core::InputError& e) {
      const std::string what = e.what();
      EXPECT_EQ(what.find('\n'), std::string::npos) << what;
      return what;
    }
    return "";
  };

  auto bad = good;
  bad[1] = 'X';
  EXPECT_NE(error_of(bad).find("x.mcap: not an MCAP file (expected the magic"), std::string::npos);

  // A payload byte inside the (uncompressed) chunk: its CRC no longer matches.
  bad = good;
  std::size_t first_chunk = 0;
  for (std::size_t i = 8; i + 9 < good.size();) {
    std::uint64_t len = 0;
    std::memcpy(&len, good.data() + i + 1, 8);
    if (good[i] == 0x06) {
      first_chunk = i;
      break;
    }
    i += 9 + static_cast<std::size_t>(len);
  }
  ASSERT_GT(first_chunk, 0u);
  bad[first_chunk + 200] ^= 0x40;
  const std::string crc = error_of(bad);
  EXPECT_NE(crc.find("x.mcap: Chunk record at offset " + std::to_string(first_chunk) +
                     ": CRC of the uncompressed records is"),
            std::string::npos)
      << crc;

  // A record length beyond the end of a complete file.
  bad = good;
  bad[first_chunk + 8] = 0x7F;
  const std::string past = error_of(bad);
  EXPECT_NE(past.find("record at offset " + std::to_string(first_chunk)), std::string::npos)
      << past;
  EXPECT_NE(past.find("runs past the end of the file"), std::string::npos) << past;

  // A summary byte: the summary CRC catches it.
  bad = good;
  bad[good.size() - 8 - 29 - 20] ^= 0x01;
  EXPECT_NE(error_of(bad).find("CRC"), std::string::npos);

  // The data section CRC covers the message indexes, which the reader otherwise skips.
  bad = good;
  std::size_t index_at = 0;
  for (std::size_t i = 8; i + 9 < good.size();) {
    std::uint64_t len = 0;
    std::memcpy(&len, good.data() + i + 1, 8);
    if (good[i] == 0x07) {
      index_at = i;
      break;
    }
    i += 9 + static_cast<std::size_t>(len);
  }
  ASSERT_GT(index_at, 0u);
  bad[index_at + 20] ^= 0x01;
  const std::string data_crc = error_of(bad);
  EXPECT_NE(data_crc.find("Data End record at offset"), std::string::npos) << data_crc;
  EXPECT_NE(data_crc.find("data section CRC"), std::string::npos) << data_crc;

  // Truncated fields inside a record: the field and what was left are named.
  auto hand = unchunked_file(1);
  hand[8 + 1] = 3;  // Header length 3: its profile string needs 4 bytes
  for (int i = 2; i < 9; ++i) hand[static_cast<std::size_t>(8 + i)] = 0;
  const std::string field = error_of(hand);
  EXPECT_NE(field.find("Header record at offset 8"), std::string::npos) << field;
}

}  // namespace
}  // namespace ringtrack::io
