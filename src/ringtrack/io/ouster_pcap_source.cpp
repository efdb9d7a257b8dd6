#include "ringtrack/io/ouster_pcap_source.hpp"

#include "ringtrack/core/error.hpp"

namespace ringtrack::io {

OusterPcapSource::OusterPcapSource(const std::filesystem::path& path,
                                   sensors::ouster::OusterMetadata metadata,
                                   sensors::ouster::OusterDecoderOptions options,
                                   std::uint16_t lidar_port)
    : reader_(path, true), decoder_(std::move(metadata), options), port_(lidar_port) {
  sensors::ouster::OusterDecoder probe(decoder_.metadata(), options);
  check_first_packet(path, port_, probe);
}

std::optional<core::OrganizedScan> OusterPcapSource::next() {
  if (auto scan = decoder_.pop_scan()) return scan;
  UdpDatagram datagram;
  while (!finished_) {
    if (!reader_.next(datagram)) {
      finished_ = true;
      if (decoder_.stats().decoded_packets == 0) {
        throw core::InputError(reader_.path() + ": no Ouster lidar packets (UDP port " +
                               std::to_string(port_) + ") among " +
                               std::to_string(reader_.stats().frames) + " frames");
      }
      decoder_.finish();
      break;
    }
    if (datagram.dst_port == port_) {
      add_packet_from(reader_, datagram, decoder_);
      if (auto scan = decoder_.pop_scan()) return scan;
    } else if (datagram.dst_port == 7503) {
      ++imu_datagrams_;
    } else {
      ++other_datagrams_;
    }
  }
  return decoder_.pop_scan();
}

std::string OusterPcapSource::summary() const {
  const auto& r = reader_.stats();
  const auto& d = decoder_.stats();
  std::string s = std::to_string(r.frames) + " frames, " + std::to_string(d.decoded_packets) +
                  " Ouster lidar packets decoded (" +
                  sensors::ouster::to_string(decoder_.metadata().profile) + "), " +
                  std::to_string(d.scans) + " scans";
  const auto add = [&s](const char* what, std::uint64_t n) {
    if (n > 0) s += ", " + std::to_string(n) + " " + what;
  };
  add("wrong-size packets", d.wrong_size);
  add("columns flagged invalid", d.invalid_columns);
  add("bad measurement ids", d.bad_measurement_id);
  add("IMU packets ignored", imu_datagrams_);
  add("other UDP ignored", other_datagrams_);
  add("lost columns", d.lost_columns);
  add("partial scans dropped", d.partial_scans_dropped);
  if (r.truncated) s += "; file truncated: " + r.truncation_message;
  return s;
}

bool pcap_holds_ouster(const std::filesystem::path& path) {
  PcapReader reader(path, true);
  UdpDatagram datagram;
  bool ouster = false;
  for (int i = 0; i < 200 && reader.next(datagram); ++i) {
    if (datagram.dst_port == 2368) return false;
    if (datagram.dst_port == 7502) ouster = true;
  }
  return ouster;
}

}  // namespace ringtrack::io
