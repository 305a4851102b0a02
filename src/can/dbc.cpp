#include "plsa/can/dbc.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <regex>
#include <set>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "plsa/core/number_text.hpp"
#include "plsa/core/printable_text.hpp"

namespace plsa::can {

namespace {

// Longest DBC line taken (a regular expression reads each line).
constexpr std::size_t kMaxDbcLineBytes = 4096;
// The id of the pseudo-message DBC editors keep unassigned signals in.
constexpr unsigned long long kIndependentSignals = 0xC0000000ull;

[[noreturn]] void rejectDbcLine(const std::string& source, std::size_t line, const std::string& why) {
  throw std::invalid_argument(source + ":" + std::to_string(line) + ": " + why);
}

double number(const std::string& text, const std::string& what, const std::string& source, std::size_t line) {
  const ParsedDecimal n = parseDecimal(text);
  if (n.kind == DecimalText::kNotDecimal) rejectDbcLine(source, line, what + " '" + text + "' is not a decimal number");
  if (n.kind != DecimalText::kNumber) rejectDbcLine(source, line, what + " '" + text + "' is not a number");
  return n.value;
}

// Unescaped double quotes in a line: an odd count opens (or closes) a string
// that runs on to the next line (CM_ comments do).
bool togglesQuote(const std::string& line) {
  bool odd = false;
  for (std::size_t k = 0; k < line.size(); ++k)
    if (line[k] == '"' && (k == 0 || line[k - 1] != '\\')) odd = !odd;
  return odd;
}

// Whether text is well-formed UTF-8 (no overlong forms, surrogates, code
// points past U+10FFFF or C1 controls) without control characters, double
// quotes or backslashes: a unit both a DBC string and JSON carry as it is.
bool printableUtf8(const std::string& text) {
  return utf8ProblemAt(text) == std::string::npos && controlCharacterAt(text) == std::string::npos &&
         text.find_first_of("\"\\") == std::string::npos;
}

struct SignalLine {
  std::string name, mux, unit;
  int start = 0, length = 0;
  bool little_endian = true, is_signed = false;
  double scale = 1.0, offset = 0.0;
};

SignalLine parseSignal(const std::string& text, const std::string& source, std::size_t line) {
  static const std::regex sg(
      R"re(^\s*SG_\s+(\w+)\s*(M|m\d+)?\s*:\s*(\d+)\s*\|\s*(\d+)\s*@\s*([01])\s*([+-])\s*\(\s*([^,\s]+)\s*,\s*([^)\s]+)\s*\)\s*\[\s*([^|\s]*)\s*\|\s*([^\]\s]*)\s*\]\s*"([^"]*)"\s*(.*)$)re");
  std::smatch m;
  if (!std::regex_match(text, m, sg))
    rejectDbcLine(
        source, line,
        "not a DBC signal line (SG_ name : start|length@order sign (scale,offset) [min|max] \"unit\" receivers)");
  SignalLine s;
  s.name = m[1];
  s.mux = m[2];
  if (m[3].length() > 4 || m[4].length() > 4)
    rejectDbcLine(source, line, "signal '" + s.name + "': start or length too large");
  s.start = std::stoi(m[3]);
  s.length = std::stoi(m[4]);
  s.little_endian = m[5] == "1";
  s.is_signed = m[6] == "-";
  s.scale = number(m[7], "signal '" + s.name + "': scale", source, line);
  s.offset = number(m[8], "signal '" + s.name + "': offset", source, line);
  s.unit = m[11];
  if (!printableUtf8(s.unit))
    rejectDbcLine(source, line, "signal '" + s.name + "': the unit is not printable UTF-8 text");
  return s;
}

// A DBC signal as plsa's byte-aligned one (or the message's counter or checksum).
void addSignal(const SignalLine& d, MessageLayout& m, const std::string& source, std::size_t line) {
  const std::string at = "message '" + m.name + "', signal '" + d.name + "': ";
  if (!d.mux.empty())
    rejectDbcLine(source, line, at + "multiplexed signals are not read (plsa's maps have fixed layouts)");
  if (d.length != 8 && d.length != 16 && d.length != 32)
    rejectDbcLine(source, line, at + std::to_string(d.length) + " bits; plsa reads 8-, 16- and 32-bit signals");
  // Intel: the start bit is the lowest bit; Motorola: the highest bit of the first byte.
  if (d.little_endian ? d.start % 8 != 0 : d.start % 8 != 7)
    rejectDbcLine(
        source, line,
        at + "starts at bit " + std::to_string(d.start) + ", not on a byte (plsa's signals are byte-aligned)");
  const int byte = d.start / 8;
  if (d.name == "counter" || d.name == "checksum") {
    if (d.length != 8 || d.is_signed || d.scale != 1.0 || d.offset != 0.0)
      rejectDbcLine(source, line, at + "a counter or checksum is one unsigned byte, scale 1, offset 0");
    (d.name == "counter" ? m.counter_byte : m.checksum_byte) = byte;
    return;
  }
  if (m.signals.size() >= static_cast<std::size_t>(MessageLayout::kMaxSignals))
    rejectDbcLine(source, line,
                  at + "more than " + std::to_string(MessageLayout::kMaxSignals) + " signals in one message");
  Signal s;
  s.name = d.name;
  s.byte = byte;
  s.bits = d.length;
  s.little_endian = d.little_endian;
  s.is_signed = d.is_signed;
  s.scale = d.scale;
  s.offset = d.offset;
  s.unit = d.unit;
  m.signals.push_back(s);
}

// The shortest of %.15g and %.17g that reads back as v.
std::string formatted(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.15g", v);
  if (std::strtod(text, nullptr) != v) std::snprintf(text, sizeof text, "%.17g", v);
  return text;
}

// Ten digits: a signal's range, which only people read (the import ignores it).
std::string rounded(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.10g", v);
  return text;
}

bool identifier(const std::string& name) {
  if (name.empty() || std::isdigit(static_cast<unsigned char>(name[0]))) return false;
  for (char c : name)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_') return false;
  return true;
}

}  // namespace

SignalMap signalMapFromDbc(const std::string& text, const std::string& source, const std::string& profile) {
  if (text.size() > kMaxDbcBytes) throw std::invalid_argument(source + ": a DBC file larger than 16 MiB");
  static const std::regex bo(R"(^\s*BO_\s+(\d+)\s+(\w+)\s*:\s*(\d+)\s+(\w+)\s*$)");
  static const std::regex valtype(R"(^\s*SIG_VALTYPE_\s+(\d+)\s+(\w+)\s*:\s*([0-3])\s*;\s*$)");
  SignalMap map;
  map.profile = profile;
  std::istringstream lines(text);
  std::string line;
  bool in_string = false, skipping = false, in_message = false;
  std::size_t string_opened = 0;  // the line a string still open began on
  std::set<std::pair<unsigned long long, std::string>> floats;
  for (std::size_t number = 1; std::getline(lines, line); ++number) {
    if (line.size() > kMaxDbcLineBytes) rejectDbcLine(source, number, "line longer than 4096 bytes");
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const bool was_in_string = in_string;
    if (togglesQuote(line)) {
      in_string = !in_string;
      if (in_string) string_opened = number;
    }
    if (was_in_string) continue;  // the rest of a comment from an earlier line
    std::istringstream words(line);
    std::string keyword;
    words >> keyword;
    std::smatch m;
    if (keyword == "BO_") {
      if (!std::regex_match(line, m, bo))
        rejectDbcLine(source, number, "not a DBC message line (BO_ id name: dlc sender)");
      if (m[1].length() > 10) rejectDbcLine(source, number, "message id '" + m[1].str() + "' too large");
      const unsigned long long id = std::stoull(m[1]);
      skipping = id == kIndependentSignals;
      in_message = !skipping;
      if (skipping) continue;
      if (id > 0x7FF)
        rejectDbcLine(
            source, number,
            "message '" + m[2].str() + "': id " + m[1].str() + " is not an 11-bit one (extended ids are not read)");
      if (map.messages.size() >= kMaxMessages)
        rejectDbcLine(source, number, "more than " + std::to_string(kMaxMessages) + " messages");
      MessageLayout message;
      message.name = m[2];
      message.id = static_cast<std::uint32_t>(id);
      if (m[3].length() > 2 || std::stoi(m[3]) > 8)
        rejectDbcLine(source, number, "message '" + message.name + "': dlc " + m[3].str() + " (classic CAN: 0..8)");
      message.dlc = std::stoi(m[3]);
      map.messages.push_back(message);
    } else if (keyword == "SG_") {
      if (skipping) continue;
      if (!in_message) rejectDbcLine(source, number, "a signal outside any message");
      addSignal(parseSignal(line, source, number), map.messages.back(), source, number);
    } else if (keyword == "SIG_VALTYPE_") {
      if (std::regex_match(line, m, valtype) && m[3] != "0" && m[1].length() <= 10)
        floats.insert({std::stoull(m[1]), m[2]});
      in_message = skipping = false;
    } else if (!keyword.empty()) {
      in_message = skipping = false;  // anything else ends a message's signal lines
    }
  }
  if (in_string)  // every line after it was read as the string's: say so, not "no BO_ messages"
    rejectDbcLine(source, string_opened, "a string opened here is never closed (a '\"' missing)");
  for (const auto& [id, name] : floats)
    for (const MessageLayout& message : map.messages)
      if (message.id == id)
        for (const Signal& s : message.signals)
          if (s.name == name)
            throw std::invalid_argument(source + ": message '" + message.name + "', signal '" + name +
                                        "': a float signal (SIG_VALTYPE_); plsa reads integers with a scale");
  if (map.messages.empty()) throw std::invalid_argument(source + ": no BO_ messages (is it a DBC file?)");
  try {
    map.validate();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(source + ": " + e.what());
  }
  return map;
}

std::string signalMapToDbc(const SignalMap& map) {
  map.validate();
  std::string out = "VERSION \"\"\n\nNS_ :\n\tCM_\n\nBS_:\n\nBU_: plsa\n\n";
  for (const MessageLayout& m : map.messages) {
    if (!identifier(m.name)) throw std::invalid_argument("DBC: message name '" + m.name + "' is not an identifier");
    out += "BO_ " + std::to_string(m.id) + " " + m.name + ": " + std::to_string(m.dlc) + " plsa\n";
    for (const Signal& s : m.signals) {
      if (!identifier(s.name)) throw std::invalid_argument("DBC: signal name '" + s.name + "' is not an identifier");
      if (s.name == "counter" || s.name == "checksum")
        throw std::invalid_argument("DBC: signal '" + s.name + "' of message '" + m.name +
                                    "': in a DBC that name is the message's counter or checksum byte");
      if (!printableUtf8(s.unit))
        throw std::invalid_argument("DBC: signal '" + s.name + "': a unit that is not printable UTF-8 without quotes");
      const PhysicalRange r = physicalRange(s);
      const int start = s.little_endian ? 8 * s.byte : 8 * s.byte + 7;
      out += " SG_ " + s.name + " : " + std::to_string(start) + "|" + std::to_string(s.bits) + "@" +
             (s.little_endian ? "1" : "0") + (s.is_signed ? "-" : "+") + " (" + formatted(s.scale) + "," +
             formatted(s.offset) + ") [" + rounded(r.lo) + "|" + rounded(r.hi) + "] \"" + s.unit + "\" plsa\n";
    }
    for (const auto& [name, byte] :
         {std::pair<const char*, int>{"counter", m.counter_byte}, {"checksum", m.checksum_byte}})
      if (byte >= 0)
        out += std::string(" SG_ ") + name + " : " + std::to_string(8 * byte) + "|8@1+ (1,0) [0|255] \"\" plsa\n";
    out += "\n";
  }
  std::string profile = map.profile;
  for (char& c : profile)
    if (c == '"' || c == '\n' || c == '\r' || c == '\\') c = '\'';
  out += "CM_ \"plsa signal map '" + profile +
         "'. A signal named counter increases by 1 (mod 256) with every frame; checksum = (id low byte + id high "
         "byte + every other data byte) mod 256.\";\n";
  return out;
}

std::string signalMapToJson(const SignalMap& map) {
  map.validate();
  nlohmann::ordered_json j;
  j["profile"] = map.profile;
  j["messages"] = nlohmann::ordered_json::array();
  for (const MessageLayout& m : map.messages) {
    nlohmann::ordered_json jm;
    jm["name"] = m.name;
    jm["id"] = m.id;
    jm["dlc"] = m.dlc;
    if (m.counter_byte >= 0) jm["counter_byte"] = m.counter_byte;
    if (m.checksum_byte >= 0) jm["checksum_byte"] = m.checksum_byte;
    jm["signals"] = nlohmann::ordered_json::array();
    for (const Signal& s : m.signals)
      jm["signals"].push_back({{"name", s.name},
                               {"byte", s.byte},
                               {"bits", s.bits},
                               {"endian", s.little_endian ? "little" : "big"},
                               {"signed", s.is_signed},
                               {"scale", s.scale},
                               {"offset", s.offset},
                               {"unit", s.unit}});
    j["messages"].push_back(jm);
  }
  try {
    return j.dump(2) + "\n";
  } catch (const nlohmann::json::exception& e) {  // text that is no UTF-8
    throw std::invalid_argument("signal map '" + map.profile + "' as JSON: " + e.what());
  }
}

}  // namespace plsa::can
