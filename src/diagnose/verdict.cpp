#include "verdict.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "plsa/diagnose/calibration.hpp"

namespace plsa::diagnose {
namespace {

// The gap left is over qualified_noise_multiple noise floors. (The
// identified reference is reported beside it, not used to decide: on short
// random excitations its free simulation can be far worse than the
// calibrated simulator, and it would then hide a real shortfall.)
bool farAboveWhatTheDataAllow(const Diagnosis& d, const Gap& left, const DiagnoseOptions& o) {
  return left.percent() > o.qualified_noise_multiple * d.noise.percent();
}

// The verdict when nothing was kept: no candidate to try (every effect on),
// or the best one's gap against re-calibrating with nothing added, which is
// the bar a candidate must clear by the margin.
std::string nothingKeptVerdict(const Diagnosis& d, const DiagnoseOptions& o) {
  char v[640];
  if (d.ranking.empty()) {
    std::snprintf(v, sizeof v,
                  "No candidate effect to try: every effect the simulator has is already on. The calibrated "
                  "simulator's held-out gap is %.1f%% against a noise floor of %.1f%%.",
                  d.gap_before.percent(), d.noise.percent());
    return v;
  }
  const CandidateResult& best = d.ranking[0];
  std::snprintf(v, sizeof v,
                "No candidate effect explains the held-out gap beyond noise: the calibrated simulator's gap is "
                "%.1f%% against a noise floor of %.1f%%. The best candidate, %s, takes it to %.1f%%, and the "
                "simulator without it, re-calibrated with the same budget (or as it was, if that is better), to "
                "%.1f%%; a candidate counts only if it beats that by more than %g times the noise floor and "
                "%.0f%% of that gap (mean squares).",
                d.gap_before.percent(), d.noise.percent(), best.effect.c_str(), best.heldout_after.percent(),
                d.recalibrated_round1.percent(), o.margin, 100.0 * o.min_relative);
  return v;
}

}  // namespace

std::string pct(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.1f%%", v);
  return b;
}

bool clearsMargin(double change, const Gap& reference, const Gap& noise, const DiagnoseOptions& o) {
  return change > o.margin * noise.total && change > o.min_relative * reference.total;
}

void judgeConfidence(Diagnosis& d, const Gap& bar, const DiagnoseOptions& o) {
  if (d.selected.empty() || d.ranking.empty()) return;
  const double best = d.ranking[0].heldout_after.total;
  const double drop = std::max(1e-12, bar.total - best);
  d.margin_over_recalibration = drop / std::max(1e-12, bar.total);
  d.margin_over_runner_up = 1.0;
  if (d.ranking.size() > 1) {
    d.runner_up = d.ranking[1].effect;
    d.margin_over_runner_up = std::clamp((d.ranking[1].heldout_after.total - best) / drop, 0.0, 1.0);
  }
  if (d.margin_over_runner_up < o.uncertain_margin)
    d.confidence = "uncertain";
  else if (farAboveWhatTheDataAllow(d, d.gap_after, o))
    d.confidence = "qualified";
  else
    d.confidence = "confident";
}

std::string verdictOf(const Diagnosis& d, const DiagnoseOptions& o) {
  std::string verdict;
  if (d.selected.empty()) {
    verdict = nothingKeptVerdict(d, o);
  } else {
    std::string list;
    for (const auto& s : d.selected) list += (list.empty() ? "" : ", then ") + s;
    char v[512];
    std::snprintf(v, sizeof v,
                  "The gap is explained by %s: adding %s shrinks the held-out gap from %.1f%% to %.1f%% "
                  "(noise floor %.1f%%",
                  d.selected[0].c_str(), list.c_str(), d.gap_before.percent(), d.gap_after.percent(),
                  d.noise.percent());
    const double closed = shrinkAboveNoise(d.gap_before, d.gap_after, d.noise);
    verdict = v + (std::isfinite(closed) ? ", " + pct(closed) + " of the gap above it closed)." : std::string(")."));
  }
  if (d.confidence == "uncertain")
    verdict += " Uncertain: " + d.runner_up + " comes within " + pct(100 * d.margin_over_runner_up) + " of " +
               d.selected[0] + "'s gain over re-calibrating without either; the data do not separate the two.";
  const std::string reached = d.reference.available && d.reference.gap.percent() < d.gap_after.percent()
                                  ? " and above the " + pct(d.reference.gap.percent()) + " an identified model reaches"
                                  : "";
  const std::string times = std::to_string(static_cast<int>(o.qualified_noise_multiple)) + " times the noise floor";
  if (d.confidence == "qualified")
    verdict += " Qualified: the gap left, " + pct(d.gap_after.percent()) + ", is over " + times + reached +
               ": part of the gap is something no candidate models.";
  if (d.selected.empty() && farAboveWhatTheDataAllow(d, d.gap_before, o))
    verdict += " But the gap, " + pct(d.gap_before.percent()) + ", is over " + times + reached +
               ": the simulator misses something no candidate models.";
  return verdict;
}

// Outputs in radians, or commands not in bar, give gaps of thousands of
// percent that no calibration or candidate can close: the RMS of the
// simulated bending vector against the measured one says so first.
std::string implausibleScaleNote(const sim::SimConfig& simulator, const std::vector<RunData>& train, OutputMap map) {
  if (map != OutputMap::kAngles) return "";  // an affine map takes any scale
  double measured = 0.0, simulated = 0.0;
  for (const auto& run : train) {
    measured += run.outputs.squaredNorm();
    simulated += simulateRun(simulator, run, map).outputs.squaredNorm();
  }
  const double ratio = std::sqrt(simulated / measured);
  if (!std::isfinite(ratio) || (ratio < 10.0 && ratio > 0.1)) return "";
  char line[320];
  if (ratio == 0.0)
    std::snprintf(line, sizeof line,
                  "the simulator as given does not bend for the training runs' commands: are the commands in "
                  "bar (--input-scale)?");
  else
    std::snprintf(line, sizeof line,
                  "the simulator as given bends %.3g times as far as the measured outputs (RMS of the bending "
                  "vector, training runs): are the outputs in degrees and the commands in bar (--input-scale)?",
                  ratio);
  return line;
}

// Each run is simulated at its own rate, but their noise floors and the
// identified reference differ.
std::string mixedSampleRatesNote(const std::vector<RunData>& runs) {
  const auto [lo, hi] = std::minmax_element(
      runs.begin(), runs.end(), [](const RunData& a, const RunData& b) { return a.sample_time_s < b.sample_time_s; });
  if (hi->sample_time_s <= 1.01 * lo->sample_time_s) return "";
  char line[320];
  std::snprintf(line, sizeof line,
                "the runs were sampled at different rates (%s at %.4g Hz, %s at %.4g Hz): each is simulated at "
                "its own rate",
                lo->name.c_str(), 1.0 / lo->sample_time_s, hi->name.c_str(), 1.0 / hi->sample_time_s);
  return line;
}

namespace {

// "<what> raised its held-out gap from <from> to <to><after>", when the rise
// clears a candidate's margin; else empty.
std::string raisedGapNote(const std::string& what, const Gap& from, const Gap& to, const std::string& after,
                          const Gap& noise, const DiagnoseOptions& o) {
  if (!clearsMargin(to.total - from.total, from, noise, o)) return "";
  char gaps[96];
  std::snprintf(gaps, sizeof gaps, " raised its held-out gap from %.1f%% to %.1f%%", from.percent(), to.percent());
  return what + gaps + after;
}

}  // namespace

// After such a polish the later rounds start from a baseline that
// generalises worse than the one chosen, and a candidate can win them by
// undoing it.
std::string polishNote(const Diagnosis::KeptStep& k, const Gap& noise, const DiagnoseOptions& o) {
  return raisedGapNote("polishing " + k.effect + "'s calibration on the training runs", k.heldout_chosen, k.heldout,
                       ": later rounds start from a baseline that generalises worse than the one chosen", noise, o);
}

// Chosen on the training runs, as the polish is: the held-out gap may rise.
std::string finalRecalibrationNote(const Diagnosis::KeptStep& k, const Gap& noise, const DiagnoseOptions& o) {
  return raisedGapNote("re-calibrating the kept model when the selection stopped (it lowered the training gap)",
                       k.heldout, k.heldout_final, "", noise, o);
}

}  // namespace plsa::diagnose
