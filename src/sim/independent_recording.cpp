#include "plsa/sim/independent_recording.hpp"

#include <cmath>

#include "plsa/core/angle_units.hpp"
#include "plsa/io/standard_columns.hpp"

namespace plsa::sim {

std::array<double, 2> TipAngles::operator()(const Eigen::Vector2d& bending_deg) {
  if (bending_deg.norm() > straight_deg_) {
    const double turn = std::remainder(std::atan2(bending_deg.y(), bending_deg.x()) - steer_deg_ * kRadPerDeg, 2 * kPi);
    steer_deg_ += turn / kRadPerDeg;
  }
  return {bending_deg.norm(), steer_deg_};
}

io::Log recordIndependentFromRest(const IndependentPhysics& physics, const Experiment& e, std::uint64_t seed,
                                  Eigen::MatrixXd* noise_free) {
  IndependentActuator a(physics, seed);
  io::Log log;
  log.source = "independent actuator, " + e.name + " from rest";
  log.columns = io::standard_columns::recorded();
  log.data.resize(e.commands.rows(), static_cast<Eigen::Index>(log.columns.size()));
  if (noise_free) noise_free->resize(e.commands.rows(), 2);
  TipAngles read, read_noise_free;
  for (Eigen::Index k = 0; k < e.commands.rows(); ++k) {
    const IndependentSample s = a.step({e.commands(k, 0), e.commands(k, 1), e.commands(k, 2)});
    const auto [bend, steer] = read(s.bending_deg);
    log.data.row(k) << static_cast<double>(k) / physics.sample_rate_hz, e.commands(k, 0), e.commands(k, 1),
        e.commands(k, 2), s.pressure_bar[0], s.pressure_bar[1], s.pressure_bar[2], bend, steer;
    if (noise_free) {
      const auto [b, st] = read_noise_free(s.bending_noise_free_deg);
      noise_free->row(k) << b, st;
    }
  }
  return log;
}

}  // namespace plsa::sim
