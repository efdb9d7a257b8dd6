// `ringtrack eval`: CLEAR MOT, MT/PT/ML and ID metrics of tracks against ground truth, per
// sequence and summed over sequences (docs/evaluation.md).

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "commands.hpp"
#include "plots.hpp"
#include "ringtrack/core/error.hpp"
#include "ringtrack/eval/map_metrics.hpp"
#include "ringtrack/eval/tracking_eval.hpp"
#include "ringtrack/experiment/evaluate_files.hpp"
#include "ringtrack/experiment/results_json.hpp"
#include "ringtrack/io/mot_tables.hpp"
#include "ringtrack/io/pcd.hpp"
#include "ringtrack/io/ply.hpp"
#include "ringtrack/io/sequence.hpp"
#include "ringtrack/mapping/static_map.hpp"

namespace ringtrack::cli {
namespace {

namespace fs = std::filesystem;

struct EvalOptions {
  std::vector<std::string> gt;
  std::vector<std::string> tracks;
  std::string format = "ringtrack";
  double threshold_m = 0.5;
  double min_iou = 0.5;
  bool all_hypotheses = false;         // --all-hypotheses: the same as --hypotheses all
  std::string hypotheses = "dynamic";  // dynamic (paper mode), person or all
  std::string target_class = "person";
  std::int64_t min_points = 1;
  bool ignore_stamps = false;
  double moving_radius_m = 1.0;
  bool json = false;
  std::vector<std::string> filtered;  // per sequence: `ringtrack run --filtered-scans` output
  std::string map_errors_png;         // with --filtered and one sequence: the error picture
};

// Where the dynamic-object filter erred, in the world frame (the third Fig. 7 picture): dynamic
// points it kept and static points it removed, over the static points it kept (the scene, thinned
// to one point per voxel: millions of points otherwise).
struct MapErrorPoints {
  static constexpr float kKept = 0.0f;  // kinds, written as the PLY's intensity
  static constexpr float kDynamicKept = 1.0f;
  static constexpr float kStaticRemoved = 2.0f;
  static constexpr double kSceneVoxelM = 0.2;

  std::vector<Eigen::Vector3f> errors;
  std::vector<float> kind;
  mapping::StaticMap scene{kSceneVoxelM};

  void add(const Eigen::Isometry3f& world_from_sensor, const Eigen::Vector3f& p, bool dynamic,
           bool kept) {
    if (dynamic == kept) {
      errors.push_back(world_from_sensor * p);
      kind.push_back(dynamic ? kDynamicKept : kStaticRemoved);
    } else if (kept) {
      scene.insert(world_from_sensor * p, kKept);
    }  // else a dynamic point removed: right, and gone from the map
  }
  // The scene's voxels, then the errors (drawn on top).
  void write_ply(const fs::path& path) const {
    std::vector<Eigen::Vector3f> points;
    std::vector<float> kinds;
    scene.for_each([&](const mapping::MapPoint& m) {
      points.push_back(m.position);
      kinds.push_back(kKept);
    });
    points.insert(points.end(), errors.begin(), errors.end());
    kinds.insert(kinds.end(), kind.begin(), kind.end());
    io::write_ply(path, points, kinds);
  }
};

struct SequenceResult {
  std::string name;
  std::string gt_path;
  std::string tracks_path;
  eval::TrackingEvalResult result;     // for MOTChallenge only `summary` is filled
  std::optional<eval::MapCounts> map;  // with --filtered
};

// Map metrics of filtered scans against the sequence's per-point labels: a point is dynamic when
// its object moves in any scan of objects.csv (docs/evaluation.md); kept = still valid.
eval::MapCounts evaluate_filtered(const fs::path& sequence_dir, const fs::path& objects_csv,
                                  const fs::path& filtered_dir, MapErrorPoints* errors) {
  std::vector<std::int64_t> dynamic_ids;
  for (const auto& row : io::read_objects_csv(objects_csv)) {
    if (row.moving) dynamic_ids.push_back(row.id);
  }
  std::sort(dynamic_ids.begin(), dynamic_ids.end());
  dynamic_ids.erase(std::unique(dynamic_ids.begin(), dynamic_ids.end()), dynamic_ids.end());
  io::SequenceReader reader(sequence_dir);
  eval::MapCounts counts;
  io::SequenceScan item;
  while (reader.next(item)) {
    if (item.labels.empty()) {
      throw core::InputError(item.path.string() +
                             ": no label field; map metrics need per-point labels");
    }
    char name[32];
    std::snprintf(name, sizeof name, "%06zu.pcd", item.index);
    const fs::path path = filtered_dir / name;
    if (!fs::is_regular_file(path)) {
      throw core::InputError(path.string() + ": missing filtered scan for scan " +
                             std::to_string(item.index));
    }
    const auto filtered = io::read_pcd(path);
    if (filtered.scan.rings() != item.scan.rings() ||
        filtered.scan.columns() != item.scan.columns()) {
      throw core::InputError(path.string() + ": grid " + std::to_string(filtered.scan.rings()) +
                             " x " + std::to_string(filtered.scan.columns()) +
                             " differs from the sequence's " + std::to_string(item.scan.rings()) +
                             " x " + std::to_string(item.scan.columns()));
    }
    const Eigen::Isometry3f world_from_sensor = item.pose.isometry().cast<float>();
    for (std::size_t i = 0; i < item.scan.size(); ++i) {
      if (!item.scan.valid(i)) continue;
      const auto label = static_cast<std::int64_t>(item.labels[i]);
      const bool dynamic =
          label > 0 && std::binary_search(dynamic_ids.begin(), dynamic_ids.end(), label);
      counts.add_point(label, dynamic, filtered.scan.valid(i));
      if (errors)
        errors->add(world_from_sensor, item.scan.point(i), dynamic, filtered.scan.valid(i));
    }
  }
  return counts;
}

// A sequence folder stands for its ground-truth file inside.
fs::path resolve_gt(const std::string& arg, bool motchallenge, std::string& name) {
  fs::path p(arg);
  // Names come from the absolute path so that "." or "objects.csv" still name the folder.
  std::error_code ec;
  fs::path full = fs::weakly_canonical(fs::absolute(p), ec);
  if (ec) full = p;
  if (fs::is_directory(p)) {
    name =
        full.filename().empty() ? full.parent_path().filename().string() : full.filename().string();
    fs::path file = motchallenge ? p / "gt" / "gt.txt" : p / "objects.csv";
    if (!fs::is_regular_file(file)) {
      throw core::InputError(
          arg + ": sequence folder without " +
          (motchallenge ? std::string("gt/gt.txt") : std::string("objects.csv")));
    }
    return file;
  }
  const fs::path parent = full.parent_path();
  name = parent.filename().empty() ? full.stem().string() : parent.filename().string();
  if (motchallenge && name == "gt" && !parent.parent_path().filename().empty()) {
    name = parent.parent_path().filename().string();  // SEQ/gt/gt.txt
  }
  return p;
}

eval::TrackingEvalResult evaluate_ringtrack(const fs::path& gt_path, const fs::path& tracks_path,
                                            const EvalOptions& o) {
  experiment::FileEvalOptions options;
  options.evaluation.threshold_m = o.threshold_m;
  options.evaluation.target_class = o.target_class;
  options.evaluation.min_points = o.min_points;
  options.evaluation.hypotheses = eval::parse_selection(o.hypotheses);
  options.evaluation.moving_radius_m = o.moving_radius_m;
  options.ignore_stamps = o.ignore_stamps;
  return experiment::evaluate_track_files(gt_path, tracks_path, options);
}

eval::TrackingEvalResult evaluate_motchallenge(const fs::path& gt_path, const fs::path& tracks_path,
                                               const EvalOptions& o) {
  const auto convert = [](const std::vector<io::MotChallengeRow>& rows) {
    std::vector<eval::BoxObservation> out;
    out.reserve(rows.size());
    for (const io::MotChallengeRow& r : rows) {
      out.push_back({r.frame, r.id, r.left, r.top, r.width, r.height});
    }
    return out;
  };
  const auto gt = convert(io::read_motchallenge(gt_path, true));
  const auto hyps = convert(io::read_motchallenge(tracks_path, false));
  eval::TrackingEvalResult result;
  result.summary = eval::evaluate_boxes(gt, hyps, o.min_iou);
  result.gt_rows_used = static_cast<std::int64_t>(gt.size());
  result.hypotheses_total = result.summary.hypotheses;
  result.hypotheses_evaluated = result.summary.hypotheses;
  return result;
}

std::string fixed(double v, int decimals) {
  if (!std::isfinite(v)) return "-";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

// One column per sequence (and "overall" with several), one row per metric.
void print_table(const std::vector<SequenceResult>& sequences,
                 std::vector<const eval::MotSummary*> columns, const eval::MotSummary& overall,
                 bool mot) {
  std::vector<std::string> header = {"metric"};
  for (const SequenceResult& s : sequences) header.push_back(s.name);
  if (sequences.size() > 1) {
    header.push_back("overall");
    columns.push_back(&overall);
  }
  using Getter = std::string (*)(const eval::MotSummary&);
  std::vector<std::pair<std::string, Getter>> rows = {
      {"MOTA", [](const eval::MotSummary& s) { return fixed(s.mota(), 4); }},
      {mot ? "MOTP (1-IoU)" : "MOTP (m)",
       [](const eval::MotSummary& s) { return fixed(s.motp(), 4); }},
  };
  if (!mot) {
    rows.emplace_back("MOTP x-y (m)",
                      [](const eval::MotSummary& s) { return fixed(s.horizontal_motp(), 4); });
    rows.emplace_back("z bias (m)",
                      [](const eval::MotSummary& s) { return fixed(s.mean_vertical_error(), 4); });
  }
  const std::vector<std::pair<std::string, Getter>> counts = {
      {"TP (matches+IDSW)",
       [](const eval::MotSummary& s) { return std::to_string(s.true_positives()); }},
      {"matches", [](const eval::MotSummary& s) { return std::to_string(s.matches); }},
      {"FP", [](const eval::MotSummary& s) { return std::to_string(s.false_positives); }},
      {"FN (misses)", [](const eval::MotSummary& s) { return std::to_string(s.misses); }},
      {"IDSW", [](const eval::MotSummary& s) { return std::to_string(s.switches); }},
      {"fragmentations",
       [](const eval::MotSummary& s) { return std::to_string(s.fragmentations); }},
      {"recall", [](const eval::MotSummary& s) { return fixed(s.recall(), 4); }},
      {"precision", [](const eval::MotSummary& s) { return fixed(s.precision(), 4); }},
      {"MT", [](const eval::MotSummary& s) { return std::to_string(s.mostly_tracked); }},
      {"PT", [](const eval::MotSummary& s) { return std::to_string(s.partially_tracked); }},
      {"ML", [](const eval::MotSummary& s) { return std::to_string(s.mostly_lost); }},
      {"MT ratio", [](const eval::MotSummary& s) { return fixed(s.mostly_tracked_ratio(), 4); }},
      {"PT ratio", [](const eval::MotSummary& s) { return fixed(s.partially_tracked_ratio(), 4); }},
      {"ML ratio", [](const eval::MotSummary& s) { return fixed(s.mostly_lost_ratio(), 4); }},
      {"IDF1", [](const eval::MotSummary& s) { return fixed(s.idf1(), 4); }},
      {"IDP", [](const eval::MotSummary& s) { return fixed(s.idp(), 4); }},
      {"IDR", [](const eval::MotSummary& s) { return fixed(s.idr(), 4); }},
      {"GT objects", [](const eval::MotSummary& s) { return std::to_string(s.gt_objects); }},
      {"hypotheses", [](const eval::MotSummary& s) { return std::to_string(s.hypotheses); }},
      {"GT presences", [](const eval::MotSummary& s) { return std::to_string(s.gt_presences); }},
      {"hyp presences",
       [](const eval::MotSummary& s) { return std::to_string(s.hypothesis_presences); }},
      {"frames", [](const eval::MotSummary& s) { return std::to_string(s.frames); }},
  };
  rows.insert(rows.end(), counts.begin(), counts.end());
  std::vector<std::size_t> width(header.size(), 0);
  for (std::size_t c = 0; c < header.size(); ++c) width[c] = header[c].size();
  std::vector<std::vector<std::string>> cells;
  for (const auto& [label, get] : rows) {
    std::vector<std::string> line = {label};
    for (const eval::MotSummary* s : columns) line.push_back(get(*s));
    for (std::size_t c = 0; c < line.size(); ++c) width[c] = std::max(width[c], line[c].size());
    cells.push_back(std::move(line));
  }
  const auto print_line = [&](const std::vector<std::string>& line) {
    for (std::size_t c = 0; c < line.size(); ++c) {
      const std::size_t pad = width[c] - line[c].size();
      if (c == 0) {
        std::cout << line[c] << std::string(pad, ' ');
      } else {
        std::cout << "  " << std::string(pad, ' ') << line[c];
      }
    }
    std::cout << "\n";
  };
  print_line(header);
  for (const auto& line : cells) print_line(line);
}

void print_text(const std::vector<SequenceResult>& sequences, const eval::MotSummary& overall,
                const eval::MotSummary& overall_moving, const EvalOptions& o) {
  const bool mot = o.format == "motchallenge";
  if (mot) {
    std::cout << "MOTChallenge boxes: a pair matches when IoU >= " << o.min_iou
              << "; MOTP is the mean (1 - IoU) of the matches\n";
  } else {
    std::cout << "ground truth: class '" << o.target_class << "' with >= " << o.min_points
              << " hit points; match when distance < " << o.threshold_m << " m; "
              << (o.hypotheses == "all"
                      ? "all hypotheses"
                      : (o.hypotheses == "person"
                             ? "person mode: hypotheses flagged person at least once, moving or "
                               "standing"
                             : "paper mode: hypotheses dynamic at least once"))
              << "\n";
  }
  for (const SequenceResult& s : sequences) {
    std::cout << "sequence " << s.name << ": gt " << s.gt_path << ", tracks " << s.tracks_path;
    if (!mot) {
      std::cout << " (" << s.result.gt_rows_used << " ground-truth rows used, "
                << s.result.gt_rows_skipped << " skipped; " << s.result.hypotheses_evaluated
                << " of " << s.result.hypotheses_total << " hypotheses evaluated)";
    }
    std::cout << "\n";
  }
  std::vector<const eval::MotSummary*> columns;
  for (const SequenceResult& s : sequences) columns.push_back(&s.result.summary);
  print_table(sequences, columns, overall, mot);
  if (mot) return;

  // The second block: ground truth restricted to objects that move (docs/evaluation.md).
  std::cout
      << "\nmoving objects only: ground truth restricted to objects whose x-y position leaves "
         "a disc of radius "
      << o.moving_radius_m
      << " m around their first position; objects that never move are don't-care (a "
         "hypothesis matched to one is neither TP nor FP)\n";
  for (const SequenceResult& s : sequences) {
    std::cout << "sequence " << s.name << ": " << s.result.moving_objects << " moving, "
              << s.result.still_objects << " never-moving (don't-care) objects\n";
  }
  columns.clear();
  for (const SequenceResult& s : sequences) columns.push_back(&s.result.moving_only);
  print_table(sequences, columns, overall_moving, mot);
}

void run_eval(const EvalOptions& o) {
  if (!o.filtered.empty() && o.filtered.size() != o.gt.size()) {
    throw core::InputError("--filtered given " + std::to_string(o.filtered.size()) +
                           " times but --gt " + std::to_string(o.gt.size()) +
                           " times: give one filtered-scans folder per sequence, or none");
  }
  if (o.gt.size() != o.tracks.size()) {
    throw core::InputError("--gt given " + std::to_string(o.gt.size()) + " times but --tracks " +
                           std::to_string(o.tracks.size()) +
                           " times: give one tracks file per sequence, in the same order");
  }
  if (!o.map_errors_png.empty() && (o.filtered.size() != 1)) {
    throw core::InputError(
        "--map-errors-png needs --filtered and exactly one sequence (one picture per run)");
  }
  const bool mot = o.format == "motchallenge";
  std::vector<SequenceResult> sequences;
  MapErrorPoints errors;
  eval::MotSummary overall;
  eval::MotSummary overall_moving;
  eval::MapCounts overall_map;
  for (std::size_t k = 0; k < o.gt.size(); ++k) {
    SequenceResult s;
    const fs::path gt_path = resolve_gt(o.gt[k], mot, s.name);
    const fs::path tracks_path(o.tracks[k]);
    s.gt_path = gt_path.string();
    s.tracks_path = tracks_path.string();
    s.result = mot ? evaluate_motchallenge(gt_path, tracks_path, o)
                   : evaluate_ringtrack(gt_path, tracks_path, o);
    overall += s.result.summary;
    overall_moving += s.result.moving_only;
    if (!o.filtered.empty()) {
      if (mot)
        throw core::InputError(
            "--filtered: map metrics need ringtrack sequences, not MOTChallenge");
      s.map = evaluate_filtered(fs::path(gt_path).parent_path(), gt_path, o.filtered[k],
                                o.map_errors_png.empty() ? nullptr : &errors);
      overall_map += *s.map;
    }
    sequences.push_back(std::move(s));
  }

  if (!o.map_errors_png.empty()) {
    // The points go beside the picture as PLY (intensity = kind), which the script draws.
    const fs::path ply = fs::path(o.map_errors_png).replace_extension(".ply");
    errors.write_ply(ply);
    run_plot_script("plot_map_errors.py", {ply, o.map_errors_png});
  }
  if (!o.json) {
    print_text(sequences, overall, overall_moving, o);
    if (!o.filtered.empty()) {
      for (const auto& s : sequences) {
        std::printf(
            "map %-12s preservation %.4f (%lld of %lld static points kept), rejection %.4f (%lld "
            "of %lld dynamic points removed)\n",
            s.name.c_str(), s.map->preservation_rate(), static_cast<long long>(s.map->static_kept),
            static_cast<long long>(s.map->static_points), s.map->rejection_rate(),
            static_cast<long long>(s.map->dynamic_removed),
            static_cast<long long>(s.map->dynamic_points));
      }
    }
    return;
  }
  nlohmann::ordered_json out;
  out["format"] = o.format;
  if (mot) {
    out["min_iou"] = o.min_iou;
    out["match_rule"] = "IoU >= min_iou";
    out["motp_unit"] = "1-IoU";
  } else {
    out["threshold_m"] = o.threshold_m;
    out["match_rule"] = "distance < threshold_m";
    out["motp_unit"] = "m";
    out["class"] = o.target_class;
    out["min_points"] = o.min_points;
    out["hypotheses"] = o.hypotheses;
    out["all_hypotheses"] = o.hypotheses == "all";
    out["moving_radius_m"] = o.moving_radius_m;
  }
  out["sequences"] = nlohmann::ordered_json::array();
  for (const SequenceResult& s : sequences) {
    nlohmann::ordered_json j = {{"name", s.name}, {"gt", s.gt_path}, {"tracks", s.tracks_path}};
    if (!mot) {
      j["gt_rows_used"] = s.result.gt_rows_used;
      j["gt_rows_skipped"] = s.result.gt_rows_skipped;
      j["hypotheses_total"] = s.result.hypotheses_total;
      j["hypotheses_evaluated"] = s.result.hypotheses_evaluated;
    }
    j["metrics"] = experiment::metrics_json(s.result.summary);
    if (!mot) {
      j["moving_only"] = experiment::moving_only_json(s.result.moving_objects,
                                                      s.result.still_objects, s.result.moving_only);
    }
    if (s.map) j["map"] = experiment::map_json(*s.map);
    out["sequences"].push_back(std::move(j));
  }
  out["overall"] = experiment::metrics_json(overall);
  if (!mot) {
    std::int64_t moving = 0;
    std::int64_t still = 0;
    for (const SequenceResult& s : sequences) {
      moving += s.result.moving_objects;
      still += s.result.still_objects;
    }
    out["overall_moving_only"] = experiment::moving_only_json(moving, still, overall_moving);
  }
  if (!o.filtered.empty()) out["overall_map"] = experiment::map_json(overall_map);
  std::cout << out.dump(2) << "\n";
}

}  // namespace

void register_eval(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "eval", "CLEAR MOT, MT/PT/ML and IDF1 of tracks against ground truth (docs/evaluation.md)");
  auto o = std::make_shared<EvalOptions>();
  cmd->add_option("--gt", o->gt,
                  "ground truth: SEQUENCE_DIR (its objects.csv; motchallenge: its gt/gt.txt) or "
                  "the file; repeat for several sequences")
      ->required();
  cmd->add_option("--tracks", o->tracks,
                  "tracks.csv of `ringtrack run` (motchallenge: a result file); one per --gt")
      ->required();
  cmd->add_option("--format", o->format, "ringtrack (objects.csv/tracks.csv) or motchallenge")
      ->check(CLI::IsMember({"ringtrack", "motchallenge"}))
      ->capture_default_str();
  cmd->add_option("--threshold", o->threshold_m,
                  "a pair matches when its 3-D distance is below this, metres")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--min-iou", o->min_iou, "motchallenge: a pair matches when IoU >= this")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  auto* selection =
      cmd->add_option("--hypotheses", o->hypotheses,
                      "hypotheses to evaluate, each in all its scans: dynamic = those dynamic at "
                      "least once (the paper's mode), person = those flagged person at least "
                      "once (standing people too), all = every one")
          ->check(CLI::IsMember({"dynamic", "person", "all"}))
          ->capture_default_str();
  cmd->add_flag("--all-hypotheses", o->all_hypotheses, "the same as --hypotheses all")
      ->excludes(selection);
  cmd->add_option("--class", o->target_class, "ground-truth class to evaluate")
      ->capture_default_str();
  cmd->add_option("--min-points", o->min_points,
                  "a ground-truth object counts in a scan with at least this many hit points")
      ->check(CLI::Range(std::int64_t{1}, std::int64_t{1} << 40))
      ->capture_default_str();
  cmd->add_flag("--ignore-stamps", o->ignore_stamps,
                "do not require equal stamps for the same scan index in both files");
  cmd->add_option("--moving-radius", o->moving_radius_m,
                  "for the \"moving objects only\" figures: an object moves when its x-y "
                  "position leaves the disc of this radius around its first position, metres")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_flag("--json", o->json, "print JSON instead of a table");
  cmd->add_option(
      "--filtered", o->filtered,
      "per sequence: the filtered/ folder of `ringtrack run --filtered-scans`; adds the "
      "map metrics (preservation and rejection rates, docs/evaluation.md)");
  cmd->add_option("--map-errors-png", o->map_errors_png,
                  "with --filtered and one sequence: a top-down picture of the filter's errors, "
                  "dynamic points kept (red) and static points removed (blue) over the static "
                  "points kept (grey), and the points as PLY beside it (needs "
                  "python3-matplotlib)");
  cmd->callback([o] {
    if (o->all_hypotheses) o->hypotheses = "all";
    run_eval(*o);
  });
}

}  // namespace ringtrack::cli
