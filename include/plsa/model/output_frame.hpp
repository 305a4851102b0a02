// The frame a model's outputs live in. A tip's bending and steering angles
// (the paper's eqs. (5) and (6)) are polar coordinates of its direction; a
// constant-curvature segment's dynamics are linear in the Cartesian
// components, and steering is undefined at zero bend, so such a model may run
// on (bend cos steer, bend sin steer) and answer in the logged angles.
#pragma once

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "plsa/core/angle_units.hpp"
#include "plsa/core/check.hpp"

namespace plsa {

enum class OutputFrame {
  kAsLogged,     ///< the model's outputs are the logged columns
  kTipCartesian  ///< logged: bending angle, steering angle (deg or rad); model: bend cos(steer), bend sin(steer)
};

inline const char* toString(OutputFrame f) { return f == OutputFrame::kAsLogged ? "as_logged" : "tip_cartesian"; }

/// Throws naming the accepted spellings.
inline OutputFrame outputFrameFromString(const std::string& s) {
  if (s == "as_logged") return OutputFrame::kAsLogged;
  if (s == "tip_cartesian") return OutputFrame::kTipCartesian;
  throw std::invalid_argument("output frame '" + s + "': expected as_logged or tip_cartesian");
}

/// Radians per unit of a tip_cartesian model's logged angles, from the
/// model's output unit: "deg" or "rad". Throws naming the unit otherwise.
inline double radiansPerAngleUnit(const std::string& unit) {
  if (unit == "deg") return kRadPerDeg;
  if (unit == "rad") return 1.0;
  throw std::invalid_argument("output unit '" + unit + "': a tip's bending and steering angles are in deg or rad");
}

/// Its inverse: 180 / pi (exactly the product the degree's rows take) or 1.
inline double angleUnitsPerRadian(const std::string& unit) {
  return radiansPerAngleUnit(unit) == 1.0 ? 1.0 : 180.0 / kPi;
}

/// Bending and steering angles to the tip direction's components (in the
/// bending angle's unit); `rad_per_unit`: radiansPerAngleUnit.
inline void tipComponents(double bend, double steer, double rad_per_unit, double& x, double& y) noexcept {
  x = bend * std::cos(steer * rad_per_unit);
  y = bend * std::sin(steer * rad_per_unit);
}

/// Back to bending and steering; the steering angle is taken on the branch
/// nearest `steer_reference`, so a prediction follows the measured angle
/// across half a turn (+-180 deg, +-pi rad) instead of jumping by a turn.
inline void tipAngles(double x, double y, double steer_reference, double rad_per_unit, double& bend,
                      double& steer) noexcept {
  const double turn = rad_per_unit == kRadPerDeg ? 360.0 : 2.0 * kPi / rad_per_unit;
  bend = std::hypot(x, y);
  const double a = std::atan2(y, x) / rad_per_unit;
  steer = a + turn * std::round((steer_reference - a) / turn);
}

/// A record (T x n_y) in the model's frame; `rad_per_unit` as tipComponents.
inline Eigen::MatrixXd toModelFrame(OutputFrame frame, const Eigen::MatrixXd& y, double rad_per_unit) {
  if (frame == OutputFrame::kAsLogged) return y;
  PLSA_CHECK(y.cols() == 2, "tip_cartesian output frame: needs exactly two outputs (bending, steering), got " +
                                std::to_string(y.cols()));
  Eigen::MatrixXd m(y.rows(), 2);
  for (Eigen::Index k = 0; k < y.rows(); ++k) tipComponents(y(k, 0), y(k, 1), rad_per_unit, m(k, 0), m(k, 1));
  return m;
}

inline std::vector<Eigen::MatrixXd> toModelFrame(OutputFrame frame, const std::vector<Eigen::MatrixXd>& records,
                                                 double rad_per_unit) {
  std::vector<Eigen::MatrixXd> out;
  out.reserve(records.size());
  for (const Eigen::MatrixXd& y : records) out.push_back(toModelFrame(frame, y, rad_per_unit));
  return out;
}

}  // namespace plsa
