// JSON input as plsa's loaders read it (model files, simulator
// configurations, signal maps): what nlohmann accepts silently is refused
// with the file and the field named. Duplicate keys (the last would win),
// numbers beyond double range, nesting deeper than any plsa file, unknown
// keys, and numbers cast to integers without a range check.
// Header-only; include it only from targets that link nlohmann_json.
#pragma once

#include <cmath>
#include <initializer_list>
#include <set>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

namespace plsa::io {

/// Deepest nesting of objects and arrays a plsa file has, with room to spare.
inline constexpr int kMaxJsonDepth = 32;

/// Parses `text`; throws std::invalid_argument "SOURCE: reason" for invalid
/// JSON, a number beyond double range, a key given twice in one object (naming
/// its path) or nesting deeper than kMaxJsonDepth.
inline nlohmann::json parseStrictJson(const std::string& text, const std::string& source) {
  using nlohmann::json;
  std::vector<std::set<std::string>> seen;  // keys of each open object
  std::vector<std::string> path;            // the key being read at each open object
  auto where = [&path] {
    std::string p;
    for (const auto& k : path) p += (p.empty() ? "" : ".") + k;
    return p;
  };
  const json::parser_callback_t check = [&](int depth, json::parse_event_t event, json& parsed) {
    switch (event) {
      case json::parse_event_t::object_start:
      case json::parse_event_t::array_start:
        if (depth >= kMaxJsonDepth)
          throw std::invalid_argument(source + ": nested deeper than " + std::to_string(kMaxJsonDepth) +
                                      " levels at '" + where() + "'");
        if (event == json::parse_event_t::object_start) {
          seen.emplace_back();
          path.emplace_back();
        }
        break;
      case json::parse_event_t::key: {
        const std::string key = parsed.get<std::string>();
        path.back() = key;
        if (!seen.back().insert(key).second)
          throw std::invalid_argument(source + ": key '" + where() + "' is given twice (which one is meant?)");
        break;
      }
      case json::parse_event_t::object_end:
        seen.pop_back();
        path.pop_back();
        break;
      default:
        break;
    }
    return true;
  };
  try {
    return json::parse(text, check);
  } catch (const json::exception& e) {  // parse_error, and out_of_range for 1e400
    throw std::invalid_argument(source + ": not valid JSON: " + e.what());
  }
}

/// Throws std::invalid_argument naming `path` and the known keys when
/// `object` has a key outside `known`: a field this build does not read
/// would otherwise be dropped, and the file mean something else here.
template <class Keys>
void requireKnownKeysIn(const nlohmann::json& object, const Keys& known, const std::string& path,
                        const std::string& source) {
  for (auto it = object.begin(); it != object.end(); ++it) {
    bool ok = false;
    for (std::string_view k : known) ok = ok || it.key() == k;
    if (ok) continue;
    std::string list;
    for (std::string_view k : known) list += (list.empty() ? "" : ", ") + std::string(k);
    throw std::invalid_argument(source + ": unknown key '" + path + it.key() + "' (this build reads: " + list +
                                "); written by a newer plsa?");
  }
}

inline void requireKnownKeys(const nlohmann::json& object, std::initializer_list<std::string_view> known,
                             const std::string& path, const std::string& source) {
  requireKnownKeysIn(object, known, path, source);
}

/// A finite number at `path` (not a bool, string or null).
inline double finiteNumber(const nlohmann::json& v, const std::string& path, const std::string& source) {
  if (!v.is_number()) throw std::invalid_argument(source + ": '" + path + "' must be a number");
  const double x = v.get<double>();
  if (!std::isfinite(x)) throw std::invalid_argument(source + ": '" + path + "' must be finite");
  return x;
}

/// An integer in [lo, hi] at `path`: a float, even 3.0 or 1e300, is refused
/// before any conversion (a huge float cast to an integer is undefined).
inline long long integerIn(const nlohmann::json& v, long long lo, long long hi, const std::string& path,
                           const std::string& source) {
  const std::string range = " must be an integer in " + std::to_string(lo) + ".." + std::to_string(hi);
  if (!v.is_number_integer()) throw std::invalid_argument(source + ": '" + path + "'" + range);
  if (v.is_number_unsigned()) {
    const auto u = v.get<unsigned long long>();
    if (hi < 0 || u > static_cast<unsigned long long>(hi))
      throw std::invalid_argument(source + ": '" + path + "'" + range);
    return static_cast<long long>(u);
  }
  const auto s = v.get<long long>();
  if (s < lo || s > hi) throw std::invalid_argument(source + ": '" + path + "'" + range);
  return s;
}

}  // namespace plsa::io
