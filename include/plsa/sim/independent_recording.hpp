// A run of the independent actuator recorded as a user records one: from a
// vented actuator at rest, the commands, the chambers' pressures and the tip
// sensor's bend and steering angles, as a plsa log.
#pragma once

#include <array>
#include <cstdint>

#include <Eigen/Dense>

#include "plsa/io/csv_log.hpp"
#include "plsa/sim/experiment.hpp"
#include "plsa/sim/independent_actuator.hpp"

namespace plsa::sim {

/// A bending vector read as bend and steering angles, as a tip sensor's
/// software reports them: steering unwrapped (continuous), and held at its
/// last value while the tip is within `straight_deg` of straight, where its
/// direction is noise (from 0).
class TipAngles {
 public:
  explicit TipAngles(double straight_deg = 1.0) : straight_deg_(straight_deg) {}
  /// {bend, steer} in degrees.
  std::array<double, 2> operator()(const Eigen::Vector2d& bending_deg);

 private:
  double straight_deg_;
  double steer_deg_ = 0.0;
};

/// The experiment's whole command trajectory, pre-roll included, run on a
/// new IndependentActuator(physics, seed) and logged with
/// io::standard_columns::recorded(), its bending as TipAngles. With
/// `noise_free`, also the same angles read without the sensor's white
/// noise (a row per sample: bend, steer): the most any model can predict.
io::Log recordIndependentFromRest(const IndependentPhysics& physics, const Experiment& e, std::uint64_t seed,
                                  Eigen::MatrixXd* noise_free = nullptr);

}  // namespace plsa::sim
