#include "plsa/can/udp_transport.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

#include "plsa/can/socketcan_transport.hpp"

namespace plsa::can {

namespace {

constexpr std::uint8_t kMagic[4] = {'P', 'L', 'C', 'N'};
constexpr std::uint8_t kVersion = 1;

sockaddr_in loopback(std::uint16_t port) {
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(port);
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  return a;
}

}  // namespace

void encodeDatagram(DatagramKind kind, const CanFrame& f, std::array<std::uint8_t, kUdpCanDatagramSize>& out) noexcept {
  std::memcpy(out.data(), kMagic, 4);
  out[4] = kVersion;
  out[5] = static_cast<std::uint8_t>(kind);
  for (int i = 0; i < 4; ++i) out[static_cast<std::size_t>(6 + i)] = static_cast<std::uint8_t>(f.id >> (8 * i));
  out[10] = f.dlc;
  std::memcpy(out.data() + 11, f.data.data(), 8);
}

bool decodeDatagram(const std::uint8_t* data, std::size_t size, DatagramKind& kind, CanFrame& f) noexcept {
  if (size != kUdpCanDatagramSize || std::memcmp(data, kMagic, 4) != 0 || data[4] != kVersion) return false;
  if (data[5] > static_cast<std::uint8_t>(DatagramKind::kBusState)) return false;
  kind = static_cast<DatagramKind>(data[5]);
  std::uint32_t id = 0;
  for (int i = 0; i < 4; ++i) id |= static_cast<std::uint32_t>(data[6 + i]) << (8 * i);
  if (id > 0x7FF || data[10] > 8) return false;
  if (kind == DatagramKind::kBusState && data[11] > static_cast<std::uint8_t>(BusState::kBusOff)) return false;
  f.id = id;
  f.dlc = data[10];
  std::memcpy(f.data.data(), data + 11, 8);
  return true;
}

UdpCanTransport::UdpCanTransport(const UdpCanOptions& o)
    : peers_(o.peer_ports), faults_(o.faults), rng_(o.faults.seed) {
  if (!(faults_.drop_probability >= 0 && faults_.drop_probability <= 1) ||
      !(faults_.corrupt_probability >= 0 && faults_.corrupt_probability <= 1) || faults_.delay.count() < 0)
    throw std::invalid_argument("UDP CAN: drop and corrupt are probabilities in [0, 1], delay >= 0");
  fd_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd_ < 0) throw std::runtime_error(std::string("UDP CAN: socket failed: ") + std::strerror(errno));
  sockaddr_in a = loopback(o.listen_port);
  if (::bind(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
    const int err = errno;
    ::close(fd_);
    throw std::runtime_error("UDP CAN: cannot listen on 127.0.0.1:" + std::to_string(o.listen_port) + ": " +
                             std::strerror(err));
  }
  socklen_t len = sizeof a;
  ::getsockname(fd_, reinterpret_cast<sockaddr*>(&a), &len);
  port_ = ntohs(a.sin_port);
}

UdpCanTransport::~UdpCanTransport() {
  if (fd_ >= 0) ::close(fd_);
}

TransportStatus UdpCanTransport::send(const CanFrame& frame) {
  if (frame.dlc > 8 || frame.id > 0x7FF) return TransportStatus::kBadFrame;
  if (state_ == BusState::kBusOff) return TransportStatus::kBusOff;
  std::array<std::uint8_t, kUdpCanDatagramSize> d{};
  encodeDatagram(DatagramKind::kFrame, frame, d);
  bool ok = true;
  for (std::uint16_t p : peers_) {
    const sockaddr_in to = loopback(p);
    if (::sendto(fd_, d.data(), d.size(), MSG_DONTWAIT, reinterpret_cast<const sockaddr*>(&to), sizeof to) < 0) {
      stats_.last_errno = errno;
      // No listener yet is normal on loopback (ECONNREFUSED): a bus with nobody on it.
      if (errno == ENOBUFS || errno == EAGAIN || errno == EWOULDBLOCK) {
        ++stats_.back_pressure;
        return TransportStatus::kBackPressure;
      }
      if (errno != ECONNREFUSED) ok = false;
    }
  }
  if (!ok) return TransportStatus::kIoError;
  ++stats_.sent;
  return TransportStatus::kOk;
}

void UdpCanTransport::announceBusState(BusState state) {
  state_ = state;
  CanFrame f;
  f.data[0] = static_cast<std::uint8_t>(state);
  std::array<std::uint8_t, kUdpCanDatagramSize> d{};
  encodeDatagram(DatagramKind::kBusState, f, d);
  for (std::uint16_t p : peers_) {
    const sockaddr_in to = loopback(p);
    ::sendto(fd_, d.data(), d.size(), MSG_DONTWAIT, reinterpret_cast<const sockaddr*>(&to), sizeof to);
  }
}

bool UdpCanTransport::takeDue(CanFrame& frame) {
  if (delayed_count_ == 0 || delayed_[delayed_head_].timestamp_us > steadyClockUs()) return false;
  frame = delayed_[delayed_head_];
  delayed_head_ = (delayed_head_ + 1) % kDelayCapacity;
  --delayed_count_;
  ++stats_.received;
  return true;
}

TransportStatus UdpCanTransport::receive(CanFrame& frame, std::chrono::microseconds timeout) {
  const std::int64_t until = steadyClockUs() + timeout.count();
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  for (;;) {
    std::uint8_t buf[64];
    // Take what has arrived while there is room; the rest waits in the socket buffer.
    while (delayed_count_ < kDelayCapacity) {
      const ssize_t n = ::recv(fd_, buf, sizeof buf, MSG_DONTWAIT);
      if (n < 0) {
        if (errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR && errno != ECONNREFUSED) {
          stats_.last_errno = errno;
          return TransportStatus::kIoError;
        }
        if (errno == EAGAIN || errno == EWOULDBLOCK) break;
        continue;
      }
      DatagramKind kind{};
      CanFrame f;
      if (!decodeDatagram(buf, static_cast<std::size_t>(n), kind, f)) {
        ++stats_.malformed;
        continue;
      }
      if (kind == DatagramKind::kBusState) {
        ++stats_.error_frames;
        state_ = static_cast<BusState>(f.data[0]);
        continue;
      }
      if (uni(rng_) < faults_.drop_probability) {
        ++stats_.dropped;
        continue;
      }
      if (f.dlc > 0 && uni(rng_) < faults_.corrupt_probability) {
        f.data[static_cast<std::size_t>(rng_() % f.dlc)] ^= static_cast<std::uint8_t>(1u << (rng_() % 8));
        ++stats_.corrupted;
      }
      f.timestamp_us = steadyClockUs() + faults_.delay.count();  // when it is delivered
      delayed_[(delayed_head_ + delayed_count_) % kDelayCapacity] = f;
      ++delayed_count_;
    }
    if (takeDue(frame)) return TransportStatus::kOk;
    const std::int64_t now = steadyClockUs();
    if (now >= until) return TransportStatus::kTimeout;
    std::int64_t wait = until - now;
    if (delayed_count_ > 0) wait = std::min(wait, delayed_[delayed_head_].timestamp_us - now);
    pollfd pfd{fd_, POLLIN, 0};
    const timespec ts{static_cast<time_t>(wait / 1000000), static_cast<long>((wait % 1000000) * 1000)};
    if (::ppoll(&pfd, 1, &ts, nullptr) < 0 && errno != EINTR) {
      stats_.last_errno = errno;
      return TransportStatus::kIoError;
    }
  }
}

namespace {

std::uint16_t parsePort(const std::string& text, const std::string& spec) {
  std::size_t used = 0;
  unsigned long v = 0;
  try {
    v = std::stoul(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != text.size() || text.empty() || v == 0 || v > 65535)
    throw std::invalid_argument("CAN transport '" + spec + "': '" + text + "' is not a port (1..65535)");
  return static_cast<std::uint16_t>(v);
}

double parseNumber(const std::string& key, const std::string& text, const std::string& spec) {
  std::size_t used = 0;
  double v = 0;
  try {
    v = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != text.size() || text.empty())
    throw std::invalid_argument("CAN transport '" + spec + "': " + key + "='" + text + "' is not a number");
  return v;
}

}  // namespace

std::unique_ptr<CanTransport> openTransport(const std::string& spec, const std::vector<std::uint32_t>& receive_ids) {
  if (spec.rfind("udp:", 0) == 0) {
    std::string rest = spec.substr(4), query;
    if (const auto q = rest.find('?'); q != std::string::npos) {
      query = rest.substr(q + 1);
      rest = rest.substr(0, q);
    }
    const auto colon = rest.find(':');
    if (colon == std::string::npos)
      throw std::invalid_argument("CAN transport '" + spec + "': expected udp:<listen-port>:<peer-port>[,...]");
    UdpCanOptions o;
    o.listen_port = parsePort(rest.substr(0, colon), spec);
    std::string peers = rest.substr(colon + 1);
    for (std::size_t start = 0; start <= peers.size();) {
      const auto comma = std::min(peers.find(',', start), peers.size());
      o.peer_ports.push_back(parsePort(peers.substr(start, comma - start), spec));
      start = comma + 1;
    }
    for (std::size_t start = 0; !query.empty() && start <= query.size();) {
      const auto amp = std::min(query.find('&', start), query.size());
      const std::string kv = query.substr(start, amp - start);
      const auto eq = kv.find('=');
      if (eq == std::string::npos)
        throw std::invalid_argument("CAN transport '" + spec + "': '" + kv + "' needs key=value");
      const std::string key = kv.substr(0, eq);
      const double v = parseNumber(key, kv.substr(eq + 1), spec);
      if (key == "drop")
        o.faults.drop_probability = v;
      else if (key == "corrupt")
        o.faults.corrupt_probability = v;
      else if (key == "delay_us")
        o.faults.delay = std::chrono::microseconds(static_cast<long long>(v));
      else if (key == "seed")
        o.faults.seed = static_cast<std::uint64_t>(v);
      else
        throw std::invalid_argument("CAN transport '" + spec + "': unknown option '" + key +
                                    "' (drop, corrupt, delay_us, seed)");
      start = amp + 1;
    }
    return std::make_unique<UdpCanTransport>(o);
  }
  std::string iface = spec.rfind("socketcan:", 0) == 0 ? spec.substr(10) : spec;
  if (iface.empty() || iface.size() >= 16 || iface.find_first_of(":/? ") != std::string::npos)
    throw std::invalid_argument("CAN transport '" + spec +
                                "': expected an interface name (can0), socketcan:<iface> or udp:<listen>:<peer>");
  SocketCanOptions so;
  so.interface = iface;
  so.receive_ids = receive_ids;
  return std::make_unique<SocketCanTransport>(so);
}

}  // namespace plsa::can
