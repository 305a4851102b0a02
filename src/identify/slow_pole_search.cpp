// The slow poles of an input-side model (identification_run.hpp): one extra
// real pole in every bank, tried against none, then a second beside it, each
// scored on held-out simulation and kept only if it is clearly better
// (eval::clearGain: its gain exceeds one standard error across folds and
// outputs, the one-standard-error rule, or one output shows it plainly and
// none loses by it). Tied (the
// default), their coefficients carry fitted fractions of each bank's own
// response (slow_mode_tie.hpp).
#include <algorithm>
#include <cmath>
#include <complex>

#include "identification_run.hpp"
#include "plsa/core/number_text.hpp"
#include "plsa/eval/paired_gain.hpp"

namespace plsa::identify {

// The banks' poles before the search, each with the poles of `taus` (s) added;
// tied, the fit options tie them.
void IdentificationRun::setSlowPoles(const std::vector<double>& taus) {
  model.poles = poles_before_slow;
  fit_options.slow_mode = {};
  if (taus.empty()) return;
  std::vector<double> slow;
  for (double tau : taus) slow.push_back(std::exp(-dt / tau));
  for (auto& row : model.poles)
    for (PoleSet& ps : row) {
      std::vector<std::complex<double>> p = ps.poles();
      for (double pole : slow) p.emplace_back(pole, 0.0);
      ps = PoleSet(p);
    }
  if (o.slow_pole_form == SlowPoleForm::kTied)
    fit_options.slow_mode = {slow, model.output_frame == OutputFrame::kTipCartesian,
                             o.slow_fraction_fit == SlowFractionFit::kLevel};
}

// Each of `taus` added to the slow poles `kept`, scored on held-out
// simulation (appended to `scores`); the best, the first of a tie.
IdentificationRun::SlowPoleTrial IdentificationRun::bestSlowPoleBeside(const std::vector<double>& kept,
                                                                       const std::vector<double>& taus,
                                                                       std::vector<std::pair<double, double>>& scores) {
  SlowPoleTrial best;
  for (double tau : taus) {
    if (std::find(kept.begin(), kept.end(), tau) != kept.end()) continue;
    std::vector<double> with = kept;
    with.push_back(tau);
    setSlowPoles(with);
    const double score = crossValidated(Score::kSimulation);
    scores.emplace_back(tau, score);
    if (score > best.score + 1e-9) best = {tau, score, fold_scores};
  }
  return best;
}

// Whether `best` is clearly better than the held-out terms `base`
// (eval::clearGain; its gain over them into `gain`); the verdict appended to `line`.
bool IdentificationRun::judgeSlowPole(const SlowPoleTrial& best, const std::vector<double>& base,
                                      std::pair<double, double>& gain, std::string& line) const {
  if (!(best.tau > 0)) {
    gain = {0.0, 0.0};
    line += "none kept";
    return false;
  }
  const eval::ClearGain c = eval::clearGain(best.terms, base, o.outputs.size());
  gain = c.overall;
  line += c.clear() ? "kept " + formatNumber(best.tau) + " s (pole " + formatNumber(std::exp(-dt / best.tau)) + ")"
                    : std::string("none kept");
  line += "; the best, " + formatNumber(best.tau) + " s, " + gainText(gain) +
          (c.by_overall      ? ""
           : c.by_one_output ? ", within one standard error overall, over two on one output and losing on none"
                             : ", within one standard error") +
          " (" + perOutputGains(best.terms, base, o.outputs) + ")";
  return c.clear();
}

void IdentificationRun::searchSlowPole(const std::optional<HeldOutScore>& as_it_stands) {
  if (model.schedule_side != ScheduleSide::kInput || o.slow_pole_candidates.empty()) return;
  PLSA_CHECK(o.slow_pole_count >= 1 && o.slow_pole_count <= 2, "identify: the slow pole count must be 1 or 2");
  poles_before_slow = model.poles;
  std::vector<double> taus;
  for (double tau : o.slow_pole_candidates)
    if (tau != 0 && std::find(taus.begin(), taus.end(), tau) == taus.end()) taus.push_back(tau);
  // "none" is the model as it stands: its score where the drift stage has it.
  beginScoring("slow poles", (as_it_stands ? 0 : 1) + taus.size());
  setSlowPoles({});
  rep.slow_pole_scores.emplace_back(0.0, as_it_stands ? as_it_stands->score : crossValidated(Score::kSimulation));
  const std::vector<double> none_terms = as_it_stands ? as_it_stands->terms : fold_scores;
  const SlowPoleTrial best = bestSlowPoleBeside({}, taus, rep.slow_pole_scores);
  std::string s = std::string("[5/5] slow pole in every bank (") + optionName(o.slow_pole_form) +
                  ", scored on held-out simulation): ";
  const bool keep = judgeSlowPole(best, none_terms, rep.slow_pole_gain, s);
  s += ". Scores:";
  for (const auto& [tau, sc] : rep.slow_pole_scores)
    s += " " + (tau > 0 ? formatNumber(tau) + "s" : std::string("none")) + "->" + scoreText(sc);
  say(s);
  rep.slow_pole_time_constants_s = keep ? std::vector<double>{best.tau} : std::vector<double>{};
  if (keep && o.slow_pole_count >= 2 && taus.size() >= 2) searchSecondSlowPole(taus, best);
  setSlowPoles(rep.slow_pole_time_constants_s);
  rep.slow_pole_tie = fit_options.slow_mode;
}

// Each other candidate beside the kept first slow pole, against the first
// alone (its score and terms from the first search: the same folds).
void IdentificationRun::searchSecondSlowPole(const std::vector<double>& taus, const SlowPoleTrial& first) {
  beginScoring("second slow pole", taus.size() - 1);
  rep.second_slow_pole_scores.emplace_back(0.0, first.score);
  const SlowPoleTrial best = bestSlowPoleBeside({first.tau}, taus, rep.second_slow_pole_scores);
  std::string s = "[5/5] a second slow pole beside " + formatNumber(first.tau) + " s: ";
  if (judgeSlowPole(best, first.terms, rep.second_slow_pole_gain, s))
    rep.slow_pole_time_constants_s.push_back(best.tau);
  s += ". Scores:";
  for (const auto& [tau, sc] : rep.second_slow_pole_scores)
    s += " " + (tau > 0 ? formatNumber(tau) + "s" : formatNumber(first.tau) + "s alone") + "->" + scoreText(sc);
  say(s);
}

// The final fit's fractions, per kept slow pole and output.
std::string IdentificationRun::slowFractionLine() const {
  const std::vector<double>& taus = rep.slow_pole_time_constants_s;
  std::string f = taus.size() == 1 ? "[5/5] the tied slow pole carries a fraction of each bank's response:"
                                   : "[5/5] the tied slow poles carry fractions of each bank's response:";
  for (std::size_t k = 0; k < rep.slow_pole_fraction.size(); ++k) {
    f += " " + o.outputs[k];
    for (Eigen::Index m = 0; m < rep.slow_pole_fraction[k].size(); ++m)
      f += (taus.size() == 1 ? " " : " " + formatNumber(taus[static_cast<std::size_t>(m)]) + " s ") +
           formatNumber(rep.slow_pole_fraction[k](m));
  }
  return f;
}

}  // namespace plsa::identify
