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

// The bank's poles less one copy of each of `slow`.
PoleSet withoutPoles(const PoleSet& bank, const std::vector<double>& slow, const std::string& where) {
  std::vector<std::complex<double>> p = bank.poles();
  for (double pole : slow) {
    const auto at = std::find_if(p.begin(), p.end(), [&](std::complex<double> z) {
      return std::abs(z - std::complex<double>(pole, 0.0)) <= 1e-12;
    });
    PLSA_CHECK(at != p.end(),
               "tiedSlowMode: the bank " + where + " does not carry the slow pole " + significantDigits(pole, 6));
    p.erase(at);
  }
  PLSA_CHECK(!p.empty(), "tiedSlowMode: the bank " + where + " has no pole besides the slow ones");
  return PoleSet(p);
}

// The response of the first-order lag (1 - p)/(q - p) to each basis function
// whose impulse response H holds (row k: time k + 1): the lag's output at
// time t takes the basis function's at t - 1, which is row t - 2.
Eigen::MatrixXd laggedResponse(const Eigen::MatrixXd& H, double p) {
  Eigen::MatrixXd L(H.rows(), H.cols());
  Eigen::RowVectorXd z = Eigen::RowVectorXd::Zero(H.cols()), before = z;
  for (Eigen::Index k = 0; k < H.rows(); ++k) {
    z = p * z + (1.0 - p) * before;
    L.row(k) = z;
    before = H.row(k);
  }
  return L;
}

// One bank's A and K_m: its basis functions b_i on `fast`, and
// (1 - p_m)/(q - p_m) b_i, written on the basis of `slow` (the same poles and
// every p_m) by least squares on their impulse responses, which they fit
// exactly.
TiedBlock tiedBank(const PoleSet& fast, const PoleSet& slow, const std::vector<double>& poles,
                   const std::string& where) {
  const Eigen::MatrixXd Hf = ObfBank<>(fast).impulseResponse(kImpulseLength);
  const Eigen::MatrixXd Hs = ObfBank<>(slow).impulseResponse(kImpulseLength);
  const auto qr = Hs.colPivHouseholderQr();
  TiedBlock b{qr.solve(Hf), {}};
  double miss = (Hs * b.A - Hf).norm() / Hf.norm();
  for (double p : poles) {
    const Eigen::MatrixXd L = laggedResponse(Hf, p);
    b.K.push_back(qr.solve(L));
    miss = std::max(miss, (Hs * b.K.back() - L).norm() / L.norm());
  }
  PLSA_CHECK(miss <= 1e-8, "tiedSlowMode: the bank " + where + " does not represent its lagged response (relative " +
                               "residual " + significantDigits(miss, 3) + ")");
  return b;
}

// Output o's block: its banks in regressor order (input, then play channel).
TiedBlock outputBlock(const DioPwlObfModel& model, const DioPwlObfModel& fast, int o,
                      const std::vector<double>& poles) {
  const auto oo = static_cast<std::size_t>(o);
  const auto zero = [&] { return Eigen::MatrixXd::Zero(model.regressorSize(o), fast.regressorSize(o)); };
  TiedBlock b{zero(), std::vector<Eigen::MatrixXd>(poles.size(), zero())};
  Eigen::Index rs = 0, rf = 0;
  for (std::size_t j = 0; j < model.poles[oo].size(); ++j) {
    const TiedBlock bank =
        tiedBank(fast.poles[oo][j], model.poles[oo][j], poles, model.inputs[j] + " -> " + model.outputs[oo]);
    for (int copy = 0; copy < model.bankCopies(j); ++copy) {
      b.A.block(rs, rf, bank.A.rows(), bank.A.cols()) = bank.A;
      for (std::size_t m = 0; m < poles.size(); ++m) b.K[m].block(rs, rf, bank.A.rows(), bank.A.cols()) = bank.K[m];
      rs += bank.A.rows();
      rf += bank.A.cols();
    }
  }
  return b;
}

}  // namespace

TiedSlowMode tiedSlowMode(const DioPwlObfModel& model, const std::vector<double>& poles) {
  PLSA_CHECK(!poles.empty(), "tiedSlowMode: no slow pole to tie");
  for (std::size_t m = 0; m < poles.size(); ++m) {
    PLSA_CHECK(std::isfinite(poles[m]) && poles[m] > 0 && poles[m] < 1,
               "tiedSlowMode: the slow poles must lie in (0, 1)");
    for (std::size_t n = 0; n < m; ++n) PLSA_CHECK(poles[n] != poles[m], "tiedSlowMode: the slow poles must differ");
  }
  PLSA_CHECK(model.schedule_side == ScheduleSide::kInput, "tiedSlowMode: a tied slow pole needs input-side scheduling");
  TiedSlowMode tie{model, {}};
  tie.fast.coefficients.clear();
  tie.fast.region_fits.clear();
  tie.fast.output_level.clear();
  for (std::size_t o = 0; o < model.poles.size(); ++o)
    for (std::size_t j = 0; j < model.poles[o].size(); ++j)
      tie.fast.poles[o][j] = withoutPoles(model.poles[o][j], poles, model.inputs[j] + " -> " + model.outputs[o]);
  for (int o = 0; o < model.outputCount(); ++o) tie.blocks.push_back(outputBlock(model, tie.fast, o, poles));
  return tie;
}

CoefficientSums::Group reducedGroup(const TiedSlowMode& tie, const CoefficientSums::Group& total,
                                    const SlowFractions& alpha) {
  const int R = tie.fast.partition.regionCount();
  const std::size_t ny = tie.blocks.size();
  PLSA_CHECK(alpha.size() == ny && total.J.size() == ny, "reducedGroup: need one fraction set and one sum per output");
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

// The least-squares terms of one output's fractions, N alpha = b, given its
// coefficients' fast part ce and each slow pole's lagged part ck[m] under the
// normal matrix G and right-hand side h; zero where there is no slow content.
struct FractionTerms {
  Eigen::MatrixXd N;
  Eigen::VectorXd b;
};

FractionTerms fractionTerms(const Eigen::MatrixXd& G, const Eigen::VectorXd& h, const Eigen::VectorXd& ce,
                            const std::vector<Eigen::VectorXd>& ck) {
  const auto m = static_cast<Eigen::Index>(ck.size());
  FractionTerms t{Eigen::MatrixXd::Zero(m, m), Eigen::VectorXd::Zero(m)};
  std::vector<Eigen::VectorXd> Gck;
  for (const Eigen::VectorXd& k : ck) Gck.push_back(G * k);
  const Eigen::VectorXd r = h - G * ce;
  for (Eigen::Index i = 0; i < m; ++i) {
    t.b(i) = ck[static_cast<std::size_t>(i)].dot(r);
    for (Eigen::Index j = 0; j < m; ++j)
      t.N(i, j) = ck[static_cast<std::size_t>(i)].dot(Gck[static_cast<std::size_t>(j)]);
  }
  if (!(t.N.trace() > 1e-12 * ce.dot(G * ce))) return {Eigen::MatrixXd::Zero(m, m), Eigen::VectorXd::Zero(m)};
  return t;
}

// The fractions of N alpha = b; 0 without slow content. A relative ridge of
// 1e-10 keeps two slow poles whose lagged parts are nearly alike solvable.
Eigen::VectorXd solveFractions(const FractionTerms& t) {
  if (!(t.N.trace() > 0)) return Eigen::VectorXd::Zero(t.b.size());
  Eigen::MatrixXd N = t.N;
  N.diagonal().array() += 1e-10 * t.N.trace() / static_cast<double>(N.rows());
  return N.ldlt().solve(t.b);
}

// Each output's fractions from its terms, or one set from their sums when shared.
SlowFractions fractionsOf(const std::vector<FractionTerms>& terms, bool shared) {
  SlowFractions alpha;
  FractionTerms sum{Eigen::MatrixXd::Zero(terms.front().N.rows(), terms.front().N.cols()),
                    Eigen::VectorXd::Zero(terms.front().b.size())};
  for (const FractionTerms& t : terms) {
    alpha.push_back(solveFractions(t));
    sum.N += t.N;
    sum.b += t.b;
  }
  if (shared) std::fill(alpha.begin(), alpha.end(), solveFractions(sum));
  for (const Eigen::VectorXd& a : alpha) PLSA_CHECK(a.allFinite(), "fitSlowFraction: the slow fraction is not finite");
  return alpha;
}

// The blended problem's step for one output at fractions alpha: the
// coefficients every node shares, then the fractions' terms given them.
FractionTerms blendedTerms(const TiedBlock& b, const Eigen::MatrixXd& Gs, const Eigen::VectorXd& hs,
                           const Eigen::VectorXd& alpha, double ridge) {
  const Eigen::MatrixXd M = b.at(alpha);
  Eigen::MatrixXd G = M.transpose() * Gs * M;
  const auto m = static_cast<Eigen::Index>(b.K.size());
  if (!(G.trace() > 0)) return {Eigen::MatrixXd::Zero(m, m), Eigen::VectorXd::Zero(m)};
  G.diagonal().array() += ridge * G.trace() / static_cast<double>(G.rows());
  const Eigen::VectorXd c = G.ldlt().solve(M.transpose() * hs);
  std::vector<Eigen::VectorXd> ck;
  for (const Eigen::MatrixXd& K : b.K) ck.push_back(K * c);
  return fractionTerms(Gs, hs, b.A * c, ck);
}

}  // namespace

SlowFractions fitSlowFraction(const TiedSlowMode& tie, const CoefficientSums::Group& total, bool shared, double ridge) {
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
  SlowFractions alpha(ny, Eigen::VectorXd::Zero(static_cast<Eigen::Index>(tie.blocks.front().K.size())));
  for (int sweep = 0; sweep < kMaxSweeps; ++sweep) {
    std::vector<FractionTerms> terms;
    for (std::size_t o = 0; o < ny; ++o) terms.push_back(blendedTerms(tie.blocks[o], Gs[o], hs[o], alpha[o], ridge));
    const SlowFractions next = fractionsOf(terms, shared);
    const bool settled = slowFractionSettled(alpha, next);
    alpha = next;
    if (settled) break;
  }
  return alpha;
}

namespace {

// Each region's coefficients of `c` (stacked, width M.cols() each) through M.
Eigen::VectorXd throughBlock(const Eigen::MatrixXd& M, const Eigen::VectorXd& c, int regions) {
  Eigen::VectorXd v(regions * M.rows());
  for (int l = 0; l < regions; ++l) v.segment(l * M.rows(), M.rows()) = M * c.segment(l * M.cols(), M.cols());
  return v;
}

// Each region's rows of `X` (height M.rows() each) through M^T.
Eigen::MatrixXd throughBlockT(const Eigen::MatrixXd& M, const Eigen::MatrixXd& X, int regions) {
  Eigen::MatrixXd v(regions * M.cols(), X.cols());
  for (int l = 0; l < regions; ++l)
    v.middleRows(l * M.cols(), M.cols()) = M.transpose() * X.middleRows(l * M.rows(), M.rows());
  return v;
}

}  // namespace

SlowFractions gaussNewtonFractions(const TiedSlowMode& tie, const CoefficientSums::Group& total,
                                   const DioPwlObfModel& fast, const SlowFractions& alpha, bool shared) {
  const int R = tie.fast.partition.regionCount();
  const auto np = static_cast<Eigen::Index>(alpha.front().size());
  std::vector<FractionTerms> terms;
  for (std::size_t o = 0; o < tie.blocks.size(); ++o) {
    const TiedBlock& b = tie.blocks[o];
    const Eigen::MatrixXd M = b.at(alpha[o]);
    const Eigen::VectorXd cf = fast.stackedCoefficients(static_cast<int>(o));
    Eigen::MatrixXd Kc(R * M.rows(), np);  // each fraction's direction in the slow coordinates
    for (Eigen::Index m = 0; m < np; ++m) Kc.col(m) = throughBlock(b.K[static_cast<std::size_t>(m)], cf, R);
    const Eigen::VectorXd r = total.Jh[o] - total.J[o] * throughBlock(M, cf, R);
    const Eigen::MatrixXd JKc = total.J[o] * Kc;
    // The coefficients' best response to the fractions, projected out.
    Eigen::MatrixXd Jr = throughBlockT(M, throughBlockT(M, total.J[o], R).transpose(), R);
    Jr.diagonal().array() += 1e-12 * Jr.trace() / static_cast<double>(Jr.rows());
    const auto ldlt = Jr.ldlt();
    const Eigen::MatrixXd B = throughBlockT(M, JKc, R);
    FractionTerms t{Kc.transpose() * JKc - B.transpose() * ldlt.solve(B),
                    Kc.transpose() * r - B.transpose() * ldlt.solve(throughBlockT(M, r, R))};
    if (!(t.N.trace() > 0)) t = {Eigen::MatrixXd::Zero(np, np), Eigen::VectorXd::Zero(np)};
    terms.push_back(t);
  }
  SlowFractions step = fractionsOf(terms, shared);
  for (std::size_t o = 0; o < step.size(); ++o) step[o] += alpha[o];
  return step;
}

double tiedMisfit(const TiedSlowMode& tie, const CoefficientSums::Group& total, const DioPwlObfModel& fast,
                  const SlowFractions& alpha) {
  const int R = fast.partition.regionCount();
  double misfit = 0.0;
  for (std::size_t o = 0; o < alpha.size(); ++o) {
    const Eigen::VectorXd c =
        throughBlock(tie.blocks[o].at(alpha[o]), fast.stackedCoefficients(static_cast<int>(o)), R);
    misfit += c.dot(total.J[o] * c) - 2.0 * c.dot(total.Jh[o]);
  }
  return misfit;
}

bool slowFractionSettled(const SlowFractions& before, const SlowFractions& after) {
  double moved = 0.0, size = 1.0;
  for (std::size_t o = 0; o < after.size(); ++o) {
    moved = std::max(moved, (after[o] - before[o]).cwiseAbs().maxCoeff());
    size = std::max(size, after[o].cwiseAbs().maxCoeff());
  }
  return moved <= 1e-7 * size;
}

}  // namespace plsa::identify
