// What a diagnosis says in words (src/diagnose only, not installed): the
// margin a change of the held-out gap must clear, the verdict and its
// confidence, and notes on input or a search that look wrong.
#pragma once

#include <string>
#include <vector>

#include "plsa/diagnose/diagnosis.hpp"

namespace plsa::diagnose {

/// A gap in percent, one decimal ("8.3%").
std::string pct(double v);

/// Whether a change of the held-out gap (mean squares) counts: over
/// `margin` noise floors and over `min_relative` of `reference` (the gap it
/// is measured from).
bool clearsMargin(double change, const Gap& reference, const Gap& noise, const DiagnoseOptions& o);

/// Round 1's confidence (Diagnosis::confidence and its margins) against the
/// re-calibration bar.
void judgeConfidence(Diagnosis& d, const Gap& bar, const DiagnoseOptions& o);

/// The verdict in words, with its confidence's qualification.
std::string verdictOf(const Diagnosis& d, const DiagnoseOptions& o);

/// Notes, each empty when there is nothing to say: the simulator as given
/// bending ten times as far as the measured angles or a tenth as far
/// (training runs; angles only, an affine map takes any scale); runs at
/// different sample rates; a kept effect whose polish, or the kept model's
/// re-calibration when the selection stopped, raised its held-out gap by
/// more than the margin.
std::string implausibleScaleNote(const sim::SimConfig& simulator, const std::vector<RunData>& train, OutputMap map);
std::string mixedSampleRatesNote(const std::vector<RunData>& runs);
std::string polishNote(const Diagnosis::KeptStep& k, const Gap& noise, const DiagnoseOptions& o);
std::string finalRecalibrationNote(const Diagnosis::KeptStep& k, const Gap& noise, const DiagnoseOptions& o);

}  // namespace plsa::diagnose
