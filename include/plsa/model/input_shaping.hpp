// What each input of a DIO-PWL-OBF model goes through before its OBF
// filters: its level counted from a threshold, softened and coupled to the
// other inputs, then one or more play (backlash) channels. One value,
// InputShaping, used by the batch regressors, the predictor and the model
// file alike: a new shaping feature touches this header, the file format and
// the identification stage that fits it.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "plsa/core/check.hpp"

namespace plsa {

/// Play (backlash) operator: the output follows the input only once it leaves
/// a band of half-width r around it; r = 0 passes the input through. Placed
/// before the OBF filters it gives the model the memory of the last reversal
/// that hysteresis needs (docs/identification.md). Allocation-free.
inline double playOperator(double input, double previous_output, double half_width) noexcept {
  // std::clamp's result (half_width >= 0), as min and max: no branch in the predictor's loops.
  return std::min(std::max(previous_output, input - half_width), input + half_width);
}

/// One play channel: half-width `width + slope * max(0, u)`. A slope makes the
/// band grow with the level, as when the friction behind hysteresis scales
/// with the strain; slope 0 is a fixed band (implicit from a plain width).
struct PlayChannel {
  double width = 0.0;                                                  ///< input units
  double slope = 0.0;                                                  ///< fraction of the (non-negative) input level
  PlayChannel(double w = 0.0, double s = 0.0) : width(w), slope(s) {}  // NOLINT: a plain width is a channel
  double halfWidth(double u) const noexcept { return width + slope * std::max(0.0, u); }
  /// The played output after `previous` once the input reaches u (the band taken at u).
  double follow(double u, double previous) const noexcept { return playOperator(u, previous, halfWidth(u)); }
  bool passesThrough() const noexcept { return width == 0.0 && slope == 0.0; }
  bool operator==(const PlayChannel& o) const { return width == o.width && slope == o.slope; }
};

/// Where a play channel starts: every run begins from a vented actuator, so
/// at the first sample the pressure has just risen and the band trails below
/// it (rising). Centred was the convention of models written before this
/// field existed; starting centred hides a band's worth of output from the
/// first rise and leaves a lasting offset in simulation (docs/identification.md).
enum class PlayStart { kRising, kCentred };

inline double playStartState(double u, const PlayChannel& ch, PlayStart start) noexcept {
  return start == PlayStart::kRising ? u - ch.halfWidth(u) : u;
}

/// What input j's play channels see: its positive level softened, `x - s x^2`
/// (a wall whose strain saturates; flat past its peak at x = 1/2s, so it never
/// falls as the input rises), then less kappa times that times the other
/// inputs' positive parts: a chamber's wall stiffened by its pressurised
/// neighbours, to first order. kappa = s = 0 passes u_j through.
/// `positive_sum` is sum_k max(0, u_k).
inline double coupledLevel(double u_j, double positive_sum, double kappa, double softening = 0.0) noexcept {
  const double own = std::max(0.0, u_j);
  double level = u_j;
  if (softening > 0.0 && own > 0.0) {
    const double x = std::min(own, 0.5 / softening);
    level = x - softening * x * x;
  }
  return level - kappa * std::max(0.0, level) * (positive_sum - own);
}

/// An input's level counted from `threshold` (InputShaping::threshold):
/// zero below it, as a chamber that has not reached its opening pressure.
/// Threshold 0 passes the input through, negative levels included.
inline double levelAbove(double u, double threshold) noexcept {
  return threshold > 0.0 ? std::max(0.0, u - threshold) : u;
}

/// One input's term of coupledLevel's `positive_sum`: its part above
/// `threshold`. Loops that fuse the sum with other work add these.
inline double positivePartAbove(double u, double threshold) noexcept { return std::max(0.0, u - threshold); }

/// coupledLevel's `positive_sum` for levels counted from `threshold`.
template <typename Derived>
double positiveSumAbove(const Eigen::MatrixBase<Derived>& u, double threshold) noexcept {
  double s = 0.0;
  for (Eigen::Index j = 0; j < u.size(); ++j) s += positivePartAbove(u(j), threshold);
  return s;
}

/// The shaping of a model's inputs (the file's input_play, play_start,
/// play_coupling, play_threshold and play_softening). Input j's channel c
/// filters play[j][c] applied to level(u_j, positiveSum(u)).
struct InputShaping {
  /// [input][channel] play channels: each input feeds one OBF bank per
  /// channel, through a play operator of that width (0 = the raw input, as in
  /// the paper). Several channels form an identified Prandtl-Ishlinskii operator.
  std::vector<std::vector<PlayChannel>> play;
  PlayStart start = PlayStart::kRising;
  double coupling = 0.0;  ///< kappa of coupledLevel, 1/input unit; 0 = each channel sees its own input
  /// Input level the channels count from: they see max(0, u - threshold)
  /// (levelAbove), so a growing band and the coupling start there, as a
  /// chamber's wall only stretches once its pressure passes an opening
  /// threshold. 0 = the inputs as they are. Input units.
  double threshold = 0.0;
  /// s of coupledLevel, 1/input unit: the level above the threshold softens to
  /// x - s x^2 before the coupling and the play, as a strain that saturates
  /// with pressure. 0 = linear (files written before it existed).
  double softening = 0.0;

  int channelCount(int input) const { return static_cast<int>(play[static_cast<std::size_t>(input)].size()); }
  /// Whether levels differ from the raw inputs (threshold, softening or coupling set).
  bool shapesLevels() const noexcept { return coupling != 0.0 || threshold != 0.0 || softening != 0.0; }
  /// The sum that level() couples through, over the whole input vector.
  template <typename Derived>
  double positiveSum(const Eigen::MatrixBase<Derived>& u) const noexcept {
    return positiveSumAbove(u, threshold);
  }
  /// The level input j's channels see, given positiveSum(u). Allocation-free.
  double level(double u_j, double positive_sum) const noexcept {
    return coupledLevel(levelAbove(u_j, threshold), positive_sum, coupling, softening);
  }
  /// d level(u_j, positiveSum(u)) / d u_j (`own`) and / d u_k for each other
  /// input k that pushesOthers(u_k) (`other`; 0 for the rest), one-sided
  /// where the level has a corner. What the predictor's sensitivity chains
  /// through the channels.
  struct Slopes {
    double own = 0.0, other = 0.0;
  };
  Slopes slopes(double u_j, double positive_sum) const noexcept {
    const double above = levelAbove(u_j, threshold);
    const double own = std::max(0.0, above), others = positive_sum - own;
    double soft = 1.0, softened = above;
    if (softening > 0.0 && own > 0.0) {
      const double x = std::min(own, 0.5 / softening);
      softened = x - softening * x * x;
      soft = own < 0.5 / softening ? 1.0 - 2.0 * softening * own : 0.0;
    }
    Slopes s;
    const bool below_threshold = threshold > 0.0 && !(u_j > threshold);  // levelAbove is flat there
    s.own = below_threshold ? 0.0 : soft * (1.0 - coupling * (softened > 0.0 ? 1.0 : 0.0) * others);
    s.other = -coupling * std::max(0.0, softened);
    return s;
  }
  /// Whether input k at u_k enters positiveSum (and so moves the others' levels).
  bool pushesOthers(double u_k) const noexcept { return u_k > threshold; }

  /// Throws std::invalid_argument naming the first inconsistency for a model
  /// of `inputs` inputs.
  void validate(std::size_t inputs) const {
    PLSA_CHECK(play.size() == inputs, "model: need one input_play list per input");
    for (const auto& ch : play) {
      PLSA_CHECK(!ch.empty(), "model: every input needs at least one play channel (width 0 for the raw input)");
      for (const PlayChannel& c : ch)
        PLSA_CHECK(std::isfinite(c.width) && c.width >= 0 && std::isfinite(c.slope) && c.slope >= 0,
                   "model: input_play widths and slopes must be finite and >= 0");
    }
    PLSA_CHECK(std::isfinite(coupling) && coupling >= 0, "model: play_coupling must be finite and >= 0");
    PLSA_CHECK(std::isfinite(threshold) && threshold >= 0, "model: play_threshold must be finite and >= 0");
    PLSA_CHECK(std::isfinite(softening) && softening >= 0, "model: play_softening must be finite and >= 0");
  }
};

}  // namespace plsa
