// Step 7: the DIO-PWL-OBF coefficients by regularised least squares over all
// samples, each sample feeding its region's block. Each region is pulled
// toward the global linear solution; regions with too little data are
// reported and take their nearest fitted neighbours' coefficients.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Dense>

#include "plsa/eval/model_regressors.hpp"
#include "plsa/model/dio_pwl_obf_model.hpp"

namespace plsa::identify {

/// Input side: the slow poles every bank carries besides its own, their
/// coefficients tied to the rest (slow_mode_tie.hpp); none: every
/// coefficient free.
struct SlowModeTie {
  std::vector<double> poles;
  bool shared = true;  ///< one fraction per slow pole for every output, else one set per output
  /// Then choose the fractions by the training records' simulated level
  /// (slow_fraction_levels.hpp), where the fit is given its records.
  bool fractions_on_levels = false;
};

struct CoefficientFitOptions {
  double ridge = 1e-6;           ///< on the global solution, relative to the regressors' scale
  double pull_to_global = 1e-2;  ///< ridge of each region toward the global solution (relative)
  int min_samples_per_parameter = 4;
  SlowModeTie slow_mode;
};

struct CoefficientFitReport {
  int regions_fitted = 0;
  int regions_fallback = 0;
  std::vector<std::string> notes;  ///< one line per fallback region, in words
  /// With tied slow poles: the fraction of the response that creeps through
  /// each, [output](slow pole) (all outputs equal when shared); empty otherwise.
  std::vector<Eigen::VectorXd> slow_fraction;
};

/// Per-sample weights of the least-squares terms, one vector per record
/// (T entries, >= 0); empty: every sample counts once. Weight 0 leaves a
/// sample out of the fit while the regressors still run through it, so held-out
/// stretches of a log keep the filters', lag's and play channels' states
/// continuous (identify's interleaved cross-validation).
using SampleWeights = std::vector<Eigen::VectorXd>;

/// Fills model.coefficients and model.region_fits. The model's poles,
/// partition, inputs and outputs must be set; U[r], Y[r] are records (T x n),
/// Y in the log's frame (converted to the model's output_frame here).
CoefficientFitReport fitCoefficients(DioPwlObfModel& model, const std::vector<Eigen::MatrixXd>& U,
                                     const std::vector<Eigen::MatrixXd>& Y, const CoefficientFitOptions& options = {},
                                     const SampleWeights& weights = {});

/// The least-squares sums behind fitCoefficients, kept apart per group of
/// samples (cross-validation folds), so that a fit leaving one group out costs
/// a solve rather than another pass over the data.
struct CoefficientSums {
  struct Group {
    std::vector<std::vector<Eigen::MatrixXd>> G;  ///< [output][region] normal matrices (not input side)
    std::vector<std::vector<Eigen::VectorXd>> h;  ///< [output][region] right-hand sides (not input side)
    std::vector<Eigen::MatrixXd> J;               ///< [output] joint normal matrix (interpolated or input side)
    std::vector<Eigen::VectorXd> Jh;              ///< [output] its right-hand side
    std::vector<double> count;                    ///< [region] schedule weight of the samples
  };
  std::vector<Group> groups;
};

/// Sums over records whose regressors are given (modelRegressors(model, U[r])
/// of the model's current structure); sample k of record r joins group
/// group[r](k) in [0, groups). Y in the log's frame.
CoefficientSums coefficientSums(const DioPwlObfModel& model, const std::vector<eval::ModelRegressors>& regressors,
                                const std::vector<Eigen::MatrixXd>& Y, const std::vector<Eigen::VectorXi>& group,
                                int groups);

/// The same sums from the input records, their regressors made a chunk at a
/// time (eval::RegressorStream): memory of a chunk, not of the records.
CoefficientSums coefficientSums(const DioPwlObfModel& model, const std::vector<Eigen::MatrixXd>& U,
                                const std::vector<Eigen::MatrixXd>& Y, const std::vector<Eigen::VectorXi>& group,
                                int groups);

/// The training records behind a fit, for what sums cannot give: the
/// simulated level a tied fit's fractions are chosen on
/// (SlowModeTie::fractions_on_levels). Y in the model's output frame;
/// weights as fitCoefficients' (empty: every sample once).
struct LevelRecords {
  const std::vector<Eigen::MatrixXd>& U;
  const std::vector<Eigen::MatrixXd>& Y;
  const SampleWeights& weights;
};

/// fitCoefficients from sums made for the model's current structure, leaving
/// out group `leave_out` (-1: none). `levels`: the records the sums were
/// made from, weighted as the fit (group `leave_out` out), or null.
CoefficientFitReport solveCoefficients(DioPwlObfModel& model, const CoefficientSums& sums, int leave_out,
                                       const CoefficientFitOptions& options = {}, const LevelRecords* levels = nullptr);

/// The records behind cross-validation's fold fits: Y in the model's output
/// frame, and each fold's weights (its own group's samples weighted 0).
struct FoldRecords {
  const std::vector<Eigen::MatrixXd>& U;
  const std::vector<Eigen::MatrixXd>& Y;
  const std::vector<SampleWeights>& weights;
};

/// solveCoefficients for every fold at once: fits[f] (the model's current
/// structure) leaves out group f of the sums (groups past the last fold are
/// in every fit: a search window's warm-up). The same fits as one call per
/// fold, but tied slow fractions fitted on the level (SlowModeTie::
/// fractions_on_levels) simulate every fold in one pass per round.
std::vector<CoefficientFitReport> solveFoldCoefficients(std::vector<DioPwlObfModel>& fits, const CoefficientSums& sums,
                                                        const CoefficientFitOptions& options, const FoldRecords& folds);

/// Input-side models: output_level as the (weighted) mean of y - modelLevels
/// over the training samples, so that free simulation needs no measured start.
/// `increments`, when given, are modelIncrements(model, U[r]) for every record.
void fitOutputLevel(DioPwlObfModel& model, const std::vector<Eigen::MatrixXd>& U, const std::vector<Eigen::MatrixXd>& Y,
                    const SampleWeights& weights = {}, const std::vector<Eigen::MatrixXd>& increments = {});

/// Throws unless `weights` is empty or has one finite, non-negative weight per sample of every record.
void checkSampleWeights(const std::vector<Eigen::MatrixXd>& U, const SampleWeights& weights, const char* who);

}  // namespace plsa::identify
