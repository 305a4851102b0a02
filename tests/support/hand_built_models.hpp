// Small DioPwlObfModel values built by hand for the predictor tests: a few
// poles, one or two inputs and outputs, one region or a 2x2 interpolated grid,
// coefficients chosen by a formula (no simulator, no identification), so a
// test can work out what the predictor must answer in closed form.
#pragma once

#include <algorithm>
#include <cmath>
#include <complex>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "plsa/core/pole_set.hpp"
#include "plsa/model/dio_pwl_obf_model.hpp"
#include "plsa/model/pwl_partition.hpp"

namespace plsa::hand_built {

/// Grid nodes of the 2x2 partition, on inputs 0 and 1 alike.
inline constexpr double kNodeLow = 0.2;
inline constexpr double kNodeHigh = 0.4;
/// Every model's input range (the predictor accepts it widened by its input_margin).
inline constexpr double kInputMin = 0.0;
inline constexpr double kInputMax = 0.6;

enum class Grid {
  kOneRegion,  ///< PwlPartition::single()
  kGrid2x2,    ///< interpolated on inputs 0 and 1, nodes {kNodeLow, kNodeHigh} each: 4 regions
  kLevels,     ///< interpolated on inputs 0 .. levels.size() - 1, each at its Spec::levels
};

/// What to build; build() writes it into a model (the shaping fields into
/// its InputShaping).
struct Spec {
  int inputs = 1;
  int outputs = 1;
  /// Every bank's poles (each input-output pair has the same set).
  std::vector<std::complex<double>> poles = {{0.8, 0.0}};
  Grid grid = Grid::kOneRegion;
  std::vector<std::vector<double>> levels;  ///< Grid::kLevels: each scheduling input's nodes
  ScheduleSide side = ScheduleSide::kOutput;
  double schedule_lag_s = 0.0;
  /// Each input's play channels (the same list for every input); one width-0 channel = the raw input.
  std::vector<PlayChannel> channels = {PlayChannel{}};
  PlayStart start = PlayStart::kRising;
  double coupling = 0.0;
  double threshold = 0.0;
  double softening = 0.0;
};

/// n distinct real poles, well apart (0.85 alone; else 0.92 down to 0.1).
inline std::vector<std::complex<double>> realPoles(int n) {
  std::vector<std::complex<double>> p;
  for (int i = 0; i < n; ++i) p.emplace_back(n == 1 ? 0.85 : 0.92 - 0.82 * i / (n - 1), 0.0);
  return p;
}

/// n poles with one conjugate pair first (n >= 2), then distinct real ones.
inline std::vector<std::complex<double>> polesWithAPair(int n) {
  std::vector<std::complex<double>> p = {{0.7, 0.2}, {0.7, -0.2}};
  for (int i = 0; i < n - 2; ++i) p.emplace_back(0.9 - 0.8 * i / std::max(1, n - 3), 0.0);
  return p;
}

/// The chosen coefficient of a region, output and regressor: of order one,
/// alternating in sign, different in every region, so a wrong region or
/// weight shows.
inline double chosenCoefficient(int region, int output, int index) {
  return (1.0 + 0.5 * output) * (1.0 + 0.3 * region) * (index % 2 == 0 ? 1.0 : -0.4) / (1.0 + 0.25 * index);
}

/// The model `spec` describes; validate() passes.
inline DioPwlObfModel build(const Spec& spec) {
  DioPwlObfModel m;
  for (int j = 0; j < spec.inputs; ++j) m.inputs.push_back("u" + std::to_string(j + 1));
  for (int o = 0; o < spec.outputs; ++o) m.outputs.push_back("y" + std::to_string(o + 1));
  m.input_min = kInputMin;
  m.input_max = kInputMax;
  m.poles.assign(static_cast<std::size_t>(spec.outputs),
                 std::vector<PoleSet>(static_cast<std::size_t>(spec.inputs), PoleSet(spec.poles)));
  m.shaping.play.assign(static_cast<std::size_t>(spec.inputs), spec.channels);
  m.shaping.start = spec.start;
  m.shaping.coupling = spec.coupling;
  m.shaping.threshold = spec.threshold;
  m.shaping.softening = spec.softening;
  m.schedule_lag_s = spec.schedule_lag_s;
  m.schedule_side = spec.side;
  if (spec.grid == Grid::kGrid2x2)
    m.partition = PwlPartition::interpolated({0, 1}, {{kNodeLow, kNodeHigh}, {kNodeLow, kNodeHigh}});
  if (spec.grid == Grid::kLevels) {
    std::vector<int> on;
    for (std::size_t s = 0; s < spec.levels.size(); ++s) on.push_back(static_cast<int>(s));
    m.partition = PwlPartition::interpolated(on, spec.levels);
  }
  const auto regions = static_cast<std::size_t>(m.partition.regionCount());
  m.coefficients.resize(regions);
  for (std::size_t r = 0; r < regions; ++r)
    for (int o = 0; o < spec.outputs; ++o) {
      Eigen::VectorXd c(m.regressorSize(o));
      for (Eigen::Index i = 0; i < c.size(); ++i) c(i) = chosenCoefficient(static_cast<int>(r), o, static_cast<int>(i));
      m.coefficients[r].push_back(c);
    }
  m.region_fits.assign(regions, RegionFit{});
  m.validate();
  return m;
}

/// One input, one output, one region, one pole `a`, coefficient `c`: the
/// model y_k = y_{k-1} + c x_k, x_{k+1} = a x_k + sqrt(1 - a^2) (u_k - u_{k-1}).
inline DioPwlObfModel onePole(double a, double c) {
  Spec s;
  s.poles = {{a, 0.0}};
  DioPwlObfModel m = build(s);
  m.coefficients[0][0](0) = c;
  return m;
}

/// One input, one output, one region, one pole `a`, coefficient `c`, the
/// input through one play channel `channel` (starting rising).
inline DioPwlObfModel onePoleWithPlay(double a, double c, const PlayChannel& channel) {
  Spec s;
  s.poles = {{a, 0.0}};
  s.channels = {channel};
  DioPwlObfModel m = build(s);
  m.coefficients[0][0](0) = c;
  return m;
}

/// Two inputs, one output, one region, one pole `a` on both, coefficients
/// `c` (input 0, input 1); the channels see each input's level above
/// `threshold`, softened by `softening` and coupled by `coupling`.
inline DioPwlObfModel onePoleShaped(double a, const Eigen::Vector2d& c, double threshold, double coupling,
                                    double softening) {
  Spec s;
  s.inputs = 2;
  s.poles = {{a, 0.0}};
  s.threshold = threshold;
  s.coupling = coupling;
  s.softening = softening;
  DioPwlObfModel m = build(s);
  m.coefficients[0][0] = c;
  return m;
}

/// A structure the typed tests stamp for every pole count.
enum class Variant {
  kOneRegion,         ///< one input and output, raw
  kGridOutputSide,    ///< two inputs and outputs, 2x2 grid, two play channels per input
  kGridInputSide,     ///< the same on the input side, through a lag, threshold, coupling and softening
  kGridComplexPoles,  ///< the output-side grid with a conjugate pair (no modal form; n >= 2)
};

inline const char* name(Variant v) {
  switch (v) {
    case Variant::kOneRegion:
      return "one region";
    case Variant::kGridOutputSide:
      return "2x2 grid, output side";
    case Variant::kGridInputSide:
      return "2x2 grid, input side, lagged and shaped";
    case Variant::kGridComplexPoles:
      return "2x2 grid, a conjugate pair";
  }
  return "?";
}

/// The variant's model with `n` poles per bank.
inline DioPwlObfModel variant(Variant v, int n) {
  Spec s;
  s.poles = realPoles(n);
  if (v == Variant::kOneRegion) return build(s);
  s.inputs = 2;
  s.outputs = 2;
  s.grid = Grid::kGrid2x2;
  s.channels = {PlayChannel(0.0), PlayChannel(0.03, 0.1)};
  if (v == Variant::kGridComplexPoles) s.poles = polesWithAPair(n);
  if (v == Variant::kGridInputSide) {
    s.side = ScheduleSide::kInput;
    s.schedule_lag_s = 0.3;
    s.start = PlayStart::kRising;
    s.threshold = 0.05;
    s.coupling = 0.8;
    s.softening = 0.6;
  }
  return build(s);
}

}  // namespace plsa::hand_built
