#include "plsa/lcm/predictor_node.hpp"

#include <poll.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>

#include <lcm/lcm-cpp.hpp>
#include <plsa_lcm/actuator_state_t.hpp>
#include <plsa_lcm/prediction_t.hpp>
#include <plsa_lcm/status_t.hpp>

#include "plsa/core/check.hpp"
#include "plsa/io/standard_columns.hpp"
#include "plsa/lcm/message_codec.hpp"
#include "plsa/lcm/state_codec.hpp"
#include "plsa/predict/predictor.hpp"
#include "plsa/predict/realtime_thread.hpp"

namespace plsa::lcm {
namespace {

using Clock = std::chrono::steady_clock;

// Where a model column lives in an actuator-state message.
struct Field {
  enum Kind { kPressure, kCommand, kBend, kSteer } kind;
  int index = 0;
};

Field fieldFor(const std::string& name) {
  namespace columns = io::standard_columns;
  if (name == columns::kBend) return {Field::kBend, 0};
  if (name == columns::kSteer) return {Field::kSteer, 0};
  for (const auto& [prefix, kind] :
       {std::pair{columns::kPressurePrefix, Field::kPressure}, std::pair{columns::kCommandPrefix, Field::kCommand}}) {
    const std::string p = prefix;
    if (name.rfind(p, 0) == 0) {
      const int i = std::atoi(name.c_str() + p.size());
      if (i >= 1 && i <= columns::kChambers) return {kind, i - 1};
    }
  }
  throw std::invalid_argument("plsa predict: model column '" + name +
                              "' is not in actuator-state messages (p_1..3, cmd_1..3, bend_deg, steer_deg)");
}

double read(const plsa_lcm::actuator_state_t& m, const Field& f) {
  switch (f.kind) {
    case Field::kPressure:
      return f.index < m.n_chambers ? m.pressure_bar[static_cast<std::size_t>(f.index)] : NAN;
    case Field::kCommand:
      return f.index < m.n_chambers ? m.command_bar[static_cast<std::size_t>(f.index)] : NAN;
    case Field::kBend:
      return m.bend_deg;
    case Field::kSteer:
      return m.steer_deg;
  }
  return NAN;
}

class PredictorNode {
 public:
  // `longest`: the longest of o.horizons, which runPredictorNode has checked.
  PredictorNode(const DioPwlObfModel& model, const PredictorNodeOptions& o, int longest, const std::atomic<bool>& stop)
      : o_(o), stop_(stop), lcm_(o.url), predictor_(model, options(longest)) {
    if (!lcm_.good()) throw std::runtime_error("plsa predict: cannot open LCM");
    for (const auto& n : model.inputs) in_.push_back(fieldFor(n));
    for (const auto& n : model.outputs) out_.push_back(fieldFor(n));
    names_ = model.outputs;
    sample_time_ = model.sample_time_s;
    max_h_ = predictor_.maxHorizon();
    traj_.resize(max_h_, model.outputCount());
    plan_.resize(0, model.inputCount());
    u_.resize(model.inputCount());
    y_.resize(model.outputCount());
    latency_.assign(4096, 0.0);
    sorted_.assign(4096, 0.0);
    msgs_.resize(o.horizons.size());
    for (std::size_t i = 0; i < o.horizons.size(); ++i) {
      auto& p = msgs_[i];
      p.sample_time_s = model.sample_time_s;
      p.horizon = o.horizons[i];
      p.n_outputs = model.outputCount();
      p.output_names = names_;
      p.trajectory.assign(static_cast<std::size_t>(p.horizon),
                          std::vector<double>(static_cast<std::size_t>(p.n_outputs)));
    }
    lcm_.subscribe(o.state_channel, &PredictorNode::onState, this);
  }

  PredictorNodeStats run() {
    stats_.realtime = enterRealTime(o_.realtime_priority).words;
    std::fprintf(stderr, "plsa predict: real time: %s\n", stats_.realtime.c_str());
    auto next_status = Clock::now() + std::chrono::seconds(1);
    const int fd = lcm_.getFileno();
    while (!stop_.load()) {
      pollfd pfd{fd, POLLIN, 0};
      if (::poll(&pfd, 1, 100) > 0) lcm_.handle();
      if (Clock::now() >= next_status) {
        publishStatus();
        next_status += std::chrono::seconds(1);
      }
    }
    publishStatus();
    return stats_;
  }

 private:
  static PredictorOptions options(int longest) {
    PredictorOptions p;
    p.max_horizon = longest;
    return p;
  }

  // Raw bytes: decoded by the checked decoder, never by lcm-gen's alone.
  void onState(const ::lcm::ReceiveBuffer* rbuf, const std::string&) {
    ++stats_.states;
    const auto t0 = Clock::now();
    if (have_arrival_) {
      const double interval = std::chrono::duration<double>(t0 - last_arrival_).count();
      jitter_[static_cast<std::size_t>(jitter_n_++ % jitter_.size())] = std::abs(interval - sample_time_) * 1e6;
    }
    last_arrival_ = t0;
    have_arrival_ = true;
    const std::string why = decodeMessage(rbuf->data, rbuf->data_size, state_);
    if (!why.empty()) {
      ++stats_.rejected;
      ++malformed_;
      last_problem_ = why;
      return;
    }
    const plsa_lcm::actuator_state_t* m = &state_;
    for (std::size_t j = 0; j < in_.size(); ++j) u_(static_cast<Eigen::Index>(j)) = read(*m, in_[j]);
    for (std::size_t o = 0; o < out_.size(); ++o) y_(static_cast<Eigen::Index>(o)) = read(*m, out_[o]);
    const PredictorStatus st = predictor_.update(static_cast<double>(m->utime) * 1e-6, u_, y_);
    if (st == PredictorStatus::kTimeGap || st == PredictorStatus::kClockStepBack) {
      ++restarts_;
      last_problem_ = toString(st);
    }
    if (!accepted(st)) {
      ++stats_.rejected;
      ++rejected_by_[-static_cast<int>(st) % kReasons];
      last_problem_ = toString(st);
      return;
    }
    if (predictor_.predict(max_h_, plan_, traj_) != PredictorStatus::kOk) return;
    latency_[static_cast<std::size_t>(lat_n_++ % latency_.size())] =
        std::chrono::duration<double, std::micro>(Clock::now() - t0).count();
    for (auto& p : msgs_) {
      p.utime = m->utime;
      p.state_seq = m->seq;
      for (int h = 0; h < p.horizon; ++h)
        for (int o = 0; o < p.n_outputs; ++o)
          p.trajectory[static_cast<std::size_t>(h)][static_cast<std::size_t>(o)] = traj_(h, o);
      lcm_.publish(o_.prediction_channel, &p);
      ++stats_.predictions;
    }
    if (std::chrono::duration<double>(Clock::now() - t0).count() > sample_time_) ++stats_.deadline_misses;
  }

  void publishStatus() {
    const std::size_t n = std::min<std::size_t>(static_cast<std::size_t>(lat_n_), latency_.size());
    std::copy(latency_.begin(), latency_.begin() + static_cast<long>(n), sorted_.begin());
    std::sort(sorted_.begin(), sorted_.begin() + static_cast<long>(n));
    auto q = [&](double f) {
      return n ? sorted_[std::min(n - 1, static_cast<std::size_t>(f * static_cast<double>(n)))] : 0.0;
    };
    plsa_lcm::status_t s;
    s.utime = epochMicroseconds();
    s.source = "plsa predict";
    // Rates over the time since the last status: what a monitor alarms on.
    const auto now = Clock::now();
    const double dt = std::max(1e-3, std::chrono::duration<double>(now - last_status_).count());
    const double states_per_s = static_cast<double>(stats_.states - states_at_status_) / dt;
    const double rejected_per_s = static_cast<double>(stats_.rejected - rejected_at_status_) / dt;
    last_status_ = now;
    states_at_status_ = stats_.states;
    rejected_at_status_ = stats_.rejected;
    s.state = rejected_per_s > 0 ? plsa_lcm::status_t::FAULT : plsa_lcm::status_t::OK;
    s.message = last_problem_.empty() ? "running"
                : rejected_per_s > 0  ? "rejecting samples; last: " + last_problem_
                                      : "running; last rejected or restarted: " + last_problem_;
    const std::size_t jn = std::min<std::size_t>(static_cast<std::size_t>(jitter_n_), jitter_.size());
    std::copy(jitter_.begin(), jitter_.begin() + static_cast<long>(jn), sorted_.begin());
    std::sort(sorted_.begin(), sorted_.begin() + static_cast<long>(jn));
    const double jitter_p99 =
        jn ? sorted_[std::min(jn - 1, static_cast<std::size_t>(0.99 * static_cast<double>(jn)))] : 0.0;
    s.names = {"states",
               "predictions",
               "rejected",
               "latency_p50_us",
               "latency_p99_us",
               "latency_max_us",
               "states_per_s",
               "rejected_per_s",
               "rejected_malformed",
               "rejected_not_finite",
               "rejected_out_of_range",
               "rejected_time",
               "restarts",
               "deadline_misses",
               "arrival_jitter_p99_us",
               "realtime_fifo"};
    s.values = {static_cast<double>(stats_.states),
                static_cast<double>(stats_.predictions),
                static_cast<double>(stats_.rejected),
                q(0.5),
                q(0.99),
                n ? sorted_[n - 1] : 0.0,
                states_per_s,
                rejected_per_s,
                static_cast<double>(malformed_),
                static_cast<double>(rejected_by_[-static_cast<int>(PredictorStatus::kNotFinite)]),
                static_cast<double>(rejected_by_[-static_cast<int>(PredictorStatus::kInputOutOfRange)]),
                static_cast<double>(rejected_by_[-static_cast<int>(PredictorStatus::kTimeNotIncreasing)]),
                static_cast<double>(restarts_),
                static_cast<double>(stats_.deadline_misses),
                jitter_p99,
                stats_.realtime.rfind("SCHED_FIFO priority", 0) == 0 ? 1.0 : 0.0};
    s.n_values = static_cast<int32_t>(s.names.size());
    lcm_.publish(o_.status_channel, &s);
  }

  PredictorNodeOptions o_;
  const std::atomic<bool>& stop_;
  ::lcm::LCM lcm_;
  Predictor<> predictor_;
  std::vector<Field> in_, out_;
  std::vector<std::string> names_;
  int max_h_ = 1;
  Eigen::MatrixXd traj_, plan_;
  Eigen::VectorXd u_, y_;
  std::vector<double> latency_, sorted_;
  std::int64_t lat_n_ = 0;
  std::vector<plsa_lcm::prediction_t> msgs_;
  std::string last_problem_;
  PredictorNodeStats stats_;
  plsa_lcm::actuator_state_t state_;
  static constexpr int kReasons = 10;
  std::array<std::int64_t, kReasons> rejected_by_{};  // by -PredictorStatus
  std::int64_t malformed_ = 0, restarts_ = 0;
  Clock::time_point last_status_ = Clock::now();
  Clock::time_point last_arrival_{};
  bool have_arrival_ = false;
  double sample_time_ = 0.0125;
  std::vector<double> jitter_ = std::vector<double>(4096, 0.0);
  std::int64_t jitter_n_ = 0;
  std::int64_t states_at_status_ = 0, rejected_at_status_ = 0;
};

}  // namespace

PredictorNodeStats runPredictorNode(const DioPwlObfModel& model, const PredictorNodeOptions& options,
                                    const std::atomic<bool>& stop) {
  // Before LCM is opened: a negative horizon would size a trajectory from it,
  // a huge one allocate and publish megabytes every tick.
  requireHorizons(options.horizons, "plsa predict");
  const int longest = *std::max_element(options.horizons.begin(), options.horizons.end());
  // A sample time measured from a log is 1/80 s give or take rounding; the relative
  // slack keeps 60 s at 80 Hz at 4800 samples.
  const double steps = kMaxPublishedHorizonS / model.sample_time_s * (1 + 1e-9);
  if (longest > steps) {
    const int cap = static_cast<int>(std::floor(steps));
    char msg[200];
    std::snprintf(msg, sizeof msg,
                  "plsa predict: horizon %d (%.4g s) is beyond the %g s published at most: %d samples at %g s", longest,
                  longest * model.sample_time_s, kMaxPublishedHorizonS, cap, model.sample_time_s);
    throw std::invalid_argument(msg);
  }
  PredictorNode node(model, options, longest, stop);
  return node.run();
}

}  // namespace plsa::lcm
