// libFuzzer target: serialized ROS messages (ROS 1 or CDR) through the message parsers:
// velodyne_msgs/VelodyneScan (then its packets through the Velodyne decoder),
// pandar_msgs/PandarScan, sensor_msgs/PointCloud2 (then organized into a scan), and ouster-ros's
// PacketMsg (then its packet through the Ouster decoder of a fixed _DUAL metadata, the last
// return selected). Input byte 0 chooses the serialization (bit 0), the type (bits 1-2: 0
// VelodyneScan, 1 PandarScan, 2 PointCloud2, 3 PacketMsg) and the organizer's model and cut
// azimuth (bits 3-7); the rest is the message.
#include <cstdint>
#include <string>

#include "fuzz_support.hpp"
#include "ringtrack/io/pointcloud2.hpp"
#include "ringtrack/io/rosbag_source.hpp"
#include "ringtrack/io/velodyne_decoder.hpp"
#include "ringtrack/sensors/hesai/hesai_format.hpp"
#include "ringtrack/sensors/ouster/ouster_decoder.hpp"
#include "ringtrack/sensors/ouster/ouster_metadata.hpp"

using namespace ringtrack;

namespace {

// 8 beams, 16 columns of 16-byte pixels per packet: 32 + 16 x (12 + 8 x 16) + 32 = 2304 bytes.
sensors::ouster::OusterMetadata ouster_metadata() {
  return sensors::ouster::parse_ouster_metadata(
      R"({"lidar_mode": "512x10", "beam_altitude_angles": [10, 7, 4, 1, -2, -5, -8, -11],
          "beam_azimuth_angles": [1, -1, 1, -1, 1, -1, 1, -1],
          "lidar_origin_to_beam_origin_mm": 15,
          "lidar_to_sensor_transform": [-1, 0, 0, 0, 0, -1, 0, 0, 0, 0, 1, 36, 0, 0, 0, 1],
          "data_format": {"columns_per_frame": 512, "columns_per_packet": 16,
                          "pixels_per_column": 8, "pixel_shift_by_row": [0, 4, 8, 12, 0, 4, 8, 12],
                          "udp_profile_lidar": "RNG19_RFL8_SIG16_NIR16_DUAL"}})",
      "fuzz.json");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  fuzz::FuzzInput in(data, size);
  const std::uint8_t control = in.byte();
  const auto serialization =
      (control & 1) != 0 ? io::RosSerialization::kCdr : io::RosSerialization::kRos1;
  const auto message = in.rest();
  switch ((control >> 1) & 3) {
    case 0:
      fuzz::expect_errors([&] {
        const auto packets = io::parse_velodyne_scan(message, serialization, "fuzz message");
        io::VelodyneDecoder decoder;
        for (const auto& p : packets) {
          decoder.add_packet(p.data, p.stamp_ns);
          fuzz::drain_decoder(decoder);
        }
        decoder.finish();
        fuzz::drain_decoder(decoder);
      });
      break;
    case 1:
      fuzz::expect_errors([&] {
        for (const auto& p : io::parse_pandar_scan(message, serialization, "fuzz message")) {
          (void)sensors::hesai::identify_hesai_packet(p.data);
        }
      });
      break;
    case 3:
      fuzz::expect_errors([&] {
        const auto packet = io::parse_ouster_packet_msg(message, serialization, "fuzz message");
        static const sensors::ouster::OusterMetadata metadata = ouster_metadata();
        sensors::ouster::OusterDecoderOptions options;
        options.return_selection = sensors::ouster::OusterReturn::kLast;
        sensors::ouster::OusterDecoder decoder(metadata, options);
        decoder.add_packet(packet, 0);
        decoder.finish();
        fuzz::drain_decoder(decoder);
      });
      break;
    default:
      fuzz::expect_errors([&] {
        const io::PointCloud2 cloud = io::parse_pointcloud2(message, serialization, "fuzz message");
        const char* models[] = {"", "vlp16", "vlp32c", "hdl32e"};
        io::PointCloud2Options options;
        options.model = models[(control >> 3) & 3];
        options.cut_azimuth_deg = ((control >> 5) & 7) * 45.0;
        io::PointCloud2Organizer organizer(options);
        fuzz::check_scan(organizer.organize(cloud, "fuzz message"));
      });
  }
  return 0;
}
