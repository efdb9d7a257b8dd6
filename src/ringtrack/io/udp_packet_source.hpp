#pragma once
/// Live sensor packets from a UDP socket, decoded into scans on a receiver thread. One receiver
/// serves every packet family (Velodyne, Ouster): the family's decoder sits behind
/// UdpPacketDecoder.

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <exception>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <thread>

#include "ringtrack/core/organized_scan.hpp"
#include "ringtrack/core/sensor_model.hpp"
#include "ringtrack/io/source.hpp"

namespace ringtrack::io {

/// Where to listen and how much to buffer.
struct UdpOptions {
  std::string host{"0.0.0.0"};        ///< local IPv4 address to bind (0.0.0.0: every interface)
  std::uint16_t port{2368};           ///< UDP port; 0 picks a free one (see port())
  int receive_buffer_bytes{8 << 20};  ///< SO_RCVBUF request (the kernel may cap it)
  bool reuse_address{true};  ///< SO_REUSEADDR: share the port with other listeners, e.g. a ROS
                             ///< driver (Velodyne sensors broadcast by default)
  std::size_t max_queued_scans{2};  ///< decoded scans waiting for next(); beyond, the oldest
                                    ///< is dropped (counted), so the socket is never blocked
};

/// Counters of the socket side of a UDP source.
struct UdpStats {
  std::uint64_t datagrams{0};       ///< datagrams received
  std::uint64_t dropped_scans{0};   ///< whole scans dropped because the consumer fell behind
  std::uint64_t receive_errors{0};  ///< failed receive calls (other than timeouts)
};

/// A packet family's scan assembly as the receiver thread drives it. Calls are serialized by
/// the receiver's mutex.
class UdpPacketDecoder {
 public:
  virtual ~UdpPacketDecoder() = default;
  /// Decodes one datagram received at stamp_ns (kernel receive time); may throw
  /// core::InputError, which stops the receiver and reaches the consumer through next().
  virtual void add_packet(std::span<const std::uint8_t> payload, std::int64_t stamp_ns) = 0;
  /// The oldest completed scan, if any.
  virtual std::optional<core::OrganizedScan> pop_scan() = 0;
  /// Ends the stream: completes the scan in progress when the family's rules keep it.
  virtual void finish() = 0;
  /// The sensor model, once known.
  [[nodiscard]] virtual std::optional<core::SensorModel> model() const = 0;
  /// The summary line after "udp://HOST:PORT: ", with the socket's counters woven in.
  [[nodiscard]] virtual std::string summary(const UdpStats& socket) const = 0;
};

/// Receives packets on a UDP socket and decodes them on its own thread, so a slow consumer costs
/// whole scans (counted), never packets in the middle of a scan.
class UdpPacketSource {
 public:
  /// Binds the socket and starts receiving; throws core::InputError when the address cannot be
  /// bound, core::ConfigError on bad options.
  UdpPacketSource(UdpOptions options, std::unique_ptr<UdpPacketDecoder> decoder);
  /// Stops the receiver thread.
  virtual ~UdpPacketSource();
  UdpPacketSource(const UdpPacketSource&) = delete;
  UdpPacketSource& operator=(const UdpPacketSource&) = delete;

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
  [[nodiscard]] UdpStats stats() const;
  /// The sensor model, once the decoder knows it.
  [[nodiscard]] std::optional<core::SensorModel> model() const;
  /// One line summarizing what was received, decoded and dropped.
  [[nodiscard]] std::string summary() const;

 protected:
  /// Holds the receiver's mutex: the decoder may be read while it is held.
  [[nodiscard]] std::unique_lock<std::mutex> lock_decoder() const {
    return std::unique_lock(mutex_);
  }
  /// The decoder (read it under lock_decoder()).
  [[nodiscard]] const UdpPacketDecoder& decoder() const { return *decoder_; }

 private:
  void receive_loop();
  void push_ready();  // moves decoded scans to the queue; caller holds mutex_

  UdpOptions options_;
  std::unique_ptr<UdpPacketDecoder> decoder_;
  int fd_{-1};
  std::uint16_t port_{0};
  std::atomic<bool> stopping_{false};
  mutable std::mutex mutex_;
  std::condition_variable ready_cv_;
  std::deque<core::OrganizedScan> queue_;
  UdpStats stats_;
  std::exception_ptr error_;
  bool finished_{false};
  std::thread thread_;
};

/// A live UDP source as a ScanSource: next() waits for scans and, once `interrupt` is set (a
/// SIGINT handler), stops the receiver and hands out what remains.
class UdpScanSource final : public ScanSource {
 public:
  /// Takes the receiver; `description` names the input ("udp://...:2368 (live Velodyne UDP)").
  UdpScanSource(std::unique_ptr<UdpPacketSource> source, std::string description,
                const std::atomic<bool>* interrupt);
  /// The next scan; nullopt once interrupted and drained.
  std::optional<core::OrganizedScan> next() override;
  /// The sensor model; throws core::Error before the decoder knows it.
  [[nodiscard]] const core::SensorModel& model() const override;
  /// The input's name and kind.
  [[nodiscard]] std::string description() const override { return description_; }
  /// The receiver's summary line.
  [[nodiscard]] std::string summary() const override { return source_->summary(); }
  /// Always true.
  [[nodiscard]] bool live() const override { return true; }

 private:
  std::unique_ptr<UdpPacketSource> source_;
  std::string description_;
  const std::atomic<bool>* interrupt_;
  mutable std::optional<core::SensorModel> model_;  // copied from the decoder once known
};

/// Parses "udp://HOST:PORT" (HOST may be empty or *, PORT defaults to `default_port`) into
/// options; throws core::ConfigError on anything else.
UdpOptions parse_udp_url(const std::string& url, std::uint16_t default_port = 2368);

}  // namespace ringtrack::io
