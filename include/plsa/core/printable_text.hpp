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

}  // namespace plsa
