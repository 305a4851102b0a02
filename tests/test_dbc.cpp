// Signal maps as DBC files: plsa's profile written and read back unchanged,
// a DBC as another tool writes it read (comments, attributes, value tables,
// Motorola byte order, the pseudo-message of unassigned signals), and what a
// signal map cannot carry refused with its line.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "plsa/can/dbc.hpp"
#include "support/refusals.hpp"

namespace plsa::can {
namespace {

// Two maps alike in every message and signal field (their profile names aside),
// compared through the JSON profile, which writes every field.
void expectSameMap(SignalMap a, SignalMap b) {
  a.profile = b.profile = "";
  EXPECT_EQ(signalMapToJson(a), signalMapToJson(b));
}

TEST(Dbc, PlsasProfileRoundTripsThroughDbcAndJson) {
  SignalMap map = defaultSignalMap();
  map.messages[1].signals[0].little_endian = false;  // a Motorola signal too
  map.messages[1].signals[1].offset = -0.125;
  const std::string dbc = signalMapToDbc(map);
  EXPECT_NE(dbc.find("BO_ 256 valve_command: 8 plsa"), std::string::npos) << dbc;
  EXPECT_NE(dbc.find(" SG_ setpoint_1 : 0|16@1+ (1e-05,0) [0|0.65535]"), std::string::npos) << dbc;
  EXPECT_NE(dbc.find(" SG_ counter : 48|8@1+ (1,0) [0|255]"), std::string::npos) << dbc;
  EXPECT_NE(dbc.find(" SG_ pressure_1 : 7|16@0+"), std::string::npos) << dbc;  // MSB of byte 0
  expectSameMap(signalMapFromDbc(dbc, "p.dbc", "p"), map);
  expectSameMap(signalMapFromJson(signalMapToJson(map), "p.json"), map);
  EXPECT_EQ(signalMapFromDbc(dbc, "p.dbc", "p").profile, "p");
}

TEST(Dbc, AnotherToolsDbcIsReadForItsMessagesAndSignals) {
  const std::string dbc = R"(VERSION "1.0"

NS_ :
	NS_DESC_
	CM_
	BA_DEF_
	SG_MUL_VAL_

BS_:

BU_: ECU Valves

BO_ 512 pressure_sensor: 8 Valves
 SG_ pressure_1 : 0|16@1+ (1E-005,0) [0|0.65535] "bar" ECU
 SG_ pressure_2 : 23|16@0+ (1E-005,0) [0|0.65535] "bar"  ECU,Logger
 SG_ pressure_3 : 32|16@1- (1E-005,0.1) [-0.2|0.4] "bar" ECU
 SG_ counter : 48|8@1+ (1,0) [0|255] "" ECU
 SG_ checksum : 56|8@1+ (1,0) [0|255] "" ECU

BO_ 3221225472 VECTOR__INDEPENDENT_SIG_MSG: 0 Vector__XXX
 SG_ spare : 0|3@1+ (1,0) [0|0] "" Vector__XXX

CM_ BO_ 512 "The sensors' frame;
 SG_ this line is inside a comment";
BA_DEF_ BO_ "GenMsgCycleTime" INT 0 10000;
BA_ "GenMsgCycleTime" BO_ 512 12;
VAL_ 512 counter 0 "zero" ;
)";
  const SignalMap map = signalMapFromDbc(dbc, "bus.dbc", "bus");
  ASSERT_EQ(map.messages.size(), 1u);
  const MessageLayout& m = map.messages[0];
  EXPECT_EQ(m.id, 0x200u);
  EXPECT_EQ(m.counter_byte, 6);
  EXPECT_EQ(m.checksum_byte, 7);
  ASSERT_EQ(m.signals.size(), 3u);
  EXPECT_EQ(m.signals[1].byte, 2);  // Motorola: bit 23 is the MSB of byte 2
  EXPECT_FALSE(m.signals[1].little_endian);
  EXPECT_TRUE(m.signals[2].is_signed);
  EXPECT_EQ(m.signals[2].offset, 0.1);
  EXPECT_EQ(m.signals[0].unit, "bar");
  // Decodes a frame as the DBC says: pressure_2 big-endian 0x3039 = 12345 counts.
  CanFrame f;
  const double values[] = {0.2, 0.12345, 0.0};
  ASSERT_TRUE(encodeFrame(m, values, 9, f));
  EXPECT_EQ(f.data[2], 0x30);
  EXPECT_EQ(f.data[3], 0x39);
}

TEST(Dbc, WhatASignalMapCannotCarryIsNamedWithItsLine) {
  const std::string head = "BU_: A\n\nBO_ 256 valve_command: 8 A\n";
  const std::vector<test::Refusal> cases = {
      {"BU_: A\nBO_ 2147483904 ext: 8 A\n SG_ a : 0|16@1+ (1,0) [0|0] \"\" A\n", ":2: message 'ext': id 2147483904"},
      {head + " SG_ a : 4|16@1+ (1,0) [0|0] \"\" A\n", ":4: message 'valve_command', signal 'a': starts at bit 4"},
      {head + " SG_ a : 0|12@1+ (1,0) [0|0] \"\" A\n", "12 bits; plsa reads 8-, 16- and 32-bit signals"},
      {head + " SG_ a M : 0|8@1+ (1,0) [0|0] \"\" A\n", "multiplexed signals are not read"},
      {head + " SG_ a : 0|16@1+ (1,0) [0|0] \"\" A\n SG_ counter : 16|8@1+ (2,0) [0|0] \"\" A\n",
       "a counter or checksum is one unsigned byte"},
      {head + " SG_ a : 0|16@1+ (x,0) [0|0] \"\" A\n", "scale 'x' is not a number"},
      {head + " SG_ a : 0|16@1+ (0x10,0) [0|0] \"\" A\n", "scale '0x10' is not a decimal number"},  // read as 16
      {head + " SG_ a : 0|16@1+ (1e308,0) [0|0] \"\" A\n", "raw range past the largest double"},
      {head + " SG_ a : 0|16@1+ (1,0) [0|0] A\n", ":4: not a DBC signal line"},
      {head + " SG_ a : 0|16@1+ (1,0) [0|0] \"\" A\nSIG_VALTYPE_ 256 a : 1;\n", "a float signal (SIG_VALTYPE_)"},
      {"BO_ 256 m: 9 A\n", "dlc 9 (classic CAN: 0..8)"},
      {" SG_ a : 0|16@1+ (1,0) [0|0] \"\" A\n", ":1: a signal outside any message"},
      {head + " SG_ a : 56|16@1+ (1,0) [0|0] \"\" A\n", "lies beyond the frame's 8 bytes"},
      {"VERSION \"\"\n", "no BO_ messages"},
      {"CM_ \"a stray quote\n" + head + " SG_ a : 0|16@1+ (1,0) [0|0] \"\" A\n",  // found by a probe
       ":1: a string opened here is never closed"},
      {head + " SG_ a : 0|16@1+ (1,0) [0|0] \"d\xE9g\" A\n", "the unit is not printable UTF-8"},  // Latin-1
      {head + " SG_ a : 0|16@1+ (1,0) [0|0] \"\xED\xA0\x80\" A\n", "the unit is not printable UTF-8"},
      {head + " SG_ a : 0|16@1+ (1,0) [0|0] \"\\\" A\n", "the unit is not printable UTF-8"},
      {head + std::string(5000, ' ') + "\n", "line longer than 4096 bytes"},
  };
  test::expectEachRefused<std::invalid_argument>(
      cases, [](const std::string& text) { signalMapFromDbc(text, "bus.dbc", "bus"); }, "bus.dbc");
}

TEST(Dbc, AUnitIsCarriedAsUtf8AndOneDbcCannotHoldIsRefused) {
  SignalMap map = defaultSignalMap();
  map.messages[2].signals[0].unit = "\xC2\xB0";  // the degree sign
  EXPECT_EQ(signalMapFromDbc(signalMapToDbc(map), "p.dbc", "p").messages[2].signals[0].unit, "\xC2\xB0");
  map.messages[2].signals[0].unit = "a \"b\"";
  EXPECT_THROW(signalMapToDbc(map), std::invalid_argument);
  map.messages[2].signals[0].unit = "a\\";  // found by fuzz_signal_map: read back, it opened a string
  EXPECT_THROW(signalMapToDbc(map), std::invalid_argument);
  map.messages[2].signals[0].unit = "deg";
  map.messages[2].signals[1].name = "counter";  // a DBC would read it back as the counter byte
  EXPECT_THROW(signalMapToDbc(map), std::invalid_argument);
}

TEST(Dbc, LoadSignalMapTakesADbcFileByItsName) {
  const auto path = std::filesystem::temp_directory_path() / "plsa_test_profile.DBC";
  std::ofstream(path) << signalMapToDbc(defaultSignalMap());
  const SignalMap map = loadSignalMap(path.string());
  EXPECT_EQ(map.profile, "plsa_test_profile");
  expectSameMap(map, defaultSignalMap());
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace plsa::can
