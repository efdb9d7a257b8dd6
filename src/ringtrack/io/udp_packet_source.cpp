#include "ringtrack/io/udp_packet_source.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstring>
#include <ctime>
#include <vector>

#include "ringtrack/core/error.hpp"

namespace ringtrack::io {
namespace {

std::int64_t realtime_ns() {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

}  // namespace

UdpOptions parse_udp_url(const std::string& url, std::uint16_t default_port) {
  const std::string scheme = "udp://";
  if (url.rfind(scheme, 0) != 0) {
    throw core::ConfigError("'" + url + "': expected udp://HOST:PORT");
  }
  UdpOptions options;
  options.port = default_port;
  const std::string rest = url.substr(scheme.size());
  const auto colon = rest.rfind(':');
  std::string host = colon == std::string::npos ? rest : rest.substr(0, colon);
  if (colon != std::string::npos) {
    const std::string port = rest.substr(colon + 1);
    char* end = nullptr;
    const long value = std::strtol(port.c_str(), &end, 10);
    if (port.empty() || *end != '\0' || value < 0 || value > 65535) {
      throw core::ConfigError("'" + url + "': port '" + port + "' is not 0..65535");
    }
    options.port = static_cast<std::uint16_t>(value);
  }
  if (host.empty() || host == "*") host = "0.0.0.0";
  in_addr probe{};
  if (inet_pton(AF_INET, host.c_str(), &probe) != 1) {
    throw core::ConfigError("'" + url + "': host '" + host + "' is not an IPv4 address");
  }
  options.host = host;
  return options;
}

UdpPacketSource::UdpPacketSource(UdpOptions options, std::unique_ptr<UdpPacketDecoder> decoder)
    : options_(std::move(options)), decoder_(std::move(decoder)) {
  if (options_.max_queued_scans < 1) {
    throw core::ConfigError("udp source: max_queued_scans must be at least 1");
  }
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(options_.port);
  if (inet_pton(AF_INET, options_.host.c_str(), &address.sin_addr) != 1) {
    throw core::ConfigError("udp source: host '" + options_.host + "' is not an IPv4 address");
  }
  fd_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd_ < 0) throw core::InputError(std::string("udp source: socket: ") + std::strerror(errno));
  const int one = 1;
  if (options_.reuse_address) ::setsockopt(fd_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
  ::setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &options_.receive_buffer_bytes,
               sizeof options_.receive_buffer_bytes);
  ::setsockopt(fd_, SOL_SOCKET, SO_TIMESTAMPNS, &one, sizeof one);  // kernel receive time
  if (::bind(fd_, reinterpret_cast<const sockaddr*>(&address), sizeof address) != 0) {
    const std::string why = std::strerror(errno);
    ::close(fd_);
    throw core::InputError("udp://" + options_.host + ":" + std::to_string(options_.port) +
                           ": cannot bind: " + why);
  }
  socklen_t length = sizeof address;
  ::getsockname(fd_, reinterpret_cast<sockaddr*>(&address), &length);
  port_ = ntohs(address.sin_port);
  thread_ = std::thread([this] { receive_loop(); });
}

UdpPacketSource::~UdpPacketSource() {
  stop();
  if (fd_ >= 0) ::close(fd_);
}

void UdpPacketSource::push_ready() {
  while (auto scan = decoder_->pop_scan()) {
    if (queue_.size() >= options_.max_queued_scans) {
      queue_.pop_front();  // the consumer fell behind: keep the freshest scans
      ++stats_.dropped_scans;
    }
    queue_.push_back(std::move(*scan));
    ready_cv_.notify_all();
  }
}

void UdpPacketSource::receive_loop() {
  // The largest UDP payload: Ouster packets of 128 beams take about 25 kB.
  std::vector<std::uint8_t> buffer(65536);
  alignas(cmsghdr) std::array<char, 256> control{};
  while (!stopping_.load()) {
    pollfd pfd{fd_, POLLIN, 0};
    const int ready = ::poll(&pfd, 1, 50);  // wake up regularly to notice stop()
    if (ready <= 0) {
      if (ready < 0 && errno != EINTR) {
        const std::lock_guard lock(mutex_);
        ++stats_.receive_errors;
      }
      continue;
    }
    iovec iov{buffer.data(), buffer.size()};
    msghdr message{};
    message.msg_iov = &iov;
    message.msg_iovlen = 1;
    message.msg_control = control.data();
    message.msg_controllen = control.size();
    const ssize_t n = ::recvmsg(fd_, &message, MSG_DONTWAIT);
    if (n < 0) {
      if (errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) {
        const std::lock_guard lock(mutex_);
        ++stats_.receive_errors;
      }
      continue;
    }
    std::int64_t stamp_ns = 0;
    for (cmsghdr* c = CMSG_FIRSTHDR(&message); c != nullptr; c = CMSG_NXTHDR(&message, c)) {
      if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SCM_TIMESTAMPNS) {
        timespec ts{};
        std::memcpy(&ts, CMSG_DATA(c), sizeof ts);
        stamp_ns = static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
      }
    }
    if (stamp_ns == 0) stamp_ns = realtime_ns();
    const std::lock_guard lock(mutex_);
    ++stats_.datagrams;
    try {
      decoder_->add_packet(
          std::span<const std::uint8_t>(buffer.data(), static_cast<std::size_t>(n)), stamp_ns);
    } catch (...) {
      error_ = std::current_exception();
      stopping_.store(true);
      ready_cv_.notify_all();
      return;
    }
    push_ready();
  }
}

std::optional<core::OrganizedScan> UdpPacketSource::next(std::chrono::milliseconds timeout) {
  std::unique_lock lock(mutex_);
  ready_cv_.wait_for(lock, timeout, [this] { return !queue_.empty() || error_ || finished_; });
  if (error_) {
    auto error = error_;
    error_ = nullptr;
    std::rethrow_exception(error);
  }
  if (queue_.empty()) return std::nullopt;
  core::OrganizedScan scan = std::move(queue_.front());
  queue_.pop_front();
  return scan;
}

void UdpPacketSource::stop() {
  stopping_.store(true);
  if (thread_.joinable()) thread_.join();
  const std::lock_guard lock(mutex_);
  if (!finished_ && !error_) {
    decoder_->finish();
    push_ready();
  }
  finished_ = true;
  ready_cv_.notify_all();
}

UdpStats UdpPacketSource::stats() const {
  const std::lock_guard lock(mutex_);
  return stats_;
}

std::optional<core::SensorModel> UdpPacketSource::model() const {
  const std::lock_guard lock(mutex_);
  return decoder_->model();
}

std::string UdpPacketSource::summary() const {
  const std::lock_guard lock(mutex_);
  return "udp://" + options_.host + ":" + std::to_string(port_) + ": " + decoder_->summary(stats_);
}

UdpScanSource::UdpScanSource(std::unique_ptr<UdpPacketSource> source, std::string description,
                             const std::atomic<bool>* interrupt)
    : source_(std::move(source)), description_(std::move(description)), interrupt_(interrupt) {}

std::optional<core::OrganizedScan> UdpScanSource::next() {
  using namespace std::chrono_literals;
  while (true) {
    if (interrupt_ != nullptr && interrupt_->load() && !source_->stopped()) source_->stop();
    if (auto scan = source_->next(100ms)) return scan;
    if (source_->stopped()) return source_->next(0ms);
  }
}

const core::SensorModel& UdpScanSource::model() const {
  if (!model_) model_ = source_->model();
  if (!model_) throw core::Error("udp input: the model is not known before the first scan");
  return *model_;
}

}  // namespace ringtrack::io
