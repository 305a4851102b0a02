// plsa's structure search after the paper's pipeline (identification_run.hpp):
// scheduling side and play channels, coupling, schedule lag, threshold and
// softening (threshold_search.cpp), the joint refinement
// (joint_refinement.cpp), sensor drift and the slow poles
// (slow_pole_search.cpp), each chosen by cross-validated held-out score; then
// the final fit.
#include <algorithm>
#include <cmath>

#include "identification_run.hpp"
#include "plsa/core/number_text.hpp"
#include "plsa/eval/dio_prediction.hpp"
#include "plsa/eval/paired_gain.hpp"
#include "plsa/identify/output_drift.hpp"
#include "plsa/eval/validation.hpp"

namespace plsa::identify {
namespace {

// Cross-validation scores rows of the training logs themselves, whose sensor
// the model's level is referenced to: no yaw to register, and the drift is
// taken out of the rows about that run's own mean time.
constexpr eval::SimulationStart kSameSession{0, false};

// Why a bank was not kept, for its stage's line: empty when it was.
std::string bankVerdict(bool significant, bool keep, double min_gain) {
  if (keep) return "";
  if (!significant) return ", under two standard errors";
  return ", under the least gain kept (" + formatNumber(min_gain) + ")";
}

}  // namespace

// The structures to choose from: each partition on the output side (the
// paper's), and the interpolated one on the input side too.
void IdentificationRun::listStructures() {
  for (std::size_t pi = 0; pi < partitions.size(); ++pi) {
    const bool interp = partitions[pi].scheduling() == Scheduling::kInterpolated;
    if (o.scheduling != SchedulingChoice::kInputSide)
      structures.push_back({pi, ScheduleSide::kOutput, interp ? "I" : "S"});
    if (interp && !o.direction_split &&
        (o.scheduling == SchedulingChoice::kInputSide || o.scheduling == SchedulingChoice::kAuto))
      structures.push_back({pi, ScheduleSide::kInput, "N"});
  }
  PLSA_CHECK(!structures.empty(), "identify: input-side scheduling cannot split by direction");
  PLSA_CHECK(!o.play_candidates.empty(), "identify: need at least one play channel set ({0} for none)");
  for (const auto& set : o.play_candidates) PLSA_CHECK(!set.empty(), "identify: a play channel set is empty");
  range.assign(static_cast<std::size_t>(ni), 0.0);
  for (int in_i = 0; in_i < ni; ++in_i)
    range[static_cast<std::size_t>(in_i)] = all_u.col(in_i).maxCoeff() - all_u.col(in_i).minCoeff();
}

const IdentificationRun::Structure* IdentificationRun::firstInputSide() const {
  const auto it = std::find_if(structures.begin(), structures.end(),
                               [](const Structure& st) { return st.side == ScheduleSide::kInput; });
  return it == structures.end() ? nullptr : &*it;
}

void IdentificationRun::applyStructure(const Structure& st) {
  model.partition = partitions[st.partition];
  model.schedule_side = st.side;
}

void IdentificationRun::applyPlay(const std::vector<PlayChannel>& set) {
  model.shaping.play.assign(static_cast<std::size_t>(ni), {});
  for (int in_i = 0; in_i < ni; ++in_i)
    for (const PlayChannel& c : set) {
      PLSA_CHECK(c.width >= 0 && std::isfinite(c.width) && c.slope >= 0 && std::isfinite(c.slope),
                 "identify: play widths and slopes must be finite and >= 0");
      model.shaping.play[static_cast<std::size_t>(in_i)].emplace_back(c.width * range[static_cast<std::size_t>(in_i)],
                                                                      c.slope);
    }
}

// Cross-validation folds (IdentifyOptions::cv_layout). Contiguous: every
// log cut into time blocks, each scored by a model fitted on the others.
// Interleaved: chunks dealt to the folds in turn, held-out rows weighted out;
// a search window's warm-up rows (sampleForSearch) in every fold's fit, scored
// in none.
// The fewest samples an interleaved cross-validation chunk holds.
constexpr double kMinChunkRows = 16.0;

void IdentificationRun::cutFolds() {
  PLSA_CHECK(o.play_selection_folds >= 2, "identify: cross-validation needs at least 2 folds");
  interleaved = o.cv_layout == CvLayout::kInterleaved;
  fold_groups = o.play_selection_folds;
  PLSA_CHECK(!interleaved || (std::isfinite(o.cv_chunk_s) && o.cv_chunk_s > 0),
             "identify: cross-validation chunks must last a positive, finite number of seconds");
  // Contiguous blocks hold out a stretch of the experiment, often a part of
  // the grid the other blocks never visit, so they score extrapolation and
  // favour structures that extrapolate rather than fit; interleaved chunks
  // leave every fold the whole grid.
  if (interleaved) {
    // Every log shorter than one chunk puts every sample in fold 0: the fold
    // fit leaving it out has nothing to fit. Refused, naming the option, when
    // a score needs the folds (interleavedFoldFits); folds beyond the data
    // are left out of the scores.
    Eigen::Index longest = 0;
    for (const auto& u : U) longest = std::max(longest, u.rows());
    const double chunk_rows = std::max(1.0, std::round(o.cv_chunk_s / dt));
    // Chunks of a few samples hold every scored sample out beside fitted
    // neighbours: the folds leak, and each score costs many times more.
    PLSA_CHECK(chunk_rows >= kMinChunkRows, "identify: --cv-chunk " + formatNumber(o.cv_chunk_s) + " s is " +
                                                formatNumber(chunk_rows) + " sample(s) at " + formatNumber(dt) +
                                                " s; give at least " + formatNumber(kMinChunkRows * dt) + " s (" +
                                                formatNumber(kMinChunkRows) + " samples)");
    if (chunk_rows >= static_cast<double>(longest))
      unusable_folds = "identify: --cv-chunk " + formatNumber(o.cv_chunk_s) +
                       " s puts every sample in one cross-validation fold, leaving the others nothing to fit on: the "
                       "longest log (or search window) lasts " +
                       formatNumber(static_cast<double>(longest) * dt) + " s; give a chunk under that";
    // At most the longest log's rows: the same folds, and no conversion beyond int64.
    const auto chunk =
        static_cast<Eigen::Index>(std::min(chunk_rows, static_cast<double>(std::max<Eigen::Index>(1, longest))));
    for (std::size_t r = 0; r < U.size(); ++r) {
      Eigen::VectorXi f(U[r].rows());
      for (Eigen::Index k = 0; k < f.size(); ++k) f(k) = static_cast<int>((k / chunk) % o.play_selection_folds);
      if (r < warmup_rows.size() && warmup_rows[r] > 0) {
        f.head(warmup_rows[r]).setConstant(o.play_selection_folds);
        fold_groups = o.play_selection_folds + 1;
      }
      fold_rows.push_back(f);
    }
  }
  for (std::size_t r = 0; !interleaved && r < U.size(); ++r) {
    const Eigen::Index len = U[r].rows() / o.play_selection_folds;
    for (int f = 0; f < o.play_selection_folds; ++f) {
      const Eigen::Index b = f * len, n = f + 1 == o.play_selection_folds ? U[r].rows() - b : len;
      BU.push_back(U[r].middleRows(b, n));
      BY.push_back(Y[r].middleRows(b, n));
      BT.push_back(times[r].segment(b, n));
      fold_of.push_back(f);
    }
  }
  rep.play_scores.clear();
  FY = BY;    // per block
  FYlog = Y;  // per log
}

// Held-out fit of the model as configured now, averaged over outputs and
// folds: 40 steps ahead, or (input side) simulated from the model's level.
// Fits are always scored against the logged outputs; they are fitted to
// FY, the logged ones until a sensor drift is kept, or, with
// drift_per_fold, to each fold's own outputs less the drift estimated on them.
// On long logs a held-out score takes seconds and a stage minutes: after
// progress_interval_s without a line, one says where the search is.
double IdentificationRun::crossValidated(Score what) {
  const double score = crossValidatedOnce(what);
  ++scoring.done;
  if (std::chrono::duration<double>(Clock::now() - last_line).count() >= o.progress_interval_s)
    say("[5/5] scoring " + scoring.stage + ": " + std::to_string(scoring.done) +
        (scoring.total > 0 ? " of " + std::to_string(scoring.total) : std::string()) + " held-out fits, last " +
        scoreText(score));
  return score;
}

void IdentificationRun::beginScoring(std::string stage, std::size_t count) {
  scoring.stage = std::move(stage);
  scoring.done = 0;
  scoring.total = static_cast<int>(count);
}

// The regressors run over whole logs and do not depend on the fold: one pass
// sums every fold's terms, each fold's fit is a solve, and a second pass gives
// every fold's increments. Both passes stream the regressors a chunk at a
// time: a long log's would take gigabytes.
IdentificationRun::FoldFits IdentificationRun::interleavedFoldFits() {
  if (!unusable_folds.empty()) throw std::invalid_argument(unusable_folds);
  CoefficientSums sums;
  if (!drift_per_fold) sums = coefficientSums(model, U, FYlog, fold_rows, fold_groups);
  const auto folds = static_cast<std::size_t>(o.play_selection_folds);
  FoldFits ff{std::vector<DioPwlObfModel>(folds, model), std::vector<SampleWeights>(folds),
              std::vector<std::vector<Eigen::MatrixXd>>(folds, FYlog),
              std::vector<std::vector<Eigen::MatrixXd>>(folds)};
  const std::vector<Eigen::MatrixXd> FYm =
      fit_options.slow_mode.fractions_on_levels ? model.toModelFrame(FYlog) : std::vector<Eigen::MatrixXd>{};
  for (std::size_t f = 0; f < folds; ++f) {
    for (const Eigen::VectorXi& rows : fold_rows)
      ff.W[f].push_back((rows.array() != static_cast<int>(f)).cast<double>().matrix());
    if (drift_per_fold) {
      ff.TY[f] =
          removeOutputDrift(ff.TY[f], times, estimateOutputDrift(model, U, ff.TY[f], times, fit_options, 3, ff.W[f]));
      fitCoefficients(ff.fit[f], U, ff.TY[f], fit_options, ff.W[f]);
    }
  }
  if (!drift_per_fold) solveFoldCoefficients(ff.fit, sums, fit_options, {U, FYm, ff.W});
  for (std::size_t r = 0; r < U.size(); ++r) {
    std::vector<Eigen::MatrixXd> per_fold = eval::modelIncrements(ff.fit, U[r]);
    for (std::size_t f = 0; f < folds; ++f) ff.dy[f].push_back(std::move(per_fold[f]));
  }
  return ff;
}

double IdentificationRun::crossValidatedInterleaved(Score what) {
  const bool sim = what == Score::kSimulation;
  const int key = sim ? 0 : o.play_selection_horizon;
  FoldFits folds = interleavedFoldFits();
  double score = 0.0;
  int n = 0;
  fold_scores.clear();
  for (int f = 0; f < o.play_selection_folds; ++f) {
    const auto ff = static_cast<std::size_t>(f);
    DioPwlObfModel& fit = folds.fit[ff];
    const std::vector<Eigen::MatrixXd>& dys = folds.dy[ff];
    if (sim) fitOutputLevel(fit, U, folds.TY[ff], folds.W[ff], dys);
    // One fit per output over every held-out row of the fold, all logs together.
    std::vector<std::vector<double>> meas(static_cast<std::size_t>(no)), pred(static_cast<std::size_t>(no));
    for (std::size_t r = 0; r < U.size(); ++r) {
      if (U[r].rows() <= o.play_selection_horizon) continue;
      const std::vector<std::map<int, eval::AlignedPrediction>> p = eval::predictOutputs(
          fit, U[r], Y[r], sim ? std::vector<int>{} : std::vector<int>{key}, sim, dys[r], kSameSession);
      for (int out_i = 0; out_i < no; ++out_i) {
        const eval::AlignedPrediction& a = p[static_cast<std::size_t>(out_i)].at(key);
        for (Eigen::Index i = 0; i < a.values.size(); ++i)
          if (fold_rows[r](a.first + i) == f) {
            meas[static_cast<std::size_t>(out_i)].push_back(Y[r](a.first + i, out_i));
            pred[static_cast<std::size_t>(out_i)].push_back(a.values(i));
          }
      }
    }
    for (int out_i = 0; out_i < no; ++out_i) {
      const auto& m = meas[static_cast<std::size_t>(out_i)];
      if (m.size() < 2) {
        fold_scores.push_back(NAN);  // kept in place: the terms pair up by fold and output
        continue;
      }
      fold_scores.push_back(
          eval::nrmseFit(Eigen::Map<const Eigen::VectorXd>(m.data(), static_cast<Eigen::Index>(m.size())),
                         Eigen::Map<const Eigen::VectorXd>(pred[static_cast<std::size_t>(out_i)].data(),
                                                           static_cast<Eigen::Index>(m.size()))));
      score += fold_scores.back();
      ++n;
    }
  }
  model = std::move(folds.fit.back());  // as a fold-by-fold refit leaves it: the last fold's fit
  return score / std::max(1, n);
}

double IdentificationRun::crossValidatedContiguous(Score what) {
  double score = 0.0;
  int n = 0;
  fold_scores.clear();
  for (int f = 0; f < o.play_selection_folds; ++f) {
    std::vector<Eigen::MatrixXd> TU, TY;
    std::vector<Eigen::VectorXd> TT;
    for (std::size_t b = 0; b < BU.size(); ++b)
      if (fold_of[b] != f) {
        TU.push_back(BU[b]);
        TY.push_back(FY[b]);
        TT.push_back(BT[b]);
      }
    if (drift_per_fold) TY = removeOutputDrift(TY, TT, estimateOutputDrift(model, TU, TY, TT, fit_options));
    fitCoefficients(model, TU, TY, fit_options);
    if (what == Score::kSimulation) fitOutputLevel(model, TU, TY);
    for (std::size_t b = 0; b < BU.size(); ++b) {
      if (fold_of[b] != f || BU[b].rows() <= o.play_selection_horizon) continue;
      const bool sim = what == Score::kSimulation;
      const std::vector<std::map<int, eval::AlignedPrediction>> pred = eval::predictOutputs(
          model, BU[b], BY[b], sim ? std::vector<int>{} : std::vector<int>{o.play_selection_horizon}, sim,
          kSameSession);
      for (int out_i = 0; out_i < no; ++out_i, ++n) {
        fold_scores.push_back(eval::fitOf(
            BY[b].col(out_i), pred[static_cast<std::size_t>(out_i)].at(sim ? 0 : o.play_selection_horizon)));
        score += fold_scores.back();
      }
    }
  }
  return score / std::max(1, n);
}

// Step 7: coefficients, for each candidate set of play channels and each
// structure; keep the pair whose model predicts held-out data best k steps ahead.
void IdentificationRun::searchPlayAndScheduling() {
  rep.play_scores.clear();
  const auto known_scores = static_cast<std::size_t>(
      std::count_if(first_set_scores.begin(), first_set_scores.end(), [](const auto& v) { return v.has_value(); }));
  beginScoring("play channels and scheduling", structures.size() * o.play_candidates.size() - known_scores);
  for (std::size_t pi = 0; pi < structures.size(); ++pi)
    for (std::size_t si = 0; si < o.play_candidates.size(); ++si) {
      const auto& set = o.play_candidates[si];
      applyStructure(structures[pi]);
      applyPlay(set);
      // The first set's score where the grid's level stage already has it (the same fit and folds).
      const bool known = si == 0 && pi < first_set_scores.size() && first_set_scores[pi];
      const double score = known ? first_set_scores[pi]->score : crossValidated();
      rep.play_scores.emplace_back(set, score);
      if (score > best_score + 1e-9) {
        best_score = score;
        best_terms = known ? first_set_scores[pi]->terms : fold_scores;
        best_set = set;
        best_structure = pi;
      }
    }
}

// Coupled channels, on the chosen scheduling: every play set again with
// each coupling (a fraction of the largest training input level, inverted).
void IdentificationRun::searchCoupling() {
  beginScoring("coupled play channels", o.play_coupling_candidates.size() * o.play_candidates.size());
  for (double c : o.play_coupling_candidates) {
    PLSA_CHECK(c >= 0 && std::isfinite(c), "identify: play couplings must be finite and >= 0");
    applyStructure(structures[best_structure]);
    model.shaping.coupling = c / top_level;
    for (const auto& set : o.play_candidates) {
      applyPlay(set);
      const double score = crossValidated();
      rep.coupling_scores.push_back({set, c, score});
      if (score > best_score + 1e-9) {
        best_score = score;
        best_terms = fold_scores;
        best_set = set;
        best_coupling = model.shaping.coupling;
      }
    }
  }
  model.shaping.coupling = best_coupling;
  applyStructure(structures[best_structure]);
  applyPlay(best_set);
  reportPlayChoice();
}

// Banks of plays on the chosen scheduling: each uncoupled and with the
// chosen coupling, against the set chosen so far (its held-out terms kept
// from when it was scored, or scored again). A bank multiplies the
// regressors of every later fit, so the best is kept only when it gains
// more than two standard errors over folds and outputs, a higher bar than
// the slow poles' and the drift's one, and more than play_bank_min_gain
// (docs/identification.md, "Banks of plays").
void IdentificationRun::searchPlayBank() {
  if (o.play_bank_candidates.empty()) return;
  std::vector<double> couplings = {0.0};
  if (best_coupling > 0) couplings.push_back(best_coupling);
  const bool rescore = best_terms.empty();
  beginScoring("banks of plays", (rescore ? 1 : 0) + o.play_bank_candidates.size() * couplings.size());
  applyStructure(structures[best_structure]);
  model.shaping.coupling = best_coupling;
  applyPlay(best_set);
  const double before = rescore ? crossValidated() : best_score;
  const std::vector<double> before_terms = rescore ? fold_scores : best_terms;
  struct Trial {
    std::vector<PlayChannel> bank;
    double coupling = 0.0, score = -INFINITY;
    std::vector<double> terms;
  } best;
  for (const auto& bank : o.play_bank_candidates)
    for (const double c : couplings) {
      model.shaping.coupling = c;
      applyPlay(bank);
      const double score = crossValidated();
      rep.play_bank_scores.push_back({bank, c * top_level, score});
      if (score > best.score + 1e-9) best = {bank, c, score, fold_scores};
    }
  rep.play_bank_gain = eval::pairedGain(best.terms, before_terms);
  const bool significant = rep.play_bank_gain.first > 2.0 * rep.play_bank_gain.second;
  const bool keep = significant && rep.play_bank_gain.first > o.play_bank_min_gain;
  if (keep) {
    rep.play_bank_kept = best.bank;
    best_score = best.score;
    best_set = best.bank;
    best_coupling = best.coupling;
  }
  model.shaping.coupling = best_coupling;
  applyPlay(best_set);
  std::string line = "[5/5] banks of plays (several widths per input, on the chosen scheduling): ";
  line += keep ? "kept " + formatPlaySet(best.bank) + (best.coupling > 0 ? " coupled" : "") : std::string("none kept");
  line += "; the best, " + formatPlaySet(best.bank) + ", " + gainText(rep.play_bank_gain) +
          bankVerdict(significant, keep, o.play_bank_min_gain) + " over " + scoreText(before) + " (" +
          perOutputGains(best.terms, before_terms, o.outputs) + "). Scores (coupling x top level{plays}):";
  for (const auto& b : rep.play_bank_scores)
    line += " " + fixedDecimals(b.coupling, 2) + formatPlaySet(b.set) + "->" + scoreText(b.score);
  say(line);
}

void IdentificationRun::reportPlayChoice() {
  if (o.play_candidates.size() * structures.size() > 1) {
    const bool chosen_interp = model.partition.scheduling() == Scheduling::kInterpolated;
    const bool chosen_input = model.schedule_side == ScheduleSide::kInput;
    std::string s = std::string("[5/5] chosen by ") + std::to_string(o.play_selection_horizon) +
                    "-step fit on held-out " + std::string(interleaved ? "chunks" : "blocks") + ": " +
                    (chosen_input    ? "input-side interpolated"
                     : chosen_interp ? "interpolated"
                                     : "switched") +
                    " scheduling, play channels " + formatPlaySet(best_set) +
                    " (widths: fractions of each input's range; u: of its level). Scores (I interpolated, "
                    "S switched, N input side):";
    std::size_t i = 0;
    for (const auto& [f, sc] : rep.play_scores)
      s += std::string(" ") + structures[i++ / o.play_candidates.size()].tag + formatPlaySet(f) + "->" + scoreText(sc);
    say(s);
  }
  if (!rep.coupling_scores.empty()) {
    std::string s = "[5/5] coupled to the other inputs (kappa x top level): ";
    s += best_coupling > 0 ? "kept " + fixedDecimals(best_coupling * top_level, 2) : std::string("none kept");
    s += ". Scores:";
    for (const auto& c : rep.coupling_scores)
      s += " " + fixedDecimals(c.coupling, 2) + formatPlaySet(c.set) + "->" + scoreText(c.score);
    say(s);
  }
}

// A lag on the scheduling inputs, on the chosen model: it moves the
// coefficients with the actuator's state rather than its command. Tried
// shortest first; a longer one is kept only for a gain of kScheduleLagTie fit
// points or more: scores within it read as a tie (100.00 for every lag on
// noise-free data kept the longest, 0.8 s), and a tie keeps the shorter lag.
void IdentificationRun::searchScheduleLag() {
  if (o.schedule_lag_candidates.empty()) return;
  constexpr double kScheduleLagTie = 0.01;
  std::vector<double> lags = o.schedule_lag_candidates;
  for (double lag : lags) PLSA_CHECK(lag >= 0 && std::isfinite(lag), "identify: schedule lags must be finite and >= 0");
  std::sort(lags.begin(), lags.end());
  double best_lag = 0.0;
  rep.schedule_lag_scores.emplace_back(0.0, best_score);
  beginScoring("scheduling lags", lags.size());
  for (double lag : lags) {
    model.schedule_lag_s = lag;
    const double score = crossValidated();
    rep.schedule_lag_scores.emplace_back(lag, score);
    if (score >= best_score + kScheduleLagTie) {
      best_score = score;
      best_lag = lag;
    }
  }
  model.schedule_lag_s = best_lag;
  std::string s = "[5/5] lag on the scheduling inputs: ";
  s += best_lag > 0 ? "kept " + formatNumber(best_lag) + " s" : std::string("none kept");
  s += ". Scores:";
  for (const auto& [lag, sc] : rep.schedule_lag_scores) s += " " + formatNumber(lag) + "s->" + scoreText(sc);
  say(s);
}

std::string perOutputGains(const std::vector<double>& a, const std::vector<double>& b,
                           const std::vector<std::string>& outputs) {
  const auto gains = eval::perOutputPairedGains(a, b, outputs.size());  // checks that they pair up
  std::string s;
  for (std::size_t out_i = 0; out_i < outputs.size(); ++out_i)
    s += (out_i ? ", " : "") + outputs[out_i] + " " + formatNumber(gains[out_i].first) + " +- " +
         formatNumber(gains[out_i].second);
  return s;
}

std::optional<IdentificationRun::HeldOutScore> IdentificationRun::searchOutputDrift() {
  // A sensor drift, on an input-side model: estimated on each fold's training
  // blocks and taken out of them; kept if the held-out simulation, scored
  // against the logged outputs, gains more than one standard error (as the
  // slow pole).
  Yfit = Y;
  std::optional<HeldOutScore> as_it_stands;
  if (model.schedule_side == ScheduleSide::kInput && o.output_drift != OutputDriftChoice::kOff) {
    beginScoring("sensor drift", 2);
    const double without = crossValidated(Score::kSimulation);
    const std::vector<double> without_scores = fold_scores;
    drift_per_fold = true;
    const double with = crossValidated(Score::kSimulation);
    drift_per_fold = false;
    rep.drift_scores = {without, with};
    rep.drift_gain = eval::pairedGain(fold_scores, without_scores);
    const auto [gain, se] = rep.drift_gain;
    const OutputDrift drift = estimateOutputDrift(model, U, Y, times, fit_options);
    std::string s = "[5/5] sensor drift over the training run: ";
    for (std::size_t oi = 0; oi < drift.rate.size(); ++oi)
      if (frame != OutputFrame::kTipCartesian || oi == 1)
        s += o.outputs[oi] + " " + formatNumber(drift.rate[oi]) + "/s ";
    rep.output_drift = drift;
    if (o.output_drift == OutputDriftChoice::kOn || gain > se) {
      rep.drift_taken_out = true;
      Yfit = removeOutputDrift(Y, times, drift);
      // Later stages fit to the outputs less the drift found on all of them.
      FYlog = Yfit;
      for (std::size_t b = 0, r = 0; !interleaved && r < U.size(); ++r) {
        const Eigen::Index len = U[r].rows() / o.play_selection_folds;
        for (int f = 0; f < o.play_selection_folds; ++f, ++b) FY[b] = Yfit[r].middleRows(f * len, BY[b].rows());
      }
      s += o.output_drift == OutputDriftChoice::kOn ? "taken out (forced on)" : "taken out";
    } else {
      s += "left in";
      as_it_stands = HeldOutScore{without, without_scores};
    }
    s += " (held-out simulation " + scoreText(without) + " as logged, " + scoreText(with) +
         " with it taken out: " + gainText({gain, se}) + (gain > se ? "" : ", within one standard error") + "; " +
         perOutputGains(fold_scores, without_scores, o.outputs) + ")";
    say(s);
  } else if (o.output_drift != OutputDriftChoice::kOff) {
    say("[5/5] sensor drift: not estimated (it needs input-side scheduling, where the level is a function of the "
        "inputs)");
  } else if (model.schedule_side == ScheduleSide::kInput) {
    say("[5/5] sensor drift: not estimated (output drift off: the outputs as logged; 'auto' (--output-drift "
        "auto) estimates a drift linear in time and keeps it when held-out simulation gains)");
  }
  return as_it_stands;
}

// The chosen structure fitted on all the training data.
DioPwlObfModel IdentificationRun::fitFinal() {
  rep.coefficients = fitCoefficients(model, U, Yfit, fit_options);
  // An input-side model's level is a function of its inputs: simulate from it.
  if (model.schedule_side == ScheduleSide::kInput) fitOutputLevel(model, U, Yfit);
  if (rep.drift_taken_out) {
    model.training_drift_per_s = rep.output_drift.rate;
    model.training_drift_reference_s = rep.output_drift.reference_time_s;
  }
  say("[5/5] coefficients: " + std::to_string(rep.coefficients.regions_fitted) + " regions fitted, " +
      std::to_string(rep.coefficients.regions_fallback) + " with too little data took their neighbours'");
  rep.slow_pole_fraction = rep.coefficients.slow_fraction;
  if (!rep.slow_pole_fraction.empty()) say(slowFractionLine());
  for (const auto& n : rep.coefficients.notes) say("      " + n);
  model.validate();
  return model;
}

}  // namespace plsa::identify
