// Checks on the runs a diagnosis is given, before any work (run_checks.hpp).
#include "plsa/diagnose/run_checks.hpp"

#include <algorithm>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "plsa/identify/pipeline.hpp"

namespace plsa::diagnose {
namespace {

// Seconds of data in `runs`.
double secondsOf(const std::vector<RunData>& runs) {
  double s = 0.0;
  for (const auto& r : runs) s += static_cast<double>(r.samples()) * r.sample_time_s;
  return s;
}

std::string namesOf(const std::vector<RunData>& runs) {
  std::string names;
  for (const auto& r : runs) names += (names.empty() ? "'" : ", '") + r.name + "'";
  return names;
}

// Whether the training commands drive the simulator through anything that
// depends on its physics: a command that changes within a run, a run
// replayed from rest under a pressure (a step from vent: the step response
// calibrates the chambers and the bending mode), or runs held at different
// levels. Commands that never change on runs replayed settled leave the
// simulator in one state: every calibration ties, and a gap would be blamed
// on the simulator that belongs to a wrong column.
bool drivenTraining(const std::vector<RunData>& train) {
  for (const auto& r : train) {
    if (r.samples() == 0) continue;
    for (Eigen::Index j = 0; j < r.commands.cols(); ++j)
      if (r.commands.col(j).maxCoeff() - r.commands.col(j).minCoeff() > 1e-6) return true;
    if (r.start == RunStart::kAtRest && r.commands.row(0).maxCoeff() > 1e-6) return true;
    if ((r.commands.row(0) - train[0].commands.row(0)).cwiseAbs().maxCoeff() > 1e-6) return true;
  }
  return false;
}

// Whether every pressure column holds one value in every sample of every run.
bool pressuresHeldThroughout(const std::vector<RunData>& runs) {
  std::vector<Eigen::MatrixXd> pressures;
  for (const auto& r : runs) pressures.push_back(r.pressures);
  for (Eigen::Index j = 0; j < 3; ++j)
    if (!identify::holdsOneValue(pressures, j)) return false;
  return true;
}

}  // namespace

void refuseRepeatedRuns(const std::vector<RunData>& runs) {
  if (runs.empty()) throw std::invalid_argument("diagnose: no real runs given");
  for (std::size_t i = 0; i < runs.size(); ++i)
    for (std::size_t j = i + 1; j < runs.size(); ++j)
      if (runs[i].samples() == runs[j].samples() && runs[i].commands == runs[j].commands &&
          runs[i].outputs == runs[j].outputs)
        throw std::invalid_argument("diagnose: runs '" + runs[i].name + "' and '" + runs[j].name +
                                    "' hold the same samples; each run may appear once");
}

void refuseUnusableSplit(const std::vector<RunData>& train, const std::vector<RunData>& held) {
  if (!drivenTraining(train))
    throw std::invalid_argument("diagnose: the chamber commands of the training run(s) " + namesOf(train) +
                                " never change and start settled: nothing drives the simulator, so its physics "
                                "cannot be calibrated (check --inputs)");
  if (std::all_of(train.begin(), train.end(), [](const RunData& r) { return r.hasPressures(); }) &&
      pressuresHeldThroughout(train))
    throw std::invalid_argument(
        "diagnose: the measured pressures of the training run(s) " + namesOf(train) +
        " hold one value each in every sample while the commands drive the chambers: a sensor that "
        "was not logging? (check --pressures; --pressures none diagnoses without them)");
  const double train_s = secondsOf(train), held_s = secondsOf(held);
  if (train_s < kMinTrainingSeconds || held_s < kMinHeldOutSeconds) {
    char line[160];
    std::snprintf(line, sizeof line, "diagnose: %.1f s of training and %.1f s of held-out data (", train_s, held_s);
    char need[200];
    std::snprintf(need, sizeof need,
                  "); a diagnosis needs at least %.0f s and %.0f s (record longer runs, give several, or, for one "
                  "run, change --heldout-fraction)",
                  kMinTrainingSeconds, kMinHeldOutSeconds);
    throw std::invalid_argument(line + namesOf(train) + " / " + namesOf(held) + need);
  }
}

}  // namespace plsa::diagnose
