// Names, units and laws that plsa reads from files are printable text: a
// control character (a NUL above all) would cut or garble every message that
// quotes the name, and be written on into the files made from it. The
// readers refuse one, naming it with controlCharacterName.
#pragma once

#include <cstdio>
#include <string>
#include <string_view>

namespace plsa {

/// Index of the first control character (U+0000-U+001F or DEL) in `s`, or npos.
inline std::size_t controlCharacterAt(std::string_view s) noexcept {
  for (std::size_t i = 0; i < s.size(); ++i)
    if (static_cast<unsigned char>(s[i]) < 0x20 || s[i] == 0x7f) return i;
  return std::string_view::npos;
}

/// "U+0000" for a NUL: how a message names a byte it cannot print.
inline std::string controlCharacterName(char c) {
  char code[8];
  std::snprintf(code, sizeof code, "U+%04X", static_cast<unsigned>(static_cast<unsigned char>(c)));
  return code;
}

/// Index of the first byte of `s` that is not well-formed UTF-8 (an
/// overlong form, a surrogate, a code point past U+10FFFF or a cut
/// sequence) or that starts a C1 control character (U+0080-U+009F), or npos.
inline std::size_t utf8ProblemAt(std::string_view s) noexcept {
  for (std::size_t k = 0; k < s.size();) {
    const auto c = static_cast<unsigned char>(s[k]);
    if (c < 0x80) {
      ++k;
      continue;
    }
    const std::size_t more = c >= 0xC2 && c <= 0xDF ? 1 : c >= 0xE0 && c <= 0xEF ? 2 : c >= 0xF0 && c <= 0xF4 ? 3 : 0;
    if (more == 0 || k + more >= s.size()) return k;  // a lead byte, and all its continuation bytes
    const auto next = static_cast<unsigned char>(s[k + 1]);
    if ((c == 0xE0 && next < 0xA0) || (c == 0xED && next >= 0xA0) || (c == 0xF0 && next < 0x90) ||
        (c == 0xF4 && next >= 0x90) || (c == 0xC2 && next < 0xA0))
      return k;
    for (std::size_t i = 1; i <= more; ++i)
      if ((static_cast<unsigned char>(s[k + i]) >> 6) != 0x2) return k;
    k += more + 1;
  }
  return std::string_view::npos;
}

}  // namespace plsa
