// A tip_cartesian model's predictions back from the tip direction's
// components to bending and steering angles, in place and allocation-free:
// what the predictor does to every row it returns for such a model.
#pragma once

#include <cmath>

#include <Eigen/Dense>

#include "plsa/core/check.hpp"
#include "plsa/model/output_frame.hpp"
#include "plsa/predict/kernels.hpp"

namespace plsa {

/// A steering angle (in the model's angle unit) with its direction's cosine
/// and sine: the last measured one, taken once per sample, from which every
/// prediction's rows turn; `rad_per_unit` (radiansPerAngleUnit) and its
/// inverse, the unit's size.
struct SteeringReference {
  double angle = 0.0, cos = 1.0, sin = 0.0, rad_per_unit = kRadPerDeg, unit_per_rad = 180.0 / kPi;
  static SteeringReference of(double steer, double rad_per_unit, double unit_per_rad) noexcept {
    return {steer, std::cos(steer * rad_per_unit), std::sin(steer * rad_per_unit), rad_per_unit, unit_per_rad};
  }
};

/// Rows [0, horizon) of out: the components (x, y) one by one, from the
/// steering angle `reference` of the row before them. Row by row by
/// atan2: a large turn, or a straight tip (no direction: it keeps the
/// steering it had).
inline void tipAnglesRowByRow(int horizon, const SteeringReference& reference,
                              Eigen::Ref<Eigen::MatrixXd> out) noexcept {
  PLSA_DEBUG_ASSERT(out.cols() == 2 && out.rows() >= horizon);
  double steer = reference.angle;
  double px = reference.cos, py = reference.sin;
  for (int h = 0; h < horizon; ++h) {
    const double x = out(h, 0), y = out(h, 1);
    if (x != 0.0 || y != 0.0) {
      steer += std::atan2(px * y - py * x, px * x + py * y) / reference.rad_per_unit;
      px = x;
      py = y;
    }
    out(h, 0) = std::sqrt(x * x + y * y);
    out(h, 1) = steer;
  }
}

/// The same. Each steering angle is the one before it plus the turn between
/// the two directions (so on the branch nearest it, as tipAngles picks). The
/// turns are computed for all rows at once by the arctangent series where
/// they are small (every step of a smooth prediction), in `turn` and `bend`
/// (horizon each); otherwise the rows go through tipAnglesRowByRow.
inline void tipAnglesFromComponents(int horizon, const SteeringReference& reference, double* turn, double* bend,
                                    Eigen::Ref<Eigen::MatrixXd> out) noexcept {
  PLSA_DEBUG_ASSERT(out.cols() == 2 && out.rows() >= horizon && turn != nullptr && bend != nullptr);
  if (!tipTurns(out.col(0).data(), out.col(1).data(), horizon, reference.cos, reference.sin, turn, bend))
    return tipAnglesRowByRow(horizon, reference, out);
  const double unit_per_rad = reference.unit_per_rad;  // a product per row, not a division
  double steer = reference.angle;
  for (int h = 0; h < horizon; ++h) {
    steer += turn[h] * unit_per_rad;
    out(h, 0) = bend[h];
    out(h, 1) = steer;
  }
}

}  // namespace plsa
