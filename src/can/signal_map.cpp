#include "plsa/can/signal_map.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "plsa/can/dbc.hpp"
#include "plsa/core/text_file.hpp"
#include "plsa/io/standard_columns.hpp"
#include "plsa/io/strict_json.hpp"

namespace plsa::can {
namespace {

std::uint8_t checksum(const MessageLayout& m, const CanFrame& f) {
  unsigned sum = (m.id & 0xFF) + ((m.id >> 8) & 0xFF);
  for (int i = 0; i < f.dlc; ++i)
    if (i != m.checksum_byte) sum += f.data[static_cast<std::size_t>(i)];
  return static_cast<std::uint8_t>(sum & 0xFF);
}

std::uint32_t readRaw(const Signal& s, const CanFrame& f) {
  std::uint32_t raw = 0;
  const int n = s.bits / 8;
  for (int i = 0; i < n; ++i) {
    const std::uint32_t byte = f.data[static_cast<std::size_t>(s.byte + (s.little_endian ? i : n - 1 - i))];
    raw |= byte << (8 * i);
  }
  return raw;
}

}  // namespace

const char* toString(DecodeStatus s) {
  switch (s) {
    case DecodeStatus::kOk:
      return "ok";
    case DecodeStatus::kWrongId:
      return "wrong identifier";
    case DecodeStatus::kWrongLength:
      return "wrong data length (DLC)";
    case DecodeStatus::kBadChecksum:
      return "checksum mismatch";
    case DecodeStatus::kCounterGap:
      return "counter gap (a frame was lost)";
  }
  return "unknown";
}

const MessageLayout* SignalMap::find(const std::string& name) const noexcept {
  for (const auto& m : messages)
    if (m.name == name) return &m;
  return nullptr;
}

const MessageLayout& SignalMap::message(const std::string& name) const {
  std::string known;
  for (const auto& m : messages) {
    if (m.name == name) return m;
    known += (known.empty() ? "" : ", ") + m.name;
  }
  throw std::invalid_argument("signal map '" + profile + "' has no message '" + name + "' (has: " + known + ")");
}

void SignalMap::validate() const {
  if (messages.empty()) throw std::invalid_argument("signal map '" + profile + "': no messages");
  for (auto at = messages.begin(); at != messages.end(); ++at) {
    const MessageLayout& m = *at;
    const std::string where = "signal map '" + profile + "', message '" + m.name + "': ";
    for (auto before = messages.begin(); before != at; ++before) {
      if (before->name == m.name) throw std::invalid_argument(where + "a message of this name comes earlier");
      if (before->id == m.id)
        throw std::invalid_argument(where + "id " + std::to_string(m.id) + " is also message '" + before->name +
                                    "'s: one frame would be read as both");
    }
    for (auto s = m.signals.begin(); s != m.signals.end(); ++s)
      if (std::find_if(m.signals.begin(), s, [&](const Signal& t) { return t.name == s->name; }) != s)
        throw std::invalid_argument(where + "signal '" + s->name + "' is named twice");
    if (m.id > 0x7FF) throw std::invalid_argument(where + "id above 11 bits");
    if (m.dlc < 0 || m.dlc > 8) throw std::invalid_argument(where + "dlc must be 0..8");
    if (m.signals.empty() || m.signals.size() > static_cast<std::size_t>(MessageLayout::kMaxSignals))
      throw std::invalid_argument(where + "needs 1 to 8 signals");
    std::array<bool, 8> used{};
    auto claim = [&](int byte, const std::string& what) {
      if (byte < 0 || byte >= m.dlc)
        throw std::invalid_argument(where + what + " lies beyond the frame's " + std::to_string(m.dlc) + " bytes");
      if (used[static_cast<std::size_t>(byte)])
        throw std::invalid_argument(where + what + " overlaps another field at byte " + std::to_string(byte));
      used[static_cast<std::size_t>(byte)] = true;
    };
    if (m.counter_byte >= 0) claim(m.counter_byte, "the counter");
    if (m.checksum_byte >= 0) claim(m.checksum_byte, "the checksum");
    for (const auto& s : m.signals) {
      if (s.bits != 8 && s.bits != 16 && s.bits != 32)
        throw std::invalid_argument(where + "signal '" + s.name + "': bits must be 8, 16 or 32 (byte-aligned signals)");
      if (!(s.scale != 0.0) || !std::isfinite(s.scale) || !std::isfinite(s.offset))
        throw std::invalid_argument(where + "signal '" + s.name + "': scale must be finite and non-zero");
      const PhysicalRange range = physicalRange(s);
      if (!std::isfinite(range.lo) || !std::isfinite(range.hi))
        throw std::invalid_argument(where + "signal '" + s.name +
                                    "': its scale and offset take the raw range past the largest double");
      for (int b = 0; b < s.bits / 8; ++b) claim(s.byte + b, "signal '" + s.name + "'");
    }
  }
}

namespace {

// An integer field in [lo, hi] (io::integerIn: floats, strings and
// out-of-range values refused before any conversion); `fallback` when absent.
long long integerField(const nlohmann::json& j, const char* key, long long lo, long long hi, const std::string& where,
                       const nlohmann::json* fallback = nullptr) {
  const nlohmann::json* v = j.contains(key) ? &j.at(key) : fallback;
  if (!v) throw std::invalid_argument(where + "missing field '" + key + "'");
  return io::integerIn(*v, lo, hi, key, where.substr(0, where.size() - 2));  // `where` ends in ": "
}

// A string field (`fallback` when absent, required when null), named when it is another type.
std::string textField(const nlohmann::json& j, const char* key, const std::string& where,
                      const char* fallback = nullptr) {
  if (!j.contains(key)) {
    if (!fallback) throw std::invalid_argument(where + "missing field '" + key + "'");
    return fallback;
  }
  if (!j.at(key).is_string()) throw std::invalid_argument(where + "'" + key + "' must be a string");
  return j.at(key).get<std::string>();
}

bool flagField(const nlohmann::json& j, const char* key, bool fallback, const std::string& where) {
  if (!j.contains(key)) return fallback;
  if (!j.at(key).is_boolean()) throw std::invalid_argument(where + "'" + key + "' must be true or false");
  return j.at(key).get<bool>();
}

}  // namespace

SignalMap signalMapFromJson(const std::string& text, const std::string& source) {
  using nlohmann::json;
  const json j = io::parseStrictJson(text, source);
  SignalMap map;
  try {
    if (!j.is_object()) throw std::invalid_argument("the top level must be an object");
    io::requireKnownKeys(j, {"profile", "messages"}, "", source);
    map.profile = textField(j, "profile", "");
    if (!j.contains("messages")) throw std::invalid_argument("missing field 'messages'");
    const json& messages = j.at("messages");
    if (!messages.is_array() || messages.size() > kMaxMessages)
      throw std::invalid_argument("'messages' must be an array of at most " + std::to_string(kMaxMessages));
    for (const auto& jm : messages) {
      if (!jm.is_object()) throw std::invalid_argument("each of 'messages' must be an object");
      MessageLayout m;
      m.name = textField(jm, "name", "a message: ");
      const std::string where = "message '" + m.name + "': ";
      io::requireKnownKeys(jm, {"name", "id", "dlc", "counter_byte", "checksum_byte", "signals"},
                           "messages[" + m.name + "].", source);
      const nlohmann::json none = -1;
      m.id = static_cast<std::uint32_t>(integerField(jm, "id", 0, 0x7FF, where));
      m.dlc = static_cast<int>(integerField(jm, "dlc", 0, 8, where));
      m.counter_byte = static_cast<int>(integerField(jm, "counter_byte", -1, 7, where, &none));
      m.checksum_byte = static_cast<int>(integerField(jm, "checksum_byte", -1, 7, where, &none));
      if (!jm.contains("signals")) throw std::invalid_argument(where + "missing field 'signals'");
      const json& signals = jm.at("signals");
      if (!signals.is_array() || signals.size() > static_cast<std::size_t>(MessageLayout::kMaxSignals))
        throw std::invalid_argument(where + "'signals' must be an array of at most " +
                                    std::to_string(MessageLayout::kMaxSignals));
      for (const auto& js : signals) {
        if (!js.is_object()) throw std::invalid_argument(where + "each signal must be an object");
        Signal s;
        s.name = textField(js, "name", where + "a signal: ");
        const std::string at = where + "signal '" + s.name + "': ";
        io::requireKnownKeys(js, {"name", "byte", "bits", "endian", "signed", "scale", "offset", "unit"},
                             "messages[" + m.name + "].signals[" + s.name + "].", source);
        s.byte = static_cast<int>(integerField(js, "byte", 0, 7, at));
        s.bits = static_cast<int>(integerField(js, "bits", 8, 32, at));
        const std::string endian = textField(js, "endian", at, "little");
        if (endian != "little" && endian != "big") throw std::invalid_argument(at + "endian must be 'little' or 'big'");
        s.little_endian = endian == "little";
        s.is_signed = flagField(js, "signed", false, at);
        if (!js.contains("scale")) throw std::invalid_argument(at + "missing field 'scale'");
        s.scale = io::finiteNumber(js.at("scale"), at + "scale", source);
        s.offset = js.contains("offset") ? io::finiteNumber(js.at("offset"), at + "offset", source) : 0.0;
        s.unit = textField(js, "unit", at, "");
        m.signals.push_back(s);
      }
      map.messages.push_back(std::move(m));
    }
  } catch (const json::exception& e) {
    throw std::invalid_argument(source + ": " + e.what());
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    throw std::invalid_argument(what.rfind(source + ": ", 0) == 0 ? what : source + ": " + what);
  }
  try {
    map.validate();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(source + ": " + e.what());
  }
  return map;
}

std::vector<std::string> driverProfileWarnings(const SignalMap& map) {
  std::vector<std::string> out;
  const std::pair<const char*, std::vector<std::string>> expected[] = {
      {"valve_command", {"setpoint_1", "setpoint_2", "setpoint_3"}},
      {"pressure_sensor", {"pressure_1", "pressure_2", "pressure_3"}},
      {"tip_angle", io::standard_columns::tipAngles()}};
  for (const auto& [name, signals] : expected) {
    const MessageLayout* m = map.find(name);
    if (!m) continue;
    const std::string where = "signal map '" + map.profile + "', message '" + name + "': ";
    if (m->counter_byte < 0) out.push_back(where + "no rolling counter: a lost or replayed frame cannot be detected");
    if (m->checksum_byte < 0) out.push_back(where + "no checksum: a corrupted frame would be applied as it reads");
    std::string names, want;
    bool same = m->signals.size() == signals.size();
    for (std::size_t i = 0; i < m->signals.size(); ++i) {
      names += (i ? ", " : "") + m->signals[i].name;
      same = same && i < signals.size() && m->signals[i].name == signals[i];
    }
    for (std::size_t i = 0; i < signals.size(); ++i) want += (i ? ", " : "") + signals[i];
    if (!same)
      out.push_back(where + "signals are taken by position, in this order: " + names + " (documented names: " + want +
                    "); check chamber " + (std::string(name) == "tip_angle" ? "and angle " : "") + "order");
    const std::string unit = std::string(name) == "tip_angle" ? "deg" : "bar";
    for (const Signal& s : m->signals)
      if (s.unit != unit) out.push_back(where + "signal '" + s.name + "' is in '" + s.unit + "'; plsa reads " + unit);
  }
  return out;
}

SignalMap loadSignalMap(const std::string& path) {
  const std::string name = std::filesystem::path(path).filename().string();
  const auto dot = name.rfind('.');
  std::string ext = dot == std::string::npos ? "" : name.substr(dot);
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (ext == ".dbc" && dot > 0)
    return signalMapFromDbc(readTextFile(path, "DBC file", kMaxDbcBytes), path, name.substr(0, dot));
  return signalMapFromJson(readTextFile(path, "signal map"), path);
}

SignalMap defaultSignalMap() {
  auto pressures = [](const std::string& prefix) {
    std::vector<Signal> s;
    for (int i = 0; i < 3; ++i) s.push_back({prefix + std::to_string(i + 1), 2 * i, 16, true, false, 1e-5, 0.0, "bar"});
    return s;
  };
  SignalMap map{"plsa-default",
                {{"valve_command", 0x100, 8, 6, 7, pressures("setpoint_")},
                 {"pressure_sensor", 0x200, 8, 6, 7, pressures("pressure_")},
                 {"tip_angle",
                  0x210,
                  8,
                  6,
                  7,
                  {{io::standard_columns::kBend, 0, 16, true, true, 0.01, 0.0, "deg"},
                   {io::standard_columns::kSteer, 2, 16, true, true, 0.01, 0.0, "deg"}}}}};
  map.validate();
  return map;
}

PhysicalRange physicalRange(const Signal& s) noexcept {
  const double raw_lo = s.is_signed ? -std::ldexp(1.0, s.bits - 1) : 0.0;
  const double raw_hi = s.is_signed ? std::ldexp(1.0, s.bits - 1) - 1 : std::ldexp(1.0, s.bits) - 1;
  const double a = raw_lo * s.scale + s.offset, b = raw_hi * s.scale + s.offset;
  return {std::min(a, b), std::max(a, b)};
}

bool encodeFrame(const MessageLayout& m, const double* values, std::uint8_t counter, CanFrame& out) noexcept {
  out = CanFrame{};
  out.id = m.id;
  out.dlc = static_cast<std::uint8_t>(m.dlc);
  for (std::size_t k = 0; k < m.signals.size(); ++k) {
    const Signal& s = m.signals[k];
    if (!std::isfinite(values[k])) return false;
    const double raw = std::round((values[k] - s.offset) / s.scale);
    const double lo = s.is_signed ? -std::ldexp(1.0, s.bits - 1) : 0.0;
    const double hi = s.is_signed ? std::ldexp(1.0, s.bits - 1) - 1 : std::ldexp(1.0, s.bits) - 1;
    if (raw < lo || raw > hi) return false;
    const auto bits = static_cast<std::uint32_t>(static_cast<std::int64_t>(raw));
    const int n = s.bits / 8;
    for (int i = 0; i < n; ++i)
      out.data[static_cast<std::size_t>(s.byte + (s.little_endian ? i : n - 1 - i))] =
          static_cast<std::uint8_t>((bits >> (8 * i)) & 0xFF);
  }
  if (m.counter_byte >= 0) out.data[static_cast<std::size_t>(m.counter_byte)] = counter;
  if (m.checksum_byte >= 0) out.data[static_cast<std::size_t>(m.checksum_byte)] = checksum(m, out);
  return true;
}

DecodeStatus decodeFrame(const MessageLayout& m, const CanFrame& f, double* values, int& last_counter) noexcept {
  if (f.id != m.id) return DecodeStatus::kWrongId;
  if (f.dlc != m.dlc) return DecodeStatus::kWrongLength;
  if (m.checksum_byte >= 0 && f.data[static_cast<std::size_t>(m.checksum_byte)] != checksum(m, f))
    return DecodeStatus::kBadChecksum;
  for (std::size_t k = 0; k < m.signals.size(); ++k) {
    const Signal& s = m.signals[k];
    std::uint32_t raw = readRaw(s, f);
    double v;
    if (s.is_signed) {
      const std::uint32_t sign = 1u << (s.bits - 1);
      v = (raw & sign) ? static_cast<double>(static_cast<std::int64_t>(raw) - (std::int64_t{1} << s.bits))
                       : static_cast<double>(raw);
    } else {
      v = static_cast<double>(raw);
    }
    values[k] = v * s.scale + s.offset;
  }
  if (m.counter_byte >= 0) {
    const int c = f.data[static_cast<std::size_t>(m.counter_byte)];
    const bool gap = last_counter >= 0 && c != ((last_counter + 1) & 0xFF);
    last_counter = c;
    if (gap) return DecodeStatus::kCounterGap;
  }
  return DecodeStatus::kOk;
}

}  // namespace plsa::can
