// `ringtrack run INPUT --out DIR`: the whole pipeline over a recorded sequence, with its outputs.

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <set>
#include <unistd.h>

#include "commands.hpp"
#include "ringtrack/core/error.hpp"
#include "ringtrack/io/csv_writers.hpp"
#include "ringtrack/io/output_file.hpp"
#include "ringtrack/io/pcd.hpp"
#include "ringtrack/io/ply.hpp"
#include "ringtrack/io/sequence.hpp"
#include "ringtrack/pipeline/pipeline.hpp"

namespace ringtrack::cli {
namespace {

namespace fs = std::filesystem;

struct RunOptions {
  std::string input;
  std::string out;
  std::string poses;
  std::string poses_format{"tum"};
  bool filtered_scans{false};
  bool quiet{false};
  ConfigOptions config;
};

io::TrackRow track_row(std::uint64_t scan, std::int64_t stamp_ns, const tracking::Hypothesis& h) {
  io::TrackRow row;
  row.scan = scan;
  row.stamp_ns = stamp_ns;
  row.id = h.id;
  row.position = h.position();
  row.velocity = h.velocity_mps;
  row.box = h.box;
  row.dynamic = h.dynamic;
  row.ever_dynamic = h.ever_dynamic;
  row.age = static_cast<std::uint32_t>(h.age_scans);
  row.points = static_cast<std::uint32_t>(h.points);
  return row;
}

io::TimingRow timing_row(std::uint64_t scan, std::int64_t stamp_ns, const pipeline::StageTimes& t) {
  return {scan,
          stamp_ns,
          {{"segmentation", t.segmentation_ms},
           {"detection", t.detection_ms},
           {"tracking", t.tracking_ms},
           {"mapping", t.mapping_ms}},
          t.total_ms};
}

double percentile(std::vector<double> values, double q) {
  if (values.empty()) return 0.0;
  const auto k = static_cast<std::size_t>(q * static_cast<double>(values.size() - 1) + 0.5);
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
  return values[k];
}

// The scan with the cells the filter removed marked invalid: what the static map was built from.
core::OrganizedScan without_cells(const core::OrganizedScan& scan, std::span<const std::uint32_t> cells) {
  core::OrganizedScan out = scan;
  for (auto i : cells) out.set_invalid(out.ring_of(i), out.column_of(i), core::ReturnStatus::kNoReturn);
  return out;
}

void run(const RunOptions& o) {
  const core::Config config = o.config.load();
  io::SequenceReadOptions read_options;
  if (!o.poses.empty()) {
    read_options.poses = o.poses;
    read_options.poses_format = o.poses_format == "kitti" ? io::PoseFileFormat::kKitti : io::PoseFileFormat::kTum;
  }
  io::SequenceReader reader(o.input, read_options);
  if (reader.size() == 0) throw core::InputError(o.input + ": no scans found");

  const fs::path out = o.out;
  std::error_code ec;
  fs::create_directories(out, ec);
  if (ec) throw core::InputError(o.out + ": cannot create the output folder: " + ec.message());
  if (o.filtered_scans) fs::create_directories(out / "filtered", ec);
  {
    io::OutputFile config_file(out / "config.yaml");
    config_file.write(core::dump_config(config));
    config_file.close();
  }

  pipeline::Pipeline pipeline(config);
  io::TracksCsvWriter tracks(out / "tracks.csv");
  io::TimingCsvWriter timing(out / "timing.csv");
  std::vector<double> total_ms;
  std::set<std::uint64_t> track_ids, dynamic_ids;
  const bool progress = !o.quiet && isatty(STDERR_FILENO);
  io::SequenceScan item;
  std::vector<io::TrackRow> rows;
  while (reader.next(item)) {
    const auto& result = pipeline.process(item.scan, item.pose);
    rows.clear();
    for (const auto& h : result.hypotheses) {
      rows.push_back(track_row(item.index, item.scan.stamp_ns, h));
      track_ids.insert(h.id);
      if (h.ever_dynamic) dynamic_ids.insert(h.id);
    }
    tracks.write(rows);
    timing.write(timing_row(item.index, item.scan.stamp_ns, result.times));
    total_ms.push_back(result.times.total_ms);
    if (o.filtered_scans) {
      char name[32];
      std::snprintf(name, sizeof name, "%06zu.pcd", item.index);
      io::write_pcd(out / "filtered" / name, without_cells(item.scan, result.removed_cells), {});
    }
    if (progress) std::fprintf(stderr, "\rscan %zu / %zu", item.index + 1, reader.size());
  }
  if (progress) std::fprintf(stderr, "\n");
  pipeline.finish();
  tracks.close();
  timing.close();

  const auto map_points = pipeline.static_map().points();
  std::vector<Eigen::Vector3f> xyz;
  std::vector<float> intensity;
  xyz.reserve(map_points.size());
  intensity.reserve(map_points.size());
  for (const auto& p : map_points) {
    xyz.push_back(p.position);
    intensity.push_back(p.intensity);
  }
  io::write_ply(out / "static_map.ply", xyz, intensity);

  std::printf("scans            %zu\n", total_ms.size());
  std::printf("tracks           %zu (%zu ever dynamic)\n", track_ids.size(), dynamic_ids.size());
  std::printf("static map       %zu voxels\n", map_points.size());
  std::printf("ms per scan      median %.3f, p95 %.3f, max %.3f\n", percentile(total_ms, 0.5),
              percentile(total_ms, 0.95), *std::max_element(total_ms.begin(), total_ms.end()));
  std::printf("outputs          %s/{tracks.csv,timing.csv,static_map.ply,config.yaml%s}\n", o.out.c_str(),
              o.filtered_scans ? ",filtered/" : "");
}

}  // namespace

void register_run(CLI::App& app) {
  auto* cmd = app.add_subcommand("run", "run the pipeline over a sequence folder or a folder of organized PCD files");
  auto o = std::make_shared<RunOptions>();
  cmd->add_option("input", o->input, "sequence folder (docs/formats.md) or folder of organized PCD files")
      ->required();
  cmd->add_option("--out", o->out, "output folder (created)")->required();
  cmd->add_option("--poses", o->poses, "sensor poses (sensor in world) replacing the folder's poses.txt")
      ->check(CLI::ExistingFile);
  cmd->add_option("--poses-format", o->poses_format, "tum (t x y z qx qy qz qw) or kitti (3x4 per scan)")
      ->check(CLI::IsMember({"tum", "kitti"}));
  cmd->add_flag("--filtered-scans", o->filtered_scans,
                "also write each scan without its dynamic-object points as filtered/NNNNNN.pcd");
  cmd->add_flag("--quiet", o->quiet, "no progress on stderr");
  o->config.add_to(*cmd);
  cmd->callback([o] { run(*o); });
}

}  // namespace ringtrack::cli
