// End to end over CAN: LCM command -> `plsa can-bridge` -> CAN (frames over
// loopback UDP, with drops and bit flips injected) -> `plsa sim --can`
// (simulated valves and sensors) -> CAN -> bridge -> LCM state. Checks the
// response, the clamp, the command-timeout vent with its latched fault and
// clearing, and the vent on SIGINT. Runs in a private network namespace.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <stdexcept>
#include <vector>

#include <lcm/lcm-cpp.hpp>
#include <plsa_lcm/actuator_state_t.hpp>
#include <plsa_lcm/pressure_command_t.hpp>
#include <plsa_lcm/status_t.hpp>

#include "plsa/can/valve_driver.hpp"
#include "plsa/lcm/can_bridge.hpp"
#include "support/child_process.hpp"
#include "support/isolated_lcm_test.hpp"
#include "support/lcm_bytes.hpp"

using namespace std::chrono_literals;

namespace {

struct Inbox {
  std::vector<plsa_lcm::actuator_state_t> bridge, truth;
  std::vector<plsa_lcm::status_t> statuses;
  void onBridge(const lcm::ReceiveBuffer*, const std::string&, const plsa_lcm::actuator_state_t* m) {
    bridge.push_back(*m);
  }
  void onTruth(const lcm::ReceiveBuffer*, const std::string&, const plsa_lcm::actuator_state_t* m) {
    truth.push_back(*m);
  }
  void onStatus(const lcm::ReceiveBuffer*, const std::string&, const plsa_lcm::status_t* m) { statuses.push_back(*m); }
};

double statusValue(const plsa_lcm::status_t& s, const std::string& name) {
  for (std::size_t i = 0; i < s.names.size(); ++i)
    if (s.names[i] == name) return s.values[i];
  return NAN;
}

class CanBridgeTest : public plsa::test::IsolatedLcmTest {
 protected:
  void SetUp() override {
    IsolatedLcmTest::SetUp();
    if (IsSkipped() || HasFatalFailure()) return;
    lcm_->subscribe("BRIDGE_STATE", &Inbox::onBridge, &inbox_);
    lcm_->subscribe("SIM_TRUTH", &Inbox::onTruth, &inbox_);
    lcm_->subscribe("BRIDGE_STATUS", &Inbox::onStatus, &inbox_);
  }

  // Handles LCM for `d`, sending `cmd` at 80 Hz when given.
  void run(std::chrono::milliseconds d, const std::array<double, 3>* cmd) {
    const auto end = std::chrono::steady_clock::now() + d;
    auto next = std::chrono::steady_clock::now();
    while (std::chrono::steady_clock::now() < end) {
      if (cmd && std::chrono::steady_clock::now() >= next) {
        plsa_lcm::pressure_command_t c;
        c.utime = seq_;
        c.seq = seq_++;
        c.n_chambers = 3;
        c.pressure_bar = {(*cmd)[0], (*cmd)[1], (*cmd)[2]};
        lcm_->publish("BRIDGE_COMMAND", &c);
        next += 12500us;
      }
      lcm_->handleTimeout(2);
    }
  }

  // Handles LCM until `done` holds or `limit` passes (start-up on a loaded machine).
  template <class Done>
  bool runUntil(Done done, std::chrono::milliseconds limit) {
    const auto end = std::chrono::steady_clock::now() + limit;
    while (!done() && std::chrono::steady_clock::now() < end) lcm_->handleTimeout(10);
    return done();
  }

  const plsa_lcm::status_t* lastStatusWith(const std::string& words) const {
    for (auto it = inbox_.statuses.rbegin(); it != inbox_.statuses.rend(); ++it)
      if (it->message.find(words) != std::string::npos) return &*it;
    return nullptr;
  }

  Inbox inbox_;
  std::int64_t seq_ = 0;
};

}  // namespace

TEST_F(CanBridgeTest, CommandsReachTheSimulatedValvesAndStopsVent) {
  plsa::test::ChildProcess sim({exe_, "sim", "--can", "udp:7201:7200", "--state-channel", "SIM_TRUTH", "--seed", "3"});
  // The device is on the bus before the bridge's sensor watchdog starts.
  ASSERT_TRUE(runUntil([&] { return !inbox_.truth.empty(); }, 10s)) << "the simulator never published its state";
  plsa::test::ChildProcess bridge({exe_, "can-bridge", "--iface", "udp:7200:7201?drop=0.03&corrupt=0.03&seed=5",
                                   "--command-channel", "BRIDGE_COMMAND", "--state-channel", "BRIDGE_STATE",
                                   "--status-channel", "BRIDGE_STATUS", "--command-timeout", "0.25"});
  ASSERT_TRUE(runUntil([&] { return !inbox_.bridge.empty(); }, 10s)) << "the bridge published no state";
  run(500ms, nullptr);
  EXPECT_EQ(lastStatusWith("no valid pressure reading"), nullptr) << "sensor frames did not reach the bridge";

  // Step: chamber 1 to 0.25 bar, chamber 2 asked for 0.6 (clamped to 0.4).
  const std::array<double, 3> step{0.25, 0.6, 0.0};
  inbox_.bridge.clear();
  run(3000ms, &step);
  ASSERT_GT(inbox_.bridge.size(), 150u);
  const auto& last = inbox_.bridge.back();
  EXPECT_EQ(last.vented, 0);
  EXPECT_NEAR(last.command_bar[0], 0.25, 1e-9);
  EXPECT_NEAR(last.command_bar[1], 0.4, 1e-9) << "set-point not clamped";
  // Chamber pressure follows the set-point through the simulated pneumatics
  // and comes back over CAN (1e-5 bar counts).
  EXPECT_NEAR(last.pressure_bar[0], 0.25, 0.03);
  EXPECT_NEAR(last.pressure_bar[1], 0.40, 0.04);
  EXPECT_LT(last.pressure_bar[2], 0.02);
  // The tip angle travels over CAN too and matches the simulator's own state.
  ASSERT_TRUE(std::isfinite(last.bend_deg));
  ASSERT_FALSE(inbox_.truth.empty());
  EXPECT_GT(last.bend_deg, 5.0);
  EXPECT_NEAR(last.bend_deg, inbox_.truth.back().bend_deg, 1.0);
  // Injected faults were caught by the checksum and counter checks, never applied.
  const plsa_lcm::status_t* st = lastStatusWith("running");
  ASSERT_NE(st, nullptr);
  EXPECT_GT(statusValue(*st, "bad_checksum"), 0.0);
  EXPECT_GT(statusValue(*st, "counter_gaps"), 0.0);
  for (const auto& s : inbox_.bridge) EXPECT_LE(s.pressure_bar[0], 0.45) << "a corrupted reading got through";

  // Hostile commands: a negative and a huge chamber count once killed the
  // bridge with the valves pressurised. They are rejected and named; the
  // bridge keeps its set-points and its state stream.
  plsa_lcm::pressure_command_t probe;
  probe.n_chambers = 3;
  probe.pressure_bar = {0.25, 0.6, 0.0};
  for (const std::uint32_t n : {0xFFFFFFFFu, 0x10000000u}) {
    const std::string bad = plsa::test::withInt32(plsa::test::encoded(probe).substr(0, 28), 24, n);
    lcm_->publish("BRIDGE_COMMAND", bad.data(), static_cast<unsigned>(bad.size()));
    run(300ms, &step);
  }
  ASSERT_NE(lastStatusWith("n_chambers = -1 is outside 0..16"), nullptr) << "the malformed command was not named";
  inbox_.bridge.clear();
  run(500ms, &step);
  ASSERT_GT(inbox_.bridge.size(), 20u) << "the bridge stopped publishing after a malformed command";
  EXPECT_EQ(inbox_.bridge.back().vented, 0);
  EXPECT_NEAR(inbox_.bridge.back().pressure_bar[0], 0.25, 0.03);

  // Commands stop: within the 0.25 s timeout (plus a tick) the driver vents and latches.
  inbox_.bridge.clear();
  run(1500ms, nullptr);
  ASSERT_NE(lastStatusWith("commands stopped"), nullptr) << "no command-timeout fault reported";
  ASSERT_FALSE(inbox_.bridge.empty());
  EXPECT_EQ(inbox_.bridge.back().vented, 1);
  for (double c : inbox_.bridge.back().command_bar) EXPECT_EQ(c, 0.0);
  EXPECT_LT(inbox_.bridge.back().pressure_bar[0], 0.03) << "chamber 1 did not vent";
  EXPECT_LT(inbox_.bridge.back().pressure_bar[1], 0.03) << "chamber 2 did not vent";

  // The fault latches: fresh commands alone do not re-pressurise...
  const std::array<double, 3> again{0.2, 0.0, 0.0};
  run(500ms, &again);
  EXPECT_EQ(inbox_.bridge.back().vented, 1);
  EXPECT_EQ(inbox_.bridge.back().command_bar[0], 0.0);
  // ...until the fault is cleared explicitly.
  plsa_lcm::status_t clear;
  clear.utime = 0;
  clear.source = "test";
  clear.state = plsa_lcm::status_t::OK;
  clear.message = "clear the fault";
  clear.n_values = 0;
  lcm_->publish("PLSA_CLEAR_FAULT", &clear);
  run(1500ms, &again);
  EXPECT_NE(lastStatusWith("fault cleared"), nullptr);
  EXPECT_EQ(inbox_.bridge.back().vented, 0);
  EXPECT_NEAR(inbox_.bridge.back().pressure_bar[0], 0.2, 0.03);

  // SIGINT: the bridge sends a vent frame before it exits; the simulator's
  // own state shows the valves at zero and the chambers emptying.
  EXPECT_EQ(bridge.stop(SIGINT), 0);
  inbox_.truth.clear();
  run(1500ms, nullptr);
  ASSERT_FALSE(inbox_.truth.empty());
  for (double c : inbox_.truth.back().command_bar) EXPECT_EQ(c, 0.0);
  EXPECT_LT(inbox_.truth.back().pressure_bar[0], 0.03);

  // SIGKILL leaves no time to vent: the valve controller's own command
  // timeout (0.5 s here) vents the chambers.
  plsa::test::ChildProcess doomed({exe_, "can-bridge", "--iface", "udp:7200:7201", "--command-channel",
                                   "BRIDGE_COMMAND", "--state-channel", "BRIDGE_STATE", "--status-channel",
                                   "BRIDGE_STATUS"});
  inbox_.bridge.clear();
  ASSERT_TRUE(runUntil([&] { return !inbox_.bridge.empty(); }, 10s)) << "the second bridge published no state";
  run(1500ms, &again);
  ASSERT_FALSE(inbox_.truth.empty());
  EXPECT_NEAR(inbox_.truth.back().command_bar[0], 0.2, 1e-3) << "the second bridge did not pressurise";
  EXPECT_EQ(doomed.stop(SIGKILL), 128 + SIGKILL);
  inbox_.truth.clear();
  run(300ms, nullptr);
  ASSERT_FALSE(inbox_.truth.empty());
  EXPECT_NEAR(inbox_.truth.back().command_bar[0], 0.2, 1e-3) << "the valves should hold within their timeout";
  run(1200ms, nullptr);
  for (double c : inbox_.truth.back().command_bar) EXPECT_EQ(c, 0.0) << "the valves did not vent on their own";
  EXPECT_LT(inbox_.truth.back().pressure_bar[0], 0.05);
  EXPECT_EQ(sim.stop(SIGTERM), 0);
}

namespace {

// A transport that fails as a library might: its statistics throw on the
// second call (the bridge's first periodic status), from inside the loop.
class ThrowingTransport : public plsa::can::CanTransport {
 public:
  explicit ThrowingTransport(std::unique_ptr<plsa::can::CanTransport> inner) : inner_(std::move(inner)) {}
  plsa::can::TransportStatus send(const plsa::can::CanFrame& f) override {
    events.push_back(thrown_ ? "send after the error" : "send");
    last = f;
    return inner_->send(f);
  }
  plsa::can::TransportStatus receive(plsa::can::CanFrame& f, std::chrono::microseconds t) override {
    return inner_->receive(f, t);
  }
  plsa::can::BusState busState() const override { return inner_->busState(); }
  plsa::can::TransportStats stats() const override {
    if (++stats_calls_ == 2) {
      thrown_ = true;
      throw std::runtime_error("transport statistics unavailable");
    }
    return inner_->stats();
  }
  std::vector<std::string> events;
  plsa::can::CanFrame last;

 private:
  std::unique_ptr<plsa::can::CanTransport> inner_;
  mutable int stats_calls_ = 0;
  mutable bool thrown_ = false;
};

}  // namespace

// An exception escaping the bridge's loop leaves through its vent: a vent
// frame is the last thing it sends, and the error still reaches the caller.
TEST_F(CanBridgeTest, AnErrorEscapingTheLoopSendsAVentFrameFirst) {
  auto bus = plsa::can::InProcessBus::create();
  ThrowingTransport transport(bus->connect());
  const plsa::can::SignalMap map = plsa::can::defaultSignalMap();
  plsa::lcm::CanBridgeOptions o;
  o.limits.sensor_timeout_s = 10;  // no sensor on this bus: keep that fault out of the way
  o.command_channel = "THROWING_COMMAND";
  std::atomic<bool> stop{false};
  try {
    plsa::lcm::runCanBridge(o, transport, map, stop);
    FAIL() << "the error did not reach the caller";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "transport statistics unavailable");
  }
  ASSERT_FALSE(transport.events.empty());
  EXPECT_EQ(transport.events.back(), "send after the error");
  double values[8];
  int counter = -1;
  ASSERT_NE(plsa::can::decodeFrame(map.message("valve_command"), transport.last, values, counter),
            plsa::can::DecodeStatus::kBadChecksum);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(values[i], 0.0);
}
