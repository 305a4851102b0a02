// Signal maps: frames encoded and decoded with counter and checksum, profiles and their errors (can/signal_map.hpp).
#include <gtest/gtest.h>

#include <cstdint>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "plsa/can/signal_map.hpp"
#include "plsa/testing/alloc_guard.hpp"

using namespace plsa::can;

namespace {

std::string errorOf(const std::string& json) {
  try {
    signalMapFromJson(json, "map.json");
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "accepted";
}

const char* kOneMessage = R"({"profile": "t", "messages": [{"name": "m", "id": 256, "dlc": 8, "counter_byte": 6,
  "checksum_byte": 7, "signals": [%s]}]})";

std::string withSignals(const std::string& signals) {
  char buf[1024];
  std::snprintf(buf, sizeof buf, kOneMessage, signals.c_str());
  return buf;
}

}  // namespace

TEST(SignalMap, DefaultProfileRoundTripsAndDetectsCorruption) {
  const SignalMap map = defaultSignalMap();
  const MessageLayout& m = map.message("pressure_sensor");
  const double in[3] = {0.1, 0.25, 0.39999};
  CanFrame f;
  ASSERT_TRUE(encodeFrame(m, in, 5, f));
  double out[8];
  int counter = 4;
  ASSERT_EQ(decodeFrame(m, f, out, counter), DecodeStatus::kOk);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(out[i], in[i], 5e-6);
  for (int byte = 0; byte < 8; ++byte) {
    CanFrame bad = f;
    bad.data[static_cast<std::size_t>(byte)] ^= 0x10;
    int c = 4;
    EXPECT_EQ(decodeFrame(m, bad, out, c), DecodeStatus::kBadChecksum) << "byte " << byte;
  }
  CanFrame short_frame = f;
  short_frame.dlc = 6;
  EXPECT_EQ(decodeFrame(m, short_frame, out, counter), DecodeStatus::kWrongLength);
  ASSERT_TRUE(encodeFrame(m, in, 7, f));  // counter 5 -> 7: one frame lost
  counter = 5;
  EXPECT_EQ(decodeFrame(m, f, out, counter), DecodeStatus::kCounterGap);
  const double too_big[3] = {0.9, 0.0, 0.0};  // 0.9 bar does not fit 16 bits at 1e-5
  EXPECT_FALSE(encodeFrame(m, too_big, 0, f));
  EXPECT_THROW(map.message("heater"), std::invalid_argument);
}

TEST(SignalMap, SignedBigEndianSignalsAndJsonErrors) {
  const SignalMap map = signalMapFromJson(withSignals(
      R"({"name": "a", "byte": 0, "bits": 16, "endian": "big", "signed": true, "scale": 0.01, "offset": 1.0},
         {"name": "b", "byte": 2, "bits": 32, "scale": 1.0})"));
  const double in[2] = {-3.21, 123456.0};
  CanFrame f;
  ASSERT_TRUE(encodeFrame(map.messages[0], in, 0, f));
  double out[8];
  int c = -1;
  ASSERT_EQ(decodeFrame(map.messages[0], f, out, c), DecodeStatus::kOk);
  EXPECT_NEAR(out[0], -3.21, 1e-9);
  EXPECT_EQ(out[1], 123456.0);
  EXPECT_NE(errorOf(withSignals(R"({"name": "a", "byte": 5, "bits": 16, "scale": 1})")).find("overlaps"),
            std::string::npos);
  EXPECT_NE(errorOf(withSignals(R"({"name": "a", "byte": 0, "bits": 12, "scale": 1})")).find("8, 16 or 32"),
            std::string::npos);
  EXPECT_NE(errorOf(withSignals(R"({"name": "a", "byte": 0, "bits": 8, "scale": 0})")).find("non-zero"),
            std::string::npos);
  EXPECT_NE(
      errorOf(withSignals(R"({"name": "a", "byte": 0, "bits": 8, "scale": 1, "endian": "middle"})")).find("endian"),
      std::string::npos);
  EXPECT_NE(errorOf(R"({"profile": "t"})").find("map.json"), std::string::npos);
  EXPECT_NE(errorOf("{").find("not valid JSON"), std::string::npos);
  // Found by fuzz_signal_map: a number too large for a double is a JSON error too, not a crash.
  EXPECT_NE(errorOf("77.276e25776e257LF{").find("not valid JSON"), std::string::npos);
  EXPECT_NE(errorOf(withSignals(R"({"name": "a", "byte": 0, "bits": 8, "scale": 1e999})")).find("map.json"),
            std::string::npos);
  // Found by a probe: a finite scale whose raw range overflows decoded every frame as inf (written to CSV, exit 0).
  EXPECT_NE(errorOf(withSignals(R"({"name": "a", "byte": 0, "bits": 16, "scale": 1e308})")).find("largest double"),
            std::string::npos);
  EXPECT_NE(errorOf(withSignals(R"({"name": "a", "byte": 0, "bits": 8, "scale": 1e305, "offset": 1.797e308})"))
                .find("largest double"),
            std::string::npos);
  // Found by fuzz_signal_map under UBSan: a float too large for the id's
  // integer type was converted before any check. Integer fields are now
  // type- and range-checked first.
  EXPECT_NE(errorOf(R"({"profile": "p", "messages": [{"name": "m", "id": 2564444444444444444001722586, "dlc": 8,
    "signals": [{"name": "a", "byte": 0, "bits": 16, "scale": 1}]}]})")
                .find("'id' must be an integer"),
            std::string::npos);
  EXPECT_NE(errorOf(R"({"profile": "p", "messages": [{"name": "m", "id": 256, "dlc": 8.5,
    "signals": [{"name": "a", "byte": 0, "bits": 16, "scale": 1}]}]})")
                .find("'dlc' must be an integer"),
            std::string::npos);
  EXPECT_NE(errorOf(withSignals(R"({"name": "a", "byte": -3, "bits": 16, "scale": 1})"))
                .find("'byte' must be an integer in 0..7"),
            std::string::npos);
}

TEST(SignalMap, DecodingAllocatesNothing) {
  const SignalMap map = defaultSignalMap();
  const MessageLayout& m = map.message("pressure_sensor");
  CanFrame f;
  const double in[3] = {0.1, 0.2, 0.3};
  ASSERT_TRUE(encodeFrame(m, in, 0, f));
  double out[8];
  int c = -1;
  int ok = 0;
  plsa::testing::AllocGuard guard;
  for (int k = 0; k < 10000; ++k) {
    f.data[6] = static_cast<std::uint8_t>(k);
    ok += decodeFrame(m, f, out, c) == DecodeStatus::kBadChecksum ? 0 : 1;
  }
  EXPECT_EQ(guard.allocations(), 0u);
  EXPECT_EQ(ok, (10000 + 255) / 256);  // the checksum is right only where the counter byte is back at 0
}

// Profiles that let two messages share an id or a signal name are refused;
// what the driver cannot guard against (no counter or checksum, signals in
// another order or unit) is named in warnings.
TEST(SignalMap, RefusesAmbiguousProfilesAndWarnsOfUnguardedOnes) {
  const std::string two = R"({"profile": "t", "messages": [
    {"name": "valve_command", "id": 256, "dlc": 8, "signals": [{"name": "a", "byte": 0, "bits": 16, "scale": 1e-5}]},
    {"name": "pressure_sensor", "id": 256, "dlc": 8, "signals": [{"name": "b", "byte": 0, "bits": 16, "scale": 1e-5}]}]})";
  EXPECT_NE(errorOf(two).find("id 256 is also message 'valve_command's"), std::string::npos) << errorOf(two);
  EXPECT_NE(errorOf(withSignals(R"({"name": "a", "byte": 0, "bits": 16, "scale": 1},
                                   {"name": "a", "byte": 2, "bits": 16, "scale": 1})"))
                .find("signal 'a' is named twice"),
            std::string::npos);
  EXPECT_NE(errorOf(withSignals(R"({"name": "a", "byte": 0, "bits": 16, "scale": 1, "gain": 2})")).find("unknown key"),
            std::string::npos);
  EXPECT_NE(errorOf(R"({"profile": "t", "profile": "u", "messages": []})").find("given twice"), std::string::npos);
  // Fields of the wrong type or missing are named, not nlohmann's words; a map of no messages is no map.
  EXPECT_NE(errorOf(withSignals(R"({"name": "a", "byte": 0, "bits": 16, "scale": 1, "signed": 1})"))
                .find("signal 'a': 'signed' must be true or false"),
            std::string::npos);
  EXPECT_NE(errorOf(withSignals(R"({"name": "a", "byte": 0, "bits": 0, "scale": 1})"))
                .find("'bits' must be an integer in 8..32"),
            std::string::npos);
  EXPECT_NE(errorOf("{}").find("missing field 'profile'"), std::string::npos) << errorOf("{}");
  EXPECT_NE(errorOf(R"({"profile": "t", "messages": []})").find("no messages"), std::string::npos);
  EXPECT_NE(errorOf(withSignals(R"({"name": "a", "byte": 0, "bits": 16, "scale": 1e400})")).find("not valid JSON"),
            std::string::npos);

  EXPECT_TRUE(driverProfileWarnings(defaultSignalMap()).empty());
  SignalMap bare = defaultSignalMap();
  for (auto& m : bare.messages)
    if (m.name == "valve_command") {
      m.counter_byte = m.checksum_byte = -1;
      std::swap(m.signals[0].name, m.signals[1].name);
    }
  bare.validate();
  const std::vector<std::string> w = driverProfileWarnings(bare);
  ASSERT_EQ(w.size(), 3u);
  EXPECT_NE(w[0].find("no rolling counter"), std::string::npos) << w[0];
  EXPECT_NE(w[1].find("no checksum"), std::string::npos) << w[1];
  EXPECT_NE(w[2].find("taken by position, in this order: setpoint_2, setpoint_1, setpoint_3"), std::string::npos)
      << w[2];
}
