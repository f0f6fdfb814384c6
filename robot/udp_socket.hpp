#pragma once
// A non-blocking IPv4 UDP socket for FRI: bound to one local port, receiving with the sender's
// address so that the caller can drop datagrams from anyone but the configured robot.
// POSIX only. The socket owns its file descriptor (move-only).
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>

namespace flexirob::robot {

/// An IPv4 address and port, both in host byte order.
struct UdpEndpoint {
  std::uint32_t address = 0;  ///< e.g. 0x7F000001 for 127.0.0.1
  std::uint16_t port = 0;     ///< 0: any port (when used as a filter) / ephemeral (when binding)

  /// "host[:port]": a dotted IPv4 address or a host name (resolved to IPv4). Without a port,
  /// `default_port` is used. Throws InputError("robot address: ...") naming `what`.
  static UdpEndpoint parse(const std::string& text, std::uint16_t default_port, const std::string& what);
  /// "a.b.c.d:port".
  std::string toString() const;
  bool isLoopback() const { return (address >> 24) == 127; }
  bool operator==(const UdpEndpoint&) const = default;
};

/// What one receive() call got.
struct UdpReceiveResult {
  std::size_t size = 0;     ///< the datagram's full size, even when it did not fit the buffer
  bool truncated = false;   ///< the datagram was larger than the buffer (an oversized datagram)
  UdpEndpoint from;
};

class UdpSocket {
 public:
  /// Binds to local_address:port (port 0: the system picks a free port, see localPort()).
  /// Throws InputError with the system's reason if the address is invalid or in use.
  UdpSocket(const std::string& local_address, std::uint16_t port);
  ~UdpSocket();
  UdpSocket(UdpSocket&& other) noexcept;
  UdpSocket& operator=(UdpSocket&& other) noexcept;
  UdpSocket(const UdpSocket&) = delete;
  UdpSocket& operator=(const UdpSocket&) = delete;

  /// The bound local endpoint (with the actual port when bound to port 0).
  UdpEndpoint localEndpoint() const { return local_; }
  std::uint16_t localPort() const { return local_.port; }

  /// Sends one datagram without blocking. False if the system refused it (buffer full,
  /// unreachable): UDP gives no other guarantee anyway.
  bool sendTo(std::span<const std::uint8_t> bytes, const UdpEndpoint& to);
  /// Takes the next pending datagram without blocking; nothing pending gives std::nullopt.
  std::optional<UdpReceiveResult> receive(std::span<std::uint8_t> buffer);
  /// Waits up to timeout_s [s] (>= 0) for a datagram to arrive; true if one is pending.
  bool waitReadable(double timeout_s) const;

 private:
  int fd_ = -1;
  UdpEndpoint local_;
};

}  // namespace flexirob::robot
