// The predictor's low-level kernels and arithmetic environment: AVX2+FMA
// builds of the hot loops chosen at run time, the held paths' table
// product, and the scope in which subnormal numbers are flushed to zero.
#pragma once

#include <cmath>

#include <Eigen/Dense>

#if defined(__SSE2__)
#include <xmmintrin.h>
#endif

// x86-64 with GCC or Clang: the hot kernels also come compiled for AVX2 and
// FMA, chosen at run time when the processor has them.
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define PLSA_PREDICT_AVX2 1
#define PLSA_TARGET_AVX2 __attribute__((target("avx2,fma")))
#define PLSA_ALWAYS_INLINE __attribute__((always_inline)) inline
#else
#define PLSA_PREDICT_AVX2 0
#define PLSA_TARGET_AVX2
#define PLSA_ALWAYS_INLINE inline
#endif

namespace plsa {

/// Whether this processor runs the AVX2+FMA versions of the predictor's kernels.
inline bool predictorUsesAvx2() noexcept {
#if PLSA_PREDICT_AVX2
  static const bool yes = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  return yes;
#else
  return false;
#endif
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

/// y[0, n) = a x[0, n), or += with `add`, in a generic and an AVX2 build.
PLSA_ALWAYS_INLINE void addScaledBody(const double* __restrict x, double a, Eigen::Index n, double* __restrict y,
                                      bool add) noexcept {
  if (add)
    for (Eigen::Index i = 0; i < n; ++i) y[i] += a * x[i];
  else
    for (Eigen::Index i = 0; i < n; ++i) y[i] = a * x[i];
}
inline void addScaledGeneric(const double* x, double a, Eigen::Index n, double* y, bool add) noexcept {
  addScaledBody(x, a, n, y, add);
}
PLSA_TARGET_AVX2 inline void addScaledAvx2(const double* x, double a, Eigen::Index n, double* y, bool add) noexcept {
  addScaledBody(x, a, n, y, add);
}
inline void addScaled(const double* x, double a, Eigen::Index n, double* y, bool add) noexcept {
  if (predictorUsesAvx2())
    addScaledAvx2(x, a, n, y, add);
  else
    addScaledGeneric(x, a, n, y, add);
}

/// The turn (rad) from each tip-frame row (x[h], y[h]) to the next, the
/// first from (x0, y0), by the arctangent series (double precision for a
/// tangent up to 0.1), into `turn`; false when some turn is too large for it
/// (or a row points back), and the caller goes row by row with atan2. Also
/// each row's length into `bend`. Vectorises: no row waits for another.
PLSA_ALWAYS_INLINE bool tipTurnsBody(const double* __restrict x, const double* __restrict y, int rows, double x0,
                                     double y0, double* __restrict turn, double* __restrict bend) noexcept {
  int rough = 0;
  for (int h = 0; h < rows; ++h) {
    const double px = h ? x[h - 1] : x0, py = h ? y[h - 1] : y0;
    const double cross = px * y[h] - py * x[h], dot = px * x[h] + py * y[h];
    rough |= static_cast<int>(!((dot > 0.0) & (std::abs(cross) <= 0.1 * dot)));
    const double t = cross / dot, t2 = t * t;
    turn[h] =
        t *
        (1.0 + t2 * (-1.0 / 3 +
                     t2 * (1.0 / 5 + t2 * (-1.0 / 7 + t2 * (1.0 / 9 + t2 * (-1.0 / 11 + t2 * (1.0 / 13 - t2 / 15)))))));
    bend[h] = std::sqrt(x[h] * x[h] + y[h] * y[h]);
  }
  return rough == 0;
}
inline bool tipTurnsGeneric(const double* x, const double* y, int rows, double x0, double y0, double* turn,
                            double* bend) noexcept {
  return tipTurnsBody(x, y, rows, x0, y0, turn, bend);
}
PLSA_TARGET_AVX2 inline bool tipTurnsAvx2(const double* x, const double* y, int rows, double x0, double y0,
                                          double* turn, double* bend) noexcept {
  return tipTurnsBody(x, y, rows, x0, y0, turn, bend);
}
inline bool tipTurns(const double* x, const double* y, int rows, double x0, double y0, double* turn,
                     double* bend) noexcept {
  return predictorUsesAvx2() ? tipTurnsAvx2(x, y, rows, x0, y0, turn, bend)
                             : tipTurnsGeneric(x, y, rows, x0, y0, turn, bend);
}

/// Filter states smaller than this are zero (far below any measurable
/// output, far above the subnormal range).
inline constexpr double kTinyState = 1e-150;

/// For its scope, arithmetic flushes subnormal results and operands to zero
/// (x86 SSE: MXCSR's FTZ and DAZ bits, restored on exit; elsewhere a no-op,
/// and the stored states' flush alone keeps them out). Every real-time call
/// of the predictor runs under one, so no intermediate of a prediction can
/// slow down on a subnormal number either.
class SubnormalsFlushed {
 public:
#if defined(__SSE2__)
  SubnormalsFlushed() noexcept : saved_(_mm_getcsr()) { _mm_setcsr(saved_ | 0x8040u); }
  ~SubnormalsFlushed() { _mm_setcsr(saved_); }

 private:
  unsigned saved_;
#endif
};

}  // namespace plsa
