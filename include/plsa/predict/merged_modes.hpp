// The input side's planned prediction on merged modes (docs/predictor.md):
// each bank's node and channel copies merged once into one state per mode,
// then per step zeta <- lambda zeta + beta (g' - g), g each input's level
// over the grid nodes its lagged input blends. Everything a step reads and
// writes besides the tables lives in this run's own fixed arrays, so the
// compiler keeps it in registers and no store of a predicted row (through
// the caller's matrix) forces it to reload them.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>

#include <Eigen/Dense>

#include "plsa/predict/compiled_model.hpp"
#include "plsa/predict/kernels.hpp"

namespace plsa::merged {

/// Sizes a run keeps in fixed arrays; larger models take the step-by-step path.
inline constexpr int kMaxInputs = 16;
inline constexpr int kMaxChannels = 64;
inline constexpr int kMaxOutputs = 8;
inline constexpr int kMaxBlock = 160;  // outputs x poles, padded to 4
inline constexpr int kMaxGridInputs = 4;

/// Whether a modal input-side model's planned prediction runs here.
inline bool fits(const CompiledModel& m) noexcept {
  return m.modal && m.input_side && m.n_u <= kMaxInputs && static_cast<int>(m.play.size()) <= kMaxChannels &&
         m.n_y <= kMaxOutputs && m.modal_form.block <= kMaxBlock &&
         static_cast<int>(m.node_grid.inputs.size()) <= kMaxGridInputs;
}

/// The plan's inputs as a run steps them: the input, its lag on the
/// scheduling inputs, the played channels and the grid's blend.
struct PlannedSchedule {
  int nu = 0, nc = 0, grid_inputs = 0;
  double pole = 0.0;
  const InputShaping* shaping = nullptr;  ///< the compiled model's (outlives the run)
  bool shaped = false;
  std::array<double, kMaxInputs> u{}, us{};
  std::array<double, kMaxChannels> vc{};
  std::array<PlayChannel, kMaxChannels> play{};
  std::array<int, kMaxChannels> input_of{};
  std::array<int, kMaxGridInputs> grid_input{}, last_level{}, stride{}, hint{};
  std::array<const double*, kMaxGridInputs> levels{};

  PlannedSchedule(const CompiledModel& m, const Eigen::VectorXd& u0, const Eigen::VectorXd& us0,
                  const Eigen::VectorXd& vc0) noexcept
      : nu(m.n_u),
        nc(static_cast<int>(m.play.size())),
        grid_inputs(static_cast<int>(m.node_grid.inputs.size())),
        pole(m.schedule_pole),
        shaping(&m.shaping),
        shaped(m.shaping.shapesLevels()) {
    for (int j = 0; j < nu; ++j) u[j] = u0(j), us[j] = us0(j);
    for (int c = 0; c < nc; ++c) {
      const auto cc = static_cast<std::size_t>(c);
      vc[cc] = vc0(c);
      play[cc] = m.play[cc];
      input_of[cc] = m.channel_input[cc];
    }
    for (int s = 0; s < grid_inputs; ++s) {
      const auto ss = static_cast<std::size_t>(s);
      grid_input[ss] = m.node_grid.inputs[ss];
      levels[ss] = m.node_grid.levels[ss].data();
      last_level[ss] = static_cast<int>(m.node_grid.levels[ss].size()) - 1;
      stride[ss] = m.node_grid.strides[ss];
    }
  }

  /// Row h of a column-major plan (leading dimension ld).
  PLSA_ALWAYS_INLINE void take(const double* plan, Eigen::Index ld, int h) noexcept {
    for (int j = 0; j < nu; ++j) u[static_cast<std::size_t>(j)] = plan[h + j * ld];
  }

  /// The lag's next value toward u (lagTowards, as the predictor's own).
  PLSA_ALWAYS_INLINE void lag() noexcept {
    for (std::size_t j = 0; j < static_cast<std::size_t>(nu); ++j) us[j] = lagTowards(us[j], u[j], pole);
  }

  /// The played channels moved to u (threshold, coupling, softening first).
  PLSA_ALWAYS_INLINE void moveChannels() noexcept {
    const double positive_sum =
        shaping->coupling != 0.0 ? shaping->positiveSum(Eigen::Map<const Eigen::VectorXd>(u.data(), nu)) : 0.0;
    for (int c = 0; c < nc; ++c) {
      const auto cc = static_cast<std::size_t>(c);
      double level = u[static_cast<std::size_t>(input_of[cc])];
      if (shaped) level = shaping->level(level, positive_sum);
      vc[cc] = play[cc].follow(level, vc[cc]);
    }
  }

  /// The grid's blend at us: the same regions and weights as
  /// PwlPartition::blend, each input's cell searched from its last one.
  PLSA_ALWAYS_INLINE void blend(ScheduleBlend& out) noexcept {
    out.count = 1;
    out.region[0] = 0;
    out.weight[0] = 1.0;
    for (int s = 0; s < grid_inputs; ++s) {
      const auto ss = static_cast<std::size_t>(s);
      const double* lv = levels[ss];
      const int last = last_level[ss];
      const double x = us[static_cast<std::size_t>(grid_input[ss])];
      int i = 0;
      double t = 0.0;
      if (x >= lv[last]) {
        i = last;
      } else if (x > lv[0]) {
        i = std::min(hint[ss], last - 1);
        while (x < lv[i]) --i;
        while (x >= lv[i + 1]) ++i;
        t = (x - lv[i]) / (lv[i + 1] - lv[i]);
      }
      hint[ss] = i;
      const int c = out.count;
      for (int k = 0; k < c; ++k) {
        const auto kk = static_cast<std::size_t>(k);
        if (t > 0.0) {
          out.region[kk + static_cast<std::size_t>(c)] = out.region[kk] + (i + 1) * stride[ss];
          out.weight[kk + static_cast<std::size_t>(c)] = out.weight[kk] * t;
        }
        out.region[kk] += i * stride[ss];
        out.weight[kk] *= 1.0 - t;
      }
      if (t > 0.0) out.count = 2 * c;
    }
  }
};

/// Four doubles as one vector (GCC and Clang vector extensions: one AVX
/// register in an AVX2 build, two SSE2 ones otherwise); `Loose` at any
/// double's alignment.
typedef double Quad __attribute__((vector_size(32)));
typedef double LooseQuad __attribute__((vector_size(32), aligned(8)));

/// Doubles seen as quads (GCC's vector types alias their elements).
inline const LooseQuad* quads(const double* p) noexcept { return reinterpret_cast<const LooseQuad*>(p); }
inline LooseQuad* quads(double* p) noexcept { return reinterpret_cast<LooseQuad*>(p); }

/// Input j's levels: sum over the blend's nodes r and j's channels c of
/// w_r v_c times the node-channel row (ModalForm::by_copy), into `level`
/// (one block, a multiple of 4). B: the block size fixed at compile time, or 0.
template <int B>
PLSA_ALWAYS_INLINE void levelsOfInput(const CompiledModel& m, int j, const ScheduleBlend& blend, const double* vc,
                                      double* __restrict level) noexcept {
  const ModalForm& f = m.modal_form;
  const int count = (B > 0 ? B : f.block) / 4;
  const int first = m.first_channel[static_cast<std::size_t>(j)], channels = m.channels(j);
  const double* table = f.by_copy[static_cast<std::size_t>(j)].data();
  Quad acc[B > 0 ? B / 4 : kMaxBlock / 4];
  for (int i = 0; i < count; ++i) acc[i] = Quad{0.0, 0.0, 0.0, 0.0};
  for (int c = 0; c < channels; ++c) {
    const double v = vc[first + c];
    if (v == 0.0) continue;
    for (int k = 0; k < blend.count; ++k) {
      const double weight = blend.weight[static_cast<std::size_t>(k)] * v;
      const Quad w = {weight, weight, weight, weight};
      const double* row =
          table + static_cast<std::ptrdiff_t>(blend.region[static_cast<std::size_t>(k)] * channels + c) * count * 4;
      const LooseQuad* r = merged::quads(row);
      for (int i = 0; i < count; ++i) acc[i] += w * r[i];
    }
  }
  LooseQuad* out = merged::quads(level);
  for (int i = 0; i < count; ++i) out[i] = acc[i];
}

/// Output o's share of a block-long total (its modes o * n .. o * n + n - 1),
/// summed in pairs (half the dependent additions of a running sum).
PLSA_ALWAYS_INLINE double outputSum(const double* total, int o, int n) noexcept {
  const double* t = total + o * n;
  double even = 0.0, odd = 0.0;
  int i = 0;
  for (; i + 1 < n; i += 2) even += t[i], odd += t[i + 1];
  if (i < n) even += t[i];
  return even + odd;
}

/// Where a run starts: each input's merged modes (one block each, padding
/// zero) and the output they add to; `level` is scratch of the same size.
/// With the block size fixed at compile time the run copies the modes into
/// its own arrays; otherwise it works in `zeta` and `level` in place.
struct MergedStart {
  double* zeta = nullptr;     ///< [inputs * block]
  double* level = nullptr;    ///< [inputs * block]
  const double* y = nullptr;  ///< [outputs]
};

/// The run: rows 0..horizon-1 of `out` (column-major, leading dimension
/// ldo) from the merged modes at `start`, the plan (column-major, `plan_rows`
/// rows, held past its last) driving the schedule; `y_end` gets the last
/// row. An input whose channels are zero and whose modes are at rest (a
/// chamber never pressurised) is skipped until it moves.
template <int B>
PLSA_ALWAYS_INLINE void runPlanned(const CompiledModel& m, PlannedSchedule& sched, const MergedStart& start,
                                   int horizon, const double* plan, Eigen::Index plan_ld, Eigen::Index plan_rows,
                                   double* out, Eigen::Index ldo, double* y_end) noexcept {
  const ModalForm& f = m.modal_form;
  const int n = m.poles, block = B > 0 ? B : f.block, nu = m.n_u, ny = m.n_y;
  alignas(32) double own_zeta[kMaxInputs * (B > 0 ? B : 1)];
  alignas(32) double own_level[kMaxInputs * (B > 0 ? B : 1)];
  alignas(32) double total[B > 0 ? B : kMaxBlock];
  double* __restrict zeta = B > 0 ? own_zeta : start.zeta;
  double* __restrict level = B > 0 ? own_level : start.level;
  if (B > 0)
    for (int i = 0; i < nu * block; ++i) zeta[i] = start.zeta[i];
  ScheduleBlend blend;
  sched.blend(blend);
  for (int j = 0; j < nu; ++j) levelsOfInput<B>(m, j, blend, sched.vc.data(), level + j * block);
  std::array<bool, kMaxInputs> resting{};
  for (int j = 0; j < nu; ++j) {
    bool rest = true;
    for (int i = 0; i < block; ++i) rest = rest && zeta[j * block + i] == 0.0 && level[j * block + i] == 0.0;
    resting[static_cast<std::size_t>(j)] = rest;
  }
  for (int i = 0; i < block; ++i) total[i] = 0.0;
  for (int j = 0; j < nu; ++j)
    for (int i = 0; i < block; ++i) total[i] += zeta[j * block + i];
  double y[kMaxOutputs], dy[kMaxOutputs];
  for (int o = 0; o < ny; ++o) {
    y[o] = start.y[o];
    dy[o] = outputSum(total, o, n);
  }
  const double* lambda = f.merged_lambda.data();
  const double* beta = f.merged_beta.data();
  for (int h = 0; h < horizon; ++h) {
    for (int o = 0; o < ny; ++o) out[h + o * ldo] = y[o] += dy[o];
    if (h + 1 == horizon) break;
    if (h < plan_rows) sched.take(plan, plan_ld, h);
    sched.lag();
    sched.moveChannels();
    sched.blend(blend);
    Quad sum[B > 0 ? B / 4 : kMaxBlock / 4];
    for (int i = 0; i < block / 4; ++i) sum[i] = Quad{0.0, 0.0, 0.0, 0.0};
    for (int j = 0; j < nu; ++j) {
      const auto jj = static_cast<std::size_t>(j);
      if (resting[jj]) {
        bool still = true;
        for (int c = m.first_channel[jj]; c < m.first_channel[jj + 1]; ++c)
          still = still && sched.vc[static_cast<std::size_t>(c)] == 0.0;
        if (still) continue;
        resting[jj] = false;
      }
      const int at = j * block;
      alignas(32) double next[B > 0 ? B : kMaxBlock];
      levelsOfInput<B>(m, j, blend, sched.vc.data(), next);
      const LooseQuad *l = quads(lambda + at), *b = quads(beta + at), *g = quads(next);
      LooseQuad *z = quads(zeta + at), *now = quads(level + at);
      for (int i = 0; i < block / 4; ++i) {
        z[i] = l[i] * z[i] + b[i] * (g[i] - now[i]);
        now[i] = g[i];
        sum[i] += z[i];
      }
    }
    LooseQuad* t = quads(total);
    for (int i = 0; i < block / 4; ++i) t[i] = sum[i];
    for (int o = 0; o < ny; ++o) dy[o] = outputSum(total, o, n);
  }
  for (int o = 0; o < ny; ++o) y_end[o] = y[o];
}

}  // namespace plsa::merged
