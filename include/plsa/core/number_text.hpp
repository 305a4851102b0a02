// Numbers as text. In progress lines and messages: a fixed number of
// decimals, or a few significant digits, never a string cut short (cutting
// "-10627.3" to five characters prints -1062). From files: one rule for a
// number field (parseDecimal).
#pragma once

#include <cmath>
#include <cstdio>
#include <cstdlib>
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

/// What a field read as a number holds.
enum class DecimalText {
  kNumber,      ///< a finite decimal number
  kNotANumber,  ///< empty, or more than a number
  kNotDecimal,  ///< hexadecimal (strtod reads 0x10 as 16; logs and DBC files write decimals)
  kNotFinite,   ///< inf, nan, or beyond double range
};
struct ParsedDecimal {
  double value = 0.0;
  DecimalText kind = DecimalText::kNotANumber;
};

/// `text` read whole as a decimal number: the readers' one rule for a number field.
inline ParsedDecimal parseDecimal(const std::string& text) {
  if (text.empty()) return {};
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (end != text.c_str() + text.size()) return {};
  if (text.find_first_of("xX") != std::string::npos) return {v, DecimalText::kNotDecimal};
  return {v, std::isfinite(v) ? DecimalText::kNumber : DecimalText::kNotFinite};
}

}  // namespace plsa
