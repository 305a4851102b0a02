#include <gtest/gtest.h>

#include <cstdlib>
#include <memory>
#include <vector>

#include <Eigen/Dense>

#include "plsa/testing/alloc_guard.hpp"

// The guard must see allocations, or a zero-allocation test proves nothing.
TEST(AllocGuard, CountsOperatorNew) {
  plsa::testing::AllocGuard guard;
  auto p = std::make_unique<int>(3);
  std::vector<double> v(100);
  EXPECT_EQ(guard.allocations(), 2u);
  EXPECT_EQ(*p + static_cast<int>(v.size()), 103);
}

TEST(AllocGuard, CountsEigenHeapTemporaries) {
  Eigen::MatrixXd a = Eigen::MatrixXd::Random(8, 8);
  plsa::testing::AllocGuard guard;
  Eigen::MatrixXd b = a * a;  // Eigen allocates with malloc, not new
  if (plsa::testing::countsMalloc())
    EXPECT_GE(guard.allocations(), 1u);
  else
    GTEST_SKIP() << "sanitizer build owns malloc; only operator new is counted here";
  EXPECT_GT(b.norm(), 0.0);
}

TEST(AllocGuard, CountsMalloc) {
  if (!plsa::testing::countsMalloc()) GTEST_SKIP() << "sanitizer build owns malloc";
  plsa::testing::AllocGuard guard;
  void* p = std::malloc(64);
  asm volatile("" : : "g"(p) : "memory");  // keep the compiler from eliding the pair
  EXPECT_EQ(guard.allocations(), 1u);
  std::free(p);
}

TEST(AllocGuard, NotArmedOutsideScope) {
  const auto before = plsa::testing::threadAllocationCount();
  { auto p = std::make_unique<int>(1); }
  EXPECT_EQ(plsa::testing::threadAllocationCount(), before);
}
