#include "ringtrack/io/hesai_pcap_source.hpp"

#include "ringtrack/core/error.hpp"
#include "ringtrack/sensors/hesai/hesai_format.hpp"

namespace ringtrack::io {

HesaiPcapSource::HesaiPcapSource(const std::filesystem::path& path, std::uint16_t data_port,
                                 const sensors::hesai::HesaiDecoderOptions& options,
                                 bool allow_truncated)
    : reader_(path, allow_truncated), port_(data_port), decoder_(options) {
  sensors::hesai::HesaiDecoder probe(options);
  check_first_packet(path, port_, probe);
}

std::optional<core::OrganizedScan> HesaiPcapSource::next() {
  if (auto scan = decoder_.pop_scan()) return scan;
  UdpDatagram datagram;
  while (!finished_) {
    if (!reader_.next(datagram)) {
      finished_ = true;
      if (decoder_.stats().decoded_packets == 0) {
        throw core::InputError(
            reader_.path() + ": no Hesai point-cloud packets (UDP port " + std::to_string(port_) +
            ") among " + std::to_string(reader_.stats().frames) + " frames (" + summary() + ")");
      }
      decoder_.finish();
      break;
    }
    if (datagram.dst_port != port_) {
      ++other_datagrams_;
      continue;
    }
    add_packet_from(reader_, datagram, decoder_);
    if (auto scan = decoder_.pop_scan()) return scan;
  }
  return decoder_.pop_scan();
}

std::string HesaiPcapSource::summary() const {
  const auto& r = reader_.stats();
  const auto& d = decoder_.stats();
  std::string s = std::to_string(r.frames) + " frames, " + std::to_string(d.decoded_packets) +
                  " Hesai packets decoded, " + std::to_string(d.scans) + " scans" +
                  hesai_problem_counts(d);
  if (other_datagrams_ > 0) s += ", " + std::to_string(other_datagrams_) + " other UDP ignored";
  if (r.truncated) s += "; file truncated: " + r.truncation_message;
  return s;
}

std::string hesai_problem_counts(const sensors::hesai::HesaiDecoderStats& d) {
  std::string s;
  const auto add = [&s](const char* what, std::uint64_t n) {
    if (n > 0) s += ", " + std::to_string(n) + " " + what;
  };
  add("wrong-size", d.wrong_size);
  add("bad-header", d.bad_header);
  add("bad-azimuth", d.bad_azimuth);
  add("unknown-return-mode", d.unknown_return_mode);
  add("return-mode-changed", d.mode_changed);
  add("repeated blocks", d.repeated_blocks);
  add("lost firing blocks", d.lost_blocks);
  add("invalid columns", d.invalid_columns);
  add("partial scans dropped", d.partial_scans_dropped);
  return s;
}

bool pcap_holds_hesai(const std::filesystem::path& path, std::uint16_t port) {
  PcapReader reader(path, true);
  UdpDatagram datagram;
  for (int i = 0; i < 1000 && reader.next(datagram); ++i) {
    if (datagram.dst_port != port) continue;
    return sensors::hesai::identify_hesai_packet(datagram.payload) != nullptr;
  }
  return false;
}

}  // namespace ringtrack::io
