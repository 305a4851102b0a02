// End to end over LCM: `plsa sim` as a separate process in a private network
// namespace (run_isolated.sh), driven by pressure commands from this test.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <map>
#include <set>
#include <string>
#include <system_error>
#include <thread>
#include <vector>

#include <plsa_lcm/actuator_state_t.hpp>
#include <plsa_lcm/status_t.hpp>

#include "plsa/lcm/lcm_log.hpp"
#include "plsa/lcm/state_codec.hpp"
#include "plsa/sim/actuator.hpp"
#include "support/child_process.hpp"
#include "support/lcm_bytes.hpp"
#include "support/lcm_sim_fixture.hpp"

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using plsa::test::LcmSimTest;

TEST_F(LcmSimTest, LockstepStepResponseMatchesSimulatorThenVentsWhenCommandsStop) {
  const fs::path log_path = fs::temp_directory_path() / ("plsa_lcm_test_" + std::to_string(::getpid()) + ".lcmlog");
  // lcm-logger has no ready signal: it also records a probe channel, and the
  // test starts once a probe has reached the file (it flushes every 100 ms).
  // A fixed sleep was not enough on a loaded CI machine (110 states lost).
  plsa::test::ChildProcess logger(
      {"/usr/bin/lcm-logger", "-q", "-f", "-c", "PLSA_STATE|PLSA_LOGGER_PROBE", log_path.string()});
  ASSERT_TRUE(waitFor(
      [&] {
        publishRaw("PLSA_LOGGER_PROBE", "probe");
        std::error_code ec;
        const auto bytes = fs::file_size(log_path, ec);
        return !ec && bytes > 0;
      },
      20s))
      << "lcm-logger recorded no probe within 20 s";
  plsa::test::ChildProcess sim({exe_, "sim", "--lockstep", "--seed", "5", "--command-timeout", "0.3"});
  ASSERT_TRUE(waitFor([&] { return !inbox_.statuses.empty(); }, 10s)) << "plsa sim never said it started";

  // Paper-style local step: rest, then 0.3 bar on chamber 1.
  std::vector<std::array<double, 3>> commands(80, {0.0, 0.0, 0.0});
  commands.resize(400, {0.3, 0.0, 0.0});
  // Paced at 500 Hz (six times the real 80 Hz): unpaced lock-step runs at
  // several kHz and lcm-logger, descheduled on a loaded machine, drops bursts.
  for (std::size_t k = 0; k < commands.size(); ++k) {
    std::this_thread::sleep_for(2ms);
    send(commands[k], static_cast<std::int64_t>(k));
    ASSERT_TRUE(waitFor([&] { return inbox_.states.size() > k; }, 2s)) << "no state for command " << k;
  }
  // The same simulator in this process, same seed and commands: identical numbers.
  plsa::sim::Actuator local(plsa::sim::SimConfig{}, 5);
  double max_diff = 0;
  for (std::size_t k = 0; k < commands.size(); ++k) {
    const auto s = local.step(commands[k]);
    max_diff = std::max(max_diff, std::abs(s.bend_deg - inbox_.states[k].bend_deg));
    EXPECT_EQ(inbox_.states[k].seq, static_cast<std::int64_t>(k));
    EXPECT_EQ(inbox_.states[k].vented, 0);
  }
  EXPECT_EQ(max_diff, 0.0);
  // One time base: states are stamped on the epoch time line, from the node's
  // start plus simulated time (5 s for 400 samples), as its statuses are.
  const std::int64_t now_us = plsa::lcm::epochMicroseconds();
  EXPECT_EQ(inbox_.states[399].utime - inbox_.states[0].utime, 399 * 12'500);
  EXPECT_LT(std::llabs(inbox_.states[0].utime - now_us), 60'000'000) << "state utime is not epoch microseconds";
  EXPECT_LT(std::llabs(inbox_.statuses.front().utime - now_us), 60'000'000) << "status utime is not epoch time";
  EXPECT_LT(inbox_.states[79].bend_deg, 2.5);    // at rest: sensor tilt and noise only
  EXPECT_GT(inbox_.states[399].bend_deg, 45.0);  // settled step response
  EXPECT_GT(inbox_.states[399].pressure_bar[0], 0.29);

  // Stop commanding: after the timeout the node vents on its own.
  const std::size_t before = inbox_.states.size();
  ASSERT_TRUE(waitFor(
      [&] {
        return inbox_.states.size() > before && inbox_.states.back().vented == 1 &&
               inbox_.states.back().pressure_bar[0] < 0.005;
      },
      5s))
      << "chambers did not vent after commands stopped";
  EXPECT_TRUE(sawStatus(plsa_lcm::status_t::VENTED, "no command for 0.300 s"));

  EXPECT_EQ(sim.stop(SIGTERM), 0);
  EXPECT_TRUE(waitFor([&] { return sawStatus(plsa_lcm::status_t::STOPPED, "vented"); }, 2s));
  logger.stop(SIGINT);

  // The recording reads back as a log with the standard columns. LCM over
  // UDP may drop a datagram under load, so rows are matched by time stamp
  // and at most 1% of the 400 may be missing; every recorded row must match.
  const plsa::io::Log rec = plsa::lcm::readLcmLog(log_path.string());
  std::map<std::int64_t, const plsa_lcm::actuator_state_t*> by_time;
  for (const auto& st : inbox_.states) by_time[st.utime] = &st;
  const Eigen::VectorXd time = rec.column("time_s"), bend = rec.column("bend_deg"), p1 = rec.column("p_1");
  int matched = 0;
  std::set<std::int64_t> recorded;
  // Epoch microseconds (~1.8e15) make a round trip through seconds as a
  // double to within 1 us: rows match the state nearest their time.
  auto nearest = [&](double t) {
    const std::int64_t us = std::llround(t * 1e6);
    for (std::int64_t d : {0, -1, 1})
      if (const auto it = by_time.find(us + d); it != by_time.end()) return it;
    return by_time.end();
  };
  for (Eigen::Index r = 0; r < rec.samples(); ++r)
    if (const auto it = nearest(time(r)); it != by_time.end()) recorded.insert(it->first);
  std::string missing;
  for (const auto& st : inbox_.states)
    if (st.seq < 400 && !recorded.count(st.utime)) missing += " " + std::to_string(st.seq);
  for (Eigen::Index r = 0; r < rec.samples(); ++r) {
    const auto it = nearest(time(r));
    ASSERT_NE(it, by_time.end()) << "recorded row " << r << " at " << time(r) << " s was never published";
    EXPECT_EQ(bend(r), it->second->bend_deg) << "row " << r;
    EXPECT_EQ(p1(r), it->second->pressure_bar[0]) << "row " << r;
    if (it->second->seq < 400) ++matched;
  }
  EXPECT_GE(matched, 396) << "the recording lost more than 1% of the commanded states; missing seq:" << missing;
  fs::remove(log_path);
}

TEST_F(LcmSimTest, RejectsMalformedCommandsAndKeepsRunning) {
  plsa::test::ChildProcess sim({exe_, "sim", "--lockstep"});
  ASSERT_TRUE(waitFor([&] { return !inbox_.statuses.empty(); }, 10s));
  send({std::numeric_limits<double>::quiet_NaN(), 0, 0}, 0);
  ASSERT_TRUE(waitFor([&] { return sawStatus(plsa_lcm::status_t::VENTED, "rejected a command"); }, 2s));
  // Hostile bytes: the counts that killed the node (a length error, then 2 GiB and SIGSEGV).
  for (const std::uint32_t n : {0xFFFFFFFFu, 0x10000000u}) {
    std::this_thread::sleep_for(250ms);  // rejections are reported at most every 200 ms
    publishRaw("PLSA_COMMAND", plsa::test::withInt32(encodedCommand().substr(0, 28), 24, n));
  }
  ASSERT_TRUE(waitFor([&] { return sawStatus(plsa_lcm::status_t::VENTED, "n_chambers = 268435456"); }, 2s));
  EXPECT_TRUE(sawStatus(plsa_lcm::status_t::VENTED, "n_chambers = -1 is outside 0..16"));
  // A flood is counted, not echoed: 50 malformed commands at once, a status or two.
  std::this_thread::sleep_for(250ms);
  inbox_.statuses.clear();
  const auto t0 = std::chrono::steady_clock::now();
  for (int i = 0; i < 50; ++i) publishRaw("PLSA_COMMAND", encodedCommand().substr(0, 27));
  const bool quick = std::chrono::steady_clock::now() - t0 < 150ms;
  waitFor([] { return false; }, 500ms);
  int echoed = 0;
  for (const auto& s : inbox_.statuses) echoed += s.message.find("rejected a command") != std::string::npos;
  EXPECT_GE(echoed, 1);
  if (quick) {
    EXPECT_LE(echoed, 2) << "each malformed command was echoed";
  }
  EXPECT_TRUE(inbox_.states.empty()) << "a rejected command must not advance the simulation";
  send({0.9, 0, 0}, 1);  // above the limit: clamped, not rejected
  ASSERT_TRUE(waitFor([&] { return !inbox_.states.empty(); }, 2s));
  EXPECT_DOUBLE_EQ(inbox_.states[0].command_bar[0], 0.4);
  EXPECT_EQ(sim.stop(SIGINT), 0);
}

TEST_F(LcmSimTest, RealTimeModePublishesEverySampleAndStaysVentedWithoutCommands) {
  plsa::test::ChildProcess sim({exe_, "sim", "--duration", "1.0"});
  const auto t0 = std::chrono::steady_clock::now();
  // Receive while it runs: LCM drops what the socket buffer cannot hold.
  ASSERT_TRUE(waitFor([&] { return sawStatus(plsa_lcm::status_t::STOPPED, "vented"); }, 10s));
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_EQ(sim.waitExit(5000ms), 0);
  // 80 samples for one simulated second, then the final vent state.
  ASSERT_EQ(inbox_.states.size(), 81u);
  for (std::size_t k = 0; k < inbox_.states.size(); ++k) {
    EXPECT_EQ(inbox_.states[k].seq, static_cast<std::int64_t>(k));
    EXPECT_EQ(inbox_.states[k].vented, 1);
  }
  EXPECT_GT(wall, 0.9) << "real-time mode ran faster than real time";
}
