// Which frame identification fits a model's outputs in when the user does not
// say: a tip's bending and steering angles are polar coordinates of its
// direction, and a constant-curvature segment is linear in the Cartesian
// components (output_frame.hpp), so two outputs that are such angles are
// fitted in the tip frame. Recognised from the column names and checked on
// the data: a bending angle is a polar radius and so is never negative.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Dense>

#include "plsa/model/output_frame.hpp"

namespace plsa::identify {

struct OutputFrameChoice {
  OutputFrame frame = OutputFrame::kAsLogged;
  /// One sentence for the progress lines: what was chosen and why, and the
  /// option that says otherwise.
  std::string reason;
};

/// The frame for `outputs` logged as `Y` (one matrix per log, a column per
/// output): tip_cartesian when there are two outputs, the first named as a
/// bending angle (containing "bend", "theta" or "inclin") and the second as a
/// steering angle ("steer", "azimuth" or "phi"), and no more than 1% of the
/// bending samples lie below -0.5 deg; as_logged otherwise. Case-insensitive.
OutputFrameChoice chooseOutputFrame(const std::vector<std::string>& outputs, const std::vector<Eigen::MatrixXd>& Y);

}  // namespace plsa::identify
