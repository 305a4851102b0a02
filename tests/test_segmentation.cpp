// Step 1: the reference's one-input steps and its levels (plsa/identify/segmentation.hpp).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "plsa/identify/segmentation.hpp"

using namespace plsa::identify;

TEST(Segmentation, FindsOneInputStepsAndLevels) {
  Eigen::MatrixXd ref = Eigen::MatrixXd::Zero(600, 2);
  ref.block(100, 0, 500, 1).setConstant(0.2);
  ref.block(200, 1, 400, 1).setConstant(0.25);
  ref.block(300, 0, 300, 1).setConstant(0.3);
  ref.block(400, 0, 200, 1).setConstant(0.35);
  ref.block(400, 1, 200, 1).setConstant(0.3);  // both move at once: not a local step
  const auto segs = segmentSteps(ref, 0.01, 50);
  ASSERT_EQ(segs.size(), 3u);
  EXPECT_EQ(segs[1].input, 1);
  EXPECT_EQ(segs[1].begin, 200);
  EXPECT_EQ(segs[1].end, 300);
  EXPECT_TRUE(segs[2].rising());
  EXPECT_DOUBLE_EQ(segs[2].to, 0.3);
  const auto levels = referenceLevels(ref, 0.01, 50);
  EXPECT_EQ(levels[0], (std::vector<double>{0.0, 0.2, 0.3, 0.35}));
}

// Pressures logged without their commands: a staircase through a pneumatic
// lag, with sensor noise and a spike. As logged their noise cuts them at
// nearly every sample, so no step holds 1 s; their plateaus give back each
// step (the input that moved, its direction, where it started to move) and
// each commanded level once.
TEST(Segmentation, PlateausOfMeasuredPressuresGiveTheirCommandsSteps) {
  const Eigen::Index hold = 240, min_len = 80;  // 3 s steps at 80 Hz; a local step needs 1 s
  // The regulator holds 0.2475 at 0.247 one time and 0.248 the next: the two
  // sides of a rounding boundary of the 0.005 resolution, one level still.
  const std::vector<double> first = {0.0, 0.2, 0.247, 0.3, 0.248, 0.2, 0.2, 0.2};
  const std::vector<double> second = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.3, 0.25};
  const auto n = static_cast<Eigen::Index>(first.size()) * hold;
  Eigen::MatrixXd cmd(n, 3), u(n, 3);
  for (Eigen::Index k = 0; k < n; ++k) {
    const auto i = static_cast<std::size_t>(k / hold);
    cmd.row(k) << first[i], second[i], 0.0;
  }
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.002);
  const double pole = std::exp(-1.0 / 8.0);  // a 0.1 s fill lag
  Eigen::RowVectorXd p = Eigen::RowVectorXd::Zero(3);
  for (Eigen::Index k = 0; k < n; ++k) {
    p = pole * p + (1 - pole) * cmd.row(k);
    for (Eigen::Index j = 0; j < 3; ++j) u(k, j) = p(j) + noise(rng);
  }
  u(1000, 0) += 0.05;  // a glitch mid-plateau
  EXPECT_TRUE(segmentSteps(u, 0.005, min_len).empty()) << "the noise alone no longer cuts the log";
  const Eigen::MatrixXd ref = plateauReference(u, min_len, 0.005);
  const std::vector<LocalDataSet> want = segmentSteps(cmd, 0.005, min_len), got = segmentSteps(ref, 0.005, min_len);
  ASSERT_EQ(want.size(), 7u);
  ASSERT_EQ(got.size(), want.size());
  for (std::size_t s = 0; s < want.size(); ++s) {
    SCOPED_TRACE("step " + std::to_string(s));
    EXPECT_EQ(got[s].input, want[s].input);
    EXPECT_EQ(got[s].rising(), want[s].rising());
    EXPECT_GE(got[s].begin, want[s].begin);  // where the pressure leaves its band: a sample or two in
    EXPECT_LE(got[s].begin, want[s].begin + 3);
    EXPECT_NEAR(got[s].to, want[s].to, 0.002);
  }
  const auto levels = referenceLevels(ref, 0.005, min_len);
  ASSERT_EQ(levels[0].size(), 4u);  // 0, 0.2, 0.2475, 0.3: each read once
  const std::vector<double> commanded = {0.0, 0.2, 0.2475, 0.3};
  for (std::size_t i = 0; i < 4; ++i) EXPECT_NEAR(levels[0][i], commanded[i], 0.001);
  ASSERT_EQ(levels[1].size(), 3u);
  ASSERT_EQ(levels[2].size(), 1u);
  // A column that never holds 1 s (an excitation every half second) is left as it is.
  Eigen::MatrixXd random(n, 1);
  for (Eigen::Index k = 0; k < n; ++k) random(k, 0) = 0.1 * ((k / 40) % 7);
  EXPECT_EQ(plateauReference(random, min_len, 0.005), random);
  // Nor is a random walk, which holds within its band for 1 s now and then
  // (at least once here), but not for most of the run.
  Eigen::MatrixXd walk(n, 1);
  std::normal_distribution<double> unit(0.0, 1.0);
  double w = 0.2;
  for (Eigen::Index k = 0; k < n; ++k) walk(k, 0) = w = std::clamp(w + 0.01 * unit(rng), 0.05, 0.35);
  EXPECT_EQ(plateauReference(walk, min_len, 0.005), walk);
  EXPECT_THROW(plateauReference(u, 0, 0.005), std::invalid_argument);
}
