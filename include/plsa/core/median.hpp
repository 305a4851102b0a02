// The median of a list of values, the robust centre several readers and
// estimators use (a log's sample time, a noise level from differences).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <vector>

namespace plsa {

/// The median of `values` (of an even count, the upper of the two middle
/// values), found on the copy it is given in linear time; NaN for none.
inline double median(std::vector<double> values) {
  if (values.empty()) return std::numeric_limits<double>::quiet_NaN();
  const auto mid = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), mid, values.end());
  return *mid;
}

/// Appends |x(i) - 2 x(i-1) + x(i-2)| for every i of a column `x` (anything
/// with size() and operator()(i): an Eigen column, say) to `out`: what
/// whiteNoiseFromSecondDifferences reads, pooled over as many columns as
/// are appended.
template <typename Column>
void appendAbsSecondDifferences(const Column& x, std::vector<double>& out) {
  for (decltype(x.size()) i = 2; i < x.size(); ++i) out.push_back(std::abs(x(i) - 2.0 * x(i - 1) + x(i - 2)));
}

/// The standard deviation of white noise on a signal, read off the absolute
/// values of its second differences (white noise gives them variance
/// 6 sigma^2) by their median (MAD), so that the signal's steps and
/// transients do not pass for noise; NaN for none.
inline double whiteNoiseFromSecondDifferences(std::vector<double> abs_second_differences) {
  return 1.4826 * median(std::move(abs_second_differences)) / std::sqrt(6.0);
}

}  // namespace plsa
