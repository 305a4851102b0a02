// Numbers in progress lines and messages: a fixed number of decimals, or a
// few significant digits. Never a string cut short (cutting "-10627.3" to
// five characters prints -1062).
#pragma once

#include <cstdio>
#include <string>

namespace plsa {

/// v with `decimals` digits after the point: fixedDecimals(-477.123, 2) is "-477.12".
inline std::string fixedDecimals(double v, int decimals) {
  char text[64];
  std::snprintf(text, sizeof text, "%.*f", decimals, v);
  return text;
}

/// v to `digits` significant digits, the shorter of fixed and exponent
/// notation: significantDigits(0.0033812, 3) is "0.00338", 1.793e-05 "1.79e-05".
inline std::string significantDigits(double v, int digits) {
  char text[64];
  std::snprintf(text, sizeof text, "%.*g", digits, v);
  return text;
}

}  // namespace plsa
