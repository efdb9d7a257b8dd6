#pragma once
/// Live Velodyne packets from a UDP socket, decoded into scans on a receiver thread.

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <exception>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "ringtrack/core/organized_scan.hpp"
#include "ringtrack/io/velodyne_decoder.hpp"

namespace ringtrack::io {

/// Where to listen and how much to buffer.
struct VelodyneUdpOptions {
  std::string host{"0.0.0.0"};        ///< local IPv4 address to bind (0.0.0.0: every interface)
  std::uint16_t port{2368};           ///< UDP port; 0 picks a free one (see port())
  int receive_buffer_bytes{8 << 20};  ///< SO_RCVBUF request (the kernel may cap it)
  bool reuse_address{true};  ///< SO_REUSEADDR: share the port with other listeners, e.g. a ROS
                             ///< driver (Velodyne sensors broadcast by default)
  std::size_t max_queued_scans{2};  ///< decoded scans waiting for next(); beyond, the oldest
                                    ///< is dropped (counted), so the socket is never blocked
};

/// Counters of a UDP source.
struct VelodyneUdpStats {
  std::uint64_t datagrams{0};       ///< datagrams received
  std::uint64_t dropped_scans{0};   ///< whole scans dropped because the consumer fell behind
  std::uint64_t receive_errors{0};  ///< failed receive calls (other than timeouts)
};

/// Receives Velodyne data packets on a UDP socket and decodes them on its own thread, so a slow
/// consumer costs whole scans (counted), never packets in the middle of a scan.
class VelodyneUdpSource {
 public:
  /// Binds the socket and starts receiving; throws core::InputError when the address cannot be
  /// bound, core::ConfigError on bad options.
  VelodyneUdpSource(VelodyneUdpOptions options, VelodyneDecoderOptions decoder_options = {});
  /// Stops the receiver thread.
  ~VelodyneUdpSource();
  VelodyneUdpSource(const VelodyneUdpSource&) = delete;
  VelodyneUdpSource& operator=(const VelodyneUdpSource&) = delete;

  /// The bound UDP port.
  [[nodiscard]] std::uint16_t port() const { return port_; }
  /// The next decoded scan, waiting up to `timeout`; nullopt on timeout, or once stopped and
  /// drained. Rethrows an error of the receiver thread (e.g. a contradicting product byte).
  std::optional<core::OrganizedScan> next(std::chrono::milliseconds timeout);
  /// Stops receiving and completes the scan in progress (kept if it covers a revolution, or
  /// with keep_partial_scans); queued scans stay available to next(). Idempotent.
  void stop();
  /// True once stop() ran or the receiver thread ended on an error.
  [[nodiscard]] bool stopped() const { return stopping_.load(); }
  /// Socket counters (a snapshot).
  [[nodiscard]] VelodyneUdpStats stats() const;
  /// The sensor model, once the first packet told it.
  [[nodiscard]] std::optional<core::SensorModel> model() const;
  /// Decoder counters (a snapshot).
  [[nodiscard]] VelodyneDecoderStats decoder_stats() const;
  /// One line summarizing what was received, decoded and dropped.
  [[nodiscard]] std::string summary() const;

 private:
  void receive_loop();
  void push_ready();  // moves decoded scans to the queue; caller holds mutex_

  VelodyneUdpOptions options_;
  VelodyneDecoder decoder_;
  int fd_{-1};
  std::uint16_t port_{0};
  std::atomic<bool> stopping_{false};
  mutable std::mutex mutex_;
  std::condition_variable ready_cv_;
  std::deque<core::OrganizedScan> queue_;
  VelodyneUdpStats stats_;
  std::exception_ptr error_;
  bool finished_{false};
  std::thread thread_;
};

/// Parses "udp://HOST:PORT" (HOST may be empty or *, PORT defaults to 2368) into options;
/// throws core::ConfigError on anything else.
VelodyneUdpOptions parse_udp_url(const std::string& url);

}  // namespace ringtrack::io
