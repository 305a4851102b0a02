// The fixture of the end-to-end LCM tests (test_lcm_sim.cpp, test_predictor_node.cpp):
// `plsa` processes driven over LCM inside run_isolated.sh, their states and
// statuses collected with the checked decoders.
#pragma once

#include <gtest/gtest.h>

#include <array>
#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>
#include <plsa_lcm/actuator_state_t.hpp>
#include <plsa_lcm/pressure_command_t.hpp>
#include <plsa_lcm/status_t.hpp>

#include "plsa/lcm/message_codec.hpp"
#include "support/isolated_lcm_test.hpp"
#include "support/lcm_bytes.hpp"

namespace plsa::test {

// The test listens on channels it also sends hostile bytes to: it decodes with
// the checked decoders too, and keeps only what they accept.
struct Inbox {
  std::vector<plsa_lcm::actuator_state_t> states;
  std::vector<plsa_lcm::status_t> statuses;
  void onState(const ::lcm::ReceiveBuffer* b, const std::string&) {
    plsa_lcm::actuator_state_t m;
    if (plsa::lcm::decodeMessage(b->data, b->data_size, m).empty()) states.push_back(m);
  }
  void onStatus(const ::lcm::ReceiveBuffer* b, const std::string&) {
    plsa_lcm::status_t m;
    if (plsa::lcm::decodeMessage(b->data, b->data_size, m).empty()) statuses.push_back(m);
  }
};

class LcmSimTest : public plsa::test::IsolatedLcmTest {
 protected:
  void SetUp() override {
    IsolatedLcmTest::SetUp();
    if (IsSkipped() || HasFatalFailure()) return;
    lcm_->subscribe("PLSA_STATE", &Inbox::onState, &inbox_);
    lcm_->subscribe("PLSA_STATUS", &Inbox::onStatus, &inbox_);
  }

  // Handles messages until `done()` or the timeout; returns done().
  template <class Pred>
  bool waitFor(Pred done, std::chrono::milliseconds timeout) {
    const auto end = std::chrono::steady_clock::now() + timeout;
    while (!done() && std::chrono::steady_clock::now() < end) lcm_->handleTimeout(20);
    return done();
  }

  void send(std::array<double, 3> p, std::int64_t seq) {
    plsa_lcm::pressure_command_t c;
    c.utime = seq;
    c.seq = seq;
    c.n_chambers = 3;
    c.pressure_bar = {p[0], p[1], p[2]};
    lcm_->publish("PLSA_COMMAND", &c);
  }

  void publishRaw(const std::string& channel, const std::string& bytes) {
    lcm_->publish(channel, bytes.data(), static_cast<unsigned>(bytes.size()));
  }

  static std::string encodedCommand() {
    plsa_lcm::pressure_command_t c{};
    c.n_chambers = 3;
    c.pressure_bar = {0.1, 0.1, 0.1};
    return plsa::test::encoded(c);
  }

  bool sawSource(const std::string& source) const {
    for (const auto& s : inbox_.statuses)
      if (s.source == source) return true;
    return false;
  }

  bool sawStatus(int8_t state, const std::string& words) const {
    for (const auto& s : inbox_.statuses)
      if (s.state == state && s.message.find(words) != std::string::npos) return true;
    return false;
  }

  Inbox inbox_;
};

}  // namespace plsa::test
