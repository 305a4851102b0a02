// The sensitivity of an n-step prediction to its planned inputs
// (Predictor::sensitivity, docs/predictor.md): with the schedule frozen where
// it is, each play channel drives each output's modes through a cumulative
// modal kernel, and the plan decides, step by step, which channels it moves
// and by how much. The workspace is sized once (allocate) and never
// allocates again.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>

#include <Eigen/Dense>

#include "plsa/core/check.hpp"
#include "plsa/predict/compiled_model.hpp"
#include "plsa/predict/kernels.hpp"
#include "plsa/predict/merged_modes.hpp"
#include "plsa/predict/predictor_options.hpp"
#include "plsa/predict/sensor_yaw.hpp"
#include "plsa/predict/shaped_levels_quad.hpp"

namespace plsa {

/// Inputs a sensitivity is computed for at most (their drive per step is kept
/// in fixed arrays), and play channels.
inline constexpr int kMaxSensitivityInputs = 16;
inline constexpr int kMaxSensitivityChannels = 64;

class PlanSensitivity {
 public:
  void allocate(const CompiledModel& m, int max_horizon) {
    const auto channels = static_cast<Eigen::Index>(m.play.size());
    kernel_.setZero(max_horizon, channels * m.n_y);
    drive_.setZero(static_cast<Eigen::Index>(max_horizon) * channels, m.n_u);
    next_.setZero(static_cast<Eigen::Index>(max_horizon) * channels);
    pushed_.setZero(next_.size());
    turn_.setZero(max_horizon, 4);
    responses_.setZero(static_cast<Eigen::Index>(max_horizon) * m.n_y, channels);
    moving_.setZero(channels);
    weight_.setZero(m.poles);
    vc_.setZero(channels);
  }

  /// The Jacobian of `nominal` (the prediction under `plan`, in the model's
  /// frame) with respect to the plan, into `jacobian`; the schedule frozen at
  /// (us, dir) with node weights node_w, the channels starting at vc.
  void compute(const CompiledModel& m, int horizon, const Eigen::Ref<const Eigen::MatrixXd>& plan,
               const Eigen::VectorXd& us, const DirectionState& dir, const Eigen::VectorXd& node_w,
               const Eigen::VectorXd& vc, const Eigen::Ref<const Eigen::MatrixXd>& nominal, const SensorYaw::Turn& yaw,
               Eigen::Ref<Eigen::MatrixXd> jacobian, JacobianFill what) noexcept {
    frozenKernels(m, horizon, us, dir, node_w);
    if (oneChannelPerInput(m) && predictorUsesAvx2())
      channelPathQuad(m, plan, vc);
    else
      channelPath(m, plan, vc);
    nextPushes(plan.rows(), static_cast<Eigen::Index>(m.play.size()));
    fill(m, horizon, nominal, yaw, jacobian, what == JacobianFill::kWhole);
  }

 private:
  // Sensitivity, stage 1: with the schedule frozen where it is, each channel c
  // drives output o's modes through a_qc (its copies' coefficients weighted
  // by the frozen schedule); one unit on c from plan step s on moves row h by
  // CK_oc(h - 1 - s), CK the cumulative sum of K_oc(m) = sum_q beta_q a_qc lambda_q^m.
  void frozenKernels(const CompiledModel& m, int horizon, const Eigen::VectorXd& us, const DirectionState& dir,
                     const Eigen::VectorXd& node_w) noexcept {
    const ModalForm& f = m.modal_form;
    const int n = m.poles;
    ScheduleBlend blend;
    m.partition.blend(us, dir, blend);
    for (int c = 0; c < static_cast<int>(m.play.size()); ++c) {
      const int j = m.channel_input[static_cast<std::size_t>(c)], first = m.first_channel[static_cast<std::size_t>(j)];
      const int channels = m.channels(j);
      for (int o = 0; o < m.n_y; ++o) {
        auto kernel = kernel_.col(c * m.n_y + o).head(horizon);
        kernel.setZero();
        for (int i = 0; i < n; ++i) {
          const int q = (j * m.n_y + o) * n + i, begin = f.offset[static_cast<std::size_t>(q)];
          double a = 0.0;
          for (int k = 0; k < blend.count; ++k) {
            const auto row = f.coefficient.row(blend.region[static_cast<std::size_t>(k)]);
            if (m.input_side)
              for (int r = 0; r < m.nodes; ++r) a += node_w(r) * row(begin + r * channels + (c - first));
            else
              a += blend.weight[static_cast<std::size_t>(k)] * row(begin + (c - first));
          }
          weight_(i) = f.beta(q) * a;
        }
        // CK = sum_i beta_i a_i S_i(h), S_i(h) = sum_{s<=h} lambda_i^s: input
        // j's columns of the output's power-sum table (modes of an output run
        // input-major), one table product.
        const Eigen::MatrixXd& sums = f.power_sum[static_cast<std::size_t>(o)];
        accumulateColumns(sums.data() + static_cast<Eigen::Index>(j) * n * sums.rows(), sums.rows(), horizon, n,
                          weight_.data(), kernel.data());
      }
    }
  }

  // Sensitivity, stage 2: each channel along the plan: at step s whether the
  // input pushed its band (then the channel takes d level / d u, through the
  // band's slope, the threshold, softening and coupling; otherwise it holds
  // and takes nothing), and the next step that pushes it again.
  void channelPath(const CompiledModel& m, const Eigen::Ref<const Eigen::MatrixXd>& plan,
                   const Eigen::VectorXd& vc_now) noexcept {
    const Eigen::Index steps = plan.rows(), channels = static_cast<Eigen::Index>(m.play.size());
    const int nu = m.n_u;  // at most kMaxSensitivityInputs (sensitivity() checks)
    PLSA_DEBUG_ASSERT(nu <= kMaxSensitivityInputs && plan.cols() == nu && vc_now.size() == channels);
    const InputShaping& shaping = m.shaping;
    vc_ = vc_now;
    double* vc = vc_.data();
    double* drive = drive_.data();  // row-major: (s * channels + c) * nu + k
    int* pushed_at = pushed_.data();
    double u[kMaxSensitivityInputs];
    for (Eigen::Index s = 0; s < steps; ++s) {
      double positive_sum = 0.0;
      for (int j = 0; j < nu; ++j) {
        u[j] = plan(s, j);
        positive_sum += positivePartAbove(u[j], shaping.threshold);
      }
      for (Eigen::Index c = 0; c < channels; ++c) {
        const PlayChannel& play = m.play[static_cast<std::size_t>(c)];
        const int j = m.channel_input[static_cast<std::size_t>(c)];
        const double level = shaping.level(u[j], positive_sum);
        const double before = vc[c], after = play.follow(level, before);
        vc[c] = after;
        double* d = drive + (s * channels + c) * nu;
        for (int k = 0; k < nu; ++k) d[k] = 0.0;
        // At the band's edge a held input moves the channel as soon as it goes
        // on: take that side's derivative (a controller needs it at rest).
        const double half = play.halfWidth(level), tol = 1e-12 * (std::abs(level) + half + 1e-9);
        const bool edge = std::abs(after - (level - half)) <= tol || std::abs(after - (level + half)) <= tol;
        const bool pushed = after != before || edge || play.passesThrough();
        pushed_at[s * channels + c] = pushed ? 1 : 0;
        if (!pushed) continue;  // inside the band
        // d after / d level: 1 -+ the band's growth on the side it was pushed.
        const double growth = level > 0.0 ? play.slope : 0.0;
        const double band = after <= level ? 1.0 - growth : 1.0 + growth;
        const InputShaping::Slopes slope = shaping.slopes(u[j], positive_sum);
        d[j] = band * slope.own;
        if (shaping.coupling == 0.0) continue;
        const double by_others = band * slope.other;
        for (int k = 0; k < nu; ++k)
          if (k != j && shaping.pushesOthers(u[k])) d[k] = by_others;
      }
    }
  }

  // Whether channel c is input c's only one, for at most four inputs (the
  // usual chamber model): channelPathQuad's case.
  static bool oneChannelPerInput(const CompiledModel& m) noexcept {
    bool yes = m.n_u <= 4 && static_cast<int>(m.play.size()) == m.n_u;
    for (int c = 0; yes && c < m.n_u; ++c) yes = m.channel_input[static_cast<std::size_t>(c)] == c;
    return yes;
  }

  // channelPath for oneChannelPerInput in an AVX2 build (as 256-bit vectors
  // lowered to SSE2 it is slower than channelPath), every channel of a step
  // as one vector (lane c channel c), the same arithmetic lane by lane: std::max(0, x) is
  // 0 < x ? x : 0, std::min(a, b) b < a ? b : a, std::max(a, b) a < b ? b : a.
  PLSA_TARGET_AVX2 void channelPathQuad(const CompiledModel& m, const Eigen::Ref<const Eigen::MatrixXd>& plan,
                                        const Eigen::VectorXd& vc_now) noexcept {
    using merged::Quad;
    const Eigen::Index steps = plan.rows();
    const int nu = m.n_u;
    const InputShaping& shaping = m.shaping;
    const double threshold = shaping.threshold, kappa = shaping.coupling;
    const Quad zero{}, one = zero + 1.0;
    Quad vc{}, width{}, slope{}, through{};
    for (int c = 0; c < nu; ++c) {
      const PlayChannel& play = m.play[static_cast<std::size_t>(c)];
      vc[c] = vc_now(c), width[c] = play.width, slope[c] = play.slope;
      through[c] = play.passesThrough() ? 1.0 : 0.0;
    }
    double* drive = drive_.data();  // row-major: (s * channels + c) * nu + k
    int* pushed_at = pushed_.data();
    for (Eigen::Index s = 0; s < steps; ++s) {
      Quad u{};
      for (int j = 0; j < nu; ++j) u[j] = plan(s, j);
      // InputShaping::level and ::slopes: the level above the threshold, softened, coupled.
      const ShapedLevelsQuad shaped = shapedLevelsQuad(shaping, u);
      const Quad level = shaped.level, own = shaped.own, softness = shaped.softness;
      const double positive_sum = shaped.positive_sum;
      const Quad softened_up = zero < shaped.softened ? shaped.softened : zero;
      // The channel's play: PlayChannel::follow, and whether this step pushed its band.
      const Quad before = vc, half = width + slope * (zero < level ? level : zero);
      const Quad low = level - half, high = level + half, held = before < low ? low : before;
      vc = high < held ? high : held;
      const Quad tol = 1e-12 * ((level < zero ? -level : level) + half + 1e-9);
      const Quad off_low = vc - low, off_high = vc - high;
      const auto edge =
          ((off_low < zero ? -off_low : off_low) <= tol) | ((off_high < zero ? -off_high : off_high) <= tol);
      const auto pushed = (vc != before) | edge | (through != zero);
      // d after / d level (1 -+ the band's growth on the side pushed) by d level / d u.
      const Quad band = vc <= level ? one - (zero < level ? slope : zero) : one + (zero < level ? slope : zero);
      const auto flat = threshold > 0.0 ? !(u > threshold) : zero != zero;  // levelAbove is flat below it
      const Quad slope_own =
          flat ? zero : softness * (one - kappa * (zero < shaped.softened ? one : zero) * (positive_sum - own));
      const Quad by_own = pushed ? band * slope_own : zero;
      const Quad by_others = pushed ? band * (-kappa * softened_up) : zero;
      for (int c = 0; c < nu; ++c) {
        double* d = drive + (s * nu + c) * nu;
        pushed_at[s * nu + c] = pushed[c] ? 1 : 0;
        for (int k = 0; k < nu; ++k) d[k] = k == c ? by_own[c] : kappa != 0.0 && u[k] > threshold ? by_others[c] : 0.0;
      }
    }
  }

  // The next push of each channel after each step (from pushed_).
  void nextPushes(Eigen::Index steps, Eigen::Index channels) noexcept {
    for (Eigen::Index c = 0; c < channels; ++c) {
      Eigen::Index next = steps;
      for (Eigen::Index s = steps - 1; s >= 0; --s) {
        next_(s * channels + c) = static_cast<int>(next);
        if (pushed_(s * channels + c)) next = s;
      }
    }
  }

  // Sensitivity, stage 3: jacobian(h, o; s, j) = sum_c D_cj(s) (CK(h-1-s) -
  // CK(h-1-t)), t the channel's next push (the second term only once h-1 >=
  // t); a tip_cartesian model's row pairs turned by the sensor's yaw
  // (SensorYaw::turn) and from components into angles at the nominal prediction on
  // the way (d(bend, steer) / d(x, y)); the structural zeros (rows h <= s of
  // column (s, j)) only when `whole`.
  void fill(const CompiledModel& m, int horizon, const Eigen::Ref<const Eigen::MatrixXd>& nominal,
            const SensorYaw::Turn& yaw, Eigen::Ref<Eigen::MatrixXd> jacobian, bool whole) noexcept {
    const int ny = m.n_y, nu = m.n_u;
    const Eigen::Index channels = static_cast<Eigen::Index>(m.play.size());
    const bool tip = m.frame == OutputFrame::kTipCartesian;
    if (tip) {  // the rows' 2 x 2 turn from the model's components to angles
      const double c = yaw.cos, s = yaw.sin;
      for (int h = 0; h < horizon; ++h) {
        const double x = nominal(h, 0), y = nominal(h, 1), r2 = x * x + y * y;
        const double inv_r = r2 == 0.0 ? 0.0 : 1.0 / std::sqrt(r2);  // straight: no direction to move
        const double inv_r2 = inv_r * inv_r / m.rad_per_angle_unit;
        // (d bend, d steer) by the sensor's components: (bx, sx) * d x + (by, sy) * d y ...
        const double bx = x * inv_r, sx = -y * inv_r2, by = y * inv_r, sy = x * inv_r2;
        // ... which are the model's turned by the yaw: (0, 1) * d x + (2, 3) * d y in the model's.
        turn_(h, 0) = c * bx + s * by;
        turn_(h, 1) = c * sx + s * sy;
        turn_(h, 2) = c * by - s * bx;
        turn_(h, 3) = c * sy - s * sx;
      }
    }
    std::array<const double*, kMaxSensitivityChannels> response{};
    std::array<double, kMaxSensitivityChannels> scale{};
    for (Eigen::Index s = 0; s + 1 < horizon; ++s) {
      const Eigen::Index rows = horizon - 1 - s;  // rows h = s + 1 .. horizon - 1 move with step s
      if (whole)
        for (int j = 0; j < nu; ++j) jacobian.col(s * nu + j).head((s + 1) * ny).setZero();
      // Each channel the step pushes: its rows once, as a column orders them.
      int moving = 0;
      for (Eigen::Index c = 0; c < channels; ++c) {
        if (drive_.row(s * channels + c).isZero(0.0)) continue;
        double* out = responses_.col(moving).data();  // [(h - s - 1) * ny + o]
        channelResponse(ny, c, s, rows, next_(s * channels + c) - s, tip, out);
        moving_[moving++] = static_cast<int>(c);
      }
      // Each input's column: the pushed channels' rows by their drive on it, stored once.
      for (int j = 0; j < nu; ++j) {
        int k = 0;
        for (int i = 0; i < moving; ++i) {
          const double d = drive_(s * channels + moving_[i], j);
          if (d == 0.0) continue;
          response[static_cast<std::size_t>(k)] = responses_.col(i).data();
          scale[static_cast<std::size_t>(k++)] = d;
        }
        double* column = jacobian.col(s * nu + j).data() + (s + 1) * ny;
        if (k == 0)
          std::fill(column, column + rows * ny, 0.0);
        else
          combineScaled(response.data(), scale.data(), k, rows * ny, column);
      }
    }
  }

  // Rows s+1.. of one unit on channel c from step s on, held for `tail`
  // steps: CK(r) - CK(r - tail) per output, turned into angles for a tip
  // frame, interleaved as a Jacobian column orders them (r * ny + o).
  void channelResponse(int ny, Eigen::Index c, Eigen::Index s, Eigen::Index rows, Eigen::Index tail, bool tip,
                       double* __restrict out) const noexcept {
    const Eigen::Index held = std::min(tail, rows);
    if (tip) {  // two outputs, turned on the way: a row's pair at once
      const double *kx = kernel_.col(c * 2).data(), *ky = kernel_.col(c * 2 + 1).data();
      const Pair* turn = reinterpret_cast<const Pair*>(turn_.data()) + 2 * (s + 1);  // rows s + 1 on
      LoosePair* row = reinterpret_cast<LoosePair*>(out);
      for (Eigen::Index r = 0; r < held; ++r) row[r] = turnedPair(turn + 2 * r, kx[r], ky[r]);
      for (Eigen::Index r = held; r < rows; ++r)
        row[r] = turnedPair(turn + 2 * r, kx[r] - kx[r - tail], ky[r] - ky[r - tail]);
      return;
    }
    for (int o = 0; o < ny; ++o) {
      const double* k = kernel_.col(c * ny + o).data();
      for (Eigen::Index r = 0; r < held; ++r) out[r * ny + o] = k[r];
      for (Eigen::Index r = held; r < rows; ++r) out[r * ny + o] = k[r] - k[r - tail];
    }
  }

  // Two doubles as one vector (GCC and Clang vector extensions: one SSE2
  // register); `Loose` at any double's alignment.
  typedef double Pair __attribute__((vector_size(16)));
  typedef double LoosePair __attribute__((vector_size(16), aligned(8)));

  // A row's (d bend, d steer) from its (d x, d y): turn[0] dx + turn[1] dy.
  static PLSA_ALWAYS_INLINE Pair turnedPair(const Pair* turn, double dx, double dy) noexcept {
    return turn[0] * Pair{dx, dx} + turn[1] * Pair{dy, dy};
  }

  Eigen::MatrixXd kernel_;  // [h][c * n_y + o]: CK
  RowMajorMatrix drive_;    // [step * channels + channel] x inputs
  Eigen::VectorXi next_, pushed_;
  Eigen::Matrix<double, Eigen::Dynamic, 4, Eigen::RowMajor> turn_;  // [h]: two pairs (turnedPair)
  Eigen::MatrixXd responses_;  // a step's pushed channels' rows, one column each (channelResponse)
  Eigen::VectorXi moving_;     // their channels
  Eigen::VectorXd weight_;     // one kernel's beta a per pole
  Eigen::VectorXd vc_;         // the channels along the plan
};

}  // namespace plsa
