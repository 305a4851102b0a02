// The input side's prediction under a held input while its lagged schedule
// still moves (docs/predictor.md, "The paths of predict()"): in each stretch
// where every scheduling input stays in one grid cell the mode levels are
// polynomials in rho^h, so each stretch is a product of the closed-form
// tables (ModalForm::power_sum, lag_sum) with its start state; a cell change
// is one explicit step between two stretches. Its workspace is sized once.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include <Eigen/Dense>

#include "plsa/predict/compiled_model.hpp"
#include "plsa/predict/kernels.hpp"
#include "plsa/predict/merged_modes.hpp"

namespace plsa {

class HeldLaggedForm {
 public:
  void allocate(const CompiledModel& m) {
    const Eigen::Index slots = m.modal && m.input_side ? static_cast<Eigen::Index>(m.n_u) * m.modal_form.block : 0;
    for (Eigen::VectorXd* v : {&merged_, &g_, &g_next_}) v->setZero(slots);
    held_levels_.setZero(slots * static_cast<Eigen::Index>(m.node_grid.inputs.size() + 1));
    lag_drive_.setZero(static_cast<Eigen::Index>(m.n_u) * m.poles +
                       static_cast<Eigen::Index>(m.node_grid.inputs.size()));
    work_us_.setZero(m.n_u);
  }

  void run(const CompiledModel& m, const Eigen::VectorXd& zeta, const Eigen::VectorXd& us, const Eigen::VectorXd& u,
           const Eigen::VectorXd& vc, const Eigen::VectorXd& y, int horizon, Eigen::Ref<Eigen::MatrixXd> out) noexcept {
    const ModalForm& f = m.modal_form;
    const int block = f.block, per_input = m.n_y * m.poles;
    PLSA_DEBUG_ASSERT(m.node_grid.inputs.size() <= 4 && static_cast<int>(f.lag_sum.size()) == m.n_y);
    vc_ = &vc;
    lag_power_ = &f.lag_power;
    merged_.setZero();
    for (int j = 0; j < m.n_u; ++j) merged_.segment(j * block, per_input) = zeta.segment(j * per_input, per_input);
    const int inputs = static_cast<int>(m.node_grid.inputs.size());
    for (int s = 0; s < inputs; ++s) {
      lag_start_[static_cast<std::size_t>(s)] = us(m.node_grid.inputs[static_cast<std::size_t>(s)]);
      lag_target_[static_cast<std::size_t>(s)] = u(m.node_grid.inputs[static_cast<std::size_t>(s)]);
    }
    for (int o = 0; o < m.n_y; ++o) base_[static_cast<std::size_t>(o)] = y(o);
    for (int first = 0; first < horizon;) {
      const int last = stretchEnd(m, first, horizon);
      stretchLevels(m, first);
      heldStretchRows(m, first, last, out);
      if (last + 1 < horizon) stepAcrossCells(m, first, last);
      for (int o = 0; o < m.n_y; ++o) base_[static_cast<std::size_t>(o)] = out(last, o);
      first = last + 1;
    }
  }

 private:
  // A held input's lagged scheduling input s, h steps ahead.
  double laggedAt(int s, int h) const noexcept {
    const auto ss = static_cast<std::size_t>(s);
    return lag_target_[ss] + (lag_start_[ss] - lag_target_[ss]) * (*lag_power_)(h);
  }

  // The cell of a scheduling input at x (as PwlPartition::blend takes it):
  // -1 below or at the first level, L-1 at or above the last, else i with
  // levels[i] <= x < levels[i + 1].
  static int cellOf(const std::vector<double>& lv, double x) noexcept {
    if (x >= lv.back()) return static_cast<int>(lv.size()) - 1;
    if (!(x > lv.front())) return -1;
    return static_cast<int>(std::upper_bound(lv.begin(), lv.end(), x) - lv.begin()) - 1;
  }

  // The last step of the stretch starting at `first` in which no scheduling
  // input changes cell (the lag moves each monotonically toward its target).
  int stretchEnd(const CompiledModel& m, int first, int horizon) const noexcept {
    const double pole = m.schedule_pole;
    int last = horizon - 1;
    for (std::size_t s = 0; s < m.node_grid.inputs.size(); ++s) {
      const std::vector<double>& lv = m.node_grid.levels[s];
      const int cell = cellOf(lv, laggedAt(static_cast<int>(s), first));
      // The first later step in another cell: its estimate from the logarithm, then checked.
      const double x = laggedAt(static_cast<int>(s), first), target = lag_target_[s];
      if (cellOf(lv, target) == cell || x == target) continue;
      const double bound = target < x
                               ? lv[static_cast<std::size_t>(std::max(cell, 0))]
                               : lv[static_cast<std::size_t>(std::min(cell + 1, static_cast<int>(lv.size()) - 1))];
      const double ratio = (bound - target) / (x - target);
      int h = first + 1;
      if (ratio > 0.0 && ratio < 1.0)
        h = std::max(first + 1, first + static_cast<int>(std::log(ratio) / std::log(pole)) - 1);
      while (h <= last && cellOf(lv, laggedAt(static_cast<int>(s), h)) == cell) ++h;
      last = std::min(last, h - 1);
    }
    return last;
  }

  // The stretch's levels as polynomials in e = rho^(h - first): level_d (d =
  // 0..D) per mode slot, from the weights of its cell's corners.
  void stretchLevels(const CompiledModel& m, int first) noexcept {
    const ModalForm& f = m.modal_form;
    const NodeGrid& grid = m.node_grid;
    const int inputs = static_cast<int>(grid.inputs.size()), block = f.block;
    // Corners: node index and weight polynomial (degree <= inputs).
    int corners = 1;
    corner_node_[0] = 0;
    std::fill(corner_poly_[0].begin(), corner_poly_[0].end(), 0.0);
    corner_poly_[0][0] = 1.0;
    for (int s = 0; s < inputs; ++s) {
      const auto ss = static_cast<std::size_t>(s);
      const std::vector<double>& lv = grid.levels[ss];
      const double x = laggedAt(s, first), target = lag_target_[ss];
      const int cell = cellOf(lv, x);
      if (cell < 0 || cell == static_cast<int>(lv.size()) - 1) {  // outside: the edge node, weight 1
        for (int c = 0; c < corners; ++c)
          corner_node_[static_cast<std::size_t>(c)] += std::max(cell, 0) * grid.strides[ss];
        continue;
      }
      const double width = lv[static_cast<std::size_t>(cell) + 1] - lv[static_cast<std::size_t>(cell)];
      const double a = (target - lv[static_cast<std::size_t>(cell)]) / width, b = (x - target) / width;  // t = a + b e
      for (int c = 0; c < corners; ++c) {
        auto& low = corner_poly_[static_cast<std::size_t>(c)];
        auto& high = corner_poly_[static_cast<std::size_t>(c + corners)];
        for (int d = inputs; d >= 0; --d) {
          const double below = d > 0 ? low[static_cast<std::size_t>(d) - 1] : 0.0;
          high[static_cast<std::size_t>(d)] = a * low[static_cast<std::size_t>(d)] + b * below;
          low[static_cast<std::size_t>(d)] = (1.0 - a) * low[static_cast<std::size_t>(d)] - b * below;
        }
        corner_node_[static_cast<std::size_t>(c + corners)] =
            corner_node_[static_cast<std::size_t>(c)] + (cell + 1) * grid.strides[ss];
        corner_node_[static_cast<std::size_t>(c)] += cell * grid.strides[ss];
      }
      corners *= 2;
    }
    held_levels_.setZero();
    for (int j = 0; j < m.n_u; ++j) {
      const int first_channel = m.first_channel[static_cast<std::size_t>(j)], channels = m.channels(j);
      const double* table = f.by_copy[static_cast<std::size_t>(j)].data();
      for (int c = 0; c < corners; ++c)
        for (int ch = 0; ch < channels; ++ch) {
          const double v = (*vc_)(first_channel + ch);
          if (v == 0.0) continue;
          const double* row =
              table + static_cast<std::ptrdiff_t>(corner_node_[static_cast<std::size_t>(c)] * channels + ch) * block;
          std::array<double, 5> w{};
          for (int d = 0; d <= inputs; ++d)
            w[static_cast<std::size_t>(d)] = v * corner_poly_[static_cast<std::size_t>(c)][static_cast<std::size_t>(d)];
          spreadRow(row, block, w.data(), inputs + 1, merged_.size(), held_levels_.data() + j * block);
        }
    }
  }

  // Rows first..last: y = base + sum over each output's modes of
  // S(m) zeta(first) + sum_d KS_d(m) c_d, c_d = beta level_d (rho^d - 1),
  // m = h - first. With KS_d = (S - S_d) / (lambda - rho^d) (ModalForm::
  // lag_gap_inverse) that is one product with the power sums of the modes
  // and of the rates rho^d; the pairs too close to divide add their own KS_d.
  void heldStretchRows(const CompiledModel& m, int first, int last, Eigen::Ref<Eigen::MatrixXd> out) noexcept {
    const ModalForm& f = m.modal_form;
    const int n = m.poles, block = f.block, inputs = static_cast<int>(m.node_grid.inputs.size());
    const int rows = last - first + 1, modes = m.n_u * n;
    const Eigen::Index slots = merged_.size();
    std::array<double, 5> drop{};  // rho^d - 1
    for (int d = 1; d <= inputs; ++d) drop[static_cast<std::size_t>(d)] = f.lag_power(d) - 1.0;
    double* x = lag_drive_.data();
    const Eigen::Index gaps = f.lag_gap_inverse.rows();
    for (int o = 0; o < m.n_y; ++o) {
      for (int j = 0; j < m.n_u; ++j) {
        for (int i = 0; i < n; ++i) x[j * n + i] = merged_(j * block + o * n + i);
      }
      for (int d = 1; d <= inputs; ++d) {  // each mode's c_d / (lambda - rho^d), and their sum for S_{rho^d}
        double rate = 0.0;
        const double* gap = f.lag_gap_inverse.data() + (d - 1) * gaps;
        for (int j = 0; j < m.n_u; ++j) {
          const Eigen::Index slot = j * block + o * n, q = (j * m.n_y + o) * n;
          for (int i = 0; i < n; ++i) {
            const double c = drive(f, slot + i, d, slots, drop) * gap[q + i];
            x[j * n + i] += c;
            rate -= c;
          }
        }
        x[modes + d - 1] = rate;
      }
      auto column = out.col(o).segment(first, rows);
      column.setConstant(base_[static_cast<std::size_t>(o)]);
      const Eigen::MatrixXd& sums = f.power_sum[static_cast<std::size_t>(o)];
      accumulateMovingGroups(sums.data(), sums.rows(), rows, m.n_u, n, x, column.data());
      accumulateColumns(sums.data() + modes * sums.rows(), sums.rows(), rows, inputs, x + modes, column.data());
      const Eigen::MatrixXd& table = f.lag_sum[static_cast<std::size_t>(o)];
      for (const auto& [q, d] : f.lag_coincident[static_cast<std::size_t>(o)]) {
        const int j = q / (m.n_y * n), i = q % n;
        const double c = drive(f, j * block + o * n + i, d, slots, drop);
        if (c != 0.0)
          accumulateColumns(table.data() + (j * (inputs + 1) * n + d * n + i) * table.rows(), table.rows(), rows, 1, &c,
                            column.data());
      }
    }
  }

  // c_d of a merged mode: beta level_d (rho^d - 1).
  double drive(const ModalForm& f, Eigen::Index slot, int d, Eigen::Index slots,
               const std::array<double, 5>& drop) const noexcept {
    return f.merged_beta(slot) * held_levels_(d * slots + slot) * drop[static_cast<std::size_t>(d)];
  }

  // From the last step of one stretch to the first of the next: the modes
  // at `last` from the closed form, then one explicit step to the new cell.
  void stepAcrossCells(const CompiledModel& m, int first, int last) noexcept {
    const ModalForm& f = m.modal_form;
    const int n = m.poles, block = f.block, inputs = static_cast<int>(m.node_grid.inputs.size());
    const int steps = last - first;
    const Eigen::Index slots = merged_.size();
    const double e = f.lag_power(steps);
    std::array<double, 5> drop{};  // rho^d - 1
    for (int d = 1; d <= inputs; ++d) drop[static_cast<std::size_t>(d)] = f.lag_power(d) - 1.0;
    const int width = (inputs + 1) * n;
    for (int o = 0; o < m.n_y; ++o) {
      const Eigen::MatrixXd& table = f.lag_sum[static_cast<std::size_t>(o)];
      for (int j = 0; j < m.n_u; ++j)
        for (int i = 0; i < n; ++i) {
          const Eigen::Index slot = j * block + o * n + i;
          // One step's term of a cumulative column: its difference.
          auto term = [&](int d) {
            const Eigen::Index col = j * width + d * n + i;
            return steps == 0 ? (d == 0 ? 1.0 : 0.0) : table(steps, col) - table(steps - 1, col);
          };
          double z = term(0) * merged_(slot), level = held_levels_(slot);  // lambda^steps zeta
          double ed = 1.0;
          for (int d = 1; d <= inputs; ++d) {
            ed *= e;
            z += f.merged_beta(slot) * held_levels_(d * slots + slot) * drop[static_cast<std::size_t>(d)] * term(d);
            level += held_levels_(d * slots + slot) * ed;
          }
          merged_(slot) = z;
          g_(slot) = level;  // the level at `last`
        }
    }
    // The level one step on, in its new cell, explicitly.
    for (std::size_t s = 0; s < m.node_grid.inputs.size(); ++s)
      work_us_(m.node_grid.inputs[s]) = laggedAt(static_cast<int>(s), last + 1);
    ScheduleBlend blend;
    m.node_partition.blend(work_us_, DirectionState{}, blend);
    for (int j = 0; j < m.n_u; ++j) merged::levelsOfInput<0>(m, j, blend, vc_->data(), g_next_.data() + j * block);
    for (Eigen::Index k = 0; k < slots; ++k)
      merged_(k) = f.merged_lambda(k) * merged_(k) + f.merged_beta(k) * (g_next_(k) - g_(k));
  }

  const Eigen::VectorXd* vc_ = nullptr;         // the channels of the run under way
  const Eigen::VectorXd* lag_power_ = nullptr;  // the model's rho^h
  Eigen::VectorXd merged_, g_, g_next_, work_us_;
  // The scheduling inputs' start and target, the stretch's corners (node,
  // weight polynomial) and level polynomials.
  std::array<double, 4> lag_start_{}, lag_target_{};
  std::array<double, 8> base_{};
  std::array<int, 16> corner_node_{};
  std::array<std::array<double, 5>, 16> corner_poly_{};
  Eigen::VectorXd held_levels_, lag_drive_;
};

}  // namespace plsa
