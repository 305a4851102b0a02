#include "plsa/identify/coefficient_fit.hpp"

#include <climits>
#include <cmath>

#include "plsa/core/parallel_for.hpp"
#include "plsa/identify/lower_gram.hpp"
#include "tied_solve.hpp"

namespace plsa::identify {
namespace {

// Steps between two regions: cell moves per scheduling input plus direction flips.
int regionDistance(const PwlPartition& p, int a, int b) {
  int d = 0;
  for (std::size_t s = 0; s < p.inputs().size(); ++s) {
    d += std::abs(p.cellOf(a, s) - p.cellOf(b, s));
    d += p.fallingOf(a, s) != p.fallingOf(b, s) ? 1 : 0;
  }
  return d;
}

}  // namespace

void checkSampleWeights(const std::vector<Eigen::MatrixXd>& U, const SampleWeights& weights, const char* who) {
  if (weights.empty()) return;
  PLSA_CHECK(weights.size() == U.size(), std::string(who) + ": need one weight vector per record");
  for (std::size_t r = 0; r < U.size(); ++r)
    PLSA_CHECK(weights[r].size() == U[r].rows() && weights[r].allFinite() && (weights[r].array() >= 0).all(),
               std::string(who) + ": record " + std::to_string(r) + " needs one finite weight >= 0 per sample");
}

namespace {

CoefficientSums::Group emptyGroup(const DioPwlObfModel& model) {
  const int R = model.partition.regionCount();
  const int ny = model.outputCount();
  const bool joint =
      model.partition.scheduling() == Scheduling::kInterpolated || model.schedule_side == ScheduleSide::kInput;
  CoefficientSums::Group g;
  g.G.resize(static_cast<std::size_t>(ny));
  g.h.resize(static_cast<std::size_t>(ny));
  g.J.resize(static_cast<std::size_t>(ny));
  g.Jh.resize(static_cast<std::size_t>(ny));
  for (int out = 0; out < ny; ++out) {
    const auto oo = static_cast<std::size_t>(out);
    const int n = model.regressorSize(out);
    // Input side keeps only J: its G blocks are J's diagonal blocks.
    if (model.schedule_side != ScheduleSide::kInput) {
      g.G[oo].assign(static_cast<std::size_t>(R), Eigen::MatrixXd::Zero(n, n));
      g.h[oo].assign(static_cast<std::size_t>(R), Eigen::VectorXd::Zero(n));
    }
    if (joint) {
      g.J[oo] = Eigen::MatrixXd::Zero(R * n, R * n);
      g.Jh[oo] = Eigen::VectorXd::Zero(R * n);
    }
  }
  g.count.assign(static_cast<std::size_t>(R), 0.0);
  return g;
}

// Sample k's record: its weight (1 when `w` is null) and group (0 when `group` is null).
struct RecordWeights {
  const Eigen::VectorXd* w;
  const Eigen::VectorXi* group;
  double weightOf(Eigen::Index k) const { return w ? (*w)(k) : 1.0; }
  int groupOf(Eigen::Index k) const { return group ? (*group)(k) : 0; }
};

// Rows of the record a chunk of regressors covers, and the first that has an
// increment (a record's row 0 has none).
struct ChunkRows {
  Eigen::Index first, begin, end;
  explicit ChunkRows(const eval::ModelRegressors& reg)
      : first(reg.first_row),
        begin(std::max<Eigen::Index>(reg.first_row, 1)),
        end(reg.first_row + static_cast<Eigen::Index>(reg.schedule.size())) {}
};

// Each group's weighted sample count per region.
void countRegions(const eval::ModelRegressors& reg, const RecordWeights& rw, CoefficientSums& sums) {
  const ChunkRows rows(reg);
  for (Eigen::Index k = rows.begin; k < rows.end; ++k) {
    const ScheduleBlend& b = reg.schedule[static_cast<std::size_t>(k - rows.first)];
    std::vector<double>& count = sums.groups[static_cast<std::size_t>(rw.groupOf(k))].count;
    for (int m = 0; m < b.count; ++m)
      count[static_cast<std::size_t>(b.region[static_cast<std::size_t>(m)])] +=
          rw.weightOf(k) * b.weight[static_cast<std::size_t>(m)];
  }
}

// Input side, one output: every node's regressors side by side, one dense
// least-squares problem, the largest cost of identification. Over a tile of
// samples most nodes' regressors are negligible (ModelRegressors::live):
// each run of samples in one tile and group adds the Gram matrix of its live
// nodes' blocks, which changes no sum beyond rounding and cuts the work about
// twentyfold on a grid experiment. Y is the whole record; reg a chunk of it.
void accumulateInputSide(const DioPwlObfModel& model, const eval::ModelRegressors& reg, const Eigen::MatrixXd& Y,
                         const RecordWeights& rw, int out, CoefficientSums& sums) {
  const ChunkRows rows(reg);
  const Eigen::Index T = rows.end, tile = eval::ModelRegressors::kTileRows;
  const auto oo = static_cast<std::size_t>(out);
  const Eigen::MatrixXd& phi = reg.phi[oo];
  const Eigen::Index width = model.regressorSize(out);
  const auto nodes = static_cast<int>(phi.cols() / width);
  std::vector<int> active;
  Eigen::MatrixXd P, G;
  for (Eigen::Index a = rows.begin; a < T;) {
    Eigen::Index e = a + 1;
    while (e < T && (e - rows.first) % tile != 0 && rw.groupOf(e) == rw.groupOf(a)) ++e;
    const Eigen::Index len = e - a;
    active.clear();
    for (int node = 0; node < nodes; ++node)
      if (reg.live.empty() || reg.live[oo]((a - rows.first) / tile, node)) active.push_back(node);
    if (!active.empty()) {
      // The active nodes' regressors and, last, the increments: one Gram
      // holds P'P and (its last row) P'dy.
      const auto m = static_cast<Eigen::Index>(active.size()) * width;
      P.resize(len, m + 1);
      for (std::size_t i = 0; i < active.size(); ++i)
        P.middleCols(static_cast<Eigen::Index>(i) * width, width) =
            phi.block(a - rows.first, active[i] * width, len, width);
      P.col(m) = Y.col(out).segment(a, len) - Y.col(out).segment(a - 1, len);
      if (rw.w) P = rw.w->segment(a, len).cwiseSqrt().asDiagonal() * P;
      lowerGram(P, G);
      const auto h = G.row(m).head(m).transpose();
      CoefficientSums::Group& g = sums.groups[static_cast<std::size_t>(rw.groupOf(a))];
      // Active nodes ascend, so block (i, j), i >= j, lands in J's lower triangle.
      for (std::size_t i = 0; i < active.size(); ++i) {
        const Eigen::Index gi = static_cast<Eigen::Index>(i) * width, ji = active[i] * width;
        g.Jh[oo].segment(ji, width) += h.segment(gi, width);
        for (std::size_t j = 0; j <= i; ++j)
          g.J[oo].block(ji, active[j] * width, width, width) +=
              G.block(gi, static_cast<Eigen::Index>(j) * width, width, width);
      }
    }
    a = e;
  }
}

// Output side: each sample's outer product into the regions its schedule
// blends (and, interpolated, the joint problem's blocks).
void accumulateOutputSide(const DioPwlObfModel& model, const eval::ModelRegressors& reg, const Eigen::MatrixXd& Y,
                          const RecordWeights& rw, CoefficientSums& sums) {
  const bool joint = model.partition.scheduling() == Scheduling::kInterpolated;
  const ChunkRows rows(reg);
  for (Eigen::Index k = rows.begin; k < rows.end; ++k) {
    const double wk = rw.weightOf(k);
    if (wk == 0.0) continue;
    CoefficientSums::Group& g = sums.groups[static_cast<std::size_t>(rw.groupOf(k))];
    const ScheduleBlend& b = reg.schedule[static_cast<std::size_t>(k - rows.first)];
    for (int out = 0; out < model.outputCount(); ++out) {
      const auto oo = static_cast<std::size_t>(out);
      const auto phi = reg.phi[oo].row(k - rows.first).transpose();
      const double dy = Y(k, out) - Y(k - 1, out);
      const Eigen::MatrixXd outer = wk * phi * phi.transpose();
      const Eigen::Index n = phi.size();
      for (int i = 0; i < b.count; ++i) {
        const auto ra = static_cast<std::size_t>(b.region[static_cast<std::size_t>(i)]);
        const double wa = b.weight[static_cast<std::size_t>(i)];
        g.G[oo][ra] += wa * wa * outer;
        g.h[oo][ra] += wk * wa * dy * phi;
        if (!joint) continue;
        g.Jh[oo].segment(static_cast<Eigen::Index>(ra) * n, n) += wk * wa * dy * phi;
        for (int c = 0; c < b.count; ++c) {
          const auto rc = static_cast<std::size_t>(b.region[static_cast<std::size_t>(c)]);
          g.J[oo].block(static_cast<Eigen::Index>(ra) * n, static_cast<Eigen::Index>(rc) * n, n, n) +=
              wa * b.weight[static_cast<std::size_t>(c)] * outer;
        }
      }
    }
  }
}

// The terms of a record's rows that `reg` covers into the sums: sample k
// joins group(k) (group 0 when `group` is null), times its weight (1 when `w`
// is null). Y, w and group are the whole record's.
void accumulate(const DioPwlObfModel& model, const eval::ModelRegressors& reg, const Eigen::MatrixXd& Y,
                const Eigen::VectorXd* w, const Eigen::VectorXi* group, CoefficientSums& sums) {
  const RecordWeights rw{w, group};
  countRegions(reg, rw, sums);
  if (model.schedule_side != ScheduleSide::kInput) return accumulateOutputSide(model, reg, Y, rw, sums);
  // The outputs' problems are independent: one thread each.
  const auto ny = static_cast<std::size_t>(model.outputCount());
  parallelFor(ny, static_cast<int>(ny),
              [&](std::size_t out) { accumulateInputSide(model, reg, Y, rw, static_cast<int>(out), sums); });
}

// A record's outputs (model frame) against the model and its sample count.
void checkRecord(const DioPwlObfModel& model, const Eigen::MatrixXd& Y, Eigen::Index rows, std::size_t r,
                 const char* who) {
  PLSA_CHECK(Y.cols() == model.outputCount() && Y.rows() == rows,
             std::string(who) + ": record " + std::to_string(r) + " does not match the model's inputs and outputs");
  PLSA_CHECK(Y.allFinite(), std::string(who) + ": record " + std::to_string(r) + " has NaN or Inf outputs");
}

void checkInputs(const DioPwlObfModel& model, const Eigen::MatrixXd& U, std::size_t r, const char* who) {
  PLSA_CHECK(U.cols() == model.inputCount(),
             std::string(who) + ": record " + std::to_string(r) + " does not match the model's inputs and outputs");
}

void checkGroups(const Eigen::VectorXi& group, Eigen::Index rows, int groups, std::size_t r) {
  PLSA_CHECK(group.size() == rows && (group.array() >= 0).all() && (group.array() < groups).all(),
             "coefficientSums: record " + std::to_string(r) + " needs one group in [0, " + std::to_string(groups) +
                 ") per sample");
}

// A record's terms a chunk of regressors at a time (RegressorStream): memory
// of a chunk, not of the record.
void accumulateStreamed(const DioPwlObfModel& model, const Eigen::MatrixXd& U, const Eigen::MatrixXd& Y,
                        const Eigen::VectorXd* w, const Eigen::VectorXi* group, CoefficientSums& sums) {
  eval::RegressorStream stream(model, U);
  eval::ModelRegressors chunk;
  while (stream.next(chunk)) accumulate(model, chunk, Y, w, group, sums);
}

// Sums per group over records: record(r, Y_r, sums) adds record r's terms,
// after the checks every record shares.
template <typename Record>
CoefficientSums groupedSums(const DioPwlObfModel& model, std::size_t records,
                            const std::vector<Eigen::MatrixXd>& Y_logged, const std::vector<Eigen::VectorXi>& group,
                            int groups, const Record& record) {
  PLSA_CHECK(records > 0 && records == Y_logged.size() && group.size() == Y_logged.size(),
             "coefficientSums: need one input record (or regressor set), output record and group vector per record");
  PLSA_CHECK(groups >= 1, "coefficientSums: need at least one group");
  const std::vector<Eigen::MatrixXd> Y = model.toModelFrame(Y_logged);
  CoefficientSums sums;
  sums.groups.assign(static_cast<std::size_t>(groups), emptyGroup(model));
  for (std::size_t r = 0; r < Y.size(); ++r) {
    checkGroups(group[r], Y[r].rows(), groups, r);
    record(r, Y[r], sums);
  }
  return sums;
}

}  // namespace

CoefficientSums coefficientSums(const DioPwlObfModel& model, const std::vector<eval::ModelRegressors>& regressors,
                                const std::vector<Eigen::MatrixXd>& Y_logged, const std::vector<Eigen::VectorXi>& group,
                                int groups) {
  return groupedSums(
      model, regressors.size(), Y_logged, group, groups,
      [&](std::size_t r, const Eigen::MatrixXd& Y, CoefficientSums& sums) {
        PLSA_CHECK(regressors[r].first_row == 0,
                   "coefficientSums: record " + std::to_string(r) + "'s regressors are a chunk, not the whole record");
        checkRecord(model, Y, static_cast<Eigen::Index>(regressors[r].schedule.size()), r, "coefficientSums");
        accumulate(model, regressors[r], Y, nullptr, &group[r], sums);
      });
}

CoefficientSums coefficientSums(const DioPwlObfModel& model, const std::vector<Eigen::MatrixXd>& U,
                                const std::vector<Eigen::MatrixXd>& Y_logged, const std::vector<Eigen::VectorXi>& group,
                                int groups) {
  return groupedSums(model, U.size(), Y_logged, group, groups,
                     [&](std::size_t r, const Eigen::MatrixXd& Y, CoefficientSums& sums) {
                       checkInputs(model, U[r], r, "coefficientSums");
                       checkRecord(model, Y, U[r].rows(), r, "coefficientSums");
                       accumulateStreamed(model, U[r], Y, nullptr, &group[r], sums);
                     });
}

CoefficientFitReport fitCoefficients(DioPwlObfModel& model, const std::vector<Eigen::MatrixXd>& U,
                                     const std::vector<Eigen::MatrixXd>& Y, const CoefficientFitOptions& o,
                                     const SampleWeights& weights) {
  PLSA_CHECK(!U.empty() && U.size() == Y.size(), "fitCoefficients: need matching input and output records");
  checkSampleWeights(U, weights, "fitCoefficients");
  CoefficientSums sums;
  sums.groups.assign(1, emptyGroup(model));
  const std::vector<Eigen::MatrixXd> Ym = model.toModelFrame(Y);
  for (std::size_t r = 0; r < U.size(); ++r) {
    checkInputs(model, U[r], r, "fitCoefficients");
    checkRecord(model, Ym[r], U[r].rows(), r, "fitCoefficients");
    accumulateStreamed(model, U[r], Ym[r], weights.empty() ? nullptr : &weights[r], nullptr, sums);
  }
  const LevelRecords records{U, Ym, weights};
  return solveCoefficients(model, sums, -1, o, &records);
}

namespace {

// Every group's sums but `leave_out`'s (-1: none left out); on the input side
// the per-node blocks G and h read off the joint problem's diagonal.
CoefficientSums::Group summedGroups(const DioPwlObfModel& model, const CoefficientSums& sums, int leave_out,
                                    bool joint) {
  const int R = model.partition.regionCount(), ny = model.outputCount();
  CoefficientSums::Group total = emptyGroup(model);
  for (std::size_t gi = 0; gi < sums.groups.size(); ++gi) {
    if (static_cast<int>(gi) == leave_out) continue;
    const CoefficientSums::Group& g = sums.groups[gi];
    for (int out = 0; out < ny; ++out) {
      const auto oo = static_cast<std::size_t>(out);
      for (std::size_t l = 0; l < total.G[oo].size(); ++l) {
        total.G[oo][l] += g.G[oo][l];
        total.h[oo][l] += g.h[oo][l];
      }
      if (joint) {
        total.J[oo] += g.J[oo];
        total.Jh[oo] += g.Jh[oo];
      }
    }
    for (int l = 0; l < R; ++l) total.count[static_cast<std::size_t>(l)] += g.count[static_cast<std::size_t>(l)];
  }
  if (model.schedule_side != ScheduleSide::kInput) return total;
  for (int out = 0; out < ny; ++out) {
    const auto oo = static_cast<std::size_t>(out);
    const int n = model.regressorSize(out);
    total.J[oo] = Eigen::MatrixXd(total.J[oo].selfadjointView<Eigen::Lower>());
    total.G[oo].resize(static_cast<std::size_t>(R));
    total.h[oo].assign(static_cast<std::size_t>(R), Eigen::VectorXd::Zero(n));
    for (int l = 0; l < R; ++l) {
      total.G[oo][static_cast<std::size_t>(l)] = total.J[oo].block(l * n, l * n, n, n);
      total.h[oo][static_cast<std::size_t>(l)] = total.Jh[oo].segment(l * n, n);
    }
  }
  return total;
}

// Which regions have the samples for a fit of their own; records each
// region's sample count in the model.
std::vector<bool> regionsWithOwnFit(DioPwlObfModel& model, const std::vector<double>& count,
                                    const CoefficientFitOptions& o) {
  const int R = model.partition.regionCount();
  std::vector<bool> own(static_cast<std::size_t>(R), false);
  int max_params = 0;
  for (int out = 0; out < model.outputCount(); ++out) max_params = std::max(max_params, model.regressorSize(out));
  for (int l = 0; l < R; ++l) {
    own[static_cast<std::size_t>(l)] = count[static_cast<std::size_t>(l)] >= o.min_samples_per_parameter * max_params;
    model.region_fits[static_cast<std::size_t>(l)].samples =
        static_cast<int>(std::lround(count[static_cast<std::size_t>(l)]));
  }
  return own;
}

// One output's coefficients in every region with its own fit, each pulled
// toward the global solution (the blended model's: all nodes equal, when
// joint); returns the global solution, which regions without a fit fall back on.
Eigen::VectorXd solveOutput(DioPwlObfModel& model, CoefficientSums::Group& total, int out, bool joint,
                            const std::vector<bool>& own, const CoefficientFitOptions& o) {
  const int R = model.partition.regionCount();
  const auto oo = static_cast<std::size_t>(out);
  const int n = model.regressorSize(out);
  const auto& G = total.G[oo];
  const auto& h = total.h[oo];
  Eigen::MatrixXd& J = total.J[oo];
  Eigen::VectorXd& Jh = total.Jh[oo];
  Eigen::MatrixXd Gs = Eigen::MatrixXd::Zero(n, n);
  Eigen::VectorXd hs = Eigen::VectorXd::Zero(n);
  for (int l = 0; l < R; ++l) {
    Gs += G[static_cast<std::size_t>(l)];
    hs += h[static_cast<std::size_t>(l)];
  }
  PLSA_CHECK(std::isfinite(Gs.trace()),
             "fitCoefficients: the regressors are not finite (an input, or an option scaled by one, beyond range)");
  PLSA_CHECK(Gs.trace() > 0,
             "fitCoefficients: the regressors are all zero: no training sample in this fit, or inputs that never move");
  const double scale = Gs.trace() / n;
  Gs.diagonal().array() += o.ridge * scale;
  Eigen::VectorXd global;
  if (!joint) {
    global = Gs.ldlt().solve(hs);
  } else {
    Eigen::MatrixXd Gsum = Eigen::MatrixXd::Zero(n, n);
    for (int a = 0; a < R; ++a)
      for (int c = 0; c < R; ++c) Gsum += J.block(a * n, c * n, n, n);
    Eigen::VectorXd hsum = Eigen::VectorXd::Zero(n);
    for (int a = 0; a < R; ++a) hsum += Jh.segment(a * n, n);
    Gsum.diagonal().array() += o.ridge * scale;
    global = Gsum.ldlt().solve(hsum);
  }
  if (joint) {
    for (int l = 0; l < R; ++l) {
      const double sl = std::max(G[static_cast<std::size_t>(l)].trace() / n, 1e-12 * scale);
      const double w = o.pull_to_global * (own[static_cast<std::size_t>(l)] ? sl : scale);
      J.block(l * n, l * n, n, n).diagonal().array() += w;
      Jh.segment(l * n, n) += w * global;
    }
    const Eigen::VectorXd c = J.ldlt().solve(Jh);
    for (int l = 0; l < R; ++l) model.coefficients[static_cast<std::size_t>(l)][oo] = c.segment(l * n, n);
    return global;
  }
  for (int l = 0; l < R; ++l) {
    const auto ll = static_cast<std::size_t>(l);
    if (!own[ll]) continue;
    Eigen::MatrixXd Gl = G[ll];
    const double sl = std::max(Gl.trace() / n, 1e-12 * scale);
    Gl.diagonal().array() += o.pull_to_global * sl;
    model.coefficients[ll][oo] = Gl.ldlt().solve(h[ll] + o.pull_to_global * sl * global);
  }
  return global;
}

// Regions without a fit of their own take the mean of their nearest fitted
// regions' coefficients, or the global ones when none is fitted; each says so.
CoefficientFitReport fallBack(DioPwlObfModel& model, const std::vector<bool>& own,
                              const std::vector<Eigen::VectorXd>& global) {
  const int R = model.partition.regionCount(), ny = model.outputCount();
  CoefficientFitReport report;
  for (int l = 0; l < R; ++l) {
    const auto ll = static_cast<std::size_t>(l);
    if (own[ll]) {
      ++report.regions_fitted;
      continue;
    }
    ++report.regions_fallback;
    int best = INT_MAX;
    std::vector<int> nearest;
    for (int m = 0; m < R; ++m) {
      if (!own[static_cast<std::size_t>(m)]) continue;
      const int d = regionDistance(model.partition, l, m);
      if (d < best) {
        best = d;
        nearest.clear();
      }
      if (d == best) nearest.push_back(m);
    }
    RegionFit& fit = model.region_fits[ll];
    const std::string where = model.partition.describe(l, model.inputs);
    if (nearest.empty()) {
      for (int out = 0; out < ny; ++out)
        model.coefficients[ll][static_cast<std::size_t>(out)] = global[static_cast<std::size_t>(out)];
      fit.fallback_from = -2;
      fit.note = "too little data (" + std::to_string(fit.samples) + " samples): global linear coefficients";
    } else {
      for (int out = 0; out < ny; ++out) {
        Eigen::VectorXd acc = Eigen::VectorXd::Zero(model.regressorSize(out));
        for (int m : nearest) acc += model.coefficients[static_cast<std::size_t>(m)][static_cast<std::size_t>(out)];
        model.coefficients[ll][static_cast<std::size_t>(out)] = acc / static_cast<double>(nearest.size());
      }
      fit.fallback_from = nearest.front();
      fit.note = "too little data (" + std::to_string(fit.samples) + " samples): mean of " +
                 std::to_string(nearest.size()) + " nearest fitted region(s), first " + std::to_string(nearest.front());
    }
    report.notes.push_back("region " + std::to_string(l) + " (" + where + "): " + fit.note);
  }
  return report;
}

}  // namespace

CoefficientFitReport solveGroup(DioPwlObfModel& model, CoefficientSums::Group& total, bool joint,
                                const CoefficientFitOptions& o) {
  const int R = model.partition.regionCount();
  const int ny = model.outputCount();
  model.output_level.clear();  // it belongs to the old coefficients
  model.coefficients.assign(static_cast<std::size_t>(R), std::vector<Eigen::VectorXd>(static_cast<std::size_t>(ny)));
  model.region_fits.assign(static_cast<std::size_t>(R), RegionFit{});
  const std::vector<bool> own = regionsWithOwnFit(model, total.count, o);
  std::vector<Eigen::VectorXd> global(static_cast<std::size_t>(ny));
  for (int out = 0; out < ny; ++out)
    global[static_cast<std::size_t>(out)] = solveOutput(model, total, out, joint, own, o);
  return fallBack(model, own, global);
}

namespace {

// Interpolated and input-side structures solve one joint problem per output.
bool jointProblem(const DioPwlObfModel& model) {
  return model.partition.scheduling() == Scheduling::kInterpolated || model.schedule_side == ScheduleSide::kInput;
}

void checkSumsFit(const DioPwlObfModel& model, const CoefficientSums& sums, const char* who) {
  PLSA_CHECK(static_cast<int>(sums.groups.front().count.size()) == model.partition.regionCount() &&
                 static_cast<int>(sums.groups.front().J.size()) == model.outputCount(),
             std::string(who) + ": the sums were made for another model structure");
}

// Fold fits share one structure: the regressors are made from the first.
void checkSameStructure(const std::vector<DioPwlObfModel>& fits) {
  const DioPwlObfModel& a = fits.front();
  for (std::size_t f = 1; f < fits.size(); ++f) {
    const DioPwlObfModel& b = fits[f];
    bool same = b.inputCount() == a.inputCount() && b.outputCount() == a.outputCount() &&
                b.schedule_side == a.schedule_side && b.partition.scheduling() == a.partition.scheduling() &&
                b.partition.regionCount() == a.partition.regionCount();
    for (int o = 0; same && o < a.outputCount(); ++o) same = b.regressorSize(o) == a.regressorSize(o);
    PLSA_CHECK(same,
               "solveFoldCoefficients: fold " + std::to_string(f) + "'s model has another structure than fold 0's");
  }
}

}  // namespace

CoefficientFitReport solveCoefficients(DioPwlObfModel& model, const CoefficientSums& sums, int leave_out,
                                       const CoefficientFitOptions& o, const LevelRecords* levels) {
  PLSA_CHECK(!sums.groups.empty() && leave_out >= -1 && leave_out < static_cast<int>(sums.groups.size()),
             "solveCoefficients: group to leave out must be -1 or one of the sums' groups");
  checkSumsFit(model, sums, "solveCoefficients");
  const bool joint = jointProblem(model);
  CoefficientSums::Group total = summedGroups(model, sums, leave_out, joint);
  if (o.slow_mode.poles.empty()) return solveGroup(model, total, joint, o);
  const SampleWeights none;
  return solveTied({{model, total, levels ? levels->weights : none}}, o, levels ? &levels->U : nullptr,
                   levels ? &levels->Y : nullptr)
      .front();
}

std::vector<CoefficientFitReport> solveFoldCoefficients(std::vector<DioPwlObfModel>& fits, const CoefficientSums& sums,
                                                        const CoefficientFitOptions& o, const FoldRecords& folds) {
  PLSA_CHECK(!fits.empty() && fits.size() <= sums.groups.size() && folds.weights.size() == fits.size(),
             "solveFoldCoefficients: " + std::to_string(fits.size()) + " fold models, " +
                 std::to_string(folds.weights.size()) + " weight sets and " + std::to_string(sums.groups.size()) +
                 " groups of sums: need a model and a weight set per fold, at most one fold per group");
  checkSameStructure(fits);
  checkSumsFit(fits.front(), sums, "solveFoldCoefficients");
  std::vector<CoefficientFitReport> reports;
  if (o.slow_mode.poles.empty()) {
    for (std::size_t f = 0; f < fits.size(); ++f)
      reports.push_back(solveCoefficients(fits[f], sums, static_cast<int>(f), o));
    return reports;
  }
  const bool joint = jointProblem(fits.front());
  std::vector<CoefficientSums::Group> totals;
  for (std::size_t f = 0; f < fits.size(); ++f)
    totals.push_back(summedGroups(fits[f], sums, static_cast<int>(f), joint));
  std::vector<TiedFit> tied;
  for (std::size_t f = 0; f < fits.size(); ++f) tied.push_back({fits[f], totals[f], folds.weights[f]});
  return solveTied(tied, o, &folds.U, &folds.Y);
}

void fitOutputLevel(DioPwlObfModel& model, const std::vector<Eigen::MatrixXd>& U,
                    const std::vector<Eigen::MatrixXd>& Y_logged, const SampleWeights& weights,
                    const std::vector<Eigen::MatrixXd>& increments) {
  PLSA_CHECK(model.schedule_side == ScheduleSide::kInput, "fitOutputLevel: needs an input-side model");
  PLSA_CHECK(!U.empty() && U.size() == Y_logged.size(), "fitOutputLevel: need matching input and output records");
  checkSampleWeights(U, weights, "fitOutputLevel");
  PLSA_CHECK(increments.empty() || increments.size() == U.size(),
             "fitOutputLevel: need one increment record per record");
  const std::vector<Eigen::MatrixXd> Y = model.toModelFrame(Y_logged);
  Eigen::VectorXd sum = Eigen::VectorXd::Zero(model.outputCount());
  double n = 0.0;
  for (std::size_t r = 0; r < U.size(); ++r) {
    PLSA_CHECK(Y[r].cols() == model.outputCount() && Y[r].rows() == U[r].rows() && Y[r].allFinite(),
               "fitOutputLevel: record " + std::to_string(r) + " does not match the model's outputs or has NaN");
    if (U[r].rows() == 0) continue;
    const Eigen::MatrixXd residual =
        Y[r] - (increments.empty() ? eval::modelLevels(model, U[r]) : eval::modelLevels(model, U[r], increments[r]));
    if (weights.empty()) {
      sum += residual.colwise().sum().transpose();
      n += static_cast<double>(U[r].rows());
    } else {
      sum += residual.transpose() * weights[r];
      n += weights[r].sum();
    }
  }
  PLSA_CHECK(n > 0, "fitOutputLevel: no samples (or all weights zero)");
  model.output_level.resize(static_cast<std::size_t>(model.outputCount()));
  for (int o = 0; o < model.outputCount(); ++o) model.output_level[static_cast<std::size_t>(o)] = sum(o) / n;
}

}  // namespace plsa::identify
