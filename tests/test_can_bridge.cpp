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

#include <lcm/lcm-cpp.hpp>
#include <plsa_lcm/actuator_state_t.hpp>
#include <plsa_lcm/pressure_command_t.hpp>
#include <plsa_lcm/status_t.hpp>

#include "support/child_process.hpp"
#include "support/isolated_lcm_test.hpp"

using namespace std::chrono_literals;

namespace {

struct Inbox {
  std::vector<plsa_lcm::actuator_state_t> bridge, truth;
  std::vector<plsa_lcm::status_t> statuses;
  void onBridge(const lcm::ReceiveBuffer*, const std::string&, const plsa_lcm::actuator_state_t* m) { bridge.push_back(*m); }
  void onTruth(const lcm::ReceiveBuffer*, const std::string&, const plsa_lcm::actuator_state_t* m) { truth.push_back(*m); }
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
  EXPECT_EQ(sim.stop(SIGTERM), 0);
}
