// What each fuzz target does with its bytes, shared by the libFuzzer entry
// points (fuzz_entry.cpp, clang) and the corpus replay test
// (tests/test_fuzz_corpus.cpp, every build), so every committed regression
// input runs in the ordinary test suite too. Each decoder of outside bytes
// must either accept the input (and then the result must hold its
// invariants) or throw std::invalid_argument / std::runtime_error with a
// message; anything else (another exception, a crash, a sanitizer report) is
// a defect. Invariant violations call std::abort so the fuzzer stops there.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <sstream>
#include <stdexcept>
#include <string>

#include <Eigen/Dense>

#include "plsa/can/candump_log.hpp"
#include "plsa/can/dbc.hpp"
#include "plsa/can/signal_map.hpp"
#include "plsa/can/udp_transport.hpp"
#include "plsa/can/valve_driver.hpp"
#include "plsa/io/csv_log.hpp"
#include "plsa/model/model_file.hpp"
#include "plsa/predict/predictor.hpp"
#include "plsa/sim/actuator.hpp"
#include "plsa/sim/sim_config.hpp"
#ifdef PLSA_FUZZ_WITH_LCM
#include "plsa/lcm/lcm_log.hpp"
#include "plsa/lcm/message_codec.hpp"
#endif

namespace plsa::fuzz {

inline void require(bool ok) {
  if (!ok) std::abort();
}

// Runs `parse`; a clean refusal is a std::invalid_argument or std::runtime_error with a message.
template <class Parse>
bool acceptedOrRefused(Parse parse) {
  try {
    parse();
    return true;
  } catch (const std::invalid_argument& e) {
    require(std::strlen(e.what()) > 0);
  } catch (const std::runtime_error& e) {
    require(std::strlen(e.what()) > 0);
  }
  return false;
}

inline std::string text(const std::uint8_t* data, std::size_t size) {
  return std::string(reinterpret_cast<const char*>(data), size);
}

/// CSV logs: a parsed log is rectangular, finite, named, with time increasing.
inline void csvLog(const std::uint8_t* data, std::size_t size) {
  std::istringstream in(text(data, size));
  io::Log log;
  if (!acceptedOrRefused([&] { log = io::readCsvLog(in, "fuzz.csv"); })) return;
  require(log.samples() > 0 && static_cast<std::size_t>(log.data.cols()) == log.columns.size());
  require(log.data.allFinite());
  if (log.hasColumn("time_s")) {
    const Eigen::VectorXd t = log.column("time_s");
    for (Eigen::Index k = 1; k < t.size(); ++k) require(t(k) > t(k - 1));
  }
}

/// candump bus logs: a read log has the recorded columns, finite values and
/// a uniform time grid from 0; recognising one never throws.
inline void candumpLog(const std::uint8_t* data, std::size_t size) {
  const std::string bytes = text(data, size);
  (void)can::looksLikeCandump(bytes.substr(0, io::kSniffBytes));
  std::istringstream in(bytes);
  io::Log log;
  if (!acceptedOrRefused([&] { log = can::readCandumpLog(in, "fuzz.log", can::defaultSignalMap()); })) return;
  require(log.samples() >= 2 && static_cast<std::size_t>(log.data.cols()) == log.columns.size());
  require(log.data.allFinite() && log.columns.front() == "time_s" && log.hasColumn("p_1"));
  const Eigen::VectorXd t = log.column("time_s");
  require(t(0) == 0.0);
  for (Eigen::Index k = 1; k < t.size(); ++k) require(t(k) > t(k - 1));
}

/// Model files: a loaded model validates, writes and reads back to the same
/// text, and drives a predictor for a few samples without a crash.
inline void modelFile(const std::uint8_t* data, std::size_t size) {
  DioPwlObfModel m;
  if (!acceptedOrRefused([&] { m = modelFromJson(text(data, size), "fuzz.json"); })) return;
  m.validate();
  const std::string once = modelToJson(m);
  require(modelToJson(modelFromJson(once, "again")) == once);
  // Keep the predictor's set-up small: a fuzzed model may have thousands of poles.
  std::size_t states = 0;
  for (const auto& row : m.poles)
    for (const auto& ps : row) states += static_cast<std::size_t>(ps.size());
  if (states * static_cast<std::size_t>(m.partition.regionCount()) > 4096) return;
  PredictorOptions po;
  po.max_horizon = 8;
  std::unique_ptr<Predictor<>> p;
  if (!acceptedOrRefused([&] { p = std::make_unique<Predictor<>>(m, po); })) return;
  Eigen::VectorXd u = Eigen::VectorXd::Zero(m.inputCount()), y = Eigen::VectorXd::Zero(m.outputCount());
  Eigen::MatrixXd out(8, m.outputCount());
  for (int k = 0; k < 4; ++k) {
    (void)p->update(k * m.sample_time_s, u, y);
    (void)p->predict(8, Eigen::MatrixXd(0, m.inputCount()), out);
  }
}

/// Simulator configurations: a parsed one validates, round-trips, and steps.
inline void simConfig(const std::uint8_t* data, std::size_t size) {
  sim::SimConfig c;
  if (!acceptedOrRefused([&] { c = sim::simConfigFromJson(text(data, size), "fuzz.json"); })) return;
  c.validate();
  const std::string once = sim::simConfigToJson(c);
  require(sim::simConfigToJson(sim::simConfigFromJson(once, "again")) == once);
  sim::Actuator a(c, 1);
  for (int k = 0; k < 8; ++k) {
    const sim::ActuatorSample s = a.step({0.1 * k / 8, 0.0, 0.2});
    require(std::isfinite(s.bend_deg) && std::isfinite(s.steer_deg));
  }
}

/// Signal maps: a parsed map validates, and every message encodes and decodes back.
/// Signal maps, as JSON and as DBC: a parsed map validates, writes and reads
/// back the same in both formats, and every message encodes and decodes back.
inline void checkSignalMap(const can::SignalMap& map) {
  map.validate();
  const std::string json = can::signalMapToJson(map);
  require(can::signalMapToJson(can::signalMapFromJson(json, "again.json")) == json);
  std::string dbc;
  if (acceptedOrRefused([&] { dbc = can::signalMapToDbc(map); })) {  // names that are no identifiers: refused
    can::SignalMap back = can::signalMapFromDbc(dbc, "again.dbc", map.profile);
    require(can::signalMapToJson(back) == json);
  }
  (void)can::driverProfileWarnings(map);
  for (const auto& m : map.messages) {
    double values[can::MessageLayout::kMaxSignals] = {};
    for (std::size_t s = 0; s < m.signals.size(); ++s) values[s] = m.signals[s].offset;  // raw 0 always fits
    can::CanFrame f;
    require(can::encodeFrame(m, values, 5, f));
    double back[can::MessageLayout::kMaxSignals];
    int counter = 4;
    require(can::decodeFrame(m, f, back, counter) == can::DecodeStatus::kOk);
    for (std::size_t s = 0; s < m.signals.size(); ++s)
      require(std::abs(back[s] - values[s]) <= 1e-9 * (1 + std::abs(values[s])));
  }
}
inline void signalMap(const std::uint8_t* data, std::size_t size) {
  can::SignalMap map;
  if (acceptedOrRefused([&] { map = can::signalMapFromJson(text(data, size), "fuzz.json"); })) checkSignalMap(map);
  if (acceptedOrRefused([&] { map = can::signalMapFromDbc(text(data, size), "fuzz.dbc", "fuzz"); }))
    checkSignalMap(map);
}

// A transport that plays back bytes as frames, 11 bytes each (id 2, dlc 1, data 8).
class ReplayTransport : public can::CanTransport {
 public:
  ReplayTransport(const std::uint8_t* d, std::size_t n) : d_(d), n_(n) {}
  can::TransportStatus send(const can::CanFrame&) override { return can::TransportStatus::kOk; }
  can::TransportStatus receive(can::CanFrame& f, std::chrono::microseconds) override {
    if (pos_ + 11 > n_) return can::TransportStatus::kTimeout;
    f = can::CanFrame{};
    f.id = (static_cast<std::uint32_t>(d_[pos_]) | static_cast<std::uint32_t>(d_[pos_ + 1]) << 8) & 0x7FF;
    f.dlc = d_[pos_ + 2] % 9;
    std::memcpy(f.data.data(), d_ + pos_ + 3, 8);
    pos_ += 11;
    return can::TransportStatus::kOk;
  }
  can::BusState busState() const override { return can::BusState::kActive; }
  can::TransportStats stats() const override { return {}; }

 private:
  const std::uint8_t* d_;
  std::size_t n_, pos_ = 0;
};

/// CAN frames into the decoder (every message of the default profile) and the
/// valve driver: readings finite and within the signal's range, set-points
/// within the clamp whatever the sensors claim.
inline void canFrames(const std::uint8_t* data, std::size_t size) {
  static const can::SignalMap map = can::defaultSignalMap();
  int counters[8] = {-1, -1, -1, -1, -1, -1, -1, -1};
  double values[can::MessageLayout::kMaxSignals];
  can::CanFrame f;
  ReplayTransport frames(data, size);
  while (frames.receive(f, std::chrono::microseconds(0)) == can::TransportStatus::kOk)
    for (std::size_t m = 0; m < map.messages.size(); ++m) {
      const auto st = can::decodeFrame(map.messages[m], f, values, counters[m]);
      if (st == can::DecodeStatus::kOk || st == can::DecodeStatus::kCounterGap)
        for (std::size_t s = 0; s < map.messages[m].signals.size(); ++s) require(std::isfinite(values[s]));
    }
  ReplayTransport replay(data, size);
  can::ValveDriver driver(replay, map, can::SafetyLimits{}, 0.0);
  driver.command(0.0, {0.1, 0.2, 0.3});
  driver.tick(0.01);
  for (double p : driver.pressures()) require(std::isfinite(p) && p >= 0 && p <= 0.65536);
  for (double o : driver.output()) require(o >= 0 && o <= 0.4);
  // A reading above the overpressure limit vents at once.
  for (double p : driver.pressures())
    if (p > can::SafetyLimits{}.overpressureBar()) require(driver.output() == (std::array<double, 3>{0, 0, 0}));
}

/// Loopback-UDP datagrams: a decoded one re-encodes to the same bytes.
inline void udpDatagram(const std::uint8_t* data, std::size_t size) {
  can::DatagramKind kind{};
  can::CanFrame f;
  if (!can::decodeDatagram(data, size, kind, f)) return;
  require(f.dlc <= 8 && f.id <= 0x7FF);
  std::array<std::uint8_t, can::kUdpCanDatagramSize> again{};
  can::encodeDatagram(kind, f, again);
  require(std::memcmp(again.data(), data, again.size()) == 0);
}

#ifdef PLSA_FUZZ_WITH_LCM
/// One LCM message type: an accepted message re-encodes to exactly its bytes,
/// and its counts match its arrays.
template <class Message>
void lcmMessage(const std::uint8_t* data, std::size_t size) {
  Message m;
  if (!lcm::decodeMessage(data, size, m).empty()) return;
  std::string again(static_cast<std::size_t>(m.getEncodedSize()), '\0');
  require(m.encode(again.data(), 0, static_cast<int>(again.size())) == static_cast<int>(size));
  require(again.size() == size && std::memcmp(again.data(), data, size) == 0);
}

/// LCM event logs: a read log is rectangular, finite, with time increasing.
inline void lcmLog(const std::uint8_t* data, std::size_t size) {
  std::istringstream in(text(data, size));
  io::Log log;
  if (!acceptedOrRefused([&] { log = lcm::readLcmLog(in, "fuzz.lcmlog"); })) return;
  require(log.samples() > 0 && log.data.cols() == 9 && log.data.allFinite());
  for (Eigen::Index k = 1; k < log.samples(); ++k) require(log.data(k, 0) > log.data(k - 1, 0));
}
#endif

}  // namespace plsa::fuzz
