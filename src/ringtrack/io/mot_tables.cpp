#include "ringtrack/io/mot_tables.hpp"

#include <cmath>
#include <limits>
#include <map>
#include <string_view>
#include <unordered_map>
#include <utility>

#include "ringtrack/core/error.hpp"
#include "ringtrack/io/text.hpp"

namespace ringtrack::io {
namespace {

std::vector<std::string> lines_of(std::istream& in) {
  std::vector<std::string> lines;
  std::string line;
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    lines.push_back(std::move(line));
  }
  return lines;
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

bool blank(std::string_view line) {
  return trim(line).empty();
}

// Comma-separated fields, empty ones kept so that columns never shift.
std::vector<std::string_view> split_fields(std::string_view line) {
  std::vector<std::string_view> out;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = line.find(',', start);
    out.push_back(
        trim(line.substr(start, comma == std::string_view::npos ? line.npos : comma - start)));
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  return out;
}

// A CSV table with a header naming its columns; rows are read by column name.
class Table {
 public:
  Table(const std::vector<std::string>& lines, std::string name, std::string_view header)
      : lines_(lines), name_(std::move(name)) {
    while (header_line_ < lines_.size() && blank(lines_[header_line_])) ++header_line_;
    if (header_line_ == lines_.size()) {
      throw core::InputError(name_ + ": empty file, expected the header '" + std::string(header) +
                             "'");
    }
    const auto names = split_fields(lines_[header_line_]);
    for (std::size_t k = 0; k < names.size(); ++k) {
      if (!columns_.emplace(std::string(names[k]), k).second) {
        throw core::InputError(where(header_line_) + ": column '" + std::string(names[k]) +
                               "' appears twice in the header");
      }
    }
    width_ = names.size();
    for (const auto required : split_fields(header)) {
      if (columns_.count(std::string(required)) == 0) {
        throw core::InputError(where(header_line_) + ": missing column '" + std::string(required) +
                               "' (expected the header '" + std::string(header) + "')");
      }
    }
  }

  [[nodiscard]] std::string where(std::size_t index) const {
    return name_ + ":" + std::to_string(index + 1);
  }
  [[nodiscard]] const std::string& name() const { return name_; }

  // Calls f(row_index) for every non-blank data line after fields_ is set to its fields.
  template <typename F>
  void for_each_row(F f) {
    for (std::size_t i = header_line_ + 1; i < lines_.size(); ++i) {
      if (blank(lines_[i])) continue;
      fields_ = split_fields(lines_[i]);
      if (fields_.size() != width_) {
        throw core::InputError(where(i) + ": expected " + std::to_string(width_) +
                               " comma-separated fields as in the header, got " +
                               std::to_string(fields_.size()));
      }
      line_ = i;
      f(i);
    }
  }

  [[nodiscard]] bool has(const char* column) const { return columns_.count(column) != 0; }
  [[nodiscard]] std::string_view raw(const char* column) const {
    return fields_[columns_.at(column)];
  }
  [[noreturn]] void fail(const char* column, const std::string& expected) const {
    throw core::InputError(where(line_) + ": column '" + column + "': expected " + expected +
                           ", got '" + std::string(raw(column)) + "'");
  }
  [[nodiscard]] std::int64_t integer(const char* column, std::int64_t min, std::int64_t max) const {
    const auto v = parse_int(raw(column));
    if (!v || *v < min || *v > max) {
      fail(column, "an integer in [" + std::to_string(min) + ", " + std::to_string(max) + "]");
    }
    return *v;
  }
  // A number; "nan" is accepted (the writers emit it for undefined values), garbage is not.
  [[nodiscard]] double number(const char* column) const {
    const auto v = parse_double(raw(column));
    if (!v) fail(column, "a number");
    return *v;
  }
  [[nodiscard]] double finite(const char* column) const {
    const auto v = parse_double(raw(column));
    if (!v || !std::isfinite(*v)) fail(column, "a finite number");
    return *v;
  }
  [[nodiscard]] std::int64_t stamp_ns(const char* column) const {
    const auto v = parse_stamp_ns(raw(column));
    if (!v) fail(column, "a stamp in seconds");
    return *v;
  }
  [[nodiscard]] bool flag(const char* column) const {
    const std::string_view s = raw(column);
    if (s != "0" && s != "1") fail(column, "0 or 1");
    return s == "1";
  }
  [[nodiscard]] Eigen::Vector3d vector(const char* cx, const char* cy, const char* cz,
                                       bool require_finite) const {
    return require_finite ? Eigen::Vector3d(finite(cx), finite(cy), finite(cz))
                          : Eigen::Vector3d(number(cx), number(cy), number(cz));
  }
  // The six box columns: all nan = empty box, otherwise finite with min <= max.
  [[nodiscard]] core::Box3d box() const {
    const Eigen::Vector3d lo = vector("min_x", "min_y", "min_z", false);
    const Eigen::Vector3d hi = vector("max_x", "max_y", "max_z", false);
    if (lo.array().isNaN().all() && hi.array().isNaN().all()) return {};
    if (!lo.allFinite() || !hi.allFinite() || (lo.array() > hi.array()).any()) {
      throw core::InputError(where(line_) +
                             ": columns min_x..max_z: expected a box with finite min <= max, or "
                             "nan in all six for no box");
    }
    return {lo, hi};
  }

 private:
  const std::vector<std::string>& lines_;
  std::string name_;
  std::size_t header_line_ = 0;
  std::size_t width_ = 0;
  std::unordered_map<std::string, std::size_t> columns_;
  std::vector<std::string_view> fields_;
  std::size_t line_ = 0;
};

constexpr std::int64_t kMaxU32 = std::numeric_limits<std::uint32_t>::max();
constexpr std::int64_t kMaxI64 = std::numeric_limits<std::int64_t>::max();

// Rejects a repeated (scan, id) and a scan whose rows disagree on the stamp, naming both lines.
class RowChecks {
 public:
  RowChecks(const Table& table, const char* scan_word) : table_(table), scan_word_(scan_word) {}
  void add(std::size_t line, std::uint64_t scan, std::uint64_t id, std::int64_t stamp_ns) {
    const auto [it, fresh] = seen_.emplace(std::pair{scan, id}, line);
    if (!fresh) {
      throw core::InputError(table_.where(line) + ": id " + std::to_string(id) +
                             " appears twice in " + scan_word_ + " " + std::to_string(scan) +
                             " (first at line " + std::to_string(it->second + 1) + ")");
    }
    const auto [st, first] = stamps_.emplace(scan, std::pair{stamp_ns, line});
    if (!first && st->second.first != stamp_ns) {
      throw core::InputError(table_.where(line) + ": " + scan_word_ + " " + std::to_string(scan) +
                             " has stamp " + format_stamp(stamp_ns) + " but " +
                             format_stamp(st->second.first) + " at line " +
                             std::to_string(st->second.second + 1));
    }
  }
  // Stamps must not decrease with the scan index.
  void finish() const {
    const std::pair<const std::uint64_t, std::pair<std::int64_t, std::size_t>>* prev = nullptr;
    for (const auto& entry : stamps_) {
      if (prev != nullptr && entry.second.first < prev->second.first) {
        throw core::InputError(table_.where(entry.second.second) + ": " + scan_word_ + " " +
                               std::to_string(entry.first) + " has stamp " +
                               format_stamp(entry.second.first) + ", earlier than " +
                               format_stamp(prev->second.first) + " of " + scan_word_ + " " +
                               std::to_string(prev->first));
      }
      prev = &entry;
    }
  }

 private:
  const Table& table_;
  const char* scan_word_;
  std::map<std::pair<std::uint64_t, std::uint64_t>, std::size_t> seen_;
  std::map<std::uint64_t, std::pair<std::int64_t, std::size_t>> stamps_;
};

std::vector<ObjectRow> parse_objects(const std::vector<std::string>& lines,
                                     const std::string& name) {
  Table table(lines, name, kObjectsCsvHeader);
  RowChecks checks(table, "scan");
  std::vector<ObjectRow> rows;
  table.for_each_row([&](std::size_t line) {
    ObjectRow r;
    r.scan = static_cast<std::uint64_t>(table.integer("scan", 0, kMaxI64));
    r.stamp_ns = table.stamp_ns("stamp");
    r.id = static_cast<std::uint32_t>(table.integer("id", 0, kMaxU32));
    r.class_name = std::string(table.raw("class"));
    if (r.class_name.empty()) table.fail("class", "a class name");
    r.points = static_cast<std::uint32_t>(table.integer("points", 0, kMaxU32));
    // An object without hit points has no centroid or box: nan is expected there.
    r.centroid = table.vector("x", "y", "z", r.points > 0);
    r.box = table.box();
    if (r.points > 0 && r.box.empty()) {
      throw core::InputError(table.where(line) + ": object " + std::to_string(r.id) + " has " +
                             std::to_string(r.points) + " points but no box (nan)");
    }
    r.true_center = table.vector("true_x", "true_y", "true_z", false);
    r.moving = table.flag("moving");
    checks.add(line, r.scan, r.id, r.stamp_ns);
    rows.push_back(std::move(r));
  });
  checks.finish();
  return rows;
}

// The columns every tracks.csv has: the header before the person column was added (issue 10).
constexpr std::string_view kTracksCsvRequired =
    "scan,stamp,id,x,y,z,vx,vy,vz,min_x,min_y,min_z,max_x,max_y,max_z,dynamic,ever_dynamic,age,"
    "points";

std::vector<TrackRow> parse_tracks(const std::vector<std::string>& lines, const std::string& name,
                                   TracksCsvColumns* present) {
  Table table(lines, name, kTracksCsvRequired);
  const bool has_person = table.has("person");
  if (present != nullptr) present->person = has_person;
  RowChecks checks(table, "scan");
  std::vector<TrackRow> rows;
  table.for_each_row([&](std::size_t line) {
    TrackRow r;
    r.scan = static_cast<std::uint64_t>(table.integer("scan", 0, kMaxI64));
    r.stamp_ns = table.stamp_ns("stamp");
    r.id = static_cast<std::uint64_t>(table.integer("id", 0, kMaxI64));
    r.position = table.vector("x", "y", "z", true);
    r.velocity = table.vector("vx", "vy", "vz", false);
    r.box = table.box();
    r.dynamic = table.flag("dynamic");
    r.ever_dynamic = table.flag("ever_dynamic");
    r.age = static_cast<std::uint32_t>(table.integer("age", 0, kMaxU32));
    r.points = static_cast<std::uint32_t>(table.integer("points", 0, kMaxU32));
    r.person = has_person && table.flag("person");
    checks.add(line, r.scan, r.id, r.stamp_ns);
    rows.push_back(std::move(r));
  });
  checks.finish();
  return rows;
}

std::vector<MotChallengeRow> parse_motchallenge(const std::vector<std::string>& lines,
                                                const std::string& name, bool ground_truth) {
  std::vector<MotChallengeRow> rows;
  std::map<std::pair<std::int64_t, std::int64_t>, std::size_t> seen;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const auto tokens = split_tokens(lines[i], true);
    if (tokens.empty()) continue;
    const std::string where = name + ":" + std::to_string(i + 1);
    if (tokens.size() < 6) {
      throw core::InputError(where +
                             ": expected at least 6 values (frame, id, left, top, width, "
                             "height), got " +
                             std::to_string(tokens.size()));
    }
    const auto bad = [&](std::size_t k, const char* expected) {
      return core::InputError(where + ": value " + std::to_string(k + 1) + ": expected " +
                              expected + ", got '" + std::string(tokens[k]) + "'");
    };
    // Some writers print integral values as "12.000": accept them as integers.
    const auto integer = [&](std::size_t k) {
      const auto v = parse_double(tokens[k]);
      if (!v || !std::isfinite(*v) || std::trunc(*v) != *v || std::abs(*v) > 9.0e15) {
        throw bad(k, "an integer");
      }
      return static_cast<std::int64_t>(*v);
    };
    const auto number = [&](std::size_t k) {
      const auto v = parse_double(tokens[k]);
      if (!v || !std::isfinite(*v)) throw bad(k, "a finite number");
      return *v;
    };
    MotChallengeRow r;
    r.frame = integer(0);
    r.id = integer(1);
    r.left = number(2);
    r.top = number(3);
    r.width = number(4);
    r.height = number(5);
    if (r.width < 0.0) throw bad(4, "a non-negative width");
    if (r.height < 0.0) throw bad(5, "a non-negative height");
    if (tokens.size() >= 7) r.confidence = number(6);
    if (ground_truth && r.confidence == 0.0) continue;
    const auto [it, fresh] = seen.emplace(std::pair{r.frame, r.id}, i);
    if (!fresh) {
      throw core::InputError(where + ": id " + std::to_string(r.id) + " appears twice in frame " +
                             std::to_string(r.frame) + " (first at line " +
                             std::to_string(it->second + 1) + ")");
    }
    rows.push_back(r);
  }
  return rows;
}

}  // namespace

std::vector<ObjectRow> read_objects_csv(const std::filesystem::path& path) {
  return parse_objects(read_lines(path), path.string());
}

std::vector<ObjectRow> read_objects_csv(std::istream& in, const std::string& name) {
  return parse_objects(lines_of(in), name);
}

std::vector<TrackRow> read_tracks_csv(const std::filesystem::path& path,
                                      TracksCsvColumns* present) {
  return parse_tracks(read_lines(path), path.string(), present);
}

std::vector<TrackRow> read_tracks_csv(std::istream& in, const std::string& name,
                                      TracksCsvColumns* present) {
  return parse_tracks(lines_of(in), name, present);
}

std::vector<MotChallengeRow> read_motchallenge(const std::filesystem::path& path,
                                               bool ground_truth) {
  return parse_motchallenge(read_lines(path), path.string(), ground_truth);
}

std::vector<MotChallengeRow> read_motchallenge(std::istream& in, const std::string& name,
                                               bool ground_truth) {
  return parse_motchallenge(lines_of(in), name, ground_truth);
}

void check_scan_stamps(const std::vector<ObjectRow>& objects, const std::string& objects_name,
                       const std::vector<TrackRow>& tracks, const std::string& tracks_name) {
  const auto stamps_of = [](const auto& rows, const std::string& name) {
    std::map<std::uint64_t, std::int64_t> stamps;
    for (const auto& r : rows) {
      const auto [it, fresh] = stamps.emplace(r.scan, r.stamp_ns);
      if (!fresh && it->second != r.stamp_ns) {
        throw core::InputError(name + ": scan " + std::to_string(r.scan) + " has stamps " +
                               format_stamp(it->second) + " and " + format_stamp(r.stamp_ns));
      }
    }
    const std::pair<const std::uint64_t, std::int64_t>* prev = nullptr;
    for (const auto& entry : stamps) {
      if (prev != nullptr && entry.second < prev->second) {
        throw core::InputError(name + ": scan " + std::to_string(entry.first) + " has stamp " +
                               format_stamp(entry.second) + ", earlier than scan " +
                               std::to_string(prev->first) + " (" + format_stamp(prev->second) +
                               ")");
      }
      prev = &entry;
    }
    return stamps;
  };
  const auto gt = stamps_of(objects, objects_name);
  const auto tr = stamps_of(tracks, tracks_name);
  for (const auto& [scan, stamp] : tr) {
    const auto it = gt.find(scan);
    if (it != gt.end() && it->second != stamp) {
      throw core::InputError("scan indices do not match: scan " + std::to_string(scan) +
                             " has stamp " + format_stamp(it->second) + " in " + objects_name +
                             " but " + format_stamp(stamp) + " in " + tracks_name);
    }
  }
}

}  // namespace ringtrack::io
