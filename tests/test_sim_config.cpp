// The simulator's configuration (JSON round trip, addressable parameters)
// and the actuator's checks on its commands.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <set>

#include "plsa/sim/actuator.hpp"
#include "plsa/sim/experiment.hpp"
#include "support/sim_probes.hpp"

using namespace plsa::sim;
using namespace plsa::sim::probes;

// --- configuration, input checks, determinism ----------------------------------

TEST(SimConfig, JsonRoundTripAndErrors) {
  SimConfig c;
  c.creep.enabled = false;
  c.hysteresis.formulation = "prandtl_ishlinskii";
  c.coupling.per_bar = 0.5;
  c.integrator = "exponential";
  const SimConfig back = simConfigFromJson(simConfigToJson(c));
  EXPECT_EQ(back.integrator, "exponential");
  EXPECT_EQ(SimConfig{}.integrator, "euler");
  EXPECT_FALSE(back.creep.enabled);
  EXPECT_EQ(back.hysteresis.formulation, "prandtl_ishlinskii");
  EXPECT_EQ(back.coupling.per_bar, 0.5);
  auto error = [](const std::string& text) {
    try {
      simConfigFromJson(text, "cfg.json");
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_NE(error(R"({"creep": {"fraktion": 0.1}})").find("unknown key 'creep.fraktion'"), std::string::npos);
  EXPECT_NE(error(R"({"creep": {"fraction": 3}})").find("creep.fraction = 3 is outside"), std::string::npos);
  EXPECT_NE(error(R"({"creep": {"enabled": "yes"}})").find("true or false"), std::string::npos);
  EXPECT_NE(error(R"({"deadzone": {"formulation": "round"}})").find("formulation 'round'"), std::string::npos);
  EXPECT_NE(error(R"({"bogus": {}})").find("unknown section 'bogus'"), std::string::npos);
  EXPECT_NE(error(R"({"integrator": "rk4"})").find("integrator 'rk4' is not one of euler, exponential"),
            std::string::npos);
  EXPECT_NE(error(R"({"integrator": 1})").find("cfg.json: integrator must be a string"), std::string::npos);
  EXPECT_NE(error("{").find("not valid JSON"), std::string::npos);
  // A number beyond double range escaped as a raw library exception; a key given twice kept the last.
  EXPECT_NE(error(R"({"sample_rate_hz": 1e400})").find("cfg.json: not valid JSON"), std::string::npos);
  EXPECT_NE(error(R"({"creep": {"fraction": 0.1, "fraction": 0.2}})").find("key 'creep.fraction' is given twice"),
            std::string::npos);
  EXPECT_NE(error(R"({"geometry": {"bend_direction_deg": [0, null, 240]}})").find("must be a number"),
            std::string::npos);
  // A NUL in a string cut every message that quoted it ("coupling.formulation 'multi").
  EXPECT_EQ(error(R"({"coupling": {"formulation": "multi\u0000plicative"}})"),
            "cfg.json: the string at 'coupling.formulation' has the control character U+0000 at byte 5 (names, units "
            "and laws are printable text)");
  EXPECT_NE(
      error(R"({"coupling": {"per\u0007bar": 0.5}})").find("a key in 'coupling' has the control character U+0007"),
      std::string::npos);
  EXPECT_NE(error(R"({"bogus\u001f": 1})").find("a key at the top level has the control character U+001F at byte 5"),
            std::string::npos);
  // 0.75 p - 1 p^2 peaks at 0.375 bar, inside the 0.4 bar range; -0.9 peaks beyond it.
  EXPECT_NE(error(R"({"elongation": {"quadratic": -1.0}})").find("stops rising at 0.375 bar"), std::string::npos);
  EXPECT_EQ(error(R"({"elongation": {"quadratic": -0.9}})"), "accepted");
  EXPECT_EQ(error(R"({"elongation": {"quadratic": -1.0}, "max_pressure_bar": 0.35})"), "accepted");
  // Chamber directions: angles, three apart (a probe: 1e300 and [0, 0, 0] were taken).
  EXPECT_NE(error(R"({"geometry": {"bend_direction_deg": [0, 120, 1e300]}})")
                .find("geometry.bend_direction_deg[2] = 1e+300 is outside [-360, 360] deg"),
            std::string::npos);
  EXPECT_NE(error(R"({"geometry": {"bend_direction_deg": [0, 0, 0]}})")
                .find("geometry.bend_direction_deg[0] and [1] are under 1 deg apart"),
            std::string::npos);
  EXPECT_NE(error(R"({"geometry": {"bend_direction_deg": [0, 120, 359.5]}})").find("[0] and [2] are under 1 deg apart"),
            std::string::npos);
  EXPECT_EQ(error(R"({"geometry": {"bend_direction_deg": [-90, 30, 150]}})"), "accepted");
}

TEST(SimConfig, ParametersAreAddressableByModule) {
  SimConfig c;
  auto p = c.parameters("pneumatic_lag");
  ASSERT_EQ(p.size(), 3u);
  *p[2].value = 0.07;
  EXPECT_EQ(c.pneumatic_lag.delay_s, 0.07);
  // The flexible law's: exponent, pressure scaling and the supply line's volume besides.
  c.pneumatic_lag.formulation = "power";
  p = c.parameters("pneumatic_lag");
  ASSERT_EQ(p.size(), 6u);
  EXPECT_EQ(p.back().name, "line_time_constant_s");
  *p.back().value = 0.12;
  EXPECT_EQ(c.pneumatic_lag.line_time_constant_s, 0.12);
  EXPECT_GE(c.parameters("nominal").size(), 6u);
  EXPECT_THROW(c.parameters("friction"), std::invalid_argument);
}

TEST(SimActuator, ClampsCommandsAndRejectsNaN) {
  Actuator a(SimConfig{}, 1);
  const auto s = a.step({0.9, -0.2, 0.1});
  EXPECT_EQ(s.command_bar[0], 0.4);
  EXPECT_EQ(s.command_bar[1], 0.0);
  EXPECT_THROW(a.step({std::nan(""), 0, 0}), std::invalid_argument);
}
