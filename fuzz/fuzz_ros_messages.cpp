// libFuzzer target: serialized ROS messages (ROS 1 or CDR) through the message parsers:
// velodyne_msgs/VelodyneScan (then its packets through the Velodyne decoder),
// pandar_msgs/PandarScan, and sensor_msgs/PointCloud2 (then organized into a scan). Input byte 0
// chooses the serialization (bit 0), the type (bits 1-2) and the organizer's model and cut
// azimuth (bits 3-7); the rest is the message.
#include <cstdint>
#include <string>

#include "fuzz_support.hpp"
#include "ringtrack/io/pointcloud2.hpp"
#include "ringtrack/io/rosbag_source.hpp"
#include "ringtrack/io/velodyne_decoder.hpp"
#include "ringtrack/sensors/hesai/hesai_format.hpp"

using namespace ringtrack;

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
