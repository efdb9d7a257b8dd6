#include "ringtrack/io/foxglove_sink.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <unordered_set>

#include "ringtrack/io/foxglove_proto.hpp"
#include "ringtrack/io/text.hpp"

namespace ringtrack::io {
namespace {

namespace fg = foxglove;

// Colours: dynamic tracks warm, static ones cool, so a glance tells which objects moved.
constexpr fg::Color kDynamic{1.0, 0.35, 0.1, 0.6};
constexpr fg::Color kStatic{0.2, 0.55, 1.0, 0.6};
constexpr fg::Color kText{1.0, 1.0, 1.0, 1.0};
constexpr fg::Color kDetection{0.95, 0.9, 0.2, 0.35};
constexpr fg::Color kRelaxedDetection{0.7, 0.7, 0.7, 0.35};
constexpr double kMinArrowSpeedMps = 0.05;  // slower tracks get no arrow (reported speed is 0)

std::uint64_t log_time(std::int64_t stamp_ns) {
  return static_cast<std::uint64_t>(std::max<std::int64_t>(stamp_ns, 0));
}

void key_value(ProtoWriter& w, std::uint32_t field, std::string_view key, std::string_view value) {
  const auto at = w.begin(field);
  w.string(1, key);
  w.string(2, value);
  w.end(at);
}

std::string fixed(double v, int decimals) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

// A "deletion of all entities" before each update: the scene shows exactly this scan's state.
void delete_all(ProtoWriter& w, std::int64_t stamp_ns) {
  const auto at = w.begin(1);
  fg::timestamp(w, 1, stamp_ns);
  w.varint(2, 1);  // SceneEntityDeletion.Type.ALL
  w.end(at);
}

void cube(ProtoWriter& w, std::uint32_t field, const core::Box3& box, const fg::Color& c) {
  const auto at = w.begin(field);
  fg::pose(w, 1, ((box.min + box.max) * 0.5F).cast<double>());
  fg::vector3(w, 2, (box.max - box.min).cast<double>().cwiseMax(0.01));
  fg::color(w, 3, c);
  w.end(at);
}

template <typename T>
void put(std::uint8_t* p, T v) {
  std::memcpy(p, &v, sizeof v);
}

}  // namespace

FoxgloveSink::FoxgloveSink(const std::filesystem::path& path, FoxgloveSinkOptions options)
    : options_(std::move(options)), writer_(path, options_.mcap) {
  const auto& descriptors = fg::descriptor_set();
  const auto cloud = writer_.add_schema(fg::kPointCloud, "protobuf", descriptors);
  const auto scene = writer_.add_schema(fg::kSceneUpdate, "protobuf", descriptors);
  const auto transform = writer_.add_schema(fg::kFrameTransform, "protobuf", descriptors);
  scan_channel_ = writer_.add_channel(cloud, kMcapScanTopic, "protobuf");
  transform_channel_ = writer_.add_channel(transform, kMcapTransformTopic, "protobuf");
  detections_channel_ = writer_.add_channel(scene, kMcapDetectionsTopic, "protobuf");
  tracks_channel_ = writer_.add_channel(scene, kMcapTracksTopic, "protobuf");
  map_channel_ = writer_.add_channel(cloud, kMcapMapTopic, "protobuf");
}

void FoxgloveSink::write_metadata(const std::string& name, const McapStringMap& entries) {
  writer_.write_metadata(name, entries);
}

void FoxgloveSink::write_frame(const core::OrganizedScan& scan, const core::Pose& pose,
                               const pipeline::FrameResult& result, const mapping::StaticMap& map) {
  stamp_ns_ = result.stamp_ns;
  write_transform(pose);
  write_cloud(scan, result);
  write_detections(result);
  write_tracks(result);
  ++stats_.scans;
  if (options_.map_every_scans > 0 && stats_.scans % options_.map_every_scans == 0) {
    write_map(map, stamp_ns_);
  }
}

void FoxgloveSink::write_pipeline_frame(const core::OrganizedScan& scan,
                                        const core::Pose& world_pose,
                                        const pipeline::FrameResult& result,
                                        const mapping::StaticMap& map) {
  if (stats_.scans == 0) write_metadata("frame", {{"origin_m", origin_comment(result.origin)}});
  core::Pose local = world_pose;
  local.translation -= result.origin;
  write_frame(scan, local, result, map);
}

void FoxgloveSink::finish(const mapping::StaticMap& map, std::int64_t stamp_ns) {
  write_map(map, stamp_ns);
  writer_.close();
}

void FoxgloveSink::write_transform(const core::Pose& pose) {
  ProtoWriter& w = message_;
  w.clear();
  fg::timestamp(w, 1, stamp_ns_);
  w.string(2, options_.world_frame);
  w.string(3, options_.sensor_frame);
  fg::vector3(w, 4, pose.translation);
  fg::quaternion(w, 5, pose.rotation.normalized());
  writer_.write_message(transform_channel_, log_time(stamp_ns_), log_time(stamp_ns_), w.bytes());
}

// The per-cell label arrays stay zero between scans: only the cells of detections and the
// removed cells are set, and reset once the cloud is written, so a scan costs its labelled cells
// rather than clearing three arrays of every cell.
void FoxgloveSink::label_cells(const pipeline::FrameResult& result, std::size_t cells) {
  if (cell_track_.size() != cells) {
    cell_track_.assign(cells, 0);
    cell_detection_.assign(cells, 0);
    cell_removed_.assign(cells, 0);
  }
  labelled_.clear();
  std::vector<std::uint32_t> detection_track(result.detections.size(), 0);
  for (const auto& h : result.hypotheses) {
    if (h.reported && h.detection >= 0 &&
        static_cast<std::size_t>(h.detection) < detection_track.size()) {
      detection_track[static_cast<std::size_t>(h.detection)] =
          static_cast<std::uint32_t>(std::min<std::uint64_t>(h.id, 0xFFFFFFFFU));
    }
  }
  for (std::size_t k = 0; k < result.detections.size(); ++k) {
    const auto label = static_cast<std::uint16_t>(std::min<std::size_t>(k + 1, 0xFFFF));
    const auto mark = [&](std::uint32_t cell) {
      if (cell >= cells) return;
      cell_detection_[cell] = label;
      cell_track_[cell] = detection_track[k];
      labelled_.push_back(cell);
    };
    for (const auto cell : result.detections[k].indices) mark(cell);
    for (const auto cell : result.detections[k].completion) mark(cell);
  }
  for (const auto cell : result.removed_cells) {
    if (cell >= cells) continue;
    cell_removed_[cell] = 1;
    labelled_.push_back(cell);
  }
}

void FoxgloveSink::clear_labels() {
  for (const auto cell : labelled_) {
    cell_track_[cell] = 0;
    cell_detection_[cell] = 0;
    cell_removed_[cell] = 0;
  }
  labelled_.clear();
}

void FoxgloveSink::write_cloud(const core::OrganizedScan& scan,
                               const pipeline::FrameResult& result) {
  const std::size_t cells = scan.size();
  label_cells(result, cells);

  // The message's small fields go to message_; the points are written straight into the MCAP
  // chunk (add_message), so the ~300 kB of a VLP-16 scan are written once, not copied.
  const std::size_t points = scan.valid_count();
  ProtoWriter& w = message_;
  w.clear();
  fg::timestamp(w, 1, stamp_ns_);
  w.string(2, options_.sensor_frame);
  fg::pose(w, 3, Eigen::Vector3d::Zero());
  w.fixed32(4, kMcapScanPointStride);
  fg::packed_field(w, 5, "x", 0, fg::NumericType::kFloat32);
  fg::packed_field(w, 5, "y", 4, fg::NumericType::kFloat32);
  fg::packed_field(w, 5, "z", 8, fg::NumericType::kFloat32);
  fg::packed_field(w, 5, "intensity", 12, fg::NumericType::kFloat32);
  fg::packed_field(w, 5, "track_id", 16, fg::NumericType::kUint32);
  fg::packed_field(w, 5, "detection", 20, fg::NumericType::kUint16);
  fg::packed_field(w, 5, "segment", 22, fg::NumericType::kUint8);
  fg::packed_field(w, 5, "removed", 23, fg::NumericType::kUint8);
  w.bytes_header(6, points * kMcapScanPointStride);
  const auto head = w.bytes();
  const auto out = writer_.add_message(scan_channel_, log_time(stamp_ns_), log_time(stamp_ns_),
                                       head.size() + points * kMcapScanPointStride);
  std::memcpy(out.data(), head.data(), head.size());
  std::uint8_t* p = out.data() + head.size();
  const auto& xs = scan.xs();
  const auto& ys = scan.ys();
  const auto& zs = scan.zs();
  const auto& in = scan.intensities();
  const auto& labels = result.segment_labels;
  for (std::size_t i = 0; i < cells; ++i) {
    if (!scan.valid(i)) continue;
    put(p, xs[i]);
    put(p + 4, ys[i]);
    put(p + 8, zs[i]);
    put(p + 12, in[i]);
    put(p + 16, cell_track_[i]);
    put(p + 20, cell_detection_[i]);
    p[22] = i < labels.size() ? labels[i] : 0;
    p[23] = cell_removed_[i];
    p += kMcapScanPointStride;
  }
  clear_labels();
  stats_.points += points;
}

void FoxgloveSink::write_detections(const pipeline::FrameResult& result) {
  ProtoWriter& w = message_;
  w.clear();
  delete_all(w, stamp_ns_);
  if (!result.detections.empty()) {
    const auto entity = w.begin(2);
    fg::timestamp(w, 1, stamp_ns_);
    w.string(2, options_.world_frame);
    w.string(3, "detections");
    for (const auto& d : result.detections) {
      cube(w, 8, d.box, d.relaxed ? kRelaxedDetection : kDetection);
    }
    w.end(entity);
  }
  writer_.write_message(detections_channel_, log_time(stamp_ns_), log_time(stamp_ns_), w.bytes());
}

void FoxgloveSink::write_tracks(const pipeline::FrameResult& result) {
  std::unordered_set<std::uint64_t> alive;
  for (const auto& h : result.hypotheses) {
    alive.insert(h.id);
    if (!h.reported) continue;
    auto& trail = trajectories_[h.id];
    trail.push_back(h.reported_position);
    while (trail.size() > std::max<std::size_t>(options_.trajectory_points, 1)) trail.pop_front();
  }
  std::erase_if(trajectories_, [&](const auto& kv) { return alive.count(kv.first) == 0; });

  ProtoWriter& w = message_;
  w.clear();
  delete_all(w, stamp_ns_);
  for (const auto& h : result.hypotheses) {
    if (!h.reported) continue;
    const fg::Color& c = h.dynamic ? kDynamic : kStatic;
    const auto entity = w.begin(2);
    fg::timestamp(w, 1, stamp_ns_);
    w.string(2, options_.world_frame);
    w.string(3, "track/" + std::to_string(h.id));
    key_value(w, 6, "id", std::to_string(h.id));
    key_value(w, 6, "dynamic", h.dynamic ? "1" : "0");
    key_value(w, 6, "ever_dynamic", h.ever_dynamic ? "1" : "0");
    key_value(w, 6, "person", h.person ? "1" : "0");
    key_value(w, 6, "speed_mps", fixed(h.velocity_mps.norm(), 3));
    key_value(w, 6, "points", std::to_string(h.points));
    const double speed = h.velocity_mps.norm();
    if (speed >= kMinArrowSpeedMps) {
      // Length: the distance covered in one second.
      const auto arrow = w.begin(7);
      fg::pose(w, 1, h.reported_position,
               Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitX(), h.velocity_mps));
      w.double_field(2, speed);
      w.double_field(3, 0.05);
      w.double_field(4, 0.2);
      w.double_field(5, 0.15);
      fg::color(w, 6, {c.r, c.g, c.b, 1.0});
      w.end(arrow);
    }
    if (!h.box.empty()) cube(w, 8, h.box, c);
    const auto& trail = trajectories_[h.id];
    if (trail.size() >= 2) {
      const auto line = w.begin(11);  // LINE_STRIP is type 0, the default
      fg::pose(w, 2, Eigen::Vector3d::Zero());
      w.double_field(3, 0.04);
      for (const auto& p : trail) fg::vector3(w, 5, p);
      fg::color(w, 6, {c.r, c.g, c.b, 1.0});
      w.end(line);
    }
    {
      const double top = h.box.empty() ? h.reported_position.z() + 1.0 : h.box.max.z() + 0.3;
      const auto text = w.begin(13);
      fg::pose(w, 1, {h.reported_position.x(), h.reported_position.y(), top});
      w.varint(2, 1);  // billboard
      w.double_field(3, 0.4);
      fg::color(w, 5, kText);
      w.string(6, std::to_string(h.id) + (h.person ? " person" : ""));
      w.end(text);
    }
    w.end(entity);
    ++stats_.track_entities;
  }
  writer_.write_message(tracks_channel_, log_time(stamp_ns_), log_time(stamp_ns_), w.bytes());
}

void FoxgloveSink::write_map(const mapping::StaticMap& map, std::int64_t stamp_ns) {
  ProtoWriter& w = message_;
  w.clear();
  w.reserve_more(256 + map.size() * kMcapMapPointStride);
  fg::timestamp(w, 1, stamp_ns);
  w.string(2, options_.world_frame);
  fg::pose(w, 3, Eigen::Vector3d::Zero());
  w.fixed32(4, kMcapMapPointStride);
  fg::packed_field(w, 5, "x", 0, fg::NumericType::kFloat32);
  fg::packed_field(w, 5, "y", 4, fg::NumericType::kFloat32);
  fg::packed_field(w, 5, "z", 8, fg::NumericType::kFloat32);
  fg::packed_field(w, 5, "intensity", 12, fg::NumericType::kFloat32);
  w.bytes_header(6, map.size() * kMcapMapPointStride);
  std::uint8_t* p = w.grow(map.size() * kMcapMapPointStride);
  map.for_each([&](const mapping::MapPoint& m) {
    put(p, m.position.x());
    put(p + 4, m.position.y());
    put(p + 8, m.position.z());
    put(p + 12, m.intensity);
    p += kMcapMapPointStride;
  });
  writer_.write_message(map_channel_, log_time(stamp_ns), log_time(stamp_ns), w.bytes());
  ++stats_.maps;
}

}  // namespace ringtrack::io
