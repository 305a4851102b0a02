// Where the play channels count from, and how softly the level leaves it
// (IdentifyOptions::play_threshold_candidates, play_softening_candidates):
// each threshold with each softening and each growing play set, by the
// held-out k-step score.
#include <algorithm>
#include <cmath>

#include "identification_run.hpp"
#include "plsa/core/number_text.hpp"

namespace plsa::identify {
namespace {

/// The settings tried. A threshold moves where a growing band starts and how
/// much of a neighbour the coupling sees, so each one is tried with every
/// growing set as well as the chosen one; each softening (none unless asked
/// for) with each threshold, since both reshape the same level.
struct ThresholdGrid {
  std::vector<std::vector<PlayChannel>> sets;
  std::vector<double> thresholds{0.0}, softenings{0.0};  ///< fractions, as the options give them
};

ThresholdGrid thresholdGrid(const IdentificationRun& r) {
  const IdentifyOptions& o = r.o;
  ThresholdGrid g;
  g.sets.push_back(r.best_set);
  for (const auto& set : o.play_candidates)
    if (set != r.best_set && std::any_of(set.begin(), set.end(), [](const PlayChannel& c) { return c.slope > 0; }))
      g.sets.push_back(set);
  for (double d : o.play_threshold_candidates) {
    PLSA_CHECK(d >= 0 && d < 1, "identify: play thresholds must be fractions of the top input level in [0, 1)");
    if (d > 0) g.thresholds.push_back(d);
  }
  for (double f : o.play_softening_candidates) {
    PLSA_CHECK(f >= 0 && f < 0.5,
               "identify: play softenings must be fractions of the top input level above the threshold in [0, 0.5)");
    if (f > 0 && r.input_side_chosen) g.softenings.push_back(f);
  }
  return g;
}

/// The search's closing progress line.
std::string thresholdLine(const IdentificationRun& r, bool softened) {
  const InputShaping& s = r.model.shaping;
  const double above = r.top_level - s.threshold;
  std::string line = softened ? "[5/5] play channels counted from a threshold and softened (x top level; coupling "
                                "and softening x top level above it): "
                              : "[5/5] play channels counted from a threshold (x top level; coupling x top level "
                                "above it): ";
  line += s.threshold > 0 || s.softening > 0
              ? "kept " + formatNumber(s.threshold / r.top_level) + " (" + formatNumber(s.threshold) +
                    " input units), coupling " + formatNumber(s.coupling * above) +
                    (softened ? ", softening " + formatNumber(s.softening * above) : std::string()) + ", play " +
                    formatPlaySet(r.best_set)
              : std::string("none kept");
  line += softened ? ". Scores (threshold/coupling/softening{play}):" : ". Scores (threshold/coupling{play}):";
  for (const auto& t : r.rep.threshold_scores)
    line += " " + formatNumber(t.threshold) + "/" + formatNumber(t.coupling) +
            (softened ? "/" + formatNumber(t.softening) : std::string()) + formatPlaySet(t.set) + "->" +
            scoreText(t.score);
  return line;
}

}  // namespace

void IdentificationRun::searchThreshold() {
  // Softening and the joint refinement shape the level by the held-out k-step
  // score, which does not see what they do to a simulation; only an input-side
  // model can be scored in held-out simulation, which guards the refinement.
  // On the output side a softened level kept by the k-step score was seen to
  // cost a clean plant's simulation points (docs/identification.md, 'Joint
  // refinement'), so neither runs there.
  input_side_chosen = model.schedule_side == ScheduleSide::kInput;
  if (!input_side_chosen && (!o.play_softening_candidates.empty() || o.play_refine_evaluations > 0))
    say("[5/5] softening and joint refinement: input-side structures only (output side chosen), skipped");
  if (o.play_threshold_candidates.empty() && o.play_softening_candidates.empty()) return;
  const ThresholdGrid g = thresholdGrid(*this);
  // A neighbour's level now counts from the threshold: the chosen coupling
  // is kept as a fraction of the top level above it.
  const double coupling_fraction = best_coupling * top_level;
  double best_threshold = 0.0, best_softening = 0.0;
  rep.threshold_scores.push_back({best_set, 0.0, coupling_fraction, 0.0, best_score});
  beginScoring("play thresholds", g.thresholds.size() * g.softenings.size() * g.sets.size() - g.sets.size());
  for (double d : g.thresholds) {
    model.shaping.threshold = d * top_level;
    const double above = top_level - model.shaping.threshold;
    model.shaping.coupling = coupling_fraction / above;
    for (double f : g.softenings) {
      if (d == 0 && f == 0) continue;  // scored already
      model.shaping.softening = f / above;
      for (const auto& set : g.sets) {
        applyPlay(set);
        const double score = crossValidated();
        rep.threshold_scores.push_back({set, d, coupling_fraction, f, score});
        if (score > best_score + 1e-9) {
          best_score = score;
          best_set = set;
          best_threshold = model.shaping.threshold;
          best_coupling = model.shaping.coupling;
          best_softening = model.shaping.softening;
        }
      }
    }
  }
  model.shaping.threshold = best_threshold;
  model.shaping.coupling = best_coupling;
  model.shaping.softening = best_softening;
  applyPlay(best_set);
  say(thresholdLine(*this, g.softenings.size() > 1));
}

}  // namespace plsa::identify
