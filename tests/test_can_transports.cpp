// The CAN backends: CAN over loopback UDP (two endpoints in this process,
// ephemeral ports), the SocketCAN option and frame handling through its
// system-call seam, and the real SocketCAN socket on vcan0 where the kernel
// has it (skipped with the reason where it does not).
#include <gtest/gtest.h>

#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <poll.h>
#include <sys/time.h>

#include <cerrno>
#include <cstring>
#include <map>
#include <thread>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <unistd.h>

#include "plsa/can/socketcan_transport.hpp"
#include "plsa/can/udp_transport.hpp"
#include "plsa/can/valve_driver.hpp"

using namespace plsa::can;
using namespace std::chrono_literals;

namespace {

CanFrame frame(std::uint32_t id, std::uint8_t first) {
  CanFrame f;
  f.id = id;
  f.dlc = 8;
  for (std::size_t i = 0; i < 8; ++i) f.data[i] = static_cast<std::uint8_t>(first + i);
  return f;
}

struct UdpPair {
  std::unique_ptr<UdpCanTransport> a, b;
  explicit UdpPair(const FaultInjection& faults_at_b = {}) {
    a = std::make_unique<UdpCanTransport>(UdpCanOptions{});
    UdpCanOptions ob;
    ob.peer_ports = {a->localPort()};
    ob.faults = faults_at_b;
    b = std::make_unique<UdpCanTransport>(ob);
    a->setPeerPorts({b->localPort()});
  }
};

}  // namespace

TEST(UdpCan, DatagramCodecRejectsAnythingMalformed) {
  std::array<std::uint8_t, kUdpCanDatagramSize> d{};
  const CanFrame f = frame(0x123, 7);
  encodeDatagram(DatagramKind::kFrame, f, d);
  DatagramKind kind{};
  CanFrame g;
  ASSERT_TRUE(decodeDatagram(d.data(), d.size(), kind, g));
  EXPECT_EQ(g.id, 0x123u);
  EXPECT_EQ(g.data, f.data);
  EXPECT_FALSE(decodeDatagram(d.data(), d.size() - 1, kind, g)) << "short datagram";
  auto bad = d;
  bad[0] = 'X';
  EXPECT_FALSE(decodeDatagram(bad.data(), bad.size(), kind, g)) << "magic";
  bad = d;
  bad[4] = 2;
  EXPECT_FALSE(decodeDatagram(bad.data(), bad.size(), kind, g)) << "version";
  bad = d;
  bad[10] = 9;
  EXPECT_FALSE(decodeDatagram(bad.data(), bad.size(), kind, g)) << "dlc 9";
  bad = d;
  bad[7] = 0x08;  // id 0x823: above 11 bits
  EXPECT_FALSE(decodeDatagram(bad.data(), bad.size(), kind, g)) << "29-bit id";
  bad = d;
  bad[5] = 7;
  EXPECT_FALSE(decodeDatagram(bad.data(), bad.size(), kind, g)) << "kind";
}

TEST(UdpCan, FramesCrossBetweenEndpointsWithTimeStamps) {
  UdpPair p;
  EXPECT_EQ(p.a->send(frame(0x100, 1)), TransportStatus::kOk);
  CanFrame got;
  ASSERT_EQ(p.b->receive(got, 500ms), TransportStatus::kOk);
  EXPECT_EQ(got.id, 0x100u);
  EXPECT_EQ(got.data[7], 8);
  EXPECT_GT(got.timestamp_us, 0);
  EXPECT_EQ(p.b->receive(got, 20ms), TransportStatus::kTimeout);
  EXPECT_EQ(p.a->send(frame(0x800, 1)), TransportStatus::kBadFrame);
  EXPECT_EQ(p.a->stats().sent, 1u);
  EXPECT_EQ(p.b->stats().received, 1u);
}

TEST(UdpCan, InjectedDropCorruptAndDelay) {
  FaultInjection drop;
  drop.drop_probability = 0.3;
  drop.seed = 11;
  {
    UdpPair p(drop);
    CanFrame got;
    int n = 0;
    for (int batch = 0; batch < 8; ++batch) {  // bursts the socket buffer holds
      for (int i = 0; i < 50; ++i)
        ASSERT_EQ(p.a->send(frame(0x200, static_cast<std::uint8_t>(i))), TransportStatus::kOk);
      while (p.b->receive(got, 50ms) == TransportStatus::kOk) ++n;
    }
    EXPECT_EQ(static_cast<std::uint64_t>(n) + p.b->stats().dropped, 400u);
    EXPECT_GT(n, 220);
    EXPECT_LT(n, 340);
  }
  FaultInjection corrupt;
  corrupt.corrupt_probability = 1.0;
  {
    UdpPair p(corrupt);
    const CanFrame sent = frame(0x200, 3);
    ASSERT_EQ(p.a->send(sent), TransportStatus::kOk);
    CanFrame got;
    ASSERT_EQ(p.b->receive(got, 500ms), TransportStatus::kOk);
    int flipped = 0;
    for (std::size_t i = 0; i < 8; ++i)
      flipped += __builtin_popcount(static_cast<unsigned>(got.data[i] ^ sent.data[i]));
    EXPECT_EQ(flipped, 1);
    EXPECT_EQ(p.b->stats().corrupted, 1u);
  }
  FaultInjection delay;
  delay.delay = 30ms;
  {
    UdpPair p(delay);
    const auto t0 = std::chrono::steady_clock::now();
    ASSERT_EQ(p.a->send(frame(0x200, 3)), TransportStatus::kOk);
    CanFrame got;
    EXPECT_EQ(p.b->receive(got, 10ms), TransportStatus::kTimeout) << "delivered before its delay";
    ASSERT_EQ(p.b->receive(got, 500ms), TransportStatus::kOk);
    EXPECT_GE(std::chrono::steady_clock::now() - t0, 30ms);
  }
}

TEST(UdpCan, BusOffAnnouncedByAPeerVentsTheDriver) {
  UdpPair p;
  const SignalMap map = defaultSignalMap();
  ValveDriver driver(*p.b, map, SafetyLimits{}, 0.0);
  // A sensor reading keeps the watchdog quiet, then the peer's controller goes bus-off.
  double reading[3] = {0.1, 0.1, 0.1};
  CanFrame f;
  ASSERT_TRUE(encodeFrame(map.message("pressure_sensor"), reading, 0, f));
  ASSERT_EQ(p.a->send(f), TransportStatus::kOk);
  std::this_thread::sleep_for(20ms);
  driver.tick(0.01);
  EXPECT_EQ(driver.fault(), DriverFault::kNone);
  p.a->announceBusState(BusState::kBusOff);
  EXPECT_EQ(p.a->send(f), TransportStatus::kBusOff) << "a bus-off controller must not transmit";
  std::this_thread::sleep_for(20ms);
  driver.tick(0.02);
  EXPECT_EQ(driver.fault(), DriverFault::kBusOff);
  EXPECT_EQ(p.b->stats().error_frames, 1u);
}

TEST(UdpCan, GarbageDatagramsAreCountedNotDelivered) {
  UdpPair p;
  // Raw garbage from a third socket on loopback to b's port.
  const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  ASSERT_GE(fd, 0);
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_port = htons(p.b->localPort());
  to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  const char junk[] = "not a CAN frame at all";
  ASSERT_GT(::sendto(fd, junk, sizeof junk, 0, reinterpret_cast<sockaddr*>(&to), sizeof to), 0);
  ::close(fd);
  CanFrame got;
  EXPECT_EQ(p.b->receive(got, 50ms), TransportStatus::kTimeout);
  EXPECT_EQ(p.b->stats().malformed, 1u);
}

TEST(UdpCan, TransportSpecificationsAreCheckedWithClearErrors) {
  auto errorOf = [](const std::string& spec) -> std::string {
    try {
      openTransport(spec, {});
    } catch (const std::exception& e) {
      return e.what();
    }
    return "accepted";
  };
  EXPECT_NE(errorOf("udp:7300").find("expected udp:<listen-port>:<peer-port>"), std::string::npos);
  EXPECT_NE(errorOf("udp:7300:99999").find("'99999' is not a port"), std::string::npos);
  EXPECT_NE(errorOf("udp:7300:7301?loss=0.1").find("unknown option 'loss'"), std::string::npos);
  EXPECT_NE(errorOf("udp:7300:7301?drop=2").find("probabilities"), std::string::npos);
  EXPECT_NE(errorOf("bad/name").find("expected an interface name"), std::string::npos);
  EXPECT_EQ(errorOf("udp:7302:7303?drop=0.1&delay_us=500"), "accepted");
}

// ---- SocketCAN through its seam ------------------------------------------

namespace {

// Records what the backend asks of the kernel and plays back frames.
struct FakeSocketOps : SocketOps {
  struct Incoming {
    can_frame frame{};
    bool with_timestamp = true;
    std::int64_t overflow = -1;  // -1: no SO_RXQ_OVFL message
  };
  std::map<int, std::vector<std::uint8_t>> options;
  std::vector<Incoming> incoming;
  std::vector<can_frame> sent;
  int send_errno = 0;
  int bound_index = -1;
  int socket(int domain, int type, int protocol) override {
    EXPECT_EQ(domain, PF_CAN);
    EXPECT_TRUE(type & SOCK_RAW);
    EXPECT_TRUE(type & SOCK_NONBLOCK) << "the real-time path must never block in send or recv";
    EXPECT_EQ(protocol, CAN_RAW);
    return 42;
  }
  unsigned interfaceIndex(const std::string& name) override { return name == "vcan0" ? 7 : 0; }
  int bindCan(int, int index) override {
    bound_index = index;
    return 0;
  }
  int setOption(int, int level, int name, const void* value, socklen_t size) override {
    const int key = level * 1000 + name;
    options[key].assign(static_cast<const std::uint8_t*>(value), static_cast<const std::uint8_t*>(value) + size);
    return 0;
  }
  int poll(pollfd* fds, unsigned, int) override {
    fds[0].revents = incoming.empty() ? 0 : POLLIN;
    return incoming.empty() ? 0 : 1;
  }
  long receiveMessage(int, msghdr* msg, int) override {
    if (incoming.empty()) {
      errno = EAGAIN;
      return -1;
    }
    const Incoming in = incoming.front();
    incoming.erase(incoming.begin());
    std::memcpy(msg->msg_iov[0].iov_base, &in.frame, sizeof in.frame);
    auto* control = static_cast<char*>(msg->msg_control);
    std::size_t used = 0;
    if (in.with_timestamp) {
      auto* c = reinterpret_cast<cmsghdr*>(control);
      c->cmsg_level = SOL_SOCKET;
      c->cmsg_type = SO_TIMESTAMP;
      c->cmsg_len = CMSG_LEN(sizeof(timeval));
      const timeval tv{1234, 567};
      std::memcpy(CMSG_DATA(c), &tv, sizeof tv);
      used += CMSG_SPACE(sizeof(timeval));
    }
    if (in.overflow >= 0) {
      auto* c = reinterpret_cast<cmsghdr*>(control + used);
      c->cmsg_level = SOL_SOCKET;
      c->cmsg_type = SO_RXQ_OVFL;
      c->cmsg_len = CMSG_LEN(sizeof(std::uint32_t));
      const auto v = static_cast<std::uint32_t>(in.overflow);
      std::memcpy(CMSG_DATA(c), &v, sizeof v);
      used += CMSG_SPACE(sizeof(std::uint32_t));
    }
    msg->msg_controllen = used;
    return sizeof(can_frame);
  }
  long send(int, const void* data, std::size_t size, int flags) override {
    EXPECT_TRUE(flags & MSG_DONTWAIT);
    if (send_errno) {
      errno = send_errno;
      return -1;
    }
    can_frame f{};
    std::memcpy(&f, data, std::min(size, sizeof f));
    sent.push_back(f);
    return static_cast<long>(size);
  }
  int close(int) override { return 0; }

  void push(canid_t id, std::uint8_t d1 = 0, std::int64_t overflow = -1) {
    Incoming in;
    in.frame.can_id = id;
    in.frame.can_dlc = 8;
    in.frame.data[1] = d1;
    in.overflow = overflow;
    incoming.push_back(in);
  }
};

}  // namespace

TEST(SocketCanSeam, ConfiguresFiltersErrorMaskTimestampsAndOverflowCounts) {
  auto ops = std::make_shared<FakeSocketOps>();
  SocketCanOptions o;
  o.interface = "vcan0";
  o.receive_ids = {0x200, 0x210};
  SocketCanTransport t(o, ops);
  EXPECT_EQ(ops->bound_index, 7);
  const auto& filter = ops->options.at(SOL_CAN_RAW * 1000 + CAN_RAW_FILTER);
  ASSERT_EQ(filter.size(), 2 * sizeof(can_filter));
  can_filter f[2];
  std::memcpy(f, filter.data(), sizeof f);
  EXPECT_EQ(f[0].can_id, 0x200u);
  EXPECT_EQ(f[1].can_id, 0x210u);
  EXPECT_EQ(f[0].can_mask & CAN_SFF_MASK, CAN_SFF_MASK);
  EXPECT_TRUE(f[0].can_mask & CAN_EFF_FLAG) << "extended frames with the same low bits must not pass";
  can_err_mask_t mask = 0;
  std::memcpy(&mask, ops->options.at(SOL_CAN_RAW * 1000 + CAN_RAW_ERR_FILTER).data(), sizeof mask);
  EXPECT_TRUE(mask & CAN_ERR_BUSOFF);
  EXPECT_TRUE(mask & CAN_ERR_CRTL);
  EXPECT_EQ(ops->options.count(SOL_SOCKET * 1000 + SO_TIMESTAMP), 1u);
  EXPECT_EQ(ops->options.count(SOL_SOCKET * 1000 + SO_RXQ_OVFL), 1u);
}

TEST(SocketCanSeam, FramesErrorFramesAndBackPressure) {
  auto ops = std::make_shared<FakeSocketOps>();
  SocketCanOptions o;
  o.interface = "vcan0";
  SocketCanTransport t(o, ops);
  ops->push(0x200, 5, 3);           // a data frame; the kernel dropped 3 before it
  ops->push(0x200 | CAN_EFF_FLAG);  // extended: ignored
  ops->push(CAN_ERR_FLAG | CAN_ERR_CRTL, CAN_ERR_CRTL_TX_PASSIVE);
  CanFrame got;
  ASSERT_EQ(t.receive(got, 10ms), TransportStatus::kOk);
  EXPECT_EQ(got.id, 0x200u);
  EXPECT_EQ(got.data[1], 5);
  EXPECT_EQ(got.timestamp_us, 1234 * 1000000LL + 567) << "kernel receive time stamp";
  EXPECT_EQ(t.stats().overflows, 3u);
  EXPECT_EQ(t.receive(got, 10ms), TransportStatus::kTimeout);
  EXPECT_EQ(t.stats().ignored, 1u);
  EXPECT_EQ(t.busState(), BusState::kErrorPassive);
  ops->push(CAN_ERR_FLAG | CAN_ERR_BUSOFF);
  EXPECT_EQ(t.receive(got, 10ms), TransportStatus::kTimeout);
  EXPECT_EQ(t.busState(), BusState::kBusOff);
  EXPECT_EQ(t.send(frame(0x100, 0)), TransportStatus::kBusOff);
  ops->push(CAN_ERR_FLAG | CAN_ERR_RESTARTED);
  EXPECT_EQ(t.receive(got, 10ms), TransportStatus::kTimeout);
  EXPECT_EQ(t.busState(), BusState::kActive);
  EXPECT_EQ(t.stats().error_frames, 3u);

  ASSERT_EQ(t.send(frame(0x100, 9)), TransportStatus::kOk);
  ASSERT_EQ(ops->sent.size(), 1u);
  EXPECT_EQ(ops->sent[0].can_id, 0x100u);
  EXPECT_EQ(ops->sent[0].data[0], 9);
  ops->send_errno = ENOBUFS;  // the interface queue is full
  EXPECT_EQ(t.send(frame(0x100, 9)), TransportStatus::kBackPressure);
  EXPECT_EQ(t.stats().back_pressure, 1u);
  ops->send_errno = ENETDOWN;
  EXPECT_EQ(t.send(frame(0x100, 9)), TransportStatus::kIoError);
  EXPECT_EQ(t.stats().last_errno, ENETDOWN);
}

TEST(SocketCanSeam, SetUpFailuresNameTheStep) {
  auto ops = std::make_shared<FakeSocketOps>();
  SocketCanOptions o;
  o.interface = "can9";
  try {
    SocketCanTransport t(o, ops);
    FAIL() << "opened a missing interface";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("no interface 'can9'"), std::string::npos) << e.what();
  }
}

// ---- the real kernel -------------------------------------------------------

TEST(SocketCanKernel, Vcan0LoopsFramesBetweenTwoSockets) {
  const std::string why = socketCanUnavailableReason("vcan0");
  if (!why.empty()) GTEST_SKIP() << "SocketCAN on vcan0 not available here: " << why;
  SocketCanOptions o;
  o.interface = "vcan0";
  o.receive_ids = {0x321};
  SocketCanTransport tx(o), rx(o);
  ASSERT_EQ(tx.send(frame(0x321, 4)), TransportStatus::kOk);
  ASSERT_EQ(tx.send(frame(0x322, 4)), TransportStatus::kOk);  // filtered out at rx
  CanFrame got;
  ASSERT_EQ(rx.receive(got, 500ms), TransportStatus::kOk);
  EXPECT_EQ(got.id, 0x321u);
  EXPECT_EQ(got.data[0], 4);
  EXPECT_GT(got.timestamp_us, 0);
  EXPECT_EQ(rx.receive(got, 50ms), TransportStatus::kTimeout);
}
