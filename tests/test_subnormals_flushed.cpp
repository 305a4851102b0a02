#include "plsa/core/subnormals_flushed.hpp"

#include <gtest/gtest.h>

#include <limits>

namespace {

// x * y at run time (volatile: no constant folding), in the current mode.
double product(double x, double y) {
  volatile double a = x, b = y;
  return a * b;
}

constexpr double kSubnormal = std::numeric_limits<double>::min() / 1024.0;

}  // namespace

// Inside the scope a subnormal operand reads as zero and a subnormal result
// becomes zero; the mode in force before (also an outer scope's) comes back
// when it ends, so a caller's arithmetic is never changed.
TEST(SubnormalsFlushed, FlushesInItsScopeAndRestoresTheModeBefore) {
  ASSERT_GT(product(kSubnormal, 1.0), 0.0);
  ASSERT_GT(product(1e-200, 1e-110), 0.0);  // 1e-310: subnormal
  {
    const plsa::SubnormalsFlushed outer;
#if defined(__SSE2__)
    EXPECT_EQ(product(kSubnormal, 1.0), 0.0);
    EXPECT_EQ(product(1e-200, 1e-110), 0.0);
#endif
    EXPECT_EQ(product(1e-200, 1e-100), 1e-200 * 1e-100);  // normal numbers as ever
    { const plsa::SubnormalsFlushed inner; }
#if defined(__SSE2__)
    EXPECT_EQ(product(kSubnormal, 1.0), 0.0);  // the inner scope restored the outer's mode
#endif
  }
  EXPECT_GT(product(kSubnormal, 1.0), 0.0);
  EXPECT_GT(product(1e-200, 1e-110), 0.0);
}
