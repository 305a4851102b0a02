// JSON input as plsa's loaders read it (model files, simulator
// configurations, signal maps): what nlohmann accepts silently is refused
// with the file and the field named. Duplicate keys (the last would win),
// numbers beyond double range, nesting deeper than any plsa file, control
// characters in a string or key (a NUL cut every message that quoted it),
// unknown keys, and numbers cast to integers without a range check.
// Header-only; include it only from targets that link nlohmann_json.
#pragma once

#include <cmath>
#include <cstddef>
#include <initializer_list>
#include <set>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "plsa/core/printable_text.hpp"

namespace plsa::io {

/// Deepest nesting of objects and arrays a plsa file has, with room to spare.
inline constexpr int kMaxJsonDepth = 32;
/// Objects and arrays a document may hold: the largest model a file may
/// carry has a few hundred thousand; each costs about 80 bytes in memory
/// against 2 in the text (64 MB of "{}" took 2.2 GB to build).
inline constexpr long kMaxJsonContainers = 4'000'000;

/// What parseStrictJson refuses, found in one SAX pass before the document
/// is built (nlohmann's parser callback is quadratic in an array's length:
/// a model of 800k regions took minutes to load).
class StrictJsonCheck {
 public:
  using json = nlohmann::json;
  explicit StrictJsonCheck(const std::string& source) : source_(source) {}

  bool null() { return true; }
  bool boolean(bool) { return true; }
  bool number_integer(json::number_integer_t) { return true; }
  bool number_unsigned(json::number_unsigned_t) { return true; }
  bool number_float(json::number_float_t v, const json::string_t& text) {
    if (!std::isfinite(v)) refuse("not valid JSON: number overflow parsing '" + text + "' at '" + where() + "'");
    return true;
  }
  bool string(json::string_t& s) {
    if (const std::size_t at = plsa::controlCharacterAt(s); at != std::string::npos)
      refuseControlCharacter(s, at, "the string at '" + where() + "'");
    return true;
  }
  bool binary(json::binary_t&) { return true; }
  bool start_object(std::size_t) {
    open();
    seen_.emplace_back();
    path_.emplace_back();
    return true;
  }
  bool key(json::string_t& k) {
    if (const std::size_t at = plsa::controlCharacterAt(k); at != std::string::npos)
      refuseControlCharacter(k, at, path_.size() == 1 ? "a key at the top level" : "a key in '" + where(1) + "'");
    path_.back() = k;
    if (!seen_.back().insert(k).second) refuse("key '" + where() + "' is given twice (which one is meant?)");
    return true;
  }
  bool end_object() {
    seen_.pop_back();
    path_.pop_back();
    --depth_;
    return true;
  }
  bool start_array(std::size_t) {
    open();
    return true;
  }
  bool end_array() {
    --depth_;
    return true;
  }
  bool parse_error(std::size_t, const std::string&, const nlohmann::detail::exception& e) {
    refuse(std::string("not valid JSON: ") + e.what());
    return false;
  }

 private:
  void open() {
    if (depth_ >= kMaxJsonDepth)
      refuse("nested deeper than " + std::to_string(kMaxJsonDepth) + " levels at '" + where() + "'");
    if (++containers_ > kMaxJsonContainers)
      refuse("more than " + std::to_string(kMaxJsonContainers) + " objects and arrays (is this the right file?)");
    ++depth_;
  }
  [[noreturn]] void refuse(const std::string& why) const { throw std::invalid_argument(source_ + ": " + why); }
  [[noreturn]] void refuseControlCharacter(const std::string& s, std::size_t at, const std::string& what) const {
    refuse(what + " has the control character " + controlCharacterName(s[at]) + " at byte " + std::to_string(at) +
           " (names, units and laws are printable text)");
  }
  /// The path being read, less its last `drop` keys.
  std::string where(std::size_t drop = 0) const {
    std::string p;
    for (std::size_t i = 0; i + drop < path_.size(); ++i) p += (p.empty() ? "" : ".") + path_[i];
    return p;
  }

  std::string source_;
  int depth_ = 0;
  long containers_ = 0;
  std::vector<std::set<std::string>> seen_;  // keys of each open object
  std::vector<std::string> path_;            // the key being read at each open object
};

/// Parses `text`; throws std::invalid_argument "SOURCE: reason" for invalid
/// JSON, a number beyond double range, a key given twice in one object (naming
/// its path), a control character in a string or key, nesting deeper than
/// kMaxJsonDepth, or more than kMaxJsonContainers objects and arrays. Linear
/// in the text.
inline nlohmann::json parseStrictJson(const std::string& text, const std::string& source) {
  StrictJsonCheck check(source);
  nlohmann::json::sax_parse(text, &check);  // throws on the first refusal
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {  // checked above; kept so that nothing raw escapes
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
    if (hi < 0 || u > static_cast<unsigned long long>(hi) || (lo > 0 && u < static_cast<unsigned long long>(lo)))
      throw std::invalid_argument(source + ": '" + path + "'" + range);
    return static_cast<long long>(u);
  }
  const auto s = v.get<long long>();
  if (s < lo || s > hi) throw std::invalid_argument(source + ": '" + path + "'" + range);
  return s;
}

}  // namespace plsa::io
