#include "plsa/identify/slow_fraction_levels.hpp"

#include "plsa/core/check.hpp"
#include "plsa/eval/model_regressors.hpp"

namespace plsa::identify {
namespace {

// `structure` with each region's fast coefficients mapped through `block(out)`.
template <class Block>
DioPwlObfModel mappedThrough(const DioPwlObfModel& structure, const TiedSlowMode& tie, Block block) {
  DioPwlObfModel m = structure;
  m.output_level.clear();
  m.coefficients = tie.fast.coefficients;
  for (auto& region : m.coefficients)
    for (std::size_t out = 0; out < region.size(); ++out) region[out] = block(out) * region[out];
  return m;
}

// The model at the fractions first, then one per slow pole: each region's
// coefficients through K_m alone, whose simulated level is that pole's
// direction.
std::vector<DioPwlObfModel> directionModels(const TiedSlowMode& tie, const DioPwlObfModel& structure,
                                            const SlowFractions& alpha) {
  std::vector<DioPwlObfModel> models{
      mappedThrough(structure, tie, [&](std::size_t out) { return tie.blocks[out].at(alpha[out]); })};
  for (std::size_t m = 0; m < tie.blocks.front().K.size(); ++m)
    models.push_back(mappedThrough(structure, tie, [&](std::size_t out) { return tie.blocks[out].K[m]; }));
  return models;
}

// Normal equations of the level step: unknowns the fraction steps (one set,
// or one per output) and each output's level.
struct LevelNormals {
  Eigen::MatrixXd N;
  Eigen::VectorXd b;
  double ee = 0.0;
};

void accumulateRecord(const std::vector<Eigen::MatrixXd>& level, const Eigen::MatrixXd& y, const Eigen::VectorXd* w,
                      bool shared, LevelNormals& n) {
  const auto ny = y.cols(), np = static_cast<Eigen::Index>(level.size()) - 1;
  const Eigen::Index fractions = shared ? np : np * ny;
  Eigen::VectorXd x(n.b.size());
  for (Eigen::Index k = 0; k < y.rows(); ++k) {
    const double wk = w ? (*w)(k) : 1.0;
    if (wk == 0.0) continue;
    for (Eigen::Index o = 0; o < ny; ++o) {
      x.setZero();
      for (Eigen::Index m = 0; m < np; ++m) x((shared ? 0 : o * np) + m) = level[static_cast<std::size_t>(m + 1)](k, o);
      x(fractions + o) = 1.0;
      const double e = y(k, o) - level.front()(k, o);
      n.N.selfadjointView<Eigen::Lower>().rankUpdate(x, wk);
      n.b += wk * e * x;
      n.ee += wk * e * e;
    }
  }
}

}  // namespace

LevelFractionStep levelFractionStep(const TiedSlowMode& tie, const DioPwlObfModel& structure,
                                    const SlowFractions& alpha, const LevelRecords& records, bool shared) {
  PLSA_CHECK(
      records.U.size() == records.Y.size() && (records.weights.empty() || records.weights.size() == records.U.size()),
      "levelFractionStep: need one output and weight record per input record");
  const std::vector<DioPwlObfModel> models = directionModels(tie, structure, alpha);
  const auto ny = static_cast<Eigen::Index>(alpha.size()), np = static_cast<Eigen::Index>(alpha.front().size());
  const Eigen::Index fractions = shared ? np : np * ny;
  LevelNormals n{Eigen::MatrixXd::Zero(fractions + ny, fractions + ny), Eigen::VectorXd::Zero(fractions + ny)};
  for (std::size_t r = 0; r < records.U.size(); ++r) {
    if (records.U[r].rows() == 0) continue;
    const std::vector<Eigen::MatrixXd> dy = eval::modelIncrements(models, records.U[r]);
    std::vector<Eigen::MatrixXd> level;
    for (std::size_t j = 0; j < models.size(); ++j) level.push_back(eval::modelLevels(models[j], records.U[r], dy[j]));
    accumulateRecord(level, records.Y[r], records.weights.empty() ? nullptr : &records.weights[r], shared, n);
  }
  LevelFractionStep step{alpha, n.ee};
  for (Eigen::Index o = 0; o < ny; ++o) {
    const double c = n.N(fractions + o, fractions + o);
    if (c > 0) step.misfit -= n.b(fractions + o) * n.b(fractions + o) / c;
  }
  Eigen::MatrixXd N = n.N.selfadjointView<Eigen::Lower>();
  if (!(N.topLeftCorner(fractions, fractions).trace() > 0)) return step;
  N.diagonal().head(fractions).array() += 1e-9 * N.topLeftCorner(fractions, fractions).trace() / fractions;
  const Eigen::VectorXd delta = N.ldlt().solve(n.b).head(fractions);
  if (!delta.allFinite()) return step;
  for (Eigen::Index o = 0; o < ny; ++o)
    step.alpha[static_cast<std::size_t>(o)] += delta.segment(shared ? 0 : o * np, np);
  return step;
}

}  // namespace plsa::identify
