// Steps 5-6, pole selection: each pair's local poles clustered into its
// basis poles by the method asked for, or (PoleMethod::kAuto) by FKcM and by
// fuzzy c-means, the structure search's first stage keeping the one whose
// model scores higher on held-out data.
#include <algorithm>
#include <cmath>
#include <sstream>

#include "identification_run.hpp"
#include "plsa/identify/pole_clustering.hpp"

namespace plsa::identify {
namespace {

using C = std::complex<double>;

constexpr double kPoleMethodMargin = 0.1;  // fit points (choosePoleMethod)

// Printed in ascending order (the clustering returns centres in no particular order).
std::string fmtPoles(std::vector<C> p) {
  std::sort(p.begin(), p.end(), [](const auto& a, const auto& b) {
    return a.real() != b.real() ? a.real() < b.real() : a.imag() < b.imag();
  });
  std::ostringstream s;
  s.precision(4);
  for (std::size_t i = 0; i < p.size(); ++i) {
    s << (i ? " " : "") << p[i].real();
    if (p[i].imag() != 0) s << (p[i].imag() > 0 ? "+" : "") << p[i].imag() << "i";
  }
  return s.str();
}

ClusteringResult cluster(PoleMethod method, const std::vector<C>& poles, const ClusteringOptions& o) {
  switch (method) {
    case PoleMethod::kFkcm:
      return fkcmClustering(poles, o);
    case PoleMethod::kFuzzyCMeans:
      return fuzzyCMeansClustering(poles, o);
    case PoleMethod::kKMeans:
      return kMeansClustering(poles, o);
    case PoleMethod::kGlobalRho:
      return globalRhoSearch(poles, o);
    case PoleMethod::kAuto:
      break;
  }
  throw std::invalid_argument("identify: pole method out of range");
}

}  // namespace

// Which local poles each pair clusters: its own; with fewer than two, its
// output's (and an output without any borrows every other output's: the
// same chambers drive them all), saying so.
std::vector<IdentificationRun::PoleSource> IdentificationRun::poleSources() {
  std::vector<std::vector<C>> output_poles(static_cast<std::size_t>(no));
  std::vector<C> every_pole;
  for (int out_i = 0; out_i < no; ++out_i)
    for (int in_i = 0; in_i < ni; ++in_i) {
      const auto& id = pairAt(in_i, out_i).identified;
      output_poles[static_cast<std::size_t>(out_i)].insert(output_poles[static_cast<std::size_t>(out_i)].end(),
                                                           id.begin(), id.end());
      every_pole.insert(every_pole.end(), id.begin(), id.end());
    }
  if (every_pole.empty()) every_pole = uncertainPoles();
  if (every_pole.empty()) noUsablePoles(0);
  std::vector<PoleSource> sources;
  for (int out_i = 0; out_i < no; ++out_i) {
    const auto& mine = output_poles[static_cast<std::size_t>(out_i)];
    if (mine.empty() && !rep.uncertain_poles)
      say("[3/5] no usable local fit for " + o.outputs[static_cast<std::size_t>(out_i)] +
          " (every one rejected): it takes the other outputs' poles");
    for (int in_i = 0; in_i < ni; ++in_i) {
      const PairPoles& pp = pairAt(in_i, out_i);
      if (pp.identified.size() >= 2)
        sources.push_back({pp.identified, " own"});
      else if (!mine.empty())
        sources.push_back({mine, " output-wide"});
      else
        sources.push_back({every_pole, rep.uncertain_poles ? " uncertain" : " other outputs'"});
    }
  }
  return sources;
}

// Every pair's basis poles by one method. Window fits give every input of an
// output the same poles: each distinct set is clustered once (on an hour of
// data, seconds per set).
IdentificationRun::PoleCandidate IdentificationRun::clusterPairs(PoleMethod method,
                                                                 const std::vector<PoleSource>& sources) {
  ClusteringOptions co = o.clustering;
  co.centres = o.poles_per_pair;
  std::vector<std::pair<const std::vector<C>*, ClusteringResult>> clustered;
  PoleCandidate cand{method, std::vector<std::vector<PoleSet>>(static_cast<std::size_t>(no)), {}};
  for (int out_i = 0; out_i < no; ++out_i)
    for (int in_i = 0; in_i < ni; ++in_i) {
      const PoleSource& src = sources[static_cast<std::size_t>(out_i * ni + in_i)];
      auto same =
          std::find_if(clustered.begin(), clustered.end(), [&](const auto& c) { return *c.first == src.poles; });
      if (same == clustered.end()) same = clustered.insert(same, {&src.poles, cluster(method, src.poles, co)});
      const ClusteringResult& r = same->second;
      cand.chosen.push_back(r);
      cand.poles[static_cast<std::size_t>(out_i)].push_back(PoleSet(r.centres));
      say("[3/5] poles " + o.inputs[static_cast<std::size_t>(in_i)] + " -> " +
          o.outputs[static_cast<std::size_t>(out_i)] + " (" + r.method + " over " + std::to_string(src.poles.size()) +
          src.label + " poles, rho " + std::to_string(r.rho).substr(0, 8) + "): " + fmtPoles(r.centres));
    }
  return cand;
}

void IdentificationRun::selectPoles() {
  model.sample_time_s = dt;
  model.inputs = o.inputs;
  model.outputs = o.outputs;
  model.output_frame = frame;
  const std::vector<PoleSource> sources = poleSources();
  // Fuzzy c-means places real centres only: with complex pairs asked for, auto is FKcM.
  const bool both = o.pole_method == PoleMethod::kAuto && o.clustering.complex_pairs == 0;
  const std::vector<PoleMethod> methods =
      both ? std::vector<PoleMethod>{PoleMethod::kFkcm, PoleMethod::kFuzzyCMeans}
           : std::vector<PoleMethod>{o.pole_method == PoleMethod::kAuto ? PoleMethod::kFkcm : o.pole_method};
  pole_candidates.clear();
  for (PoleMethod m : methods) pole_candidates.push_back(clusterPairs(m, sources));
  adoptPoles(pole_candidates.front());
}

void IdentificationRun::adoptPoles(const PoleCandidate& c) {
  model.poles = c.poles;
  for (std::size_t i = 0; i < rep.pairs.size(); ++i) rep.pairs[i].chosen = c.chosen[i];
}

// With kAuto: each method's poles scored on the first play set, by held-out
// 40-step fit on the first structure and, when a structure schedules on the
// input side, held-out simulation on the first such one (the mean of the
// two); FKcM (the paper's) unless fuzzy c-means scores higher by more than
// kPoleMethodMargin fit points (on a staircase both find nearly the same
// poles and scores, and a tie keeps the paper's). FKcM minimises the largest
// weighted distance to any local pole, so on window fits (hundreds of local
// poles, some spurious) a few outliers can set its centres, and a simulation
// on them can run away; the scores decide on the data.
double IdentificationRun::poleMethodScore(const Structure* input_side, PoleMethodScore& into) {
  applyPlay(o.play_candidates.front());
  applyStructure(structures.front());
  into.step_ahead = crossValidated();
  if (!input_side) return into.step_ahead;
  applyStructure(*input_side);
  into.simulation = crossValidated(Score::kSimulation);
  return 0.5 * (into.step_ahead + into.simulation);
}

void IdentificationRun::choosePoleMethod() {
  if (pole_candidates.size() < 2) return;
  const auto first_input_side = std::find_if(structures.begin(), structures.end(),
                                             [](const Structure& st) { return st.side == ScheduleSide::kInput; });
  const Structure* input_side = first_input_side == structures.end() ? nullptr : &*first_input_side;
  const bool sim = input_side != nullptr;
  beginScoring("pole methods", pole_candidates.size() * (sim ? 2 : 1));
  rep.pole_method_scores.clear();
  std::size_t best = 0;
  double best_fit = -INFINITY;
  for (std::size_t i = 0; i < pole_candidates.size(); ++i) {
    adoptPoles(pole_candidates[i]);
    PoleMethodScore sc{optionName(pole_candidates[i].method)};
    double score = poleMethodScore(input_side, sc);
    if (!std::isfinite(score)) score = -INFINITY;  // a simulation run off to NaN loses
    rep.pole_method_scores.push_back(sc);
    if (score > best_fit + kPoleMethodMargin) {
      best_fit = score;
      best = i;
    }
  }
  adoptPoles(pole_candidates[best]);
  std::string s = "[5/5] poles kept: " + std::string(optionName(pole_candidates[best].method)) +
                  " (held-out fits on the first play set, 40 steps ahead" + (sim ? " and simulated" : "") +
                  "; fkcm unless fcm scores 0.1 higher:";
  for (const PoleMethodScore& sc : rep.pole_method_scores)
    s += " " + sc.method + "->" + std::to_string(sc.step_ahead).substr(0, 5) +
         (sim ? "/" + std::to_string(sc.simulation).substr(0, 5) : std::string());
  say(s + ")");
}

}  // namespace plsa::identify
