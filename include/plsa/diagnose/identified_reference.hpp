// What a data-driven model reaches on the diagnosis's own split: a DIO-PWL
// OBF model identified on the training runs and simulated freely on the
// held-out ones, scored with the gap's output measure. A calibrated
// simulator that ends far above this and above the noise floor misses
// something no candidate effect models, and the verdict says so.
#pragma once

#include <string>
#include <vector>

#include "plsa/diagnose/calibration.hpp"
#include "plsa/diagnose/run_data.hpp"

namespace plsa::diagnose {

struct IdentifiedReference {
  bool available = false;
  Gap gap;           ///< outputs only (the model predicts no pressures); percent() as for any gap
  std::string note;  ///< why it is unavailable, or what it was identified on
};

/// Identifies on `train` (measured pressures as inputs when every run has
/// them, else the commands; outputs as the runs hold them, fitted as given)
/// and simulates each of `held` from its inputs. Never throws for data the
/// identification cannot use: `available` is false and `note` says why.
IdentifiedReference identifiedReference(const std::vector<RunData>& train, const std::vector<RunData>& held);

}  // namespace plsa::diagnose
