#include "plsa/identify/lower_gram.hpp"

#include <algorithm>

#include "plsa/core/simd.hpp"

namespace plsa::identify {
namespace {

#if PLSA_X86_DISPATCH
using simd::Quad;

// Columns i .. i+3 (clamped to the last: repeats are not stored) against
// columns j and j+1 (j+1 < n when `two`), four rows a step in sixteen
// accumulators held in registers, then the rows past the last multiple of four.
PLSA_TARGET_AVX2 void lowerGramBlock(const double* p, Eigen::Index ld, Eigen::Index rows, Eigen::Index n,
                                     Eigen::Index i, Eigen::Index j, bool two, double* g, Eigen::Index ldg) {
  const double* b[2] = {p + j * ld, p + (two ? j + 1 : j) * ld};
  const double* a[4];
  for (int k = 0; k < 4; ++k) a[k] = p + std::min(i + k, n - 1) * ld;
  Quad acc[4][2] = {};
  const Eigen::Index quads = rows / 4 * 4;
  for (Eigen::Index r = 0; r < quads; r += 4) {
    const Quad b0 = *simd::quads(b[0] + r), b1 = *simd::quads(b[1] + r);
    for (int k = 0; k < 4; ++k) {
      const Quad x = *simd::quads(a[k] + r);
      acc[k][0] += x * b0;
      acc[k][1] += x * b1;
    }
  }
  for (int k = 0; k < 4 && i + k < n; ++k)
    for (int c = 0; c < (two ? 2 : 1); ++c) {
      if (i + k < j + c) continue;  // the upper triangle of a diagonal block
      double s = (acc[k][c][0] + acc[k][c][1]) + (acc[k][c][2] + acc[k][c][3]);
      for (Eigen::Index r = quads; r < rows; ++r) s += a[k][r] * b[c][r];
      g[(i + k) + (j + c) * ldg] = s;
    }
}

void lowerGramAvx2(const Eigen::Ref<const Eigen::MatrixXd>& p, Eigen::MatrixXd& gram) {
  const Eigen::Index n = p.cols();
  for (Eigen::Index j = 0; j < n; j += 2)
    for (Eigen::Index i = j; i < n; i += 4)
      lowerGramBlock(p.data(), p.outerStride(), p.rows(), n, i, j, j + 1 < n, gram.data(), n);
}
#endif

}  // namespace

void lowerGram(const Eigen::Ref<const Eigen::MatrixXd>& p, Eigen::MatrixXd& gram) {
  gram.resize(p.cols(), p.cols());
#if PLSA_X86_DISPATCH
  if (simd::cpuHasAvx2Fma()) {
    gram.triangularView<Eigen::StrictlyUpper>().setZero();
    return lowerGramAvx2(p, gram);
  }
#endif
  gram.setZero();
  gram.selfadjointView<Eigen::Lower>().rankUpdate(p.transpose());
}

}  // namespace plsa::identify
