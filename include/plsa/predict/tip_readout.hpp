// A modal input-side model's tip read from its filter states instead of
// summed step by step. Each step the output moves by its modes' zeta (a mode's
// copies merged through their coefficients), and zeta <- lambda zeta + beta
// (g' - g), g the mode's level (its copies' w_r v_c through the same
// coefficients), so the output less sum (beta g - lambda zeta) / (1 - lambda)
// stays put: anchored once where the tip is known, the tip at any later
// sample is that constant plus the states' part (ModalForm::readout_level,
// readout_mode). The sensor yaw's tracking reads it on its tracked samples
// only, where summing every step's increments cost the predictor's update
// as much again. Allocation-free.
#pragma once

#include <Eigen/Dense>

#include "plsa/predict/compiled_model.hpp"

namespace plsa {

class TipReadout {
 public:
  /// Whether `m`'s tip can be read from its states (modal, input side, every
  /// mode settling, two tip components).
  static bool available(const CompiledModel& m) noexcept {
    return m.modal && m.input_side && m.n_y >= 2 && m.modal_form.readout_mode.size() > 0;
  }
  /// The states' part of outputs 0 and 1: the merged modes `zeta` (mode order,
  /// as ModelStep::mergeModes), the node weights and channel levels.
  static void statesPart(const CompiledModel& m, const Eigen::VectorXd& zeta, const Eigen::VectorXd& node_w,
                         const Eigen::VectorXd& vc, double part[2]) noexcept {
    const ModalForm& f = m.modal_form;
    const int n = m.poles;
    part[0] = part[1] = 0.0;
    for (int j = 0; j < m.n_u; ++j) {
      const Eigen::MatrixXd& level = f.readout_level[static_cast<std::size_t>(j)];
      const int first = m.first_channel[static_cast<std::size_t>(j)], channels = m.channels(j);
      for (int r = 0; r < m.nodes; ++r) {
        if (node_w(r) == 0.0) continue;
        for (int c = 0; c < channels; ++c) {
          const double w = node_w(r) * vc(first + c);
          part[0] += w * level(r * channels + c, 0);
          part[1] += w * level(r * channels + c, 1);
        }
      }
      for (int o = 0; o < 2; ++o) {
        const int q = (j * m.n_y + o) * n;
        part[o] -= f.readout_mode.segment(q, n).dot(zeta.segment(q, n));
      }
    }
  }
  /// Anchors the readout where the tip is known (`tip`, with the states' part then).
  void anchor(const double tip[2], const double part[2]) noexcept {
    constant_[0] = tip[0] - part[0];
    constant_[1] = tip[1] - part[1];
  }
  /// The tip, from the states' part now.
  void read(const double part[2], double tip[2]) const noexcept {
    tip[0] = constant_[0] + part[0];
    tip[1] = constant_[1] + part[1];
  }

 private:
  double constant_[2] = {0.0, 0.0};
};

}  // namespace plsa
