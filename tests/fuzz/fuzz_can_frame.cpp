// libFuzzer target: arbitrary bytes as CAN frames for the decoder (every
// message of the default profile), as loopback-UDP datagrams, and as a
// stream of sensor frames into the valve driver. Must never crash, read out
// of bounds, or produce a non-finite reading.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>

#include "plsa/can/udp_transport.hpp"
#include "plsa/can/valve_driver.hpp"

namespace {

// A transport that plays back fuzz bytes as frames, 11 bytes each.
class ReplayTransport : public plsa::can::CanTransport {
 public:
  ReplayTransport(const std::uint8_t* d, std::size_t n) : d_(d), n_(n) {}
  plsa::can::TransportStatus send(const plsa::can::CanFrame&) override { return plsa::can::TransportStatus::kOk; }
  plsa::can::TransportStatus receive(plsa::can::CanFrame& f, std::chrono::microseconds) override {
    if (pos_ + 11 > n_) return plsa::can::TransportStatus::kTimeout;
    f = plsa::can::CanFrame{};
    f.id = (static_cast<std::uint32_t>(d_[pos_]) | static_cast<std::uint32_t>(d_[pos_ + 1]) << 8) & 0x7FF;
    f.dlc = d_[pos_ + 2] % 9;
    std::memcpy(f.data.data(), d_ + pos_ + 3, 8);
    pos_ += 11;
    return plsa::can::TransportStatus::kOk;
  }
  plsa::can::BusState busState() const override { return plsa::can::BusState::kActive; }
  plsa::can::TransportStats stats() const override { return {}; }

 private:
  const std::uint8_t* d_;
  std::size_t n_, pos_ = 0;
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const plsa::can::SignalMap map = plsa::can::defaultSignalMap();
  plsa::can::DatagramKind kind{};
  plsa::can::CanFrame f;
  (void)plsa::can::decodeDatagram(data, size, kind, f);
  ReplayTransport replay(data, size);
  int counters[8] = {-1, -1, -1, -1, -1, -1, -1, -1};
  double values[plsa::can::MessageLayout::kMaxSignals];
  ReplayTransport frames(data, size);
  while (frames.receive(f, std::chrono::microseconds(0)) == plsa::can::TransportStatus::kOk)
    for (std::size_t m = 0; m < map.messages.size(); ++m) {
      const auto st = plsa::can::decodeFrame(map.messages[m], f, values, counters[m]);
      if (st == plsa::can::DecodeStatus::kOk || st == plsa::can::DecodeStatus::kCounterGap)
        for (std::size_t s = 0; s < map.messages[m].signals.size(); ++s)
          if (!std::isfinite(values[s])) std::abort();
    }
  plsa::can::ValveDriver driver(replay, map, plsa::can::SafetyLimits{}, 0.0);
  driver.command(0.0, {0.1, 0.2, 0.3});
  driver.tick(0.01);
  for (double p : driver.pressures())
    if (!std::isfinite(p) || p < 0 || p > 0.65536) std::abort();
  for (double o : driver.output())
    if (!(o >= 0 && o <= 0.4)) std::abort();
  return 0;
}
