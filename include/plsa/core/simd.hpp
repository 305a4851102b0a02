// Four-double vectors and run-time dispatch to AVX2 builds of hot loops,
// shared by the predictor's kernels and identification's Gram.
// PLSA_X86_DISPATCH is 1 where the compiler can build a function for AVX2
// (x86-64, GCC or Clang) and the processor is asked at run time whether it
// may run it; PLSA_TARGET_AVX2 marks such a function. Vector code (Quad)
// belongs only in such functions: lowered to SSE2 it was slower than scalar.
#pragma once

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define PLSA_X86_DISPATCH 1
#define PLSA_TARGET_AVX2 __attribute__((target("avx2,fma")))
#define PLSA_ALWAYS_INLINE __attribute__((always_inline)) inline
#else
#define PLSA_X86_DISPATCH 0
#define PLSA_TARGET_AVX2
#define PLSA_ALWAYS_INLINE inline
#endif

namespace plsa::simd {

/// Four doubles as one vector (GCC and Clang vector extensions: one AVX
/// register in an AVX2 function); `LooseQuad` at any double's alignment.
typedef double Quad __attribute__((vector_size(32)));
typedef double LooseQuad __attribute__((vector_size(32), aligned(8)));

/// Doubles seen as quads (GCC's vector types alias their elements).
inline const LooseQuad* quads(const double* p) noexcept { return reinterpret_cast<const LooseQuad*>(p); }
inline LooseQuad* quads(double* p) noexcept { return reinterpret_cast<LooseQuad*>(p); }

/// Whether this processor runs AVX2 (and FMA) code built here; false where
/// nothing is built for it.
inline bool cpuHasAvx2() noexcept {
#if PLSA_X86_DISPATCH
  static const bool yes = __builtin_cpu_supports("avx2");
  return yes;
#else
  return false;
#endif
}
inline bool cpuHasAvx2Fma() noexcept {
#if PLSA_X86_DISPATCH
  static const bool yes = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  return yes;
#else
  return false;
#endif
}

}  // namespace plsa::simd
