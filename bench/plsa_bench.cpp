// plsa-bench: latency of the real-time predictor on the models users run.
//   plsa-bench --latency [--calls N] [--only NAME] [--json FILE]
//       per call p50/p99.9 of update and predict on models identified by plsa
//       itself (the demo's and its structural variants, 1-3 chambers, input and
//       output side, with and without lag, slow pole, tip frame), against a
//       straightforward dynamic implementation of the same model; the
//       sensitivity of an 80-step prediction to its plan; after a
//       125 s hold; 100 segments of the demo's model per tick; and the
//       synthetic output-side models of earlier benchmarks. --only NAME
//       measures just the model of that name (e.g. "demo"), for profiling.
//   plsa-bench --loop SECONDS [--segments N] [--json FILE]
//       an 80 Hz loop on absolute deadlines (clock_nanosleep) with SCHED_FIFO
//       and locked, pre-faulted memory where permitted: wake-up jitter, work
//       per tick and deadline misses, N segments of the demo's model.
//   plsa-bench                        Google Benchmark runs of single calls
#include <benchmark/benchmark.h>
#include <time.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <map>
#include <memory>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include "identified_models.hpp"
#include "plsa/core/text_file.hpp"
#include "plsa/predict/predictor.hpp"
#include "plsa/predict/realtime_thread.hpp"
#include "plsa/sim/actuator.hpp"
#include "plsa/sim/sim_config.hpp"
#include "straightforward_predictor.hpp"

namespace {

using Clock = std::chrono::steady_clock;
using plsa::bench::BenchModel;

// The predictor's calls come kCallsPerState to a state (the schedule moves
// every fourth call, FedPredictor::moveOn).
constexpr long kCallsPerState = 4;

struct Stats {
  double p50 = 0, p99 = 0, p999 = 0, max = 0;
  // Over the states, each state's fastest call (0 where calls do not share
  // states): the call's own work. An interrupt or the host's scheduling hits
  // one call of a state; a costly state is costly in each of its calls.
  double state_p50 = 0, state_p999 = 0;
};

double quantile(const std::vector<double>& sorted, double q) {
  return sorted[std::min(sorted.size() - 1, static_cast<std::size_t>(q * static_cast<double>(sorted.size())))];
}

/// ns in call order; with calls_per_state > 1, calls [k n, (k + 1) n) share a state.
Stats stats(std::vector<double>& ns, long calls_per_state = 1) {
  Stats s;
  if (calls_per_state > 1) {
    std::vector<double> fastest;
    const auto n = static_cast<std::size_t>(calls_per_state);
    for (std::size_t i = 0; i + n <= ns.size(); i += n)
      fastest.push_back(*std::min_element(ns.begin() + static_cast<std::ptrdiff_t>(i),
                                          ns.begin() + static_cast<std::ptrdiff_t>(i + n)));
    std::sort(fastest.begin(), fastest.end());
    s.state_p50 = quantile(fastest, 0.5);
    s.state_p999 = quantile(fastest, 0.999);
  }
  std::sort(ns.begin(), ns.end());
  s.p50 = quantile(ns, 0.5), s.p99 = quantile(ns, 0.99), s.p999 = quantile(ns, 0.999), s.max = ns.back();
  return s;
}

/// Times call(i) for i < calls, each on its own; prepare(i) runs before it,
/// untimed (the updates and plans that move the schedule between calls).
/// With calls_per_state, the calls that share a state are also taken
/// together (Stats::state_p50, state_p999).
template <class P, class F>
Stats timeCalls(long calls, P&& prepare, F&& call, long calls_per_state = 1) {
  std::vector<double> ns(static_cast<std::size_t>(calls));
  for (long i = 0; i < calls; ++i) {
    prepare(i);
    const auto t0 = Clock::now();
    call(i);
    ns[static_cast<std::size_t>(i)] = std::chrono::duration<double, std::nano>(Clock::now() - t0).count();
  }
  return stats(ns, calls_per_state);
}

template <class F>
Stats timeCalls(long calls, F&& call) {
  return timeCalls(
      calls, [](long) {}, call);
}

std::map<std::string, Stats> g_results;
std::map<std::string, double> g_figures;

void say(const std::string& line) {
  std::printf("%s\n", line.c_str());
  std::fflush(stdout);
}

void report(const std::string& name, const Stats& s) {
  g_results[name] = s;
  std::printf("  %-58s p50 %9.0f ns  p99.9 %9.0f ns  max %10.0f ns", name.c_str(), s.p50, s.p999, s.max);
  if (s.state_p50 > 0)
    std::printf("  (fastest of a state's %ld calls: p50 %.0f ns, p99.9 %.0f ns)", kCallsPerState, s.state_p50,
                s.state_p999);
  std::printf("\n");
  std::fflush(stdout);
}

void writeJson(const std::string& path) {
  if (path.empty()) return;
  std::ostringstream out;
  out << "{\n  \"latency_ns\": {";
  bool first = true;
  for (const auto& [k, s] : g_results) {
    out << (first ? "\n" : ",\n") << "    \"" << k << "\": {\"p50\": " << s.p50 << ", \"p99\": " << s.p99
        << ", \"p99_9\": " << s.p999 << ", \"max\": " << s.max;
    if (s.state_p50 > 0) out << ", \"state_p50\": " << s.state_p50 << ", \"state_p99_9\": " << s.state_p999;
    out << "}";
    first = false;
  }
  out << "\n  },\n  \"figures\": {";
  first = true;
  for (const auto& [k, v] : g_figures) {
    out << (first ? "\n" : ",\n") << "    \"" << k << "\": " << v;
    first = false;
  }
  out << "\n  }\n}\n";
  plsa::writeTextFile(path, out.str(), "benchmark results");
}

// The driving run: inputs and outputs of the simulator's joystick run, looped.
struct Drive {
  Eigen::MatrixXd u, y;
  double dt = 0.0125;
  Eigen::Index rows() const { return u.rows(); }
};

// Both implementations fed the same run must predict the same (planned input).
double disagreement(const plsa::DioPwlObfModel& m, const Drive& d) {
  plsa::Predictor<> fast(m);
  plsa::bench::StraightforwardPredictor slow(m);
  Eigen::MatrixXd out(80, m.outputCount());
  double worst = 0.0;
  for (Eigen::Index t = 0; t < 1600; ++t) {
    fast.update(static_cast<double>(t) * d.dt, d.u.row(t), d.y.row(t));
    slow.update(d.u.row(t).transpose(), d.y.row(t).transpose());
    if (t % 50 != 49) continue;
    const Eigen::MatrixXd plan = d.u.middleRows(t + 1, 79);
    fast.predict(80, plan, out);
    worst = std::max(worst, (out - slow.predict(80, plan)).cwiseAbs().maxCoeff());
    fast.predict(80, Eigen::MatrixXd(0, m.inputCount()), out);
    worst = std::max(worst, (out - slow.predict(80, Eigen::MatrixXd(0, m.inputCount()))).cwiseAbs().maxCoeff());
  }
  return worst;
}

// One predictor fed the driving run, looped, sample by sample.
struct FedPredictor {
  FedPredictor(const plsa::DioPwlObfModel& m, const Drive& drive, const plsa::PredictorOptions& po)
      : p(m, po),
        d(drive),
        T(drive.rows() - 80),
        out(po.max_horizon, m.outputCount()),
        plan(79, m.inputCount()),
        hold(0, m.inputCount()) {}
  /// The next sample; returns its row.
  Eigen::Index feed() {
    const Eigen::Index t = tick % T;
    p.update(static_cast<double>(tick++) * d.dt, d.u.row(t), d.y.row(t));
    return t;
  }
  // Every kCallsPerState-th call a new sample (and plan) first, untimed: the schedule moves between calls.
  void moveOn(long i) {
    if (i % kCallsPerState == 0) feed();
  }
  void moveOnWithPlan(long i) {
    if (i % kCallsPerState == 0) plan = d.u.middleRows(feed() + 1, 79);
  }

  plsa::Predictor<> p;
  const Drive& d;
  Eigen::Index T;
  long tick = 0;
  Eigen::MatrixXd out, plan;
  const Eigen::MatrixXd hold;
};

// Both fills on the same states and plans, call by call, taking turns to go
// first (the cost depends on which channels the plan moves).
void measureSensitivity(const std::string& tag, FedPredictor& f, long predicts) {
  const int n_y = f.p.outputCount(), n_u = f.p.inputCount();
  Eigen::MatrixXd jacobian(80 * n_y, 79 * n_u);
  Eigen::MatrixXd moving_rows = Eigen::MatrixXd::Zero(jacobian.rows(), jacobian.cols());
  std::vector<double> whole_ns, moving_ns;
  for (long i = 0; i < predicts / 4; ++i) {
    f.moveOnWithPlan(i);
    const auto whole = std::tuple{plsa::JacobianFill::kWhole, &jacobian, &whole_ns};
    const auto moving = std::tuple{plsa::JacobianFill::kMovingRows, &moving_rows, &moving_ns};
    for (auto [fill, target, ns] : {(i & 1) ? moving : whole, (i & 1) ? whole : moving}) {
      const auto t0 = Clock::now();
      f.p.sensitivity(80, f.plan, *target, fill);
      benchmark::DoNotOptimize(target->data());
      ns->push_back(std::chrono::duration<double, std::nano>(Clock::now() - t0).count());
    }
  }
  report(tag + ": sensitivity 80 (jacobian to the plan)", stats(whole_ns, kCallsPerState));
  report(tag + ": sensitivity 80, moving rows only", stats(moving_ns, kCallsPerState));
  // For scale: the memory's own cost of writing every entry of that Jacobian
  // once (for the demo 160 x 237 doubles, 303 KB: more than L1 holds), timed alike.
  g_figures[tag + ": jacobian rows"] = static_cast<double>(jacobian.rows());
  g_figures[tag + ": jacobian columns"] = static_cast<double>(jacobian.cols());
  report(tag + ": writing that jacobian's entries once (setZero)", timeCalls(predicts / 4, [&](long) {
           jacobian.setZero();
           benchmark::DoNotOptimize(jacobian.data());
           benchmark::ClobberMemory();
         }));
}

// A robot at rest for 125 s: the held input's schedule settles, its modes decay.
void measureAfterHold(const std::string& tag, FedPredictor& f, long predicts) {
  const Eigen::VectorXd rest_u = f.d.u.row(f.tick % f.T).transpose(), rest_y = f.d.y.row(f.tick % f.T).transpose();
  for (int k = 0; k < 10000; ++k) f.p.update(static_cast<double>(f.tick++) * f.d.dt, rest_u, rest_y);
  g_figures[tag + ": subnormal states after a 125 s hold"] = f.p.subnormalStates();
  for (int h : {80, 400}) {
    const Stats s = timeCalls(
        predicts / (h / 80),
        [&](long i) {
          if (i % kCallsPerState == 0) f.p.update(static_cast<double>(f.tick++) * f.d.dt, rest_u, rest_y);
        },
        [&](long) {
          f.p.predict(h, f.hold, f.out);
          benchmark::DoNotOptimize(f.out.data());
        },
        kCallsPerState);
    report(tag + ": predict " + std::to_string(h) + ", after a 125 s hold", s);
    g_figures[tag + ": predict " + std::to_string(h) + " after a hold, p99.9/p50"] = s.p999 / s.p50;
  }
}

// The straightforward implementation of the same model, same run, and the
// speed-up over it.
void measureStraightforward(const std::string& tag, const plsa::DioPwlObfModel& m, const Drive& d, long calls) {
  const Eigen::Index T = d.rows() - 80;
  plsa::bench::StraightforwardPredictor slow(m);
  for (Eigen::Index t = 0; t < 2000; ++t) slow.update(d.u.row(t % T).transpose(), d.y.row(t % T).transpose());
  const long slow_calls = std::max(200L, calls / 100);
  long slow_tick = 2000;
  const Stats slow_planned = timeCalls(slow_calls, [&](long) {
    const Eigen::Index t = slow_tick++ % T;
    slow.update(d.u.row(t).transpose(), d.y.row(t).transpose());
    const Eigen::MatrixXd traj = slow.predict(80, d.u.middleRows(t + 1, 79));
    benchmark::DoNotOptimize(traj.data());
  });
  report(tag + ": straightforward update + predict 80, planned", slow_planned);
  const Stats slow_held = timeCalls(slow_calls, [&](long) {
    const Eigen::Index t = slow_tick++ % T;
    slow.update(d.u.row(t).transpose(), d.y.row(t).transpose());
    const Eigen::MatrixXd traj = slow.predict(80, Eigen::MatrixXd(0, m.inputCount()));
    benchmark::DoNotOptimize(traj.data());
  });
  report(tag + ": straightforward update + predict 80, held", slow_held);
  const double upd = g_results[tag + ": update"].p50;
  g_figures[tag + ": speed-up over straightforward, planned (p50)"] =
      slow_planned.p50 / (upd + g_results[tag + ": predict 80, planned input"].p50);
  g_figures[tag + ": speed-up over straightforward, held (p50)"] =
      slow_held.p50 / (upd + g_results[tag + ": predict 80, input held, moving"].p50);
  std::printf(
      "  speed-up over the straightforward implementation (update + predict 80, p50): planned %.0fx, held %.0fx\n",
      g_figures[tag + ": speed-up over straightforward, planned (p50)"],
      g_figures[tag + ": speed-up over straightforward, held (p50)"]);
}

void measureModel(const BenchModel& bm, const Drive& d, long calls) {
  const plsa::DioPwlObfModel& m = bm.model;
  const std::string tag = bm.name;
  std::printf("%s: %s\n", tag.c_str(), bm.structure.c_str());
  const double agree = disagreement(m, d);
  g_figures[tag + ": largest difference to the straightforward implementation"] = agree;
  std::printf("  predictions agree with the straightforward implementation to %.2g (output units)\n", agree);
  plsa::PredictorOptions po;
  po.max_horizon = 400;
  FedPredictor f(m, d, po);
  std::printf("  form: %s\n", f.p.heldPathIsModal() ? "modal" : "state-space banks");
  for (int k = 0; k < 2000; ++k) f.feed();
  report(tag + ": update", timeCalls(calls, [&](long) { f.feed(); }));
  const long predicts = std::max(1000L, calls / 2);
  // predict(h) over `count` calls, the input held or planned.
  auto timePredict = [&](long count, int h, bool planned) {
    return timeCalls(
        count, [&](long i) { planned ? f.moveOnWithPlan(i) : f.moveOn(i); },
        [&](long) {
          f.p.predict(h, planned ? f.plan : f.hold, f.out);
          benchmark::DoNotOptimize(f.out.data());
        },
        kCallsPerState);
  };
  report(tag + ": predict 80, input held, moving", timePredict(predicts, 80, false));
  report(tag + ": predict 80, planned input", timePredict(predicts, 80, true));
  measureSensitivity(tag, f, predicts);
  report(tag + ": predict 400, input held, moving", timePredict(predicts / 4, 400, false));
  measureAfterHold(tag, f, predicts);
  measureStraightforward(tag, m, d, calls);
}

// N segments, each its own compiled copy of the demo's model: update and
// predict 80 (input held) for all of them per tick.
void measureSegments(const plsa::DioPwlObfModel& m, const Drive& d, int n, long ticks) {
  std::vector<std::unique_ptr<plsa::Predictor<>>> segs;
  for (int s = 0; s < n; ++s) segs.push_back(std::make_unique<plsa::Predictor<>>(m));
  Eigen::MatrixXd out(80, m.outputCount());
  const Eigen::MatrixXd hold(0, m.inputCount());
  const Eigen::Index T = d.rows();
  long tick = 0;
  const Stats st = timeCalls(ticks, [&](long) {
    const Eigen::Index t = tick % T;
    for (auto& s : segs) {
      s->update(static_cast<double>(tick) * d.dt, d.u.row(t), d.y.row(t));
      s->predict(80, hold, out);
    }
    ++tick;
  });
  const std::string name = std::to_string(n) + " segments of the demo's model: update + predict 80 per tick";
  report(name, st);
  g_figures[std::to_string(n) + " segments: p99.9 share of the 12.5 ms period"] = st.p999 / 12.5e6;
  std::printf("  p99.9 is %.1f%% of the 12.5 ms period\n", 100.0 * st.p999 / 12.5e6);
}

// Synthetic output-side models as in earlier benchmarks (5 poles per pair
// spread like FKcM centres, 4x4 interpolated grid), for continuity.
plsa::DioPwlObfModel syntheticModel(int chambers, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> jitter(-0.005, 0.005), coef(-1.0, 1.0);
  plsa::DioPwlObfModel m;
  for (int j = 0; j < chambers; ++j) m.inputs.push_back("p_" + std::to_string(j + 1));
  m.outputs = {"y_1", "y_2"};
  m.input_min = 0.0;
  m.input_max = 0.4;
  m.poles.assign(2, {});
  for (int o = 0; o < 2; ++o)
    for (int j = 0; j < chambers; ++j) {
      std::vector<double> p;
      for (int i = 0; i < 5; ++i) p.push_back(0.84 + 0.11 * i / 4.0 + jitter(rng));
      m.poles[static_cast<std::size_t>(o)].push_back(plsa::PoleSet::real(p));
    }
  m.shaping.play.assign(static_cast<std::size_t>(chambers), {0.01});
  std::vector<int> inputs;
  std::vector<std::vector<double>> levels;
  for (int s = 0; s < std::min(chambers, 2); ++s) {
    inputs.push_back(s);
    levels.push_back({0.2, 0.25, 0.3, 0.35});
  }
  m.partition = plsa::PwlPartition::interpolated(inputs, levels);
  m.coefficients.assign(static_cast<std::size_t>(m.partition.regionCount()), {});
  for (auto& region : m.coefficients)
    for (int o = 0; o < 2; ++o) {
      Eigen::VectorXd c(m.regressorSize(o));
      for (Eigen::Index i = 0; i < c.size(); ++i) c(i) = coef(rng);
      region.push_back(c);
    }
  m.region_fits.assign(m.coefficients.size(), plsa::RegionFit{});
  m.validate();
  return m;
}

Drive syntheticDrive(int chambers) {
  Drive d;
  d.u.resize(8000, chambers);
  d.y.resize(8000, 2);
  for (Eigen::Index k = 0; k < d.u.rows(); ++k) {
    for (int j = 0; j < chambers; ++j)
      d.u(k, j) = 0.275 + 0.09 * std::sin(0.003 * static_cast<double>(k) * (j + 1) + j);
    d.y.row(k) << 10.0 + std::sin(0.01 * static_cast<double>(k)), 20.0;
  }
  return d;
}

// The machine's own tail: a fixed amount of arithmetic, the same in every
// call, timed like the predictor's calls. Its p99.9 / p50 is what interrupts
// and the host's scheduling add to a call of that length, whatever it does.
double fixedWork(long steps) {
  double x = 1.0;
  for (long k = 0; k < steps; ++k) {
    x = x * 0.999999 + 1e-6;
    benchmark::DoNotOptimize(x);  // every step done, none folded away
  }
  return x;
}

void measureMachineTail(long calls) {
  const auto t0 = Clock::now();
  benchmark::DoNotOptimize(fixedWork(100000));
  const double ns_per_step = std::chrono::duration<double, std::nano>(Clock::now() - t0).count() / 100000.0;
  for (double target_ns : {1000.0, 3000.0, 10000.0}) {
    const long steps = std::max(1L, static_cast<long>(target_ns / ns_per_step));
    const Stats s = timeCalls(calls / 4, [&](long) { benchmark::DoNotOptimize(fixedWork(steps)); });
    const std::string name = "fixed work of about " + std::to_string(static_cast<int>(target_ns / 1000)) + " us";
    report(name, s);
    g_figures[name + ": p99.9/p50"] = s.p999 / s.p50;
  }
}

void runLatency(long calls, const std::string& only) {
  std::printf("plsa-bench latency: %ld calls per line (predict: %ld), p50 and p99.9 of each call\n", calls,
              std::max(1000L, calls / 2));
  const std::vector<BenchModel> models = plsa::bench::identifiedModels(1, say);
  const plsa::io::Log run = plsa::bench::drivingRun(1);
  // As a controller's thread would run (after identification, whose threads must not inherit it).
  std::printf("real time: %s\n", plsa::enterRealTime(50).words.c_str());
  measureMachineTail(calls);
  for (const BenchModel& bm : models) {
    if (!only.empty() && bm.name != only) continue;
    Drive d;
    d.u = run.columnsOf(bm.model.inputs);
    d.y = run.columnsOf(bm.model.outputs);
    measureModel(bm, d, calls);
  }
  if (!only.empty()) return;
  Drive d;
  d.u = run.columnsOf(models.front().model.inputs);
  d.y = run.columnsOf(models.front().model.outputs);
  // At least 10000 ticks: the p99.9 is then the tenth-longest tick, not the second.
  for (int n : {1, 10, 100}) measureSegments(models.front().model, d, n, std::max(10000L, calls / (10L * n)));
  for (int chambers : {2, 3}) {
    const plsa::DioPwlObfModel m = syntheticModel(chambers, 7);
    measureModel({"synthetic, " + std::to_string(chambers) + " chambers", plsa::bench::describe(m), m},
                 syntheticDrive(chambers), calls);
  }
}

void runLoop(double seconds, int segments) {
  const std::vector<BenchModel> models = plsa::bench::identifiedModels(1, say);
  const plsa::io::Log run = plsa::bench::drivingRun(1);
  const plsa::DioPwlObfModel& m = models.front().model;
  std::vector<std::unique_ptr<plsa::Predictor<>>> segs;
  for (int s = 0; s < segments; ++s) segs.push_back(std::make_unique<plsa::Predictor<>>(m));
  const Eigen::MatrixXd u = run.columnsOf(m.inputs), y = run.columnsOf(m.outputs);
  Eigen::MatrixXd out(80, m.outputCount());
  const Eigen::MatrixXd hold(0, m.inputCount());
  const long period_ns = 12'500'000;
  const long ticks = static_cast<long>(seconds * 80.0);
  std::vector<double> jitter, work;
  jitter.reserve(static_cast<std::size_t>(ticks));
  work.reserve(static_cast<std::size_t>(ticks));
  const std::string setup = plsa::enterRealTime(50).words;
  long misses = 0;
  timespec next{};
  clock_gettime(CLOCK_MONOTONIC, &next);
  for (long k = 0; k < ticks; ++k) {
    next.tv_nsec += period_ns;
    while (next.tv_nsec >= 1'000'000'000) {
      next.tv_nsec -= 1'000'000'000;
      ++next.tv_sec;
    }
    clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, nullptr);
    timespec woke{};
    clock_gettime(CLOCK_MONOTONIC, &woke);
    jitter.push_back(static_cast<double>((woke.tv_sec - next.tv_sec) * 1'000'000'000L + (woke.tv_nsec - next.tv_nsec)));
    const Eigen::Index t = k % u.rows();
    for (auto& s : segs) {
      s->update(static_cast<double>(k) * 0.0125, u.row(t), y.row(t));
      s->predict(80, hold, out);
    }
    timespec done{};
    clock_gettime(CLOCK_MONOTONIC, &done);
    const double elapsed =
        static_cast<double>((done.tv_sec - next.tv_sec) * 1'000'000'000L + (done.tv_nsec - next.tv_nsec));
    work.push_back(elapsed - jitter.back());
    if (elapsed > static_cast<double>(period_ns)) ++misses;
  }
  std::printf("plsa-bench loop: %ld ticks at 80 Hz, %d segments of the demo's model (update + predict 80 each); %s\n",
              ticks, segments, setup.c_str());
  report("loop wake-up jitter", stats(jitter));
  report("loop work per tick", stats(work));
  g_figures["loop deadline misses"] = static_cast<double>(misses);
  g_figures["loop ticks"] = static_cast<double>(ticks);
  g_figures["loop segments"] = static_cast<double>(segments);
  std::printf("  deadline misses: %ld of %ld\n", misses, ticks);
}

// The demo's model updated on one sample after another, the sensor's yaw
// tracked past its window (the default) or not (yaw_tracking_s = 0).
void demoUpdates(benchmark::State& state, double yaw_tracking_s) {
  static const std::vector<BenchModel> models = plsa::bench::identifiedModels(1, [](const std::string&) {});
  plsa::PredictorOptions o;
  o.yaw_tracking_s = yaw_tracking_s;
  plsa::Predictor<> p(models.front().model, o);
  const Eigen::Vector3d u(0.25, 0.3, 0.0);
  const Eigen::Vector2d y(10.0, 40.0);
  long k = 0;
  for (auto _ : state) {
    p.update(static_cast<double>(k++) * 0.0125, u, y);
  }
}
void BM_DemoUpdate(benchmark::State& state) { demoUpdates(state, plsa::PredictorOptions{}.yaw_tracking_s); }
BENCHMARK(BM_DemoUpdate)->Name("Predictor<>::update (the demo's model)");
void BM_DemoUpdateUntracked(benchmark::State& state) { demoUpdates(state, 0.0); }
BENCHMARK(BM_DemoUpdateUntracked)->Name("Predictor<>::update (the demo's model, yaw not tracked)");

// One 120 s replay (9600 samples at 80 Hz, random pressures held 1.25 s
// each) of the simulated actuator at the 4 ms internal step a diagnosis's
// calibrations take: what each of its simulator runs costs. Every effect
// off, then with the diagnosis's flexible (power) pneumatic lag or
// stiffening switched on (the lag as calibrated on bench/diagnose_cost.py's
// lag case).
plsa::sim::SimConfig everyEffectOff() {
  plsa::sim::SimConfig c;
  c.sensor.noise_deg = 0.0;
  for (const std::string& effect : plsa::sim::effectNames()) c.setEffectEnabled(effect, false);
  c.internal_step_s = 0.004;
  return c;
}
void actuatorReplay(benchmark::State& state, const plsa::sim::SimConfig& c) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> pressure(0.0, 0.36);
  std::vector<std::array<double, 3>> commands(9600);
  for (std::size_t k = 0; k < commands.size(); k += 100) {
    const std::array<double, 3> held = {pressure(rng), pressure(rng), pressure(rng)};
    std::fill(commands.begin() + static_cast<long>(k), commands.begin() + static_cast<long>(k + 100), held);
  }
  int substeps = 1;
  for (auto _ : state) {
    plsa::sim::Actuator a(c, 1);
    substeps = a.substepsPerSample();
    for (const auto& u : commands) benchmark::DoNotOptimize(a.stepReading(u));
  }
  // Seconds per internal step (Google Benchmark prints it with its SI prefix: 77n is 77 ns).
  state.counters["per_internal_step"] =
      benchmark::Counter(static_cast<double>(commands.size()) * substeps,
                         benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}
void BM_ReplayEffectsOff(benchmark::State& state) { actuatorReplay(state, everyEffectOff()); }
BENCHMARK(BM_ReplayEffectsOff)
    ->Name("sim::Actuator, 120 s replay at 4 ms (every effect off)")
    ->Unit(benchmark::kMillisecond);
// everyEffectOff() with one effect on in its power law at `values` (by parameter name).
plsa::sim::SimConfig withPowerLaw(const std::string& effect, const std::map<std::string, double>& values) {
  plsa::sim::SimConfig c = everyEffectOff();
  c.setEffectEnabled(effect, true);
  c.formulationOf(effect) = "power";
  std::size_t set = 0;
  for (const plsa::sim::ParamRef& p : c.parameters(effect))
    if (values.count(p.name)) *p.value = values.at(p.name), ++set;
  if (set != values.size()) throw std::invalid_argument("plsa-bench: a parameter of " + effect + " misnamed");
  return c;
}
plsa::sim::SimConfig calibratedPowerLag() {
  return withPowerLaw("pneumatic_lag", {{"fill_time_constant_s", 0.035},
                                        {"vent_time_constant_s", 0.042},
                                        {"delay_s", 0.030},
                                        {"exponent", 0.89},
                                        {"pressure_per_bar", -1.97},
                                        {"line_time_constant_s", 0.018}});
}
plsa::sim::SimConfig powerStiffening() {
  return withPowerLaw("stiffening", {{"per_bar", 10.0}, {"exponent", 1.3}, {"static_share", 0.4}});
}
void BM_ReplayPowerLag(benchmark::State& state) { actuatorReplay(state, calibratedPowerLag()); }
BENCHMARK(BM_ReplayPowerLag)
    ->Name("sim::Actuator, 120 s replay at 4 ms (power pneumatic lag)")
    ->Unit(benchmark::kMillisecond);
void BM_ReplayPowerStiffening(benchmark::State& state) { actuatorReplay(state, powerStiffening()); }
BENCHMARK(BM_ReplayPowerStiffening)
    ->Name("sim::Actuator, 120 s replay at 4 ms (power stiffening)")
    ->Unit(benchmark::kMillisecond);
// The same three as the diagnosis calibrates them: the exponential
// integrator at one 12.5 ms step a sample (internal_step_s 0.01 at 80 Hz).
plsa::sim::SimConfig exponentialOneStepASample(plsa::sim::SimConfig c) {
  c.integrator = "exponential";
  c.internal_step_s = 0.01;
  return c;
}
void BM_ReplayEffectsOffExponential(benchmark::State& state) {
  actuatorReplay(state, exponentialOneStepASample(everyEffectOff()));
}
BENCHMARK(BM_ReplayEffectsOffExponential)
    ->Name("sim::Actuator, 120 s replay at 12.5 ms, exponential (every effect off)")
    ->Unit(benchmark::kMillisecond);
void BM_ReplayPowerLagExponential(benchmark::State& state) {
  actuatorReplay(state, exponentialOneStepASample(calibratedPowerLag()));
}
BENCHMARK(BM_ReplayPowerLagExponential)
    ->Name("sim::Actuator, 120 s replay at 12.5 ms, exponential (power pneumatic lag)")
    ->Unit(benchmark::kMillisecond);
void BM_ReplayPowerStiffeningExponential(benchmark::State& state) {
  actuatorReplay(state, exponentialOneStepASample(powerStiffening()));
}
BENCHMARK(BM_ReplayPowerStiffeningExponential)
    ->Name("sim::Actuator, 120 s replay at 12.5 ms, exponential (power stiffening)")
    ->Unit(benchmark::kMillisecond);

}  // namespace

int main(int argc, char** argv) {
  std::string json, only;
  long calls = 200'000;
  double loop_s = 0;
  int segments = 100;
  bool latency = false;
  std::vector<char*> rest = {argv[0]};
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&](const char* what) -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "plsa-bench: %s needs a value\n", what);
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--latency")
      latency = true;
    else if (a == "--calls")
      calls = std::stol(value("--calls"));
    else if (a == "--loop")
      loop_s = std::stod(value("--loop"));
    else if (a == "--segments")
      segments = std::stoi(value("--segments"));
    else if (a == "--json")
      json = value("--json");
    else if (a == "--only")
      only = value("--only");
    else
      rest.push_back(argv[i]);
  }
  if (calls < 1000 || segments < 1 || loop_s < 0) {
    std::fprintf(stderr, "plsa-bench: --calls >= 1000, --segments >= 1, --loop >= 0\n");
    return 2;
  }
  if (latency || loop_s > 0) {
    if (latency) runLatency(calls, only);
    if (loop_s > 0) runLoop(loop_s, segments);
    writeJson(json);
    return 0;
  }
  int n = static_cast<int>(rest.size());
  benchmark::Initialize(&n, rest.data());
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
