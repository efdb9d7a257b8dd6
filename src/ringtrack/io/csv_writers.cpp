#include "ringtrack/io/csv_writers.hpp"

#include <limits>

#include "ringtrack/core/error.hpp"
#include "ringtrack/io/text.hpp"

namespace ringtrack::io {
namespace {

// 0.1 mm, 0.1 mm/s and 0.1 us: finer than any sensor, coarse enough for stable diffs.
constexpr int kDecimals = 4;

void append_number(std::string& out, double v) {
  out += ',';
  append_fixed(out, v, kDecimals);
}

void append_vector(std::string& out, const Eigen::Vector3d& v) {
  for (int k = 0; k < 3; ++k) append_number(out, v[k]);
}

void append_box(std::string& out, const core::Box3d& box) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (int k = 0; k < 3; ++k) append_number(out, box.empty() ? nan : box.min[k]);
  for (int k = 0; k < 3; ++k) append_number(out, box.empty() ? nan : box.max[k]);
}

bool valid_stage_name(const std::string& name) {
  if (name.empty()) return false;
  for (char c : name) {
    if (!((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_')) return false;
  }
  return true;
}

}  // namespace

std::string format_track_row(const TrackRow& row) {
  std::string out = std::to_string(row.scan);
  out += ',';
  out += format_stamp(row.stamp_ns);
  out += ',';
  out += std::to_string(row.id);
  append_vector(out, row.position);
  append_vector(out, row.velocity);
  append_box(out, row.box);
  out += row.dynamic ? ",1" : ",0";
  out += row.ever_dynamic ? ",1" : ",0";
  out += ',';
  out += std::to_string(row.age);
  out += ',';
  out += std::to_string(row.points);
  out += row.person ? ",1" : ",0";
  return out;
}

std::string format_object_row(const ObjectRow& row) {
  if (row.class_name.empty() || row.class_name.find_first_of(",\"\r\n") != std::string::npos) {
    throw core::Error("objects.csv: class name '" + row.class_name + "' of object " +
                      std::to_string(row.id) +
                      " must be non-empty without commas, quotes or line breaks");
  }
  std::string out = std::to_string(row.scan);
  out += ',';
  out += format_stamp(row.stamp_ns);
  out += ',';
  out += std::to_string(row.id);
  out += ',';
  out += row.class_name;
  out += ',';
  out += std::to_string(row.points);
  append_vector(out, row.centroid);
  append_box(out, row.box);
  append_vector(out, row.true_center);
  out += row.moving ? ",1" : ",0";
  return out;
}

TracksCsvWriter::TracksCsvWriter(const std::filesystem::path& path) : file_(path) {
  file_.write(kTracksCsvHeader);
  file_.write("\n");
}

void TracksCsvWriter::write(const TrackRow& row) {
  std::string line = format_track_row(row);
  line += '\n';
  file_.write(line);
}

void TracksCsvWriter::write(std::span<const TrackRow> rows) {
  for (const auto& r : rows) write(r);
}

ObjectsCsvWriter::ObjectsCsvWriter(const std::filesystem::path& path) : file_(path) {
  file_.write(kObjectsCsvHeader);
  file_.write("\n");
}

void ObjectsCsvWriter::write(const ObjectRow& row) {
  std::string line = format_object_row(row);
  line += '\n';
  file_.write(line);
}

void ObjectsCsvWriter::write(std::span<const ObjectRow> rows) {
  for (const auto& r : rows) write(r);
}

TimingCsvWriter::TimingCsvWriter(const std::filesystem::path& path) : file_(path) {}

void TimingCsvWriter::write(const TimingRow& row) {
  if (!header_written_) {
    std::string header = "scan,stamp";
    for (const auto& s : row.stages) {
      if (!valid_stage_name(s.name) || s.name == "total") {
        throw core::Error(file_.path().string() + ": stage name '" + s.name +
                          "' must match [a-z0-9_]+ and differ from 'total'");
      }
      stages_.push_back(s.name);
      header += ',' + s.name + "_ms";
    }
    header += ",total_ms\n";
    file_.write(header);
    header_written_ = true;
  }
  bool same = row.stages.size() == stages_.size();
  for (std::size_t k = 0; same && k < stages_.size(); ++k) same = row.stages[k].name == stages_[k];
  if (!same) {
    throw core::Error(file_.path().string() + ": scan " + std::to_string(row.scan) +
                      " has other stages than the header");
  }
  std::string line = std::to_string(row.scan);
  line += ',';
  line += format_stamp(row.stamp_ns);
  for (const auto& s : row.stages) append_number(line, s.ms);
  append_number(line, row.total_ms);
  line += '\n';
  file_.write(line);
}

void TimingCsvWriter::close() {
  if (!header_written_ && file_.is_open()) {
    file_.write("scan,stamp,total_ms\n");
    header_written_ = true;
  }
  file_.close();
}

}  // namespace ringtrack::io
