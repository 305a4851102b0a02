// The model's value types: the tip frame's components and the play channel.
#include "support/identify_fixtures.hpp"

using namespace plsa;
using namespace plsa::test_fixtures;
using C = std::complex<double>;

TEST(OutputFrame, TipComponentsRoundTripOnTheReferenceBranch) {
  const double deg = radiansPerAngleUnit("deg");
  double x = 0, y = 0, bend = 0, steer = 0;
  tipComponents(30.0, 60.0, deg, x, y);
  EXPECT_NEAR(x, 15.0, 1e-12);
  EXPECT_NEAR(y, 30.0 * std::sqrt(3.0) / 2.0, 1e-12);
  tipAngles(x, y, 55.0, deg, bend, steer);
  EXPECT_NEAR(bend, 30.0, 1e-12);
  EXPECT_NEAR(steer, 60.0, 1e-12);
  // Across +-180 deg the angle follows the reference instead of jumping a turn.
  tipComponents(20.0, 185.0, deg, x, y);
  tipAngles(x, y, 179.0, deg, bend, steer);
  EXPECT_NEAR(steer, 185.0, 1e-9);
  tipAngles(x, y, -170.0, deg, bend, steer);
  EXPECT_NEAR(steer, -175.0, 1e-9);
  tipAngles(x, y, 900.0, deg, bend, steer);  // several turns on: the nearest branch still
  EXPECT_NEAR(steer, 905.0, 1e-9);
  // Records: exactly two outputs, else an error naming the frame.
  const Eigen::MatrixXd three = Eigen::MatrixXd::Ones(4, 3);
  try {
    toModelFrame(OutputFrame::kTipCartesian, three, deg);
    ADD_FAILURE() << "three outputs accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("exactly two outputs"), std::string::npos) << e.what();
  }
  EXPECT_EQ(toModelFrame(OutputFrame::kAsLogged, three, deg), three);
  EXPECT_THROW(outputFrameFromString("polar"), std::invalid_argument);
}

// The same direction logged in radians: the same components (in the bending's
// unit), and a turn of 2 pi where degrees take 360.
TEST(OutputFrame, TipComponentsInRadians) {
  const double rad = radiansPerAngleUnit("rad"), deg = radiansPerAngleUnit("deg");
  EXPECT_EQ(rad, 1.0);
  EXPECT_EQ(angleUnitsPerRadian("rad"), 1.0);
  EXPECT_EQ(angleUnitsPerRadian("deg"), 180.0 / kPi);
  double xd = 0, yd = 0, xr = 0, yr = 0, bend = 0, steer = 0;
  tipComponents(30.0, 185.0, deg, xd, yd);
  tipComponents(30.0 * deg, 185.0 * deg, rad, xr, yr);
  EXPECT_NEAR(xr, xd * deg, 1e-12);
  EXPECT_NEAR(yr, yd * deg, 1e-12);
  tipAngles(xr, yr, 179.0 * deg, rad, bend, steer);
  EXPECT_NEAR(bend, 30.0 * deg, 1e-12);
  EXPECT_NEAR(steer, 185.0 * deg, 1e-12);  // past pi on the reference's branch
  tipAngles(xr, yr, -3.0, rad, bend, steer);
  EXPECT_NEAR(steer, 185.0 * deg - 2.0 * kPi, 1e-12);
  try {
    radiansPerAngleUnit("grad");
    ADD_FAILURE() << "grad accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'grad'"), std::string::npos) << e.what();
  }
}

// Rising from a vent, the band trails below the first pressure, so the next
// rise moves the played input at once; centred, the first half-band is lost.
TEST(PlayChannel, RisingStartFollowsTheFirstRiseAndSlopeGrowsTheBand) {
  Eigen::VectorXd u(4);
  u << 0.2, 0.25, 0.3, 0.28;
  const PlayChannel fixed(0.03), growing(0.0, 0.1);
  const Eigen::VectorXd rising = eval::playedInput(u, fixed, PlayStart::kRising);
  const Eigen::VectorXd centred = eval::playedInput(u, fixed, PlayStart::kCentred);
  EXPECT_NEAR(rising(1) - rising(0), 0.05, 1e-12);
  EXPECT_NEAR(centred(1) - centred(0), 0.02, 1e-12);
  EXPECT_NEAR(rising(3), rising(2), 1e-12);  // a reversal smaller than the band does not move it
  const Eigen::VectorXd g = eval::playedInput(u, growing, PlayStart::kRising);
  EXPECT_NEAR(g(0), 0.2 - 0.02, 1e-12);
  EXPECT_NEAR(g(2), 0.3 - 0.03, 1e-12);  // the band is 10% of the level
  EXPECT_NEAR(g(3), g(2), 1e-12);        // dropping 0.02 stays inside a 0.028 band
  // Coupling: a chamber's level less kappa x its level x its pressurised neighbours'.
  EXPECT_EQ(coupledLevel(0.3, 0.3 + 0.2, 0.0), 0.3);
  EXPECT_NEAR(coupledLevel(0.3, 0.3 + 0.2 + 0.0, 1.0), 0.3 - 0.3 * 0.2, 1e-15);
  EXPECT_NEAR(coupledLevel(-0.01, 0.2, 1.0), -0.01, 1e-15);  // an empty chamber is not pushed further
  // Softening: x - s x^2 first, then the coupling on what is left; flat past the peak at 1/2s.
  EXPECT_NEAR(coupledLevel(0.3, 0.3, 0.0, 1.0), 0.3 - 0.09, 1e-15);
  EXPECT_NEAR(coupledLevel(0.3, 0.3 + 0.2, 1.0, 1.0), 0.21 - 0.21 * 0.2, 1e-15);
  EXPECT_NEAR(coupledLevel(0.3, 0.3, 0.0, 2.0), 0.125, 1e-15);
  EXPECT_EQ(coupledLevel(0.3, 0.3, 0.0, 2.0), coupledLevel(0.25, 0.25, 0.0, 2.0));
  EXPECT_LT(coupledLevel(0.2, 0.2, 0.0, 2.0), coupledLevel(0.24, 0.24, 0.0, 2.0));
  EXPECT_NEAR(coupledLevel(-0.01, 0.2, 1.0, 1.0), -0.01, 1e-15);
  // A threshold: levels count from it, zero below it; none passes negatives through.
  EXPECT_NEAR(levelAbove(0.3, 0.07), 0.23, 1e-15);
  EXPECT_EQ(levelAbove(0.05, 0.07), 0.0);
  EXPECT_EQ(levelAbove(-0.01, 0.0), -0.01);
  EXPECT_NEAR(positiveSumAbove(Eigen::Vector3d(0.3, 0.2, 0.0), 0.07), 0.23 + 0.13, 1e-15);
}
