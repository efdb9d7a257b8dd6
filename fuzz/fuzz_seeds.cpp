#include "fuzz_seeds.hpp"

#include <cmath>
#include <cstdint>
#include <fstream>
#include <iterator>
#include <limits>
#include <numbers>
#include <span>
#include <string>
#include <vector>

#include "ringtrack/core/config.hpp"
#include "ringtrack/core/organized_scan.hpp"
#include "ringtrack/core/pose.hpp"
#include "ringtrack/io/csv_writers.hpp"
#include "ringtrack/io/kitti_bin.hpp"
#include "ringtrack/io/mcap_writer.hpp"
#include "ringtrack/io/pcd.hpp"
#include "ringtrack/io/poses.hpp"
#include "ringtrack/io/sequence.hpp"
#include "ringtrack/sensors/hesai/hesai_format.hpp"
#include "support/hesai_encoder.hpp"
#include "support/ouster_encoder.hpp"
#include "support/rosbag_writers.hpp"
#include "support/velodyne_encoder.hpp"
#include "support/zstd_util.hpp"

namespace ringtrack::fuzz {
namespace {

namespace fs = std::filesystem;
using Bytes = std::vector<std::uint8_t>;

Bytes read_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void put(const fs::path& dir, const std::string& name, const Bytes& bytes) {
  fs::create_directories(dir);
  std::ofstream out(dir / name, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
}

void put(const fs::path& dir, const std::string& name, const std::string& text) {
  put(dir, name, Bytes(text.begin(), text.end()));
}

Bytes concat(std::initializer_list<std::span<const std::uint8_t>> parts) {
  Bytes out;
  for (const auto& p : parts) out.insert(out.end(), p.begin(), p.end());
  return out;
}

Bytes as_bytes(const std::string& s) {
  return {s.begin(), s.end()};
}

Bytes u16_le(std::size_t v) {
  return {static_cast<std::uint8_t>(v & 0xFF), static_cast<std::uint8_t>((v >> 8) & 0xFF)};
}

// A ring of returns whose range varies with the column, so that scans hold a little structure.
test::VelodyneEchoPair echo(long long sequence, int laser) {
  const auto d = static_cast<std::uint16_t>(2000 + 37 * ((sequence + laser) % 50));
  return {{d, static_cast<std::uint8_t>(laser * 9)}, {static_cast<std::uint16_t>(d + 300), 5}};
}

std::vector<test::EncodedVelodynePacket> velodyne_packets(int count, std::uint8_t mode = 0x37) {
  test::VelodyneEncoder encoder({.return_mode = mode});
  return encoder.encode(0, count, echo);
}

Bytes pcap_bytes(const std::vector<test::PcapFrame>& frames, const fs::path& scratch) {
  const fs::path path = scratch / "seed.pcap";
  test::write_pcap(path, test::PcapLink::kEthernet, frames);
  return read_bytes(path);
}

void velodyne_seeds(const fs::path& out, const fs::path& scratch) {
  Bytes decoder{0x00};
  for (const auto& p : velodyne_packets(3)) {
    decoder.push_back(0x01);
    decoder.insert(decoder.end(), p.payload.begin(), p.payload.end());
  }
  put(out / "fuzz_velodyne_decoder", "three_packets", decoder);
  const auto frames = test::frame_packets(test::PcapLink::kEthernet, velodyne_packets(3));
  put(out / "fuzz_velodyne_pcap", "three_packets_raw",
      concat({Bytes{0x00}, pcap_bytes(frames, scratch)}));
}

void sensor_pcap_seeds(const fs::path& out, const fs::path& scratch) {
  const std::string calibration = test::hesai_calibration_csv(32);
  test::HesaiEncoder hesai({.model = "PandarXT32"});
  std::vector<test::PcapFrame> frames;
  const auto hesai_echo = [](long long, int c) {
    const test::HesaiEcho e{static_cast<std::uint16_t>(1000 + 10 * c), 40};
    return std::pair{e, e};
  };
  std::int64_t stamp = 1'700'000'000'000'000'000;
  for (const auto& p : hesai.encode(0, 3, hesai_echo)) {
    frames.push_back(test::udp_frame(test::PcapLink::kEthernet, p, 2368, stamp += 500'000));
  }
  // fuzz_hesai_decoder: control = the format's index (strongest return), no calibration text,
  // then each packet led by 0x20 (the format's size plus the UDP sequence number).
  const auto formats = sensors::hesai::hesai_formats();
  std::uint8_t index = 0;
  while (std::string(formats[index].name) != "PandarXT32") ++index;
  Bytes decoder{index, 0x00};
  for (const auto& p : hesai.encode(0, 3, hesai_echo)) {
    decoder.push_back(0x20);
    decoder.insert(decoder.end(), p.begin(), p.end());
  }
  put(out / "fuzz_hesai_decoder", "xt32_three_packets", decoder);
  put(out / "fuzz_sensor_pcap", "hesai_xt32_raw",
      concat({Bytes{0x02}, u16_le(calibration.size()), as_bytes(calibration),
              pcap_bytes(frames, scratch)}));

  const test::OusterEncoderOptions options{.pixels_per_column = 16, .columns_per_packet = 16};
  const std::string metadata = test::ouster_metadata_json(options);
  frames.clear();
  Bytes decoder_input{0x05, 0x00};  // fuzz_ouster_decoder: RNG19 single return, 16 beams, no text
  for (int packet = 0; packet < 3; ++packet) {
    const auto bytes = test::encode_ouster_packet(options, packet * 16, stamp, [](int m, int beam) {
      return test::OusterEcho{static_cast<std::uint32_t>(3000 + 10 * (m + beam)), 0, 50};
    });
    frames.push_back(test::udp_frame(test::PcapLink::kEthernet, bytes, 7502, stamp += 1'600'000));
    decoder_input.push_back(0x00);  // the metadata's packet size
    decoder_input.insert(decoder_input.end(), bytes.begin(), bytes.end());
  }
  put(out / "fuzz_ouster_decoder", "rng19_three_packets", decoder_input);
  // The _DUAL profile (control: profile 2, 16 beams, the last return).
  test::OusterEncoderOptions dual = options;
  dual.profile = "RNG19_RFL8_SIG16_NIR16_DUAL";
  Bytes dual_input{0x46, 0x00};
  for (int packet = 0; packet < 3; ++packet) {
    const auto bytes = test::encode_ouster_packet(dual, packet * 16, stamp, [](int m, int beam) {
      const auto r = static_cast<std::uint32_t>(3000 + 10 * (m + beam));
      return test::OusterEcho{r, (m + beam) % 2 == 0 ? r + 500 : r - 500, 50, 20};
    });
    dual_input.push_back(0x00);
    dual_input.insert(dual_input.end(), bytes.begin(), bytes.end());
  }
  put(out / "fuzz_ouster_decoder", "dual_last_three_packets", dual_input);
  put(out / "fuzz_sensor_pcap", "ouster_rng19_raw",
      concat(
          {Bytes{0x03}, u16_le(metadata.size()), as_bytes(metadata), pcap_bytes(frames, scratch)}));
}

test::TestPointCloud2 small_cloud(bool with_ring) {
  std::vector<test::TestPoint> points;
  for (int ring = 0; ring < 16; ++ring) {
    for (int c = 0; c < 8; ++c) {
      const double azimuth = 0.3 * c, elevation = (-15.0 + 2.0 * ring) * std::numbers::pi / 180.0;
      const double r = 5.0 + 0.1 * c;
      points.push_back({static_cast<float>(r * std::cos(elevation) * std::cos(azimuth)),
                        static_cast<float>(r * std::cos(elevation) * std::sin(azimuth)),
                        static_cast<float>(r * std::sin(elevation)), 10.0F,
                        static_cast<std::uint16_t>(ring), 1e-5F * static_cast<float>(c)});
    }
  }
  return test::make_xyzirt_cloud(points, with_ring ? 1 : 16, with_ring ? 128 : 8, 1'000'000'000,
                                 with_ring);
}

test::TestVelodyneScan velodyne_scan_message(int packets) {
  test::TestVelodyneScan scan;
  scan.stamp_ns = 1'700'000'000'000'000'000;
  for (const auto& p : velodyne_packets(packets))
    scan.packets.push_back({p.host_stamp_ns, p.payload});
  return scan;
}

// One lidar packet of fuzz_ros_messages's Ouster metadata (8 beams, _DUAL).
std::vector<std::uint8_t> ouster_ros_packet() {
  test::OusterEncoderOptions o;
  o.profile = "RNG19_RFL8_SIG16_NIR16_DUAL";
  o.pixels_per_column = 8;
  return test::encode_ouster_packet(o, 0, 1'000'000'000, [](int m, int beam) {
    const auto r = static_cast<std::uint32_t>(2000 + 10 * (m + beam));
    return test::OusterEcho{r, r + 300, 40, 10};
  });
}

void ros_message_seeds(const fs::path& out) {
  const fs::path dir = out / "fuzz_ros_messages";
  for (const auto [encoding, bit] :
       {std::pair{test::RosEncoding::kRos1, 0}, std::pair{test::RosEncoding::kCdr, 1}}) {
    const std::string suffix = bit != 0 ? "_cdr" : "_ros1";
    const auto b = static_cast<std::uint8_t>(bit);
    put(dir, "velodyne_scan" + suffix,
        concat({Bytes{b}, test::serialize_velodyne_scan(velodyne_scan_message(2), encoding)}));
    put(dir, "cloud_ring" + suffix,
        concat({Bytes{static_cast<std::uint8_t>(b | 4)},
                test::serialize_pointcloud2(small_cloud(true), encoding)}));
    put(dir, "ouster_packet" + suffix,
        concat({Bytes{static_cast<std::uint8_t>(b | 6)},
                test::serialize_ouster_packet(ouster_ros_packet(), encoding)}));
    put(dir, "cloud_organized" + suffix,
        concat({Bytes{static_cast<std::uint8_t>(b | 4 | 8)},
                test::serialize_pointcloud2(small_cloud(false), encoding)}));
  }
}

void rosbag_seeds(const fs::path& out, const fs::path& scratch) {
  const auto packets = velodyne_packets(4);
  for (const std::string compression : {"none", "bz2", "lz4"}) {
    for (const bool indexed : {true, false}) {
      const fs::path path = scratch / "seed.bag";
      test::write_rosbag1(path, {{"/velodyne_packets", "velodyne_msgs/VelodyneScan"}},
                          test::velodyne_scan_messages(packets, 0, test::RosEncoding::kRos1, 2),
                          {.compression = compression, .chunk_bytes = 2048, .indexed = indexed});
      put(out / "fuzz_rosbag1", "velodyne_" + compression + (indexed ? "" : "_unindexed"),
          read_bytes(path));
    }
  }
  const fs::path cloud_bag = scratch / "cloud.bag";
  test::write_rosbag1(
      cloud_bag, {{"/points", "sensor_msgs/PointCloud2"}, {"/chatter", "std_msgs/String"}},
      {{1, 5, test::serialize_string("hello", test::RosEncoding::kRos1)},
       {0, 10, test::serialize_pointcloud2(small_cloud(true), test::RosEncoding::kRos1)}},
      {.compression = "lz4"});
  put(out / "fuzz_rosbag1", "pointcloud2_lz4", read_bytes(cloud_bag));

  const fs::path folder = scratch / "bag2";
  write_small_rosbag2(folder);
  put(out / "fuzz_rosbag2", "velodyne_db3", read_bytes(folder / "bag2_0.db3"));
  put(out / "fuzz_rosbag2", "metadata_yaml", read_bytes(folder / "metadata.yaml"));
  const auto db3 = read_bytes(folder / "bag2_0.db3");
  put(out / "fuzz_rosbag2", "velodyne_db3_zstd", test::zstd_compress(db3));
}

// fuzz_mcap_reader (its harness: control byte 0 = the raw file, with its summary): ROS 2 MCAP
// files of two VelodyneScan messages in each chunk compression.
void mcap_seeds(const fs::path& out, const fs::path& scratch) {
  const auto messages =
      test::velodyne_scan_messages(velodyne_packets(4), 0, test::RosEncoding::kCdr, 2);
  for (const auto [compression, name] :
       {std::pair{io::McapCompression::kNone, "none"}, std::pair{io::McapCompression::kLz4, "lz4"},
        std::pair{io::McapCompression::kZstd, "zstd"}}) {
    const fs::path path = scratch / "seed.mcap";
    io::McapWriterOptions options;
    options.profile = "ros2";
    options.compression = compression;
    options.chunk_bytes = 2048;
    options.background = false;
    io::McapWriter writer(path, options);
    const std::string_view definition = "std_msgs/Header header\nVelodynePacket[] packets\n";
    const auto schema = writer.add_schema(
        "velodyne_msgs/msg/VelodyneScan", "ros2msg",
        std::span(reinterpret_cast<const std::uint8_t*>(definition.data()), definition.size()));
    const auto channel = writer.add_channel(schema, "/velodyne_packets", "cdr");
    for (const auto& m : messages) {
      const auto t = static_cast<std::uint64_t>(m.stamp_ns);
      writer.write_message(channel, t, t, m.data);
    }
    writer.close();
    put(out / "fuzz_mcap_reader", std::string("velodyne_") + name,
        concat({Bytes{0x00}, read_bytes(path)}));
  }
}

void pcd_seeds(const fs::path& out) {
  core::OrganizedScan scan(8, 16);
  std::vector<std::uint32_t> labels(scan.size());
  for (int ring = 0; ring < 8; ++ring) {
    for (int c = 0; c < 16; ++c) {
      const float a = 0.39F * static_cast<float>(c);
      if ((ring + c) % 7 == 0) continue;  // a few cells without a return
      const float r = 4.0F + 0.25F * static_cast<float>(ring);
      scan.set_return(ring, c, r, 7.0F,
                      {r * std::cos(a), r * std::sin(a), -1.0F + 0.2F * static_cast<float>(ring)});
      labels[static_cast<std::size_t>(ring) * 16 + c] = static_cast<std::uint32_t>(c % 3);
    }
  }
  for (const auto encoding :
       {io::PcdEncoding::kAscii, io::PcdEncoding::kBinary, io::PcdEncoding::kBinaryCompressed}) {
    const std::string name(io::to_string(encoding));
    put(out / "fuzz_pcd", name, io::encode_pcd(scan, labels, encoding));
    put(out / "fuzz_pcd", name + "_nolabels", io::encode_pcd(scan, {}, encoding));
  }
  put(out / "fuzz_pcd", "unorganized_ring_ascii",
      "VERSION 0.7\nFIELDS x y z intensity ring\nSIZE 4 4 4 4 2\nTYPE F F F F U\n"
      "COUNT 1 1 1 1 1\nWIDTH 4\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 4\nDATA ascii\n"
      "1 0 -0.2 5 0\n0 1 -0.1 5 0\n1 0 0.2 5 1\n-1 0 0.3 5 1\n");
}

void kitti_bin_seeds(const fs::path& out) {
  // Two rings 2 degrees apart, 64 columns, a NaN point and a point at the origin; its own
  // truncated copy.
  core::UnorganizedCloud cloud;
  for (int ring = 0; ring < 2; ++ring) {
    for (int c = 0; c < 64; ++c) {
      const float a = 0.0982F * static_cast<float>(c);
      const float z = ring == 0 ? -0.175F : 0.0F;
      cloud.xyz.emplace_back(5.0F * std::cos(a), 5.0F * std::sin(a), z);
      cloud.intensity.push_back(static_cast<float>(c));
    }
  }
  cloud.xyz.emplace_back(std::numeric_limits<float>::quiet_NaN(), 0.0F, 0.0F);
  cloud.xyz.emplace_back(0.0F, 0.0F, 0.0F);
  cloud.intensity.resize(cloud.xyz.size(), 1.0F);
  const std::string bin = io::encode_kitti_bin(cloud);
  put(out / "fuzz_kitti_bin", "two_rings", bin);
  put(out / "fuzz_kitti_bin", "truncated", bin.substr(0, bin.size() - 5));
}

void text_seeds(const fs::path& out, const fs::path& source_dir) {
  const fs::path config = out / "fuzz_config";
  put(config, "defaults", core::dump_config(core::Config{}));
  put(config, "override", "segmentation:\n  max_width_m: 1.5\ntracking:\n  confirm_hits: 3\n");
  put(config, "assignments", "segmentation.max_width_m=1.5\nmapping.voxel_size_m=0.2\n");
  put(config, "sequence",
      io::format_sequence_yaml(io::SequenceMeta{.columns = 1800, .scans = 12, .name = "seed"}));

  const fs::path scenario = out / "fuzz_scenario";
  for (const auto* folder : {"config/scenarios", "config/validation"}) {
    for (const auto& entry : fs::directory_iterator(source_dir / folder)) {
      put(scenario, entry.path().filename().string(), read_bytes(entry.path()));
    }
  }

  const fs::path tables = out / "fuzz_text_tables";
  std::string tum;
  for (int i = 0; i < 4; ++i) {
    core::Pose pose;
    pose.stamp_ns = 1'000'000'000 + i * 100'000'000LL;
    pose.translation = {0.5 * i, -0.2 * i, 0.1};
    pose.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(0.1 * i, Eigen::Vector3d::UnitZ()));
    tum += io::format_tum_line(pose) + "\n";
  }
  put(tables, "tum", "# t x y z qx qy qz qw\n" + tum);
  put(tables, "kitti", "1 0 0 0 0 1 0 0 0 0 1 0\n0.995 -0.0998 0 0.5 0.0998 0.995 0 0.1 0 0 1 0\n");
  put(tables, "stamps", "# stamps\n0.0\n0.1\n0.200000001\n");
  io::ObjectRow object;
  object.scan = 1;
  object.stamp_ns = 100'000'000;
  object.id = 3;
  object.points = 12;
  object.centroid = {4.0, 1.0, 0.9};
  object.box.extend(Eigen::Vector3f(3.8F, 0.8F, 0.0F));
  object.box.extend(Eigen::Vector3f(4.2F, 1.2F, 1.8F));
  object.true_center = {4.0, 1.0, 0.9};
  io::TrackRow track;
  track.scan = 1;
  track.stamp_ns = 100'000'000;
  track.id = 7;
  track.position = {4.1, 1.0, 0.9};
  track.box = object.box;
  track.dynamic = track.ever_dynamic = true;
  track.age = 3;
  track.points = 12;
  const std::string objects =
      std::string(io::kObjectsCsvHeader) + "\n" + io::format_object_row(object) + "\n";
  const std::string tracks =
      std::string(io::kTracksCsvHeader) + "\n" + io::format_track_row(track) + "\n";
  put(tables, "objects_csv", objects);
  put(tables, "tracks_csv", tracks);
  put(tables, "objects_and_tracks", objects + "%%\n" + tracks);
  put(tables, "motchallenge", "1,1,10,20,30,40,1,1,1\n2,1,12,20,30,40,1,1,1\n2,2,50 60 10 20 0\n");
}

}  // namespace

void write_small_rosbag2(const std::filesystem::path& folder) {
  std::filesystem::remove_all(folder);
  test::write_rosbag2(
      folder, {{"/velodyne_packets", "velodyne_msgs/msg/VelodyneScan"}},
      test::velodyne_scan_messages(velodyne_packets(4), 0, test::RosEncoding::kCdr, 2));
}

void write_all_seeds(const std::filesystem::path& out, const std::filesystem::path& source_dir) {
  const fs::path scratch = out / ".scratch";
  fs::create_directories(scratch);
  velodyne_seeds(out, scratch);
  sensor_pcap_seeds(out, scratch);
  ros_message_seeds(out);
  rosbag_seeds(out, scratch);
  mcap_seeds(out, scratch);
  pcd_seeds(out);
  kitti_bin_seeds(out);
  text_seeds(out, source_dir);
  fs::remove_all(scratch);
}

}  // namespace ringtrack::fuzz
