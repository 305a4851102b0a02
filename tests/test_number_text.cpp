// Numbers as progress lines print them (whole, never cut to a width), and
// number fields as the readers take them, and the median the readers share.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "plsa/core/median.hpp"
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

// The readers' one rule for a number field (CSV cells, DBC numbers): whole,
// decimal, finite; each failure told apart for its message.
TEST(NumberText, ParseDecimalTakesWholeFiniteDecimalsOnly) {
  for (const auto& [text, value] : std::vector<std::pair<std::string, double>>{
           {"0", 0.0}, {"-1.5", -1.5}, {"2.5e-3", 2.5e-3}, {"+7", 7.0}, {"1E3", 1000.0}}) {
    const ParsedDecimal n = parseDecimal(text);
    EXPECT_EQ(n.kind, DecimalText::kNumber) << text;
    EXPECT_EQ(n.value, value) << text;
  }
  for (const std::string text : {"", "1 ", "1.5x", "abc", "1,5", "0x"})
    EXPECT_EQ(parseDecimal(text).kind, DecimalText::kNotANumber) << "'" << text << "'";
  for (const std::string text : {"0x10", "0X1p3", "-0x1"})
    EXPECT_EQ(parseDecimal(text).kind, DecimalText::kNotDecimal) << text;
  for (const std::string text : {"inf", "-Infinity", "nan", "1e400"})
    EXPECT_EQ(parseDecimal(text).kind, DecimalText::kNotFinite) << text;
}

// The median several readers share: the middle of an odd count, the upper
// middle of an even one, whatever the order; NaN for an empty list.
TEST(Median, TakesTheMiddleOfAnyOrderAndNaNForNone) {
  EXPECT_EQ(plsa::median({3.0, -1.0, 2.0}), 2.0);
  EXPECT_EQ(plsa::median({4.0, 1.0, 3.0, 2.0}), 3.0);
  EXPECT_EQ(plsa::median({0.0125, 0.0125, 0.5, 0.0125}), 0.0125);  // a gap does not move a sample time
  EXPECT_TRUE(std::isnan(plsa::median({})));
}
