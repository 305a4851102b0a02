// A model swapped under a running loop: the control thread updates and
// predicts every tick while another thread installs a re-identified model;
// the control thread adopts it whole at its next update, without a lock or a
// pause, and its predictions stay finite throughout.
//   hot_swap model.json [new-model.json]   (default: the same file again, as a re-identification would write)
#include <atomic>
#include <chrono>
#include <cstdio>
#include <thread>

#include "plsa/model/model_file.hpp"
#include "plsa/predict/predictor.hpp"
#include "plsa/sim/experiment.hpp"

int main(int argc, char** argv) {
  if (argc < 2 || argc > 3) {
    std::fprintf(stderr, "usage: hot_swap model.json [new-model.json]\n");
    return 2;
  }
  plsa::Predictor<> predictor(plsa::loadModel(argv[1]));
  const plsa::DioPwlObfModel next = plsa::loadModel(argc > 2 ? argv[2] : argv[1]);
  plsa::sim::Actuator arm(plsa::sim::SimConfig{}, 4);
  plsa::sim::ExperimentOptions o;
  o.seed = 4;
  o.joystick_duration_s = 20.0;
  const plsa::sim::Experiment plan = plsa::sim::joystickExperiment(o);

  std::atomic<bool> swap_now{false}, swapped{false};
  std::thread installer([&] {  // e.g. the thread that re-identifies in the background
    while (!swap_now.load()) std::this_thread::yield();
    predictor.install(next);  // compiles here, off the real-time thread
    swapped.store(true);
  });
  Eigen::MatrixXd predicted(80, predictor.outputCount());
  const Eigen::MatrixXd hold(0, 3);  // no plan: the input held
  const std::uint64_t first_id = predictor.modelId();
  long ticks_before = 0, ticks_after = 0, bad = 0;
  for (Eigen::Index t = 0; t < plan.commands.rows(); ++t) {
    const plsa::sim::ActuatorSample s = arm.step({plan.commands(t, 0), plan.commands(t, 1), plan.commands(t, 2)});
    const Eigen::Vector3d p(s.pressure_bar[0], s.pressure_bar[1], s.pressure_bar[2]);
    if (static_cast<int>(predictor.update(s.time_s, p, Eigen::Vector2d(s.bend_deg, s.steer_deg))) < 0) ++bad;
    if (predictor.predict(80, hold, predicted) != plsa::PredictorStatus::kOk || !predicted.allFinite()) ++bad;
    (predictor.modelId() == first_id ? ticks_before : ticks_after) += 1;
    if (t == plan.commands.rows() / 2) swap_now.store(true);
    // This loop runs faster than the 80 Hz it stands for; while the install is
    // under way it keeps the real period, so the swap lands mid-run.
    if (swap_now.load() && !swapped.load()) std::this_thread::sleep_for(std::chrono::microseconds(12500));
  }
  installer.join();
  predictor.collectRetired();  // frees the old model: once the loop is done, or from any non-real-time thread
  std::printf("model %llu for %ld ticks, then model %llu for %ld ticks; %ld failed calls\n",
              static_cast<unsigned long long>(first_id), ticks_before,
              static_cast<unsigned long long>(predictor.modelId()), ticks_after, bad);
  return swapped.load() && ticks_after > 0 && bad == 0 ? 0 : 1;
}
