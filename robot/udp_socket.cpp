#include "robot/udp_socket.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netdb.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <utility>

#include "robot/errors.hpp"

namespace flexirob::robot {
namespace {

sockaddr_in toSockaddr(const UdpEndpoint& endpoint) {
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(endpoint.address);
  address.sin_port = htons(endpoint.port);
  return address;
}

// Resolves a dotted quad or a host name to one IPv4 address.
std::optional<std::uint32_t> resolveIpv4(const std::string& host) {
  in_addr numeric{};
  if (inet_pton(AF_INET, host.c_str(), &numeric) == 1) return ntohl(numeric.s_addr);
  addrinfo hints{};
  hints.ai_family = AF_INET;
  hints.ai_socktype = SOCK_DGRAM;
  addrinfo* result = nullptr;
  if (getaddrinfo(host.c_str(), nullptr, &hints, &result) != 0 || result == nullptr) return std::nullopt;
  sockaddr_in resolved{};
  std::memcpy(&resolved, result->ai_addr, sizeof(resolved));
  freeaddrinfo(result);
  return ntohl(resolved.sin_addr.s_addr);
}

}  // namespace

UdpEndpoint UdpEndpoint::parse(const std::string& text, std::uint16_t default_port, const std::string& what) {
  if (text.empty()) throw InputError(what + ": expected host[:port], got an empty value");
  std::string host = text;
  std::uint16_t port = default_port;
  const auto colon = text.rfind(':');
  if (colon != std::string::npos) {
    host = text.substr(0, colon);
    const std::string port_text = text.substr(colon + 1);
    char* end = nullptr;
    errno = 0;
    const long value = port_text.empty() ? -1 : std::strtol(port_text.c_str(), &end, 10);
    if (port_text.empty() || end != port_text.c_str() + port_text.size() || errno == ERANGE || value < 1 ||
        value > 65535) {
      throw InputError(what + ": expected a port in [1, 65535], got '" + port_text + "'");
    }
    port = static_cast<std::uint16_t>(value);
  }
  if (host.empty()) throw InputError(what + ": expected host[:port], got '" + text + "'");
  const auto address = resolveIpv4(host);
  if (!address) throw InputError(what + ": cannot resolve '" + host + "' to an IPv4 address");
  return UdpEndpoint{*address, port};
}

std::string UdpEndpoint::toString() const {
  return std::to_string(address >> 24) + "." + std::to_string((address >> 16) & 0xFF) + "." +
         std::to_string((address >> 8) & 0xFF) + "." + std::to_string(address & 0xFF) + ":" + std::to_string(port);
}

UdpSocket::UdpSocket(const std::string& local_address, std::uint16_t port) {
  const auto address = resolveIpv4(local_address);
  if (!address) throw InputError("bind address: cannot resolve '" + local_address + "' to an IPv4 address");
  fd_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd_ < 0) throw InputError(std::string("cannot open a UDP socket: ") + std::strerror(errno));
  const sockaddr_in bind_address = toSockaddr(UdpEndpoint{*address, port});
  if (::bind(fd_, reinterpret_cast<const sockaddr*>(&bind_address), sizeof(bind_address)) != 0) {
    const std::string reason = std::strerror(errno);
    ::close(fd_);
    fd_ = -1;
    throw InputError("cannot bind UDP " + UdpEndpoint{*address, port}.toString() + ": " + reason);
  }
  sockaddr_in bound{};
  socklen_t length = sizeof(bound);
  ::getsockname(fd_, reinterpret_cast<sockaddr*>(&bound), &length);
  local_ = UdpEndpoint{ntohl(bound.sin_addr.s_addr), ntohs(bound.sin_port)};
}

UdpSocket::~UdpSocket() {
  if (fd_ >= 0) ::close(fd_);
}

UdpSocket::UdpSocket(UdpSocket&& other) noexcept
    : fd_(std::exchange(other.fd_, -1)), local_(other.local_) {}

UdpSocket& UdpSocket::operator=(UdpSocket&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = std::exchange(other.fd_, -1);
    local_ = other.local_;
  }
  return *this;
}

bool UdpSocket::sendTo(std::span<const std::uint8_t> bytes, const UdpEndpoint& to) {
  const sockaddr_in address = toSockaddr(to);
  const ssize_t sent = ::sendto(fd_, bytes.data(), bytes.size(), MSG_DONTWAIT,
                                reinterpret_cast<const sockaddr*>(&address), sizeof(address));
  return sent == static_cast<ssize_t>(bytes.size());
}

std::optional<UdpReceiveResult> UdpSocket::receive(std::span<std::uint8_t> buffer) {
  sockaddr_in from{};
  socklen_t from_length = sizeof(from);
  // MSG_TRUNC: the return value is the datagram's real size, so oversized datagrams are seen as
  // such instead of being mistaken for well-sized ones.
  for (;;) {
    const ssize_t received = ::recvfrom(fd_, buffer.data(), buffer.size(), MSG_DONTWAIT | MSG_TRUNC,
                                        reinterpret_cast<sockaddr*>(&from), &from_length);
    if (received < 0) {
      if (errno == EINTR) continue;
      // EAGAIN: nothing pending; ECONNREFUSED and the like are ICMP echoes of earlier sends
      // that carry no datagram.
      return std::nullopt;
    }
    UdpReceiveResult result;
    result.size = static_cast<std::size_t>(received);
    result.truncated = result.size > buffer.size();
    result.from = UdpEndpoint{ntohl(from.sin_addr.s_addr), ntohs(from.sin_port)};
    return result;
  }
}

bool UdpSocket::waitReadable(double timeout_s) const {
  pollfd descriptor{fd_, POLLIN, 0};
  const double clamped = std::isfinite(timeout_s) ? std::clamp(timeout_s, 0.0, 3600.0) : 0.0;
  timespec timeout{};
  timeout.tv_sec = static_cast<time_t>(clamped);
  timeout.tv_nsec = static_cast<long>((clamped - static_cast<double>(timeout.tv_sec)) * 1e9);
  const int ready = ::ppoll(&descriptor, 1, &timeout, nullptr);
  return ready > 0 && (descriptor.revents & POLLIN) != 0;
}

}  // namespace flexirob::robot
