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

/// A steering angle (deg) with its direction's cosine and sine: the last
/// measured one, taken once per sample, from which every prediction's rows turn.
struct SteeringReference {
  double deg = 0.0, cos = 1.0, sin = 0.0;
  static SteeringReference of(double steer_deg) noexcept {
    return {steer_deg, std::cos(steer_deg * kRadPerDeg), std::sin(steer_deg * kRadPerDeg)};
  }
};

/// Rows [0, horizon) of out: the components (x, y) one by one, from the
/// steering angle `reference` of the row before them. Row by row by
/// atan2: a large turn, or a straight tip (no direction: it keeps the
/// steering it had).
inline void tipAnglesRowByRow(int horizon, const SteeringReference& reference,
                              Eigen::Ref<Eigen::MatrixXd> out) noexcept {
  PLSA_DEBUG_ASSERT(out.cols() == 2 && out.rows() >= horizon);
  double steer = reference.deg;
  double px = reference.cos, py = reference.sin;
  for (int h = 0; h < horizon; ++h) {
    const double x = out(h, 0), y = out(h, 1);
    if (x != 0.0 || y != 0.0) {
      steer += std::atan2(px * y - py * x, px * x + py * y) / kRadPerDeg;
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
  constexpr double kDegPerRad = 180.0 / kPi;  // a product per row, not a division
  double steer = reference.deg;
  for (int h = 0; h < horizon; ++h) {
    steer += turn[h] * kDegPerRad;
    out(h, 0) = bend[h];
    out(h, 1) = steer;
  }
}

}  // namespace plsa
