// CAN frames and the transport interface the driver layer sits on: send,
// receive with timeout and time stamps, error frames, statistics. Backends:
// an in-process bus here (tests, fault injection); SocketCAN and CAN over
// loopback UDP (cross-process tests) in their own headers.
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <random>

namespace plsa::can {

/// Microseconds on the steady clock: the time base of the transports' stamps and delays.
inline std::int64_t steadyClockUs() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

struct CanFrame {
  std::uint32_t id = 0;  ///< 11-bit standard identifier
  std::uint8_t dlc = 0;  ///< data length, 0..8
  std::array<std::uint8_t, 8> data{};
  std::int64_t timestamp_us = 0;  ///< receive time stamp (transport's clock)
};

enum class BusState { kActive, kErrorPassive, kBusOff };

enum class TransportStatus : int {
  kOk = 0,
  kTimeout = -1,       ///< nothing received in time
  kBackPressure = -2,  ///< transmit queue full (ENOBUFS): try again, not a crash
  kBusOff = -3,        ///< controller is bus-off: nothing goes out
  kBadFrame = -4,      ///< DLC above 8 or identifier above 11 bits
  kIoError = -5,       ///< the operating system refused (errno in stats().last_errno)
};

const char* toString(TransportStatus s);
const char* toString(BusState s);

struct TransportStats {
  std::uint64_t sent = 0, received = 0, dropped = 0, corrupted = 0, back_pressure = 0, overflows = 0;
  std::uint64_t error_frames = 0;  ///< controller error frames seen (bus state changes)
  std::uint64_t malformed = 0;     ///< datagrams / frames that were not CAN frames of ours, discarded
  std::uint64_t ignored = 0;       ///< frames not for us (extended ids, remote frames)
  int last_errno = 0;
};

class CanTransport {
 public:
  virtual ~CanTransport() = default;
  virtual TransportStatus send(const CanFrame& frame) = 0;
  /// Waits up to `timeout` for a frame.
  virtual TransportStatus receive(CanFrame& frame, std::chrono::microseconds timeout) = 0;
  virtual BusState busState() const = 0;
  virtual TransportStats stats() const = 0;
};

/// Faults the in-process bus injects on delivery.
struct FaultInjection {
  double drop_probability = 0.0;
  double corrupt_probability = 0.0;  ///< flips one data bit
  std::chrono::microseconds delay{0};
  std::uint64_t seed = 1;
};

/// An in-process bus: every endpoint receives what the others send (not its own).
class InProcessBus : public std::enable_shared_from_this<InProcessBus> {
 public:
  static std::shared_ptr<InProcessBus> create() { return std::shared_ptr<InProcessBus>(new InProcessBus()); }
  /// A new endpoint on this bus.
  std::unique_ptr<CanTransport> connect(std::size_t queue_capacity = 256);
  void setFaults(const FaultInjection& f);
  void setBusState(BusState s);
  BusState busState() const;

 private:
  InProcessBus() = default;
  struct Endpoint;
  friend struct Endpoint;
  void deliver(const Endpoint* from, const CanFrame& frame);

  mutable std::mutex mutex_;
  std::vector<Endpoint*> endpoints_;
  FaultInjection faults_;
  std::mt19937_64 rng_{1};
  BusState state_ = BusState::kActive;
};

}  // namespace plsa::can
