#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "plsa/core/pole_set.hpp"

using plsa::PoleSet;
using C = std::complex<double>;

TEST(PoleSet, KeepsRealPolesAndPairsInOrder) {
  const PoleSet p({C(0.5, 0), C(0.3, 0.4), C(0.9, 0), C(0.3, -0.4)});
  ASSERT_EQ(p.sections().size(), 3u);
  EXPECT_EQ(p.size(), 4);
  EXPECT_FALSE(p.sections()[0].is_pair());
  EXPECT_TRUE(p.sections()[1].is_pair());
  EXPECT_GT(p.sections()[1].pole.imag(), 0.0);
  EXPECT_DOUBLE_EQ(p.sections()[2].pole.real(), 0.9);
}

TEST(PoleSet, StoresPairByItsUpperMemberWhicheverComesFirst) {
  const PoleSet p({C(0.3, -0.4), C(0.3, 0.4)});
  EXPECT_DOUBLE_EQ(p.sections()[0].pole.imag(), 0.4);
}

TEST(PoleSet, RejectsUnstablePoleNamingIt) {
  try {
    PoleSet({C(0.5, 0), C(1.0, 0)});
    FAIL() << "accepted a pole on the unit circle";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("pole 1"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(">= 1"), std::string::npos) << e.what();
  }
  EXPECT_THROW(PoleSet({C(0.8, 0.8), C(0.8, -0.8)}), std::invalid_argument);
  EXPECT_THROW(PoleSet::real({-1.2}), std::invalid_argument);
}

TEST(PoleSet, RejectsNaNAndInf) {
  EXPECT_THROW(PoleSet::real({std::nan("")}), std::invalid_argument);
  EXPECT_THROW(PoleSet({C(0.1, std::numeric_limits<double>::infinity())}), std::invalid_argument);
}

TEST(PoleSet, RejectsUnpairedComplexPole) {
  try {
    PoleSet({C(0.3, 0.4), C(0.3, 0.41)});
    FAIL() << "accepted an unpaired complex pole";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("conjugate"), std::string::npos) << e.what();
  }
  EXPECT_THROW(PoleSet({C(0.3, 0.4), C(0.3, -0.4), C(0.3, 0.4)}), std::invalid_argument);
}

TEST(PoleSet, TreatsRoundOffImaginaryPartAsReal) {
  const PoleSet p({C(0.7, 1e-15)});
  EXPECT_FALSE(p.sections()[0].is_pair());
  EXPECT_EQ(p.size(), 1);
}

TEST(PoleSet, Factories) {
  EXPECT_EQ(PoleSet::fir(4).size(), 4);
  EXPECT_EQ(PoleSet::laguerre(0.6, 3).poles()[2], C(0.6, 0));
  const PoleSet k = PoleSet::kautz(C(0.5, 0.2), 2);
  EXPECT_EQ(k.size(), 4);
  EXPECT_EQ(k.sections().size(), 2u);
  const PoleSet g = PoleSet::repeated(PoleSet::real({0.9, 0.5}), 3);
  EXPECT_EQ(g.size(), 6);
  EXPECT_DOUBLE_EQ(g.poles()[4].real(), 0.9);
  EXPECT_THROW(PoleSet::fir(0), std::invalid_argument);
  EXPECT_THROW(PoleSet::kautz(C(0.5, 0.0), 1), std::invalid_argument);
}
