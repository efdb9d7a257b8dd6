// libFuzzer target: PCD bytes (ascii, binary, binary_compressed) through decode_pcd, with the
// default options and with organizing of unorganized clouds by ring (top row first), then the
// column azimuth estimate; and the input as a raw LZF stream. Oracle: an accepted scan encodes
// (every encoding) to PCD that decodes back to the same shape.
#include <cstdint>
#include <span>
#include <vector>

#include "fuzz_support.hpp"
#include "ringtrack/io/lzf.hpp"
#include "ringtrack/io/pcd.hpp"

using namespace ringtrack;

namespace {

void round_trip(const io::PcdScan& read) {
  for (const auto encoding :
       {io::PcdEncoding::kAscii, io::PcdEncoding::kBinary, io::PcdEncoding::kBinaryCompressed}) {
    const std::string pcd = io::encode_pcd(read.scan, read.labels, encoding);
    fuzz::must_succeed([&] {
      const io::PcdScan again =
          io::decode_pcd(std::span(reinterpret_cast<const std::uint8_t*>(pcd.data()), pcd.size()),
                         "encoded.pcd", {.row_order = io::PcdRowOrder::kBottomFirst});
      fuzz::require(again.scan.rings() == read.scan.rings() &&
                        again.scan.columns() == read.scan.columns() &&
                        again.labels.size() == read.labels.size(),
                    "pcd round trip shape");
    });
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::span<const std::uint8_t> bytes(data, size);
  fuzz::expect_errors([&] {
    io::PcdScan read = io::decode_pcd(bytes, "fuzz.pcd");
    io::estimate_column_azimuths(read.scan);
    round_trip(read);
  });
  fuzz::expect_errors([&] {
    io::PcdReadOptions options;
    options.row_order = io::PcdRowOrder::kTopFirst;
    options.organize_columns = 64;
    io::PcdScan read = io::decode_pcd(bytes, "fuzz.pcd", options);
    io::estimate_column_azimuths(read.scan);
  });
  fuzz::expect_errors([&] {
    std::vector<std::uint8_t> out(4 * size + 16);
    io::lzf_decompress(bytes, out);
  });
  return 0;
}
