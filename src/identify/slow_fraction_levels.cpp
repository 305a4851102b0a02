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

// The model at the fractions first, then, when `directions`, one per slow
// pole: each region's coefficients through K_m alone, whose simulated level
// is that pole's direction.
std::vector<DioPwlObfModel> levelModels(const TiedSlowMode& tie, const DioPwlObfModel& structure,
                                        const SlowFractions& alpha, bool directions) {
  std::vector<DioPwlObfModel> models{
      mappedThrough(structure, tie, [&](std::size_t out) { return tie.blocks[out].at(alpha[out]); })};
  for (std::size_t m = 0; directions && m < tie.blocks.front().K.size(); ++m)
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

// The step from a fit's normals: each output's level eliminated for the
// misfit, then the fractions' least squares (none when only the misfit was
// asked: no direction was simulated).
LevelFractionStep stepFrom(const LevelNormals& n, const SlowFractions& alpha, Eigen::Index fractions, bool shared) {
  const auto ny = static_cast<Eigen::Index>(alpha.size());
  const Eigen::Index np = shared ? fractions : fractions / ny;  // the directions simulated
  LevelFractionStep step{alpha, n.ee};
  for (Eigen::Index o = 0; o < ny; ++o) {
    const double c = n.N(fractions + o, fractions + o);
    if (c > 0) step.misfit -= n.b(fractions + o) * n.b(fractions + o) / c;
  }
  if (fractions == 0) return step;
  Eigen::MatrixXd N = n.N.selfadjointView<Eigen::Lower>();
  if (!(N.topLeftCorner(fractions, fractions).trace() > 0)) return step;
  N.diagonal().head(fractions).array() += 1e-9 * N.topLeftCorner(fractions, fractions).trace() / fractions;
  const Eigen::VectorXd delta = N.ldlt().solve(n.b).head(fractions);
  if (!delta.allFinite()) return step;
  for (Eigen::Index o = 0; o < ny; ++o)
    step.alpha[static_cast<std::size_t>(o)] += delta.segment(shared ? 0 : o * np, np);
  return step;
}

}  // namespace

std::vector<LevelFractionStep> levelFractionSteps(const DioPwlObfModel& structure,
                                                  const std::vector<LevelFractionQuery>& queries,
                                                  const std::vector<Eigen::MatrixXd>& U,
                                                  const std::vector<Eigen::MatrixXd>& Y, bool shared) {
  PLSA_CHECK(U.size() == Y.size(), "levelFractionSteps: need one output record per input record");
  if (queries.empty()) return {};
  std::vector<DioPwlObfModel> models;  // every query's, one after another
  std::vector<std::size_t> first;
  std::vector<LevelNormals> normals;
  std::vector<Eigen::Index> fractions;
  for (const LevelFractionQuery& q : queries) {
    PLSA_CHECK(q.weights.empty() || q.weights.size() == U.size(),
               "levelFractionSteps: need one weight record per input record");
    std::vector<DioPwlObfModel> own = levelModels(q.tie, structure, q.alpha, q.step);
    const auto ny = static_cast<Eigen::Index>(q.alpha.size()), np = static_cast<Eigen::Index>(own.size()) - 1;
    fractions.push_back(shared ? np : np * ny);
    normals.push_back({Eigen::MatrixXd::Zero(fractions.back() + ny, fractions.back() + ny),
                       Eigen::VectorXd::Zero(fractions.back() + ny)});
    first.push_back(models.size());
    for (DioPwlObfModel& m : own) models.push_back(std::move(m));
  }
  first.push_back(models.size());
  for (std::size_t r = 0; r < U.size(); ++r) {
    if (U[r].rows() == 0) continue;
    const std::vector<Eigen::MatrixXd> dy = eval::modelIncrements(models, U[r]);
    for (std::size_t q = 0; q < queries.size(); ++q) {
      std::vector<Eigen::MatrixXd> level;
      for (std::size_t j = first[q]; j < first[q + 1]; ++j) level.push_back(eval::modelLevels(models[j], U[r], dy[j]));
      const SampleWeights& w = queries[q].weights;
      accumulateRecord(level, Y[r], w.empty() ? nullptr : &w[r], shared, normals[q]);
    }
  }
  std::vector<LevelFractionStep> steps;
  for (std::size_t q = 0; q < queries.size(); ++q)
    steps.push_back(stepFrom(normals[q], queries[q].alpha, fractions[q], shared));
  return steps;
}

LevelFractionStep levelFractionStep(const TiedSlowMode& tie, const DioPwlObfModel& structure,
                                    const SlowFractions& alpha, const LevelRecords& records, bool shared) {
  return levelFractionSteps(structure, {{tie, alpha, records.weights, true}}, records.U, records.Y, shared).front();
}

}  // namespace plsa::identify
