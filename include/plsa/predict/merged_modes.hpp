// The input side's planned prediction on merged modes (docs/predictor.md):
// each bank's node and channel copies merged once into one state per mode,
// then per step zeta <- lambda zeta + beta (g' - g), g each input's level
// over the grid nodes its lagged input blends. Steps go in chunks: first the
// schedule's pass over the chunk (plan rows, lag, channels, the cell's
// corners), whose only carried state is the schedule's, then each input's
// vector pass over the same steps, whose only carried state is its modes;
// neither waits on the other step by step. Everything a run reads and writes
// besides the tables lives in its own fixed arrays.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>

#include <Eigen/Dense>

#include "plsa/core/check.hpp"
#include "plsa/predict/compiled_model.hpp"
#include "plsa/predict/kernels.hpp"
#include "plsa/predict/shaped_levels_quad.hpp"

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

using simd::LooseQuad;
using simd::Quad;
using simd::quads;

/// The plan's inputs as a run steps them: the input, its lag on the
/// scheduling inputs, the played channels and the grid's blend.
struct PlannedSchedule {
  int nu = 0, nc = 0, grid_inputs = 0;
  double pole = 0.0;
  const InputShaping* shaping = nullptr;  ///< the compiled model's (outlives the run)
  bool shaped = false;
  std::array<double, kMaxInputs> u{}, us{};
  std::array<double, kMaxChannels> vc;  ///< the first nc set
  const PlayChannel* play = nullptr;    ///< [nc] the compiled model's
  const int* input_of = nullptr;        ///< [nc] each channel's input
  std::array<int, kMaxGridInputs> grid_input{}, last_level{}, stride{}, upper_step{}, hint{};
  std::array<const double*, kMaxGridInputs> levels{};
  /// One channel per input and at most four inputs (the usual chamber
  /// model), in an AVX2 run: stepQuad moves every input, lag and channel as one vector each,
  /// lane j input j (lanes past the inputs stay zero). The quads then hold
  /// the state; `us` is kept for the blend.
  bool quad = false;
  Quad u4{}, us4{}, vc4{}, width4{}, slope4{};

  PlannedSchedule(const CompiledModel& m, const Eigen::VectorXd& u0, const Eigen::VectorXd& us0,
                  const Eigen::VectorXd& vc0) noexcept
      : nu(m.n_u),
        nc(static_cast<int>(m.play.size())),
        grid_inputs(static_cast<int>(m.node_grid.inputs.size())),
        pole(m.schedule_pole),
        shaping(&m.shaping),
        shaped(m.shaping.shapesLevels()),
        play(m.play.data()),
        input_of(m.channel_input.data()) {
    for (int j = 0; j < nu; ++j) u[j] = u0(j), us[j] = us0(j);
    for (int c = 0; c < nc; ++c) {
      const auto cc = static_cast<std::size_t>(c);
      vc[cc] = vc0(c);
    }
    quad = nu <= 4 && nc == nu && predictorUsesAvx2();  // as 256-bit vectors lowered to SSE2 it is slower
    for (int c = 0; c < nc; ++c) quad = quad && input_of[c] == c;
    for (int j = 0; quad && j < nu; ++j) {
      u4[j] = u[static_cast<std::size_t>(j)], us4[j] = us[static_cast<std::size_t>(j)];
      vc4[j] = vc[static_cast<std::size_t>(j)];
      width4[j] = play[j].width, slope4[j] = play[j].slope;
    }
    for (int s = 0; s < grid_inputs; ++s) {
      const auto ss = static_cast<std::size_t>(s);
      grid_input[ss] = m.node_grid.inputs[ss];
      levels[ss] = m.node_grid.levels[ss].data();
      last_level[ss] = static_cast<int>(m.node_grid.levels[ss].size()) - 1;
      stride[ss] = m.node_grid.strides[ss];
      upper_step[ss] = last_level[ss] > 0 ? stride[ss] : 0;  // one level: the upper corner is the node itself
    }
  }

  /// One step's inputs: row h of a column-major plan (leading dimension ld)
  /// when `take`, else u held; the lag's next value toward u (lagStep: over
  /// a plan the lag is not snapped to u; it settles within about
  /// ulp(u) / (1 - pole) of u, which moves a prediction by rounding only);
  /// returns positiveSum(u) when the coupling needs it.
  PLSA_ALWAYS_INLINE double takeAndLag(const double* plan, Eigen::Index ld, int h, bool take) noexcept {
    const double threshold = shaping->threshold;
    const bool coupled = shaping->coupling != 0.0;
    double positive_sum = 0.0;
    for (int j = 0; j < nu; ++j) {
      const auto jj = static_cast<std::size_t>(j);
      if (take) u[jj] = plan[h + j * ld];
      us[jj] = lagStep(us[jj], u[jj], pole);
      if (coupled) positive_sum += positivePartAbove(u[jj], threshold);
    }
    return positive_sum;
  }

  /// The played channels moved to u (threshold, coupling, softening first;
  /// positive_sum from takeAndLag): `next` from `previous` (either may be vc).
  PLSA_ALWAYS_INLINE void moveChannels(double positive_sum, const double* previous, double* next) const noexcept {
    for (int c = 0; c < nc; ++c) {
      const auto cc = static_cast<std::size_t>(c);
      double level = u[static_cast<std::size_t>(input_of[cc])];
      if (shaped) level = shaping->level(level, positive_sum);
      next[c] = play[cc].follow(level, previous[c]);
    }
  }

  /// takeAndLag and moveChannels for a quad schedule, lane by lane the
  /// same arithmetic; the channels into `next` (four doubles). What one step
  /// hands the next is the lag (one multiply-add) and the channels (a clamp).
  PLSA_ALWAYS_INLINE void stepQuad(const double* plan, Eigen::Index ld, int h, bool take, double* next) noexcept {
    // Lane by lane as the scalar functions pick, NaN included: std::max(0, x)
    // is 0 < x ? x : 0, std::max(a, b) a < b ? b : a, std::min(a, b) b < a ? b : a.
    const Quad zero{};
    if (take) {
      Quad v{};
      for (int j = 0; j < nu; ++j) v[j] = plan[h + j * ld];
      u4 = v;
    }
    us4 = pole * us4 + (1.0 - pole) * u4;  // lagStep's arithmetic (a Quad through a non-AVX2 function changes its ABI)
    *quads(us.data()) = us4;
    const Quad level = shaped ? shapedLevelsQuad(*shaping, u4).level : u4;  // InputShaping::level
    const Quad half = width4 + slope4 * (zero < level ? level : zero);      // PlayChannel::follow
    const Quad low = level - half, high = level + half;
    const Quad held = vc4 < low ? low : vc4;
    vc4 = high < held ? high : held;
    *quads(next) = vc4;
  }

  /// The grid's blend at us: the regions and weights of PwlPartition::blend,
  /// each input's cell searched from its last one, always all 2^inputs
  /// corners of the cell (a corner the blend does not use weighs 0; an input
  /// at or past its last level takes the cell below at weight 1), so the
  /// step has no branch on where the input sits in its cell.
  PLSA_ALWAYS_INLINE void blend(ScheduleBlend& out) noexcept {
    int base = 0;
    double t[kMaxGridInputs];
    for (int s = 0; s < grid_inputs; ++s) {
      const auto ss = static_cast<std::size_t>(s);
      const double* lv = levels[ss];
      const int last = last_level[ss];
      const double x = us[static_cast<std::size_t>(grid_input[ss])];
      int i = 0;
      t[s] = 0.0;
      if (last > 0 && x >= lv[last]) {
        i = last - 1;
        t[s] = 1.0;
      } else if (last > 0 && x > lv[0]) {
        i = std::min(hint[ss], last - 1);
        while (x < lv[i]) --i;
        while (x >= lv[i + 1]) ++i;
        t[s] = (x - lv[i]) / (lv[i + 1] - lv[i]);
      }
      hint[ss] = i;
      base += i * stride[ss];
    }
    switch (grid_inputs) {  // the usual grids with their loops unrolled
      case 1:
        return corners<1>(base, t, out);
      case 2:
        return corners<2>(base, t, out);
      default:
        return corners<0>(base, t, out);
    }
  }

  /// The cell's corners from its lowest node `base` and the inputs' places
  /// t in it; G: the grid's inputs fixed at compile time, or 0.
  template <int G>
  PLSA_ALWAYS_INLINE void corners(int base, const double* t, ScheduleBlend& out) const noexcept {
    const int g = G > 0 ? G : grid_inputs;
    PLSA_DEBUG_ASSERT(g <= kMaxGridInputs && (G == 0 || G == grid_inputs));
    out.count = 1 << g;
    for (int k = 0; k < (1 << g); ++k) {
      int region = base;
      double weight = 1.0;
      for (int s = 0; s < g; ++s) {
        const bool upper = (k >> s) & 1;
        region += upper ? upper_step[static_cast<std::size_t>(s)] : 0;
        weight *= upper ? t[s] : 1.0 - t[s];
      }
      out.region[static_cast<std::size_t>(k)] = region;
      out.weight[static_cast<std::size_t>(k)] = weight;
    }
  }
};

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
  const std::ptrdiff_t node_rows = static_cast<std::ptrdiff_t>(channels) * count * 4;  // one node's rows
  PLSA_DEBUG_ASSERT((B == 0 || B == f.block) && f.block % 4 == 0 && f.block <= kMaxBlock);
  PLSA_DEBUG_ASSERT(blend.count >= 1 && blend.count <= (1 << kMaxGridInputs));
  Quad acc[B > 0 ? B / 4 : kMaxBlock / 4];
  for (int i = 0; i < count; ++i) acc[i] = Quad{0.0, 0.0, 0.0, 0.0};
  if (channels == 1) {  // the usual input: one channel, a row per node
    const double v = vc[first];
    for (int k = 0; k < blend.count; ++k) {
      const double weight = blend.weight[static_cast<std::size_t>(k)] * v;
      const Quad w = {weight, weight, weight, weight};
      const LooseQuad* r = merged::quads(table + blend.region[static_cast<std::size_t>(k)] * node_rows);
      for (int i = 0; i < count; ++i) acc[i] += w * r[i];
    }
  }
  for (int k = 0; k < (channels == 1 ? 0 : blend.count); ++k) {
    const double* node = table + blend.region[static_cast<std::size_t>(k)] * node_rows;
    const double w_k = blend.weight[static_cast<std::size_t>(k)];
    for (int c = 0; c < channels; ++c) {
      const double weight = w_k * vc[first + c];
      const Quad w = {weight, weight, weight, weight};
      const LooseQuad* r = merged::quads(node + c * count * 4);
      for (int i = 0; i < count; ++i) acc[i] += w * r[i];
    }
  }
  LooseQuad* out = merged::quads(level);
  for (int i = 0; i < count; ++i) out[i] = acc[i];
}

/// Output o's share of a block-long total: its modes summed through the
/// output's mask (ModalForm::output_mask), a vector at a time.
template <int B>
PLSA_ALWAYS_INLINE double outputShare(const double* total, const double* mask, int block) noexcept {
  const LooseQuad *t = quads(total), *k = quads(mask);
  Quad acc = t[0] * k[0];
  for (int i = 1; i < (B > 0 ? B : block) / 4; ++i) acc += t[i] * k[i];
  return (acc[0] + acc[2]) + (acc[1] + acc[3]);
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

/// Steps a run takes its schedule for at once (the schedule's pass), before
/// the modes follow them (the vector pass).
inline constexpr int kChunk = 8;

/// One chunk's schedule: per step the grid's blend and the channels' values.
struct ScheduleChunk {
  int steps = 0;
  std::array<ScheduleBlend, kChunk> blend;
  double vc[kChunk][kMaxChannels];
};

/// The schedule's pass: steps first .. first + chunk.steps - 1, each taking
/// its plan row (held past the plan's last), lagging, moving the channels and
/// blending. Its only carried state is the schedule's own, so successive
/// steps overlap in the processor instead of waiting on the modes.
PLSA_ALWAYS_INLINE void scheduleSteps(PlannedSchedule& sched, int first, const double* plan, Eigen::Index plan_ld,
                                      Eigen::Index plan_rows, ScheduleChunk& chunk) noexcept {
  if (sched.quad) {
    for (int k = 0; k < chunk.steps; ++k) {
      sched.stepQuad(plan, plan_ld, first + k, first + k < plan_rows, chunk.vc[k]);
      sched.blend(chunk.blend[static_cast<std::size_t>(k)]);
    }
    return;
  }
  for (int k = 0; k < chunk.steps; ++k) {
    const int h = first + k;
    const double positive_sum = sched.takeAndLag(plan, plan_ld, h, h < plan_rows);
    sched.moveChannels(positive_sum, k == 0 ? sched.vc.data() : chunk.vc[k - 1], chunk.vc[k]);
    sched.blend(chunk.blend[static_cast<std::size_t>(k)]);
  }
  if (chunk.steps > 0) std::copy(chunk.vc[chunk.steps - 1], chunk.vc[chunk.steps - 1] + sched.nc, sched.vc.data());
}

/// Whether input j's channels stay zero over the whole chunk.
inline bool channelsRestIn(const CompiledModel& m, int j, const ScheduleChunk& chunk) noexcept {
  const auto jj = static_cast<std::size_t>(j);
  for (int k = 0; k < chunk.steps; ++k)
    for (int c = m.first_channel[jj]; c < m.first_channel[jj + 1]; ++c)
      if (chunk.vc[k][c] != 0.0) return false;
  return true;
}

/// The vector pass for input j over the chunk: its levels at each step's
/// blend, zeta <- lambda zeta + beta (g' - g), and zeta added into each
/// step's total (inputs in order, as one step at a time would).
template <int B>
PLSA_ALWAYS_INLINE void modesOverChunk(const CompiledModel& m, int j, const ScheduleChunk& chunk,
                                       double* __restrict zeta, double* __restrict level,
                                       double* __restrict totals) noexcept {
  const ModalForm& f = m.modal_form;
  const int block = B > 0 ? B : f.block, at = j * block;
  const int count = block / 4;
  const LooseQuad *l = quads(f.merged_lambda.data() + at), *b = quads(f.merged_beta.data() + at);
  LooseQuad *z = quads(zeta + at), *now = quads(level + at);
  // The modes and levels in locals over the chunk (registers for a fixed
  // block): each step's update waits on the last one's, not on a store.
  Quad zk[B > 0 ? B / 4 : kMaxBlock / 4], gk[B > 0 ? B / 4 : kMaxBlock / 4];
  for (int i = 0; i < count; ++i) zk[i] = z[i], gk[i] = now[i];
  for (int k = 0; k < chunk.steps; ++k) {
    alignas(32) double next[B > 0 ? B : kMaxBlock];
    levelsOfInput<B>(m, j, chunk.blend[static_cast<std::size_t>(k)], chunk.vc[k], next);
    const LooseQuad* g = quads(next);
    LooseQuad* t = quads(totals + k * block);
    for (int i = 0; i < count; ++i) {
      zk[i] = l[i] * zk[i] + b[i] * (g[i] - gk[i]);
      gk[i] = g[i];
      t[i] += zk[i];
    }
  }
  for (int i = 0; i < count; ++i) z[i] = zk[i], now[i] = gk[i];
}

/// The run: rows 0..horizon-1 of `out` (column-major, leading dimension
/// ldo) from the merged modes at `start`, the plan (column-major, `plan_rows`
/// rows, held past its last) driving the schedule; `y_end` gets the last
/// row. Steps go in chunks of kChunk: the schedule's pass, then each input's
/// vector pass, then the rows. An input whose channels are zero and whose
/// modes are at rest (a chamber never pressurised) is skipped until it moves.
template <int B>
PLSA_ALWAYS_INLINE void runPlanned(const CompiledModel& m, PlannedSchedule& sched, const MergedStart& start,
                                   int horizon, const double* plan, Eigen::Index plan_ld, Eigen::Index plan_rows,
                                   double* out, Eigen::Index ldo, double* y_end) noexcept {
  const ModalForm& f = m.modal_form;
  const int block = B > 0 ? B : f.block, nu = m.n_u, ny = m.n_y;
  PLSA_DEBUG_ASSERT(fits(m) && (B == 0 || B == f.block) && horizon >= 1 && plan_rows >= 0);
  alignas(32) double own_zeta[kMaxInputs * (B > 0 ? B : 1)];
  alignas(32) double own_level[kMaxInputs * (B > 0 ? B : 1)];
  alignas(32) double totals[kChunk * (B > 0 ? B : kMaxBlock)];
  double* __restrict zeta = B > 0 ? own_zeta : start.zeta;
  double* __restrict level = B > 0 ? own_level : start.level;
  if (B > 0)
    for (int i = 0; i < nu * block; ++i) zeta[i] = start.zeta[i];
  ScheduleChunk chunk;
  sched.blend(chunk.blend[0]);
  for (int j = 0; j < nu; ++j) levelsOfInput<B>(m, j, chunk.blend[0], sched.vc.data(), level + j * block);
  std::array<bool, kMaxInputs> resting{};
  for (int j = 0; j < nu; ++j) {
    bool rest = true;
    for (int i = 0; i < block; ++i) rest = rest && zeta[j * block + i] == 0.0 && level[j * block + i] == 0.0;
    resting[static_cast<std::size_t>(j)] = rest;
  }
  for (int i = 0; i < block; ++i) totals[i] = 0.0;
  for (int j = 0; j < nu; ++j)
    for (int i = 0; i < block; ++i) totals[i] += zeta[j * block + i];
  const double* mask = f.output_mask.data();
  double y[kMaxOutputs];
  for (int o = 0; o < ny; ++o) out[o * ldo] = y[o] = start.y[o] + outputShare<B>(totals, mask + o * block, block);
  for (int first = 0; first + 1 < horizon; first += kChunk) {
    chunk.steps = std::min(kChunk, horizon - 1 - first);
    scheduleSteps(sched, first, plan, plan_ld, plan_rows, chunk);
    for (int i = 0; i < chunk.steps * block; ++i) totals[i] = 0.0;
    for (int j = 0; j < nu; ++j) {
      const auto jj = static_cast<std::size_t>(j);
      if (resting[jj] && channelsRestIn(m, j, chunk)) continue;
      resting[jj] = false;
      modesOverChunk<B>(m, j, chunk, zeta, level, totals);
    }
    for (int k = 0; k < chunk.steps; ++k)
      for (int o = 0; o < ny; ++o)
        out[first + k + 1 + o * ldo] = y[o] += outputShare<B>(totals + k * block, mask + o * block, block);
  }
  for (int o = 0; o < ny; ++o) y_end[o] = y[o];
}

}  // namespace plsa::merged
