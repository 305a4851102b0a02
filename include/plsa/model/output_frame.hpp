// The frame a model's outputs live in. A tip's bending and steering angles
// (the paper's eqs. (5) and (6)) are polar coordinates of its direction; a
// constant-curvature segment's dynamics are linear in the Cartesian
// components, and steering is undefined at zero bend, so such a model may run
// on (bend cos steer, bend sin steer) and answer in the logged angles.
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "plsa/core/angle_units.hpp"
#include "plsa/core/check.hpp"

namespace plsa {

enum class OutputFrame {
  kAsLogged,     ///< the model's outputs are the logged columns
  kTipCartesian  ///< logged: bending angle, steering angle (deg); model: bend cos(steer), bend sin(steer)
};

inline const char* toString(OutputFrame f) { return f == OutputFrame::kAsLogged ? "as_logged" : "tip_cartesian"; }

/// Throws naming the accepted spellings.
inline OutputFrame outputFrameFromString(const std::string& s) {
  if (s == "as_logged") return OutputFrame::kAsLogged;
  if (s == "tip_cartesian") return OutputFrame::kTipCartesian;
  throw std::invalid_argument("output frame '" + s + "': expected as_logged or tip_cartesian");
}

/// Bending and steering angles (deg) to the tip direction's components (deg).
inline void tipComponents(double bend_deg, double steer_deg, double& x, double& y) noexcept {
  x = bend_deg * std::cos(steer_deg * kRadPerDeg);
  y = bend_deg * std::sin(steer_deg * kRadPerDeg);
}

/// Back to bending and steering; the steering angle is taken on the branch
/// nearest `steer_reference_deg`, so a prediction follows the measured angle
/// across +-180 deg instead of jumping by a turn.
inline void tipAngles(double x, double y, double steer_reference_deg, double& bend_deg, double& steer_deg) noexcept {
  bend_deg = std::hypot(x, y);
  const double a = std::atan2(y, x) / kRadPerDeg;
  steer_deg = a + 360.0 * std::round((steer_reference_deg - a) / 360.0);
}

/// A record (T x n_y) in the model's frame.
inline Eigen::MatrixXd toModelFrame(OutputFrame frame, const Eigen::MatrixXd& y) {
  if (frame == OutputFrame::kAsLogged) return y;
  PLSA_CHECK(y.cols() == 2, "tip_cartesian output frame: needs exactly two outputs (bending, steering), got " +
                                std::to_string(y.cols()));
  Eigen::MatrixXd m(y.rows(), 2);
  for (Eigen::Index k = 0; k < y.rows(); ++k) tipComponents(y(k, 0), y(k, 1), m(k, 0), m(k, 1));
  return m;
}

inline std::vector<Eigen::MatrixXd> toModelFrame(OutputFrame frame, const std::vector<Eigen::MatrixXd>& records) {
  std::vector<Eigen::MatrixXd> out;
  out.reserve(records.size());
  for (const Eigen::MatrixXd& y : records) out.push_back(toModelFrame(frame, y));
  return out;
}

}  // namespace plsa
