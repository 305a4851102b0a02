// Checks on the runs a diagnosis is given, made before any work: each
// refusal names the runs and says what to check.
#pragma once

#include <vector>

#include "plsa/diagnose/run_data.hpp"

namespace plsa::diagnose {

/// The least data a diagnosis reads (seconds, summed over the runs on each
/// side of the split): a bending mode of about 1 Hz must settle and a noise
/// floor be estimated.
inline constexpr double kMinTrainingSeconds = 5.0;
inline constexpr double kMinHeldOutSeconds = 2.0;

/// Throws std::invalid_argument for no runs, or the same run twice (under
/// any names): it would be held out and trained on, a held-out gap that
/// holds nothing out.
void refuseRepeatedRuns(const std::vector<RunData>& runs);

/// Throws std::invalid_argument, naming the runs, for training that drives
/// nothing (commands that never change on runs replayed settled, all at one
/// level: every calibration would leave the simulator in one state; a step
/// from rest or runs at different levels do drive it) and for less data
/// than kMinTrainingSeconds / kMinHeldOutSeconds; and for measured
/// pressures that hold one value in every training sample while the
/// commands drive (a sensor not logging: the fill law and the identified
/// reference would read it).
void refuseUnusableSplit(const std::vector<RunData>& train, const std::vector<RunData>& held);

}  // namespace plsa::diagnose
