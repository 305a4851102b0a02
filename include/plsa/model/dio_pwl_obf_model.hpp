// An identified DIO-PWL-OBF model (method notes): one OBF pole set per
// input-output pair, a PWL partition of the scheduling inputs, and a
// coefficient vector per region and output:
//   y_k = y_{k-1} + sum_j c_{l(k), o, j}^T [B_{o,j}(q) du_j]_k.
#pragma once

#include <limits>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "plsa/core/check.hpp"
#include "plsa/core/pole_set.hpp"
#include "plsa/model/pwl_partition.hpp"
#include "plsa/obf/obf_bank.hpp"

namespace plsa {

/// How a region's coefficients came about.
struct RegionFit {
  int samples = 0;         ///< training samples that fell in the region
  int fallback_from = -1;  ///< -1: fitted on its own; else the source (region index, or -2 = global)
  std::string note;
};

struct DioPwlObfModel {
  static constexpr int kSchemaVersion = 1;

  double sample_time_s = 1.0 / 80.0;
  std::vector<std::string> inputs;   ///< column names of the inputs
  std::vector<std::string> outputs;  ///< column names of the outputs
  std::string input_unit = "bar";
  std::string output_unit = "deg";
  double input_min = -std::numeric_limits<double>::infinity();  ///< accepted input range
  double input_max = std::numeric_limits<double>::infinity();
  std::vector<std::vector<PoleSet>> poles;  ///< [output][input]
  PwlPartition partition = PwlPartition::single();
  std::vector<std::vector<Eigen::VectorXd>> coefficients;  ///< [region][output]
  std::vector<RegionFit> region_fits;                       ///< [region]

  int inputCount() const { return static_cast<int>(inputs.size()); }
  int outputCount() const { return static_cast<int>(outputs.size()); }
  int regressorSize(int output) const {
    int n = 0;
    for (const auto& p : poles[static_cast<std::size_t>(output)]) n += p.size();
    return n;
  }

  /// Throws std::invalid_argument naming the first inconsistency.
  void validate() const {
    require(sample_time_s > 0 && std::isfinite(sample_time_s), "model: sample_time_s must be positive");
    require(!inputs.empty(), "model: no inputs");
    require(!outputs.empty(), "model: no outputs");
    require(input_min < input_max, "model: input_min must be below input_max");
    require(poles.size() == outputs.size(), "model: need one row of pole sets per output");
    for (std::size_t o = 0; o < poles.size(); ++o) {
      require(poles[o].size() == inputs.size(),
              "model: output '" + outputs[o] + "' needs one pole set per input");
      for (std::size_t j = 0; j < poles[o].size(); ++j)
        require(!poles[o][j].empty(), "model: empty pole set for " + inputs[j] + " -> " + outputs[o]);
    }
    require(partition.maxInputIndex() < inputCount(), "model: the partition schedules on an input that does not exist");
    const auto regions = static_cast<std::size_t>(partition.regionCount());
    require(coefficients.size() == regions, "model: " + std::to_string(coefficients.size()) +
                                                " coefficient blocks for " + std::to_string(regions) + " regions");
    require(region_fits.size() == regions, "model: region_fits has the wrong length");
    for (std::size_t r = 0; r < regions; ++r) {
      require(coefficients[r].size() == outputs.size(),
              "model: region " + std::to_string(r) + " needs coefficients for every output");
      for (std::size_t o = 0; o < outputs.size(); ++o) {
        require(coefficients[r][o].size() == regressorSize(static_cast<int>(o)),
                "model: region " + std::to_string(r) + ", output '" + outputs[o] + "' has " +
                    std::to_string(coefficients[r][o].size()) + " coefficients, expected " +
                    std::to_string(regressorSize(static_cast<int>(o))));
        require(coefficients[r][o].allFinite(),
                "model: region " + std::to_string(r) + ", output '" + outputs[o] + "' has a NaN or Inf coefficient");
      }
    }
  }
};

/// OBF regressors of every output and the region of every sample, for an
/// input record u (T x n_u) starting at rest. At sample k the filters have
/// seen du_0..du_{k-1} and the region is scheduled on u_{k-1} (strictly causal).
struct ModelRegressors {
  std::vector<Eigen::MatrixXd> phi;    ///< [output] T x regressorSize(o)
  std::vector<ScheduleBlend> schedule; ///< [T] regions and weights
};

inline ModelRegressors modelRegressors(const std::vector<std::vector<PoleSet>>& poles, const PwlPartition& partition,
                                       const Eigen::MatrixXd& u) {
  require(!poles.empty(), "modelRegressors: no outputs");
  require(u.allFinite(), "modelRegressors: the inputs contain NaN or Inf");
  const Eigen::Index T = u.rows();
  const auto n_u = static_cast<std::size_t>(u.cols());
  ModelRegressors out;
  out.schedule.resize(static_cast<std::size_t>(T));
  DirectionState dir;
  Eigen::RowVectorXd du = Eigen::RowVectorXd::Zero(u.cols());
  for (Eigen::Index k = 0; k < T; ++k) {
    const Eigen::Index prev = k == 0 ? 0 : k - 1;
    if (k >= 2) du = u.row(k - 1) - u.row(k - 2);
    if (k >= 2) partition.updateDirections(du, dir);
    partition.blend(u.row(prev), dir, out.schedule[static_cast<std::size_t>(k)]);
  }
  for (const auto& row : poles) {
    require(row.size() == n_u, "modelRegressors: need one pole set per input");
    int width = 0;
    for (const auto& p : row) width += p.size();
    Eigen::MatrixXd phi(T, width);
    int offset = 0;
    for (std::size_t j = 0; j < n_u; ++j) {
      ObfBank<> bank(row[j]);
      const int n = bank.size();
      for (Eigen::Index k = 0; k < T; ++k) {
        phi.block(k, offset, 1, n) = bank.state().transpose();
        const double d = k == 0 ? 0.0 : u(k, static_cast<Eigen::Index>(j)) - u(k - 1, static_cast<Eigen::Index>(j));
        bank.step(d);
      }
      offset += n;
    }
    out.phi.push_back(std::move(phi));
  }
  return out;
}

/// The model's predicted increments dyhat (T x n_y) for an input record.
inline Eigen::MatrixXd modelIncrements(const DioPwlObfModel& model, const Eigen::MatrixXd& u) {
  require(u.cols() == model.inputCount(), "modelIncrements: the record has " + std::to_string(u.cols()) +
                                              " inputs, the model " + std::to_string(model.inputCount()));
  const ModelRegressors reg = modelRegressors(model.poles, model.partition, u);
  Eigen::MatrixXd dy(u.rows(), model.outputCount());
  for (Eigen::Index k = 0; k < u.rows(); ++k) {
    const ScheduleBlend& b = reg.schedule[static_cast<std::size_t>(k)];
    for (int o = 0; o < model.outputCount(); ++o) {
      double v = 0.0;
      for (int m = 0; m < b.count; ++m)
        v += b.weight[static_cast<std::size_t>(m)] *
             reg.phi[static_cast<std::size_t>(o)].row(k).dot(
                 model.coefficients[static_cast<std::size_t>(b.region[static_cast<std::size_t>(m)])][static_cast<std::size_t>(o)]);
      dy(k, o) = v;
    }
  }
  return dy;
}

}  // namespace plsa
