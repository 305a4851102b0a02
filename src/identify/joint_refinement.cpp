// The joint refinement of the play channels' threshold, coupling, softening
// and size (IdentifyOptions::play_refine_evaluations): NLopt BOBYQA from the
// staged choice on the same held-out score, kept only if held-out
// simulation does not fall.
//
// The stages before it pick one setting at a time from coarse sets; a
// bounded local search over all four from the pick, on the same held-out
// score, reaches structures none of them lists (docs/identification.md,
// 'Joint refinement'). A stage turned off (its candidates empty) keeps its
// setting, as does the channel size without a channel.
#include <algorithm>
#include <cmath>

#include <nlopt.hpp>

#include "identification_run.hpp"
#include "plsa/core/number_text.hpp"

namespace plsa::identify {
namespace {

using Point = std::vector<double>;  // threshold, coupling, softening, channel size
using Refinement = IdentifyReport::PlayRefinement;

const char* const kDimensionNames[] = {"threshold", "coupling", "softening", "channel size"};

/// The dimensions whose stage ran: of threshold, coupling, softening,
/// channel size (indices into a Point).
std::vector<std::size_t> refinedDimensions(const IdentificationRun& r) {
  std::vector<std::size_t> dims;
  if (!r.input_side_chosen) return dims;
  const IdentifyOptions& o = r.o;
  if (!o.play_threshold_candidates.empty()) dims.push_back(0);
  if (!o.play_coupling_candidates.empty()) dims.push_back(1);
  if (!o.play_softening_candidates.empty()) dims.push_back(2);
  if (std::any_of(r.best_set.begin(), r.best_set.end(), [](const PlayChannel& c) { return !c.passesThrough(); }))
    dims.push_back(3);
  return dims;
}

/// The search's coordinates: threshold x top level, coupling and softening x
/// the level span above the threshold, channels x the staged size; applied
/// to the run's model, and the staged choice restored on request.
class RefinementSpace {
 public:
  RefinementSpace(IdentificationRun& run, std::vector<std::size_t> dims)
      : run_(run), dims_(std::move(dims)), base_set_(run.best_set), kept_(run.model.shaping) {
    const InputShaping& s = run.model.shaping;
    const double above = run.top_level - s.threshold;
    start_ = {s.threshold / run.top_level, s.coupling * above, s.softening * above, 1.0};
    for (std::size_t i : dims_) start_[i] = std::clamp(start_[i], kLower[i], kUpper[i]);
  }

  const Point& start() const { return start_; }
  const std::vector<std::size_t>& dims() const { return dims_; }

  /// The start with the refined dimensions replaced by `free`.
  Point full(const Point& free) const {
    Point v = start_;
    for (std::size_t i = 0; i < dims_.size(); ++i) v[dims_[i]] = free[i];
    return v;
  }
  /// Of the refined dimensions only: start, bounds and initial steps.
  Point freeOf(const Point& p) const {
    Point out;
    for (std::size_t i : dims_) out.push_back(p[i]);
    return out;
  }
  Point lower() const { return freeOf(kLower); }
  Point upper() const { return freeOf(kUpper); }
  Point steps() const { return freeOf(kStep); }

  std::vector<PlayChannel> scaledChannels(double k) const {
    std::vector<PlayChannel> set = base_set_;
    for (PlayChannel& c : set) c = PlayChannel(c.width * k, c.slope * k);
    return set;
  }
  void apply(const Point& x) {
    InputShaping& s = run_.model.shaping;
    s.threshold = x[0] * run_.top_level;
    const double above = run_.top_level - s.threshold;
    s.coupling = x[1] / above;
    s.softening = x[2] / above;
    run_.applyPlay(scaledChannels(x[3]));
  }
  void restoreStaged() {
    InputShaping& s = run_.model.shaping;
    s.threshold = kept_.threshold;
    s.coupling = kept_.coupling;
    s.softening = kept_.softening;
    run_.applyPlay(base_set_);
  }

 private:
  inline static const Point kLower{0.0, 0.0, 0.0, 0.5}, kUpper{0.45, 0.6, 0.45, 2.0}, kStep{0.05, 0.05, 0.05, 0.15};
  IdentificationRun& run_;
  std::vector<std::size_t> dims_;
  std::vector<PlayChannel> base_set_;
  InputShaping kept_;
  Point start_;
};

/// BOBYQA over the refined dimensions, from the start, for at most
/// `evaluations` scores. The best point seen is kept by `score` itself, so a
/// stop on round-off or a flat score loses nothing.
template <class Score>
void maximiseBobyqa(const RefinementSpace& space, int evaluations, Score& score) {
  nlopt::opt opt(nlopt::LN_BOBYQA, static_cast<unsigned>(space.dims().size()));
  opt.set_lower_bounds(space.lower());
  opt.set_upper_bounds(space.upper());
  opt.set_initial_step(space.steps());
  opt.set_maxeval(evaluations);
  opt.set_xtol_abs(1e-3);
  // nlopt::opt wants a plain function pointer and a context.
  opt.set_max_objective(
      [](const std::vector<double>& v, std::vector<double>&, void* data) { return (*static_cast<Score*>(data))(v); },
      &score);
  Point x = space.freeOf(space.start());
  double f = 0.0;
  try {
    opt.optimize(x, f);
  } catch (const nlopt::roundoff_limited&) {
    // Stopped by round-off: the best point seen is still the answer.
  } catch (const std::runtime_error&) {
    // NLopt gave up (e.g. a flat score around the start): the best point seen stands.
  }
}

/// Whether the refined point keeps held-out simulation at least where the
/// staged choice has it: a higher k-step score alone was seen to cost
/// simulation points (docs/identification.md, 'Joint refinement'). Leaves the
/// refined point applied.
bool simulationHolds(IdentificationRun& r, RefinementSpace& space, const Refinement& b) {
  r.beginScoring("the refinement's simulation guard", 2);
  space.restoreStaged();
  r.rep.refine_simulation.first = r.crossValidated(IdentificationRun::Score::kSimulation);
  space.apply({b.threshold, b.coupling, b.softening, b.channel_scale});
  r.rep.refine_simulation.second = r.crossValidated(IdentificationRun::Score::kSimulation);
  return r.rep.refine_simulation.second >= r.rep.refine_simulation.first;
}

/// The refinement's closing progress line.
std::string refinementLine(const IdentificationRun& r, const RefinementSpace& space, bool kept) {
  const Refinement &b = r.rep.refine_best, &s0 = r.rep.refine_start;
  std::string over;
  for (std::size_t i : space.dims()) over += (over.empty() ? "" : ", ") + std::string(kDimensionNames[i]);
  const std::string point = "threshold " + formatNumber(b.threshold) + ", coupling " + formatNumber(b.coupling) +
                            ", softening " + formatNumber(b.softening);
  std::string outcome;
  if (kept)
    outcome = "kept " + point + ", play " + formatPlaySet(r.best_set) + " (x" + formatNumber(b.channel_scale) +
              "): " + scoreText(b.score) + " from " + scoreText(s0.score);
  else if (b.score > s0.score + 1e-9)
    outcome = "best point (" + point + ", x" + formatNumber(b.channel_scale) + ", " + scoreText(b.score) + " from " +
              scoreText(s0.score) + ") not kept";
  else
    outcome = "no better point than the choice above (" + scoreText(s0.score) + ")";
  const auto& sim = r.rep.refine_simulation;
  if (sim.first != 0.0 || sim.second != 0.0)
    outcome += "; held-out simulation " + scoreText(sim.second) + " against " + scoreText(sim.first);
  return "[5/5] refined jointly (" + std::to_string(r.rep.refine_evaluations) + " held-out scores over " + over +
         "; threshold x top level, coupling and softening x top level above it, channels x the chosen size): " +
         outcome;
}

}  // namespace

void IdentificationRun::refineJointly() {
  if (o.play_refine_evaluations <= 0) return;
  RefinementSpace space(*this, refinedDimensions(*this));
  if (space.dims().empty()) {
    if (input_side_chosen)
      say("[5/5] joint refinement: nothing to refine (no threshold, coupling, softening or play channel in the "
          "search)");
    return;
  }
  const Point& x0 = space.start();
  rep.refine_start = {x0[0], x0[1], x0[2], x0[3], best_score};
  rep.refine_best = rep.refine_start;
  beginScoring("the joint refinement", static_cast<std::size_t>(o.play_refine_evaluations));
  auto score = [&](const Point& free) {
    const Point v = space.full(free);
    space.apply(v);
    const double sc = crossValidated();
    ++rep.refine_evaluations;
    if (sc > rep.refine_best.score + 1e-9) rep.refine_best = {v[0], v[1], v[2], v[3], sc};
    if (rep.refine_evaluations % 10 == 0)
      say("[5/5] refining threshold, coupling, softening and channel size: " + std::to_string(rep.refine_evaluations) +
          " of at most " + std::to_string(o.play_refine_evaluations) + " scores, best " +
          scoreText(rep.refine_best.score));
    return std::isfinite(sc) ? sc : -1e6;
  };
  maximiseBobyqa(space, o.play_refine_evaluations, score);

  const Refinement& b = rep.refine_best;
  const bool keep = b.score > best_score + 1e-9 && simulationHolds(*this, space, b);
  if (keep) {
    best_score = b.score;
    best_set = space.scaledChannels(b.channel_scale);
  } else {
    space.restoreStaged();
  }
  say(refinementLine(*this, space, keep));
}

}  // namespace plsa::identify
