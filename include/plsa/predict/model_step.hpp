// One sample of a compiled DIO-PWL-OBF model's filter banks, the step the
// predictor runs on its states at every tick and along every plan: the
// played channels moved to the input, the node weights to the lagged
// schedule, every filter stepped with its drive; and the increment dy the
// states give for the next sample, their copies merged through the
// coefficients scheduled at (us, dir). Owns its workspace (allocate()); no
// allocation, lock or throw after that.
#pragma once

#include <array>
#include <cstddef>

#include <Eigen/Dense>

#include "plsa/predict/compiled_model.hpp"
#include "plsa/predict/filter_states.hpp"
#include "plsa/predict/kernels.hpp"

namespace plsa {

class ModelStep {
 public:
  /// Sizes the workspace for `m`'s structure (any model of it shares it).
  void allocate(const CompiledModel& m) {
    delta_.setZero(static_cast<Eigen::Index>(m.play.size()));
    next_node_w_.setZero(m.input_side ? m.nodes : 0);
    bank_x_.setZero(m.poles);
    zeta_.setZero(static_cast<Eigen::Index>(m.n_u) * m.n_y * m.poles);
    blended_.setZero(m.states());
    drive_.setZero(static_cast<Eigen::Index>(m.nodes) * static_cast<Eigen::Index>(m.play.size()));
  }

  /// One bank's state: the scratch carryFilterStates and dense banks use.
  Eigen::VectorXd& bankScratch() noexcept { return bank_x_; }

  /// us <- the lag's next value toward u (lagTowards).
  static void lagSchedule(const CompiledModel& m, const Eigen::VectorXd& u, Eigen::VectorXd& us) noexcept {
    for (Eigen::Index j = 0; j < us.size(); ++j) us(j) = lagTowards(us(j), u(j), m.schedule_pole);
  }

  /// Dense node weights (input side) at the scheduling point us.
  static void nodeWeights(const CompiledModel& m, const Eigen::VectorXd& us, Eigen::VectorXd& w) noexcept {
    ScheduleBlend blend;
    m.node_partition.blend(us, DirectionState{}, blend);
    w.setZero();
    for (int k = 0; k < blend.count; ++k)
      w(blend.region[static_cast<std::size_t>(k)]) += blend.weight[static_cast<std::size_t>(k)];
  }

  /// Moves the channels to u and steps every filter with its drive; on the
  /// input side the node weights move to the lagged input us (node_w holds
  /// the previous ones).
  void advance(const CompiledModel& m, Eigen::VectorXd& state, Eigen::VectorXd& vc, const Eigen::VectorXd& us,
               Eigen::VectorXd& node_w, const Eigen::VectorXd& u,
               std::array<bool, kMaxRestingInputs>& resting) noexcept {
    moveChannels(m, u, vc);
    if (m.input_side) nodeWeights(m, us, next_node_w_);
    driveInputs(m, vc, node_w);
    stepFilters(m, drive_, state, resting, bank_x_);
    if (m.input_side) node_w = next_node_w_;
  }

  /// zeta <- each mode's copies merged through the coefficients scheduled at
  /// (us, dir): one number per mode.
  void mergeModes(const CompiledModel& m, const Eigen::VectorXd& state, const Eigen::VectorXd& us,
                  const DirectionState& dir, Eigen::VectorXd& zeta) noexcept {
    const ModalForm& f = m.modal_form;
    ScheduleBlend blend;
    m.partition.blend(us, dir, blend);
    if (blend.count == 1) {  // one region (always on the input side): its row as it is
      segmentDots(f.coefficient.data() + static_cast<Eigen::Index>(blend.region[0]) * f.coefficient.cols(),
                  state.data(), f.offset.data(), static_cast<int>(zeta.size()), zeta.data());
      return;
    }
    blended_.setZero();
    for (int k = 0; k < blend.count; ++k)
      blended_ += blend.weight[static_cast<std::size_t>(k)] *
                  f.coefficient.row(blend.region[static_cast<std::size_t>(k)]).transpose();
    for (Eigen::Index q = 0; q < zeta.size(); ++q) {
      const int begin = f.offset[static_cast<std::size_t>(q)],
                width = f.offset[static_cast<std::size_t>(q) + 1] - begin;
      zeta(q) = blended_.segment(begin, width).dot(state.segment(begin, width));
    }
  }

  /// dy for the next sample from the filter states, scheduled on (us, dir).
  void increments(const CompiledModel& m, const Eigen::VectorXd& state, const Eigen::VectorXd& us,
                  const DirectionState& dir, Eigen::VectorXd& dy) noexcept {
    if (m.modal) {
      mergeModes(m, state, us, dir, zeta_);
      sumModes(m, zeta_, dy);
      return;
    }
    const StateSpaceForm& s = m.state_space;
    ScheduleBlend blend;
    m.partition.blend(us, dir, blend);
    const int n = m.poles;
    dy.setZero();
    for (std::size_t b = 0; b < s.bank_output.size(); ++b) {
      const int o = s.bank_output[b];
      double dot = 0.0;
      for (int k = 0; k < blend.count; ++k)
        dot += blend.weight[static_cast<std::size_t>(k)] *
               s.coefficient[static_cast<std::size_t>(blend.region[static_cast<std::size_t>(k)])]
                            [static_cast<std::size_t>(o)]
                                .segment(s.coefficient_offset[b], n)
                                .dot(state.segment(static_cast<Eigen::Index>(b) * n, n));
      dy(o) += dot;
    }
  }

 private:
  // Moves the played channels to the input u (delta_: how far each moved).
  void moveChannels(const CompiledModel& m, const Eigen::VectorXd& u, Eigen::VectorXd& vc) noexcept {
    const double positive_sum = m.shaping.coupling != 0.0 ? m.shaping.positiveSum(u) : 0.0;  // unused when uncoupled
    for (std::size_t c = 0; c < m.play.size(); ++c) {
      const auto cc = static_cast<Eigen::Index>(c);
      const double level = m.shaping.level(u(m.channel_input[c]), positive_sum);
      const double next = m.play[c].follow(level, vc(cc));
      delta_(cc) = next - vc(cc);
      vc(cc) = next;
    }
  }

  // What drives the filters this step: per copy of each input's banks (node
  // r, channel c at nodes * first_channel(j) + r * channels(j) + c), the
  // channel's move, or on the input side the move of its node's weight times
  // the channel (w' v' - w v); every output's and pole's bank of that copy
  // takes the same drive.
  void driveInputs(const CompiledModel& m, const Eigen::VectorXd& vc, const Eigen::VectorXd& node_w) noexcept {
    const int nodes = m.nodes;
    for (int ch = 0; ch < static_cast<int>(m.play.size()); ++ch) {
      const int j = m.channel_input[static_cast<std::size_t>(ch)];
      const int first = m.first_channel[static_cast<std::size_t>(j)], channels = m.channels(j);
      double* __restrict d = drive_.data() + nodes * first + (ch - first);
      const double v = vc(ch), before = v - delta_(ch);
      if (!m.input_side) {
        d[0] = delta_(ch);
        continue;
      }
      const double* __restrict next = next_node_w_.data();
      const double* __restrict now = node_w.data();
      if (channels == 1) {
        for (int r = 0; r < nodes; ++r) d[r] = next[r] * v - now[r] * before;
      } else {
        for (int r = 0; r < nodes; ++r) d[r * channels] = next[r] * v - now[r] * before;
      }
    }
  }

  // dy_o = the sum of output o's modes (modes run input, output, pole).
  static void sumModes(const CompiledModel& m, const Eigen::VectorXd& zeta, Eigen::VectorXd& dy) noexcept {
    const int n = m.poles;
    const double* z = zeta.data();
    for (int o = 0; o < m.n_y; ++o) dy(o) = 0.0;
    for (int j = 0; j < m.n_u; ++j)
      for (int o = 0; o < m.n_y; ++o, z += n) {
        double acc = 0.0;
        for (int i = 0; i < n; ++i) acc += z[i];
        dy(o) += acc;
      }
  }

  Eigen::VectorXd delta_;           // per played channel: how far it moved this step
  Eigen::VectorXd drive_;           // per state: what drives it this step
  Eigen::VectorXd next_node_w_;     // input side: the node weights after this step
  Eigen::VectorXd bank_x_;          // one bank's state (swaps, dense banks)
  Eigen::VectorXd zeta_, blended_;  // increments(): the merged modes, the blended coefficients
};

}  // namespace plsa
