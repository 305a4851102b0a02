// libFuzzer target: arbitrary text as a signal-map file. Parsing either
// throws std::invalid_argument with a message or yields a map that
// validates, and every message of it encodes and decodes back.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <stdexcept>
#include <string>

#include "plsa/can/signal_map.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  plsa::can::SignalMap map;
  try {
    map = plsa::can::signalMapFromJson(text, "fuzz.json");
  } catch (const std::invalid_argument& e) {
    if (std::string(e.what()).empty()) std::abort();
    return 0;
  }
  map.validate();  // a parsed map must already be valid: this must not throw
  for (const auto& m : map.messages) {
    double values[plsa::can::MessageLayout::kMaxSignals] = {};
    for (std::size_t s = 0; s < m.signals.size(); ++s) values[s] = m.signals[s].offset;  // raw 0 always fits
    plsa::can::CanFrame f;
    if (!plsa::can::encodeFrame(m, values, 5, f)) std::abort();
    double back[plsa::can::MessageLayout::kMaxSignals];
    int counter = 4;
    const auto st = plsa::can::decodeFrame(m, f, back, counter);
    if (st != plsa::can::DecodeStatus::kOk) std::abort();
    for (std::size_t s = 0; s < m.signals.size(); ++s)
      if (!(std::abs(back[s] - values[s]) <= 1e-9 * (1 + std::abs(values[s])))) std::abort();
  }
  return 0;
}
