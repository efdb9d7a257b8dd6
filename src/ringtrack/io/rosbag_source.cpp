#include "ringtrack/io/rosbag_source.hpp"

#include <algorithm>

#include "ringtrack/core/error.hpp"
#include "ringtrack/io/velodyne_packet.hpp"

namespace ringtrack::io {
namespace {

bool is_ouster_packets(const std::string& type) {
  const std::string t = normalize_ros_type(type);
  return t == kOusterPacketRosType || t == kOusterRos1PacketRosType;
}

bool is_supported(const std::string& type) {
  const std::string t = normalize_ros_type(type);
  return t == kVelodyneScanRosType || t == kPointCloud2RosType || t == kPandarScanRosType ||
         is_ouster_packets(t);
}

// A topic the first-supported-topic choice may take: ouster-ros publishes IMU packets with the
// lidar packets' type (/ouster/imu_packets), which the decoder cannot use.
bool selectable(const RosbagTopicInfo& t) {
  return is_supported(t.type) &&
         !(is_ouster_packets(t.type) && t.name.find("imu") != std::string::npos);
}

std::string list_topics(const std::vector<RosbagTopicInfo>& topics) {
  std::string s;
  for (const auto& t : topics) s += (s.empty() ? "" : ", ") + t.name + " (" + t.type + ")";
  return s.empty() ? "none" : s;
}

}  // namespace

std::vector<VelodyneScanPacket> parse_velodyne_scan(std::span<const std::uint8_t> message,
                                                    RosSerialization serialization,
                                                    const std::string& where) {
  RosMessageCursor in(message, serialization, where + ": VelodyneScan");
  in.header_stamp_ns();
  // A packet: time stamp (8 bytes) and a fixed-size uint8[1206] (no length prefix); CDR aligns
  // each stamp to 4 bytes.
  const std::uint32_t count = in.sequence_length(8 + kVelodyneDataPacketBytes, "packets");
  std::vector<VelodyneScanPacket> packets(count);
  for (auto& p : packets) {
    p.stamp_ns = in.time_ns();
    p.data = in.bytes(kVelodyneDataPacketBytes);
  }
  // DDS pads a CDR payload to a multiple of 4 bytes (the real bag's messages end with 2 such
  // bytes), so only ROS 1 messages must end exactly after the last packet.
  if (serialization == RosSerialization::kRos1 && in.remaining() != 0) {
    in.fail(std::to_string(in.remaining()) + " bytes after the last packet (expected none)");
  }
  return packets;
}

std::vector<PandarScanPacket> parse_pandar_scan(std::span<const std::uint8_t> message,
                                                RosSerialization serialization,
                                                const std::string& where) {
  constexpr std::size_t kBuffer = 1500;
  RosMessageCursor in(message, serialization, where + ": PandarScan");
  in.header_stamp_ns();
  const std::uint32_t count = in.sequence_length(8 + kBuffer + 4, "packets");
  std::vector<PandarScanPacket> packets(count);
  for (auto& p : packets) {
    p.stamp_ns = in.time_ns();
    const auto buffer = in.bytes(kBuffer);
    const std::uint32_t size = in.u32();
    if (size > kBuffer) {
      in.fail("packet size " + std::to_string(size) + " (expected at most 1500)");
    }
    p.data = buffer.first(size);
  }
  return packets;
}

std::span<const std::uint8_t> parse_ouster_packet_msg(std::span<const std::uint8_t> message,
                                                      RosSerialization serialization,
                                                      const std::string& where) {
  RosMessageCursor in(message, serialization, where + ": PacketMsg");
  const std::uint32_t size = in.sequence_length(1, "buf bytes");
  const auto buf = in.bytes(size);
  // As for VelodyneScan: CDR payloads may be padded to 4 bytes, ROS 1 messages end here.
  if (serialization == RosSerialization::kRos1 && in.remaining() != 0) {
    in.fail(std::to_string(in.remaining()) + " bytes after the packet (expected none)");
  }
  return buf;
}

RosbagScanSource::RosbagScanSource(const std::filesystem::path& path, RosbagSourceOptions options)
    : RosbagScanSource(open_rosbag(path), std::move(options)) {}

RosbagScanSource::RosbagScanSource(std::unique_ptr<RosbagReader> reader,
                                   RosbagSourceOptions options)
    : reader_(std::move(reader)),
      decoder_(std::move(options.decoder)),
      organizer_(std::move(options.cloud)) {
  const auto& topics = reader_->topics();
  const std::string bag = reader_->path().string();
  if (!options.topic.empty()) {
    reader_->select_topic(options.topic);  // throws for unknown topics
    topic_ = *std::find_if(topics.begin(), topics.end(),
                           [&](const RosbagTopicInfo& t) { return t.name == options.topic; });
    if (!is_supported(topic_.type)) {
      throw core::InputError(bag + ": topic " + topic_.name + " has type " + topic_.type +
                             "; expected velodyne_msgs/VelodyneScan, pandar_msgs/PandarScan or "
                             "sensor_msgs/PointCloud2, or Ouster packets "
                             "(ouster_sensor_msgs/PacketMsg)");
    }
  } else {
    // The first supported topic that has messages, else the first supported one.
    auto it = std::find_if(topics.begin(), topics.end(), [](const RosbagTopicInfo& t) {
      return selectable(t) && t.messages > 0;
    });
    if (it == topics.end()) it = std::find_if(topics.begin(), topics.end(), selectable);
    if (it == topics.end()) {
      throw core::InputError(bag +
                             ": no velodyne_msgs/VelodyneScan, pandar_msgs/PandarScan or "
                             "sensor_msgs/PointCloud2 topic, nor Ouster lidar packets "
                             "(ouster_sensor_msgs/PacketMsg) (topics: " +
                             list_topics(topics) + ")");
    }
    topic_ = *it;
    reader_->select_topic(topic_.name);
  }
  packets_topic_ = normalize_ros_type(topic_.type) == kVelodyneScanRosType;
  if (is_ouster_packets(topic_.type)) open_ouster(options);
  if (normalize_ros_type(topic_.type) == kPandarScanRosType) {
    if (options.hesai.calibration.channels() == 0) {
      if (options.calibration_path.empty()) {
        throw core::InputError(bag + ": topic " + topic_.name +
                               " holds Hesai packets; give the sensor's angle-correction file "
                               "with --calibration FILE");
      }
      options.hesai.calibration = sensors::hesai::read_hesai_calibration(options.calibration_path);
    }
    // The first packet must fit the calibration (and a named model): found here, before a
    // front end creates any output, rather than at the first next().
    {
      auto probe = open_rosbag(reader_->path());
      probe->select_topic(topic_.name);
      RosbagMessage message;
      if (probe->next(message)) {
        const std::string at = probe->current_file().string() + " (topic " + topic_.name +
                               ", message " + std::to_string(message.index) + ")";
        const auto packets = parse_pandar_scan(message.data, probe->serialization(), at);
        if (!packets.empty()) {
          sensors::hesai::HesaiDecoder check(options.hesai);
          try {
            check.add_packet(packets.front().data, packets.front().stamp_ns);
          } catch (const core::InputError& e) {
            throw core::InputError(at + ": " + e.what());
          }
        }
      }
    }
    hesai_.emplace(std::move(options.hesai));
  }
}

void RosbagScanSource::open_ouster(const RosbagSourceOptions& options) {
  const std::string bag = reader_->path().string();
  if (options.metadata_path.empty()) {
    throw core::InputError(bag + ": topic " + topic_.name +
                           " holds Ouster packets; give the sensor's metadata JSON with "
                           "--metadata FILE");
  }
  ouster_.emplace(sensors::ouster::read_ouster_metadata(options.metadata_path), options.ouster);
  // The first packet must fit the metadata: found here, before a front end creates any output.
  auto probe = open_rosbag(reader_->path());
  probe->select_topic(topic_.name);
  RosbagMessage message;
  if (!probe->next(message)) return;
  const std::string at = probe->current_file().string() + " (topic " + topic_.name + ", message " +
                         std::to_string(message.index) + ")";
  sensors::ouster::OusterDecoder check(ouster_->metadata(), options.ouster);
  try {
    check.add_packet(parse_ouster_packet_msg(message.data, probe->serialization(), at),
                     message.stamp_ns);
  } catch (const core::InputError& e) {
    throw core::InputError(at + ": " + e.what());
  }
}

std::optional<core::OrganizedScan> RosbagScanSource::next_ouster() {
  if (auto scan = ouster_->pop_scan()) return scan;
  RosbagMessage message;
  while (!finished_) {
    if (!reader_->next(message)) {
      finished_ = true;
      if (ouster_->stats().decoded_packets == 0) {
        throw core::InputError(reader_->path().string() +
                               ": no decodable Ouster lidar packets on " + topic_.name + " (" +
                               std::to_string(stats_.messages) + " messages)");
      }
      ouster_->finish();
      break;
    }
    ++stats_.messages;
    const std::string at = where(message.index);
    const auto packet = parse_ouster_packet_msg(message.data, reader_->serialization(), at);
    ++stats_.packets;
    try {
      ouster_->add_packet(packet, message.stamp_ns);  // the packets carry their own stamps
    } catch (const core::InputError& e) {
      throw core::InputError(at + ": " + e.what());
    }
    if (auto scan = ouster_->pop_scan()) return scan;
  }
  return ouster_->pop_scan();
}

std::string RosbagScanSource::where(std::uint64_t index) const {
  return reader_->current_file().string() + " (topic " + topic_.name + ", message " +
         std::to_string(index) + ")";
}

std::optional<core::OrganizedScan> RosbagScanSource::next_hesai() {
  RosbagMessage message;
  if (auto scan = hesai_->pop_scan()) return scan;
  while (!finished_) {
    if (!reader_->next(message)) {
      finished_ = true;
      if (hesai_->stats().decoded_packets == 0) {
        throw core::InputError(reader_->path().string() + ": no decodable Hesai packets on " +
                               topic_.name + " (" + std::to_string(stats_.messages) +
                               " messages, " + std::to_string(stats_.packets) + " packets)");
      }
      hesai_->finish();
      break;
    }
    ++stats_.messages;
    const std::string at = where(message.index);
    const auto packets = parse_pandar_scan(message.data, reader_->serialization(), at);
    stats_.packets += packets.size();
    try {
      for (const auto& p : packets) hesai_->add_packet(p.data, p.stamp_ns);
    } catch (const core::InputError& e) {
      throw core::InputError(at + ": " + e.what());
    }
    if (auto scan = hesai_->pop_scan()) return scan;
  }
  return hesai_->pop_scan();
}

std::optional<core::OrganizedScan> RosbagScanSource::next() {
  if (ouster_) return next_ouster();
  if (hesai_) return next_hesai();
  RosbagMessage message;
  if (!packets_topic_) {
    while (!finished_) {
      if (!reader_->next(message)) {
        finished_ = true;
        if (stats_.messages == 0) {
          throw core::InputError(reader_->path().string() + ": topic " + topic_.name +
                                 " holds no messages");
        }
        break;
      }
      ++stats_.messages;
      const std::string at = where(message.index);
      const PointCloud2 cloud = parse_pointcloud2(message.data, reader_->serialization(), at);
      return organizer_.organize(cloud, at);
    }
    return std::nullopt;
  }
  if (auto scan = decoder_.pop_scan()) return scan;
  while (!finished_) {
    if (!reader_->next(message)) {
      finished_ = true;
      if (decoder_.stats().decoded_packets == 0) {
        throw core::InputError(reader_->path().string() +
                               ": no decodable Velodyne data packets on " + topic_.name + " (" +
                               std::to_string(stats_.messages) + " messages, " +
                               std::to_string(stats_.packets) + " packets)");
      }
      decoder_.finish();
      break;
    }
    ++stats_.messages;
    const std::string at = where(message.index);
    const auto packets = parse_velodyne_scan(message.data, reader_->serialization(), at);
    stats_.packets += packets.size();
    try {
      for (const auto& p : packets) decoder_.add_packet(p.data, p.stamp_ns);
    } catch (const core::InputError& e) {
      throw core::InputError(at + ": " + e.what());
    }
    if (auto scan = decoder_.pop_scan()) return scan;
  }
  return decoder_.pop_scan();
}

const core::SensorModel& RosbagScanSource::model() const {
  if (hesai_) return hesai_->model();
  if (ouster_) return ouster_->model();
  return packets_topic_ ? decoder_.model() : organizer_.model();
}

std::string RosbagScanSource::description() const {
  return reader_->path().string() + " (ROS bag, topic " + topic_.name + ")";
}

std::string RosbagScanSource::summary() const {
  std::string line =
      std::to_string(stats_.messages) + " messages of " + topic_.name + " (" + topic_.type + ")";
  const auto add = [&line](const char* what, std::uint64_t n) {
    if (n > 0) line += ", " + std::to_string(n) + " " + what;
  };
  if (hesai_) {
    const auto& d = hesai_->stats();
    line += ", " + std::to_string(d.decoded_packets) + " Hesai packets decoded, " +
            std::to_string(d.scans) + " scans";
    add("skipped packets", d.skipped_packets());
    add("lost firing blocks", d.lost_blocks);
    add("invalid columns", d.invalid_columns);
    add("partial scans dropped", d.partial_scans_dropped);
  } else if (ouster_) {
    const auto& d = ouster_->stats();
    line += ", " + std::to_string(d.decoded_packets) + " Ouster lidar packets decoded (" +
            sensors::ouster::to_string(ouster_->metadata().profile) + "), " +
            std::to_string(d.scans) + " scans";
    add("wrong-size packets", d.wrong_size);
    add("columns flagged invalid", d.invalid_columns);
    add("bad measurement ids", d.bad_measurement_id);
    add("lost columns", d.lost_columns);
    add("partial scans dropped", d.partial_scans_dropped);
  } else if (packets_topic_) {
    const auto& d = decoder_.stats();
    line += ", " + std::to_string(d.decoded_packets) + " data packets decoded, " +
            std::to_string(d.scans) + " scans";
    add("skipped data packets", d.skipped_packets());
    add("lost firing sequences", d.lost_sequences);
    add("invalid columns", d.invalid_columns);
    add("partial scans dropped", d.partial_scans_dropped);
  } else {
    const auto& o = organizer_.stats();
    line += ", " + std::to_string(o.clouds) + " scans from " + std::to_string(o.points) + " points";
    add("empty points", o.empty_points);
    add("points that lost their cell to a nearer one", o.dropped_points);
    add("points with a bad ring", o.bad_ring_points);
    if (o.ringless.clouds > 0) line += "; without a ring field: " + o.ringless.summary();
  }
  add("messages of other topics ignored", reader_->other_messages());
  return line;
}

}  // namespace ringtrack::io
