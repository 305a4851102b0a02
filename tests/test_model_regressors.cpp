// The batch regressors: negligible tiles skipped, a used ModelRegressors refilled, and a record streamed in chunks
// (plsa/eval/model_regressors.hpp).
#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "plsa/dio/dio_transform.hpp"
#include "plsa/eval/model_regressors.hpp"
#include "plsa/identify/coefficient_fit.hpp"

using namespace plsa;
using namespace plsa::identify;

namespace {

// Input side over a 4 x 4 grid of nodes, random coefficients.
DioPwlObfModel gridModel() {
  DioPwlObfModel m;
  m.inputs = {"u1", "u2"};
  m.outputs = {"y", "z"};
  m.poles = {{PoleSet::real({0.9, 0.7}), PoleSet::real({0.85})}, {PoleSet::real({0.8}), PoleSet::real({0.9, 0.6})}};
  m.shaping.play = {{0.0}, {0.0}};
  m.partition = PwlPartition::interpolated({0, 1}, {{0.2, 0.4, 0.6, 0.8}, {0.2, 0.4, 0.6, 0.8}});
  m.schedule_side = ScheduleSide::kInput;
  const int R = m.partition.regionCount();
  std::mt19937 rng(11);
  std::normal_distribution<double> gauss(0.0, 1.0);
  m.coefficients.assign(static_cast<std::size_t>(R), {});
  for (auto& block : m.coefficients)
    for (int out = 0; out < 2; ++out) block.push_back(Eigen::VectorXd::NullaryExpr(3, [&] { return gauss(rng); }));
  m.region_fits.assign(static_cast<std::size_t>(R), RegionFit{});
  return m;
}

constexpr int kHold = 400, kSamples = 16 * kHold;

// The grid's nodes visited in turn, as a grid experiment does.
Eigen::MatrixXd gridInput() {
  Eigen::MatrixXd u(kSamples, 2);
  for (int k = 0; k < kSamples; ++k) u.row(k) << 0.2 + 0.2 * ((k / kHold) % 4), 0.2 + 0.2 * (k / (4 * kHold));
  return u;
}

Eigen::MatrixXd noisyOutputs(const DioPwlObfModel& m, const Eigen::MatrixXd& u) {
  std::mt19937 rng(12);
  std::normal_distribution<double> gauss(0.0, 1.0);
  Eigen::MatrixXd y = dioIntegrate(eval::modelIncrements(m, u));
  for (Eigen::Index k = 0; k < y.size(); ++k) y.data()[k] += 0.01 * gauss(rng);
  return y;
}

}  // namespace

// Visited in turn as a grid experiment does: over most tiles most nodes'
// regressors are zero (not yet visited) or decayed below rounding, and
// skipping them must change no increment or sum beyond rounding. Refilling a
// used ModelRegressors must equal a fresh one.
TEST(Regressors, SkippedNegligibleTilesChangeNoSumBeyondRounding) {
  const DioPwlObfModel m = gridModel();
  const int R = m.partition.regionCount(), T = kSamples;
  ASSERT_EQ(R, 16);
  const Eigen::MatrixXd u = gridInput(), y = noisyOutputs(m, u);

  const eval::ModelRegressors sparse = eval::modelRegressors(m, u);
  eval::ModelRegressors dense = sparse;
  dense.live.clear();  // every node live: the plain dense sums and products
  ASSERT_EQ(sparse.live.size(), 2u);
  for (int out = 0; out < 2; ++out) {
    const auto& live = sparse.live[static_cast<std::size_t>(out)];
    EXPECT_EQ(live.rows(), (T + eval::ModelRegressors::kTileRows - 1) / eval::ModelRegressors::kTileRows);
    EXPECT_EQ(live.cols(), R);
    EXPECT_LT(live.cast<double>().mean(), 0.5) << "a grid experiment leaves most tiles' nodes negligible";
    EXPECT_TRUE(live.col(R - 1).head(3).isConstant(false)) << "the last node is not visited before the end";
  }
  const Eigen::MatrixXd di_sparse = modelIncrements(m, sparse), di_dense = modelIncrements(m, dense);
  EXPECT_LT((di_sparse - di_dense).cwiseAbs().maxCoeff(), 1e-12 * di_dense.cwiseAbs().maxCoeff());
  Eigen::VectorXi fold(T);
  for (int k = 0; k < T; ++k) fold(k) = (k / 300) % 3;
  const CoefficientSums s_sparse = coefficientSums(m, {sparse}, {y}, {fold}, 3);
  const CoefficientSums s_dense = coefficientSums(m, {dense}, {y}, {fold}, 3);
  // The sums themselves (lower triangles: the only part kept) agree to rounding;
  // solutions would add the conditioning of a fold's normal equations.
  for (int g = 0; g < 3; ++g)
    for (std::size_t out = 0; out < 2; ++out) {
      const Eigen::MatrixXd& Js = s_sparse.groups[static_cast<std::size_t>(g)].J[out];
      const Eigen::MatrixXd& Jd = s_dense.groups[static_cast<std::size_t>(g)].J[out];
      const Eigen::MatrixXd diff =
          Eigen::MatrixXd(Js.triangularView<Eigen::Lower>()) - Eigen::MatrixXd(Jd.triangularView<Eigen::Lower>());
      EXPECT_LT(diff.cwiseAbs().maxCoeff(), 1e-12 * Jd.cwiseAbs().maxCoeff()) << "group " << g << ", output " << out;
      const Eigen::VectorXd& hs = s_sparse.groups[static_cast<std::size_t>(g)].Jh[out];
      const Eigen::VectorXd& hd = s_dense.groups[static_cast<std::size_t>(g)].Jh[out];
      EXPECT_LT((hs - hd).cwiseAbs().maxCoeff(), 1e-12 * hd.cwiseAbs().maxCoeff())
          << "group " << g << ", output " << out;
    }
  DioPwlObfModel a = m, b = m;
  solveCoefficients(a, s_sparse, -1);
  solveCoefficients(b, s_dense, -1);
  for (int out = 0; out < 2; ++out)
    EXPECT_LT((a.stackedCoefficients(out) - b.stackedCoefficients(out)).norm(),
              1e-9 * b.stackedCoefficients(out).norm());

  // A used ModelRegressors, first filled from another record, refills to the fresh one.
  eval::ModelRegressors reused = eval::modelRegressors(m, Eigen::MatrixXd(u.topRows(T / 2).reverse()));
  eval::modelRegressors(m, u, reused);
  for (std::size_t out = 0; out < 2; ++out) {
    EXPECT_EQ(reused.phi[out], sparse.phi[out]);
    EXPECT_TRUE((reused.live[out] == sparse.live[out]).all());
    EXPECT_EQ(reused.level0[out], sparse.level0[out]);
  }
  ASSERT_EQ(reused.schedule.size(), sparse.schedule.size());
  for (std::size_t k = 0; k < sparse.schedule.size(); ++k) {
    ASSERT_EQ(reused.schedule[k].count, sparse.schedule[k].count);
    for (int c = 0; c < sparse.schedule[k].count; ++c)
      EXPECT_EQ(reused.schedule[k].weight[static_cast<std::size_t>(c)],
                sparse.schedule[k].weight[static_cast<std::size_t>(c)]);
  }
  const eval::ModelRegressors empty = eval::modelRegressors(m, Eigen::MatrixXd(0, 2));
  modelRegressors(m, Eigen::MatrixXd(0, 2), reused);
  EXPECT_EQ(reused.live[0].rows(), 0);
  EXPECT_EQ(empty.phi[0].rows(), 0);
}

// A stream's chunks are the whole record's regressors cut in whole tiles: the
// same values bit for bit, the same first-sample levels, at least the same
// live tiles; its sums and increments agree with the whole record's to
// rounding, and one pass gives several coefficient sets' increments.
TEST(Regressors, StreamedChunksAreTheWholeRecordCutInTiles) {
  const DioPwlObfModel m = gridModel();
  const Eigen::MatrixXd u = gridInput(), y = noisyOutputs(m, u);
  const eval::ModelRegressors whole = eval::modelRegressors(m, u);
  const Eigen::Index tile = eval::ModelRegressors::kTileRows;
  for (const Eigen::Index max_rows : {Eigen::Index{1}, 3 * tile + 5, eval::RegressorStream::kChunkRows}) {
    eval::RegressorStream stream(m, u);
    ASSERT_EQ(stream.rows(), kSamples);
    eval::ModelRegressors chunk;
    Eigen::Index next_row = 0;
    int chunks = 0;
    while (stream.next(chunk, max_rows)) {
      ++chunks;
      const auto rows = static_cast<Eigen::Index>(chunk.schedule.size());
      ASSERT_EQ(chunk.first_row, next_row);
      const Eigen::Index expected = std::min(std::max(tile, max_rows / tile * tile), kSamples - next_row);
      ASSERT_EQ(rows, expected) << "chunks are whole tiles but the last";
      for (std::size_t out = 0; out < 2; ++out) {
        ASSERT_EQ(chunk.phi[out].rows(), rows);
        EXPECT_EQ(chunk.phi[out], whole.phi[out].middleRows(next_row, rows)) << "at row " << next_row;
        EXPECT_EQ(chunk.level0[out], whole.level0[out]);
        const auto& live = chunk.live[out];
        const auto kept = whole.live[out].middleRows(next_row / tile, live.rows());
        EXPECT_TRUE((live || !kept).all()) << "a chunk drops a tile the whole record keeps, at row " << next_row;
      }
      EXPECT_EQ(chunk.schedule[0].weight, whole.schedule[static_cast<std::size_t>(next_row)].weight);
      next_row += rows;
    }
    EXPECT_EQ(next_row, kSamples);
    EXPECT_EQ(chunks, (kSamples + std::max(tile, max_rows / tile * tile) - 1) / std::max(tile, max_rows / tile * tile));
    EXPECT_FALSE(stream.next(chunk)) << "a finished stream stays finished";
  }

  Eigen::VectorXi fold(kSamples);
  for (int k = 0; k < kSamples; ++k) fold(k) = (k / 300) % 3;
  const CoefficientSums streamed = coefficientSums(m, std::vector<Eigen::MatrixXd>{u}, {y}, {fold}, 3);
  const CoefficientSums at_once = coefficientSums(m, {whole}, {y}, {fold}, 3);
  for (std::size_t g = 0; g < 3; ++g)
    for (std::size_t out = 0; out < 2; ++out) {
      const Eigen::MatrixXd& Js = streamed.groups[g].J[out];
      const Eigen::MatrixXd& Jw = at_once.groups[g].J[out];
      const Eigen::MatrixXd diff =
          Eigen::MatrixXd(Js.triangularView<Eigen::Lower>()) - Eigen::MatrixXd(Jw.triangularView<Eigen::Lower>());
      EXPECT_LT(diff.cwiseAbs().maxCoeff(), 1e-12 * Jw.cwiseAbs().maxCoeff()) << "group " << g << ", output " << out;
      EXPECT_LT((streamed.groups[g].Jh[out] - at_once.groups[g].Jh[out]).cwiseAbs().maxCoeff(),
                1e-12 * at_once.groups[g].Jh[out].cwiseAbs().maxCoeff());
      EXPECT_EQ(streamed.groups[g].count, at_once.groups[g].count);
    }

  DioPwlObfModel other = m;
  for (auto& block : other.coefficients)
    for (Eigen::VectorXd& c : block) c = -2.0 * c.reverse();
  const std::vector<Eigen::MatrixXd> both = eval::modelIncrements(std::vector<DioPwlObfModel>{m, other}, u);
  ASSERT_EQ(both.size(), 2u);
  const Eigen::MatrixXd di_m = modelIncrements(m, whole), di_other = modelIncrements(other, whole);
  EXPECT_LT((both[0] - di_m).cwiseAbs().maxCoeff(), 1e-12 * di_m.cwiseAbs().maxCoeff());
  EXPECT_LT((both[1] - di_other).cwiseAbs().maxCoeff(), 1e-12 * di_other.cwiseAbs().maxCoeff());
  EXPECT_GT((both[1] - both[0]).cwiseAbs().maxCoeff(), 0.1 * di_m.cwiseAbs().maxCoeff());

  eval::RegressorStream empty(m, Eigen::MatrixXd(0, 2));
  eval::ModelRegressors none;
  ASSERT_TRUE(empty.next(none)) << "an empty record gives one empty chunk";
  EXPECT_EQ(none.phi[0].rows(), 0);
  EXPECT_FALSE(empty.next(none));
}
