// The checked LCM decoders: every count and length is checked before the
// generated decoder allocates, and the error names the field.
#include <gtest/gtest.h>

#include <string>

#include "plsa/lcm/message_codec.hpp"
#include "support/lcm_bytes.hpp"

namespace {

using plsa::test::encoded;
using plsa::test::withInt32;

plsa_lcm::pressure_command_t command() {
  plsa_lcm::pressure_command_t c{};
  c.utime = 7;
  c.seq = 3;
  c.n_chambers = 3;
  c.pressure_bar = {0.1, 0.2, 0.3};
  return c;
}

}  // namespace

TEST(MessageCodec, AcceptsWhatTheGeneratedEncoderWrites) {
  const std::string bytes = encoded(command());
  plsa_lcm::pressure_command_t back;
  ASSERT_EQ(plsa::lcm::decodeMessage(bytes.data(), bytes.size(), back), "");
  EXPECT_EQ(back.pressure_bar, command().pressure_bar);
  EXPECT_EQ(back.seq, 3);

  plsa_lcm::status_t s{};
  s.source = "plsa sim";
  s.message = "running";
  s.n_values = 2;
  s.names = {"a", "b"};
  s.values = {1, 2};
  const std::string sb = encoded(s);
  plsa_lcm::status_t sback;
  ASSERT_EQ(plsa::lcm::decodeMessage(sb.data(), sb.size(), sback), "");
  EXPECT_EQ(sback.names, s.names);
  EXPECT_EQ(sback.message, "running");
}

TEST(MessageCodec, RefusesCountsAndLengthsBeforeAllocatingAndNamesTheField) {
  const std::string good = encoded(command());
  plsa_lcm::pressure_command_t out;
  // The messages that crashed the bridge, sim and predictor nodes: n_chambers -1 and 2^28.
  const std::string negative = withInt32(good.substr(0, 28), 24, 0xFFFFFFFFu);
  EXPECT_EQ(plsa::lcm::decodeMessage(negative.data(), negative.size(), out),
            "plsa_lcm.pressure_command_t: n_chambers = -1 is outside 0..16 (28-byte message)");
  const std::string huge = withInt32(good.substr(0, 28), 24, 0x10000000u);
  EXPECT_NE(plsa::lcm::decodeMessage(huge.data(), huge.size(), out).find("n_chambers = 268435456"), std::string::npos);
  // A count within its limit but beyond the bytes there are.
  const std::string short_of = withInt32(good, 24, 16);
  EXPECT_NE(plsa::lcm::decodeMessage(short_of.data(), short_of.size(), out).find("pressure_bar runs past"),
            std::string::npos);
  const std::string trailing = good + "x";
  EXPECT_NE(plsa::lcm::decodeMessage(trailing.data(), trailing.size(), out).find("1 bytes after its last field"),
            std::string::npos);
  // Another type's bytes: the fingerprint differs.
  plsa_lcm::actuator_state_t as_state;
  EXPECT_NE(plsa::lcm::decodeMessage(good.data(), good.size(), as_state).find("fingerprint"), std::string::npos);
  EXPECT_NE(plsa::lcm::decodeMessage(good.data(), 3, out), "");

  plsa_lcm::status_t s{};
  s.source = "x";
  s.message = "y";
  s.n_values = 0;
  const std::string sb = encoded(s);
  plsa_lcm::status_t sout;
  // A negative string length threw std::length_error inside the generated decoder.
  for (std::uint32_t len : {0xFFFFFFF0u, 0u, 0x7FFFFFFFu}) {
    const std::string bad = withInt32(sb, 16, len);
    EXPECT_NE(plsa::lcm::decodeMessage(bad.data(), bad.size(), sout).find("source"), std::string::npos) << len;
  }
  std::string embedded = sb;
  embedded[20] = '\0';  // "x" -> a NUL inside the string, then its terminator
  EXPECT_NE(plsa::lcm::decodeMessage(embedded.data(), embedded.size(), sout).find("source"), std::string::npos);
}
