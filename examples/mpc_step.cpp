// One model-predictive controller on the simulated actuator: every 12.5 ms
// it predicts the next second of bending for a planned set of chamber
// pressures, takes the sensitivity of that prediction to the plan
// (Predictor::sensitivity), improves the plan by a few projected-gradient
// steps within the pressure limits, and applies the plan's first pressures.
//   mpc_step [model.json]   (default: a model identified here on the simulator's grid run)
#include <algorithm>
#include <cstdio>
#include <string>

#include "plsa/identify/pipeline.hpp"
#include "plsa/model/model_file.hpp"
#include "plsa/predict/predictor.hpp"
#include "plsa/sim/experiment.hpp"

namespace {

constexpr int kHorizon = 80;  // 1 s at 80 Hz
constexpr double kMinBar = 0.0, kMaxBar = 0.35;
constexpr double kSmoothness = 200.0;  // weight on the plan's steps (deg^2 per bar^2)

// Bending error over the horizon plus the plan's roughness.
double cost(const Eigen::MatrixXd& predicted, double target, const Eigen::MatrixXd& plan,
            const Eigen::RowVectorXd& now) {
  double c = (predicted.col(0).array() - target).square().sum();
  Eigen::RowVectorXd before = now;
  for (Eigen::Index s = 0; s < plan.rows(); ++s) {
    c += kSmoothness * (plan.row(s) - before).squaredNorm();
    before = plan.row(s);
  }
  return c;
}

}  // namespace

int main(int argc, char** argv) {
  plsa::DioPwlObfModel model;
  if (argc > 1) {
    model = plsa::loadModel(argv[1]);
  } else {
    std::printf("identifying a model on the simulator's grid run...\n");
    plsa::sim::Actuator rig(plsa::sim::SimConfig{}, 1);
    plsa::identify::IdentifyOptions o;
    o.output_frame = plsa::OutputFrame::kTipCartesian;
    o.scheduling = plsa::identify::SchedulingChoice::kInputSide;
    model = plsa::identify::identifyModel({plsa::sim::runExperiment(rig, plsa::sim::gridExperiment({}))}, o);
  }
  plsa::Predictor<> predictor(model);
  const int nu = model.inputCount();
  plsa::sim::Actuator arm(plsa::sim::SimConfig{}, 7);
  Eigen::VectorXd u = Eigen::VectorXd::Constant(nu, 0.2);
  if (nu > 2) u(2) = 0.0;  // the third chamber as the model was trained: vented
  // Settle at the starting pressures, feeding the predictor.
  plsa::sim::ActuatorSample state{};
  for (int k = 0; k < 400; ++k) {
    state = arm.step({u(0), nu > 1 ? u(1) : 0.0, nu > 2 ? u(2) : 0.0});
    predictor.update(state.time_s, u, Eigen::Vector2d(state.bend_deg, state.steer_deg));
  }
  const double target = state.bend_deg + 2.0;  // bend two degrees further
  std::printf("start: bend %.2f deg, target %.2f deg\n", state.bend_deg, target);
  Eigen::MatrixXd plan = u.transpose().replicate(kHorizon - 1, 1), trial(kHorizon - 1, nu);
  Eigen::MatrixXd predicted(kHorizon, 2);
  // Zeroed once: each tick writes only the rows a plan step moves (the rest stays zero).
  Eigen::MatrixXd jacobian = Eigen::MatrixXd::Zero(kHorizon * 2, (kHorizon - 1) * nu);
  for (int tick = 0; tick < 160; ++tick) {
    // A few projected-gradient steps on the plan, warm-started from the last one.
    double now = 0.0;
    for (int iteration = 0; iteration < 5; ++iteration) {
      // The Jacobian and the prediction it is taken at, from one planned prediction.
      if (predictor.sensitivity(kHorizon, plan, jacobian, plsa::JacobianFill::kMovingRows, predicted) !=
          plsa::PredictorStatus::kOk)
        return 1;
      now = cost(predicted, target, plan, u.transpose());
      Eigen::MatrixXd gradient = Eigen::MatrixXd::Zero(kHorizon - 1, nu);
      for (int h = 0; h < kHorizon; ++h)
        for (Eigen::Index s = 0; s + 1 < kHorizon; ++s)
          for (int j = 0; j < nu; ++j) gradient(s, j) += 2.0 * (predicted(h, 0) - target) * jacobian(2 * h, s * nu + j);
      Eigen::RowVectorXd before = u.transpose();
      for (Eigen::Index s = 0; s < plan.rows(); ++s) {
        gradient.row(s) += 2.0 * kSmoothness * (plan.row(s) - before);
        if (s + 1 < plan.rows()) gradient.row(s) -= 2.0 * kSmoothness * (plan.row(s + 1) - plan.row(s));
        before = plan.row(s);
      }
      // Backtracking on the true (scheduled) prediction, within the limits.
      for (double step = 1e-4; step > 1e-9; step *= 0.5) {
        trial = (plan - step * gradient).cwiseMax(kMinBar).cwiseMin(kMaxBar);
        if (nu > 2) trial.col(2).setZero();
        predictor.predict(kHorizon, trial, predicted);
        const double c = cost(predicted, target, trial, u.transpose());
        if (c < now) {
          plan = trial;
          now = c;
          break;
        }
      }
    }
    // Apply the first planned pressures; shift the plan for the next tick.
    u = plan.row(0).transpose();
    plan.topRows(kHorizon - 2) = plan.bottomRows(kHorizon - 2).eval();
    state = arm.step({u(0), nu > 1 ? u(1) : 0.0, nu > 2 ? u(2) : 0.0});
    predictor.update(state.time_s, u, Eigen::Vector2d(state.bend_deg, state.steer_deg));
    if (tick % 20 == 0 || tick == 159)
      std::printf("t %5.3f s  pressures %.3f %.3f bar  bend %6.2f deg (target %.2f)  cost %.3g\n", tick * 0.0125, u(0),
                  nu > 1 ? u(1) : 0.0, state.bend_deg, target, now);
  }
  return 0;
}
