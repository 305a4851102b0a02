// CAN frames over UDP on the loopback interface, so separate processes can
// talk CAN where the kernel has none (tests, this machine). Each endpoint
// listens on a port and sends every frame to a list of peer ports on
// 127.0.0.1 and nowhere else. Fault injection on receive (drop, corrupt,
// delay) and bus-state announcements (an error frame a peer can inject).
#pragma once

#include <array>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "plsa/can/can_transport.hpp"

namespace plsa::can {

struct UdpCanOptions {
  std::uint16_t listen_port = 0;  ///< 0: an ephemeral port (see localPort())
  std::vector<std::uint16_t> peer_ports;
  FaultInjection faults;
};

/// One datagram per frame: "PLCN", version 1, kind (0 frame, 1 bus state),
/// id (u32 LE), dlc, 8 data bytes; 19 bytes. Anything else is counted as
/// malformed and dropped.
constexpr std::size_t kUdpCanDatagramSize = 19;

enum class DatagramKind : std::uint8_t { kFrame = 0, kBusState = 1 };

/// Encodes / decodes one datagram (no allocation); decode returns false on
/// anything malformed (size, magic, version, kind, dlc, id, state value).
void encodeDatagram(DatagramKind kind, const CanFrame& frame,
                    std::array<std::uint8_t, kUdpCanDatagramSize>& out) noexcept;
bool decodeDatagram(const std::uint8_t* data, std::size_t size, DatagramKind& kind, CanFrame& frame) noexcept;

class UdpCanTransport : public CanTransport {
 public:
  /// Throws std::runtime_error naming the step that failed (port in use...).
  explicit UdpCanTransport(const UdpCanOptions& options);
  ~UdpCanTransport() override;
  UdpCanTransport(const UdpCanTransport&) = delete;
  UdpCanTransport& operator=(const UdpCanTransport&) = delete;

  TransportStatus send(const CanFrame& frame) override;
  TransportStatus receive(CanFrame& frame, std::chrono::microseconds timeout) override;
  BusState busState() const override { return state_; }
  TransportStats stats() const override { return stats_; }

  std::uint16_t localPort() const noexcept { return port_; }
  /// Replaces the peers (set-up only, e.g. once an ephemeral peer port is known).
  void setPeerPorts(std::vector<std::uint16_t> ports) { peers_ = std::move(ports); }
  /// Tells every peer the controller went to `state` (as an error frame
  /// would), and takes that state here too; bus-off stops our sends.
  void announceBusState(BusState state);

 private:
  bool takeDue(CanFrame& frame);

  int fd_ = -1;
  std::uint16_t port_ = 0;
  std::vector<std::uint16_t> peers_;
  FaultInjection faults_;
  std::mt19937_64 rng_;
  BusState state_ = BusState::kActive;
  TransportStats stats_;
  // Frames held back by the injected delay: a fixed ring, nothing allocated per frame.
  static constexpr std::size_t kDelayCapacity = 256;
  std::array<CanFrame, kDelayCapacity> delayed_{};
  std::size_t delayed_head_ = 0, delayed_count_ = 0;
};

/// Opens a transport from a specification:
///   "udp:<listen-port>:<peer-port>[,<peer-port>...][?drop=P&corrupt=P&delay_us=N&seed=S]"
///   "socketcan:<iface>" or a bare interface name ("can0", "vcan0").
/// `receive_ids` become the SocketCAN kernel filter. Throws
/// std::invalid_argument on a malformed specification.
std::unique_ptr<CanTransport> openTransport(const std::string& spec, const std::vector<std::uint32_t>& receive_ids);

}  // namespace plsa::can
