#include "plsa/identify/linear_dio_obf.hpp"

#include "plsa/core/check.hpp"
#include "plsa/obf/obf_bank.hpp"

namespace plsa::identify {

Eigen::MatrixXd dioObfRegressors(const std::vector<PoleSet>& poles_per_input, const Eigen::MatrixXd& u,
                                 DioStart start) {
  PLSA_CHECK(static_cast<Eigen::Index>(poles_per_input.size()) == u.cols(),
             "dioObfRegressors: " + std::to_string(poles_per_input.size()) + " pole sets for " +
                 std::to_string(u.cols()) + " inputs");
  PLSA_CHECK(u.allFinite(), "dioObfRegressors: the inputs contain NaN or Inf");
  const Eigen::MatrixXd du = dioDifference(u, start);
  int width = 0;
  for (const auto& p : poles_per_input) width += p.size();
  Eigen::MatrixXd phi(u.rows(), width);
  int offset = 0;
  for (std::size_t j = 0; j < poles_per_input.size(); ++j) {
    ObfBank<> bank(poles_per_input[j]);
    const int n = bank.size();
    for (Eigen::Index t = 0; t < u.rows(); ++t) {
      phi.block(t, offset, 1, n) = bank.state().transpose();
      bank.step(du(t, static_cast<Eigen::Index>(j)));
    }
    offset += n;
  }
  return phi;
}

LinearDioObf LinearDioObf::fit(const std::vector<PoleSet>& poles_per_input, const std::vector<Eigen::MatrixXd>& inputs,
                               const std::vector<Eigen::MatrixXd>& outputs, double ridge) {
  PLSA_CHECK(!inputs.empty() && inputs.size() == outputs.size(),
             "LinearDioObf::fit: need as many output records as input records, at least one");
  PLSA_CHECK(ridge >= 0.0, "LinearDioObf::fit: the ridge weight must be >= 0");
  Eigen::MatrixXd gram;
  Eigen::MatrixXd rhs;
  for (std::size_t r = 0; r < inputs.size(); ++r) {
    PLSA_CHECK(inputs[r].rows() == outputs[r].rows(),
               "LinearDioObf::fit: record " + std::to_string(r) + " has different input and output lengths");
    PLSA_CHECK(outputs[r].allFinite(), "LinearDioObf::fit: record " + std::to_string(r) + " has NaN or Inf outputs");
    const Eigen::MatrixXd phi = dioObfRegressors(poles_per_input, inputs[r]);
    const Eigen::MatrixXd dy = dioDifference(outputs[r], DioStart::kAtRest);
    if (r == 0) {
      gram = Eigen::MatrixXd::Zero(phi.cols(), phi.cols());
      rhs = Eigen::MatrixXd::Zero(phi.cols(), dy.cols());
    }
    PLSA_CHECK(dy.cols() == rhs.cols(), "LinearDioObf::fit: records have different output counts");
    gram.noalias() += phi.transpose() * phi;
    rhs.noalias() += phi.transpose() * dy;
  }
  // Ridge relative to the regressors' scale keeps it unit-free.
  const double scale = gram.diagonal().mean();
  gram.diagonal().array() += ridge * (scale > 0 ? scale : 1.0);
  LinearDioObf model;
  model.poles_per_input = poles_per_input;
  model.coefficients = gram.ldlt().solve(rhs);
  return model;
}

Eigen::MatrixXd LinearDioObf::increments(const Eigen::MatrixXd& u) const {
  return dioObfRegressors(poles_per_input, u) * coefficients;
}

}  // namespace plsa::identify
