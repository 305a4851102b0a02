// Batch regressors of a DIO-PWL-OBF model over whole input records, and
// the increments and levels they give: what identification, validation and
// the baselines run offline (the real-time predictor steps its own compiled
// form instead and never includes this).
#pragma once

#include <memory>
#include <vector>

#include <Eigen/Dense>

#include "plsa/model/dio_pwl_obf_model.hpp"

namespace plsa::eval {

/// OBF regressors of every output and the region of every sample, for an
/// input record u (T x n_u) starting at rest. At sample k the filters have
/// seen du_0..du_{k-1} and the region is scheduled on u_{k-1} (strictly causal).
/// Input side: phi holds every region's regressors side by side (T x
/// regions * regressorSize(o)), and the schedule of sample k is the weights
/// its own input gives the nodes. A RegressorStream's chunk holds rows
/// first_row .. first_row + rows - 1 of the record the same way (row i of phi,
/// schedule and live is the record's row first_row + i).
struct ModelRegressors {
  std::vector<Eigen::MatrixXd> phi;     ///< [output] T x regressorSize(o), or x regions times that
  std::vector<ScheduleBlend> schedule;  ///< [T] regions and weights
  Eigen::Index first_row = 0;           ///< the record's row of phi's first row
  /// Input side: [output] the filters' settled states at the record's first
  /// sample (DC gain times the first weighted input), laid out as phi's columns.
  std::vector<Eigen::RowVectorXd> level0;
  /// Input side: [output] for each tile of kTileRows samples and each node,
  /// whether any of the node's regressors there exceeds the rounding of its
  /// column's largest (machine epsilon times it). A node's regressors are zero
  /// until the input first nears it and decay once it leaves, so most tiles
  /// hold few live nodes; sums and products skip the rest. Empty: all live.
  static constexpr Eigen::Index kTileRows = 256;
  std::vector<Eigen::Array<bool, Eigen::Dynamic, Eigen::Dynamic>> live;
};

/// The regressors of a record a chunk of rows at a time, each chunk continuing
/// the filters' states of the one before: what a long record's least-squares
/// sums and increments run on, so that their memory does not grow with the
/// record (a whole record's regressors of an input-side model take kilobytes
/// per sample). The stream keeps the record's schedule and shaped inputs (a few
/// hundred bytes per sample) and copies of the banks; it holds no reference to
/// the model or the record. Chunks are whole tiles (kTileRows) but the last.
/// A tile counts as live (ModelRegressors::live) against the largest value its
/// columns have reached so far, so a chunk keeps at least the tiles a
/// whole-record pass keeps.
class RegressorStream {
 public:
  static constexpr Eigen::Index kChunkRows = 16 * ModelRegressors::kTileRows;

  RegressorStream(const DioPwlObfModel& model, const Eigen::MatrixXd& u);
  ~RegressorStream();
  RegressorStream(RegressorStream&&) noexcept;
  RegressorStream& operator=(RegressorStream&&) noexcept;

  Eigen::Index rows() const;
  /// The next chunk, at most max_rows rows (rounded down to whole tiles, at
  /// least one), into `chunk` (its storage reused when its shapes match);
  /// false, with `chunk` untouched, once every row has been given.
  bool next(ModelRegressors& chunk, Eigen::Index max_rows = kChunkRows);

 private:
  struct State;
  std::unique_ptr<State> state_;
};

/// One input through a play channel, starting as `start` says.
inline Eigen::VectorXd playedInput(const Eigen::VectorXd& u, const PlayChannel& ch, PlayStart start) {
  Eigen::VectorXd v = u;
  if (ch.passesThrough() || u.size() == 0) return v;
  v(0) = playStartState(u(0), ch, start);
  for (Eigen::Index k = 1; k < u.size(); ++k) v(k) = ch.follow(u(k), v(k - 1));
  return v;
}

/// The regressors of `model`'s own structure (poles, partition, input
/// shaping, lag and side) for an input record. An input without play
/// channels (shaping.play empty) takes one raw channel. Long records fill
/// each output's regressors on a thread of their own.
ModelRegressors modelRegressors(const DioPwlObfModel& model, const Eigen::MatrixXd& u);

/// The same into `out`, whose storage is reused when its shapes already match
/// (a long record's run to tens of megabytes).
void modelRegressors(const DioPwlObfModel& model, const Eigen::MatrixXd& u, ModelRegressors& out);

/// The model's predicted increments dyhat (T x n_y) from regressors of its
/// own structure (modelRegressors(model, u), or a RegressorStream's chunk:
/// then the chunk's rows), for reuse across coefficient sets.
Eigen::MatrixXd modelIncrements(const DioPwlObfModel& model, const ModelRegressors& reg);

/// The model's predicted increments dyhat (T x n_y) for an input record, its
/// regressors made a chunk at a time (RegressorStream).
Eigen::MatrixXd modelIncrements(const DioPwlObfModel& model, const Eigen::MatrixXd& u);

/// The increments of models that differ only in their coefficients (the
/// first's structure makes the regressors), from one pass over the record:
/// cross-validation's fold fits.
std::vector<Eigen::MatrixXd> modelIncrements(const std::vector<DioPwlObfModel>& models, const Eigen::MatrixXd& u);

/// Input side: the filtered part of the output's level, T x n_y, so that the
/// model's output is output_level + levels and levels(k) - levels(k-1) is the
/// increment dy(k). The filters start settled at the first input, so only the
/// first sample's regressors are needed beside `dy` = modelIncrements(model, u).
Eigen::MatrixXd modelLevels(const DioPwlObfModel& model, const Eigen::MatrixXd& u, const Eigen::MatrixXd& dy);

/// The same, the increments computed here.
Eigen::MatrixXd modelLevels(const DioPwlObfModel& model, const Eigen::MatrixXd& u);

}  // namespace plsa::eval
