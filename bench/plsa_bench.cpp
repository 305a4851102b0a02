// plsa-bench: latency of the real-time building blocks. Fixtures build
// everything outside the timed loop.
#include <benchmark/benchmark.h>

#include <cmath>

#include "plsa/obf/obf_bank.hpp"

namespace {

const plsa::PoleSet kTableTwo = plsa::PoleSet::real({0.981, 0.969, 0.964, 0.957, 0.945});

template <int N>
void BM_ObfBankStep(benchmark::State& state) {
  plsa::ObfBank<N> bank(kTableTwo);
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

BENCHMARK_MAIN();
