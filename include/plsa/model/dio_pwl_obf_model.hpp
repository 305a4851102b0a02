// An identified DIO-PWL-OBF model (method notes): one OBF pole set per
// input-output pair, a PWL partition of the scheduling inputs, and a
// coefficient vector per region and output:
//   y_k = y_{k-1} + sum_j c_{l(k), o, j}^T [B_{o,j}(q) du_j]_k.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Dense>

#include "plsa/core/check.hpp"
#include "plsa/core/number_text.hpp"
#include "plsa/core/pole_set.hpp"
#include "plsa/model/input_shaping.hpp"
#include "plsa/model/output_frame.hpp"
#include "plsa/model/pwl_partition.hpp"

namespace plsa {

/// How a region's coefficients came about.
struct RegionFit {
  int samples = 0;         ///< training samples that fell in the region
  int fallback_from = -1;  ///< -1: fitted on its own; else the source (region index, or -2 = global)
  std::string note;
};

/// Where the schedule acts. Output side (the paper): the filters run on the
/// input increments and the region's coefficients weigh their outputs. Input
/// side (plsa, interpolated scheduling): each grid node filters the increments
/// of its own weight times the played input, w_n(s) v_j, so the increments are
/// exact differences of one static map followed by the filters, and free
/// simulation cannot drift however the inputs wander (docs/identification.md).
enum class ScheduleSide { kOutput, kInput };

struct DioPwlObfModel {
  /// Model files this build writes; it reads 1 (fields added since then take
  /// the meaning they had before) and 2 (every field required, unknown keys refused).
  static constexpr int kSchemaVersion = 2;
  /// Most poles one bank takes: identification fits at most 20 (plus a slow
  /// pole); a bank's set-up grows with the square of its poles.
  static constexpr std::size_t kMaxPolesPerBank = 64;

  double sample_time_s = 1.0 / 80.0;
  std::vector<std::string> inputs;   ///< column names of the inputs
  std::vector<std::string> outputs;  ///< column names of the outputs
  std::string input_unit = "bar";
  std::string output_unit = "deg";
  double input_min = -std::numeric_limits<double>::infinity();  ///< accepted input range
  double input_max = std::numeric_limits<double>::infinity();
  /// Each input's own training range, [input][min, max]: what validation
  /// counts extrapolation against (the range above spans all inputs, so a
  /// chamber held at zero would hide another's excursions below its grid).
  /// Empty in files written before it existed.
  std::vector<std::array<double, 2>> input_ranges;
  std::vector<std::vector<PoleSet>> poles;  ///< [output][input]
  /// What each input goes through before its filters: levels counted from a
  /// threshold, softened and coupled, then play channels (input_shaping.hpp).
  InputShaping shaping;
  /// The partition is looked up at the inputs through a first-order lag of
  /// this time constant (unit gain), 0 = at the raw inputs (the paper). The
  /// coefficients then follow the actuator's state rather than its command,
  /// which keeps the integrated increments from drifting (docs/identification.md).
  double schedule_lag_s = 0.0;
  ScheduleSide schedule_side = ScheduleSide::kOutput;
  /// Input side only: the output's level is a function of the inputs alone,
  /// y = output_level + sum of the filtered weighted inputs (modelLevels), so
  /// free simulation need not start from a measured sample, whose unsettled
  /// transient it would otherwise carry for ever. Empty: simulation starts
  /// from the first measured sample. [output]
  std::vector<double> output_level;
  /// Provenance, not used to predict: the sensor drift taken out of the
  /// training outputs before the fit (identify's sensor-drift stage), per
  /// logged output in output units per second, zero at training_drift_reference_s
  /// on the training logs' clock. Empty: fitted to the outputs as logged.
  std::vector<double> training_drift_per_s;
  double training_drift_reference_s = 0.0;
  /// The frame the poles, coefficients and output_level are in; `outputs`
  /// always names the logged columns (output_frame.hpp).
  OutputFrame output_frame = OutputFrame::kAsLogged;
  /// Radians per unit of the logged angles, for tip_cartesian (output_unit deg or rad).
  double radiansPerAngleUnit() const { return plsa::radiansPerAngleUnit(output_unit); }
  /// Records (logged outputs) in the model's frame.
  std::vector<Eigen::MatrixXd> toModelFrame(const std::vector<Eigen::MatrixXd>& logged) const {
    return plsa::toModelFrame(output_frame, logged,
                              output_frame == OutputFrame::kAsLogged ? 1.0 : radiansPerAngleUnit());
  }
  Eigen::MatrixXd toModelFrame(const Eigen::MatrixXd& logged) const {
    return plsa::toModelFrame(output_frame, logged,
                              output_frame == OutputFrame::kAsLogged ? 1.0 : radiansPerAngleUnit());
  }
  /// Pole of that lag per sample (0 when there is none).
  double schedulePole() const { return schedule_lag_s > 0 ? std::exp(-sample_time_s / schedule_lag_s) : 0.0; }

  int channelCount(int input) const { return shaping.channelCount(input); }
  PwlPartition partition = PwlPartition::single();
  std::vector<std::vector<Eigen::VectorXd>> coefficients;  ///< [region][output]
  std::vector<RegionFit> region_fits;                      ///< [region]

  int inputCount() const { return static_cast<int>(inputs.size()); }
  /// Every region's coefficients for `output`, end to end in region order:
  /// the weights of an input-side model's stacked regressors.
  Eigen::VectorXd stackedCoefficients(int output) const {
    const Eigen::Index n = regressorSize(output);
    Eigen::VectorXd c(static_cast<Eigen::Index>(coefficients.size()) * n);
    for (std::size_t r = 0; r < coefficients.size(); ++r)
      c.segment(static_cast<Eigen::Index>(r) * n, n) = coefficients[r][static_cast<std::size_t>(output)];
    return c;
  }
  int outputCount() const { return static_cast<int>(outputs.size()); }
  /// Copies of input `input`'s bank in an output's regressor: one per play
  /// channel, or one when the model has no play channels.
  int bankCopies(std::size_t input) const {
    return input < shaping.play.size() ? static_cast<int>(shaping.play[input].size()) : 1;
  }
  int regressorSize(int output) const {
    int n = 0;
    for (std::size_t j = 0; j < poles[static_cast<std::size_t>(output)].size(); ++j)
      n += poles[static_cast<std::size_t>(output)][j].size() * bankCopies(j);
    return n;
  }

  /// Input `input`'s training range: its own when the model has
  /// input_ranges, else the one over all inputs.
  std::array<double, 2> trainingRange(std::size_t input) const {
    return input_ranges.empty() ? std::array<double, 2>{input_min, input_max} : input_ranges[input];
  }

  // Angles drift as a sensor drifts, by degrees a minute: a rate of a turn a
  // second or more is no drift identification finds, and the predictor turns
  // the tip's yaw by it every sample (the validation's carried yaw too).
  void validateDriftRates() const {
    if (output_unit != "deg" && output_unit != "rad") return;
    const double turn = 2.0 * kPi / radiansPerAngleUnit();
    for (double r : training_drift_per_s)
      PLSA_CHECK(std::abs(r) < turn, "model: a training_output_drift rate of " + significantDigits(r, 3) + " " +
                                         output_unit + "/s is a turn a second or more, not a sensor's drift");
  }

  /// The shaping against the training range (when the model has one), at
  /// most what identification fits: the threshold under the top level, the
  /// coupling and softening times the level span above it at most 1 and 0.5
  /// (beyond them every channel reads zero, or the coupled level overflows
  /// or folds back inside the range the model was fitted on).
  void validateShapingRange() const {
    if (!std::isfinite(input_max) || input_max <= 0.0) return;
    PLSA_CHECK(shaping.threshold < input_max, "model: play_threshold " + std::to_string(shaping.threshold) +
                                                  " is not below the top of input_range (" + std::to_string(input_max) +
                                                  "): every channel would read 0");
    const double above = input_max - shaping.threshold;
    PLSA_CHECK(shaping.coupling * above <= 1.0, "model: play_coupling times the input span above play_threshold is " +
                                                    std::to_string(shaping.coupling * above) + ", over 1");
    PLSA_CHECK(shaping.softening * above <= 0.5, "model: play_softening times the input span above play_threshold is " +
                                                     std::to_string(shaping.softening * above) +
                                                     ", over 0.5 (the level would fold back)");
  }

  /// Throws std::invalid_argument naming the first inconsistency.
  void validate() const {
    PLSA_CHECK(sample_time_s > 0 && std::isfinite(sample_time_s), "model: sample_time_s must be positive");
    PLSA_CHECK(!inputs.empty(), "model: no inputs");
    PLSA_CHECK(!outputs.empty(), "model: no outputs");
    for (const auto* names : {&inputs, &outputs})
      for (auto at = names->begin(); at != names->end(); ++at)
        PLSA_CHECK(std::find(names->begin(), at, *at) == at, "model: column '" + *at + "' is named twice");
    for (const auto& in : inputs)
      PLSA_CHECK(std::find(outputs.begin(), outputs.end(), in) == outputs.end(),
                 "model: column '" + in + "' is both an input and an output");
    PLSA_CHECK(input_min < input_max, "model: input_min must be below input_max");
    PLSA_CHECK(input_ranges.empty() || input_ranges.size() == inputs.size(),
               "model: input_ranges needs one [min, max] per input");
    for (const auto& r : input_ranges)
      PLSA_CHECK(std::isfinite(r[0]) && std::isfinite(r[1]) && r[0] <= r[1],
                 "model: every input_ranges entry must be finite with min <= max");
    PLSA_CHECK(poles.size() == outputs.size(), "model: need one row of pole sets per output");
    shaping.validate(inputs.size());
    validateShapingRange();
    PLSA_CHECK(std::isfinite(schedule_lag_s) && schedule_lag_s >= 0, "model: schedule_lag_s must be finite and >= 0");
    PLSA_CHECK(output_level.empty() || schedule_side == ScheduleSide::kInput,
               "model: output_level needs input-side scheduling (only there is the level a function of the inputs)");
    PLSA_CHECK(output_level.empty() || output_level.size() == outputs.size(),
               "model: output_level needs one value per output");
    for (double b : output_level) PLSA_CHECK(std::isfinite(b), "model: output_level values must be finite");
    PLSA_CHECK(training_drift_per_s.empty() || training_drift_per_s.size() == outputs.size(),
               "model: training_output_drift needs one rate per output");
    for (double r : training_drift_per_s)
      PLSA_CHECK(std::isfinite(r), "model: training_output_drift rates must be finite");
    validateDriftRates();
    PLSA_CHECK(std::isfinite(training_drift_reference_s), "model: training_output_drift reference time must be finite");
    PLSA_CHECK(output_frame == OutputFrame::kAsLogged ||
                   (outputs.size() == 2 && (output_unit == "deg" || output_unit == "rad")),
               "model: output_frame tip_cartesian needs two outputs in deg or rad (bending, then steering)");
    PLSA_CHECK(schedule_side == ScheduleSide::kOutput ||
                   (partition.scheduling() == Scheduling::kInterpolated && !partition.directionSplit()),
               "model: input-side scheduling needs an interpolated partition without a direction split");
    for (std::size_t o = 0; o < poles.size(); ++o) {
      PLSA_CHECK(poles[o].size() == inputs.size(), "model: output '" + outputs[o] + "' needs one pole set per input");
      for (std::size_t j = 0; j < poles[o].size(); ++j) {
        PLSA_CHECK(!poles[o][j].empty(), "model: empty pole set for " + inputs[j] + " -> " + outputs[o]);
        PLSA_CHECK(
            static_cast<std::size_t>(poles[o][j].size()) <= kMaxPolesPerBank,
            "model: more than " + std::to_string(kMaxPolesPerBank) + " poles for " + inputs[j] + " -> " + outputs[o]);
      }
    }
    PLSA_CHECK(partition.maxInputIndex() < inputCount(),
               "model: the partition schedules on an input that does not exist");
    const auto regions = static_cast<std::size_t>(partition.regionCount());
    PLSA_CHECK(coefficients.size() == regions, "model: " + std::to_string(coefficients.size()) +
                                                   " coefficient blocks for " + std::to_string(regions) + " regions");
    PLSA_CHECK(region_fits.size() == regions, "model: region_fits has the wrong length");
    for (std::size_t r = 0; r < regions; ++r) {
      PLSA_CHECK(coefficients[r].size() == outputs.size(),
                 "model: region " + std::to_string(r) + " needs coefficients for every output");
      for (std::size_t o = 0; o < outputs.size(); ++o) {
        PLSA_CHECK(coefficients[r][o].size() == regressorSize(static_cast<int>(o)),
                   "model: region " + std::to_string(r) + ", output '" + outputs[o] + "' has " +
                       std::to_string(coefficients[r][o].size()) + " coefficients, expected " +
                       std::to_string(regressorSize(static_cast<int>(o))));
        PLSA_CHECK(coefficients[r][o].allFinite(),
                   "model: region " + std::to_string(r) + ", output '" + outputs[o] + "' has a NaN or Inf coefficient");
      }
    }
  }
};

}  // namespace plsa
