// InputShaping's level, lane by lane, for the AVX2 paths whose quads hold
// one input per lane (merged::PlannedSchedule::stepQuad and
// PlanSensitivity::channelPathQuad): InputShaping::level's arithmetic, with
// the parts InputShaping::slopes chains through. std::max(0, x) is
// 0 < x ? x : 0 and std::min(a, b) b < a ? b : a, lane by lane, NaN included.
#pragma once

#include "plsa/core/simd.hpp"
#include "plsa/model/input_shaping.hpp"

namespace plsa {

/// One step's shaped levels, lane j input j; lanes past the inputs hold 0,
/// and so add nothing to the positive sum (thresholds are >= 0).
struct ShapedLevelsQuad {
  simd::Quad own;             ///< max(0, the input counted from the threshold)
  simd::Quad softened;        ///< the level before the coupling: x - s x^2, x = min(own, 1 / 2s), where own > 0
  simd::Quad softness;        ///< d softened / d own
  simd::Quad level;           ///< InputShaping::level
  double positive_sum = 0.0;  ///< InputShaping::positiveSum
};

PLSA_ALWAYS_INLINE ShapedLevelsQuad shapedLevelsQuad(const InputShaping& shaping, const simd::Quad& u) noexcept {
  using simd::Quad;
  const Quad zero{}, one = zero + 1.0;
  const double threshold = shaping.threshold, soft = shaping.softening;
  ShapedLevelsQuad s;
  const Quad gap = u - threshold, above = zero < gap ? gap : zero;
  s.positive_sum = ((above[0] + above[1]) + above[2]) + above[3];
  const Quad counted = threshold > 0.0 ? above : u;  // levelAbove
  s.own = zero < counted ? counted : zero;
  s.softened = counted;
  s.softness = one;
  if (soft > 0.0) {
    const Quad x = 0.5 / soft < s.own ? zero + 0.5 / soft : s.own;
    s.softened = zero < s.own ? x - soft * x * x : counted;
    s.softness = zero < s.own ? (s.own < 0.5 / soft ? 1.0 - 2.0 * soft * s.own : zero) : one;
  }
  const Quad softened_up = zero < s.softened ? s.softened : zero;
  s.level = s.softened - shaping.coupling * softened_up * (s.positive_sum - s.own);  // coupledLevel
  return s;
}

}  // namespace plsa
