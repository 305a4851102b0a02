// The Linux SocketCAN backend: a raw CAN socket bound to one interface, with
// kernel filters for the ids we read, controller error frames (bus-off,
// error-passive), kernel receive time stamps, receive-queue overflow counts
// and non-blocking I/O. The system calls go through SocketOps, a thin seam
// that tests replace to exercise option and frame handling without AF_CAN.
#pragma once

#include <sys/socket.h>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "plsa/can/can_transport.hpp"

struct pollfd;

namespace plsa::can {

/// The system calls the backend makes; the default forwards to the kernel.
class SocketOps {
 public:
  virtual ~SocketOps() = default;
  virtual int socket(int domain, int type, int protocol);
  virtual unsigned interfaceIndex(const std::string& name);  ///< 0: no such interface
  virtual int bindCan(int fd, int ifindex);
  virtual int setOption(int fd, int level, int name, const void* value, socklen_t size);
  virtual int poll(pollfd* fds, unsigned n, int timeout_ms);
  virtual long receiveMessage(int fd, msghdr* msg, int flags);
  virtual long send(int fd, const void* data, std::size_t size, int flags);
  virtual int close(int fd);
};

struct SocketCanOptions {
  std::string interface = "can0";
  std::vector<std::uint32_t> receive_ids;  ///< kernel filter; empty: every standard frame
  bool error_frames = true;                ///< bus-off, error-passive, controller problems
};

class SocketCanTransport : public CanTransport {
 public:
  /// Opens and configures the socket; throws std::runtime_error naming the
  /// step and the system's reason (for example: no AF_CAN in this kernel,
  /// no such interface).
  explicit SocketCanTransport(const SocketCanOptions& options,
                              std::shared_ptr<SocketOps> ops = std::make_shared<SocketOps>());
  ~SocketCanTransport() override;
  SocketCanTransport(const SocketCanTransport&) = delete;
  SocketCanTransport& operator=(const SocketCanTransport&) = delete;

  TransportStatus send(const CanFrame& frame) override;
  TransportStatus receive(CanFrame& frame, std::chrono::microseconds timeout) override;
  BusState busState() const override { return state_; }
  TransportStats stats() const override { return stats_; }

 private:
  std::shared_ptr<SocketOps> ops_;
  int fd_ = -1;
  BusState state_ = BusState::kActive;
  TransportStats stats_;
};

/// Why SocketCAN cannot be used on this machine (empty: it can): no AF_CAN
/// in the kernel, or no interface of that name.
std::string socketCanUnavailableReason(const std::string& interface);

}  // namespace plsa::can
