// An identified DIO-PWL-OBF model (method notes): one OBF pole set per
// input-output pair, a PWL partition of the scheduling inputs, and a
// coefficient vector per region and output:
//   y_k = y_{k-1} + sum_j c_{l(k), o, j}^T [B_{o,j}(q) du_j]_k.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <exception>
#include <limits>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <Eigen/Dense>

#include "plsa/core/check.hpp"
#include "plsa/core/pole_set.hpp"
#include "plsa/model/output_frame.hpp"
#include "plsa/model/pwl_partition.hpp"
#include "plsa/obf/obf_bank.hpp"

namespace plsa {

/// How a region's coefficients came about.
struct RegionFit {
  int samples = 0;         ///< training samples that fell in the region
  int fallback_from = -1;  ///< -1: fitted on its own; else the source (region index, or -2 = global)
  std::string note;
};

/// Play (backlash) operator: the output follows the input only once it leaves
/// a band of half-width r around it; r = 0 passes the input through. Placed
/// before the OBF filters it gives the model the memory of the last reversal
/// that hysteresis needs (docs/identification.md). Allocation-free.
inline double playOperator(double input, double previous_output, double half_width) noexcept {
  return std::clamp(previous_output, input - half_width, input + half_width);
}

/// One play channel: half-width `width + slope * max(0, u)`. A slope makes the
/// band grow with the level, as when the friction behind hysteresis scales
/// with the strain; slope 0 is a fixed band (implicit from a plain width).
struct PlayChannel {
  double width = 0.0;  ///< input units
  double slope = 0.0;  ///< fraction of the (non-negative) input level
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

/// An input's level counted from `threshold` (DioPwlObfModel::play_threshold):
/// zero below it, as a chamber that has not reached its opening pressure.
/// Threshold 0 passes the input through, negative levels included.
inline double levelAbove(double u, double threshold) noexcept {
  return threshold > 0.0 ? std::max(0.0, u - threshold) : u;
}

/// coupledLevel's `positive_sum` for levels counted from `threshold`.
template <typename Derived>
double positiveSumAbove(const Eigen::MatrixBase<Derived>& u, double threshold) noexcept {
  double s = 0.0;
  for (Eigen::Index j = 0; j < u.size(); ++j) s += std::max(0.0, u(j) - threshold);
  return s;
}

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
  /// [input][channel] play half-widths: each input feeds one OBF bank per
  /// channel, through a play operator of that width (0 = the raw input, as in
  /// the paper). Several channels form an identified Prandtl-Ishlinskii operator.
  std::vector<std::vector<PlayChannel>> input_play;
  PlayStart play_start = PlayStart::kRising;
  double play_coupling = 0.0;  ///< kappa of coupledLevel, 1/input unit; 0 = each channel sees its own input
  /// Input level the play channels count from: they see max(0, u - play_threshold)
  /// (levelAbove), so a growing band and the coupling start there, as a
  /// chamber's wall only stretches once its pressure passes an opening
  /// threshold. 0 = the inputs as they are. Input units.
  double play_threshold = 0.0;
  /// s of coupledLevel, 1/input unit: the level above the threshold softens to
  /// x - s x^2 before the coupling and the play, as a strain that saturates
  /// with pressure. 0 = linear (files written before it existed).
  double play_softening = 0.0;
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
  /// Pole of that lag per sample (0 when there is none).
  double schedulePole() const { return schedule_lag_s > 0 ? std::exp(-sample_time_s / schedule_lag_s) : 0.0; }

  int channelCount(int input) const { return static_cast<int>(input_play[static_cast<std::size_t>(input)].size()); }
  PwlPartition partition = PwlPartition::single();
  std::vector<std::vector<Eigen::VectorXd>> coefficients;  ///< [region][output]
  std::vector<RegionFit> region_fits;                       ///< [region]

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
  int regressorSize(int output) const {
    int n = 0;
    for (std::size_t j = 0; j < poles[static_cast<std::size_t>(output)].size(); ++j)
      n += poles[static_cast<std::size_t>(output)][j].size() *
           (j < input_play.size() ? static_cast<int>(input_play[j].size()) : 1);
    return n;
  }

  /// Input `input`'s training range: its own when the model has
  /// input_ranges, else the one over all inputs.
  std::array<double, 2> trainingRange(std::size_t input) const {
    return input_ranges.empty() ? std::array<double, 2>{input_min, input_max} : input_ranges[input];
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
    PLSA_CHECK(input_play.size() == inputs.size(), "model: need one input_play list per input");
    for (const auto& ch : input_play) {
      PLSA_CHECK(!ch.empty(), "model: every input needs at least one play channel (width 0 for the raw input)");
      for (const PlayChannel& c : ch)
        PLSA_CHECK(std::isfinite(c.width) && c.width >= 0 && std::isfinite(c.slope) && c.slope >= 0,
                "model: input_play widths and slopes must be finite and >= 0");
    }
    PLSA_CHECK(std::isfinite(play_coupling) && play_coupling >= 0, "model: play_coupling must be finite and >= 0");
    PLSA_CHECK(std::isfinite(play_threshold) && play_threshold >= 0, "model: play_threshold must be finite and >= 0");
    PLSA_CHECK(std::isfinite(play_softening) && play_softening >= 0, "model: play_softening must be finite and >= 0");
    PLSA_CHECK(std::isfinite(schedule_lag_s) && schedule_lag_s >= 0, "model: schedule_lag_s must be finite and >= 0");
    PLSA_CHECK(output_level.empty() || schedule_side == ScheduleSide::kInput,
            "model: output_level needs input-side scheduling (only there is the level a function of the inputs)");
    PLSA_CHECK(output_level.empty() || output_level.size() == outputs.size(),
            "model: output_level needs one value per output");
    for (double b : output_level) PLSA_CHECK(std::isfinite(b), "model: output_level values must be finite");
    PLSA_CHECK(training_drift_per_s.empty() || training_drift_per_s.size() == outputs.size(),
            "model: training_output_drift needs one rate per output");
    for (double r : training_drift_per_s) PLSA_CHECK(std::isfinite(r), "model: training_output_drift rates must be finite");
    PLSA_CHECK(std::isfinite(training_drift_reference_s), "model: training_output_drift reference time must be finite");
    PLSA_CHECK(output_frame == OutputFrame::kAsLogged || (outputs.size() == 2 && output_unit == "deg"),
            "model: output_frame tip_cartesian needs two outputs in deg (bending, then steering)");
    PLSA_CHECK(schedule_side == ScheduleSide::kOutput ||
                (partition.scheduling() == Scheduling::kInterpolated && !partition.directionSplit()),
            "model: input-side scheduling needs an interpolated partition without a direction split");
    for (std::size_t o = 0; o < poles.size(); ++o) {
      PLSA_CHECK(poles[o].size() == inputs.size(),
              "model: output '" + outputs[o] + "' needs one pole set per input");
      for (std::size_t j = 0; j < poles[o].size(); ++j)
        PLSA_CHECK(!poles[o][j].empty(), "model: empty pole set for " + inputs[j] + " -> " + outputs[o]);
    }
    PLSA_CHECK(partition.maxInputIndex() < inputCount(), "model: the partition schedules on an input that does not exist");
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

/// OBF regressors of every output and the region of every sample, for an
/// input record u (T x n_u) starting at rest. At sample k the filters have
/// seen du_0..du_{k-1} and the region is scheduled on u_{k-1} (strictly causal).
/// Input side: phi holds every region's regressors side by side (T x
/// regions * regressorSize(o)), and the schedule of sample k is the weights
/// its own input gives the nodes.
struct ModelRegressors {
  std::vector<Eigen::MatrixXd> phi;    ///< [output] T x regressorSize(o), or x regions times that
  std::vector<ScheduleBlend> schedule; ///< [T] regions and weights
  /// Input side: [output] the filters' settled states at the first sample
  /// (DC gain times the first weighted input), laid out as phi's columns.
  std::vector<Eigen::RowVectorXd> level0;
  /// Input side: [output] for each tile of kTileRows samples and each node,
  /// whether any of the node's regressors there exceeds the rounding of its
  /// column's largest (machine epsilon times it). A node's regressors are zero
  /// until the input first nears it and decay once it leaves, so most tiles
  /// hold few live nodes; sums and products skip the rest. Empty: all live.
  static constexpr Eigen::Index kTileRows = 256;
  std::vector<Eigen::Array<bool, Eigen::Dynamic, Eigen::Dynamic>> live;
};

/// One input through a play channel, starting as `start` says.
inline Eigen::VectorXd playedInput(const Eigen::VectorXd& u, const PlayChannel& ch, PlayStart start) {
  Eigen::VectorXd v = u;
  if (ch.passesThrough() || u.size() == 0) return v;
  v(0) = playStartState(u(0), ch, start);
  for (Eigen::Index k = 1; k < u.size(); ++k) v(k) = ch.follow(u(k), v(k - 1));
  return v;
}

/// The regressors of a structure into `out`, whose storage is reused when its
/// shapes already match (a long record's run to tens of megabytes). `play` as
/// in DioPwlObfModel::input_play; empty = one raw channel per input.
inline void fillRegressors(ModelRegressors& out, const std::vector<std::vector<PoleSet>>& poles,
                           const PwlPartition& partition, const Eigen::MatrixXd& u,
                           const std::vector<std::vector<PlayChannel>>& play, PlayStart start, double coupling,
                           double schedule_pole, ScheduleSide side, double threshold, double softening) {
  PLSA_CHECK(!poles.empty(), "modelRegressors: no outputs");
  PLSA_CHECK(u.allFinite(), "modelRegressors: the inputs contain NaN or Inf");
  const Eigen::Index T = u.rows();
  const auto n_u = static_cast<std::size_t>(u.cols());
  out.schedule.resize(static_cast<std::size_t>(T));
  DirectionState dir;
  Eigen::RowVectorXd du = Eigen::RowVectorXd::Zero(u.cols());
  // The schedule of sample k sees the inputs up to k-1 through the lag, which
  // starts settled at the first input.
  Eigen::RowVectorXd lagged = T > 0 ? u.row(0) : Eigen::RowVectorXd();
  for (Eigen::Index k = 0; k < T; ++k) {
    const Eigen::Index prev = k == 0 ? 0 : k - 1;
    if (k >= 2) du = u.row(k - 1) - u.row(k - 2);
    if (k >= 2) partition.updateDirections(du, dir);
    if (k >= 2) lagged = schedule_pole * lagged + (1.0 - schedule_pole) * u.row(prev);
    partition.blend(lagged, dir, out.schedule[static_cast<std::size_t>(k)]);
  }
  // Input side: node weights at each sample's own (lagged) input, the same
  // lag one sample on: the output side's schedule of sample k+1.
  const int regions = partition.regionCount();
  Eigen::MatrixXd node_weight;
  if (side == ScheduleSide::kInput) {
    node_weight = Eigen::MatrixXd::Zero(T, regions);
    for (Eigen::Index k = 0; k < T; ++k) {
      ScheduleBlend& b = out.schedule[static_cast<std::size_t>(k)];
      if (k + 1 < T) b = out.schedule[static_cast<std::size_t>(k + 1)];
      else if (k > 0) partition.blend((schedule_pole * lagged + (1.0 - schedule_pole) * u.row(k)).eval(), dir, b);
    }
    for (Eigen::Index k = 0; k < T; ++k) {
      const ScheduleBlend& b = out.schedule[static_cast<std::size_t>(k)];
      for (int m = 0; m < b.count; ++m)
        node_weight(k, b.region[static_cast<std::size_t>(m)]) += b.weight[static_cast<std::size_t>(m)];
    }
  }
  PLSA_CHECK(play.empty() || play.size() == n_u, "modelRegressors: need one play list per input");
  // Channel inputs: input j above the threshold (coupled to the others)
  // through each of its play channels.
  Eigen::MatrixXd coupled;
  const bool shaped = coupling != 0.0 || threshold != 0.0 || softening != 0.0;
  if (shaped) {
    coupled.resize(T, u.cols());
    for (Eigen::Index k = 0; k < T; ++k) {
      const double positive_sum = positiveSumAbove(u.row(k), threshold);
      for (Eigen::Index j = 0; j < u.cols(); ++j)
        coupled(k, j) = coupledLevel(levelAbove(u(k, j), threshold), positive_sum, coupling, softening);
    }
  }
  const Eigen::MatrixXd& level = shaped ? coupled : u;
  std::vector<std::vector<Eigen::VectorXd>> channels(n_u);
  for (std::size_t j = 0; j < n_u; ++j) {
    const std::vector<PlayChannel> list = play.empty() ? std::vector<PlayChannel>{PlayChannel{}} : play[j];
    for (const PlayChannel& ch : list)
      channels[j].push_back(playedInput(level.col(static_cast<Eigen::Index>(j)), ch, start));
  }
  for (const auto& row : poles) PLSA_CHECK(row.size() == n_u, "modelRegressors: need one pole set per input");
  const int copies = side == ScheduleSide::kInput ? regions : 1;
  out.phi.resize(poles.size());
  out.level0.resize(side == ScheduleSide::kInput ? poles.size() : 0);
  out.live.resize(side == ScheduleSide::kInput ? poles.size() : 0);
  // The filters run on every node's copy at once, a state row per copy: the
  // copies' recursions are independent, so the loop over them vectorises.
  // The outputs' regressors are independent: one thread each.
  auto fill = [&](std::size_t o) {
    Eigen::MatrixXd x, next;
    Eigen::VectorXd step_in(copies);  // each copy's input increment
    const std::vector<PoleSet>& row = poles[o];
    int width = 0;
    for (std::size_t j = 0; j < n_u; ++j) width += row[j].size() * static_cast<int>(channels[j].size());
    Eigen::MatrixXd& phi = out.phi[o];
    phi.resize(T, width * copies);
    if (side == ScheduleSide::kInput) out.level0[o].setZero(width * copies);
    int offset = 0;
    for (std::size_t j = 0; j < n_u; ++j) {
      const ObfBank<> bank(row[j]);
      const int n = bank.size();
      const Eigen::MatrixXd& A = bank.A();
      const Eigen::VectorXd& B = bank.B();
      const Eigen::RowVectorXd gain = bank.transfer(1.0).real().transpose();
      for (const Eigen::VectorXd& v : channels[j]) {
        // Input side: node r's filters see the channel weighted by the node.
        auto f = [&](Eigen::Index k, int r) { return side == ScheduleSide::kInput ? node_weight(k, r) * v(k) : v(k); };
        x.setZero(copies, n);
        next.resize(copies, n);
        // Raw loops: at five or six states Eigen's dynamic expressions cost more than the arithmetic.
        double* now = x.data();
        double* then = next.data();
        double* const col0 = phi.data() + static_cast<Eigen::Index>(offset) * T;
        for (Eigen::Index k = 0; k < T; ++k) {
          for (int i = 0; i < n; ++i)
            for (int r = 0; r < copies; ++r)
              col0[(static_cast<Eigen::Index>(r) * width + i) * T + k] = now[i * copies + r];
          for (int r = 0; r < copies; ++r) step_in(r) = k == 0 ? 0.0 : f(k, r) - f(k - 1, r);
          for (int i = 0; i < n; ++i) {
            double* const to = then + i * copies;
            for (int r = 0; r < copies; ++r) to[r] = B(i) * step_in(r);
            for (int l = 0; l < n; ++l) {
              const double a = A(i, l);
              if (a == 0.0) continue;
              const double* const from = now + l * copies;
              for (int r = 0; r < copies; ++r) to[r] += a * from[r];
            }
          }
          std::swap(now, then);
        }
        if (side == ScheduleSide::kInput && T > 0)
          for (int r = 0; r < copies; ++r)
            out.level0[o].segment(static_cast<Eigen::Index>(r) * width + offset, n) = gain * f(0, r);
        offset += n;
      }
    }
    if (side != ScheduleSide::kInput) return;
    const Eigen::Index tile = ModelRegressors::kTileRows;
    auto& live = out.live[o];
    live.resize((T + tile - 1) / tile, copies);
    if (T == 0) return;
    const Eigen::RowVectorXd negligible = std::numeric_limits<double>::epsilon() * phi.cwiseAbs().colwise().maxCoeff();
    for (Eigen::Index t = 0; t < live.rows(); ++t)
      for (int r = 0; r < copies; ++r)
        live(t, r) = (phi.block(t * tile, static_cast<Eigen::Index>(r) * width, std::min(tile, T - t * tile), width)
                          .cwiseAbs()
                          .colwise()
                          .maxCoeff()
                          .array() > negligible.segment(static_cast<Eigen::Index>(r) * width, width).array())
                         .any();
  };
  std::vector<std::exception_ptr> failed(poles.size());
  auto guarded = [&](std::size_t o) {
    try {
      fill(o);
    } catch (...) {
      failed[o] = std::current_exception();
    }
  };
  std::vector<std::thread> workers;
  const bool threaded = T >= 2048;  // below that a thread costs more than it saves
  for (std::size_t o = 1; o < poles.size() && threaded; ++o) workers.emplace_back(guarded, o);
  for (std::size_t o = 0; o < (threaded ? 1 : poles.size()); ++o) guarded(o);
  for (std::thread& t : workers) t.join();
  for (const std::exception_ptr& e : failed)
    if (e) std::rethrow_exception(e);
}

/// The same, returned.
inline ModelRegressors modelRegressors(const std::vector<std::vector<PoleSet>>& poles, const PwlPartition& partition,
                                       const Eigen::MatrixXd& u, const std::vector<std::vector<PlayChannel>>& play = {},
                                       PlayStart start = PlayStart::kRising, double coupling = 0.0,
                                       double schedule_pole = 0.0, ScheduleSide side = ScheduleSide::kOutput,
                                       double threshold = 0.0, double softening = 0.0) {
  ModelRegressors out;
  fillRegressors(out, poles, partition, u, play, start, coupling, schedule_pole, side, threshold, softening);
  return out;
}

/// The regressors of `model`'s own structure (poles, partition, play, start,
/// coupling, threshold, softening, lag and side) for an input record.
inline ModelRegressors modelRegressors(const DioPwlObfModel& model, const Eigen::MatrixXd& u) {
  return modelRegressors(model.poles, model.partition, u, model.input_play, model.play_start, model.play_coupling,
                         model.schedulePole(), model.schedule_side, model.play_threshold, model.play_softening);
}

/// The same into `out`, reusing its storage.
inline void modelRegressors(const DioPwlObfModel& model, const Eigen::MatrixXd& u, ModelRegressors& out) {
  fillRegressors(out, model.poles, model.partition, u, model.input_play, model.play_start, model.play_coupling,
                 model.schedulePole(), model.schedule_side, model.play_threshold, model.play_softening);
}

/// The model's predicted increments dyhat (T x n_y) from regressors of its
/// own structure (modelRegressors(model, u)), for reuse across coefficient sets.
inline Eigen::MatrixXd modelIncrements(const DioPwlObfModel& model, const ModelRegressors& reg) {
  PLSA_CHECK(reg.phi.size() == static_cast<std::size_t>(model.outputCount()),
          "modelIncrements: the regressors were made for another model");
  const auto T = static_cast<Eigen::Index>(reg.schedule.size());
  Eigen::MatrixXd dy(T, model.outputCount());
  if (model.schedule_side == ScheduleSide::kInput) {
    const Eigen::Index tile = ModelRegressors::kTileRows;
    for (int o = 0; o < model.outputCount(); ++o) {
      const auto oo = static_cast<std::size_t>(o);
      const Eigen::VectorXd c = model.stackedCoefficients(o);
      if (reg.live.empty()) {
        dy.col(o) = reg.phi[oo] * c;
        continue;
      }
      const Eigen::Index width = model.regressorSize(o);
      dy.col(o).setZero();
      for (Eigen::Index t = 0; t < reg.live[oo].rows(); ++t)
        for (Eigen::Index r = 0; r < reg.live[oo].cols(); ++r)
          if (reg.live[oo](t, r)) {
            const Eigen::Index rows = std::min(tile, T - t * tile);
            dy.col(o).segment(t * tile, rows).noalias() +=
                reg.phi[oo].block(t * tile, r * width, rows, width) * c.segment(r * width, width);
          }
    }
    return dy;
  }
  for (Eigen::Index k = 0; k < T; ++k) {
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

/// The model's predicted increments dyhat (T x n_y) for an input record.
inline Eigen::MatrixXd modelIncrements(const DioPwlObfModel& model, const Eigen::MatrixXd& u) {
  PLSA_CHECK(u.cols() == model.inputCount(), "modelIncrements: the record has " + std::to_string(u.cols()) +
                                              " inputs, the model " + std::to_string(model.inputCount()));
  return modelIncrements(model, modelRegressors(model, u));
}

/// Input side: the filtered part of the output's level, T x n_y, so that the
/// model's output is output_level + levels and levels(k) - levels(k-1) is the
/// increment dy(k). The filters start settled at the first input, so only the
/// first sample's regressors are needed beside `dy` = modelIncrements(model, u).
inline Eigen::MatrixXd modelLevels(const DioPwlObfModel& model, const Eigen::MatrixXd& u, const Eigen::MatrixXd& dy) {
  PLSA_CHECK(model.schedule_side == ScheduleSide::kInput,
          "modelLevels: only an input-side model has a level that is a function of its inputs");
  PLSA_CHECK(u.rows() >= 1, "modelLevels: empty record");
  PLSA_CHECK(dy.rows() == u.rows() && dy.cols() == model.outputCount(), "modelLevels: increments do not match the record");
  // Settled states depend on the first sample alone (its schedule, played and coupled level).
  const ModelRegressors first = modelRegressors(model, u.topRows(1));
  Eigen::MatrixXd level(u.rows(), model.outputCount());
  for (int o = 0; o < model.outputCount(); ++o) {
    double acc = first.level0[static_cast<std::size_t>(o)].dot(model.stackedCoefficients(o));
    level(0, o) = acc;
    for (Eigen::Index k = 1; k < u.rows(); ++k) level(k, o) = acc += dy(k, o);
  }
  return level;
}

inline Eigen::MatrixXd modelLevels(const DioPwlObfModel& model, const Eigen::MatrixXd& u) {
  return modelLevels(model, u, modelIncrements(model, u));
}

}  // namespace plsa
