// The predictor in a controller's loop: every 12.5 ms a new sample from the
// (simulated) actuator, then the next second predicted under the planned
// pressures, with buffers allocated once before the loop. At the end, how far
// the 80-step predictions landed from what the actuator then did.
//   predict_loop model.json
#include <cmath>
#include <cstdio>

#include "plsa/model/model_file.hpp"
#include "plsa/predict/predictor.hpp"
#include "plsa/sim/experiment.hpp"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: predict_loop model.json (identify_model writes one)\n");
    return 2;
  }
  constexpr int kHorizon = 80;                            // 1 s at 80 Hz
  plsa::Predictor<> predictor(plsa::loadModel(argv[1]));  // set-up: may throw
  plsa::sim::ExperimentOptions plan_options;
  plan_options.seed = 3;
  plan_options.joystick_duration_s = 30.0;
  const plsa::sim::Experiment plan = plsa::sim::joystickExperiment(plan_options);  // the controller's plan
  plsa::sim::Actuator arm(plsa::sim::SimConfig{}, 3);

  const Eigen::Index ticks = plan.commands.rows();
  Eigen::MatrixXd predicted(kHorizon, predictor.outputCount());
  Eigen::MatrixXd landed = Eigen::MatrixXd::Constant(ticks, predictor.outputCount(), NAN);  // predicted for t
  Eigen::MatrixXd measured(ticks, predictor.outputCount());
  int rejected = 0;
  for (Eigen::Index t = 0; t < ticks; ++t) {
    const Eigen::Vector3d u = plan.commands.row(t).transpose();
    const plsa::sim::ActuatorSample s = arm.step({u(0), u(1), u(2)});
    measured.row(t) << s.bend_deg, s.steer_deg;
    // Real-time part: no allocation, no lock, no throw. The model's inputs are
    // the measured chamber pressures; the plan's commands stand in for the
    // pressures the chambers will reach.
    const Eigen::Vector3d p(s.pressure_bar[0], s.pressure_bar[1], s.pressure_bar[2]);
    if (static_cast<int>(predictor.update(s.time_s, p, measured.row(t).transpose())) < 0) {  // negative: rejected
      ++rejected;
      continue;
    }
    if (t < plan.record_from || t + kHorizon >= ticks) continue;
    const auto next = plan.commands.middleRows(t + 1, kHorizon - 1);  // the inputs from the next sample on
    if (predictor.predict(kHorizon, next, predicted) == plsa::PredictorStatus::kOk)
      landed.row(t + kHorizon) = predicted.row(kHorizon - 1);
  }
  double sum = 0.0;
  int count = 0;
  for (Eigen::Index t = 0; t < ticks; ++t)
    if (std::isfinite(landed(t, 0))) {
      sum += (landed.row(t) - measured.row(t)).norm();
      ++count;
    }
  std::printf("%d predictions 80 steps ahead; mean distance to what followed %.3f deg; %d samples rejected\n", count,
              sum / count, rejected);
  return count > 0 && rejected == 0 ? 0 : 1;
}
