// Argument checks for set-up code and offline tools, and debug assertions
// for the real-time path.
// PLSA_CHECK(condition, message) always runs and throws std::invalid_argument
// with the message, which is built only when the check fails; it is never
// used on the real-time path, which returns status codes. There,
// PLSA_DEBUG_ASSERT(condition) states an invariant: checked (abort with the
// file and line) in builds without NDEBUG, gone from release builds.
#pragma once

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <vector>

namespace plsa {
namespace detail {
[[noreturn]] inline void checkFailed(const std::string& message) { throw std::invalid_argument(message); }
[[noreturn]] inline void assertFailed(const char* condition, const char* file, int line) noexcept {
  std::fprintf(stderr, "%s:%d: plsa invariant broken: %s\n", file, line, condition);
  std::abort();
}
}  // namespace detail
}  // namespace plsa

#define PLSA_CHECK(condition, ...)                              \
  do {                                                          \
    if (!(condition)) ::plsa::detail::checkFailed(__VA_ARGS__); \
  } while (false)

#ifdef NDEBUG
#define PLSA_DEBUG_ASSERT(condition) static_cast<void>(0)
#else
#define PLSA_DEBUG_ASSERT(condition) \
  ((condition) ? static_cast<void>(0) : ::plsa::detail::assertFailed(#condition, __FILE__, __LINE__))
#endif

namespace plsa {

/// The most horizons a tool takes at once: each costs a prediction per
/// sample (4000 of them took validate 2.1 GB on a 1.7 MB log).
inline constexpr std::size_t kMaxHorizons = 32;

/// Prediction horizons (samples ahead) as every tool takes them: given, at
/// most kMaxHorizons, each >= 1 and each once (a repeat would be scored,
/// averaged or published twice). Messages start with `tool`.
inline void requireHorizons(const std::vector<int>& horizons, const std::string& tool) {
  PLSA_CHECK(!horizons.empty(), tool + ": no horizons given");
  PLSA_CHECK(horizons.size() <= kMaxHorizons, tool + ": " + std::to_string(horizons.size()) +
                                                  " horizons given; at most " + std::to_string(kMaxHorizons));
  for (auto at = horizons.begin(); at != horizons.end(); ++at) {
    PLSA_CHECK(*at >= 1, tool + ": horizons must be >= 1, got " + std::to_string(*at));
    PLSA_CHECK(std::find(horizons.begin(), at, *at) == at,
               tool + ": horizon " + std::to_string(*at) + " is given twice");
  }
}

}  // namespace plsa
