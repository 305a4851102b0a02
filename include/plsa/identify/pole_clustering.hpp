// Step 5: choose OBF poles from the identified local poles. FKcM (Toth,
// Heuberger, Van den Hof 2009): fuzzy memberships plus a minimax centre update
// solved in epigraph form with NLopt, by default ending with the same kind of
// minimax on rho itself. Fuzzy c-means, k-means and a global
// search on rho are here to judge it against (docs/identification.md, "Pole selection").
#pragma once

#include <complex>
#include <cstdint>
#include <string>
#include <vector>

namespace plsa::identify {

struct ClusteringOptions {
  int centres = 5;         ///< OBF poles to choose (a complex pair counts as two)
  int complex_pairs = 0;   ///< how many of them are conjugate pairs
  double fuzziness = 2.0;  ///< m > 1
  int max_iterations = 100;
  double tolerance = 1e-7;  ///< stop when no centre moves more than this
  std::uint64_t seed = 1;
  int global_evaluations = 40000;
  /// FKcM: end with a minimax on rho itself (epigraph of log rho, NLopt
  /// COBYLA) from its centres, kept only where it lowers rho.
  bool refine_on_rho = true;
};

struct ClusteringResult {
  std::string method;
  std::vector<std::complex<double>> centres;  ///< every pole (pairs expanded)
  double rho = 0.0;                           ///< decay rate over the identified poles
  double objective = 0.0;                     ///< the method's own criterion at the end
  int iterations = 0;
};

/// Throws std::invalid_argument on no poles, unstable poles, or bad options.
ClusteringResult fkcmClustering(const std::vector<std::complex<double>>& poles, const ClusteringOptions& o);
ClusteringResult fuzzyCMeansClustering(const std::vector<std::complex<double>>& poles, const ClusteringOptions& o);
ClusteringResult kMeansClustering(const std::vector<std::complex<double>>& poles, const ClusteringOptions& o);
/// Minimises rho directly: NLopt DIRECT-L over the poles' range, then
/// Nelder-Mead polishing of that and of the other methods' answers.
ClusteringResult globalRhoSearch(const std::vector<std::complex<double>>& poles, const ClusteringOptions& o);

}  // namespace plsa::identify
