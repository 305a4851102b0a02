// The output frame chosen from the outputs' names and data (plsa/identify/output_frame_choice.hpp).
#include <gtest/gtest.h>

#include <string>

#include <Eigen/Dense>

#include "plsa/identify/output_frame_choice.hpp"

using namespace plsa;
using namespace plsa::identify;

// Identification given only column names picks the frame the outputs
// describe, says so, and says how to pick the other.
TEST(OutputFrameChoice, TipFrameFromBendingAndSteeringNamesAndNonNegativeBending) {
  Eigen::MatrixXd y(100, 2);
  y.col(0) = Eigen::VectorXd::LinSpaced(100, 0.0, 30.0);
  y.col(1) = Eigen::VectorXd::LinSpaced(100, -170.0, 170.0);
  const OutputFrameChoice tip = chooseOutputFrame({"bend_deg", "steer_deg"}, {y});
  EXPECT_EQ(tip.frame, OutputFrame::kTipCartesian);
  EXPECT_NE(tip.reason.find("--output-frame as_logged"), std::string::npos) << tip.reason;
  EXPECT_EQ(chooseOutputFrame({"Theta", "Phi"}, {y}).frame, OutputFrame::kTipCartesian);
  EXPECT_EQ(chooseOutputFrame({"tip_inclination", "tip_azimuth"}, {y}).frame, OutputFrame::kTipCartesian);
  // Reversed: named, and the fix given.
  const OutputFrameChoice reversed = chooseOutputFrame({"steer_deg", "bend_deg"}, {y});
  EXPECT_EQ(reversed.frame, OutputFrame::kAsLogged);
  EXPECT_NE(reversed.reason.find("--outputs bend_deg,steer_deg"), std::string::npos) << reversed.reason;
  // Names that say nothing: as logged, with the option named.
  const OutputFrameChoice unnamed = chooseOutputFrame({"y_1", "y_2"}, {y});
  EXPECT_EQ(unnamed.frame, OutputFrame::kAsLogged);
  EXPECT_NE(unnamed.reason.find("--output-frame tip_cartesian"), std::string::npos) << unnamed.reason;
  EXPECT_EQ(chooseOutputFrame({"bend_deg"}, {y.leftCols(1)}).frame, OutputFrame::kAsLogged);
  // A "bending" that goes negative is no polar radius: a planar angle, say.
  Eigen::MatrixXd planar = y;
  planar.col(0).array() -= 15.0;
  const OutputFrameChoice signed_bend = chooseOutputFrame({"bend_deg", "steer_deg"}, {y, planar});
  EXPECT_EQ(signed_bend.frame, OutputFrame::kAsLogged);
  EXPECT_NE(signed_bend.reason.find("below -0.5 deg"), std::string::npos) << signed_bend.reason;
  // Noise around zero bending is still a tip direction.
  Eigen::MatrixXd noisy = y;
  noisy(3, 0) = -0.3;
  EXPECT_EQ(chooseOutputFrame({"bend_deg", "steer_deg"}, {noisy}).frame, OutputFrame::kTipCartesian);
}

// The tip's angle unit: what the names say, else what the data allow (a
// radian angle stays within 2 pi), else as given; each choice says why, and
// the negative-bending check reads its -0.5 deg in that unit.
TEST(OutputFrameChoice, AngleUnitFromTheNamesElseTheData) {
  Eigen::MatrixXd deg(100, 2);
  deg.col(0) = Eigen::VectorXd::LinSpaced(100, 0.0, 30.0);
  deg.col(1) = Eigen::VectorXd::LinSpaced(100, -170.0, 170.0);
  const Eigen::MatrixXd rad = deg * kRadPerDeg;
  std::string why;
  EXPECT_EQ(chooseAngleUnit({"theta", "phi"}, {rad}, std::nullopt, why), "rad");
  EXPECT_NE(why.find("--angle-unit deg"), std::string::npos) << why;
  EXPECT_EQ(chooseAngleUnit({"theta", "phi"}, {deg}, std::nullopt, why), "deg");
  EXPECT_EQ(why, "values beyond 2 pi");
  // An azimuth in [0, 2 pi) is radians still.
  Eigen::MatrixXd azimuth = rad;
  azimuth.col(1).array() += kPi;
  EXPECT_EQ(chooseAngleUnit({"theta", "phi"}, {azimuth}, std::nullopt, why), "rad");
  // The names win over the data, the option over both.
  EXPECT_EQ(chooseAngleUnit({"bend_deg", "steer_deg"}, {rad}, std::nullopt, why), "deg");
  EXPECT_EQ(why, "as the names say");
  EXPECT_EQ(chooseAngleUnit({"bend_rad", "steer_rad"}, {deg}, std::nullopt, why), "rad");
  EXPECT_EQ(chooseAngleUnit({"theta", "phi"}, {rad}, std::string("deg"), why), "deg");
  EXPECT_EQ(why, "as given");
  EXPECT_THROW(chooseAngleUnit({"theta", "phi"}, {rad}, std::string("grad"), why), std::invalid_argument);
  try {
    chooseAngleUnit({"bend_deg", "steer_rad"}, {rad}, std::nullopt, why);
    ADD_FAILURE() << "two units accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("different angle units"), std::string::npos) << e.what();
  }
  // The choice carries the unit and says it.
  const OutputFrameChoice in_rad = chooseOutputFrame({"theta", "phi"}, {rad});
  EXPECT_EQ(in_rad.frame, OutputFrame::kTipCartesian);
  EXPECT_EQ(in_rad.angle_unit, "rad");
  EXPECT_NE(in_rad.reason.find("angles in rad"), std::string::npos) << in_rad.reason;
  EXPECT_EQ(chooseOutputFrame({"theta", "phi"}, {deg}).angle_unit, "deg");
  // -0.3 deg of noise passes in radians as in degrees; a planar angle's -15 deg does not.
  Eigen::MatrixXd noisy = rad;
  noisy(3, 0) = -0.3 * kRadPerDeg;
  EXPECT_EQ(chooseOutputFrame({"theta", "phi"}, {noisy}).frame, OutputFrame::kTipCartesian);
  Eigen::MatrixXd planar = rad;
  planar.col(0).array() -= 15.0 * kRadPerDeg;
  EXPECT_EQ(chooseOutputFrame({"theta", "phi"}, {rad, planar}).frame, OutputFrame::kAsLogged);
}
