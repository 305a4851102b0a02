// The generalisation benchmark's small version (ctest label
// "generalisation"): `plsa generalise --quick` on the independently written
// actuator, identify's defaults, every model scored on the same samples.
#include <cmath>

#include <nlohmann/json.hpp>

#include "support/cli_run.hpp"

namespace {
using Generalise = plsa::test::CliTest;
}  // namespace

TEST_F(Generalise, ScoresEveryModelOnTheIndependentActuator) {
  // Three physics (nominal, Bouc-Wen hysteresis, every effect), one seed;
  // the full matrix is `plsa generalise` (docs/identification.md).
  ASSERT_EQ(run("generalise --quick --json " + file("gen.json")), 0) << err_ << slurp(file("stdout.txt"));
  const auto j = nlohmann::json::parse(slurp(file("gen.json")));
  ASSERT_EQ(j["rows"].size(), 3u);
  for (const auto& row : j["rows"])
    for (const char* m : {"plsa", "paper", "global_linear", "arx"})
      for (const char* out : {"bend_deg", "steer_deg"})
        for (const char* h : {"40", "80", "sim"})
          EXPECT_TRUE(std::isfinite(row["fits"][m][out][h].get<double>())) << row["case"] << " " << m << " " << out;
  // plsa leads the paper's configuration and ARX(4,4) at 40 and 80 steps on
  // the mean over the rows, on both outputs.
  const auto& s = j["summary"];
  for (const char* out : {"bend_deg", "steer_deg"})
    for (const char* h : {"40", "80"})
      for (const char* peer : {"paper", "arx"})
        EXPECT_GT(s["plsa"][out][h]["mean"].get<double>(), s[peer][out][h]["mean"].get<double>())
            << out << " " << h << "-step against " << peer;
  EXPECT_NE(slurp(file("stdout.txt")).find("plsa meets 90 / 90 / 85 on both outputs in"), std::string::npos);
}
