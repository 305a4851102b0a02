// The predictor's filter states: one step of every filter (modal or
// state-space form, resting inputs skipped, no subnormal tails) and their
// carry into another compiled model's bases at a hot swap. Allocation-free.
#pragma once

#include <array>
#include <cmath>
#include <cstddef>

#include <Eigen/Dense>

#include "plsa/core/check.hpp"
#include "plsa/predict/compiled_model.hpp"
#include "plsa/predict/kernels.hpp"
#include "plsa/predict/merged_modes.hpp"

namespace plsa {

/// Inputs whose resting (never driven) filters a predictor skips; beyond
/// this many, every input's filters step.
inline constexpr int kMaxRestingInputs = 16;

template <int W>
PLSA_ALWAYS_INLINE void stepModesBody(const ModalForm& f, int begin, int end, int width, const double* __restrict d,
                                      double* __restrict state) noexcept {
  const int size = W > 0 ? W : width;
  for (int q = begin; q < end; ++q) {
    double* __restrict z = state + f.offset[static_cast<std::size_t>(q)];
    const double lambda = f.lambda(q), beta = f.beta(q);
#if defined(__SSE2__)
    const merged::Quad l = {lambda, lambda, lambda, lambda}, b = {beta, beta, beta, beta};
    merged::LooseQuad* zq = merged::quads(z);
    const merged::LooseQuad* dq = merged::quads(d);
    int k = 0;
    for (; k + 4 <= size; k += 4) zq[k / 4] = l * zq[k / 4] + b * dq[k / 4];  // four copies a vector
    for (; k < size; ++k) z[k] = lambda * z[k] + beta * d[k];
#else
    for (int k = 0; k < size; ++k) {
      const double next = lambda * z[k] + beta * d[k];
      z[k] = std::abs(next) < kTinyState ? 0.0 : next;
    }
#endif
  }
}

// Modes [begin, end) of one input, each over its `width` copies (W: fixed
// at compile time, or 0): z <- lambda z + beta d.
template <int W>
inline void stepModes(const ModalForm& f, int begin, int end, int width, const double* d, double* state) noexcept {
  stepModesBody<W>(f, begin, end, width, d, state);
}
template <int W>
PLSA_TARGET_AVX2 inline void stepModesAvx2(const ModalForm& f, int begin, int end, int width, const double* d,
                                           double* state) noexcept {
  stepModesBody<W>(f, begin, end, width, d, state);
}

/// One step of every filter: z <- lambda z + beta d (modal), or each bank's
/// x <- A x + B d. On x86 every call runs with subnormals flushed
/// (SubnormalsFlushed); elsewhere states below kTinyState are set to zero
/// here. `resting[j]`: input j's states are all zero; they stay so, and are
/// skipped, while its drive is zero (a chamber never pressurised). `drive`:
/// per copy of each input's banks (ModelStep::driveInputs); `bank_x`: a
/// bank's scratch state (poles long).
inline void stepFilters(const CompiledModel& m, const Eigen::VectorXd& drive, Eigen::VectorXd& state,
                        std::array<bool, kMaxRestingInputs>& resting, Eigen::VectorXd& bank_x) noexcept {
  const int n = m.poles;
  PLSA_DEBUG_ASSERT(state.size() == m.states() && drive.size() >= m.nodes * static_cast<Eigen::Index>(m.play.size()));
  if (m.modal) {
    const ModalForm& f = m.modal_form;
    const int per_input = m.n_y * n;
    for (int j = 0; j < m.n_u; ++j) {
      const int width = m.nodes * m.channels(j);
      const double* __restrict d = drive.data() + m.nodes * m.first_channel[static_cast<std::size_t>(j)];
      if (j < kMaxRestingInputs && resting[static_cast<std::size_t>(j)]) {
        bool still = true;
        for (int k = 0; k < width; ++k) still = still && d[k] == 0.0;
        if (still) continue;
        resting[static_cast<std::size_t>(j)] = false;
      }
      // The AVX2 build pays for its call where a mode has many copies (the
      // input side's grid nodes), not for the output side's one or two.
      const bool avx2 = width >= 8 && predictorUsesAvx2();
      if (width == 16 && avx2)
        stepModesAvx2<16>(f, j * per_input, (j + 1) * per_input, width, d, state.data());
      else if (width == 16)
        stepModes<16>(f, j * per_input, (j + 1) * per_input, width, d, state.data());
      else if (avx2)
        stepModesAvx2<0>(f, j * per_input, (j + 1) * per_input, width, d, state.data());
      else
        stepModes<0>(f, j * per_input, (j + 1) * per_input, width, d, state.data());
    }
    return;
  }
  resting.fill(false);  // tracked in modal form only
  const StateSpaceForm& s = m.state_space;
  for (std::size_t b = 0; b < s.bank_output.size(); ++b) {
    const int j = s.bank_input[b];
    const auto g = static_cast<std::size_t>(s.bank_output[b] * m.n_u + j);
    auto x = state.segment(static_cast<Eigen::Index>(b) * n, n);
    const int k = s.bank_node[b] * m.channels(j) + (s.bank_channel[b] - m.first_channel[static_cast<std::size_t>(j)]);
    const double d = drive(m.nodes * m.first_channel[static_cast<std::size_t>(j)] + k);
    if (s.cascade) {
      double w = d;
      for (Eigen::Index i = 0; i < n; ++i) {
        const double st = x(i);
        x(i) = s.xi[g](i) * st + s.gain[g](i) * w;
        w = s.gain[g](i) * st - s.xi[g](i) * w;
      }
    } else {
      bank_x.noalias() = s.A[g] * x;
      x = bank_x + s.B[g] * d;
    }
    x = (x.array().abs() < kTinyState).select(0.0, x);
  }
}

/// At a swap the filter states carry over: each bank's state x = V z in the
/// old basis becomes z = V^-1 x in the new (nothing to do when both share
/// their poles, so a swap of coefficients alone changes no state at all).
/// `scratch`: as long as the state; `bank_x`: poles long.
inline void carryFilterStates(const CompiledModel& from, const CompiledModel& to, Eigen::VectorXd& state,
                              Eigen::VectorXd& scratch, Eigen::VectorXd& bank_x) noexcept {
  if (from.modal == to.modal && (!from.modal || from.pole_values == to.pole_values)) return;
  const StateSpaceForm& s = from.state_space;
  const int n = from.poles;
  for (std::size_t b = 0; b < s.bank_output.size(); ++b) {
    const int o = s.bank_output[b], j = s.bank_input[b], r = s.bank_node[b];
    const int k = r * from.channels(j) + (s.bank_channel[b] - from.first_channel[static_cast<std::size_t>(j)]);
    const auto g = static_cast<std::size_t>(o * from.n_u + j);
    // In bank order, x of this bank...
    for (int i = 0; i < n; ++i)
      bank_x(i) = from.modal ? state(from.modal_form.offset[static_cast<std::size_t>((j * from.n_y + o) * n + i)] + k)
                             : state(static_cast<Eigen::Index>(b) * n + i);
    if (from.modal) bank_x = from.modal_form.basis[g] * bank_x.eval();
    if (to.modal) bank_x = to.modal_form.basis_inverse[g] * bank_x.eval();
    // ...written where the new form keeps it (one scratch row per bank).
    scratch.segment(static_cast<Eigen::Index>(b) * n, n) = bank_x;
  }
  for (std::size_t b = 0; b < s.bank_output.size(); ++b) {
    const int o = s.bank_output[b], j = s.bank_input[b], r = s.bank_node[b];
    const int k = r * to.channels(j) + (s.bank_channel[b] - to.first_channel[static_cast<std::size_t>(j)]);
    for (int i = 0; i < n; ++i) {
      const double v = scratch(static_cast<Eigen::Index>(b) * n + i);
      if (to.modal)
        state(to.modal_form.offset[static_cast<std::size_t>((j * to.n_y + o) * n + i)] + k) = v;
      else
        state(static_cast<Eigen::Index>(b) * n + i) = v;
    }
  }
}

}  // namespace plsa
