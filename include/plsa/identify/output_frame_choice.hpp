// Which frame identification fits a model's outputs in when the user does not
// say: a tip's bending and steering angles are polar coordinates of its
// direction, and a constant-curvature segment is linear in the Cartesian
// components (output_frame.hpp), so two outputs that are such angles are
// fitted in the tip frame. Recognised from the column names and checked on
// the data: a bending angle is a polar radius and so is never negative.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "plsa/model/output_frame.hpp"

namespace plsa::identify {

struct OutputFrameChoice {
  OutputFrame frame = OutputFrame::kAsLogged;
  /// tip_cartesian: the unit of the logged angles, "deg" or "rad" (the model's output_unit).
  std::string angle_unit = "deg";
  std::string angle_unit_reason;  ///< why that unit, in a few words (chooseAngleUnit)
  /// One sentence for the progress lines: what was chosen and why, and the
  /// option that says otherwise.
  std::string reason;
};

/// The unit of a tip's bending and steering angles, `outputs` logged as `Y`
/// (their first two columns): `given` when set; else the one the names
/// spell ("deg" in either name, or "rad"); else "deg" when some value's
/// magnitude exceeds 2 pi (+ 0.05) and "rad" when none does, as a radian
/// angle's (within +-pi or [0, 2 pi)) cannot. `why` gets the reason in a few words. Throws when the
/// names spell both units.
std::string chooseAngleUnit(const std::vector<std::string>& outputs, const std::vector<Eigen::MatrixXd>& Y,
                            const std::optional<std::string>& given, std::string& why);

/// The frame for `outputs` logged as `Y` (one matrix per log, a column per
/// output): tip_cartesian when there are two outputs, the first named as a
/// bending angle (containing "bend", "theta" or "inclin") and the second as a
/// steering angle ("steer", "azimuth" or "phi"), and no more than 1% of the
/// bending samples lie below -0.5 deg (in the angles' unit, chooseAngleUnit
/// with `unit`); as_logged otherwise. Case-insensitive.
OutputFrameChoice chooseOutputFrame(const std::vector<std::string>& outputs, const std::vector<Eigen::MatrixXd>& Y,
                                    const std::optional<std::string>& unit = std::nullopt);

}  // namespace plsa::identify
