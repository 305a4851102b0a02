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
