#include "plsa/can/socketcan_transport.hpp"

#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <poll.h>
#include <sys/time.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace plsa::can {

int SocketOps::socket(int domain, int type, int protocol) { return ::socket(domain, type, protocol); }
unsigned SocketOps::interfaceIndex(const std::string& name) { return ::if_nametoindex(name.c_str()); }
int SocketOps::bindCan(int fd, int ifindex) {
  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = ifindex;
  return ::bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr);
}
int SocketOps::setOption(int fd, int level, int name, const void* value, socklen_t size) {
  return ::setsockopt(fd, level, name, value, size);
}
int SocketOps::poll(pollfd* fds, unsigned n, int timeout_ms) { return ::poll(fds, n, timeout_ms); }
long SocketOps::receiveMessage(int fd, msghdr* msg, int flags) { return ::recvmsg(fd, msg, flags); }
long SocketOps::send(int fd, const void* data, std::size_t size, int flags) { return ::send(fd, data, size, flags); }
int SocketOps::close(int fd) { return ::close(fd); }

namespace {

std::runtime_error systemError(const std::string& what, int err) {
  return std::runtime_error("SocketCAN: " + what + ": " + std::strerror(err));
}

}  // namespace

SocketCanTransport::SocketCanTransport(const SocketCanOptions& o, std::shared_ptr<SocketOps> ops)
    : ops_(std::move(ops)) {
  fd_ = ops_->socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
  if (fd_ < 0) {
    const int err = errno;
    throw systemError(
        err == EAFNOSUPPORT ? "socket(PF_CAN) failed (this kernel has no CAN support)" : "socket(PF_CAN) failed", err);
  }
  try {
    const unsigned index = ops_->interfaceIndex(o.interface);
    if (index == 0) throw systemError("no interface '" + o.interface + "'", errno ? errno : ENODEV);
    std::vector<can_filter> filters;
    for (std::uint32_t id : o.receive_ids) {
      if (id > CAN_SFF_MASK) throw std::runtime_error("SocketCAN: receive id above 11 bits");
      // Standard frames of exactly this id: the EFF and RTR bits must be clear.
      filters.push_back({id, CAN_SFF_MASK | CAN_EFF_FLAG | CAN_RTR_FLAG});
    }
    if (!filters.empty() && ops_->setOption(fd_, SOL_CAN_RAW, CAN_RAW_FILTER, filters.data(),
                                            static_cast<socklen_t>(filters.size() * sizeof(can_filter))) != 0)
      throw systemError("setsockopt(CAN_RAW_FILTER)", errno);
    const can_err_mask_t err_mask = o.error_frames ? (CAN_ERR_BUSOFF | CAN_ERR_CRTL | CAN_ERR_RESTARTED) : 0;
    if (ops_->setOption(fd_, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &err_mask, sizeof err_mask) != 0)
      throw systemError("setsockopt(CAN_RAW_ERR_FILTER)", errno);
    const int on = 1;
    if (ops_->setOption(fd_, SOL_SOCKET, SO_TIMESTAMP, &on, sizeof on) != 0)
      throw systemError("setsockopt(SO_TIMESTAMP)", errno);
    if (ops_->setOption(fd_, SOL_SOCKET, SO_RXQ_OVFL, &on, sizeof on) != 0)
      throw systemError("setsockopt(SO_RXQ_OVFL)", errno);
    if (ops_->bindCan(fd_, static_cast<int>(index)) != 0) throw systemError("bind to '" + o.interface + "'", errno);
  } catch (...) {
    ops_->close(fd_);
    throw;
  }
}

SocketCanTransport::~SocketCanTransport() {
  if (fd_ >= 0) ops_->close(fd_);
}

TransportStatus SocketCanTransport::send(const CanFrame& frame) {
  if (frame.dlc > 8 || frame.id > CAN_SFF_MASK) return TransportStatus::kBadFrame;
  if (state_ == BusState::kBusOff) return TransportStatus::kBusOff;
  can_frame f{};
  f.can_id = frame.id;
  f.can_dlc = frame.dlc;
  std::memcpy(f.data, frame.data.data(), 8);
  const long n = ops_->send(fd_, &f, sizeof f, MSG_DONTWAIT);
  if (n == static_cast<long>(sizeof f)) {
    ++stats_.sent;
    return TransportStatus::kOk;
  }
  stats_.last_errno = n < 0 ? errno : EIO;
  if (n < 0 && (errno == ENOBUFS || errno == EAGAIN || errno == EWOULDBLOCK)) {
    ++stats_.back_pressure;  // the interface queue is full: the caller sends again next tick
    return TransportStatus::kBackPressure;
  }
  return TransportStatus::kIoError;
}

TransportStatus SocketCanTransport::receive(CanFrame& frame, std::chrono::microseconds timeout) {
  const auto until = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(until - std::chrono::steady_clock::now());
    pollfd pfd{fd_, POLLIN, 0};
    const int r = ops_->poll(&pfd, 1, static_cast<int>(std::max<long long>(0, left.count())));
    if (r < 0) {
      if (errno == EINTR) continue;
      stats_.last_errno = errno;
      return TransportStatus::kIoError;
    }
    if (r == 0) return TransportStatus::kTimeout;
    can_frame f{};
    iovec iov{&f, sizeof f};
    alignas(cmsghdr) char control[CMSG_SPACE(sizeof(timeval)) + CMSG_SPACE(sizeof(std::uint32_t))];
    msghdr msg{};
    msg.msg_iov = &iov;
    msg.msg_iovlen = 1;
    msg.msg_control = control;
    msg.msg_controllen = sizeof control;
    const long n = ops_->receiveMessage(fd_, &msg, MSG_DONTWAIT);
    if (n < 0) {
      if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) {
        if (std::chrono::steady_clock::now() >= until) return TransportStatus::kTimeout;
        continue;
      }
      stats_.last_errno = errno;
      return TransportStatus::kIoError;
    }
    std::int64_t stamp = steadyClockUs();
    for (cmsghdr* c = CMSG_FIRSTHDR(&msg); c != nullptr; c = CMSG_NXTHDR(&msg, c)) {
      if (c->cmsg_level != SOL_SOCKET) continue;
      if (c->cmsg_type == SO_TIMESTAMP && c->cmsg_len >= CMSG_LEN(sizeof(timeval))) {
        timeval tv{};
        std::memcpy(&tv, CMSG_DATA(c), sizeof tv);
        stamp = static_cast<std::int64_t>(tv.tv_sec) * 1000000 + tv.tv_usec;  // kernel time (realtime clock)
      } else if (c->cmsg_type == SO_RXQ_OVFL && c->cmsg_len >= CMSG_LEN(sizeof(std::uint32_t))) {
        std::uint32_t dropped = 0;
        std::memcpy(&dropped, CMSG_DATA(c), sizeof dropped);
        stats_.overflows = dropped;  // the kernel's running count for this socket
      }
    }
    if (n != static_cast<long>(sizeof f) || f.can_dlc > 8) {
      ++stats_.malformed;
      continue;
    }
    if (f.can_id & CAN_ERR_FLAG) {
      ++stats_.error_frames;
      if (f.can_id & CAN_ERR_BUSOFF)
        state_ = BusState::kBusOff;
      else if ((f.can_id & CAN_ERR_CRTL) && (f.data[1] & (CAN_ERR_CRTL_RX_PASSIVE | CAN_ERR_CRTL_TX_PASSIVE)))
        state_ = BusState::kErrorPassive;
      else if ((f.can_id & CAN_ERR_RESTARTED) || ((f.can_id & CAN_ERR_CRTL) && (f.data[1] & CAN_ERR_CRTL_ACTIVE)))
        state_ = BusState::kActive;
      continue;
    }
    if (f.can_id & (CAN_EFF_FLAG | CAN_RTR_FLAG)) {
      ++stats_.ignored;
      continue;
    }
    frame.id = f.can_id & CAN_SFF_MASK;
    frame.dlc = f.can_dlc;
    std::memcpy(frame.data.data(), f.data, 8);
    frame.timestamp_us = stamp;
    ++stats_.received;
    return TransportStatus::kOk;
  }
}

std::string socketCanUnavailableReason(const std::string& interface) {
  const int fd = ::socket(PF_CAN, SOCK_RAW | SOCK_CLOEXEC, CAN_RAW);
  if (fd < 0)
    return std::string("socket(PF_CAN) failed: ") + std::strerror(errno) + " (this kernel has no CAN support)";
  ::close(fd);
  if (::if_nametoindex(interface.c_str()) == 0)
    return "no interface '" + interface + "' (load vcan and add it: modprobe vcan; ip link add " + interface +
           " type vcan; ip link set " + interface + " up)";
  return {};
}

}  // namespace plsa::can
