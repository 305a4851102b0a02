// Argument checks for set-up code and offline tools.
// `require` always runs and throws std::invalid_argument with the caller's
// message; it is never used on the real-time path, which returns status codes.
#pragma once

#include <algorithm>
#include <stdexcept>
#include <string>
#include <vector>

namespace plsa {

/// Throws std::invalid_argument(message) unless `condition` holds.
inline void require(bool condition, const std::string& message) {
  if (!condition) throw std::invalid_argument(message);
}

/// Prediction horizons (samples ahead) as every tool takes them: given, each
/// >= 1 and each once (a repeat would be scored, averaged or published twice).
/// Messages start with `tool`.
inline void requireHorizons(const std::vector<int>& horizons, const std::string& tool) {
  require(!horizons.empty(), tool + ": no horizons given");
  for (auto at = horizons.begin(); at != horizons.end(); ++at) {
    require(*at >= 1, tool + ": horizons must be >= 1, got " + std::to_string(*at));
    require(std::find(horizons.begin(), at, *at) == at, tool + ": horizon " + std::to_string(*at) + " is given twice");
  }
}

}  // namespace plsa
