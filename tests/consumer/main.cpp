// Links the installed plsa: a basis function against its closed form, and the
// predictor on a model built here, as the README's example uses them.
#include <cmath>
#include <cstdio>

#include <plsa/io/csv_log.hpp>
#include <plsa/obf/obf_bank.hpp>
#include <plsa/predict/predictor.hpp>

int main() {
  plsa::ObfBank<2> bank(plsa::PoleSet::real({0.5, 0.5}));
  bank.step(1.0);
  const double want = std::sqrt(1.0 - 0.25);
  if (std::abs(bank.state()(0) - want) > 1e-15) {
    std::printf("consumer: wrong basis response %g (want %g)\n", bank.state()(0), want);
    return 1;
  }
  plsa::DioPwlObfModel m;
  m.inputs = {"p_1"};
  m.outputs = {"bend_deg"};
  m.input_min = 0.0;
  m.input_max = 0.4;
  m.poles = {{plsa::PoleSet::real({0.9, 0.8})}};
  m.shaping.play = {{plsa::PlayChannel(0.0)}};
  m.coefficients = {{Eigen::Vector2d(1.0, 0.5)}};
  m.region_fits = {plsa::RegionFit{}};
  plsa::Predictor<> predictor(m);
  Eigen::MatrixXd out(10, 1);
  predictor.update(0.0, Eigen::VectorXd::Constant(1, 0.1), Eigen::VectorXd::Constant(1, 2.0));
  predictor.update(0.0125, Eigen::VectorXd::Constant(1, 0.2), Eigen::VectorXd::Constant(1, 2.0));
  if (predictor.predict(10, Eigen::MatrixXd(0, 1), out) != plsa::PredictorStatus::kOk || !out.allFinite()) {
    std::printf("consumer: the predictor failed\n");
    return 1;
  }
  plsa::io::Log log;
  std::printf("consumer: plsa installed package works (%d columns, prediction %g)\n",
              static_cast<int>(log.columns.size()), out(9, 0));
  return 0;
}
