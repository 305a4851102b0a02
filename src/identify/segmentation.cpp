#include "plsa/identify/segmentation.hpp"

#include <algorithm>
#include <cmath>
#include <map>

#include "plsa/core/check.hpp"
#include "plsa/core/median.hpp"

namespace plsa::identify {

std::vector<LocalDataSet> segmentSteps(const Eigen::MatrixXd& ref, double min_step, Eigen::Index min_length) {
  PLSA_CHECK(min_step > 0, "segmentSteps: min_step must be positive");
  std::vector<Eigen::Index> changes;
  for (Eigen::Index k = 1; k < ref.rows(); ++k)
    if ((ref.row(k) - ref.row(k - 1)).cwiseAbs().maxCoeff() > min_step) changes.push_back(k);
  std::vector<LocalDataSet> out;
  for (std::size_t i = 0; i < changes.size(); ++i) {
    const Eigen::Index b = changes[i];
    const Eigen::Index e = i + 1 < changes.size() ? changes[i + 1] : ref.rows();
    if (e - b < min_length) continue;
    const Eigen::RowVectorXd d = ref.row(b) - ref.row(b - 1);
    int moved = 0, which = 0;
    for (Eigen::Index j = 0; j < d.size(); ++j)
      if (std::abs(d(j)) > min_step) {
        ++moved;
        which = static_cast<int>(j);
      }
    if (moved != 1) continue;
    out.push_back({b, e, which, ref(b - 1, which), ref(b, which)});
  }
  return out;
}

namespace {

// The noise of a column, from its sample-to-sample differences (median
// absolute difference over sqrt(2), scaled to a standard deviation): the
// rare steps of a staircase do not move it.
double differenceNoise(const Eigen::VectorXd& u) {
  if (u.size() < 3) return 0.0;
  std::vector<double> d(static_cast<std::size_t>(u.size() - 1));
  for (Eigen::Index k = 1; k < u.size(); ++k) d[static_cast<std::size_t>(k - 1)] = std::abs(u(k) - u(k - 1));
  return 1.4826 * median(std::move(d)) / std::sqrt(2.0);
}

struct SteadyRun {
  Eigen::Index begin = 0, end = 0;  // [begin, end)
  double level = 0.0;               // its mean
  Eigen::Index length() const { return end - begin; }
};

// Maximal runs within `tol` of their own running mean.
std::vector<SteadyRun> steadyRuns(const Eigen::VectorXd& u, double tol) {
  std::vector<SteadyRun> runs;
  SteadyRun run{0, 0, 0.0};
  double sum = 0.0;
  for (Eigen::Index k = 0; k < u.size(); ++k) {
    if (run.length() > 0 && std::abs(u(k) - sum / static_cast<double>(run.length())) > tol) {
      run.level = sum / static_cast<double>(run.length());
      runs.push_back(run);
      run = SteadyRun{k, k, 0.0};
      sum = 0.0;
    }
    sum += u(k);
    ++run.end;
  }
  if (run.length() > 0) {
    run.level = sum / static_cast<double>(run.length());
    runs.push_back(run);
  }
  return runs;
}

// The plateaus' levels, each replaced by the mean of the plateau levels in
// its band (sorted levels closer than `band` to the one before are one).
void shareLevels(std::vector<SteadyRun>& runs, Eigen::Index min_hold, double band) {
  std::vector<double> levels;
  for (const SteadyRun& r : runs)
    if (r.length() >= min_hold) levels.push_back(r.level);
  std::sort(levels.begin(), levels.end());
  std::vector<std::pair<double, double>> bands;  // [lowest, mean] per band
  for (std::size_t i = 0, n = 0; i < levels.size(); ++i) {
    if (i == 0 || levels[i] - levels[i - 1] > band) {
      bands.push_back({levels[i], 0.0});
      n = 0;
    }
    ++n;
    bands.back().second += (levels[i] - bands.back().second) / static_cast<double>(n);
  }
  for (SteadyRun& r : runs) {
    if (r.length() < min_hold) continue;
    auto b = std::upper_bound(bands.begin(), bands.end(), r.level,
                              [](double v, const std::pair<double, double>& x) { return v < x.first; });
    r.level = std::prev(b)->second;
  }
}

}  // namespace

Eigen::MatrixXd plateauReference(const Eigen::MatrixXd& inputs, Eigen::Index min_hold, double resolution,
                                 double noise_multiple) {
  PLSA_CHECK(min_hold >= 1 && resolution > 0 && noise_multiple > 0,
             "plateauReference: the hold, resolution and noise multiple must be positive");
  Eigen::MatrixXd ref = inputs;
  for (Eigen::Index j = 0; j < inputs.cols(); ++j) {
    const Eigen::VectorXd u = inputs.col(j);
    const double tol = std::max(noise_multiple * differenceNoise(u), resolution / 2);
    std::vector<SteadyRun> runs = steadyRuns(u, tol);
    Eigen::Index held = 0;
    for (const SteadyRun& r : runs)
      if (r.length() >= min_hold) held += r.length();
    // A staircase holds its levels most of the time; a random walk or an
    // excitation holds now and then by chance: no plateaus to read.
    if (held == 0 || 2 * held < u.size()) continue;
    shareLevels(runs, min_hold, tol);
    double next = 0.0;  // the level of the plateau after, from the end back
    for (auto r = runs.rbegin(); r != runs.rend(); ++r)
      if (r->length() >= min_hold) {
        next = r->level;
        break;
      }
    for (auto r = runs.rbegin(); r != runs.rend(); ++r) {
      if (r->length() >= min_hold) next = r->level;
      ref.col(j).segment(r->begin, r->length()).setConstant(next);
    }
  }
  return ref;
}

std::vector<std::vector<double>> referenceLevels(const Eigen::MatrixXd& ref, double resolution,
                                                 Eigen::Index min_length) {
  PLSA_CHECK(resolution > 0, "referenceLevels: resolution must be positive");
  std::vector<std::vector<double>> levels(static_cast<std::size_t>(ref.cols()));
  for (Eigen::Index j = 0; j < ref.cols(); ++j) {
    std::map<long long, double> held;  // rounded key -> the level as held
    Eigen::Index run = 1;
    for (Eigen::Index k = 1; k <= ref.rows(); ++k) {
      if (k < ref.rows() && std::abs(ref(k, j) - ref(k - 1, j)) <= resolution / 2) {
        ++run;
        continue;
      }
      if (run >= min_length) held.emplace(std::llround(ref(k - 1, j) / resolution), ref(k - 1, j));
      run = 1;
    }
    for (const auto& [key, value] : held) levels[static_cast<std::size_t>(j)].push_back(value);
  }
  return levels;
}

}  // namespace plsa::identify
