#include "support/udp_replay.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <string>
#include <thread>

namespace ringtrack::test {

void replay_to_loopback(std::span<const std::vector<std::uint8_t>> payloads, std::uint16_t port) {
  using namespace std::chrono_literals;
  const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  if (fd < 0) throw std::runtime_error(std::string("socket: ") + std::strerror(errno));
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_port = htons(port);
  to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  for (std::size_t i = 0; i < payloads.size(); ++i) {
    const auto sent = ::sendto(fd, payloads[i].data(), payloads[i].size(), 0,
                               reinterpret_cast<const sockaddr*>(&to), sizeof to);
    if (sent != static_cast<ssize_t>(payloads[i].size())) {
      const std::string why = std::strerror(errno);
      ::close(fd);
      throw std::runtime_error("datagram " + std::to_string(i) + " not sent: " + why);
    }
    if (i % 20 == 19) std::this_thread::sleep_for(2ms);
  }
  ::close(fd);
}

std::uint16_t free_udp_port() {
  const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ::bind(fd, reinterpret_cast<const sockaddr*>(&a), sizeof a);
  socklen_t len = sizeof a;
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len);
  ::close(fd);
  return ntohs(a.sin_port);
}

bool udp_port_bound(std::uint16_t port) {
  std::ifstream in("/proc/net/udp");
  std::string line;
  char hex[8];
  std::snprintf(hex, sizeof hex, ":%04X ", port);
  while (std::getline(in, line)) {
    if (line.find(hex) != std::string::npos) return true;
  }
  return false;
}

}  // namespace ringtrack::test
