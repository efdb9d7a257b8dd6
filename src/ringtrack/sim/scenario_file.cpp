#include "ringtrack/sim/scenario_file.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <sstream>

#include "ringtrack/core/error.hpp"

namespace ringtrack::sim {
namespace {

// Strict reader of one YAML map: every key must be consumed; messages name source:line: entry.
class MapReader {
 public:
  MapReader(const YAML::Node& node, std::string source, std::string entry)
      : node_(node), source_(std::move(source)), entry_(std::move(entry)) {
    if (!node_.IsMap()) fail(node_, "expected a map");
  }
  [[noreturn]] void fail(const YAML::Node& at, const std::string& what) const {
    throw core::ConfigError(source_ + ":" + std::to_string(at.Mark().line + 1) + ": " + entry_ +
                            ": " + what);
  }
  [[nodiscard]] const std::string& entry() const { return entry_; }
  const std::string& source() const { return source_; }
  YAML::Node get(const char* key) {
    seen_.insert(key);
    return node_[key];
  }
  void number(const char* key, double& v) {
    const YAML::Node n = get(key);
    if (!n) return;
    if (!n.IsScalar()) fail(n, std::string(key) + ": expected a number");
    try {
      v = n.as<double>();
    } catch (const YAML::Exception&) {
      fail(n, std::string(key) + ": expected a number, got '" + n.Scalar() + "'");
    }
    if (!std::isfinite(v)) fail(n, std::string(key) + ": expected a finite number");
  }
  void integer(const char* key, int& v) {
    const YAML::Node n = get(key);
    if (!n) return;
    try {
      v = n.as<int>();
    } catch (const YAML::Exception&) {
      fail(n, std::string(key) + ": expected an integer, got '" +
                  (n.IsScalar() ? n.Scalar() : "?") + "'");
    }
  }
  void text(const char* key, std::string& v) {
    const YAML::Node n = get(key);
    if (!n) return;
    if (!n.IsScalar()) fail(n, std::string(key) + ": expected text");
    v = n.Scalar();
  }
  void boolean(const char* key, bool& v) {
    const YAML::Node n = get(key);
    if (!n) return;
    try {
      v = n.as<bool>();
    } catch (const YAML::Exception&) {
      fail(n, std::string(key) + ": expected true or false");
    }
  }
  std::vector<double> numbers(const YAML::Node& n, const std::string& key, std::size_t min_n,
                              std::size_t max_n) {
    if (!n.IsSequence() || n.size() < min_n || n.size() > max_n) {
      std::string what = key;
      what += ": expected a list of ";
      what += std::to_string(min_n);
      if (min_n != max_n) {
        what += "-";
        what += std::to_string(max_n);
      }
      what += " numbers";
      fail(n, what);
    }
    std::vector<double> out;
    for (const auto& x : n) {
      try {
        out.push_back(x.as<double>());
      } catch (const YAML::Exception&) {
        fail(x, key + ": expected numbers");
      }
    }
    return out;
  }
  template <int N>
  void vec(const char* key, Eigen::Matrix<double, N, 1>& v) {
    const YAML::Node n = get(key);
    if (!n) return;
    const auto xs = numbers(n, key, N, N);
    for (int i = 0; i < N; ++i) v[i] = xs[static_cast<std::size_t>(i)];
  }
  // Throws on keys not consumed by the getters above.
  void finish(const std::vector<const char*>& allowed) const {
    for (const auto& kv : node_) {
      // A list or map used as a key (`[-25, 20]: ...`) has no name: as<std::string>() would
      // throw yaml-cpp's own exception, which is no core::Error (found by fuzz_scenario).
      if (!kv.first.IsScalar()) fail(kv.first, "expected a key name, got a list or map as key");
      const auto key = kv.first.as<std::string>();
      if (!seen_.count(key)) {
        std::string list;
        for (const char* a : allowed) list += (list.empty() ? "" : ", ") + std::string(a);
        fail(kv.first, "unknown key '" + key + "' (expected " + list + ")");
      }
    }
  }

 private:
  YAML::Node node_;
  std::string source_, entry_;
  std::set<std::string> seen_;
};

template <typename F>
void each_entry(MapReader& top, const char* key, F&& f) {
  const YAML::Node list = top.get(key);
  if (!list) return;
  if (!list.IsSequence()) top.fail(list, std::string(key) + ": expected a list");
  for (std::size_t i = 0; i < list.size(); ++i) {
    MapReader r(list[i], top.source(), std::string(key) + "[" + std::to_string(i) + "]");
    f(r);
  }
}

std::string motion_name(SensorMotion m) {
  switch (m) {
    case SensorMotion::kStatic:
      return "static";
    case SensorMotion::kFigure8:
      return "figure8";
    case SensorMotion::kScripted:
      return "scripted";
  }
  return "static";
}

std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw core::InputError(path.string() + ": cannot open file");
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// The scenario in a parsed YAML document; parse_scenario_yaml turns what yaml-cpp throws
// itself (a conversion the checks here missed) into a ConfigError. Long because it reads the
// format key by key in the documented order (docs/simulator.md), each with its own message.
Scenario scenario_from_yaml(const YAML::Node& root, const std::string& source) {
  Scenario s;
  MapReader top(root, source, "scenario");
  top.text("name", s.name);
  top.text("description", s.description);
  top.number("duration_s", s.duration_s);
  top.vec<2>("area_m", s.area_m);
  top.vec<2>("area_center_m", s.area_center_m);
  top.number("world_radius_m", s.world_radius_m);
  if (const YAML::Node g = top.get("ground")) {
    MapReader r(g, source, "ground");
    r.boolean("enabled", s.ground.enabled);
    r.number("height_m", s.ground.height_m);
    r.number("amplitude_m", s.ground.amplitude_m);
    r.number("wavelength_m", s.ground.wavelength_m);
    r.number("phase_rad", s.ground.phase_rad);
    double refl = s.ground.reflectivity;
    r.number("reflectivity", refl);
    s.ground.reflectivity = static_cast<float>(refl);
    r.finish({"enabled", "height_m", "amplitude_m", "wavelength_m", "phase_rad", "reflectivity"});
  }
  if (const YAML::Node n = top.get("sensor")) {
    MapReader r(n, source, "sensor");
    auto& z = s.sensor;
    r.text("model", z.model);
    r.vec<3>("position_m", z.position_m);
    std::string motion = motion_name(z.motion);
    r.text("motion", motion);
    if (motion == "static")
      z.motion = SensorMotion::kStatic;
    else if (motion == "figure8")
      z.motion = SensorMotion::kFigure8;
    else if (motion == "scripted")
      z.motion = SensorMotion::kScripted;
    else
      r.fail(n["motion"], "motion: expected static, figure8 or scripted, got '" + motion + "'");
    r.number("figure8_radius_m", z.figure8_radius_m);
    r.number("max_speed_mps", z.max_speed_mps);
    r.number("tilt_gain", z.tilt_gain);
    r.number("range_noise_m", z.range_noise_m);
    r.number("dropout_probability", z.dropout_probability);
    r.number("far_dropout_probability", z.far_dropout_probability);
    if (const YAML::Node k = r.get("keyframes")) {
      if (!k.IsSequence())
        r.fail(k, "keyframes: expected a list of [t, x, y, z, roll, pitch, yaw]");
      for (const auto& row : k) {
        const auto v = r.numbers(row, "keyframes", 7, 7);
        z.keyframes.push_back({v[0], {v[1], v[2], v[3]}, {v[4], v[5], v[6]}});
      }
    }
    r.finish({"model", "position_m", "motion", "figure8_radius_m", "max_speed_mps", "tilt_gain",
              "range_noise_m", "dropout_probability", "far_dropout_probability", "keyframes"});
  }
  if (const YAML::Node n = top.get("actors")) {
    MapReader r(n, source, "actors");
    r.integer("people", s.people);
    r.integer("robots", s.robots);
    r.integer("drones", s.drones);
    r.text("trajectories", s.trajectories_file);
    if (const YAML::Node d = r.get("distractors")) {
      if (!d.IsSequence()) r.fail(d, "distractors: expected a list of [x, y]");
      for (const auto& row : d) {
        const auto v = r.numbers(row, "distractors", 2, 2);
        s.distractors.emplace_back(v[0], v[1]);
      }
    }
    r.finish({"people", "robots", "drones", "distractors", "trajectories"});
  }
  each_entry(top, "boxes", [&](MapReader& r) {
    BoxSpec b;
    r.vec<2>("center_m", b.center_m);
    r.vec<3>("size_m", b.size_m);
    r.number("base_z_m", b.base_z_m);
    r.number("yaw_deg", b.yaw_deg);
    r.number("reflectivity", b.reflectivity);
    r.finish({"center_m", "size_m", "base_z_m", "yaw_deg", "reflectivity"});
    s.boxes.push_back(b);
  });
  each_entry(top, "cylinders", [&](MapReader& r) {
    CylinderSpec c;
    r.vec<2>("center_m", c.center_m);
    r.number("radius_m", c.radius_m);
    r.number("height_m", c.height_m);
    r.number("base_z_m", c.base_z_m);
    r.number("reflectivity", c.reflectivity);
    r.finish({"center_m", "radius_m", "height_m", "base_z_m", "reflectivity"});
    s.cylinders.push_back(c);
  });
  each_entry(top, "ellipsoids", [&](MapReader& r) {
    EllipsoidSpec e;
    r.vec<3>("center_m", e.center_m);
    r.vec<3>("radii_m", e.radii_m);
    r.number("yaw_deg", e.yaw_deg);
    r.number("reflectivity", e.reflectivity);
    r.finish({"center_m", "radii_m", "yaw_deg", "reflectivity"});
    s.ellipsoids.push_back(e);
  });
  each_entry(top, "walls", [&](MapReader& r) {
    WallSpec w;
    r.vec<2>("from_m", w.from_m);
    r.vec<2>("to_m", w.to_m);
    r.number("height_m", w.height_m);
    r.number("thickness_m", w.thickness_m);
    r.number("base_z_m", w.base_z_m);
    r.number("reflectivity", w.reflectivity);
    r.finish({"from_m", "to_m", "height_m", "thickness_m", "base_z_m", "reflectivity"});
    s.walls.push_back(w);
  });
  top.finish({"name", "description", "duration_s", "area_m", "area_center_m", "world_radius_m",
              "ground", "sensor", "actors", "boxes", "cylinders", "ellipsoids", "walls"});
  if (s.name.empty()) s.name = source;
  return s;
}

}  // namespace

Scenario parse_scenario_yaml(const std::string& text, const std::string& source) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
    return scenario_from_yaml(root, source);
  } catch (const YAML::Exception& e) {
    throw core::ConfigError(source + ":" + std::to_string(e.mark.line + 1) +
                            ": invalid YAML: " + e.msg);
  }
}

namespace {

// Columns of a trajectory CSV, in their positional order (files without a header).
enum Column : std::uint8_t {
  kT,
  kId,
  kClass,
  kX,
  kY,
  kZ,
  kHeight,
  kWidth,
  kReflectivity,
  kColumns
};
constexpr const char* kColumnNames[kColumns] = {"t", "id",       "class",   "x",           "y",
                                                "z", "height_m", "width_m", "reflectivity"};

std::vector<std::string> split_csv_line(const std::string& line) {
  std::vector<std::string> f;
  std::stringstream ss(line);
  for (std::string cell; std::getline(ss, cell, ',');) {
    const auto a = cell.find_first_not_of(" \t"), b = cell.find_last_not_of(" \t");
    f.push_back(a == std::string::npos ? "" : cell.substr(a, b - a + 1));
  }
  if (!line.empty() && line.back() == ',') f.emplace_back();  // a trailing empty cell
  return f;
}

bool parses_as_number(const std::string& text) {
  try {
    std::size_t used = 0;
    (void)std::stod(text, &used);
    return used == text.size();
  } catch (const std::exception&) {
    return false;
  }
}

std::string all_column_names() {
  std::string out;
  for (const char* n : kColumnNames) out += (out.empty() ? "" : ", ") + std::string(n);
  return out;
}

// Where each column sits in a row. Files without a header are positional; a header may name the
// columns in any order and leave optional ones out.
struct CsvLayout {
  int column_at[kColumns]{};  // field index of each column, -1 = absent
  bool header_seen = false;
  std::size_t expected_fields = 0;  // with a header: at most its size ...
  std::size_t required_fields = 0;  // ... and at least up to its last required column
};

CsvLayout positional_layout() {
  CsvLayout layout;
  for (int c = 0; c < kColumns; ++c) layout.column_at[c] = c;
  return layout;
}

// Refuses unknown, repeated and missing required columns here, so that rows can trust the layout.
CsvLayout layout_from_header(const std::vector<std::string>& f, const std::string& where) {
  CsvLayout layout;
  layout.header_seen = true;
  layout.expected_fields = f.size();
  for (int c = 0; c < kColumns; ++c) layout.column_at[c] = -1;
  for (std::size_t i = 0; i < f.size(); ++i) {
    const std::string& name = f[i];
    int c = 0;
    while (c < kColumns && name != kColumnNames[c]) ++c;
    if (c == kColumns) {
      throw core::InputError(where + "header: unknown column '" + name + "' (expected " +
                             all_column_names() + ")");
    }
    if (layout.column_at[c] >= 0)
      throw core::InputError(where + "header: column '" + name + "' given twice");
    layout.column_at[c] = static_cast<int>(i);
  }
  for (const int c : {kT, kId, kClass, kX, kY}) {
    layout.required_fields =
        std::max(layout.required_fields, static_cast<std::size_t>(layout.column_at[c] + 1));
    if (layout.column_at[c] < 0) {
      throw core::InputError(where + "header: column '" + kColumnNames[c] +
                             "' is missing (t, id, class, x, y are required)");
    }
  }
  return layout;
}

// Trailing optional cells may be left out (as "t,id,class,x,y" rows under a header with z).
void check_field_count(const CsvLayout& layout, std::size_t fields, const std::string& where) {
  if (layout.header_seen ? (fields < layout.required_fields || fields > layout.expected_fields)
                         : (fields < 5 || fields > kColumns)) {
    throw core::InputError(
        where +
        (layout.header_seen
             ? "expected " + std::to_string(layout.required_fields) + "-" +
                   std::to_string(layout.expected_fields) + " fields as the header says"
             : std::string("expected t, id, class, x, y[, z[, height_m[, width_m[, "
                           "reflectivity]]]]")) +
        " (" + std::to_string(fields) + " fields)");
  }
}

// One data row seen through the layout; its errors name the line, the field and the column.
class CsvRow {
 public:
  CsvRow(const std::vector<std::string>& f, const CsvLayout& layout, const std::string& where)
      : f_(f), layout_(layout), where_(where) {}

  [[nodiscard]] const std::string& where() const { return where_; }

  // Cell of column c, or nullptr when the column is absent or the row ends before it (optional
  // ones; number() treats an empty optional cell as absent).
  [[nodiscard]] const std::string* cell(int c) const {
    const int i = layout_.column_at[c];
    if (i < 0 || static_cast<std::size_t>(i) >= f_.size()) return nullptr;
    return &f_[static_cast<std::size_t>(i)];
  }

  // Text of a column known to be present (required columns; the field count was checked).
  [[nodiscard]] const std::string& text_of(int c) const {
    return f_[static_cast<std::size_t>(layout_.column_at[c])];
  }

  // "field 4 (x): ", the prefix of every message about one cell.
  [[nodiscard]] std::string field_label(int c) const {
    return "field " + std::to_string(layout_.column_at[c] + 1) + " (" + kColumnNames[c] + "): ";
  }

  [[nodiscard]] std::optional<double> number(int c, bool required) const {
    const std::string* text_cell = cell(c);
    if (!text_cell || (!required && text_cell->empty())) return std::nullopt;
    double v = 0.0;
    try {
      std::size_t used = 0;
      v = std::stod(*text_cell, &used);
      if (used != text_cell->size() || !std::isfinite(v)) throw std::invalid_argument("x");
    } catch (const std::exception&) {
      throw core::InputError(where_ + field_label(c) + "expected a number, got '" + *text_cell +
                             "'");
    }
    return v;
  }

 private:
  const std::vector<std::string>& f_;
  const CsvLayout& layout_;
  const std::string& where_;
};

std::uint32_t parse_actor_id(const std::string& id_text, const std::string& where) {
  unsigned long id = 0;
  try {
    std::size_t used = 0;
    id = std::stoul(id_text, &used);
    if (used != id_text.size() || id == 0 || id > 0xffffffffUL) throw std::invalid_argument("x");
  } catch (const std::exception&) {
    throw core::InputError(where + "id: expected an integer >= 1, got '" + id_text + "'");
  }
  return static_cast<std::uint32_t>(id);
}

ObjectClass parse_actor_class(const std::string& text, const std::string& where) {
  try {
    return class_from_name(text);
  } catch (const core::Error& e) {
    throw core::InputError(where + e.what());
  }
}

// Gathers the rows into actors by id. Body values are per actor, so each one remembers the line
// that first gave it, for the message when a later row disagrees.
class TrajectoryRows {
 public:
  void add(const CsvRow& row, std::size_t line_no) {
    const double t = *row.number(kT, true);
    const double x = *row.number(kX, true);
    const double y = *row.number(kY, true);
    const double z = row.number(kZ, false).value_or(std::nan(""));
    const std::string& id_text = row.text_of(kId);
    const std::uint32_t id = parse_actor_id(id_text, row.where());
    const ObjectClass c = parse_actor_class(row.text_of(kClass), row.where());
    auto& a = by_id_[id];
    if (!a.waypoints.empty() && a.object_class != c) {
      throw core::InputError(row.where() + "id " + id_text + " changes class");
    }
    a.id = id;
    a.object_class = c;
    if (!a.waypoints.empty() && !(t > a.waypoints.back().t_s)) {
      throw core::InputError(row.where() + "id " + id_text + ": times must increase");
    }
    body(row, line_no, a, kHeight, a.height_m, kMinBodyHeightM, kMaxBodyHeightM, "height (m)");
    body(row, line_no, a, kWidth, a.width_m, kMinBodyWidthM, kMaxBodyWidthM, "width (m)");
    body(row, line_no, a, kReflectivity, a.reflectivity, 0.0, 1.0, "reflectivity");
    a.waypoints.push_back({t, {x, y, z}});
  }

  std::vector<ScriptedActor> actors() && {
    std::vector<ScriptedActor> out;
    for (auto& [id, a] : by_id_) out.push_back(std::move(a));
    return out;
  }

 private:
  // Body values: per actor, within their range, the same on every row that gives them.
  void body(const CsvRow& row, std::size_t line_no, const ScriptedActor& a, int col,
            std::optional<double>& slot, double lo, double hi, const char* what) {
    const std::optional<double> v = row.number(col, false);
    if (!v) return;
    const bool has_body =
        a.object_class == ObjectClass::kPerson || a.object_class == ObjectClass::kDistractor;
    const std::string& where = row.where();
    const std::string column = row.field_label(col);
    if (col != kReflectivity && !has_body) {
      throw core::InputError(where + column + "a body " + what +
                             " applies to people and distractors only, not to a " +
                             std::string(class_name(a.object_class)));
    }
    if (!(*v >= lo && *v <= hi)) {
      std::ostringstream m;
      m << where << column << "expected a " << what << " in [" << lo << ", " << hi << "], got '"
        << row.text_of(col) << "'";
      throw core::InputError(m.str());
    }
    const auto key = std::make_pair(a.id, col);
    if (slot && *slot != *v) {
      std::ostringstream m;
      m << where << column << "id " << a.id << " already has " << *slot << " (line "
        << body_line_[key] << "); body values are per actor";
      throw core::InputError(m.str());
    }
    if (!slot) body_line_[key] = line_no;
    slot = v;
  }

  std::map<std::uint32_t, ScriptedActor> by_id_;
  // Line where each actor's body values were first given (they must agree on every row).
  std::map<std::pair<std::uint32_t, int>, std::size_t> body_line_;
};

}  // namespace

std::vector<ScriptedActor> parse_trajectories_csv(std::string_view text,
                                                  const std::string& source) {
  TrajectoryRows rows;
  CsvLayout layout = positional_layout();  // until a header says otherwise
  bool first_row = true;
  std::size_t line_no = 0;
  std::size_t pos = 0;
  while (pos <= text.size()) {
    const std::size_t end = std::min(text.find('\n', pos), text.size());
    std::string line(text.substr(pos, end - pos));
    pos = end + 1;
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const auto first = line.find_first_not_of(" \t");
    if (first == std::string::npos || line[first] == '#') continue;
    const std::vector<std::string> f = split_csv_line(line);
    const std::string where = source + ":" + std::to_string(line_no) + ": ";
    if (first_row) {
      first_row = false;
      // The header is the first line that is neither blank nor a comment, when its first cell is
      // not a number.
      if (!f.empty() && !parses_as_number(f[0])) {
        layout = layout_from_header(f, where);
        continue;
      }
    }
    check_field_count(layout, f.size(), where);
    rows.add(CsvRow(f, layout, where), line_no);
  }
  return std::move(rows).actors();
}

std::string format_trajectories_csv(const std::vector<ScriptedActor>& actors) {
  std::ostringstream out;
  out.precision(17);  // exact round trip
  out << "t,id,class,x,y,z,height_m,width_m,reflectivity\n";
  const auto optional = [&](const std::optional<double>& v) {
    if (v) out << *v;
  };
  for (const ScriptedActor& a : actors) {
    for (std::size_t i = 0; i < a.waypoints.size(); ++i) {
      const Waypoint& w = a.waypoints[i];
      out << w.t_s << "," << a.id << "," << class_name(a.object_class) << "," << w.xyz_m.x() << ","
          << w.xyz_m.y() << ",";
      if (std::isfinite(w.xyz_m.z())) out << w.xyz_m.z();
      out << ",";
      if (i == 0) optional(a.height_m);
      out << ",";
      if (i == 0) optional(a.width_m);
      out << ",";
      if (i == 0) optional(a.reflectivity);
      out << "\n";
    }
  }
  return out.str();
}

Scenario load_scenario_file(const std::filesystem::path& path) {
  Scenario s = parse_scenario_yaml(read_text(path), path.string());
  if (!s.trajectories_file.empty()) {
    std::filesystem::path csv = s.trajectories_file;
    if (csv.is_relative()) csv = path.parent_path() / csv;
    s.scripted = parse_trajectories_csv(read_text(csv), csv.string());
  }
  validate(s, path.string());
  return s;
}

Scenario resolve_scenario(const std::string& arg) {
  const std::filesystem::path p(arg);
  if (p.extension() == ".yaml" || p.extension() == ".yml" || std::filesystem::is_regular_file(p)) {
    return load_scenario_file(p);
  }
  return builtin_scenario(arg);
}

// Long because it writes every field of the scenario in the file format's order: the mirror of
// scenario_from_yaml, kept as one readable sequence.
std::string format_scenario_yaml(const Scenario& s) {
  YAML::Emitter out;
  out.SetDoublePrecision(10);
  const auto v2 = [&](const Eigen::Vector2d& v) {
    out << YAML::Flow << YAML::BeginSeq << v.x() << v.y() << YAML::EndSeq;
  };
  const auto v3 = [&](const Eigen::Vector3d& v) {
    out << YAML::Flow << YAML::BeginSeq << v.x() << v.y() << v.z() << YAML::EndSeq;
  };
  out << YAML::BeginMap;
  out << YAML::Key << "name" << YAML::Value << s.name;
  out << YAML::Key << "description" << YAML::Value << s.description;
  out << YAML::Key << "duration_s" << YAML::Value << s.duration_s;
  out << YAML::Key << "area_m" << YAML::Value;
  v2(s.area_m);
  out << YAML::Key << "area_center_m" << YAML::Value;
  v2(s.area_center_m);
  out << YAML::Key << "world_radius_m" << YAML::Value << s.world_radius_m;
  out << YAML::Key << "ground" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "enabled" << YAML::Value << s.ground.enabled;
  out << YAML::Key << "height_m" << YAML::Value << s.ground.height_m;
  out << YAML::Key << "amplitude_m" << YAML::Value << s.ground.amplitude_m;
  out << YAML::Key << "wavelength_m" << YAML::Value << s.ground.wavelength_m;
  out << YAML::Key << "phase_rad" << YAML::Value << s.ground.phase_rad;
  out << YAML::Key << "reflectivity" << YAML::Value << static_cast<double>(s.ground.reflectivity);
  out << YAML::EndMap;
  const auto& z = s.sensor;
  out << YAML::Key << "sensor" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "model" << YAML::Value << z.model;
  out << YAML::Key << "position_m" << YAML::Value;
  v3(z.position_m);
  out << YAML::Key << "motion" << YAML::Value << motion_name(z.motion);
  out << YAML::Key << "figure8_radius_m" << YAML::Value << z.figure8_radius_m;
  out << YAML::Key << "max_speed_mps" << YAML::Value << z.max_speed_mps;
  out << YAML::Key << "tilt_gain" << YAML::Value << z.tilt_gain;
  out << YAML::Key << "range_noise_m" << YAML::Value << z.range_noise_m;
  out << YAML::Key << "dropout_probability" << YAML::Value << z.dropout_probability;
  out << YAML::Key << "far_dropout_probability" << YAML::Value << z.far_dropout_probability;
  if (!z.keyframes.empty()) {
    out << YAML::Key << "keyframes" << YAML::Value << YAML::BeginSeq;
    for (const auto& k : z.keyframes) {
      out << YAML::Flow << YAML::BeginSeq << k.t_s << k.xyz_m.x() << k.xyz_m.y() << k.xyz_m.z()
          << k.rpy_deg.x() << k.rpy_deg.y() << k.rpy_deg.z() << YAML::EndSeq;
    }
    out << YAML::EndSeq;
  }
  out << YAML::EndMap;
  out << YAML::Key << "actors" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "people" << YAML::Value << s.people;
  out << YAML::Key << "robots" << YAML::Value << s.robots;
  out << YAML::Key << "drones" << YAML::Value << s.drones;
  out << YAML::Key << "distractors" << YAML::Value << YAML::BeginSeq;
  for (const auto& d : s.distractors) v2(d);
  out << YAML::EndSeq;
  if (!s.trajectories_file.empty())
    out << YAML::Key << "trajectories" << YAML::Value << s.trajectories_file;
  out << YAML::EndMap;
  out << YAML::Key << "boxes" << YAML::Value << YAML::BeginSeq;
  for (const auto& b : s.boxes) {
    out << YAML::Flow << YAML::BeginMap << YAML::Key << "center_m" << YAML::Value;
    v2(b.center_m);
    out << YAML::Key << "size_m" << YAML::Value;
    v3(b.size_m);
    out << YAML::Key << "base_z_m" << YAML::Value << b.base_z_m << YAML::Key << "yaw_deg"
        << YAML::Value << b.yaw_deg << YAML::Key << "reflectivity" << YAML::Value << b.reflectivity
        << YAML::EndMap;
  }
  out << YAML::EndSeq;
  out << YAML::Key << "cylinders" << YAML::Value << YAML::BeginSeq;
  for (const auto& c : s.cylinders) {
    out << YAML::Flow << YAML::BeginMap << YAML::Key << "center_m" << YAML::Value;
    v2(c.center_m);
    out << YAML::Key << "radius_m" << YAML::Value << c.radius_m << YAML::Key << "height_m"
        << YAML::Value << c.height_m << YAML::Key << "base_z_m" << YAML::Value << c.base_z_m
        << YAML::Key << "reflectivity" << YAML::Value << c.reflectivity << YAML::EndMap;
  }
  out << YAML::EndSeq;
  out << YAML::Key << "ellipsoids" << YAML::Value << YAML::BeginSeq;
  for (const auto& e : s.ellipsoids) {
    out << YAML::Flow << YAML::BeginMap << YAML::Key << "center_m" << YAML::Value;
    v3(e.center_m);
    out << YAML::Key << "radii_m" << YAML::Value;
    v3(e.radii_m);
    out << YAML::Key << "yaw_deg" << YAML::Value << e.yaw_deg << YAML::Key << "reflectivity"
        << YAML::Value << e.reflectivity << YAML::EndMap;
  }
  out << YAML::EndSeq;
  out << YAML::Key << "walls" << YAML::Value << YAML::BeginSeq;
  for (const auto& w : s.walls) {
    out << YAML::Flow << YAML::BeginMap << YAML::Key << "from_m" << YAML::Value;
    v2(w.from_m);
    out << YAML::Key << "to_m" << YAML::Value;
    v2(w.to_m);
    out << YAML::Key << "height_m" << YAML::Value << w.height_m << YAML::Key << "thickness_m"
        << YAML::Value << w.thickness_m << YAML::Key << "base_z_m" << YAML::Value << w.base_z_m
        << YAML::Key << "reflectivity" << YAML::Value << w.reflectivity << YAML::EndMap;
  }
  out << YAML::EndSeq;
  out << YAML::EndMap;
  return std::string(
             "# ringtrack simulator scenario (docs/formats.md, \"Simulator scenario files\")\n") +
         out.c_str() + "\n";
}

}  // namespace ringtrack::sim
