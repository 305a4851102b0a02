// The joint refinement of the play channels' threshold, coupling, softening
// and size (IdentifyOptions::play_refine_evaluations): NLopt BOBYQA from the
// staged choice on the same held-out score, kept only if held-out
// simulation does not fall.
#include <algorithm>
#include <cmath>

#include <nlopt.hpp>

#include "identification_run.hpp"

namespace plsa::identify {

void IdentificationRun::refineJointly() {
  // The stages above pick one setting at a time from coarse sets; the
  // simulator's own structure scores higher than any of their picks
  // (docs/identification.md, 'Joint refinement'). A bounded local search
  // over all four from the pick, on the same held-out score.
  // Only the stages that ran are refined: a stage turned off (its candidates
  // empty) keeps its setting, as does the channel size without a channel.
  const bool any_channel =
      std::any_of(best_set.begin(), best_set.end(), [](const PlayChannel& c) { return !c.passesThrough(); });
  std::vector<std::size_t> refined_dims;  // of threshold, coupling, softening, channel size
  if (input_side_chosen) {
    if (!o.play_threshold_candidates.empty()) refined_dims.push_back(0);
    if (!o.play_coupling_candidates.empty()) refined_dims.push_back(1);
    if (!o.play_softening_candidates.empty()) refined_dims.push_back(2);
    if (any_channel) refined_dims.push_back(3);
  }
  if (o.play_refine_evaluations > 0 && input_side_chosen && refined_dims.empty())
    say("[5/5] joint refinement: nothing to refine (no threshold, coupling, softening or play channel in the search)");
  if (o.play_refine_evaluations > 0 && !refined_dims.empty()) {
    const std::vector<PlayChannel> base_set = best_set;
    const double kept_threshold = model.shaping.threshold, kept_coupling = model.shaping.coupling,
                 kept_softening = model.shaping.softening;
    auto restoreStaged = [&] {
      model.shaping.threshold = kept_threshold;
      model.shaping.coupling = kept_coupling;
      model.shaping.softening = kept_softening;
      applyPlay(base_set);
    };
    auto scaled = [&](double k) {
      std::vector<PlayChannel> set = base_set;
      for (PlayChannel& c : set) c = PlayChannel(c.width * k, c.slope * k);
      return set;
    };
    auto apply = [&](const std::vector<double>& x) {
      model.shaping.threshold = x[0] * top_level;
      const double above = top_level - model.shaping.threshold;
      model.shaping.coupling = x[1] / above;
      model.shaping.softening = x[2] / above;
      applyPlay(scaled(x[3]));
    };
    const double above0 = top_level - model.shaping.threshold;
    std::vector<double> x{model.shaping.threshold / top_level, model.shaping.coupling * above0,
                          model.shaping.softening * above0, 1.0};
    const std::vector<double> lo{0.0, 0.0, 0.0, 0.5}, hi{0.45, 0.6, 0.45, 2.0};
    for (std::size_t i : refined_dims) x[i] = std::clamp(x[i], lo[i], hi[i]);
    rep.refine_start = {x[0], x[1], x[2], x[3], best_score};
    beginScoring("the joint refinement", static_cast<std::size_t>(o.play_refine_evaluations));
    rep.refine_best = rep.refine_start;
    auto score = [&](const std::vector<double>& free) {
      std::vector<double> v = x;
      for (std::size_t i = 0; i < refined_dims.size(); ++i) v[refined_dims[i]] = free[i];
      apply(v);
      const double sc = crossValidated();
      ++rep.refine_evaluations;
      if (sc > rep.refine_best.score + 1e-9) rep.refine_best = {v[0], v[1], v[2], v[3], sc};
      if (rep.refine_evaluations % 10 == 0)
        say("[5/5] refining threshold, coupling, softening and channel size: " +
            std::to_string(rep.refine_evaluations) + " of at most " + std::to_string(o.play_refine_evaluations) +
            " scores, best " + std::to_string(rep.refine_best.score).substr(0, 5));
      return std::isfinite(sc) ? sc : -1e6;
    };
    const std::vector<double> step{0.05, 0.05, 0.05, 0.15};
    std::vector<double> lo_free, hi_free, step_free, xs;
    for (std::size_t i : refined_dims) {
      lo_free.push_back(lo[i]);
      hi_free.push_back(hi[i]);
      step_free.push_back(step[i]);
      xs.push_back(x[i]);
    }
    nlopt::opt opt(nlopt::LN_BOBYQA, static_cast<unsigned>(refined_dims.size()));
    opt.set_lower_bounds(lo_free);
    opt.set_upper_bounds(hi_free);
    opt.set_initial_step(step_free);
    opt.set_maxeval(o.play_refine_evaluations);
    opt.set_xtol_abs(1e-3);
    using Objective = decltype(score);
    // nlopt::opt wants a plain function pointer and a context.
    opt.set_max_objective([](const std::vector<double>& v, std::vector<double>&,
                             void* data) { return (*static_cast<Objective*>(data))(v); },
                          &score);
    double f = 0.0;
    try {
      opt.optimize(xs, f);
    } catch (const nlopt::roundoff_limited&) {
      // Stopped by round-off: the best point seen is still the answer.
    } catch (const std::runtime_error&) {
      // NLopt gave up (e.g. a flat score around the start): the best point seen stands.
    }
    const IdentifyReport::PlayRefinement& b = rep.refine_best;
    // Kept only if held-out simulation does not fall: a higher k-step score
    // alone was seen to cost simulation points (docs/identification.md,
    // 'Joint refinement').
    bool keep = b.score > best_score + 1e-9;
    if (keep) {
      beginScoring("the refinement's simulation guard", 2);
      restoreStaged();
      rep.refine_simulation.first = crossValidated(Score::kSimulation);
      apply({b.threshold, b.coupling, b.softening, b.channel_scale});
      rep.refine_simulation.second = crossValidated(Score::kSimulation);
      keep = rep.refine_simulation.second >= rep.refine_simulation.first;
    }
    if (keep) {
      best_score = b.score;
      best_set = scaled(b.channel_scale);
    } else {
      restoreStaged();
    }
    const IdentifyReport::PlayRefinement& s0 = rep.refine_start;
    const char* const dim_names[] = {"threshold", "coupling", "softening", "channel size"};
    std::string over;
    for (std::size_t i : refined_dims) over += (over.empty() ? "" : ", ") + std::string(dim_names[i]);
    say("[5/5] refined jointly (" + std::to_string(rep.refine_evaluations) + " held-out scores over " + over +
        "; threshold x top level, coupling and softening x top level above it, channels x the chosen size): " +
        (keep ? "kept threshold " + formatNumber(b.threshold) + ", coupling " + formatNumber(b.coupling) +
                    ", softening " + formatNumber(b.softening) + ", play " + formatPlaySet(best_set) + " (x" +
                    formatNumber(b.channel_scale) + "): " + std::to_string(b.score).substr(0, 5) + " from " +
                    std::to_string(s0.score).substr(0, 5)
         : b.score > s0.score + 1e-9
             ? "best point (threshold " + formatNumber(b.threshold) + ", coupling " + formatNumber(b.coupling) +
                   ", softening " + formatNumber(b.softening) + ", x" + formatNumber(b.channel_scale) + ", " +
                   std::to_string(b.score).substr(0, 5) + " from " + std::to_string(s0.score).substr(0, 5) +
                   ") not kept"
             : std::string("no better point than the choice above (") + std::to_string(s0.score).substr(0, 5) + ")") +
        (rep.refine_simulation.first != 0.0 || rep.refine_simulation.second != 0.0
             ? "; held-out simulation " + std::to_string(rep.refine_simulation.second).substr(0, 5) + " against " +
                   std::to_string(rep.refine_simulation.first).substr(0, 5)
             : std::string()));
  }
}

}  // namespace plsa::identify
