// Step 1: the reference's one-input steps and its levels (plsa/identify/segmentation.hpp).
#include <gtest/gtest.h>

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
