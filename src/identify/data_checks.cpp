// Checks on the logs before identification: gross outliers and columns
// that never change, each refused with the column named.
#include "plsa/identify/pipeline.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "identification_run.hpp"

namespace plsa::identify {

std::string grossOutlier(const io::Log& log, const std::vector<std::string>& names) {
  for (const auto& name : names) {
    const Eigen::VectorXd x = log.column(name);
    if (x.size() < 3) continue;
    std::vector<double> sorted(x.data(), x.data() + x.size());
    std::sort(sorted.begin(), sorted.end());
    auto quantile = [&](double q) {
      return sorted[static_cast<std::size_t>(q * static_cast<double>(sorted.size() - 1))];
    };
    const double median = quantile(0.5), band = quantile(0.99) - quantile(0.01);
    if (!(band > 0)) continue;
    for (Eigen::Index k = 0; k < x.size(); ++k) {
      const double bands = std::abs(x(k) - median) / band;
      if (bands <= kGrossOutlierBands) continue;
      std::ostringstream msg;
      msg << log.source << ": data row " << k + 1 << ", column '" << name << "': " << x(k) << " lies ";
      if (std::isfinite(bands))
        msg << bands << " times";
      else
        msg << "beyond any multiple of";
      msg << " the width of the column's 1-99% band (" << quantile(0.01) << " to " << quantile(0.99)
          << ") from its median " << median;
      return msg.str();
    }
  }
  return {};
}

// Columns that never change, over every log: an output has no response to
// identify (its fit is undefined), and inputs that all hold drive none.
// Refused before any work, naming the columns (a wrong --inputs or
// --outputs name, typically).
bool holdsOneValue(const std::vector<Eigen::MatrixXd>& blocks, Eigen::Index j) {
  double lo = INFINITY, hi = -INFINITY;
  for (const auto& b : blocks)
    if (b.rows() > 0) lo = std::min(lo, b.col(j).minCoeff()), hi = std::max(hi, b.col(j).maxCoeff());
  return !(lo <= hi) || hi - lo <= 1e-12 * std::max(1.0, std::abs(hi));
}

void IdentificationRun::refuseStillColumns() const {
  for (std::size_t j = 0; j < o.outputs.size(); ++j)
    if (holdsOneValue(Y, static_cast<Eigen::Index>(j)))
      throw std::invalid_argument("identify: output '" + o.outputs[j] + "' holds " +
                                  formatNumber(Y[0](0, static_cast<Eigen::Index>(j))) +
                                  " in every sample of the logs: there is no response to identify (check --outputs)");
  bool any_moves = false;
  std::string names;
  for (std::size_t j = 0; j < o.inputs.size(); ++j) {
    any_moves = any_moves || !holdsOneValue(U, static_cast<Eigen::Index>(j));
    names += (names.empty() ? "" : ", ") + o.inputs[j];
  }
  if (!any_moves)
    throw std::invalid_argument("identify: the inputs (" + names +
                                ") hold one value each in every sample of the logs: nothing drives a response "
                                "(check --inputs)");
}

// A log given twice, or a copy under another name, would sit in the training
// and the held-out folds at once: cross-validation would score it on itself
// and choose a structure that only fits (a probe: Python's identify took the
// same path twice; the command line took a copy).
void IdentificationRun::refuseRepeatedLogs(const std::vector<io::Log>& logs) const {
  for (std::size_t i = 0; i < U.size(); ++i)
    for (std::size_t j = 0; j < i; ++j)
      if (U[i].rows() == U[j].rows() && U[i] == U[j] && Y[i] == Y[j])
        throw std::invalid_argument("identify: " + logs[i].source + " holds the same samples as " + logs[j].source +
                                    " (a log given twice, or a copy): cross-validation would score it on itself "
                                    "(give each once)");
}

// Columns whose values a least-squares fit cannot take: beyond 1e150 their
// squares overflow (the fits then fail as "regressors all zero"), and an
// output that moves by under 1e-150 has a spread whose square underflows.
// Refused before any work, naming the column.
void IdentificationRun::refuseUnfittableMagnitudes() const {
  auto check = [](const std::vector<Eigen::MatrixXd>& blocks, const std::vector<std::string>& names, bool output) {
    for (std::size_t j = 0; j < names.size(); ++j) {
      double largest = 0.0, lo = INFINITY, hi = -INFINITY;
      for (const auto& b : blocks) {
        if (b.rows() == 0) continue;
        const auto c = b.col(static_cast<Eigen::Index>(j));
        largest = std::max(largest, c.cwiseAbs().maxCoeff());
        lo = std::min(lo, c.minCoeff());
        hi = std::max(hi, c.maxCoeff());
      }
      if (largest > kLargestFittable)
        throw std::invalid_argument("identify: column '" + names[j] + "' reaches " + formatNumber(largest) +
                                    "; values beyond 1e150 cannot be fitted (their squares overflow): is it in "
                                    "the right unit?");
      if (output && hi > lo && hi - lo < 1.0 / kLargestFittable)
        throw std::invalid_argument("identify: output '" + names[j] + "' moves by only " + formatNumber(hi - lo) +
                                    "; under 1e-150 a fit cannot be computed (its square underflows): is it in "
                                    "the right unit?");
    }
  };
  check(U, o.inputs, false);
  check(Y, o.outputs, true);
}

}  // namespace plsa::identify
