// The structure search's second stage: a quantile grid's level count by
// held-out score (IdentifyOptions::quantile_levels 0 on logs without a
// staircase). A finer grid follows a nonlinearity more closely and gives
// each region fewer samples; which wins depends on the data, so the data
// decide, scored as the play sets are: held out, play_selection_horizon steps ahead.
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "identification_run.hpp"

namespace plsa::identify {
// The counts a quantile grid may take: the automatic one, and every finer
// count up to kMaxScoredQuantileLevels whose regions (a direction split
// doubles them per input) get kMinSecondsPerRegion of the scored data (the
// search's sample of long logs) on average, stay within kMaxRegions, and
// whose coefficients those samples determine. Ascending; empty when the
// levels were given or not to be scored, or the logs hold a staircase.
// Coarser counts are not offered: the automatic rule takes 2 where the data
// are short, and then 3 cannot leave its regions enough either.
std::vector<int> IdentificationRun::gridLevelCandidates() const {
  if (o.quantile_levels > 0 || !o.score_grid_levels || grid_plan.designed || grid_plan.moving.empty()) return {};
  const auto scored = static_cast<double>(rep.search_samples);
  const double inputs = static_cast<double>(grid_plan.moving.size());
  const double split = o.direction_split ? std::pow(2.0, inputs) : 1.0;
  std::vector<int> counts{grid_plan.quantile_levels};
  for (int levels = grid_plan.quantile_levels + 1; levels <= IdentifyOptions::kMaxScoredQuantileLevels; ++levels) {
    const double regions = std::pow(static_cast<double>(levels), inputs) * split;
    const double coefficients = regions * ni * o.poles_per_pair;
    if (scored * dt / regions < IdentifyOptions::kMinSecondsPerRegion || regions > double{kMaxRegions} ||
        coefficients > scored)
      break;  // a finer count has fewer samples per region still
    counts.push_back(levels);
  }
  return counts;
}

// The partitions of a quantile grid of `levels` levels per moving input.
void IdentificationRun::setGridLevels(int levels, bool announce) {
  grid_plan.quantile_levels = levels;
  makePartitions(announce);
  structures.clear();
  listStructures();
}

// The first play set's held-out fit play_selection_horizon steps ahead (the
// play stage's score) on the grid of `levels`: on the input-side structure,
// plsa's usual choice, when there is one, else on each structure, the best.
// `by_structure` gets each structure's score, where scored.
GridLevelScore IdentificationRun::scoreGrid(int levels, std::vector<std::optional<HeldOutScore>>& by_structure) {
  setGridLevels(levels, false);
  GridLevelScore sc{levels, -INFINITY, ""};
  applyPlay(o.play_candidates.front());
  const bool input_side = firstInputSide() != nullptr;
  by_structure.assign(structures.size(), std::nullopt);
  for (std::size_t pi = 0; pi < structures.size(); ++pi) {
    if (input_side && structures[pi].side != ScheduleSide::kInput) continue;
    applyStructure(structures[pi]);
    const double score = crossValidated();
    by_structure[pi] = HeldOutScore{score, fold_scores};
    if (std::isfinite(score) && score > sc.step_ahead) {
      sc.step_ahead = score;
      sc.structure = structures[pi].tag;
    }
  }
  return sc;
}

// From the automatic count, one level finer at a time while each count
// scores kGridLevelsMargin above the best so far; a count past one that did
// not gain is not scored (each finer grid costs more to score). The kept
// count's scores go to the play stage (first_set_scores), which scores the
// first play set on every structure again.
void IdentificationRun::chooseGridLevels() {
  rep.grid_level_scores.clear();
  const std::vector<int> counts = gridLevelCandidates();
  // A staircase's levels, or no moving input (one region): no quantile grid.
  rep.grid_levels = grid_plan.designed || grid_plan.moving.empty() ? 0 : grid_plan.quantile_levels;
  if (counts.size() < 2) return;
  const int automatic = counts.front();
  beginScoring("quantile grid levels", counts.size() * (firstInputSide() ? 1 : structures.size()));
  std::vector<std::optional<HeldOutScore>> trial;
  rep.grid_level_scores.push_back(scoreGrid(automatic, first_set_scores));
  int best = automatic;
  double best_score = rep.grid_level_scores.back().step_ahead;
  for (std::size_t i = 1; i < counts.size(); ++i) {
    rep.grid_level_scores.push_back(scoreGrid(counts[i], trial));
    const double score = rep.grid_level_scores.back().step_ahead;
    if (!(score > best_score + IdentifyOptions::kGridLevelsMargin)) break;
    best = counts[i];
    best_score = score;
    first_set_scores = trial;
  }
  say(gridLevelsLine(best, automatic));
  grid_plan.scored = best != automatic;
  setGridLevels(best, best != automatic);  // the structures, in their order, as when `best` was scored
  rep.grid_levels = best;
}

std::string IdentificationRun::gridLevelsLine(int kept, int automatic) const {
  std::string line = "[5/5] quantile grid: kept " + std::to_string(kept) + " levels per input (held-out fits " +
                     std::to_string(o.play_selection_horizon) + " steps ahead on the first play set, " +
                     (firstInputSide() ? "input side; " : "best scheduling; ") + "from " + std::to_string(automatic) +
                     ", one level finer at a time while a count scores " +
                     formatNumber(IdentifyOptions::kGridLevelsMargin) + " above the best:";
  for (const GridLevelScore& sc : rep.grid_level_scores)
    line += " " + std::to_string(sc.levels) + "->" + sc.structure + " " + scoreText(sc.step_ahead);
  return line + ")";
}

}  // namespace plsa::identify
