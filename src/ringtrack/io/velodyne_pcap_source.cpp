#include "ringtrack/io/velodyne_pcap_source.hpp"

#include "ringtrack/core/error.hpp"

namespace ringtrack::io {

VelodynePcapSource::VelodynePcapSource(const std::filesystem::path& path,
                                       VelodynePcapOptions pcap_options,
                                       VelodyneDecoderOptions decoder_options)
    : reader_(path, pcap_options.allow_truncated),
      options_(pcap_options),
      decoder_(std::move(decoder_options)) {}

std::optional<core::OrganizedScan> VelodynePcapSource::next() {
  if (auto scan = decoder_.pop_scan()) return scan;
  UdpDatagram datagram;
  while (!finished_) {
    if (!reader_.next(datagram)) {
      finished_ = true;
      if (decoder_.stats().decoded_packets == 0) {
        throw core::InputError(
            reader_.path() + ": no Velodyne data packets (1206-byte UDP payloads to port " +
            std::to_string(options_.data_port) + ") among " +
            std::to_string(reader_.stats().frames) + " frames (" + summary() + ")");
      }
      decoder_.finish();
      break;
    }
    if (datagram.dst_port == options_.data_port) {
      ++stats_.data_datagrams;
      add_packet_from(reader_, datagram, decoder_);
      if (auto scan = decoder_.pop_scan()) return scan;
    } else if (datagram.dst_port == options_.position_port) {
      ++stats_.position_datagrams;
    } else {
      ++stats_.other_datagrams;
    }
  }
  return decoder_.pop_scan();
}

std::string VelodynePcapSource::summary() const {
  const auto& r = reader_.stats();
  const auto& d = decoder_.stats();
  std::string s = std::to_string(r.frames) + " frames, " + std::to_string(d.decoded_packets) +
                  " data packets decoded, " + std::to_string(d.scans) + " scans";
  const auto add = [&s](const char* what, std::uint64_t n) {
    if (n > 0) s += ", " + std::to_string(n) + " " + what;
  };
  add("wrong-size", d.wrong_size);
  add("bad-flag", d.bad_block_flag);
  add("bad-azimuth", d.bad_azimuth);
  add("unknown-return-mode", d.unknown_return_mode);
  add("product-changed", d.product_changed);
  add("out-of-order", d.out_of_order);
  add("position packets ignored", stats_.position_datagrams);
  add("other UDP ignored", stats_.other_datagrams);
  add("non-IPv4 frames ignored", r.non_ipv4);
  add("non-UDP frames ignored", r.non_udp);
  add("IP fragments ignored", r.fragments);
  add("short frames", r.short_frames);
  add("lost firing sequences", d.lost_sequences);
  add("invalid columns", d.invalid_columns);
  add("partial scans dropped", d.partial_scans_dropped);
  if (r.truncated) s += "; file truncated: " + r.truncation_message;
  return s;
}

}  // namespace ringtrack::io
