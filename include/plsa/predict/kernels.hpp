// The predictor's low-level kernels and arithmetic environment: AVX2+FMA
// builds of the hot loops chosen at run time, the held paths' table
// product, and (from core) the scope in which subnormal numbers are
// flushed to zero.
#pragma once

#include <cmath>

#include <Eigen/Dense>

#include "plsa/core/simd.hpp"
#include "plsa/core/subnormals_flushed.hpp"

#if PLSA_X86_DISPATCH
#include <immintrin.h>
#endif

// x86-64 with GCC or Clang (PLSA_X86_DISPATCH): the hot kernels also come
// compiled for AVX2 and FMA, chosen at run time when the processor has them.

namespace plsa {

/// Whether this processor runs the AVX2+FMA versions of the predictor's kernels.
inline bool predictorUsesAvx2() noexcept { return simd::cpuHasAvx2Fma(); }

/// Whether every entry of a plan is finite, without a branch per entry: x * 0
/// is a signed zero for a finite x and NaN for an infinite or NaN one, so
/// their sum is zero exactly when all are finite (Eigen sums it in vectors).
inline bool finiteEverywhere(const Eigen::Ref<const Eigen::MatrixXd>& plan) noexcept {
  return plan.size() == 0 || (plan.array() * 0.0).sum() == 0.0;
}

/// y[0, rows) += A[0, rows) x [0, cols) for a column-major table with leading
/// dimension ld: the held paths' table products, in a generic and an AVX2 build.
PLSA_ALWAYS_INLINE void accumulateColumnsBody(const double* __restrict a, Eigen::Index ld, int rows, int cols,
                                              const double* __restrict x, double* __restrict y) noexcept {
  int c = 0;
  for (; c + 4 <= cols; c += 4) {  // four columns a pass: y loaded and stored once per four
    const double *a0 = a + c * ld, *a1 = a0 + ld, *a2 = a1 + ld, *a3 = a2 + ld;
    const double x0 = x[c], x1 = x[c + 1], x2 = x[c + 2], x3 = x[c + 3];
    for (int r = 0; r < rows; ++r) y[r] += a0[r] * x0 + a1[r] * x1 + a2[r] * x2 + a3[r] * x3;
  }
  for (; c < cols; ++c) {
    const double* ac = a + c * ld;
    const double xc = x[c];
    for (int r = 0; r < rows; ++r) y[r] += ac[r] * xc;
  }
}
inline void accumulateColumnsGeneric(const double* a, Eigen::Index ld, int rows, int cols, const double* x,
                                     double* y) noexcept {
  accumulateColumnsBody(a, ld, rows, cols, x, y);
}
PLSA_TARGET_AVX2 inline void accumulateColumnsAvx2(const double* a, Eigen::Index ld, int rows, int cols,
                                                   const double* x, double* y) noexcept {
  accumulateColumnsBody(a, ld, rows, cols, x, y);
}
inline void accumulateColumns(const double* a, Eigen::Index ld, int rows, int cols, const double* x,
                              double* y) noexcept {
  if (predictorUsesAvx2())
    accumulateColumnsAvx2(a, ld, rows, cols, x, y);
  else
    accumulateColumnsGeneric(a, ld, rows, cols, x, y);
}

/// The same over `groups` groups of `group` columns (one input's modes
/// each), skipping the groups whose x is all zero (an input at rest): one
/// product per run of groups that move.
inline void accumulateMovingGroups(const double* a, Eigen::Index ld, int rows, int groups, int group, const double* x,
                                   double* y) noexcept {
  int run = 0;  // groups in the run that ends before g
  for (int g = 0; g <= groups; ++g) {
    bool moves = false;
    for (int i = 0; g < groups && i < group; ++i) moves = moves || x[g * group + i] != 0.0;
    if (moves) {
      ++run;
      continue;
    }
    const int start = (g - run) * group;
    if (run > 0) accumulateColumns(a + start * ld, ld, rows, run * group, x + start, y);
    run = 0;
  }
}

/// y[0, n) = sum over c < k of a[c] x[c][0, n), summed in c's order (k >= 1),
/// each y stored once: a Jacobian column from the channels that drive it
/// (generic and AVX2).
PLSA_ALWAYS_INLINE void combineScaledBody(const double* const* x, const double* a, int k, Eigen::Index n,
                                          double* __restrict y) noexcept {
  const double* __restrict x0 = x[0];
  const double a0 = a[0];
  if (k == 1) {
    for (Eigen::Index i = 0; i < n; ++i) y[i] = a0 * x0[i];
    return;
  }
  const double* __restrict x1 = x[1];
  const double a1 = a[1];
  if (k == 2) {
    for (Eigen::Index i = 0; i < n; ++i) y[i] = a0 * x0[i] + a1 * x1[i];
    return;
  }
  const double* __restrict x2 = x[2];
  const double a2 = a[2];
  for (Eigen::Index i = 0; i < n; ++i) y[i] = a0 * x0[i] + a1 * x1[i] + a2 * x2[i];
  for (int c = 3; c < k; ++c) {
    const double* __restrict xc = x[c];
    const double ac = a[c];
    for (Eigen::Index i = 0; i < n; ++i) y[i] += ac * xc[i];
  }
}
inline void combineScaledGeneric(const double* const* x, const double* a, int k, Eigen::Index n, double* y) noexcept {
  combineScaledBody(x, a, k, n, y);
}
PLSA_TARGET_AVX2 inline void combineScaledAvx2(const double* const* x, const double* a, int k, Eigen::Index n,
                                               double* y) noexcept {
  combineScaledBody(x, a, k, n, y);
}
inline void combineScaled(const double* const* x, const double* a, int k, Eigen::Index n, double* y) noexcept {
  if (predictorUsesAvx2())
    combineScaledAvx2(x, a, k, n, y);
  else
    combineScaledGeneric(x, a, k, n, y);
}

/// out[q] = a[offset[q], offset[q + 1]) . x[the same] for q < count: each
/// mode's copies merged through one coefficient row, four lanes a segment
/// (generic and AVX2).
PLSA_ALWAYS_INLINE void segmentDotsBody(const double* __restrict a, const double* __restrict x, const int* offset,
                                        int count, double* __restrict out) noexcept {
  for (int q = 0; q < count; ++q) {
    const int end = offset[q + 1];
    double s0 = 0.0, s1 = 0.0, s2 = 0.0, s3 = 0.0;
    int i = offset[q];
    for (; i + 4 <= end; i += 4) {
      s0 += a[i] * x[i];
      s1 += a[i + 1] * x[i + 1];
      s2 += a[i + 2] * x[i + 2];
      s3 += a[i + 3] * x[i + 3];
    }
    for (; i < end; ++i) s0 += a[i] * x[i];
    out[q] = (s0 + s1) + (s2 + s3);
  }
}
inline void segmentDotsGeneric(const double* a, const double* x, const int* offset, int count, double* out) noexcept {
  segmentDotsBody(a, x, offset, count, out);
}
PLSA_TARGET_AVX2 inline void segmentDotsAvx2(const double* a, const double* x, const int* offset, int count,
                                             double* out) noexcept {
  segmentDotsBody(a, x, offset, count, out);
}
inline void segmentDots(const double* a, const double* x, const int* offset, int count, double* out) noexcept {
  if (predictorUsesAvx2())
    segmentDotsAvx2(a, x, offset, count, out);
  else
    segmentDotsGeneric(a, x, offset, count, out);
}

/// levels[d * stride, + n) += w[d] row[0, n) for d < count: one table row
/// into several weighted sums (zero weights skipped), generic and AVX2.
PLSA_ALWAYS_INLINE void spreadRowBody(const double* __restrict row, int n, const double* __restrict w, int count,
                                      Eigen::Index stride, double* __restrict levels) noexcept {
  for (int d = 0; d < count; ++d) {
    const double wd = w[d];
    if (wd == 0.0) continue;
    double* __restrict level = levels + d * stride;
    for (int i = 0; i < n; ++i) level[i] += wd * row[i];
  }
}
inline void spreadRowGeneric(const double* row, int n, const double* w, int count, Eigen::Index stride,
                             double* levels) noexcept {
  spreadRowBody(row, n, w, count, stride, levels);
}
PLSA_TARGET_AVX2 inline void spreadRowAvx2(const double* row, int n, const double* w, int count, Eigen::Index stride,
                                           double* levels) noexcept {
  spreadRowBody(row, n, w, count, stride, levels);
}
inline void spreadRow(const double* row, int n, const double* w, int count, Eigen::Index stride,
                      double* levels) noexcept {
  if (predictorUsesAvx2())
    spreadRowAvx2(row, n, w, count, stride, levels);
  else
    spreadRowGeneric(row, n, w, count, stride, levels);
}

/// The turn (rad) from direction (px, py) to (x, y) by the arctangent
/// series, into `turn`; 1 when the turn is too large for the series (or
/// points back), else 0.
PLSA_ALWAYS_INLINE double tipTurnOf(double px, double py, double x, double y, double& turn) noexcept {
  const double cross = px * y - py * x, dot = px * x + py * y;
  const double t = cross / dot, t2 = t * t;
  constexpr double c3 = -1.0 / 3, c5 = 1.0 / 5, c7 = -1.0 / 7, c9 = 1.0 / 9, c11 = -1.0 / 11, c13 = 1.0 / 13,
                   c15 = -1.0 / 15;
  turn = t * (1.0 + t2 * (c3 + t2 * (c5 + t2 * (c7 + t2 * (c9 + t2 * (c11 + t2 * (c13 + t2 * c15)))))));
  return ((dot > 0.0) & (std::abs(cross) <= 0.1 * dot)) ? 0.0 : 1.0;
}

/// The turn (rad) from each tip-frame row (x[h], y[h]) to the next, the
/// first from (x0, y0), by the arctangent series (double precision for a
/// tangent up to 0.1), into `turn`; false when some turn is too large for it
/// (or a row points back), and the caller goes row by row with atan2.
/// Vectorises: no row waits for another, and the first row (the only one
/// from outside the arrays) is taken on its own.
PLSA_ALWAYS_INLINE bool tipTurnsBody(const double* __restrict x, const double* __restrict y, int rows, double x0,
                                     double y0, double* __restrict turn) noexcept {
  if (rows <= 0) return true;
  double rough = tipTurnOf(x0, y0, x[0], y[0], turn[0]);
  for (int h = 1; h < rows; ++h) rough += tipTurnOf(x[h - 1], y[h - 1], x[h], y[h], turn[h]);
  return rough == 0.0;
}

/// tipTurnsBody, and each row's length into `bend`: by Eigen's packet square
/// root in the generic build (std::sqrt's errno would keep a loop scalar),
/// four rows at a time in the AVX2 build.
inline bool tipTurnsGeneric(const double* x, const double* y, int rows, double x0, double y0, double* turn,
                            double* bend) noexcept {
  const bool smooth = tipTurnsBody(x, y, rows, x0, y0, turn);
  const Eigen::Map<const Eigen::ArrayXd> xs(x, rows), ys(y, rows);
  Eigen::Map<Eigen::ArrayXd>(bend, rows) = (xs * xs + ys * ys).sqrt();
  return smooth;
}
#if PLSA_X86_DISPATCH
PLSA_TARGET_AVX2 inline bool tipTurnsAvx2(const double* x, const double* y, int rows, double x0, double y0,
                                          double* turn, double* bend) noexcept {
  const bool smooth = tipTurnsBody(x, y, rows, x0, y0, turn);
  int h = 0;
  for (; h + 4 <= rows; h += 4) {
    const __m256d xs = _mm256_loadu_pd(x + h), ys = _mm256_loadu_pd(y + h);
    _mm256_storeu_pd(bend + h, _mm256_sqrt_pd(_mm256_add_pd(_mm256_mul_pd(xs, xs), _mm256_mul_pd(ys, ys))));
  }
  for (; h < rows; ++h) bend[h] = std::sqrt(x[h] * x[h] + y[h] * y[h]);
  return smooth;
}
#endif
inline bool tipTurns(const double* x, const double* y, int rows, double x0, double y0, double* turn,
                     double* bend) noexcept {
#if PLSA_X86_DISPATCH
  if (predictorUsesAvx2()) return tipTurnsAvx2(x, y, rows, x0, y0, turn, bend);
#endif
  return tipTurnsGeneric(x, y, rows, x0, y0, turn, bend);
}

/// Filter states smaller than this are zero (far below any measurable
/// output, far above the subnormal range).
inline constexpr double kTinyState = 1e-150;

}  // namespace plsa
