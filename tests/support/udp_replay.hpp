#pragma once
// Sends datagrams to a live UDP source on the loopback interface (tests of the Velodyne and
// Ouster receivers and of the CLI reading them).

#include <cstdint>
#include <span>
#include <vector>

namespace ringtrack::test {

/// Sends each payload to 127.0.0.1:port in order, pausing 2 ms after every 20th so the receive
/// buffer never fills; throws std::runtime_error when a datagram cannot be sent whole.
void replay_to_loopback(std::span<const std::vector<std::uint8_t>> payloads, std::uint16_t port);
/// A UDP port free right now on 127.0.0.1.
std::uint16_t free_udp_port();
/// True once some socket is bound to the UDP port (/proc/net/udp lists local ports in hex).
bool udp_port_bound(std::uint16_t port);

}  // namespace ringtrack::test
