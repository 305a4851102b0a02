// End to end over LCM: `plsa sim` as a separate process in a private network
// namespace (run_isolated.sh), driven by pressure commands from this test.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <map>
#include <set>
#include <system_error>
#include <thread>

#include <lcm/lcm-cpp.hpp>
#include <plsa_lcm/actuator_state_t.hpp>
#include <plsa_lcm/pressure_command_t.hpp>
#include <plsa_lcm/status_t.hpp>

#include <plsa_lcm/prediction_t.hpp>

#include "plsa/eval/fit.hpp"
#include "plsa/identify/pipeline.hpp"
#include "plsa/lcm/lcm_log.hpp"
#include "plsa/lcm/message_codec.hpp"
#include "plsa/lcm/predictor_node.hpp"
#include "plsa/model/model_file.hpp"
#include "plsa/predict/predictor.hpp"
#include "plsa/sim/experiment.hpp"
#include "plsa/sim/actuator.hpp"
#include "support/child_process.hpp"
#include "support/lcm_bytes.hpp"
#include "support/isolated_lcm_test.hpp"

namespace fs = std::filesystem;
using namespace std::chrono_literals;

namespace {

// The test listens on channels it also sends hostile bytes to: it decodes with
// the checked decoders too, and keeps only what they accept.
struct Inbox {
  std::vector<plsa_lcm::actuator_state_t> states;
  std::vector<plsa_lcm::status_t> statuses;
  void onState(const lcm::ReceiveBuffer* b, const std::string&) {
    plsa_lcm::actuator_state_t m;
    if (plsa::lcm::decodeMessage(b->data, b->data_size, m).empty()) states.push_back(m);
  }
  void onStatus(const lcm::ReceiveBuffer* b, const std::string&) {
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

}  // namespace

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
  for (Eigen::Index r = 0; r < rec.samples(); ++r) recorded.insert(std::llround(time(r) * 1e6));
  std::string missing;
  for (const auto& st : inbox_.states)
    if (st.seq < 400 && !recorded.count(st.utime)) missing += " " + std::to_string(st.seq);
  for (Eigen::Index r = 0; r < rec.samples(); ++r) {
    const auto it = by_time.find(std::llround(time(r) * 1e6));
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

// plsa sim and plsa predict as separate processes: the published 40-step
// predictions match an in-process predictor exactly and track what the
// simulator later does.
// A negative horizon sized a trajectory from it (a length error, not a
// message); a repeated one was published twice; a huge one failed with
// bad_alloc. All are refused before LCM opens.
TEST(PredictorNode, RefusesABadOrRepeatedHorizonByName) {
  const std::atomic<bool> stop{true};
  const plsa::DioPwlObfModel model;
  const auto expectRefusal = [&](std::vector<int> horizons, const std::string& words) {
    plsa::lcm::PredictorNodeOptions o;
    o.url = "udpm://239.255.76.67:7667?ttl=0";
    o.horizons = std::move(horizons);
    try {
      plsa::lcm::runPredictorNode(model, o, stop);
      ADD_FAILURE() << "accepted; expected '" << words << "'";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
    }
  };
  expectRefusal({-5, 40}, "horizons must be >= 1, got -5");
  expectRefusal({0}, "horizons must be >= 1, got 0");
  expectRefusal({40, 80, 40}, "horizon 40 is given twice");
  expectRefusal({}, "no horizons");
  expectRefusal({40, 4801}, "horizon 4801 (60.01 s) is beyond the 60 s published at most: 4800 samples at 0.0125 s");
  expectRefusal({2000000000}, "horizon 2000000000");
}

namespace {

// A small valid model of the state message's columns (no identification needed).
plsa::DioPwlObfModel handMadeModel() {
  plsa::DioPwlObfModel m;
  m.inputs = {"p_1", "p_2", "p_3"};
  m.outputs = {"bend_deg", "steer_deg"};
  m.input_min = 0.0;
  m.input_max = 0.4;
  for (int o = 0; o < 2; ++o) m.poles.push_back(std::vector<plsa::PoleSet>(3, plsa::PoleSet::real({0.9, 0.7})));
  m.shaping.play.assign(3, {plsa::PlayChannel(0.0)});
  m.coefficients = {{Eigen::VectorXd::Constant(6, 0.5), Eigen::VectorXd::Constant(6, 0.25)}};
  m.region_fits = {{100, -1, ""}};
  return m;
}

// Collects the predictions a node publishes.
struct PredictionSink {
  std::vector<plsa_lcm::prediction_t> received;
  void on(const lcm::ReceiveBuffer*, const std::string&, const plsa_lcm::prediction_t* m) { received.push_back(*m); }
};

}  // namespace

// Malformed state messages are counted and named, never a crash; one state
// stamped at INT64_MAX microseconds once stopped every later prediction while
// the status said "running": now the node restarts and says so.
TEST_F(LcmSimTest, PredictorNodeSurvivesHostileStatesAndRecoversFromAJumpInTime) {
  const fs::path model_path =
      fs::temp_directory_path() / ("plsa_hostile_model_" + std::to_string(::getpid()) + ".json");
  plsa::saveModel(model_path.string(), handMadeModel());
  PredictionSink sink;
  std::vector<plsa_lcm::prediction_t>& predictions = sink.received;
  lcm_->subscribe("PLSA_PREDICTION", &PredictionSink::on, &sink);
  plsa::test::ChildProcess pred({exe_, "predict", "--model", model_path.string(), "--horizons", "5"});
  ASSERT_TRUE(waitFor([&] { return sawSource("plsa predict"); }, 30s)) << "plsa predict never said it was running";
  std::int64_t seq = 0;
  auto sendState = [&](std::int64_t utime) {
    const plsa_lcm::actuator_state_t s = plsa::test::stateMessage(utime, seq++);
    lcm_->publish("PLSA_STATE", &s);
    const std::int64_t want = s.seq;
    return waitFor([&] { return !predictions.empty() && predictions.back().state_seq == want; }, 3s);
  };
  for (int k = 0; k < 5; ++k) ASSERT_TRUE(sendState(12500 * (k + 1))) << k;
  // A negative chamber count, a huge one, and bytes of the wrong type.
  const std::string bytes = plsa::test::encoded(plsa::test::stateMessage(12500 * 6, 99));
  publishRaw("PLSA_STATE", plsa::test::withInt32(bytes, 24, 0xFFFFFFFEu));
  publishRaw("PLSA_STATE", plsa::test::withInt32(bytes, 24, 0x10000000u));
  publishRaw("PLSA_STATE", encodedCommand());
  // One state far in the future: accepted as a gap; then the clock comes back.
  ASSERT_TRUE(sendState(std::numeric_limits<std::int64_t>::max()));
  int predicted_after = 0;
  for (int k = 6; k < 12; ++k) predicted_after += sendState(12500 * (k + 1)) ? 1 : 0;
  EXPECT_GE(predicted_after, 6 - (plsa::kClockStepSamples - 1)) << "the node did not recover from the jump in time";
  // Its last status, sent as it stops, counts everything.
  inbox_.statuses.clear();
  EXPECT_EQ(pred.stop(SIGTERM), 0);
  fs::remove(model_path);
  ASSERT_TRUE(waitFor([&] { return sawSource("plsa predict"); }, 3s)) << "no final status";
  const plsa_lcm::status_t* last = nullptr;
  for (const auto& s : inbox_.statuses)
    if (s.source == "plsa predict") last = &s;
  const auto value = [&](const std::string& name) {
    for (std::size_t i = 0; i < last->names.size(); ++i)
      if (last->names[i] == name) return last->values[i];
    return -1.0;
  };
  EXPECT_EQ(value("rejected_malformed"), 3);
  EXPECT_EQ(value("rejected_time"), plsa::kClockStepSamples - 1);
  EXPECT_EQ(value("restarts"), 2);  // the jump ahead, then the clock stepping back
}

TEST_F(LcmSimTest, PredictorNodeForecastsTheSimulator) {
  // A model of the default simulator, identified here.
  plsa::sim::ExperimentOptions eo;
  eo.hold_s = 2.5;
  eo.joystick_duration_s = 20;
  plsa::sim::Actuator rig(plsa::sim::SimConfig{}, 11);
  const plsa::io::Log train = plsa::sim::runExperiment(rig, plsa::sim::gridExperiment(eo));
  plsa::identify::IdentifyOptions io;
  io.play_candidates = {{0.1}};
  // Any model serves the node; the threshold and drift stages only cost time
  // (under ASan the threshold stage pushed this test past its limit).
  io.play_threshold_candidates = {};
  io.output_drift = plsa::identify::OutputDriftChoice::kOff;
  const plsa::DioPwlObfModel model = plsa::identify::identifyModel({train}, io);
  const fs::path model_path =
      fs::temp_directory_path() / ("plsa_predict_model_" + std::to_string(::getpid()) + ".json");
  plsa::saveModel(model_path.string(), model);

  PredictionSink sink;
  std::vector<plsa_lcm::prediction_t>& predictions = sink.received;
  lcm_->subscribe("PLSA_PREDICTION", &PredictionSink::on, &sink);
  plsa::test::ChildProcess sim({exe_, "sim", "--lockstep", "--seed", "3", "--command-timeout", "2"});
  plsa::test::ChildProcess pred({exe_, "predict", "--model", model_path.string(), "--horizons", "40"});
  // The node subscribes before its run loop starts, which publishes a status
  // a second; a fixed wait here once missed 18 states on a loaded machine.
  ASSERT_TRUE(waitFor([&] { return sawSource("plsa sim") && sawSource("plsa predict"); }, 30s))
      << "plsa sim or plsa predict never said it was running";

  // Each command waits for its state and that state's prediction: in lock
  // step with both nodes no socket buffer fills, so on a loaded machine (ASan,
  // ctest -j2) nothing is dropped and every state must be predicted.
  const plsa::sim::Experiment joy = plsa::sim::joystickExperiment(eo);
  for (Eigen::Index k = 0; k < joy.commands.rows(); ++k) {
    send({joy.commands(k, 0), joy.commands(k, 1), joy.commands(k, 2)}, k);
    const auto n = static_cast<std::size_t>(k) + 1;
    ASSERT_TRUE(waitFor([&] { return inbox_.states.size() >= n; }, 5s)) << "no state " << k;
    const std::int64_t seq = inbox_.states.back().seq;
    ASSERT_TRUE(waitFor([&] { return !predictions.empty() && predictions.back().state_seq >= seq; }, 5s))
        << "no prediction for state " << seq << " (" << predictions.size() << " so far)";
  }
  const std::size_t n_states = static_cast<std::size_t>(joy.commands.rows());
  EXPECT_EQ(sim.stop(SIGTERM), 0);
  EXPECT_EQ(pred.stop(SIGTERM), 0);
  fs::remove(model_path);

  // Reference: the same predictor in this process, fed the same states.
  ASSERT_EQ(inbox_.states.size(), n_states);
  ASSERT_EQ(predictions.size(), n_states) << "a state predicted twice or a prediction unasked for";
  ASSERT_EQ(predictions.front().state_seq, inbox_.states.front().seq);
  plsa::Predictor<> ref(model);
  std::map<std::int64_t, Eigen::MatrixXd> expected;
  Eigen::MatrixXd out(40, 2);
  for (std::size_t k = 0; k < n_states; ++k) {
    const auto& st = inbox_.states[k];
    const Eigen::Vector3d u(st.pressure_bar[0], st.pressure_bar[1], st.pressure_bar[2]);
    const Eigen::Vector2d y(st.bend_deg, st.steer_deg);
    ASSERT_EQ(ref.update(static_cast<double>(st.utime) * 1e-6, u, y), plsa::PredictorStatus::kOk);
    ASSERT_EQ(ref.predict(40, Eigen::MatrixXd(0, 3), out), plsa::PredictorStatus::kOk);
    expected[st.seq] = out;
  }
  std::vector<double> predicted, actual;
  for (const auto& p : predictions) {
    ASSERT_EQ(p.horizon, 40);
    ASSERT_EQ(p.output_names[0], "bend_deg");
    const auto& want = expected.at(p.state_seq);
    for (int h = 0; h < 40; ++h) EXPECT_EQ(p.trajectory[static_cast<std::size_t>(h)][0], want(h, 0));
    const auto later = static_cast<std::size_t>(p.state_seq + 40);
    if (p.state_seq >= joy.record_from && later < n_states) {
      predicted.push_back(p.trajectory[39][0]);
      actual.push_back(inbox_.states[later].bend_deg);
    }
  }
  const double fit =
      plsa::nrmseFit(Eigen::Map<Eigen::VectorXd>(actual.data(), static_cast<Eigen::Index>(actual.size())),
                     Eigen::Map<Eigen::VectorXd>(predicted.data(), static_cast<Eigen::Index>(predicted.size())));
  std::printf("40-step bend fit of the LCM predictor node against the simulator, held inputs: %.1f%%\n", fit);
  EXPECT_GT(fit, 50.0);
  // Its status names latency figures and no rejected samples.
  bool saw = false;
  for (const auto& s : inbox_.statuses)
    if (s.source == "plsa predict") {
      saw = true;
      EXPECT_EQ(s.names[3], "latency_p50_us");
    }
  EXPECT_TRUE(saw);
}
