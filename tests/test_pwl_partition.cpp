// The PWL partition: switched lookup with directions, interpolated blends, no allocation.
#include "support/identify_fixtures.hpp"

using namespace plsa;
using namespace plsa::test_fixtures;
using C = std::complex<double>;

TEST(PwlPartition, SwitchedLookupDirectionsAndWords) {
  const PwlPartition p({0, 1}, {{0.225, 0.275}, {0.25}}, true, 1e-3);
  EXPECT_EQ(p.cellCount(), 6);
  EXPECT_EQ(p.regionCount(), 24);
  DirectionState d;
  const double u1[] = {0.2, 0.3};
  EXPECT_EQ(p.region(u1, d), 0 + 1 * 3);
  const double du[] = {-0.01, 0.0};
  p.updateDirections(du, d);
  EXPECT_EQ(d.dir[0], -1);
  EXPECT_EQ(d.dir[1], 1);  // no move: keeps its direction
  EXPECT_EQ(p.region(u1, d), 3 + 6 * 1);
  EXPECT_EQ(p.describe(9, {"p_1", "p_2"}), "p_1 in [-inf, 0.225) falling, p_2 in [0.25, inf) rising");
  EXPECT_THROW(PwlPartition({0}, {{0.3, 0.2}}), std::invalid_argument);
}

TEST(PwlPartition, InterpolatedBlendIsMultilinearAndClamped) {
  const PwlPartition p = PwlPartition::interpolated({0, 1}, {{0.2, 0.3}, {0.1, 0.2, 0.4}});
  ScheduleBlend b;
  const double u[] = {0.225, 0.3};
  p.blend(u, DirectionState{}, b);
  ASSERT_EQ(b.count, 4);
  double sum = 0, ux = 0, uy = 0;
  for (int m = 0; m < b.count; ++m) {
    sum += b.weight[static_cast<std::size_t>(m)];
    const int r = b.region[static_cast<std::size_t>(m)];
    ux +=
        b.weight[static_cast<std::size_t>(m)] * std::vector<double>{0.2, 0.3}[static_cast<std::size_t>(p.cellOf(r, 0))];
    uy += b.weight[static_cast<std::size_t>(m)] *
          std::vector<double>{0.1, 0.2, 0.4}[static_cast<std::size_t>(p.cellOf(r, 1))];
  }
  EXPECT_NEAR(sum, 1.0, 1e-15);
  EXPECT_NEAR(ux, 0.225, 1e-15);  // weights reproduce the point: multilinear
  EXPECT_NEAR(uy, 0.3, 1e-15);
  const double outside[] = {0.9, -1.0};
  p.blend(outside, DirectionState{}, b);
  ASSERT_EQ(b.count, 1);
  EXPECT_EQ(b.region[0], 1 + 0 * 2);
}

TEST(PwlPartition, LookupAllocatesNothing) {
  const PwlPartition s({0, 1}, {{0.225, 0.275, 0.325}, {0.225, 0.275, 0.325}}, true);
  const PwlPartition i = PwlPartition::interpolated({0, 1}, {{0.2, 0.25, 0.3, 0.35}, {0.2, 0.25, 0.3, 0.35}}, true);
  Eigen::Vector2d u(0.21, 0.33);
  DirectionState d;
  ScheduleBlend b;
  int acc = 0;
  plsa::testing::AllocGuard guard;
  for (int k = 0; k < 10000; ++k) {
    u(0) = 0.2 + 0.15 * std::sin(0.01 * k);
    s.updateDirections(Eigen::Vector2d(std::cos(0.01 * k), 0.0), d);
    acc += s.region(u, d);
    i.blend(u, d, b);
    acc += b.count;
  }
  EXPECT_EQ(guard.allocations(), 0u);
  EXPECT_GT(acc, 0);
}
