#include "ringtrack/io/sequence.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <numbers>

#include "ringtrack/core/error.hpp"
#include "ringtrack/io/kitti_bin.hpp"
#include "ringtrack/io/text.hpp"

namespace ringtrack::io {
namespace fs = std::filesystem;
namespace {

constexpr double kRadToDeg = 180.0 / std::numbers::pi;
constexpr int kMaxColumns = 1 << 20;

bool is_digits(std::string_view s) {
  return !s.empty() && std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; });
}

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// Orders names as people do: digit runs compare by value, so "scan2" precedes "scan10".
bool natural_less(const std::string& a, const std::string& b) {
  std::size_t i = 0;
  std::size_t j = 0;
  const auto digit = [](char c) { return c >= '0' && c <= '9'; };
  while (i < a.size() && j < b.size()) {
    if (digit(a[i]) && digit(b[j])) {
      std::size_t i2 = i;
      std::size_t j2 = j;
      while (i2 < a.size() && digit(a[i2])) ++i2;
      while (j2 < b.size() && digit(b[j2])) ++j2;
      std::string_view da(a.data() + i, i2 - i);
      std::string_view db(b.data() + j, j2 - j);
      const auto strip = [](std::string_view s) {
        while (s.size() > 1 && s.front() == '0') s.remove_prefix(1);
        return s;
      };
      const std::string_view va = strip(da);
      const std::string_view vb = strip(db);
      if (va.size() != vb.size()) return va.size() < vb.size();
      if (va != vb) return va < vb;
      if (da.size() != db.size()) return da.size() < db.size();
      i = i2;
      j = j2;
    } else {
      if (a[i] != b[j]) return a[i] < b[j];
      ++i;
      ++j;
    }
  }
  return a.size() - i < b.size() - j;
}

std::string at_key(const fs::path& path, const YAML::Node& key_node, const std::string& key) {
  return path.string() + ":" + std::to_string(key_node.Mark().line + 1) + ": key '" + key + "'";
}

template <typename T>
T yaml_as(const YAML::Node& value, const std::string& where, const char* expected) {
  if (!value.IsScalar()) throw core::InputError(where + ": expected " + expected);
  try {
    return value.as<T>();
  } catch (const YAML::Exception&) {
    throw core::InputError(where + ": expected " + expected + ", got '" + value.Scalar() + "'");
  }
}

void set_column_stamps(core::OrganizedScan& scan, std::int64_t stamp_ns, double scan_rate_hz) {
  scan.stamp_ns = stamp_ns;
  const double column_ns = 1e9 / (scan_rate_hz * scan.columns());
  for (int c = 0; c < scan.columns(); ++c) {
    scan.column_stamp_ns[static_cast<std::size_t>(c)] =
        stamp_ns + static_cast<std::int64_t>(std::llround(c * column_ns));
  }
}

}  // namespace

// ---------------------------------------------------------------- sequence.yaml

core::SensorModel SequenceMeta::sensor_model() const {
  if (!(scan_rate_hz > 0.0)) throw core::Error("sequence: scan_rate_hz must be positive");
  if (lower(sensor) == "generic") {
    if (elevations_deg.empty()) {
      throw core::Error("sequence: sensor 'generic' needs elevations_deg (one per ring)");
    }
    auto model =
        core::SensorModel::generic(elevations_deg, std::max(columns, 8), scan_rate_hz, max_range_m);
    model.validate();
    return model;
  }
  if (!elevations_deg.empty()) {
    throw core::Error("sequence: elevations_deg is only allowed with sensor 'generic'");
  }
  return core::SensorModel::by_name(sensor, scan_rate_hz);
}

SequenceMeta SequenceMeta::for_sensor(const core::SensorModel& model, int columns) {
  SequenceMeta meta;
  meta.scan_rate_hz = model.scan_rate_hz;
  meta.columns = columns;
  for (const auto& row : core::built_in_sensors()) {
    if (row.make == nullptr) continue;
    const auto builtin = row.make(model.scan_rate_hz);
    if (builtin.name == model.name && builtin.elevation_rad == model.elevation_rad) {
      meta.sensor = row.name;
      return meta;
    }
  }
  meta.sensor = "generic";
  meta.max_range_m = model.max_range_m;
  for (double e : model.elevation_rad) {
    // Rounded to 1e-9 degrees: -3.333 comes back as -3.333, not -3.3330000000000002.
    meta.elevations_deg.push_back(std::round(e * kRadToDeg * 1e9) / 1e9);
  }
  return meta;
}

namespace {

YAML::Node load_sequence_yaml(const fs::path& path) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path.string());
  } catch (const YAML::BadFile&) {
    throw core::InputError(path.string() + ": cannot open file");
  } catch (const YAML::Exception& e) {
    throw core::InputError(path.string() + ":" + std::to_string(e.mark.line + 1) +
                           ": invalid YAML: " + e.msg);
  }
  if (!root.IsMap()) {
    throw core::InputError(path.string() +
                           ": expected a mapping of keys (format_version, sensor, ...)");
  }
  return root;
}

// The keys a sequence.yaml must have, or may have only with some sensors, that were given.
struct SequenceKeysGiven {
  bool version = false;
  bool sensor = false;
  bool rate = false;
  bool columns = false;
  bool max_range = false;
};

int read_format_version(const YAML::Node& value, const std::string& where) {
  const int version = yaml_as<int>(value, where, "an integer");
  if (version != kSequenceFormatVersion) {
    throw core::InputError(where + ": unsupported version " + std::to_string(version) +
                           " (this ringtrack reads " + std::to_string(kSequenceFormatVersion) +
                           ")");
  }
  return version;
}

std::string read_sensor_name(const YAML::Node& value, const std::string& where) {
  const std::string expected = core::built_in_model_list() + " (or generic)";
  std::string sensor = lower(yaml_as<std::string>(value, where, expected.c_str()));
  if (sensor == "generic") return sensor;
  try {
    core::SensorModel::by_name(sensor);
  } catch (const core::Error&) {
    throw core::InputError(where + ": unknown sensor '" + sensor + "' (expected " +
                           core::built_in_model_list() + " or generic)");
  }
  return sensor;
}

void append_elevations(const YAML::Node& value, const std::string& where,
                       std::vector<double>& elevations_deg) {
  if (!value.IsSequence() || value.size() == 0) {
    throw core::InputError(where + ": expected a list of ring elevations in degrees");
  }
  for (const auto& e : value) {
    const auto deg = yaml_as<double>(e, where, "a list of numbers");
    if (!std::isfinite(deg) || std::abs(deg) >= 90.0) {
      throw core::InputError(where + ": elevation " + e.Scalar() + " outside (-90, 90) degrees");
    }
    elevations_deg.push_back(deg);
  }
}

double read_scan_rate(const YAML::Node& value, const std::string& where) {
  const double rate_hz = yaml_as<double>(value, where, "a number");
  if (!(rate_hz > 0.0 && rate_hz <= 1000.0)) {
    throw core::InputError(where + ": expected a rate in (0, 1000] Hz");
  }
  return rate_hz;
}

int read_columns(const YAML::Node& value, const std::string& where) {
  const int columns = yaml_as<int>(value, where, "an integer");
  if (columns < 8 || columns > kMaxColumns) {
    throw core::InputError(where + ": expected an integer in [8, " + std::to_string(kMaxColumns) +
                           "]");
  }
  return columns;
}

// One key of sequence.yaml (docs/formats.md) into meta, with its own check and message.
void read_sequence_key(const std::string& key, const YAML::Node& value, const std::string& where,
                       SequenceMeta& meta, SequenceKeysGiven& given) {
  if (key == "format_version") {
    meta.format_version = read_format_version(value, where);
    given.version = true;
  } else if (key == "sensor") {
    meta.sensor = read_sensor_name(value, where);
    given.sensor = true;
  } else if (key == "elevations_deg") {
    append_elevations(value, where, meta.elevations_deg);
  } else if (key == "max_range_m") {
    meta.max_range_m = yaml_as<double>(value, where, "a number");
    if (!(meta.max_range_m > 0.0)) throw core::InputError(where + ": expected a positive range");
    given.max_range = true;
  } else if (key == "scan_rate_hz") {
    meta.scan_rate_hz = read_scan_rate(value, where);
    given.rate = true;
  } else if (key == "columns") {
    meta.columns = read_columns(value, where);
    given.columns = true;
  } else if (key == "scans") {
    meta.scans = yaml_as<std::uint64_t>(value, where, "a non-negative integer");
  } else if (key == "name") {
    meta.name = yaml_as<std::string>(value, where, "a string");
  } else if (key == "scenario") {
    meta.scenario = yaml_as<std::string>(value, where, "a string or number");
  } else if (key == "seed") {
    meta.seed = yaml_as<std::uint64_t>(value, where, "a non-negative integer");
  } else if (key == "sensor_height_m") {
    meta.sensor_height_m = yaml_as<double>(value, where, "a number");
    if (!(std::abs(*meta.sensor_height_m) <= 1000.0)) {
      throw core::InputError(where + ": expected a height within +-1000 m of the ground");
    }
  } else {
    throw core::InputError(where +
                           ": unknown key (expected format_version, sensor, "
                           "elevations_deg, max_range_m, scan_rate_hz, columns, scans, name, "
                           "scenario, seed, sensor_height_m)");
  }
}

// The keys against each other: the required ones given, the generic sensor's only with it.
void check_sequence_keys(const fs::path& path, const SequenceMeta& meta,
                         const SequenceKeysGiven& given) {
  const auto missing = [&](bool have, const char* key) {
    if (!have) throw core::InputError(path.string() + ": missing key '" + key + "'");
  };
  missing(given.version, "format_version");
  missing(given.sensor, "sensor");
  missing(given.rate, "scan_rate_hz");
  missing(given.columns, "columns");
  if (meta.sensor == "generic" && meta.elevations_deg.empty()) {
    throw core::InputError(path.string() + ": sensor 'generic' needs the key 'elevations_deg'");
  }
  if (meta.sensor != "generic" && (!meta.elevations_deg.empty() || given.max_range)) {
    throw core::InputError(
        path.string() + ": elevations_deg and max_range_m are only allowed with sensor 'generic'");
  }
}

}  // namespace

// Reads sequence.yaml key by key (docs/formats.md), each key with its own check and message.
SequenceMeta read_sequence_yaml(const fs::path& path) {
  const YAML::Node root = load_sequence_yaml(path);
  SequenceMeta meta;
  SequenceKeysGiven given;
  for (const auto& entry : root) {
    // A list or map as key has no name (as<std::string>() would throw yaml-cpp's own exception).
    if (!entry.first.IsScalar()) {
      throw core::InputError(path.string() + ":" + std::to_string(entry.first.Mark().line + 1) +
                             ": expected a key name, got a list or map as key");
    }
    const std::string key = entry.first.as<std::string>();
    read_sequence_key(key, entry.second, at_key(path, entry.first, key), meta, given);
  }
  check_sequence_keys(path, meta, given);
  return meta;
}

std::string format_sequence_yaml(const SequenceMeta& meta) {
  YAML::Emitter out;
  out.SetDoublePrecision(12);
  out << YAML::BeginMap;
  out << YAML::Key << "format_version" << YAML::Value << meta.format_version;
  out << YAML::Key << "sensor" << YAML::Value << meta.sensor;
  if (meta.sensor == "generic") {
    out << YAML::Key << "elevations_deg" << YAML::Value << YAML::Flow << YAML::BeginSeq;
    for (double e : meta.elevations_deg) out << e;
    out << YAML::EndSeq;
    out << YAML::Key << "max_range_m" << YAML::Value << meta.max_range_m;
  }
  out << YAML::Key << "scan_rate_hz" << YAML::Value << meta.scan_rate_hz;
  out << YAML::Key << "columns" << YAML::Value << meta.columns;
  if (meta.scans) out << YAML::Key << "scans" << YAML::Value << *meta.scans;
  if (!meta.name.empty())
    out << YAML::Key << "name" << YAML::Value << YAML::DoubleQuoted << meta.name;
  if (!meta.scenario.empty()) {
    out << YAML::Key << "scenario" << YAML::Value << YAML::DoubleQuoted << meta.scenario;
  }
  if (meta.seed) out << YAML::Key << "seed" << YAML::Value << *meta.seed;
  if (meta.sensor_height_m) {
    out << YAML::Key << "sensor_height_m" << YAML::Value << *meta.sensor_height_m;
  }
  out << YAML::EndMap;
  std::string text = "# ringtrack sequence folder, see docs/formats.md\n";
  text += out.c_str();
  text += '\n';
  return text;
}

std::string scan_file_name(std::size_t index) {
  std::string digits = std::to_string(index);
  if (digits.size() < 6) digits.insert(0, 6 - digits.size(), '0');
  return digits + ".pcd";
}

// ---------------------------------------------------------------- writer

SequenceWriter::SequenceWriter(const fs::path& folder, SequenceMeta meta,
                               SequenceWriteOptions options)
    : folder_(folder), meta_(std::move(meta)), options_(options) {
  meta_.format_version = kSequenceFormatVersion;
  meta_.scans.reset();
  meta_.sensor = lower(meta_.sensor);
  rings_ = meta_.sensor_model().rings();  // throws on an unknown or inconsistent sensor
  if (meta_.columns < 0 || meta_.columns > kMaxColumns) {
    throw core::Error(folder_.string() + ": sequence columns " + std::to_string(meta_.columns) +
                      " out of range");
  }
  static const char* const kEntries[] = {"sequence.yaml", "scans", "stamps.txt", "poses.txt",
                                         "objects.csv"};
  std::error_code ec;
  if (fs::exists(folder_, ec) && !fs::is_directory(folder_, ec)) {
    throw core::Error(folder_.string() + ": exists and is not a folder");
  }
  for (const char* entry : kEntries) {
    if (!fs::exists(folder_ / entry, ec)) continue;
    if (!options_.overwrite) {
      throw core::Error(folder_.string() + ": already holds a sequence (" + entry +
                        "); choose an empty folder or allow overwriting");
    }
    fs::remove_all(folder_ / entry, ec);
    if (ec) throw core::Error((folder_ / entry).string() + ": cannot remove: " + ec.message());
  }
  fs::create_directories(folder_ / "scans", ec);
  if (ec)
    throw core::Error((folder_ / "scans").string() + ": cannot create folder: " + ec.message());
  stamps_ = std::make_unique<OutputFile>(folder_ / "stamps.txt");
  stamps_->write("# stamp of each scan in seconds (line i = scans/i), see docs/formats.md\n");
  if (options_.ground_truth) objects_ = std::make_unique<ObjectsCsvWriter>(folder_ / "objects.csv");
}

SequenceWriter::~SequenceWriter() = default;

void SequenceWriter::add_pose(const core::Pose& pose) {
  if (finished_) throw core::Error(folder_.string() + ": add_pose after finish()");
  if (!pose.translation.allFinite() || !pose.rotation.coeffs().allFinite() ||
      pose.rotation.norm() < 0.5) {
    throw core::Error(folder_.string() + ": pose at " + format_stamp(pose.stamp_ns) +
                      " is not finite or has no rotation");
  }
  if (last_pose_ns_ && pose.stamp_ns <= *last_pose_ns_) {
    throw core::Error(folder_.string() + ": pose stamp " + format_stamp(pose.stamp_ns) +
                      " does not increase (previous " + format_stamp(*last_pose_ns_) + ")");
  }
  if (!poses_) {
    poses_ = std::make_unique<OutputFile>(folder_ / "poses.txt");
    poses_->write("# t x y z qx qy qz qw (sensor in world, TUM), see docs/formats.md\n");
  }
  std::string line = format_tum_line(pose);
  line += '\n';
  poses_->write(line);
  last_pose_ns_ = pose.stamp_ns;
}

void SequenceWriter::add_scan(const core::OrganizedScan& scan,
                              std::span<const std::uint32_t> labels,
                              const std::optional<core::Pose>& pose,
                              std::span<const ObjectRow> objects) {
  if (finished_) throw core::Error(folder_.string() + ": add_scan after finish()");
  const std::string name = "scans/" + scan_file_name(scans_);
  if (scan.rings() != rings_) {
    throw core::Error(folder_.string() + ": " + name + " has " + std::to_string(scan.rings()) +
                      " rings, the sensor " + meta_.sensor + " has " + std::to_string(rings_));
  }
  if (meta_.columns == 0) meta_.columns = scan.columns();
  if (scan.columns() != meta_.columns) {
    throw core::Error(folder_.string() + ": " + name + " has " + std::to_string(scan.columns()) +
                      " columns, the sequence has " + std::to_string(meta_.columns));
  }
  if (last_stamp_ns_ && scan.stamp_ns <= *last_stamp_ns_) {
    throw core::Error(folder_.string() + ": " + name + " stamp " + format_stamp(scan.stamp_ns) +
                      " does not increase (previous " + format_stamp(*last_stamp_ns_) + ")");
  }
  if (!objects.empty() && !objects_) {
    throw core::Error(folder_.string() + ": ground-truth objects given but ground_truth is off");
  }
  write_pcd(folder_ / name, scan, labels, options_.encoding);
  stamps_->write(format_stamp(scan.stamp_ns) + "\n");
  if (pose) add_pose(*pose);
  for (const auto& row : objects) {
    ObjectRow r = row;
    r.scan = scans_;
    r.stamp_ns = scan.stamp_ns;
    objects_->write(r);
  }
  last_stamp_ns_ = scan.stamp_ns;
  ++scans_;
}

void SequenceWriter::finish() {
  if (finished_) return;
  stamps_->close();
  if (poses_) poses_->close();
  if (objects_) objects_->close();
  meta_.scans = scans_;
  if (meta_.columns == 0) meta_.columns = std::max(8, meta_.sensor_model().columns());
  // Written under a temporary name and renamed: sequence.yaml never exists half-written.
  const fs::path tmp = folder_ / "sequence.yaml.tmp";
  write_file(tmp, format_sequence_yaml(meta_));
  std::error_code ec;
  fs::rename(tmp, folder_ / "sequence.yaml", ec);
  if (ec)
    throw core::Error((folder_ / "sequence.yaml").string() + ": cannot create: " + ec.message());
  finished_ = true;
}

// ---------------------------------------------------------------- reader

SequenceReader::SequenceReader(const fs::path& folder, SequenceReadOptions options)
    : options_(std::move(options)) {
  std::error_code ec;
  if (!fs::exists(folder, ec)) throw core::InputError(folder.string() + ": no such folder");
  if (!fs::is_directory(folder, ec)) {
    throw core::InputError(folder.string() + ": expected a folder (sequence or PCD files)");
  }
  if (fs::exists(folder / "sequence.yaml", ec)) {
    open_sequence(folder);
  } else if (fs::exists(folder / "scans", ec)) {
    throw core::InputError(folder.string() +
                           ": has scans/ but no sequence.yaml: an incomplete sequence (its writer "
                           "did not finish)");
  } else {
    open_plain(folder);
  }
  load_stamps_and_poses(folder);
}

void SequenceReader::open_sequence(const fs::path& folder) {
  is_sequence_ = true;
  const fs::path yaml = folder / "sequence.yaml";
  meta_ = read_sequence_yaml(yaml);
  try {
    sensor_ = meta_.sensor_model();
  } catch (const core::InputError&) {
    throw;
  } catch (const core::Error& e) {
    throw core::InputError(yaml.string() + ": " + e.what());
  }
  const fs::path scans = folder / "scans";
  std::error_code ec;
  if (!fs::is_directory(scans, ec)) throw core::InputError(scans.string() + ": no such folder");
  std::vector<std::pair<std::uint64_t, fs::path>> found;
  for (const auto& entry : fs::directory_iterator(scans, ec)) {
    const fs::path& p = entry.path();
    if (lower(p.extension().string()) != ".pcd") continue;
    const std::string stem = p.stem().string();
    if (!is_digits(stem) || stem.size() < 6 || stem.size() > 18 || p.extension() != ".pcd") {
      throw core::InputError(p.string() +
                             ": unexpected file name, expected NNNNNN.pcd (six digits)");
    }
    found.emplace_back(std::stoull(stem), p);
  }
  if (ec) throw core::InputError(scans.string() + ": cannot list: " + ec.message());
  std::sort(found.begin(), found.end());
  for (std::size_t i = 0; i < found.size(); ++i) {
    if (found[i].first != i) {
      throw core::InputError((scans / scan_file_name(i)).string() +
                             ": missing (scans must be numbered from 000000 without gaps)");
    }
    paths_.push_back(found[i].second);
  }
  if (meta_.scans && *meta_.scans != paths_.size()) {
    throw core::InputError(yaml.string() + ": says " + std::to_string(*meta_.scans) +
                           " scans, but scans/ holds " + std::to_string(paths_.size()));
  }
  if (fs::exists(folder / "objects.csv", ec)) objects_csv_ = folder / "objects.csv";
  if (options_.pcd.organize_rings == 0) options_.pcd.organize_rings = sensor_.rings();
}

void SequenceReader::open_plain(const fs::path& folder) {
  is_sequence_ = false;
  std::error_code ec;
  std::vector<fs::path> pcd_files;
  std::vector<fs::path> bin_files;
  for (const auto& entry : fs::directory_iterator(folder, ec)) {
    if (!entry.is_regular_file(ec)) continue;
    const std::string ext = lower(entry.path().extension().string());
    if (ext == ".pcd") pcd_files.push_back(entry.path());
    if (ext == ".bin") bin_files.push_back(entry.path());
  }
  if (ec) throw core::InputError(folder.string() + ": cannot list: " + ec.message());
  if (pcd_files.empty() && bin_files.empty()) {
    throw core::InputError(folder.string() +
                           ": no sequence.yaml, no .pcd and no .bin files (expected a sequence "
                           "folder, a folder of PCD files or a folder of KITTI-style .bin files)");
  }
  if (!pcd_files.empty() && !bin_files.empty()) {
    throw core::InputError(folder.string() + ": holds both .pcd (" +
                           std::to_string(pcd_files.size()) + ") and .bin (" +
                           std::to_string(bin_files.size()) +
                           ") files; expected one kind of scan file");
  }
  std::vector<fs::path> files = pcd_files.empty() ? std::move(bin_files) : std::move(pcd_files);
  std::sort(files.begin(), files.end(), [](const fs::path& a, const fs::path& b) {
    return natural_less(a.filename().string(), b.filename().string());
  });
  paths_ = std::move(files);
  if (!(options_.scan_rate_hz > 0.0)) {
    throw core::InputError(folder.string() + ": scan rate must be positive");
  }
  if (options_.sensor && options_.pcd.organize_rings == 0) {
    options_.pcd.organize_rings = options_.sensor->rings();
  }
  ScanFile first = read_scan_file(paths_.front());
  if (first.cloud) {
    // Clouds without rings: the named sensor's grid, else one measured on the first cloud.
    if (options_.sensor) {
      sensor_ = *options_.sensor;
      sensor_.scan_rate_hz = options_.scan_rate_hz;
    } else {
      sensor_ =
          core::measure_cloud_sensor(*first.cloud, paths_.front().string(), options_.scan_rate_hz);
      std::string range;
      append_fixed(range, sensor_.elevation_rad.front() * kRadToDeg, 3);
      range += "..";
      append_fixed(range, sensor_.elevation_rad.back() * kRadToDeg, 3);
      measured_sensor_ = "sensor measured on " + paths_.front().filename().string() + ": " +
                         std::to_string(sensor_.rings()) + " rings (" + range + " deg), " +
                         std::to_string(sensor_.columns()) + " columns";
    }
    meta_ = SequenceMeta::for_sensor(sensor_, sensor_.columns());
    meta_.scans = paths_.size();
    return;
  }
  const PcdScan& pcd = *first.pcd;
  meta_.scan_rate_hz = options_.scan_rate_hz;
  meta_.columns = pcd.scan.columns();
  meta_.scans = paths_.size();
  if (options_.sensor) {
    sensor_ = *options_.sensor;
    sensor_.scan_rate_hz = options_.scan_rate_hz;
    meta_ = SequenceMeta::for_sensor(sensor_, pcd.scan.columns());
    meta_.scans = paths_.size();
  } else {
    meta_.sensor = "generic";
    meta_.elevations_deg = measure_elevations_deg(pcd.scan, paths_.front().string());
    sensor_ = core::SensorModel::generic(meta_.elevations_deg, std::max(8, meta_.columns),
                                         options_.scan_rate_hz);
  }
}

namespace {

bool increasing(const std::vector<std::int64_t>& stamps) {
  return std::adjacent_find(stamps.begin(), stamps.end(),
                            [](std::int64_t a, std::int64_t b) { return b <= a; }) == stamps.end();
}

}  // namespace

SequenceReader::ScanFile SequenceReader::read_scan_file(const fs::path& path) const {
  ScanFile out;
  const auto bytes = read_file_bytes(path);
  if (lower(path.extension().string()) == ".bin") {
    out.cloud = decode_kitti_bin(bytes, path.string());
    return out;
  }
  if (pcd_needs_organizer(parse_pcd_header(bytes, path.string()), options_.pcd.ring_field)) {
    out.cloud = decode_pcd_cloud(bytes, path.string());
  } else {
    out.pcd = decode_pcd(bytes, path.string(), options_.pcd);
  }
  return out;
}

std::string SequenceReader::summary() const {
  if (organize_totals_.clouds == 0) return {};
  return measured_sensor_.empty() ? organize_totals_.summary()
                                  : measured_sensor_ + "; " + organize_totals_.summary();
}

void SequenceReader::load_stamps_and_poses(const fs::path& folder) {
  std::error_code ec;
  fs::path stamps_file = options_.stamps;
  if (stamps_file.empty() && fs::exists(folder / "stamps.txt", ec))
    stamps_file = folder / "stamps.txt";
  if (!stamps_file.empty()) {
    // Stamps that go back (a host clock step) are read as they are: front ends skip such scans
    // (the pipeline cannot run backwards) rather than refuse the whole folder.
    stamps_ = read_stamps(stamps_file, /*require_increasing=*/false);
    if (stamps_.size() != paths_.size()) {
      throw core::InputError(stamps_file.string() + ": " + std::to_string(stamps_.size()) +
                             " stamps for " + std::to_string(paths_.size()) +
                             " scans; expected one stamp per scan");
    }
  } else {
    stamps_.resize(paths_.size());
    for (std::size_t i = 0; i < paths_.size(); ++i) {
      stamps_[i] = std::llround(static_cast<double>(i) * 1e9 / meta_.scan_rate_hz);
    }
  }
  fs::path poses_file = options_.poses;
  if (poses_file.empty() && fs::exists(folder / "poses.txt", ec)) poses_file = folder / "poses.txt";
  poses_.resize(paths_.size());
  if (poses_file.empty()) {
    for (std::size_t i = 0; i < paths_.size(); ++i) poses_[i].stamp_ns = stamps_[i];
    return;
  }
  has_poses_ = true;
  if (options_.poses_format == PoseFileFormat::kKitti && !increasing(stamps_)) {
    // One pose per scan in scan order: nothing to interpolate, so stamps that go back (the
    // scans front ends skip) need no trajectory, which would refuse them.
    auto poses = read_kitti_poses(poses_file);
    if (poses.size() != stamps_.size()) {
      throw core::InputError(poses_file.string() + ": " + std::to_string(poses.size()) +
                             " KITTI poses for " + std::to_string(stamps_.size()) +
                             " stamps; expected one pose per stamp");
    }
    for (std::size_t i = 0; i < poses.size(); ++i) {
      poses_[i] = poses[i];
      poses_[i].stamp_ns = stamps_[i];
    }
    return;
  }
  const Trajectory trajectory = options_.poses_format == PoseFileFormat::kKitti
                                    ? read_kitti(poses_file, stamps_)
                                    : read_tum(poses_file);
  for (std::size_t i = 0; i < paths_.size(); ++i) {
    if (!trajectory.covers(stamps_[i])) {
      throw core::InputError(
          poses_file.string() + ": no pose for scan " + paths_[i].filename().string() +
          " at stamp " + format_stamp(stamps_[i]) +
          (trajectory.empty() ? std::string(" (the file has no poses)")
                              : " (poses cover " + format_stamp(trajectory.start_ns()) + " to " +
                                    format_stamp(trajectory.end_ns()) + ")"));
    }
    poses_[i] = trajectory.at(stamps_[i]);
  }
}

SequenceScan SequenceReader::read(std::size_t i) const {
  SequenceScan out;
  out.index = i;
  out.path = paths_.at(i);
  ScanFile file = read_scan_file(out.path);
  if (file.cloud) {
    if (!organizer_) organizer_.emplace(sensor_, options_.organizer);
    core::OrganizedCloud organized = organizer_->organize(*file.cloud);
    organize_totals_.add(organized.stats);
    file.pcd.emplace();
    file.pcd->scan = std::move(organized.scan);
  }
  PcdScan& pcd = *file.pcd;
  const std::string origin = is_sequence_ ? "the sensor " + meta_.sensor + " of sequence.yaml"
                                          : "the first scan " + paths_.front().filename().string();
  if (pcd.scan.rings() != sensor_.rings()) {
    throw core::InputError(out.path.string() + ": " + std::to_string(pcd.scan.rings()) +
                           " rings (HEIGHT), expected " + std::to_string(sensor_.rings()) + " as " +
                           origin);
  }
  if (pcd.scan.columns() != meta_.columns) {
    throw core::InputError(out.path.string() + ": " + std::to_string(pcd.scan.columns()) +
                           " columns (WIDTH), expected " + std::to_string(meta_.columns) + " as " +
                           (is_sequence_ ? std::string("sequence.yaml") : origin));
  }
  out.scan = std::move(pcd.scan);
  out.labels = std::move(pcd.labels);
  set_column_stamps(out.scan, stamps_[i], meta_.scan_rate_hz);
  out.pose = poses_[i];
  return out;
}

bool SequenceReader::next(SequenceScan& out) {
  if (next_ >= paths_.size()) return false;
  out = read(next_++);
  return true;
}

}  // namespace ringtrack::io
