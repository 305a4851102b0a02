// How much one model's held-out scores gain over another's, and how sure:
// the mean of paired differences and its standard error, the quantity the
// one-standard-error rule reads (a richer structure is kept only if its
// mean gain exceeds the error), per output, and clearGain, the slow poles'
// rule built on them.
#pragma once

#include <cmath>
#include <cstddef>
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

/// Each output's pairedGain of held-out terms a over b, where the terms
/// alternate by output within each fold (term k is output k % outputs).
inline std::vector<std::pair<double, double>> perOutputPairedGains(const std::vector<double>& a,
                                                                   const std::vector<double>& b, std::size_t outputs) {
  PLSA_CHECK(a.size() == b.size(), "perOutputPairedGains: the scores to compare do not pair up");
  std::vector<std::pair<double, double>> gains;
  for (std::size_t out = 0; out < outputs; ++out) {
    std::vector<double> ao, bo;
    for (std::size_t k = out; k < a.size(); k += outputs) {
      ao.push_back(a[k]);
      bo.push_back(b[k]);
    }
    gains.push_back(pairedGain(ao, bo));
  }
  return gains;
}

/// Whether held-out terms `a` (a richer structure's) are clearly better than
/// `b`: their gain over every term exceeds one standard error (the
/// one-standard-error rule), or they gain overall and on one output by more
/// than two of that output's standard errors while losing on none by more
/// than one of its own (what one output shows plainly is not lost to another
/// output's noisy terms). Terms alternate by output as perOutputPairedGains reads them.
struct ClearGain {
  std::pair<double, double> overall{0.0, INFINITY};  ///< pairedGain over every term
  bool by_overall = false;                           ///< overall gain over one standard error
  bool by_one_output = false;                        ///< otherwise: one output plain, none losing
  bool clear() const { return by_overall || by_one_output; }
};

inline ClearGain clearGain(const std::vector<double>& a, const std::vector<double>& b, std::size_t outputs) {
  ClearGain c;
  c.overall = pairedGain(a, b);
  c.by_overall = c.overall.first > c.overall.second;
  if (c.by_overall || !(c.overall.first > 0)) return c;
  bool plain = false, none_loses = true;
  for (const auto& [g, e] : perOutputPairedGains(a, b, outputs)) {
    plain = plain || g > 2.0 * e;
    none_loses = none_loses && g >= -e;
  }
  c.by_one_output = plain && none_loses;
  return c;
}

}  // namespace plsa::eval
