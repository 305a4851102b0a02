#include "plsa/diagnose/selfcheck.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <map>
#include <random>
#include <sstream>


namespace plsa::diagnose {
namespace {

// Ranges the withheld effects are drawn from: strong enough to matter,
// inside what a real actuator shows.
const std::map<std::string, std::pair<double, double>>& truthRanges() {
  static const std::map<std::string, std::pair<double, double>> r = {
      {"deadzone.threshold_bar", {0.04, 0.10}},        {"deadzone.smooth_width_bar", {0.01, 0.03}},
      {"hysteresis.width", {0.08, 0.20}},              {"stiffening.per_bar", {10.0, 30.0}},
      {"coupling.per_bar", {0.5, 1.2}},                {"pneumatic_lag.fill_time_constant_s", {0.06, 0.15}},
      {"pneumatic_lag.vent_time_constant_s", {0.03, 0.08}}, {"pneumatic_lag.delay_s", {0.02, 0.06}},
      {"creep.fraction", {0.06, 0.15}},                {"creep.time_constant_s", {3.0, 12.0}},
      {"sensor_bias.tilt_deg", {1.0, 3.0}},            {"sensor_bias.yaw_drift_deg_per_s", {0.01, 0.04}}};
  return r;
}

// Laws the "real" data may follow in an other-formulation case: never the
// one the diagnosis calibrates, nor one its flexible law contains (power
// stiffening is linear or quadratic at exponents 1 and 2, power flow orifice
// or linear at 0.5 and 1; test_sim checks it), so every such case is a
// mismatch of form.
std::vector<std::string> lawsOutsideTheCandidate(const std::string& effect, bool flexible) {
  const auto& laws = sim::formulationsOf(effect);
  const std::string flexible_law = sim::flexibleFormulationOf(effect);
  std::vector<std::string> out;
  for (std::size_t i = 1; i < laws.size(); ++i) {
    const std::string& f = laws[i];
    if (f == flexible_law) continue;
    if (flexible && !flexible_law.empty() && (f == "quadratic" || f == "orifice")) continue;
    out.push_back(f);
  }
  return out;
}

RunData recordRun(const sim::SimConfig& truth, const Eigen::MatrixXd& commands, std::uint64_t seed, const std::string& name) {
  // The same 3 s pre-roll the diagnosis assumes, sensor noise on.
  SimTrace t = replayCommands(truth, commands, seed);
  RunData r;
  r.name = name;
  r.sample_time_s = 1.0 / truth.sample_rate_hz;
  r.commands = commands;
  r.outputs = std::move(t.outputs);
  r.pressures = std::move(t.pressures);
  return r;
}

sim::SimConfig allOff() {
  sim::SimConfig c;
  for (const auto& e : sim::effectNames()) c.setEffectEnabled(e, false);
  return c;
}

}  // namespace

Eigen::MatrixXd excitationCommands(double duration_s, double rate_hz, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  const auto n = static_cast<Eigen::Index>(std::lround(duration_s * rate_hz));
  Eigen::MatrixXd u = Eigen::MatrixXd::Zero(n, 3);
  Eigen::Vector3d level = Eigen::Vector3d::Zero();
  Eigen::Index i = 0;
  while (i < n) {
    Eigen::Vector3d next;
    for (int c = 0; c < 3; ++c) next(c) = uni(rng) < 0.35 ? 0.0 : 0.03 + 0.33 * uni(rng);
    const bool ramp = uni(rng) < 0.3;
    const auto ramp_n = ramp ? static_cast<Eigen::Index>(rate_hz) : 0;
    const auto hold_n = static_cast<Eigen::Index>((0.6 + 2.4 * uni(rng)) * rate_hz);
    for (Eigen::Index k = 0; k < ramp_n && i < n; ++k, ++i)
      u.row(i) = (level + (next - level) * static_cast<double>(k + 1) / static_cast<double>(ramp_n)).transpose();
    for (Eigen::Index k = 0; k < hold_n && i < n; ++k, ++i) u.row(i) = next.transpose();
    level = next;
  }
  return u;
}

std::string SelfcheckResult::summary() const {
  std::ostringstream o;
  char line[512];
  o << "case                                   withheld -> selected (round-1 top 2)            gap before -> after (noise)  true-effect shrink  pass\n";
  for (const auto& c : cases) {
    std::string w, s, t;
    for (const auto& x : c.withheld) w += (w.empty() ? "" : "+") + x;
    for (const auto& x : c.selected) s += (s.empty() ? "" : "+") + x;
    for (const auto& x : c.top2) t += (t.empty() ? "" : ",") + x;
    std::snprintf(line, sizeof line, "%-38s %s -> %s (%s)  %.1f%% -> %.1f%% (%.1f%%)  %.0f%%  %s\n", c.name.c_str(),
                  w.empty() ? "nothing" : w.c_str(), s.empty() ? "nothing" : s.c_str(), t.c_str(), c.gap_before,
                  c.gap_after, c.noise, c.true_effect_shrink, c.pass ? "yes" : "NO");
    o << line;
  }
  o << "\nconfusion matrix (rows: withheld effect, single cases and null; columns: first effect selected)\n";
  std::snprintf(line, sizeof line, "%-14s", "");
  o << line;
  for (const auto& l : labels) {
    std::snprintf(line, sizeof line, " %13s", l.c_str());
    o << line;
  }
  o << "\n";
  for (std::size_t r = 0; r < labels.size(); ++r) {
    std::snprintf(line, sizeof line, "%-14s", labels[r].c_str());
    o << line;
    for (std::size_t c = 0; c < labels.size(); ++c) {
      std::snprintf(line, sizeof line, " %13d", confusion[r][c]);
      o << line;
    }
    o << "\n";
  }
  std::snprintf(line, sizeof line,
                "\ntargets: top-1 correct %d/%d (%.0f%%, target >= 90%%); pairs with both in the top 2: %d/%d; "
                "true-effect held-out shrink min %.0f%%, median %.0f%% (target >= 50%%); null cases claiming nothing: "
                "%d/%d -> %s\n",
                single_top1, single_cases, single_cases ? 100.0 * single_top1 / single_cases : 0.0, pair_top2,
                pair_cases, min_true_shrink, median_true_shrink, null_clean, null_cases,
                targets_met ? "all targets met" : "targets NOT met");
  o << line;
  return o.str();
}

SelfcheckResult runSelfcheck(const SelfcheckOptions& o) {
  SelfcheckResult res;
  std::vector<std::string> effects = o.effects.empty() ? sim::effectNames() : o.effects;
  res.labels = sim::effectNames();
  res.labels.push_back("none");
  res.confusion.assign(res.labels.size(), std::vector<int>(res.labels.size(), 0));
  auto index = [&](const std::string& e) {
    return static_cast<std::size_t>(std::find(res.labels.begin(), res.labels.end(), e) - res.labels.begin());
  };
  struct Spec {
    std::vector<std::string> withheld;
    std::string alternative;  ///< the law the "real" data follows; empty: the default one
    std::uint64_t seed;
  };
  std::vector<Spec> specs;
  std::uint64_t seed = o.seed;
  for (const auto& e : effects) {
    const std::vector<std::string> others = lawsOutsideTheCandidate(e, o.diagnose.flexible_laws);
    for (int s = 0; s < o.seeds_per_effect; ++s)
      specs.push_back({{e}, s % 2 == 1 ? others[static_cast<std::size_t>(s / 2) % others.size()] : "", seed++});
  }
  for (const auto& [a, b] : o.pairs) specs.push_back({{a, b}, "", seed++});
  for (int k = 0; k < o.null_cases; ++k) specs.push_back({{}, "", seed++});
  std::vector<double> shrinks;
  int number = 0;
  for (const Spec& spec : specs) {
    const auto t0 = std::chrono::steady_clock::now();
    std::mt19937_64 rng(spec.seed * 7919 + 13);
    std::uniform_real_distribution<double> uni(0.0, 1.0);
    sim::SimConfig truth = allOff();
    for (const sim::ParamRef& p : truth.parameters("nominal"))
      *p.value = std::clamp(*p.value * (1.0 + o.nominal_perturbation * (2 * uni(rng) - 1)), p.lower, p.upper);
    SelfcheckCase c;
    c.withheld = spec.withheld;
    std::string forms;
    for (const auto& e : spec.withheld) {
      truth.setEffectEnabled(e, true);
      if (!spec.alternative.empty()) truth.formulationOf(e) = spec.alternative;
      for (const sim::ParamRef& p : truth.parameters(e)) {
        const auto range = truthRanges().find(e + "." + p.name);
        if (range == truthRanges().end()) continue;
        double v = range->second.first + uni(rng) * (range->second.second - range->second.first);
        if (e == "sensor_bias" && uni(rng) < 0.5) v = -v;
        *p.value = v;
        c.truth.emplace_back(e + "." + p.name, v);
      }
      forms += (forms.empty() ? "" : ", ") + e + " " + truth.formulationOf(e);
    }
    c.formulation = forms;
    std::string label;
    for (const auto& e : spec.withheld) label += (label.empty() ? "" : "+") + e;
    c.name = (label.empty() ? std::string("null") : label) + (spec.alternative.empty() ? "" : " (" + spec.alternative + ")") + " #" +
             std::to_string(spec.seed);
    if (o.log) o.log("selfcheck " + std::to_string(++number) + "/" + std::to_string(specs.size()) + ": " + c.name);
    const std::vector<RunData> runs = {
        recordRun(truth, excitationCommands(o.train_s, truth.sample_rate_hz, spec.seed * 2 + 1), spec.seed, "train"),
        recordRun(truth, excitationCommands(o.heldout_s, truth.sample_rate_hz, spec.seed * 2 + 2), spec.seed + 1000,
                  "held-out")};
    DiagnoseOptions dopt = o.diagnose;
    if (!o.verbose) dopt.log = nullptr;
    else if (!dopt.log) dopt.log = o.log;
    const Diagnosis d = runDiagnosis(allOff(), runs, dopt);
    c.selected = d.selected;
    for (std::size_t k = 0; k < std::min<std::size_t>(2, d.ranking.size()); ++k) c.top2.push_back(d.ranking[k].effect);
    c.gap_before = d.gap_before.percent();
    c.gap_after = d.gap_after.percent();
    c.noise = d.noise.percent();
    const std::string first = d.selected.empty() ? "none" : d.selected[0];
    if (spec.withheld.size() == 1) {
      for (const auto& r : d.ranking)
        if (r.effect == spec.withheld[0]) c.true_effect_shrink = r.shrink_percent;
      // Kept first: its gap once its calibration is polished.
      if (!d.steps.empty() && d.steps[0].first == spec.withheld[0])
        c.true_effect_shrink = 100.0 * (1.0 - d.steps[0].second.percent() / std::max(1e-12, c.gap_before));
      c.pass = first == spec.withheld[0] && c.true_effect_shrink >= 50.0;
      ++res.single_cases;
      res.single_top1 += first == spec.withheld[0];
      res.confusion[index(spec.withheld[0])][index(first)]++;
      shrinks.push_back(c.true_effect_shrink);
    } else if (spec.withheld.size() == 2) {
      c.true_effect_shrink = 100.0 * (1.0 - c.gap_after / std::max(1e-12, c.gap_before));
      const bool both = std::find(c.top2.begin(), c.top2.end(), spec.withheld[0]) != c.top2.end() &&
                        std::find(c.top2.begin(), c.top2.end(), spec.withheld[1]) != c.top2.end();
      c.pass = both;
      ++res.pair_cases;
      res.pair_top2 += both;
      shrinks.push_back(c.true_effect_shrink);
    } else {
      c.pass = d.selected.empty();
      ++res.null_cases;
      res.null_clean += c.pass;
      res.confusion[index("none")][index(first)]++;
    }
    c.elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (o.log) {
      char line[256];
      std::snprintf(line, sizeof line, "  -> selected %s; gap %.1f%% -> %.1f%% (noise %.1f%%); %s (%.0f s)",
                    first.c_str(), c.gap_before, c.gap_after, c.noise, c.pass ? "pass" : "FAIL", c.elapsed_s);
      o.log(line);
    }
    res.cases.push_back(c);
  }
  if (!shrinks.empty()) {
    std::sort(shrinks.begin(), shrinks.end());
    res.min_true_shrink = shrinks.front();
    res.median_true_shrink = shrinks[shrinks.size() / 2];
  }
  res.targets_met = (res.single_cases == 0 || res.single_top1 >= 0.9 * res.single_cases) &&
                    res.pair_top2 == res.pair_cases && res.null_clean == res.null_cases &&
                    (shrinks.empty() || res.min_true_shrink >= 50.0);
  return res;
}

}  // namespace plsa::diagnose
