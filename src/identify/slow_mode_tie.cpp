#include "plsa/identify/slow_mode_tie.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <string>

#include "plsa/core/check.hpp"
#include "plsa/core/number_text.hpp"
#include "plsa/obf/obf_bank.hpp"

namespace plsa::identify {
namespace {

// Samples of the basis functions' impulse responses that A and K are solved
// on. F B c lies exactly in the span of the bank with the slow pole, so any
// horizon over which its basis functions are independent gives the exact
// map; this one keeps the slowest candidate's (20 s at 80 Hz) column well
// scaled.
constexpr int kImpulseLength = 2000;
constexpr int kMaxSweeps = 100;

// The bank's poles less one copy of `pole`.
PoleSet withoutPole(const PoleSet& bank, double pole, const std::string& where) {
  std::vector<std::complex<double>> p = bank.poles();
  const auto at = std::find_if(p.begin(), p.end(), [&](std::complex<double> z) {
    return std::abs(z - std::complex<double>(pole, 0.0)) <= 1e-12;
  });
  PLSA_CHECK(at != p.end(),
             "tiedSlowMode: the bank " + where + " does not carry the slow pole " + significantDigits(pole, 6));
  p.erase(at);
  PLSA_CHECK(!p.empty(), "tiedSlowMode: the bank " + where + " has no pole besides the slow one");
  return PoleSet(p);
}

// One bank's A and K: its basis functions b_i on `fast`, and (1 - p)/(q - p) b_i,
// written on the basis of `slow` (the same poles and p) by least squares on
// their impulse responses, which they fit exactly.
TiedBlock tiedBank(const PoleSet& fast, const PoleSet& slow, double p, const std::string& where) {
  const Eigen::MatrixXd Hf = ObfBank<>(fast).impulseResponse(kImpulseLength);
  const Eigen::MatrixXd Hs = ObfBank<>(slow).impulseResponse(kImpulseLength);
  // Row k is the response at time k + 1; the lag's output at time t takes the
  // basis function's at t - 1, which is row t - 2.
  Eigen::MatrixXd Lf(Hf.rows(), Hf.cols());
  Eigen::RowVectorXd z = Eigen::RowVectorXd::Zero(Hf.cols()), before = z;
  for (Eigen::Index k = 0; k < Hf.rows(); ++k) {
    z = p * z + (1.0 - p) * before;
    Lf.row(k) = z;
    before = Hf.row(k);
  }
  const auto qr = Hs.colPivHouseholderQr();
  TiedBlock b{qr.solve(Hf), qr.solve(Lf)};
  const double miss = std::max((Hs * b.A - Hf).norm() / Hf.norm(), (Hs * b.K - Lf).norm() / Lf.norm());
  PLSA_CHECK(miss <= 1e-8, "tiedSlowMode: the bank " + where + " does not represent its lagged response (relative " +
                               "residual " + significantDigits(miss, 3) + ")");
  return b;
}

// Output o's block: its banks in regressor order (input, then play channel).
TiedBlock outputBlock(const DioPwlObfModel& model, const DioPwlObfModel& fast, int o, double pole) {
  const auto oo = static_cast<std::size_t>(o);
  TiedBlock b{Eigen::MatrixXd::Zero(model.regressorSize(o), fast.regressorSize(o)),
              Eigen::MatrixXd::Zero(model.regressorSize(o), fast.regressorSize(o))};
  Eigen::Index rs = 0, rf = 0;
  for (std::size_t j = 0; j < model.poles[oo].size(); ++j) {
    const TiedBlock bank =
        tiedBank(fast.poles[oo][j], model.poles[oo][j], pole, model.inputs[j] + " -> " + model.outputs[oo]);
    const int channels = j < model.shaping.play.size() ? static_cast<int>(model.shaping.play[j].size()) : 1;
    for (int ch = 0; ch < channels; ++ch) {
      b.A.block(rs, rf, bank.A.rows(), bank.A.cols()) = bank.A;
      b.K.block(rs, rf, bank.K.rows(), bank.K.cols()) = bank.K;
      rs += bank.A.rows();
      rf += bank.A.cols();
    }
  }
  return b;
}

}  // namespace

TiedSlowMode tiedSlowMode(const DioPwlObfModel& model, double pole) {
  PLSA_CHECK(std::isfinite(pole) && pole > 0 && pole < 1, "tiedSlowMode: the slow pole must lie in (0, 1)");
  PLSA_CHECK(model.schedule_side == ScheduleSide::kInput, "tiedSlowMode: a tied slow pole needs input-side scheduling");
  TiedSlowMode tie{model, {}};
  tie.fast.coefficients.clear();
  tie.fast.region_fits.clear();
  tie.fast.output_level.clear();
  for (std::size_t o = 0; o < model.poles.size(); ++o)
    for (std::size_t j = 0; j < model.poles[o].size(); ++j)
      tie.fast.poles[o][j] = withoutPole(model.poles[o][j], pole, model.inputs[j] + " -> " + model.outputs[o]);
  for (int o = 0; o < model.outputCount(); ++o) tie.blocks.push_back(outputBlock(model, tie.fast, o, pole));
  return tie;
}

CoefficientSums::Group reducedGroup(const TiedSlowMode& tie, const CoefficientSums::Group& total,
                                    const std::vector<double>& alpha) {
  const int R = tie.fast.partition.regionCount();
  const std::size_t ny = tie.blocks.size();
  PLSA_CHECK(alpha.size() == ny && total.J.size() == ny, "reducedGroup: need one fraction and one sum per output");
  CoefficientSums::Group g;
  g.count = total.count;
  g.G.resize(ny);
  g.h.resize(ny);
  g.J.resize(ny);
  g.Jh.resize(ny);
  for (std::size_t o = 0; o < ny; ++o) {
    const Eigen::MatrixXd M = tie.blocks[o].at(alpha[o]);
    const Eigen::Index ws = M.rows(), wf = M.cols();
    PLSA_CHECK(total.J[o].rows() == R * ws, "reducedGroup: the sums were made for another model structure");
    Eigen::MatrixXd JM(R * ws, R * wf);
    for (int c = 0; c < R; ++c) JM.middleCols(c * wf, wf).noalias() = total.J[o].middleCols(c * ws, ws) * M;
    g.J[o].resize(R * wf, R * wf);
    g.Jh[o].resize(R * wf);
    g.G[o].resize(static_cast<std::size_t>(R));
    g.h[o].resize(static_cast<std::size_t>(R));
    for (int a = 0; a < R; ++a) {
      g.J[o].middleRows(a * wf, wf).noalias() = M.transpose() * JM.middleRows(a * ws, ws);
      g.Jh[o].segment(a * wf, wf).noalias() = M.transpose() * total.Jh[o].segment(a * ws, ws);
    }
    for (int l = 0; l < R; ++l) {
      g.G[o][static_cast<std::size_t>(l)] = g.J[o].block(l * wf, l * wf, wf, wf);
      g.h[o][static_cast<std::size_t>(l)] = g.Jh[o].segment(l * wf, wf);
    }
  }
  return g;
}

namespace {

// One sweep's step for output o at fraction alpha: the blended coefficients'
// least-squares terms for the fraction, numerator and denominator.
std::pair<double, double> fractionTerms(const TiedBlock& b, const Eigen::MatrixXd& Gs, const Eigen::VectorXd& hs,
                                        double alpha, double ridge) {
  const Eigen::MatrixXd M = b.at(alpha);
  Eigen::MatrixXd G = M.transpose() * Gs * M;
  if (!(G.trace() > 0)) return {0.0, 0.0};
  G.diagonal().array() += ridge * G.trace() / static_cast<double>(G.rows());
  const Eigen::VectorXd c = G.ldlt().solve(M.transpose() * hs);
  const Eigen::VectorXd ce = b.A * c, ck = b.K * c;
  const double den = ck.dot(Gs * ck);
  if (!(den > 1e-12 * ce.dot(Gs * ce))) return {0.0, 0.0};  // no slow content to fit a fraction to
  return {ck.dot(hs - Gs * ce), den};
}

// Each output's fraction from its (numerator, denominator), or one from their
// sums when shared; 0 where there is no slow content.
std::vector<double> fractionsOf(const std::vector<std::pair<double, double>>& terms, bool shared) {
  std::vector<double> alpha;
  double num = 0.0, den = 0.0;
  for (const auto& [n, d] : terms) {
    alpha.push_back(d > 0 ? n / d : 0.0);
    num += n;
    den += d;
  }
  if (shared) std::fill(alpha.begin(), alpha.end(), den > 0 ? num / den : 0.0);
  for (double a : alpha) PLSA_CHECK(std::isfinite(a), "fitSlowFraction: the slow fraction is not finite");
  return alpha;
}

}  // namespace

std::vector<double> fitSlowFraction(const TiedSlowMode& tie, const CoefficientSums::Group& total, bool shared,
                                    double ridge) {
  const int R = tie.fast.partition.regionCount();
  const std::size_t ny = tie.blocks.size();
  // The blended problem: every node's coefficients equal.
  std::vector<Eigen::MatrixXd> Gs(ny);
  std::vector<Eigen::VectorXd> hs(ny);
  for (std::size_t o = 0; o < ny; ++o) {
    const Eigen::Index ws = tie.blocks[o].A.rows();
    Gs[o] = Eigen::MatrixXd::Zero(ws, ws);
    hs[o] = Eigen::VectorXd::Zero(ws);
    for (int a = 0; a < R; ++a) {
      hs[o] += total.Jh[o].segment(a * ws, ws);
      for (int c = 0; c < R; ++c) Gs[o] += total.J[o].block(a * ws, c * ws, ws, ws);
    }
  }
  std::vector<double> alpha(ny, 0.0);
  for (int sweep = 0; sweep < kMaxSweeps; ++sweep) {
    std::vector<std::pair<double, double>> terms;
    for (std::size_t o = 0; o < ny; ++o) terms.push_back(fractionTerms(tie.blocks[o], Gs[o], hs[o], alpha[o], ridge));
    const std::vector<double> next = fractionsOf(terms, shared);
    const bool settled = slowFractionSettled(alpha, next);
    alpha = next;
    if (settled) break;
  }
  return alpha;
}

std::vector<double> refitSlowFraction(const TiedSlowMode& tie, const CoefficientSums::Group& total,
                                      const DioPwlObfModel& fast, bool shared) {
  const int R = tie.fast.partition.regionCount();
  std::vector<std::pair<double, double>> terms;
  for (std::size_t o = 0; o < tie.blocks.size(); ++o) {
    const TiedBlock& b = tie.blocks[o];
    const Eigen::Index ws = b.A.rows(), wf = b.A.cols();
    const Eigen::VectorXd c = fast.stackedCoefficients(static_cast<int>(o));
    Eigen::VectorXd ce(R * ws), ck(R * ws);
    for (int l = 0; l < R; ++l) {
      ce.segment(l * ws, ws) = b.A * c.segment(l * wf, wf);
      ck.segment(l * ws, ws) = b.K * c.segment(l * wf, wf);
    }
    const Eigen::VectorXd Jck = total.J[o] * ck;
    const double den = ck.dot(Jck);
    terms.emplace_back(den > 1e-12 * ce.dot(total.J[o] * ce)
                           ? std::pair<double, double>{ck.dot(total.Jh[o]) - ce.dot(Jck), den}
                           : std::pair<double, double>{0.0, 0.0});
  }
  return fractionsOf(terms, shared);
}

bool slowFractionSettled(const std::vector<double>& before, const std::vector<double>& after) {
  double moved = 0.0, size = 1.0;
  for (std::size_t o = 0; o < after.size(); ++o) {
    moved = std::max(moved, std::abs(after[o] - before[o]));
    size = std::max(size, std::abs(after[o]));
  }
  return moved <= 1e-7 * size;
}

}  // namespace plsa::identify
