// Numbers as progress lines print them: whole, never cut to a width.
#include <gtest/gtest.h>

#include "plsa/core/number_text.hpp"

using namespace plsa;

TEST(NumberText, FixedDecimalsKeepsEveryDigitBeforeThePoint) {
  EXPECT_EQ(fixedDecimals(-10627.3, 2), "-10627.30") << "a score cut to five characters read -1062";
  EXPECT_EQ(fixedDecimals(-477.126, 2), "-477.13");
  EXPECT_EQ(fixedDecimals(93.99, 2), "93.99");
  EXPECT_EQ(fixedDecimals(0.075, 4), "0.0750");
}

TEST(NumberText, SignificantDigitsSwitchesToAnExponentForSmallNumbers) {
  EXPECT_EQ(significantDigits(0.0033812, 3), "0.00338");
  EXPECT_EQ(significantDigits(-1.793e-05, 3), "-1.79e-05") << "a rate cut to six characters read -0.000";
  EXPECT_EQ(significantDigits(4.0, 3), "4");
}
