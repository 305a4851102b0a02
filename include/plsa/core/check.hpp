// Argument checks for set-up code and offline tools.
// `require` always runs and throws std::invalid_argument with the caller's
// message; it is never used on the real-time path, which returns status codes.
#pragma once

#include <stdexcept>
#include <string>

namespace plsa {

/// Throws std::invalid_argument(message) unless `condition` holds.
inline void require(bool condition, const std::string& message) {
  if (!condition) throw std::invalid_argument(message);
}

}  // namespace plsa
