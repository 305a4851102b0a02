// Steps 5-6, pole selection: each pair's local poles clustered into its
// basis poles by the method asked for, or (PoleMethod::kAuto) by FKcM and by
// fuzzy c-means, each also with local windows' poles when the steps gave too
// few, or with the windows' second-order poles when an output had no steps;
// the structure search's first stage keeps the candidate whose model scores
// higher on held-out data.
#include <algorithm>
#include <cmath>
#include <sstream>

#include "identification_run.hpp"
#include "plsa/core/number_text.hpp"
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

using Kind = IdentificationRun::PoleSourceKind;

// As the scores name it: the method, "+windows" with the windows' poles,
// "+order2" with the windows' second-order poles.
std::string candidateName(const IdentificationRun::PoleCandidate& c) {
  return std::string(optionName(c.method)) + (c.kind == Kind::kStepsAndWindows      ? "+windows"
                                              : c.kind == Kind::kSecondOrderWindows ? "+order2"
                                                                                    : "");
}

// How a progress line names the candidate's poles.
const char* kindLabel(Kind kind) {
  return kind == Kind::kStepsAndWindows ? " (with windows) " : kind == Kind::kSecondOrderWindows ? " (order 2) " : " ";
}

}  // namespace

// Which local poles each pair clusters: its own; with fewer than two, its
// output's (and an output without any borrows every other output's: the
// same chambers drive them all), saying so. kStepsAndWindows: its own are
// the steps' and the windows' (PairPoles::window_identified);
// kSecondOrderWindows: an output without steps has its windows' second-order
// poles (PairPoles::window_second_order).
std::vector<IdentificationRun::PoleSource> IdentificationRun::poleSources(PoleSourceKind kind) {
  const bool with_windows = kind == PoleSourceKind::kStepsAndWindows;
  std::vector<std::vector<C>> pair_poles;
  for (const PairPoles& pp : rep.pairs) {
    const bool windows_instead = std::find(rep.window_outputs.begin(), rep.window_outputs.end(),
                                           o.outputs[static_cast<std::size_t>(pp.output)]) != rep.window_outputs.end();
    pair_poles.push_back(kind == PoleSourceKind::kSecondOrderWindows && windows_instead ? pp.window_second_order
                                                                                        : pp.identified);
    if (with_windows)
      pair_poles.back().insert(pair_poles.back().end(), pp.window_identified.begin(), pp.window_identified.end());
  }
  const auto own = [&](int in_i, int out_i) -> const std::vector<C>& {
    return pair_poles[static_cast<std::size_t>(out_i * ni + in_i)];
  };
  std::vector<std::vector<C>> output_poles(static_cast<std::size_t>(no));
  std::vector<C> every_pole;
  for (int out_i = 0; out_i < no; ++out_i)
    for (int in_i = 0; in_i < ni; ++in_i) {
      const auto& id = own(in_i, out_i);
      output_poles[static_cast<std::size_t>(out_i)].insert(output_poles[static_cast<std::size_t>(out_i)].end(),
                                                           id.begin(), id.end());
      every_pole.insert(every_pole.end(), id.begin(), id.end());
    }
  if (every_pole.empty()) every_pole = uncertainPoles();
  if (every_pole.empty()) noUsablePoles(0);
  std::vector<PoleSource> sources;
  for (int out_i = 0; out_i < no; ++out_i) {
    const auto& mine = output_poles[static_cast<std::size_t>(out_i)];
    if (mine.empty() && !rep.uncertain_poles && kind == PoleSourceKind::kSteps)
      say("[3/5] no usable local fit for " + o.outputs[static_cast<std::size_t>(out_i)] +
          " (every one rejected): it takes the other outputs' poles");
    for (int in_i = 0; in_i < ni; ++in_i) {
      const std::vector<C>& pp = own(in_i, out_i);
      if (pp.size() >= 2)
        sources.push_back({pp, with_windows                                  ? " step and window"
                               : kind == PoleSourceKind::kSecondOrderWindows ? " own (order 2)"
                                                                             : " own"});
      else if (!mine.empty())
        sources.push_back({mine, " output-wide"});
      else
        sources.push_back({every_pole, rep.uncertain_poles ? " uncertain" : " other outputs'"});
    }
  }
  return sources;
}

// Every pair's basis poles by one method. Window fits give every input of an
// output the same poles: each distinct set is clustered once per run (on an
// hour of data, seconds per set), and a pair whose set an earlier candidate
// clustered is not printed again.
IdentificationRun::PoleCandidate IdentificationRun::clusterPairs(PoleMethod method, PoleSourceKind kind,
                                                                 const std::vector<PoleSource>& sources) {
  ClusteringOptions co = o.clustering;
  co.centres = o.poles_per_pair;
  const std::size_t earlier = clustered_sets.size();
  PoleCandidate cand{method, kind, std::vector<std::vector<PoleSet>>(static_cast<std::size_t>(no)), {}};
  for (int out_i = 0; out_i < no; ++out_i)
    for (int in_i = 0; in_i < ni; ++in_i) {
      const PoleSource& src = sources[static_cast<std::size_t>(out_i * ni + in_i)];
      auto same = std::find_if(clustered_sets.begin(), clustered_sets.end(),
                               [&](const ClusteredSet& c) { return c.method == method && c.poles == src.poles; });
      if (same == clustered_sets.end())
        same = clustered_sets.insert(same, {method, src.poles, cluster(method, src.poles, co)});
      const bool new_set = static_cast<std::size_t>(same - clustered_sets.begin()) >= earlier;
      const ClusteringResult& r = same->result;
      cand.chosen.push_back(r);
      cand.poles[static_cast<std::size_t>(out_i)].push_back(PoleSet(r.centres));
      if (!new_set) continue;
      say("[3/5] poles" + std::string(kindLabel(kind)) + o.inputs[static_cast<std::size_t>(in_i)] + " -> " +
          o.outputs[static_cast<std::size_t>(out_i)] + " (" + r.method + " over " + std::to_string(src.poles.size()) +
          src.label + " poles, rho " + fixedDecimals(r.rho, 6) + "): " + fmtPoles(r.centres));
    }
  return cand;
}

// With kAuto FKcM and fuzzy c-means, else the method asked for
// (fuzzy c-means places real centres only: with complex pairs asked for,
// auto is FKcM).
std::vector<PoleMethod> IdentificationRun::poleMethods() const {
  if (o.pole_method == PoleMethod::kAuto && o.clustering.complex_pairs == 0)
    return {PoleMethod::kFkcm, PoleMethod::kFuzzyCMeans};
  return {o.pole_method == PoleMethod::kAuto ? PoleMethod::kFkcm : o.pole_method};
}

void IdentificationRun::selectPoles() {
  model.sample_time_s = dt;
  model.inputs = o.inputs;
  model.outputs = o.outputs;
  model.output_frame = frame;
  if (frame == OutputFrame::kTipCartesian) model.output_unit = rep.output_frame.angle_unit;
  const std::vector<PoleSource> sources = poleSources(PoleSourceKind::kSteps);
  pole_candidates.clear();
  clustered_sets.clear();
  for (PoleMethod m : poleMethods()) pole_candidates.push_back(clusterPairs(m, PoleSourceKind::kSteps, sources));
  adoptPoles(pole_candidates.front());
}

// Whether the windows an output without steps took its poles from were
// fitted at second order too (local_order 1), with some usable fit.
bool IdentificationRun::secondOrderWindowsFitted() const {
  return std::any_of(rep.pairs.begin(), rep.pairs.end(),
                     [](const PairPoles& pp) { return !pp.window_second_order.empty(); });
}

void IdentificationRun::adoptPoles(const PoleCandidate& c) {
  model.poles = c.poles;
  for (std::size_t i = 0; i < rep.pairs.size(); ++i) rep.pairs[i].chosen = c.chosen[i];
}

// Each pole candidate (with kAuto FKcM's and fuzzy c-means') scored on the
// first play set, by held-out 40-step fit on the first structure and, when a
// structure schedules on the input side, held-out simulation on the first
// such one (the mean of the two); the first (FKcM, the paper's) unless
// another scores higher by more than kPoleMethodMargin fit points (on a
// staircase both find nearly the same poles and scores, and a tie keeps the
// paper's). FKcM minimises the largest weighted distance to any local pole,
// so on window fits (hundreds of local poles, some spurious) a few outliers
// can set its centres, and a simulation on them can run away; the scores
// decide on the data.
//
// An output with fewer usable step poles than a bank places has a bank of
// its one or two poles repeated. That can be the better basis (a repeated
// pole is a Laguerre basis: on the real arm's leave-one-out it simulates
// better than local windows' poles, whose slow ones follow drift, though
// the search's own held-out scores prefer the windows'), or the model's
// undoing (a slow pole from a joystick run's one pause: a simulation that
// runs away). So the steps' and windows' poles together are tried only when
// the steps' best model scores below IdentifyOptions::window_poles_below.
//
// Windows of random excitation fitted at first order (the paper's local
// model) can give slow poles only, and a model on them that runs away; the
// same windows at second order can give the faster ones, or worse poles.
// So where an output took its poles from windows, their second-order poles
// are two more candidates ("+order2"), scored alike.
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
  const bool windows = !rep.window_candidate_outputs.empty(), second_order = secondOrderWindowsFitted();
  if (pole_candidates.size() < 2 && !windows && !second_order) return;
  const Structure* input_side = firstInputSide();
  rep.pole_method_scores.clear();
  PoleChoice choice;
  scorePoleCandidates("pole methods", input_side, choice);
  std::string held_back;
  if (windows && choice.fit < o.window_poles_below) {
    addPoleCandidates(PoleSourceKind::kStepsAndWindows, "pole candidates with windows", input_side, choice);
  } else if (windows) {
    held_back = "; windows' poles for";
    for (const auto& name : rep.window_candidate_outputs) held_back += " " + name;
    held_back += " not tried: the steps' score " + formatNumber(o.window_poles_below) + " or more";
  }
  if (second_order && choice.fit < o.second_order_windows_below)
    addPoleCandidates(PoleSourceKind::kSecondOrderWindows, "pole candidates from second-order windows", input_side,
                      choice);
  else if (second_order)
    held_back += "; second-order windows' poles not tried: the first-order score " +
                 formatNumber(o.second_order_windows_below) + " or more";
  adoptPoles(pole_candidates[choice.best]);
  std::string s = "[5/5] poles kept: " + candidateName(pole_candidates[choice.best]) +
                  " (held-out fits on the first play set, 40 steps ahead" + (input_side ? " and simulated" : "") +
                  "; the first unless another scores " + formatNumber(kPoleMethodMargin) + " higher:";
  for (const PoleMethodScore& sc : rep.pole_method_scores)
    s += " " + sc.method + "->" + scoreText(sc.step_ahead) +
         (input_side ? "/" + scoreText(sc.simulation) : std::string());
  say(s + held_back + ")");
}

// One more candidate per pole method, clustering the poles `kind` names,
// scored with the others.
void IdentificationRun::addPoleCandidates(PoleSourceKind kind, const char* stage, const Structure* input_side,
                                          PoleChoice& choice) {
  const std::vector<PoleSource> sources = poleSources(kind);
  for (PoleMethod m : poleMethods()) pole_candidates.push_back(clusterPairs(m, kind, sources));
  scorePoleCandidates(stage, input_side, choice);
}

// Scores the candidates not scored yet (from rep.pole_method_scores' size
// on), keeping the best in `choice`.
void IdentificationRun::scorePoleCandidates(const char* stage, const Structure* input_side, PoleChoice& choice) {
  const std::size_t first = rep.pole_method_scores.size();
  beginScoring(stage, (pole_candidates.size() - first) * (input_side ? 2 : 1));
  for (std::size_t i = first; i < pole_candidates.size(); ++i) {
    adoptPoles(pole_candidates[i]);
    PoleMethodScore sc{candidateName(pole_candidates[i])};
    double score = poleMethodScore(input_side, sc);
    if (!std::isfinite(score)) score = -INFINITY;  // a simulation run off to NaN loses
    rep.pole_method_scores.push_back(sc);
    if (i == 0 || score > choice.fit + kPoleMethodMargin) {
      choice.fit = score;
      choice.best = i;
    }
  }
}

}  // namespace plsa::identify
