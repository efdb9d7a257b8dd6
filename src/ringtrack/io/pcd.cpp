#include "ringtrack/io/pcd.hpp"

#include <algorithm>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstring>
#include <limits>
#include <numbers>
#include <optional>

#include "ringtrack/core/error.hpp"
#include "ringtrack/io/lzf.hpp"
#include "ringtrack/io/output_file.hpp"
#include "ringtrack/io/text.hpp"

namespace ringtrack::io {
namespace {

// PCL writes binary PCD in the host's byte order, which is little-endian on every platform it
// runs on in practice; this reader and writer assume the same.
static_assert(std::endian::native == std::endian::little, "PCD binary I/O assumes little-endian");

constexpr double kTwoPi = 2.0 * std::numbers::pi;
// Organizing more rings than any spinning LiDAR has means the ring field is not a ring index.
constexpr std::int64_t kMaxRings = 1024;

[[noreturn]] void fail(const std::string& name, const std::string& what) {
  throw core::InputError(name + ": " + what);
}

// Quotes a header token for an error message, cut short and with control bytes replaced, so
// binary garbage cannot produce an unreadable message.
std::string quoted(std::string_view token) {
  std::string out = "'";
  for (char c : token.substr(0, 32)) {
    out.push_back(c >= 32 && c < 127 ? c : '?');
  }
  if (token.size() > 32) out += "...";
  return out + "'";
}

std::size_t parse_count(std::string_view token, const std::string& where, std::string_view key,
                        std::int64_t min_value) {
  // Bounded so that WIDTH and HEIGHT fit an int and WIDTH * HEIGHT * record size cannot overflow.
  constexpr std::int64_t kMax = (std::int64_t{1} << 31) - 1;
  const auto v = parse_int(token);
  if (!v || *v < min_value || *v > kMax) {
    fail(where, std::string(key) + " expects an integer in [" + std::to_string(min_value) + ", " +
                    std::to_string(kMax) + "], got " + quoted(token));
  }
  return static_cast<std::size_t>(*v);
}

std::optional<double> parse_float(std::string_view token) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  float value = 0.0f;
  const auto [ptr, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
  // Out-of-range magnitudes fall back to double parsing (and become inf when narrowed later).
  if (ec == std::errc::result_out_of_range) return parse_double(token);
  if (ec != std::errc() || ptr != token.data() + token.size()) return std::nullopt;
  return value;
}

double load(const std::uint8_t* p, char type, int size) {
  switch (type) {
    case 'F':
      if (size == 4) {
        float v;
        std::memcpy(&v, p, 4);
        return v;
      } else {
        double v;
        std::memcpy(&v, p, 8);
        return v;
      }
    case 'U':
      switch (size) {
        case 1:
          return p[0];
        case 2: {
          std::uint16_t v;
          std::memcpy(&v, p, 2);
          return v;
        }
        case 4: {
          std::uint32_t v;
          std::memcpy(&v, p, 4);
          return v;
        }
        default: {
          std::uint64_t v;
          std::memcpy(&v, p, 8);
          return static_cast<double>(v);
        }
      }
    default:
      switch (size) {
        case 1: {
          std::int8_t v;
          std::memcpy(&v, p, 1);
          return v;
        }
        case 2: {
          std::int16_t v;
          std::memcpy(&v, p, 2);
          return v;
        }
        case 4: {
          std::int32_t v;
          std::memcpy(&v, p, 4);
          return v;
        }
        default: {
          std::int64_t v;
          std::memcpy(&v, p, 8);
          return static_cast<double>(v);
        }
      }
  }
}

// Strided view of one field's first element across all points, whatever the encoding.
struct Column {
  const std::uint8_t* base{nullptr};
  std::size_t stride{0};
  char type{'F'};
  int size{8};
  [[nodiscard]] double at(std::size_t i) const { return load(base + i * stride, type, size); }
};

// Decoded data of the fields we use; owns the buffers the columns point into.
struct Data {
  std::vector<std::uint8_t> decompressed;
  std::vector<std::vector<double>> ascii;
};

Column binary_column(const std::uint8_t* data, const PcdHeader& h, const PcdField& f) {
  return {data + f.offset, h.point_bytes(), f.type, f.size};
}

// The binary layout is point-major: each field's column is a stride through the file's bytes.
std::vector<Column> binary_columns(std::span<const std::uint8_t> bytes, const PcdHeader& h,
                                   const std::string& name,
                                   const std::vector<const PcdField*>& wanted) {
  const std::size_t n = h.points();
  const std::size_t record = h.point_bytes();
  const std::size_t available = bytes.size() - h.data_offset;
  if (available / record < n) {
    fail(name, "truncated binary data: expected " + std::to_string(n) + " points of " +
                   std::to_string(record) + " bytes (" + std::to_string(n * record) +
                   " bytes) after the header at offset " + std::to_string(h.data_offset) +
                   ", found " + std::to_string(available) + " bytes");
  }
  std::vector<Column> columns;
  for (const auto* f : wanted)
    columns.push_back(binary_column(bytes.data() + h.data_offset, h, *f));
  return columns;
}

// Checks the size prefix against the header and the file before anything is allocated, then
// decompresses into data.decompressed.
void decompress_pcd_data(std::span<const std::uint8_t> bytes, const PcdHeader& h,
                         const std::string& name, Data& data) {
  const std::size_t n = h.points();
  const std::size_t record = h.point_bytes();
  const std::size_t available = bytes.size() - h.data_offset;
  if (available < 8) {
    fail(name, "truncated binary_compressed data: expected the 8-byte size prefix at offset " +
                   std::to_string(h.data_offset));
  }
  std::uint32_t compressed = 0;
  std::uint32_t uncompressed = 0;
  std::memcpy(&compressed, bytes.data() + h.data_offset, 4);
  std::memcpy(&uncompressed, bytes.data() + h.data_offset + 4, 4);
  if (n > std::numeric_limits<std::uint32_t>::max() / record || uncompressed != n * record) {
    fail(name, "binary_compressed data declares " + std::to_string(uncompressed) +
                   " uncompressed bytes, expected " + std::to_string(n) + " points x " +
                   std::to_string(record) + " bytes = " + std::to_string(n * record));
  }
  if (compressed > available - 8) {
    fail(name, "truncated binary_compressed data: expected " + std::to_string(compressed) +
                   " compressed bytes at offset " + std::to_string(h.data_offset + 8) + ", found " +
                   std::to_string(available - 8));
  }
  // Refused before it is allocated: a header's point count and size prefix are easy to make
  // agree, but no LZF stream decodes to more than kLzfMaxExpansion times its own size.
  if (static_cast<std::uint64_t>(compressed) * kLzfMaxExpansion < uncompressed) {
    fail(name, "binary_compressed data declares " + std::to_string(uncompressed) +
                   " uncompressed bytes, more than " + std::to_string(compressed) +
                   " compressed bytes can hold (at most " + std::to_string(kLzfMaxExpansion) +
                   " times as many)");
  }
  data.decompressed.resize(uncompressed);
  try {
    lzf_decompress(bytes.subspan(h.data_offset + 8, compressed), data.decompressed);
  } catch (const core::InputError& e) {
    fail(name, std::string("corrupt binary_compressed data (") + e.what() +
                   ", stream starts at file offset " + std::to_string(h.data_offset + 8) + ")");
  }
}

std::vector<Column> compressed_columns(std::span<const std::uint8_t> bytes, const PcdHeader& h,
                                       const std::string& name,
                                       const std::vector<const PcdField*>& wanted, Data& data) {
  decompress_pcd_data(bytes, h, name, data);
  const std::size_t n = h.points();
  // Field-major layout: all points' bytes of field 0, then of field 1, ...
  std::vector<Column> columns;
  for (const auto* f : wanted) {
    std::size_t start = 0;
    for (const auto& g : h.fields) {
      if (&g == f) break;
      start += n * g.bytes();
    }
    columns.push_back({data.decompressed.data() + start, f->bytes(), f->type, f->size});
  }
  return columns;
}

// Parses the ascii point lines into data.ascii, one vector of doubles per wanted field.
void parse_ascii_points(std::span<const std::uint8_t> bytes, const PcdHeader& h,
                        const std::string& name, const std::vector<const PcdField*>& wanted,
                        Data& data) {
  const std::size_t n = h.points();
  const std::size_t available = bytes.size() - h.data_offset;
  std::vector<std::size_t> token_of;  // token index of each wanted field
  std::size_t tokens_per_point = 0;
  for (const auto* f : wanted) {
    std::size_t t = 0;
    for (const auto& g : h.fields) {
      if (&g == f) break;
      t += static_cast<std::size_t>(g.count);
    }
    token_of.push_back(t);
  }
  for (const auto& g : h.fields) tokens_per_point += static_cast<std::size_t>(g.count);
  // Grown line by line rather than sized from POINTS, so a header claiming billions of points
  // in a small file cannot exhaust memory; every value needs at least two bytes.
  data.ascii.assign(wanted.size(), {});
  for (auto& v : data.ascii) v.reserve(std::min(n, available / (2 * tokens_per_point) + 1));
  std::size_t point = 0;
  std::size_t line_no = h.header_lines;
  std::size_t pos = h.data_offset;
  while (pos < bytes.size()) {
    std::size_t end = pos;
    while (end < bytes.size() && bytes[end] != '\n') ++end;
    ++line_no;
    const std::string_view line(reinterpret_cast<const char*>(bytes.data()) + pos, end - pos);
    pos = end + 1;
    const auto tokens = split_tokens(line);
    if (tokens.empty()) continue;
    const std::string where = "line " + std::to_string(line_no);
    if (point == n) {
      fail(name, where + ": more point lines than POINTS/WIDTH*HEIGHT = " + std::to_string(n));
    }
    if (tokens.size() != tokens_per_point) {
      fail(name, where + ": expected " + std::to_string(tokens_per_point) + " values, got " +
                     std::to_string(tokens.size()));
    }
    for (std::size_t k = 0; k < wanted.size(); ++k) {
      // F4 values straight to float: decimal -> double -> float can round twice.
      const auto v = wanted[k]->type == 'F' && wanted[k]->size == 4
                         ? parse_float(tokens[token_of[k]])
                         : parse_double(tokens[token_of[k]]);
      if (!v) {
        fail(name, where + ", field '" + wanted[k]->name + "': expected a number, got " +
                       quoted(tokens[token_of[k]]));
      }
      data.ascii[k].push_back(*v);
    }
    ++point;
  }
  if (point != n) {
    fail(name, "truncated ascii data: expected " + std::to_string(n) + " point lines, found " +
                   std::to_string(point));
  }
}

std::vector<Column> ascii_columns(std::span<const std::uint8_t> bytes, const PcdHeader& h,
                                  const std::string& name,
                                  const std::vector<const PcdField*>& wanted, Data& data) {
  parse_ascii_points(bytes, h, name, wanted, data);
  std::vector<Column> columns;
  for (const auto& v : data.ascii) {
    columns.push_back({reinterpret_cast<const std::uint8_t*>(v.data()), sizeof(double), 'F', 8});
  }
  return columns;
}

// One column per wanted field, in that order, whatever the encoding; data owns what they point
// into.
std::vector<Column> load_columns(std::span<const std::uint8_t> bytes, const PcdHeader& h,
                                 const std::string& name,
                                 const std::vector<const PcdField*>& wanted, Data& data) {
  switch (h.encoding) {
    case PcdEncoding::kBinary:
      return binary_columns(bytes, h, name, wanted);
    case PcdEncoding::kBinaryCompressed:
      return compressed_columns(bytes, h, name, wanted, data);
    case PcdEncoding::kAscii:
      return ascii_columns(bytes, h, name, wanted, data);
  }
  return {};
}

// An unsigned integer value of an integer field (labels, rings), or an error naming the point.
std::uint32_t integral_value(double v, std::uint64_t max, const std::string& name,
                             const std::string& field, std::size_t point) {
  if (!(v >= 0.0) || v > static_cast<double>(max) || std::floor(v) != v) {
    std::string text;
    append_fixed(text, v, 3);
    fail(name, "point " + std::to_string(point) + ": " + field + " value " + text +
                   " is not an integer in [0, " + std::to_string(max) + "]");
  }
  return static_cast<std::uint32_t>(v);
}

bool is_return(double x, double y, double z) {
  // Drivers mark missing returns with NaN or with the origin; both are no return here.
  return std::isfinite(x) && std::isfinite(y) && std::isfinite(z) &&
         (x != 0.0 || y != 0.0 || z != 0.0);
}

// Decides whether rows must be reversed so that row 0 is the bottom ring, from each row's sum
// of sin(elevation) over its points.
bool rows_need_flip(PcdRowOrder order, const std::vector<double>& elevation_sum,
                    const std::vector<std::size_t>& elevation_count) {
  if (order == PcdRowOrder::kBottomFirst) return false;
  if (order == PcdRowOrder::kTopFirst) return true;
  std::optional<double> first;
  std::optional<double> last;
  for (std::size_t r = 0; r < elevation_sum.size(); ++r) {
    if (elevation_count[r] == 0) continue;
    const double mean = elevation_sum[r] / static_cast<double>(elevation_count[r]);
    if (!first) first = mean;
    last = mean;
  }
  return first && last && *first > *last;
}

double wrap_pi(double a) {
  a = std::remainder(a, kTwoPi);
  return a <= -std::numbers::pi ? a + kTwoPi : a;
}

double wrap_two_pi(double a) {
  a = std::fmod(a, kTwoPi);
  return a < 0.0 ? a + kTwoPi : a;
}

void append_bytes(std::string& out, const void* p, std::size_t n) {
  out.append(static_cast<const char*>(p), n);
}

// The fields decode_pcd reads; intensity and label are optional, ring only for unorganized clouds.
struct ScanFields {
  const PcdField* x{nullptr};
  const PcdField* y{nullptr};
  const PcdField* z{nullptr};
  const PcdField* intensity{nullptr};
  const PcdField* label{nullptr};
  const PcdField* ring{nullptr};
};

// Finds the fields in the header, and refuses what the scan cannot be built from, naming the
// fields the file has.
ScanFields find_scan_fields(const PcdHeader& h, const std::string& name,
                            const PcdReadOptions& options) {
  std::string field_list;
  for (const auto& f : h.fields) field_list += (field_list.empty() ? "" : " ") + f.name;
  const auto require = [&](const char* field) {
    const PcdField* f = h.find(field);
    if (f == nullptr) {
      fail(name, std::string("missing field '") + field +
                     "' (expected fields x y z, optionally intensity and label; found " +
                     field_list + ")");
    }
    return f;
  };
  const auto single = [&](const PcdField* f) {
    if (f != nullptr && f->count != 1) {
      fail(name, "field '" + f->name + "' has COUNT " + std::to_string(f->count) + ", expected 1");
    }
    return f;
  };
  ScanFields s;
  s.x = single(require("x"));
  s.y = single(require("y"));
  s.z = single(require("z"));
  s.intensity = single(h.find("intensity"));
  s.label = single(h.find("label"));
  if (s.label != nullptr && s.label->type == 'F') {
    fail(name, "field 'label' has TYPE F, expected an integer type (U or I)");
  }
  if (h.height <= 1) {  // unorganized
    if (options.organize_columns <= 0) {
      fail(name, "unorganized cloud (HEIGHT 1, WIDTH " + std::to_string(h.width) +
                     "): expected an organized cloud with HEIGHT = rings and WIDTH = columns");
    }
    s.ring = single(h.find(options.ring_field));
    if (s.ring == nullptr) {
      fail(name, "unorganized cloud (HEIGHT 1) without a '" + options.ring_field +
                     "' field: cannot organize it by ring (found " + field_list + ")");
    }
  }
  return s;
}

// The loaded columns of ScanFields; the optional ones are null when the field is absent.
struct ScanColumns {
  const Column& x;
  const Column& y;
  const Column& z;
  const Column* intensity;
  const Column* label;
  const Column* ring;
};

// Row (file row for organized clouds, ring value otherwise) of each point, and the number of
// rows, to decide the row order before filling the scan.
std::size_t assign_rows(const PcdHeader& h, const std::string& name, const PcdReadOptions& options,
                        const ScanFields& fields, const ScanColumns& c,
                        std::vector<std::uint32_t>& row) {
  const std::size_t n = h.points();
  if (h.height > 1) {
    for (std::size_t i = 0; i < n; ++i) row[i] = static_cast<std::uint32_t>(i / h.width);
    return h.height;
  }
  std::uint32_t max_ring = 0;
  for (std::size_t i = 0; i < n; ++i) {
    row[i] = integral_value(c.ring->at(i), kMaxRings - 1, name, "'" + fields.ring->name + "'", i);
    max_ring = std::max(max_ring, row[i]);
  }
  const std::size_t rows = options.organize_rings > 0
                               ? static_cast<std::size_t>(options.organize_rings)
                               : std::size_t{max_ring} + 1;
  if (max_ring >= rows) {
    fail(name, "ring value " + std::to_string(max_ring) + " is outside [0, " +
                   std::to_string(rows) + ") rings");
  }
  return rows;
}

// Each row's elevation from its returns, for rows_need_flip (PcdRowOrder::kAuto reads it).
bool decide_row_flip(PcdRowOrder order, const ScanColumns& c, const std::vector<std::uint32_t>& row,
                     std::size_t rows) {
  std::vector<double> elevation_sum(rows, 0.0);
  std::vector<std::size_t> elevation_count(rows, 0);
  for (std::size_t i = 0; i < row.size(); ++i) {
    const double x = c.x.at(i);
    const double y = c.y.at(i);
    const double z = c.z.at(i);
    if (!is_return(x, y, z)) continue;
    // sin(elevation) orders rows like the elevation itself, without an atan2 per point.
    elevation_sum[row[i]] += z / std::sqrt(x * x + y * y + z * z);
    ++elevation_count[row[i]];
  }
  return rows_need_flip(order, elevation_sum, elevation_count);
}

// Puts every point in its cell: organized clouds by file position, unorganized ones by ring and
// azimuth, keeping the nearer of two points in one cell.
void fill_scan(const PcdHeader& h, const std::string& name, const ScanColumns& c,
               const std::vector<std::uint32_t>& row, std::size_t rows, int columns_out,
               PcdScan& out) {
  const bool organized = h.height > 1;
  const double step = kTwoPi / columns_out;
  const auto ring_of_row = [&](std::size_t r) {
    return static_cast<int>(out.rows_flipped ? rows - 1 - r : r);
  };
  for (std::size_t i = 0; i < row.size(); ++i) {
    const double x = c.x.at(i);
    const double y = c.y.at(i);
    const double z = c.z.at(i);
    const int ring = ring_of_row(row[i]);
    const bool hit = is_return(x, y, z);
    int column = 0;
    if (organized) {
      column = static_cast<int>(i % h.width);
    } else {
      if (!hit) continue;  // an unorganized cloud's missing returns carry no cell
      column = std::min(columns_out - 1, static_cast<int>(wrap_two_pi(std::atan2(y, x)) / step));
    }
    const std::size_t cell = out.scan.index(ring, column);
    const Eigen::Vector3f p(static_cast<float>(x), static_cast<float>(y), static_cast<float>(z));
    const auto range = static_cast<float>(std::sqrt(x * x + y * y + z * z));
    if (!organized && out.scan.valid(cell)) {
      // Dual returns and azimuth jitter put two points in one cell: keep the nearer one.
      ++out.dropped_points;
      if (out.scan.range_m(cell) <= range) continue;
    }
    if (hit) {
      double intensity = c.intensity != nullptr ? c.intensity->at(i) : 0.0;
      if (!std::isfinite(intensity)) intensity = 0.0;
      out.scan.set_return(ring, column, range, static_cast<float>(intensity), p);
    } else {
      out.scan.set_invalid(ring, column, core::ReturnStatus::kNoReturn);
    }
    if (c.label != nullptr) {
      out.labels[cell] = integral_value(c.label->at(i), std::numeric_limits<std::uint32_t>::max(),
                                        name, "label", i);
    }
  }
}

}  // namespace

std::size_t PcdHeader::point_bytes() const {
  std::size_t total = 0;
  for (const auto& f : fields) total += f.bytes();
  return total;
}

const PcdField* PcdHeader::find(std::string_view name) const {
  for (const auto& f : fields) {
    if (f.name == name) return &f;
  }
  return nullptr;
}

std::string_view to_string(PcdEncoding encoding) {
  switch (encoding) {
    case PcdEncoding::kAscii:
      return "ascii";
    case PcdEncoding::kBinary:
      return "binary";
    case PcdEncoding::kBinaryCompressed:
      return "binary_compressed";
  }
  return "binary";
}

namespace {

// A header's lines as read, before they are checked against each other.
struct PcdHeaderLines {
  std::vector<std::string_view> names;
  std::vector<std::string_view> sizes;
  std::vector<std::string_view> types;
  std::vector<std::string_view> counts;
  bool have_width = false;
  bool have_height = false;
  bool have_data = false;
  std::optional<std::size_t> points;
};

PcdEncoding parse_data_line(const std::vector<std::string_view>& rest, const std::string& where) {
  if (rest.size() != 1) fail(where, "DATA expects one of ascii, binary, binary_compressed");
  if (rest[0] == "ascii") return PcdEncoding::kAscii;
  if (rest[0] == "binary") return PcdEncoding::kBinary;
  if (rest[0] == "binary_compressed") return PcdEncoding::kBinaryCompressed;
  fail(where, "unknown DATA " + quoted(rest[0]) + " (expected ascii, binary or binary_compressed)");
}

// WIDTH, HEIGHT or POINTS.
void read_dimension_line(std::string_view key, const std::vector<std::string_view>& rest,
                         const std::string& where, PcdHeaderLines& lines, PcdHeader& h) {
  if (rest.size() != 1) fail(where, std::string(key) + " expects one integer");
  const std::size_t v = parse_count(rest[0], where, key, key == "POINTS" ? 0 : 1);
  if (key == "WIDTH") {
    h.width = v;
    lines.have_width = true;
  } else if (key == "HEIGHT") {
    h.height = v;
    lines.have_height = true;
  } else {
    lines.points = v;
  }
}

// One header line, its keyword and values, into lines and h.
void read_header_line(std::string_view key, const std::vector<std::string_view>& rest,
                      const std::string& where, PcdHeaderLines& lines, PcdHeader& h) {
  if (key == "VERSION") {
    // 0.7 is the current version; older files with the same keywords read the same way.
  } else if (key == "FIELDS" || key == "COLUMNS") {
    lines.names = rest;
  } else if (key == "SIZE") {
    lines.sizes = rest;
  } else if (key == "TYPE") {
    lines.types = rest;
  } else if (key == "COUNT") {
    lines.counts = rest;
  } else if (key == "WIDTH" || key == "HEIGHT" || key == "POINTS") {
    read_dimension_line(key, rest, where, lines, h);
  } else if (key == "VIEWPOINT") {
    if (rest.size() != 7) fail(where, "VIEWPOINT expects 7 numbers (tx ty tz qw qx qy qz)");
  } else if (key == "DATA") {
    h.encoding = parse_data_line(rest, where);
    lines.have_data = true;
  } else {
    fail(where, "unknown header keyword " + quoted(key) + " (not a PCD v0.7 file?)");
  }
}

void require_one_value_per_field(const std::vector<std::string_view>& values, const char* key,
                                 std::size_t fields, const std::string& name) {
  if (values.size() != fields) {
    fail(name, std::string(key) + " lists " + std::to_string(values.size()) + " values for " +
                   std::to_string(fields) + " FIELDS");
  }
}

// The lines against each other: every per-field line as long as FIELDS, the dimensions given.
void check_header_lines(const PcdHeaderLines& lines, const PcdHeader& h, const std::string& name) {
  if (!lines.have_data) fail(name, "no DATA line: not a PCD file, or its header is truncated");
  if (lines.names.empty()) fail(name, "header has no FIELDS");
  require_one_value_per_field(lines.sizes, "SIZE", lines.names.size(), name);
  require_one_value_per_field(lines.types, "TYPE", lines.names.size(), name);
  if (!lines.counts.empty()) {
    require_one_value_per_field(lines.counts, "COUNT", lines.names.size(), name);
  }
  if (!lines.have_width) fail(name, "header has no WIDTH");
  if (!lines.have_height) fail(name, "header has no HEIGHT");
  if (lines.points && *lines.points != h.width * h.height) {
    fail(name, "POINTS " + std::to_string(*lines.points) + " does not equal WIDTH * HEIGHT = " +
                   std::to_string(h.width) + " * " + std::to_string(h.height));
  }
}

// Field k of the checked lines (its offset is left to the caller).
PcdField parse_field(const PcdHeaderLines& lines, std::size_t k, const std::string& name) {
  PcdField f;
  f.name = std::string(lines.names[k]);
  const std::string what = "field '" + f.name + "'";
  const std::string_view type = lines.types[k];
  if (type.size() != 1 || (type[0] != 'F' && type[0] != 'U' && type[0] != 'I')) {
    fail(name, what + ": unknown TYPE " + quoted(type) + " (expected F, U or I)");
  }
  f.type = type[0];
  const auto size = parse_int(lines.sizes[k]);
  const bool size_ok =
      size && (*size == 4 || *size == 8 || (f.type != 'F' && (*size == 1 || *size == 2)));
  if (!size_ok) {
    fail(name, what + ": unsupported SIZE " + quoted(lines.sizes[k]) + " for TYPE " + f.type +
                   " (expected F4, F8, U1/U2/U4/U8 or I1/I2/I4/I8)");
  }
  f.size = static_cast<int>(*size);
  if (!lines.counts.empty()) {
    const auto count = parse_int(lines.counts[k]);
    if (!count || *count < 1 || *count > 65536) {
      fail(name, what + ": COUNT " + quoted(lines.counts[k]) + " is not an integer in [1, 65536]");
    }
    f.count = static_cast<int>(*count);
  }
  return f;
}

}  // namespace

// Reads the header's lines in the order the PCD format fixes (VERSION ... DATA), each with its own
// check and message, then checks them against each other (docs/formats.md, "PCD files").
PcdHeader parse_pcd_header(std::span<const std::uint8_t> bytes, const std::string& name) {
  PcdHeader h;
  PcdHeaderLines lines;
  std::size_t pos = 0;
  std::size_t line_no = 0;
  while (pos < bytes.size() && !lines.have_data) {
    std::size_t end = pos;
    while (end < bytes.size() && bytes[end] != '\n') ++end;
    const std::string_view line(reinterpret_cast<const char*>(bytes.data()) + pos, end - pos);
    pos = std::min(end + 1, bytes.size());
    ++line_no;
    const auto tokens = split_tokens(line);
    if (tokens.empty() || tokens.front().front() == '#') continue;
    const std::string where = name + ": header line " + std::to_string(line_no);
    const std::vector<std::string_view> rest(tokens.begin() + 1, tokens.end());
    read_header_line(tokens.front(), rest, where, lines, h);
    if (lines.have_data) {
      h.data_offset = pos;
      h.header_lines = line_no;
    }
  }
  check_header_lines(lines, h, name);
  std::size_t offset = 0;
  for (std::size_t k = 0; k < lines.names.size(); ++k) {
    PcdField f = parse_field(lines, k, name);
    f.offset = offset;
    offset += f.bytes();
    h.fields.push_back(std::move(f));
  }
  return h;
}

PcdScan decode_pcd(std::span<const std::uint8_t> bytes, const std::string& name,
                   const PcdReadOptions& options) {
  const PcdHeader h = parse_pcd_header(bytes, name);
  const ScanFields fields = find_scan_fields(h, name, options);
  std::vector<const PcdField*> wanted{fields.x, fields.y, fields.z};
  if (fields.intensity != nullptr) wanted.push_back(fields.intensity);
  if (fields.label != nullptr) wanted.push_back(fields.label);
  if (fields.ring != nullptr) wanted.push_back(fields.ring);
  Data data;
  const auto columns = load_columns(bytes, h, name, wanted, data);
  std::size_t next = 3;
  const Column* ci = fields.intensity != nullptr ? &columns[next++] : nullptr;
  const Column* cl = fields.label != nullptr ? &columns[next++] : nullptr;
  const Column* cr = fields.ring != nullptr ? &columns[next++] : nullptr;
  const ScanColumns c{columns[0], columns[1], columns[2], ci, cl, cr};

  const bool organized = h.height > 1;
  PcdScan out;
  std::vector<std::uint32_t> row(h.points());
  const std::size_t rows = assign_rows(h, name, options, fields, c, row);
  out.rows_flipped = decide_row_flip(options.row_order, c, row, rows);

  const int columns_out = organized ? static_cast<int>(h.width) : options.organize_columns;
  out.scan = core::OrganizedScan(static_cast<int>(rows), columns_out);
  if (cl != nullptr) out.labels.assign(out.scan.size(), 0);
  fill_scan(h, name, c, row, rows, columns_out, out);
  if (organized) {
    estimate_column_azimuths(out.scan);
  } else {
    const double step = kTwoPi / columns_out;
    for (int col = 0; col < columns_out; ++col) {
      out.scan.column_azimuth_rad[static_cast<std::size_t>(col)] = (col + 0.5) * step;
    }
  }
  return out;
}

core::UnorganizedCloud decode_pcd_cloud(std::span<const std::uint8_t> bytes,
                                        const std::string& name) {
  const PcdHeader h = parse_pcd_header(bytes, name);
  std::string field_list;
  for (const auto& f : h.fields) field_list += (field_list.empty() ? "" : " ") + f.name;
  std::vector<const PcdField*> wanted;
  for (const char* field : {"x", "y", "z", "intensity"}) {
    const PcdField* f = h.find(field);
    if (f == nullptr && field[0] != 'i') {
      fail(name, std::string("missing field '") + field +
                     "' (expected fields x y z, optionally intensity; found " + field_list + ")");
    }
    if (f != nullptr && f->count != 1) {
      fail(name, "field '" + f->name + "' has COUNT " + std::to_string(f->count) + ", expected 1");
    }
    if (f != nullptr) wanted.push_back(f);
  }
  Data data;
  const auto columns = load_columns(bytes, h, name, wanted, data);
  const std::size_t n = h.points();
  core::UnorganizedCloud cloud;
  cloud.xyz.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    cloud.xyz[i] =
        Eigen::Vector3f(static_cast<float>(columns[0].at(i)), static_cast<float>(columns[1].at(i)),
                        static_cast<float>(columns[2].at(i)));
  }
  if (wanted.size() > 3) {
    cloud.intensity.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      const double v = columns[3].at(i);
      cloud.intensity[i] = std::isfinite(v) ? static_cast<float>(v) : 0.0f;
    }
  }
  return cloud;
}

bool pcd_needs_organizer(const PcdHeader& header, const std::string& ring_field) {
  return header.height <= 1 && header.find(ring_field) == nullptr;
}

PcdScan read_pcd(const std::filesystem::path& path, const PcdReadOptions& options) {
  const auto bytes = read_file_bytes(path);
  return decode_pcd(bytes, path.string(), options);
}

void estimate_column_azimuths(core::OrganizedScan& scan) {
  const auto columns = static_cast<std::size_t>(scan.columns());
  const double step = kTwoPi / static_cast<double>(columns);
  std::vector<double> sum_cos(columns, 0.0);
  std::vector<double> sum_sin(columns, 0.0);
  std::vector<bool> known(columns, false);
  for (std::size_t i = 0; i < scan.size(); ++i) {
    if (!scan.valid(i)) continue;
    const double x = scan.xs()[i];
    const double y = scan.ys()[i];
    if (x == 0.0 && y == 0.0) continue;
    const auto c = static_cast<std::size_t>(scan.column_of(i));
    // Points of one column share their azimuth, so the vector sum (weighted by horizontal
    // distance) points the same way as the mean of unit vectors, without a division per point.
    sum_cos[c] += x;
    sum_sin[c] += y;
    known[c] = true;
  }
  auto& az = scan.column_azimuth_rad;
  std::vector<std::size_t> ks;
  for (std::size_t c = 0; c < columns; ++c) {
    if (known[c]) {
      az[c] = wrap_two_pi(std::atan2(sum_sin[c], sum_cos[c]));
      ks.push_back(c);
    }
  }
  if (ks.empty()) {
    for (std::size_t c = 0; c < columns; ++c) az[c] = static_cast<double>(c) * step;
    return;
  }
  // Direction of the column order (counter-clockwise or clockwise) by majority of neighbours.
  int votes = 0;
  for (std::size_t j = 0; j + 1 < ks.size(); ++j) {
    const double d = wrap_pi(az[ks[j + 1]] - az[ks[j]]);
    votes += d > 0 ? 1 : (d < 0 ? -1 : 0);
  }
  const double sign = votes >= 0 ? 1.0 : -1.0;
  for (std::size_t j = 0; j < ks.size(); ++j) {
    const std::size_t a = ks[j];
    const std::size_t b = j + 1 < ks.size() ? ks[j + 1] : ks[0] + columns;
    const std::size_t gap = b - a;
    if (gap <= 1) continue;
    // Of the turns that reach b's azimuth, take the one closest to uniform steps.
    double d = wrap_pi(az[b % columns] - az[a]);
    const double expected = sign * static_cast<double>(gap) * step;
    d += kTwoPi * std::round((expected - d) / kTwoPi);
    for (std::size_t m = 1; m < gap; ++m) {
      az[(a + m) % columns] =
          wrap_two_pi(az[a] + d * static_cast<double>(m) / static_cast<double>(gap));
    }
  }
}

namespace {

// The fields of a cloud to encode, one array per field (labels may be empty).
struct PcdFields {
  std::span<const float> xs, ys, zs, intensities;
  std::span<const std::uint32_t> labels;
  std::size_t width{0}, height{0};
};

std::string fields_header(std::size_t n, std::size_t width, std::size_t height, bool with_labels,
                          PcdEncoding encoding) {
  std::string out;
  out += "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\n";
  out += with_labels
             ? "FIELDS x y z intensity label\nSIZE 4 4 4 4 4\nTYPE F F F F U\nCOUNT 1 1 1 1 1\n"
             : "FIELDS x y z intensity\nSIZE 4 4 4 4\nTYPE F F F F\nCOUNT 1 1 1 1\n";
  out += "WIDTH " + std::to_string(width) + "\nHEIGHT " + std::to_string(height) +
         "\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " + std::to_string(n) + "\nDATA " +
         std::string(to_string(encoding)) + "\n";
  return out;
}

// A header comment must stay on its line.
void check_comment(std::string_view comment) {
  if (comment.find_first_of("\r\n") != std::string_view::npos) {
    throw core::Error("encode_pcd_points: a header comment must be one line");
  }
}

// A one-line comment (check_comment) as the header's second line.
void insert_comment(std::string& header, std::string_view comment) {
  if (comment.empty()) return;
  std::string line = "# ";
  line += comment;
  line += '\n';
  header.insert(header.find('\n') + 1, line);
}

std::string encode_fields(const PcdFields& f, PcdEncoding encoding) {
  const std::size_t n = f.xs.size();
  const bool with_labels = !f.labels.empty();
  std::string out = fields_header(n, f.width, f.height, with_labels, encoding);
  const auto& xs = f.xs;
  const auto& ys = f.ys;
  const auto& zs = f.zs;
  const auto& is = f.intensities;
  const auto& labels = f.labels;
  switch (encoding) {
    case PcdEncoding::kAscii:
      for (std::size_t i = 0; i < n; ++i) {
        append_shortest(out, xs[i]);
        out += ' ';
        append_shortest(out, ys[i]);
        out += ' ';
        append_shortest(out, zs[i]);
        out += ' ';
        append_shortest(out, is[i]);
        if (with_labels) {
          out += ' ';
          out += std::to_string(labels[i]);
        }
        out += '\n';
      }
      break;
    case PcdEncoding::kBinary:
      out.reserve(out.size() + n * (with_labels ? 20 : 16));
      for (std::size_t i = 0; i < n; ++i) {
        append_bytes(out, &xs[i], 4);
        append_bytes(out, &ys[i], 4);
        append_bytes(out, &zs[i], 4);
        append_bytes(out, &is[i], 4);
        if (with_labels) append_bytes(out, &labels[i], 4);
      }
      break;
    case PcdEncoding::kBinaryCompressed: {
      std::vector<std::uint8_t> raw(n * (with_labels ? 20 : 16));
      std::memcpy(raw.data(), xs.data(), 4 * n);
      std::memcpy(raw.data() + 4 * n, ys.data(), 4 * n);
      std::memcpy(raw.data() + 8 * n, zs.data(), 4 * n);
      std::memcpy(raw.data() + 12 * n, is.data(), 4 * n);
      if (with_labels) std::memcpy(raw.data() + 16 * n, labels.data(), 4 * n);
      const auto packed = lzf_compress(raw);
      if (raw.size() > std::numeric_limits<std::uint32_t>::max() ||
          packed.size() > std::numeric_limits<std::uint32_t>::max()) {
        throw core::Error("encode_pcd: binary_compressed data exceeds 4 GiB");
      }
      const auto compressed = static_cast<std::uint32_t>(packed.size());
      const auto uncompressed = static_cast<std::uint32_t>(raw.size());
      append_bytes(out, &compressed, 4);
      append_bytes(out, &uncompressed, 4);
      append_bytes(out, packed.data(), packed.size());
      break;
    }
  }
  return out;
}

}  // namespace

std::string encode_pcd(const core::OrganizedScan& scan, std::span<const std::uint32_t> labels,
                       PcdEncoding encoding) {
  const std::size_t n = scan.size();
  if (!labels.empty() && labels.size() != n) {
    throw core::Error("encode_pcd: " + std::to_string(labels.size()) + " labels for " +
                      std::to_string(n) + " cells");
  }
  if (n == 0) throw core::Error("encode_pcd: the scan is empty");
  return encode_fields(
      {scan.xs(), scan.ys(), scan.zs(), scan.intensities(), labels,
       static_cast<std::size_t>(scan.columns()), static_cast<std::size_t>(scan.rings())},
      encoding);
}

std::string pcd_points_header(std::size_t n, PcdEncoding encoding, std::string_view comment) {
  check_comment(comment);
  std::string header = fields_header(n, n, 1, false, encoding);
  insert_comment(header, comment);
  return header;
}

std::string encode_pcd_points(std::span<const Eigen::Vector3f> points,
                              std::span<const float> intensities, PcdEncoding encoding,
                              std::string_view comment) {
  check_comment(comment);  // before the encoding's work
  if (!intensities.empty() && intensities.size() != points.size()) {
    throw core::Error("encode_pcd_points: " + std::to_string(intensities.size()) +
                      " intensities for " + std::to_string(points.size()) + " points");
  }
  const std::size_t n = points.size();
  std::vector<float> xs(n), ys(n), zs(n), is(n, 0.0f);
  for (std::size_t i = 0; i < n; ++i) {
    xs[i] = points[i].x();
    ys[i] = points[i].y();
    zs[i] = points[i].z();
    if (!intensities.empty()) is[i] = intensities[i];
  }
  std::string out = encode_fields({xs, ys, zs, is, {}, n, 1}, encoding);
  insert_comment(out, comment);
  return out;
}

void write_pcd_points(const std::filesystem::path& path, std::span<const Eigen::Vector3f> points,
                      std::span<const float> intensities, PcdEncoding encoding,
                      std::string_view comment) {
  write_file(path, encode_pcd_points(points, intensities, encoding, comment));
}

void write_pcd(const std::filesystem::path& path, const core::OrganizedScan& scan,
               std::span<const std::uint32_t> labels, PcdEncoding encoding) {
  write_file(path, encode_pcd(scan, labels, encoding));
}

}  // namespace ringtrack::io
