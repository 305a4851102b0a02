// One identification (identifyModel) as a pipeline of named stages over a
// shared state: the data, the model being built, the cross-validation folds
// and the best choice so far. pipeline.cpp holds the paper's stages (data,
// local fits, poles, partitions; step_segments.cpp the step segments' fits),
// structure_search.cpp plsa's search over structures (joint_refinement.cpp
// its local search), each a function that reads and sets this state. Internal to the identify library.
#pragma once

#include <chrono>
#include <cmath>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Dense>

#include "plsa/core/number_text.hpp"
#include "plsa/identify/pipeline.hpp"
#include "plsa/model/dio_pwl_obf_model.hpp"

namespace plsa::identify {

/// A candidate value in a progress line (a width, lag, time constant): six
/// significant digits, 0.4, 0.15, 1.79e-05.
inline std::string formatNumber(double v) { return significantDigits(v, 6); }

/// A fit score in a progress line (percent): two decimals, -477.21.
inline std::string scoreText(double v) { return fixedDecimals(v, 2); }
/// A paired gain and its standard error in a progress line: "gains 0.13 +- 0.1".
inline std::string gainText(const std::pair<double, double>& gain) {
  return "gains " + formatNumber(gain.first) + " +- " + formatNumber(gain.second);
}
/// Each output's paired gain of held-out terms a over b, "name gain +- se"
/// joined by commas (the terms alternate by output within each fold).
std::string perOutputGains(const std::vector<double>& a, const std::vector<double>& b,
                           const std::vector<std::string>& outputs);

struct IdentificationRun {
  using Clock = std::chrono::steady_clock;
  enum class Score { kStepAhead, kSimulation };
  /// A held-out score and its terms (fold_scores when it was computed).
  struct HeldOutScore {
    double score = -INFINITY;
    std::vector<double> terms;
  };
  /// A partition and the side it schedules; tag as the progress lines print it.
  struct Structure {
    std::size_t partition;
    ScheduleSide side;
    const char* tag;
  };
  /// The scoring stage under way, for the progress lines.
  struct Scoring {
    std::string stage;
    int done = 0, total = 0;
  };

  IdentificationRun(const IdentifyOptions& options, IdentifyReport& report);
  DioPwlObfModel identify(const std::vector<io::Log>& logs);

  // The paper's stages (pipeline.cpp).
  void checkOptions(const std::vector<io::Log>& logs) const;
  void refuseRepeatedColumns() const;
  void readData(const std::vector<io::Log>& logs);
  OutputFrameChoice givenOutputFrame() const;
  void fitLocalModels(const std::vector<io::Log>& logs);
  void fitStepSegments(const std::vector<io::Log>& logs);  // step_segments.cpp
  void stepsFromPlateaus(const std::vector<io::Log>& logs);
  /// What local windows do for an output: nothing, give its poles (no usable
  /// step pole), or give a second pole candidate (too few to place a bank).
  enum class WindowUse { kNone, kInstead, kCandidate };
  std::vector<WindowUse> chooseWindows();
  std::string windowsNote() const;
  void fitLocalWindows(const std::vector<io::Log>& logs, const std::vector<WindowUse>& use);
  [[noreturn]] void noUsablePoles(int out_i) const;
  std::vector<std::complex<double>> uncertainPoles();
  void buildPartitions();
  /// The partition's grid: the staircase's reference levels per input, or,
  /// when the logs hold no designed levels, a quantile grid of
  /// quantile_levels levels over the moving inputs.
  struct GridPlan {
    bool designed = false;
    std::vector<std::vector<double>> levels;
    std::vector<int> moving;
    int quantile_levels = 0;
    bool scored = false;  ///< quantile_levels kept by held-out score (chooseGridLevels)
  };
  GridPlan gridPlan() const;
  std::vector<int> quantileInputs() const;
  int quantileLevels(std::size_t inputs) const;
  /// partitions (and the model's) for grid_plan, replacing any there are;
  /// `announce`: each partition's [4/5] line.
  void makePartitions(bool announce);
  // A quantile grid's level count by held-out score (grid_level_search.cpp).
  void chooseGridLevels();  // the second stage of the structure search
  std::vector<int> gridLevelCandidates() const;
  void setGridLevels(int levels, bool announce);
  GridLevelScore scoreGrid(int levels, std::vector<std::optional<HeldOutScore>>& by_structure);
  std::string gridLevelsLine(int kept, int automatic) const;
  static constexpr int kMaxRegions = 4096;  ///< a partition with more is refused (addPartition)

  // Pole selection (pole_selection.cpp): the local poles a pair clusters
  // (and how the progress line names them), and one method's basis poles for
  // every pair (model.poles' shape, and each pair's result in rep.pairs' order).
  struct PoleSource {
    std::vector<std::complex<double>> poles;
    const char* label;
  };
  /// Which local poles a candidate clusters.
  enum class PoleSourceKind {
    kSteps,               ///< PairPoles::identified (the windows' for an output without steps)
    kStepsAndWindows,     ///< and PairPoles::window_identified
    kSecondOrderWindows,  ///< an output without steps: PairPoles::window_second_order instead
  };
  struct PoleCandidate {
    PoleMethod method;
    PoleSourceKind kind;
    std::vector<std::vector<PoleSet>> poles;
    std::vector<ClusteringResult> chosen;
  };
  /// One clustered set of local poles, kept so that a later candidate with
  /// the same source poles (the windows' fallback, for outputs that are not
  /// short) reuses it instead of clustering and printing it again.
  struct ClusteredSet {
    PoleMethod method;
    std::vector<std::complex<double>> poles;
    ClusteringResult result;
  };
  std::vector<PoleSource> poleSources(PoleSourceKind kind);
  PoleCandidate clusterPairs(PoleMethod method, PoleSourceKind kind, const std::vector<PoleSource>& sources);
  bool secondOrderWindowsFitted() const;
  std::vector<PoleMethod> poleMethods() const;
  void selectPoles();
  void adoptPoles(const PoleCandidate& c);
  void choosePoleMethod();  // the first stage of the structure search
  double poleMethodScore(const Structure* input_side, PoleMethodScore& into);
  /// The best pole candidate so far and its score.
  struct PoleChoice {
    std::size_t best = 0;
    double fit = -INFINITY;
  };
  void scorePoleCandidates(const char* stage, const Structure* input_side, PoleChoice& choice);
  void addPoleCandidates(PoleSourceKind kind, const char* stage, const Structure* input_side, PoleChoice& choice);
  void addPartition(bool interpolated, const GridPlan& grid, bool announce);
  void requireDataForPartition(const PwlPartition& partition, const GridPlan& grid) const;
  std::string partitionLine(bool interpolated, const GridPlan& grid, const std::vector<int>& sched,
                            const std::vector<std::vector<double>>& bps) const;

  // The structure search (structure_search.cpp).
  void listStructures();
  void sampleForSearch();  // search_sample.cpp
  void cutFolds();
  void searchPlayAndScheduling();
  void searchCoupling();
  void searchPlayBank();
  void reportPlayChoice();
  void searchScheduleLag();
  void searchThreshold();
  void refineJointly();  // joint_refinement.cpp
  /// The model's held-out simulation score as the stage leaves it, where
  /// it has one (when it leaves the drift in).
  std::optional<HeldOutScore> searchOutputDrift();
  /// `as_it_stands`: the model's held-out simulation score, where known (the
  /// slow poles' "none", not scored again).
  void searchSlowPole(const std::optional<HeldOutScore>& as_it_stands);  // slow_pole_search.cpp
  struct SlowPoleTrial {
    double tau = 0.0;           ///< s; 0: none scored
    double score = -INFINITY;   ///< held-out simulation fit
    std::vector<double> terms;  ///< its held-out terms (fold_scores)
  };
  SlowPoleTrial bestSlowPoleBeside(const std::vector<double>& kept, const std::vector<double>& taus,
                                   std::vector<std::pair<double, double>>& scores);
  bool judgeSlowPole(const SlowPoleTrial& best, const std::vector<double>& base, std::pair<double, double>& gain,
                     std::string& line) const;
  void searchSecondSlowPole(const std::vector<double>& taus, const SlowPoleTrial& first);
  void setSlowPoles(const std::vector<double>& taus);
  std::string slowFractionLine() const;
  void restoreAllData();  // search_sample.cpp
  DioPwlObfModel fitFinal();

  // Scoring and the model's configuration.
  double crossValidated(Score what = Score::kStepAhead);
  double crossValidatedOnce(Score what) {
    return interleaved ? crossValidatedInterleaved(what) : crossValidatedContiguous(what);
  }
  double crossValidatedInterleaved(Score what);
  /// Interleaved: each fold's fit (the model as configured now, fitted to the
  /// other folds), the outputs it was fitted to, its weights and increments.
  struct FoldFits {
    std::vector<DioPwlObfModel> fit;
    std::vector<SampleWeights> W;
    std::vector<std::vector<Eigen::MatrixXd>> TY, dy;  ///< [fold][log]
  };
  FoldFits interleavedFoldFits();
  double crossValidatedContiguous(Score what);
  void beginScoring(std::string stage, std::size_t count);
  void applyStructure(const Structure& st);
  /// The first structure scheduled on the input side, or nullptr.
  const Structure* firstInputSide() const;
  void applyPlay(const std::vector<PlayChannel>& set);
  void stepResolution();
  void refuseStillColumns() const;
  void refuseUnfittableMagnitudes() const;
  void refuseRepeatedLogs(const std::vector<io::Log>& logs) const;
  static constexpr double kLargestFittable = 1e150;
  void say(const std::string& line);
  PairPoles& pairAt(int in_i, int out_i);

  const IdentifyOptions& o;
  IdentifyReport& rep;
  /// The coefficient fit's options: the caller's, and a tied slow pole while one is scored or kept.
  CoefficientFitOptions fit_options;
  Clock::time_point last_line;

  // The data: per log inputs, outputs as logged and in the model's frame,
  // step references and times; all logs stacked.
  std::vector<Eigen::MatrixXd> U, Y, Ym, Ref;
  std::vector<Eigen::VectorXd> times;
  double dt = 0.0;
  OutputFrame frame = OutputFrame::kAsLogged;
  Eigen::Index total = 0, min_len = 0;
  double step = 0.0;  ///< a reference change above this is a step (stepResolution)
  int ni = 0, no = 0;
  Eigen::MatrixXd all_ref, all_u;
  bool references_are_inputs = false;  ///< no commands logged or named: the inputs are the step references
  // Every log's inputs, outputs and times while the search runs on windows
  // of them (sampleForSearch; empty: it runs on every sample), and per
  // window the count of its first rows fitted but never scored.
  std::vector<Eigen::MatrixXd> all_U, all_Y;
  std::vector<Eigen::VectorXd> all_times;
  std::vector<Eigen::Index> warmup_rows;

  // The model being built, its pole sets to choose from and the structures it may take.
  DioPwlObfModel model;
  std::vector<PoleCandidate> pole_candidates;
  std::vector<ClusteredSet> clustered_sets;
  std::vector<PwlPartition> partitions;
  GridPlan grid_plan;  ///< the partitions' grid (buildPartitions; chooseGridLevels sets its level count)
  /// Per structure, the first play set's held-out score on the grid kept,
  /// where chooseGridLevels scored it (the play stage reuses it).
  std::vector<std::optional<HeldOutScore>> first_set_scores;
  std::vector<Structure> structures;
  std::vector<double> range;  ///< per input: its training range (play widths are fractions of it)
  double top_level = 1e-12;   ///< the largest training input level

  // Cross-validation: interleaved chunks (fold_rows) or contiguous blocks
  // (BU, BY, BT, fold_of); the outputs fitted per block (FY) and per log
  // (FYlog).
  bool interleaved = true;
  std::vector<Eigen::MatrixXd> BU, BY;
  std::vector<Eigen::VectorXd> BT;
  std::vector<int> fold_of;
  std::vector<Eigen::VectorXi> fold_rows;  ///< per row its fold, or fold_groups - 1 for a warm-up row
  int fold_groups = 0;                     ///< the folds, and one more when some rows are warm-up
  std::string unusable_folds;              ///< why the interleaved folds cannot be scored, or empty
  std::vector<Eigen::MatrixXd> FY, FYlog, Yfit;
  bool drift_per_fold = false;
  std::vector<double> fold_scores;  ///< the last held-out score's terms, per fold (or block) and output
  std::vector<std::vector<PoleSet>> poles_before_slow;  ///< the banks' poles before the slow pole search
  Scoring scoring;

  // The best choice so far.
  double best_score = -INFINITY;
  std::vector<double> best_terms;  ///< best_score's held-out terms, while the play stages choose (the bank's baseline)
  std::vector<PlayChannel> best_set;
  std::size_t best_structure = 0;
  double best_coupling = 0.0;
  bool input_side_chosen = false;
};

}  // namespace plsa::identify
