// A model compiled for the real-time predictor: immutable, built once at
// set-up (compileModel), shared by any number of predictors and installed
// into a running one by swapping a pointer (pinocchio's Model, where the
// predictor's own state is the Data).
//
// Two forms. The modal form serves every model whose filter banks have real,
// distinct poles with well-conditioned eigenbases (what identification
// produces): each bank's state is kept in its eigenbasis, z = V^-1 x, so a
// step is one multiply-add per state, and the copies of a bank (its play
// channels and, on the input side, its grid nodes) share their modes. A
// prediction merges the copies into one state per mode, zeta = sum M z, with
// M the coefficients carried into the eigenbasis; the horizon then runs on
// the modes alone. Any other model (complex or repeated poles, clustered
// ones) keeps its banks' state-space form and steps them.
#pragma once

#include <cmath>
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include <Eigen/Dense>

#include "plsa/model/dio_pwl_obf_model.hpp"
#include "plsa/predict/predictor_options.hpp"

namespace plsa {

using RowMajorMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

/// The model's filter banks in their eigenbases. Mode q is (input j, output
/// o, pole i), numbered q = (j * outputs + o) * poles + i. Each mode has one
/// state per copy k of its bank: k = node * channels(j) + channel; the states
/// of mode q are z[offset[q], offset[q + 1]).
/// Largest closed-form held-input tables (ModalForm::lag_sum) set-up builds,
/// in doubles (32 MB); beyond it a held input with an unsettled lag steps.
inline constexpr std::size_t kMaxHeldTableDoubles = std::size_t{4} << 20;

/// Below this |lambda - rho^d| a mode and a rate of the lag count as one
/// (their partial fraction would lose about log10(1 / gap) digits).
inline constexpr double kLagGapFloor = 1e-3;

/// Below this |1 - lambda| a mode counts as an integrator: no TipReadout.
inline constexpr double kReadoutGapFloor = 1e-7;

struct ModalForm {
  Eigen::VectorXd lambda;   ///< [modes] the pole
  Eigen::VectorXd beta;     ///< [modes] (V^-1 B) of the mode's bank
  std::vector<int> offset;  ///< [modes + 1] first state of each mode
  /// [regions] x [states]: the coefficient of each state in modal
  /// coordinates, per region (one row on the input side).
  RowMajorMatrix coefficient;
  /// Input side, merged modes: input j's modes (output o, pole i) at
  /// j * block + o * poles + i, each input's block padded with zero modes to
  /// a multiple of 4 so the per-step loops run whole vectors.
  int block = 0;
  Eigen::VectorXd merged_lambda, merged_beta;  ///< [inputs * block], 0 on the padding
  /// [outputs * block]: output o's block is 1 on its modes (o * poles ..
  /// o * poles + poles - 1) and 0 elsewhere, so an output's share of a
  /// block-long total is one masked vector sum.
  Eigen::VectorXd output_mask;
  /// Per input j: [nodes * channels(j)] x [block], the coefficients
  /// transposed so a node's contribution to all of j's modes is one row.
  std::vector<RowMajorMatrix> by_copy;
  /// Input side, every mode settling (|1 - lambda| > kReadoutGapFloor): the
  /// output read from the states (TipReadout). An output moves by its modes'
  /// zeta each step and zeta <- lambda zeta + beta (g' - g), so the output less
  /// sum (beta g - lambda zeta) / (1 - lambda) stays put. readout_level, per
  /// input j: [nodes * channels(j)] x [outputs], each copy's share of that
  /// sum per unit of its level w_r v_c; readout_mode: [modes] lambda / (1 -
  /// lambda). Both empty otherwise.
  std::vector<Eigen::MatrixXd> readout_level;
  Eigen::VectorXd readout_mode;
  /// [output]: max_horizon x (its modes, in mode order), row h = sum_{s<=h} lambda^s;
  /// with lag_sum, D more columns: the same sums of rho^d, d = 1..D.
  std::vector<Eigen::MatrixXd> power_sum;
  /// Input side with a schedule lag: a held input's lagged schedule moves as
  /// rho^h, and within a grid cell each mode's level is a polynomial of
  /// degree <= D (scheduling inputs) in it, so the horizon has a closed form.
  /// [output]: max_horizon x (inputs x (1 + D) x poles), per input j the
  /// columns S (sum_{i<=m} lambda^i) then KS_d for d = 1..D, KS(m) =
  /// sum_{i<=m} K(i), K(0) = 0, K(i+1) = lambda K(i) + rho^(d i), each over
  /// the input's poles: one table product per input that moves.
  /// Empty when there is no lag or the tables would pass kMaxHeldTableDoubles.
  std::vector<Eigen::MatrixXd> lag_sum;
  /// With lag_sum: KS_d = (S_lambda - S_{rho^d}) / (lambda - rho^d), so a
  /// stretch's rows are one product with power_sum. [modes] x [D]: 1 / (lambda -
  /// rho^d), 0 for the pairs closer than kLagGapFloor, which instead take their
  /// KS_d column from lag_sum: lag_coincident [output]: (mode, d).
  Eigen::MatrixXd lag_gap_inverse;
  /// With lag_sum: rho^h for h = 0..max(max_horizon, 4) (0 once below 1e-200).
  Eigen::VectorXd lag_power;
  std::vector<std::vector<std::pair<int, int>>> lag_coincident;
  std::vector<std::vector<int>> modes_of_output;
  /// [o * inputs + j]: the eigenbasis V and its inverse of bank (o, j), to
  /// carry states across a model swap.
  std::vector<Eigen::MatrixXd> basis, basis_inverse;
};

/// The banks as state-space filters (any model): bank b runs x <- A x + B d.
/// Banks are numbered output-major, then node, input, channel: b =
/// ((o * nodes + r) * ... ) as `bank_output`, `bank_node`, `bank_input` and
/// `bank_channel` say; the coefficients of bank b are the segment
/// `coefficient_offset[b]` of its output's (stacked) coefficient vector.
struct StateSpaceForm {
  std::vector<Eigen::MatrixXd> A;  ///< [o * inputs + j]
  std::vector<Eigen::VectorXd> B;  ///< [o * inputs + j]
  /// All poles real: each bank runs as its cascade of first-order all-pass
  /// sections (about 4 flops a section instead of a dense row).
  bool cascade = false;
  std::vector<Eigen::VectorXd> xi, gain;  ///< [o * inputs + j]
  std::vector<Eigen::VectorXd> dc_gain;   ///< [o * inputs + j]: each filter's settled output for a unit input
  std::vector<int> bank_output, bank_node, bank_input, bank_channel, coefficient_offset;
  std::vector<std::vector<Eigen::VectorXd>> coefficient;  ///< [region][output]
};

/// The input-side grid as the predictor looks it up: each scheduling input's
/// levels, searched from the last cell (a lagged input moves a cell at a
/// time), weights as PwlPartition::blend gives them.
struct NodeGrid {
  std::vector<int> inputs;
  std::vector<std::vector<double>> levels;
  std::vector<int> strides;
};

struct CompiledModel {
  int n_u = 0, n_y = 0;
  int poles = 0;  ///< per bank (every bank has as many)
  int nodes = 1;  ///< copies of each bank: the grid nodes on the input side, else 1
  int banks = 0;  ///< outputs x nodes x channels
  OutputFrame frame = OutputFrame::kAsLogged;
  /// tip_cartesian: radians per unit of the logged angles (deg or rad), and units per radian.
  double rad_per_angle_unit = 1.0, angle_unit_per_rad = 1.0;
  double sample_time = 0.0;
  /// tip_cartesian with an output level: samples the sensor's yaw is
  /// registered on after each start (SensorYaw; 0: none), and the training
  /// sensor's yaw drift it turns at, rad per sample; the least bend of a
  /// measured tip registered on, in the tip components' unit.
  int yaw_window = 0;
  double yaw_drift_per_sample = 0.0;
  double yaw_min_bend = 0.0;
  double yaw_forget = 1.0;           ///< SensorYaw tracking's factor per sample (1: none)
  std::vector<double> output_level;  ///< the model's (input side), per output; empty: none
  double accept_min = 0.0, accept_max = 0.0;
  bool input_side = false;
  PwlPartition partition;           ///< the coefficients' schedule (one region on the input side)
  PwlPartition node_partition;      ///< input side: the grid whose nodes weigh the inputs
  NodeGrid node_grid;               ///< the same, for the hot path
  std::vector<PlayChannel> play;    ///< per channel
  std::vector<int> channel_input;   ///< per channel: its input
  std::vector<int> first_channel;   ///< [inputs + 1]: input j's channels are [first, first + 1)
  InputShaping shaping;             ///< the model's: levels and start (channels flattened in `play`)
  double schedule_pole = 0.0;       ///< the scheduling inputs' lag, per sample
  std::vector<double> pole_values;  ///< [o][j][i], to tell whether two models share their bases
  int max_horizon = 0;

  bool modal = false;
  ModalForm modal_form;
  StateSpaceForm state_space;

  int channels(int input) const noexcept {
    return first_channel[static_cast<std::size_t>(input) + 1] - first_channel[static_cast<std::size_t>(input)];
  }
  /// Filter states: banks x poles in either form.
  int states() const noexcept { return banks * poles; }
};

/// The scheduling inputs' lag, one sample on: its next value from `lagged`
/// toward u. The merged modes' planned path steps it so (no branch on its
/// step-to-step chain); the predictor's own state and the step-by-step path
/// take lagTowards.
inline double lagStep(double lagged, double u, double pole) noexcept { return pole * lagged + (1.0 - pole) * u; }

/// lagStep, and once within rounding of u it is u, so a held input settles
/// the schedule exactly (and the predictor takes its held path).
inline double lagTowards(double lagged, double u, double pole) noexcept {
  const double next = lagStep(lagged, u, pole);
  const double scale = std::abs(u) > 1e-3 ? std::abs(u) : 1e-3;
  return std::abs(next - u) <= 1e-12 * scale ? u : next;
}

/// Validates `model` and builds its compiled form for predictors whose
/// options are `options` (the horizon capacity sizes the tables). Throws
/// std::invalid_argument naming what is wrong.
std::shared_ptr<const CompiledModel> compileModel(const DioPwlObfModel& model, const PredictorOptions& options);

/// Whether a predictor running `a` can adopt `b`: the same inputs, outputs,
/// banks, channels, partitions and output frame (the poles and coefficients
/// may differ).
bool sameStructure(const CompiledModel& a, const CompiledModel& b);

}  // namespace plsa
