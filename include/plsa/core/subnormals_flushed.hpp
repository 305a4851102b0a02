// A scope in which arithmetic flushes subnormal numbers to zero.
#pragma once

#if defined(__SSE2__)
#include <xmmintrin.h>
#endif

namespace plsa {

/// For its scope, arithmetic flushes subnormal results and operands to zero
/// (x86 SSE: MXCSR's FTZ and DAZ bits, restored on exit; elsewhere a no-op).
/// A state that decays towards zero (a filter or a simulated actuator at
/// rest) otherwise enters the subnormal range, where each operation on it
/// costs tens to hundreds of cycles; the values it flushes are below 2.2e-308.
/// Every real-time call of the predictor runs under one, and so does every
/// replay a diagnosis calibrates on.
class SubnormalsFlushed {
 public:
#if defined(__SSE2__)
  SubnormalsFlushed() noexcept : saved_(_mm_getcsr()) { _mm_setcsr(saved_ | 0x8040u); }
  ~SubnormalsFlushed() { _mm_setcsr(saved_); }
#else
  SubnormalsFlushed() noexcept = default;
#endif
  SubnormalsFlushed(const SubnormalsFlushed&) = delete;
  SubnormalsFlushed& operator=(const SubnormalsFlushed&) = delete;

#if defined(__SSE2__)
 private:
  unsigned saved_;
#endif
};

}  // namespace plsa
