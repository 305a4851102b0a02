// plsa-bench: latency of the real-time predictor.
//   plsa-bench                       Google Benchmark runs
//   plsa-bench --latency [--calls N] [--json FILE]
//                                    p50/p99/p99.9/max per call, fixed vs dynamic
//                                    vs a naive allocating baseline, 1-3 chambers,
//                                    and N independent 3-chamber segments
//   plsa-bench --loop SECONDS [--segments N] [--json FILE]
//                                    80 Hz loop on absolute deadlines (clock_nanosleep,
//                                    mlockall when permitted): wake-up jitter and misses
// Models are synthetic (random stable poles, random coefficients) with the
// structure of an identified one: interpolated 4x4 grid, 5 poles per pair.
#include <benchmark/benchmark.h>
#include <sys/mman.h>
#include <time.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "plsa/core/text_file.hpp"
#include "plsa/predict/predictor.hpp"

namespace {

using Clock = std::chrono::steady_clock;

// Poles spread like identified ones (FKcM centres about 0.02 apart in 0.84..0.95),
// or, with `clustered`, drawn uniformly from 0.85..0.99 where near-equal
// poles make the held path fall back from modal coordinates to the cascade.
plsa::DioPwlObfModel syntheticModel(int chambers, int outputs, int poles, std::uint64_t seed, bool clustered = false,
                                    bool input_side = false) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uniform_pole(0.85, 0.99), jitter(-0.005, 0.005), coef(-1.0, 1.0);
  plsa::DioPwlObfModel m;
  for (int j = 0; j < chambers; ++j) m.inputs.push_back("p_" + std::to_string(j + 1));
  for (int o = 0; o < outputs; ++o) m.outputs.push_back("y_" + std::to_string(o + 1));
  m.input_min = 0.0;
  m.input_max = 0.4;
  m.poles.assign(static_cast<std::size_t>(outputs), {});
  for (int o = 0; o < outputs; ++o)
    for (int j = 0; j < chambers; ++j) {
      std::vector<double> p;
      for (int i = 0; i < poles; ++i)
        p.push_back(clustered ? uniform_pole(rng) : 0.84 + 0.11 * i / std::max(1, poles - 1) + jitter(rng));
      m.poles[static_cast<std::size_t>(o)].push_back(plsa::PoleSet::real(p));
    }
  m.input_play.assign(static_cast<std::size_t>(chambers), {0.01});
  const int sched = std::min(chambers, 2);
  std::vector<int> inputs;
  std::vector<std::vector<double>> levels;
  for (int s = 0; s < sched; ++s) {
    inputs.push_back(s);
    levels.push_back({0.2, 0.25, 0.3, 0.35});
  }
  m.partition = plsa::PwlPartition::interpolated(inputs, levels);
  if (input_side) m.schedule_side = plsa::ScheduleSide::kInput;  // a bank per grid node: 16x the filters
  m.coefficients.assign(static_cast<std::size_t>(m.partition.regionCount()), {});
  for (auto& region : m.coefficients)
    for (int o = 0; o < outputs; ++o) {
      Eigen::VectorXd c(m.regressorSize(o));
      for (Eigen::Index i = 0; i < c.size(); ++i) c(i) = coef(rng);
      region.push_back(c);
    }
  m.region_fits.assign(m.coefficients.size(), plsa::RegionFit{});
  m.validate();
  return m;
}

// The straightforward implementation the fast path is measured against:
// one dense state-space of all banks, dynamic sizes, a fresh trajectory and
// temporaries on every call.
class NaivePredictor {
 public:
  explicit NaivePredictor(const plsa::DioPwlObfModel& m) : m_(m) {
    int n = 0;
    for (int o = 0; o < m.outputCount(); ++o) n += m.regressorSize(o);
    A_ = Eigen::MatrixXd::Zero(n, n);
    B_ = Eigen::MatrixXd::Zero(n, m.inputCount());
    int off = 0;
    for (int o = 0; o < m.outputCount(); ++o)
      for (int j = 0; j < m.inputCount(); ++j) {
        const plsa::ObfBank<> bank(m.poles[static_cast<std::size_t>(o)][static_cast<std::size_t>(j)]);
        A_.block(off, off, bank.size(), bank.size()) = bank.A();
        B_.block(off, j, bank.size(), 1) = bank.B();
        off += bank.size();
      }
    x_ = Eigen::VectorXd::Zero(n);
    u_ = Eigen::VectorXd::Zero(m.inputCount());
  }
  void update(const Eigen::VectorXd& u, const Eigen::VectorXd& y) {
    x_ = A_ * x_ + B_ * (u - u_);
    u_ = u;
    y_ = y;
  }
  std::vector<Eigen::VectorXd> predict(int horizon) const {
    std::vector<Eigen::VectorXd> traj;
    Eigen::VectorXd x = x_, y = y_;
    for (int h = 0; h < horizon; ++h) {
      plsa::ScheduleBlend b;
      m_.partition.blend(u_, plsa::DirectionState{}, b);
      Eigen::VectorXd dy = Eigen::VectorXd::Zero(m_.outputCount());
      int off = 0;
      for (int o = 0; o < m_.outputCount(); ++o) {
        const int n = m_.regressorSize(o);
        for (int k = 0; k < b.count; ++k)
          dy(o) += b.weight[static_cast<std::size_t>(k)] *
                   m_.coefficients[static_cast<std::size_t>(b.region[static_cast<std::size_t>(k)])][static_cast<std::size_t>(o)]
                       .dot(x.segment(off, n));
        off += n;
      }
      y = y + dy;
      traj.push_back(y);
      x = A_ * x;  // held input: no further input change
    }
    return traj;
  }

 private:
  plsa::DioPwlObfModel m_;
  Eigen::MatrixXd A_, B_;
  Eigen::VectorXd x_, u_, y_;
};

struct Stats {
  double p50 = 0, p99 = 0, p999 = 0, max = 0;
};

Stats stats(std::vector<double>& ns) {
  std::sort(ns.begin(), ns.end());
  auto at = [&](double q) { return ns[std::min(ns.size() - 1, static_cast<std::size_t>(q * static_cast<double>(ns.size())))]; };
  return {at(0.5), at(0.99), at(0.999), ns.back()};
}

// Drives inputs around the grid so scheduling switches regions.
Eigen::VectorXd inputAt(int k, int chambers) {
  Eigen::VectorXd u(chambers);
  for (int j = 0; j < chambers; ++j) u(j) = 0.275 + 0.09 * std::sin(0.003 * k * (j + 1) + j);
  return u;
}

template <class F>
Stats timeCalls(long calls, F&& f) {
  std::vector<double> ns(static_cast<std::size_t>(calls));
  for (long i = 0; i < calls; ++i) {
    const auto t0 = Clock::now();
    f(i);
    ns[static_cast<std::size_t>(i)] = std::chrono::duration<double, std::nano>(Clock::now() - t0).count();
  }
  return stats(ns);
}

std::map<std::string, Stats> g_results;
std::map<std::string, double> g_figures;

void report(const std::string& name, const Stats& s) {
  g_results[name] = s;
  std::printf("  %-46s p50 %9.0f ns  p99 %9.0f ns  p99.9 %9.0f ns  max %10.0f ns\n", name.c_str(), s.p50, s.p99, s.p999,
              s.max);
}

void writeJson(const std::string& path) {
  if (path.empty()) return;
  std::ostringstream out;
  out << "{\n  \"latency_ns\": {";
  bool first = true;
  for (const auto& [k, s] : g_results) {
    out << (first ? "\n" : ",\n") << "    \"" << k << "\": {\"p50\": " << s.p50 << ", \"p99\": " << s.p99
        << ", \"p99_9\": " << s.p999 << ", \"max\": " << s.max << "}";
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

template <int NP>
void latencyFor(const std::string& tag, int chambers, long calls, bool with_naive, bool clustered = false,
                bool input_side = false, int poles = 5, bool tip_frame = false) {
  plsa::DioPwlObfModel m = syntheticModel(chambers, 2, poles, 7, clustered, input_side);
  if (tip_frame) m.output_frame = plsa::OutputFrame::kTipCartesian;
  plsa::PredictorOptions po;
  po.max_horizon = 400;
  plsa::Predictor<NP> p(m, po);
  std::printf("  %s: held-input path %s\n", tag.c_str(), p.heldPathIsModal() ? "modal" : "cascade");
  Eigen::MatrixXd out(400, 2);
  const Eigen::MatrixXd plan(0, chambers);
  Eigen::Vector2d y(10.0, 20.0);
  for (int k = 0; k < 1000; ++k) p.update(k * 0.0125, inputAt(k, chambers), y);  // warm
  long tick = 1000;
  std::vector<Eigen::VectorXd> inputs;
  for (int k = 0; k < 4096; ++k) inputs.push_back(inputAt(k, chambers));
  report(tag + " update", timeCalls(calls, [&](long i) {
           p.update(static_cast<double>(tick++) * 0.0125, inputs[static_cast<std::size_t>(i & 4095)], y);
         }));
  for (int h : {1, 40, 80, 400}) {
    const long n = h == 400 ? calls / 10 : calls;
    report(tag + " predict " + std::to_string(h), timeCalls(n, [&](long i) {
             if ((i & 15) == 0) p.update(static_cast<double>(tick++) * 0.0125, inputs[static_cast<std::size_t>(i & 4095)], y);
             p.predict(h, plan, out);
             benchmark::DoNotOptimize(out.data());
           }));
  }
  {
    // A planned (changing) input: every step runs the cascade and the schedule.
    Eigen::MatrixXd planned(79, chambers);
    for (int h = 0; h < 79; ++h) planned.row(h) = inputAt(3 * h, chambers).transpose();
    report(tag + " predict 80, planned input", timeCalls(calls / 10, [&](long i) {
             if ((i & 15) == 0) p.update(static_cast<double>(tick++) * 0.0125, inputs[static_cast<std::size_t>(i & 4095)], y);
             p.predict(80, planned, out);
             benchmark::DoNotOptimize(out.data());
           }));
  }
  if (with_naive) {
    NaivePredictor naive(m);
    const Eigen::VectorXd yv = y;
    const Stats s = timeCalls(calls / 10, [&](long i) {
      if ((i & 15) == 0) naive.update(inputs[static_cast<std::size_t>(i & 4095)], yv);
      auto traj = naive.predict(80);
      benchmark::DoNotOptimize(traj.data());
    });
    report(tag + " predict 80, naive dynamic baseline", s);
    g_figures[tag + " predict80 speedup over naive (p50)"] = s.p50 / g_results[tag + " predict 80"].p50;
    std::printf("  %-46s %.1fx faster at p50\n", (tag + " predict 80 vs naive").c_str(),
                g_figures[tag + " predict80 speedup over naive (p50)"]);
  }
}

void runLatency(long calls) {
  std::printf("plsa-bench latency: %ld calls each (predict 400: %ld), synthetic models, 5 poles per pair unless named, 2 outputs\n",
              calls, calls / 10);
  latencyFor<5>("2 chambers, fixed", 2, calls, true);
  latencyFor<Eigen::Dynamic>("2 chambers, dynamic", 2, calls, false);
  latencyFor<5>("1 chamber, fixed", 1, calls, false);
  latencyFor<5>("3 chambers, fixed", 3, calls, false);
  latencyFor<5>("3 chambers, fixed, clustered poles", 3, calls, false, true);
  latencyFor<5>("3 chambers, fixed, input side", 3, calls / 4, false, false, true);
  // As identified now: input side with a slow pole (6 per bank), any-size predictor.
  latencyFor<Eigen::Dynamic>("3 chambers, dynamic, input side, 6 poles", 3, calls / 4, false, false, true, 6);
  // The demo's model: the same, on the tip direction's components (a conversion each way).
  latencyFor<Eigen::Dynamic>("3 chambers, dynamic, input side, 6 poles, tip frame", 3, calls / 4, false, false, true, 6,
                             true);
  // N independent 3-chamber segments, each updated and predicted 40 steps per tick.
  for (int n : {1, 10, 50, 100}) {
    std::vector<std::unique_ptr<plsa::Predictor<5>>> segs;
    for (int s = 0; s < n; ++s) segs.push_back(std::make_unique<plsa::Predictor<5>>(syntheticModel(3, 2, 5, 100 + s)));
    Eigen::MatrixXd out(40, 2);
    const Eigen::MatrixXd plan(0, 3);
    const Eigen::Vector2d y(1.0, 2.0);
    long tick = 0;
    const long ticks = std::max<long>(200, calls / (20L * n));
    const Stats st = timeCalls(ticks, [&](long) {
      const Eigen::VectorXd u = inputAt(static_cast<int>(tick), 3);
      for (auto& s : segs) {
        s->update(static_cast<double>(tick) * 0.0125, u, y);
        s->predict(40, plan, out);
      }
      ++tick;
    });
    report(std::to_string(n) + " segments: update + predict 40 per tick", st);
    g_figures[std::to_string(n) + " segments p99.9 share of 12.5 ms period"] = st.p999 / 12.5e6;
  }
}

void runLoop(double seconds, int segments) {
  const bool locked = mlockall(MCL_CURRENT | MCL_FUTURE) == 0;
  std::vector<std::unique_ptr<plsa::Predictor<5>>> segs;
  for (int s = 0; s < segments; ++s) segs.push_back(std::make_unique<plsa::Predictor<5>>(syntheticModel(3, 2, 5, 200 + s)));
  Eigen::MatrixXd out(80, 2);
  const Eigen::MatrixXd plan(0, 3);
  const Eigen::Vector2d y(1.0, 2.0);
  const long period_ns = 12'500'000;
  const long ticks = static_cast<long>(seconds * 80.0);
  std::vector<double> jitter, work;
  jitter.reserve(static_cast<std::size_t>(ticks));
  work.reserve(static_cast<std::size_t>(ticks));
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
    const Eigen::VectorXd u = inputAt(static_cast<int>(k), 3);
    for (auto& s : segs) {
      s->update(static_cast<double>(k) * 0.0125, u, y);
      s->predict(80, plan, out);
    }
    timespec done{};
    clock_gettime(CLOCK_MONOTONIC, &done);
    const double elapsed = static_cast<double>((done.tv_sec - next.tv_sec) * 1'000'000'000L + (done.tv_nsec - next.tv_nsec));
    work.push_back(elapsed - jitter.back());
    if (elapsed > static_cast<double>(period_ns)) ++misses;
  }
  std::printf("plsa-bench loop: %ld ticks at 80 Hz, %d segments (update + predict 80 each), mlockall %s\n", ticks,
              segments, locked ? "on" : "not permitted");
  report("loop wake-up jitter", stats(jitter));
  report("loop work per tick", stats(work));
  g_figures["loop deadline misses"] = static_cast<double>(misses);
  std::printf("  deadline misses: %ld of %ld\n", misses, ticks);
}

void BM_PredictorUpdate(benchmark::State& state) {
  plsa::Predictor<5> p(syntheticModel(2, 2, 5, 7));
  const Eigen::Vector2d y(1.0, 2.0);
  long k = 0;
  for (auto _ : state) {
    p.update(static_cast<double>(k) * 0.0125, inputAt(static_cast<int>(k), 2), y);
    ++k;
  }
}
BENCHMARK(BM_PredictorUpdate)->Name("Predictor<5>::update (2 chambers, 2 outputs)");

void BM_PredictorPredict(benchmark::State& state) {
  plsa::Predictor<5> p(syntheticModel(2, 2, 5, 7));
  const Eigen::Vector2d y(1.0, 2.0);
  for (int k = 0; k < 100; ++k) p.update(k * 0.0125, inputAt(k, 2), y);
  Eigen::MatrixXd out(400, 2);
  const Eigen::MatrixXd plan(0, 2);
  const int h = static_cast<int>(state.range(0));
  for (auto _ : state) {
    p.predict(h, plan, out);
    benchmark::DoNotOptimize(out.data());
  }
}
BENCHMARK(BM_PredictorPredict)->Name("Predictor<5>::predict (2 chambers, 2 outputs)")->Arg(1)->Arg(40)->Arg(80)->Arg(400);

template <int N>
void BM_ObfBankStep(benchmark::State& state) {
  plsa::ObfBank<N> bank(plsa::PoleSet::real({0.981, 0.969, 0.964, 0.957, 0.945}));
  double u = 0.1;
  for (auto _ : state) {
    bank.step(u);
    u = -u;
    benchmark::DoNotOptimize(bank.state().data());
  }
}
BENCHMARK_TEMPLATE(BM_ObfBankStep, 5)->Name("ObfBank<5>::step");
BENCHMARK_TEMPLATE(BM_ObfBankStep, Eigen::Dynamic)->Name("ObfBank<Dynamic>::step (5 poles)");

}  // namespace

int main(int argc, char** argv) {
  std::string json;
  long calls = 1'000'000;
  double loop_s = 0;
  int segments = 1;
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
    if (a == "--latency") latency = true;
    else if (a == "--calls") calls = std::stol(value("--calls"));
    else if (a == "--loop") loop_s = std::stod(value("--loop"));
    else if (a == "--segments") segments = std::stoi(value("--segments"));
    else if (a == "--json") json = value("--json");
    else rest.push_back(argv[i]);
  }
  if (calls < 1000 || segments < 1 || loop_s < 0) {
    std::fprintf(stderr, "plsa-bench: --calls >= 1000, --segments >= 1, --loop >= 0\n");
    return 2;
  }
  if (latency || loop_s > 0) {
    if (latency) runLatency(calls);
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
