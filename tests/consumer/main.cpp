// Links the installed plsa and checks one basis function against its closed form.
#include <cmath>
#include <cstdio>

#include <plsa/obf/obf_bank.hpp>
#include <plsa/io/csv_log.hpp>

int main() {
  plsa::ObfBank<2> bank(plsa::PoleSet::real({0.5, 0.5}));
  bank.step(1.0);
  const double want = std::sqrt(1.0 - 0.25);
  if (std::abs(bank.state()(0) - want) > 1e-15) {
    std::printf("consumer: wrong basis response %g (want %g)\n", bank.state()(0), want);
    return 1;
  }
  plsa::io::Log log;
  std::printf("consumer: plsa installed package works (%d columns)\n",
              static_cast<int>(log.columns.size()));
  return 0;
}
