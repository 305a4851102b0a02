// Identification as a program does it: record a grid run and a joystick run
// on the simulated actuator, identify a model on the first, validate it on
// the second, and write the model file.
//   identify_model [model.json]   (default: model.json here)
#include <cstdio>
#include <string>

#include "plsa/eval/validation.hpp"
#include "plsa/identify/pipeline.hpp"
#include "plsa/model/model_file.hpp"
#include "plsa/sim/experiment.hpp"

int main(int argc, char** argv) {
  const std::string out = argc > 1 ? argv[1] : "model.json";
  plsa::sim::Actuator rig(plsa::sim::SimConfig{}, 1);
  const plsa::io::Log train = plsa::sim::runExperiment(rig, plsa::sim::gridExperiment({}));
  plsa::sim::Actuator again(plsa::sim::SimConfig{}, 2);
  plsa::sim::ExperimentOptions joystick;
  joystick.seed = 2;
  joystick.joystick_duration_s = 40.0;
  const plsa::io::Log run = plsa::sim::runExperiment(again, plsa::sim::joystickExperiment(joystick));

  plsa::identify::IdentifyOptions o;  // the tool's defaults; progress lines to standard error
  o.progress = [](const std::string& line) { std::fprintf(stderr, "%s\n", line.c_str()); };
  const plsa::DioPwlObfModel model = plsa::identify::identifyModel({train}, o);

  const plsa::eval::ValidationResult v = plsa::eval::validateModel(model, run, {40, 80});
  for (const plsa::eval::OutputValidation& ov : v.outputs)
    std::printf("%s: 40-step fit %.1f%%, 80-step fit %.1f%%, simulation %.1f%%\n", ov.name.c_str(), ov.fit_k.at(40),
                ov.fit_k.at(80), ov.fit_sim);
  plsa::saveModel(out, model);  // atomically: a reader never sees half a file
  std::printf("wrote %s (%zu regions)\n", out.c_str(), model.coefficients.size());
  return 0;
}
