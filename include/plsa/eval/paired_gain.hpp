// How much one model's held-out scores gain over another's, and how sure:
// the mean of paired differences and its standard error, the quantity the
// one-standard-error rule reads (a richer structure is kept only if its
// mean gain exceeds the error).
#pragma once

#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "plsa/core/check.hpp"

namespace plsa::eval {

/// The mean of the differences a[k] - b[k] over the terms finite in both
/// (NaN marks a term one of them could not score; the terms stay paired by
/// position) and the standard error of that mean. With fewer than two pairs
/// there is no evidence: no gain and an infinite error. Throws if the sizes
/// differ.
inline std::pair<double, double> pairedGain(const std::vector<double>& a, const std::vector<double>& b) {
  PLSA_CHECK(a.size() == b.size(), "pairedGain: the scores to compare do not pair up (" + std::to_string(a.size()) +
                                       " vs " + std::to_string(b.size()) + ")");
  std::vector<double> d;
  for (std::size_t k = 0; k < a.size(); ++k)
    if (std::isfinite(a[k] - b[k])) d.push_back(a[k] - b[k]);
  if (d.size() < 2) return {0.0, INFINITY};
  const auto n = static_cast<double>(d.size());
  double mean = 0.0, sq = 0.0;
  for (double v : d) mean += v / n;
  for (double v : d) sq += (v - mean) * (v - mean);
  return {mean, std::sqrt(sq / (n - 1) / n)};
}

}  // namespace plsa::eval
