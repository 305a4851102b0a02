// Where a run's inputs lie against a model's training range and grid
// (InputsOutsideTraining, validation.hpp), and the warnings a user reads.
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include "plsa/eval/validation.hpp"

namespace plsa::eval {

namespace {

// The grid-node part of InputsOutsideTraining.
void gridCoverage(const PwlPartition& partition, const Eigen::MatrixXd& u, InputsOutsideTraining& out) {
  const auto n = static_cast<std::size_t>(u.cols());
  const double nan = std::numeric_limits<double>::quiet_NaN(), rows = static_cast<double>(u.rows());
  out.on_grid.assign(n, false);
  out.grid_low.assign(n, nan);
  out.grid_high.assign(n, nan);
  out.below_grid.assign(n, 0.0);
  out.above_grid.assign(n, 0.0);
  Eigen::Array<bool, Eigen::Dynamic, 1> beyond = Eigen::Array<bool, Eigen::Dynamic, 1>::Constant(u.rows(), false);
  if (partition.scheduling() == Scheduling::kInterpolated)
    for (std::size_t s = 0; s < partition.inputs().size(); ++s) {
      const auto c = static_cast<std::size_t>(partition.inputs()[s]);
      const std::vector<double>& nodes = partition.breakpoints()[s];
      if (c >= n || nodes.empty()) continue;
      out.on_grid[c] = true;
      out.grid_low[c] = nodes.front();
      out.grid_high[c] = nodes.back();
      const auto col = u.col(static_cast<Eigen::Index>(c)).array();
      const Eigen::Array<bool, Eigen::Dynamic, 1> below = col < nodes.front() - 1e-9;
      const Eigen::Array<bool, Eigen::Dynamic, 1> above = col > nodes.back() + 1e-9;
      out.below_grid[c] = static_cast<double>(below.count()) / rows;
      out.above_grid[c] = static_cast<double>(above.count()) / rows;
      beyond = beyond || below || above;
    }
  out.any_beyond_grid = static_cast<double>(beyond.count()) / rows;
}

}  // namespace

InputsOutsideTraining inputsOutsideTraining(const DioPwlObfModel& model, const Eigen::MatrixXd& u) {
  PLSA_CHECK(u.cols() == static_cast<Eigen::Index>(model.inputs.size()), "inputsOutsideTraining: one column per input");
  InputsOutsideTraining out;
  if (u.rows() == 0) return out;
  Eigen::Array<bool, Eigen::Dynamic, Eigen::Dynamic> outside(u.rows(), u.cols());
  for (Eigen::Index c = 0; c < u.cols(); ++c) {
    const auto [lo, hi] = model.trainingRange(static_cast<std::size_t>(c));
    outside.col(c) = (u.col(c).array() < lo - 1e-9) || (u.col(c).array() > hi + 1e-9);
    out.each.push_back(static_cast<double>(outside.col(c).count()) / static_cast<double>(u.rows()));
  }
  out.any = static_cast<double>(outside.rowwise().any().count()) / static_cast<double>(u.rows());
  gridCoverage(model.partition, u, out);
  return out;
}

std::vector<std::string> inputCoverageWarnings(const DioPwlObfModel& model, const InputsOutsideTraining& c) {
  std::vector<std::string> out;
  auto pct = [](double share) {
    char b[32];
    std::snprintf(b, sizeof b, "%.1f%%", 100.0 * share);
    return std::string(b);
  };
  auto num = [](double v) {
    char b[32];
    std::snprintf(b, sizeof b, "%g", v);
    return std::string(b);
  };
  for (std::size_t i = 0; i < model.inputs.size() && i < c.each.size(); ++i) {
    const std::string& name = model.inputs[i];
    const auto [lo, hi] = model.trainingRange(i);
    const std::string range = "training range [" + num(lo) + ", " + num(hi) + "]";
    if (i < c.on_grid.size() && c.on_grid[i]) {
      if (c.below_grid[i] > 0 || c.above_grid[i] > 0)
        out.push_back(name + " is below the training grid's lowest node " + num(c.grid_low[i]) + " on " +
                      pct(c.below_grid[i]) + " and above its highest node " + num(c.grid_high[i]) + " on " +
                      pct(c.above_grid[i]) + " of the samples, where the model holds the outer node's dynamics (" +
                      range + ", left on " + pct(c.each[i]) + ")");
    } else if (c.each[i] > 0) {
      out.push_back(name + " is outside its " + range + " on " + pct(c.each[i]) + " of the samples");
    }
  }
  return out;
}

}  // namespace plsa::eval
