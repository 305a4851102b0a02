// Batch regressors, increments and levels of a DIO-PWL-OBF model over whole
// input records (model_regressors.hpp): offline only, the real-time
// predictor never runs them.
#include "plsa/eval/model_regressors.hpp"

#include <algorithm>
#include <exception>
#include <limits>

#include "plsa/core/parallel_for.hpp"
#include "plsa/core/simd.hpp"
#include "plsa/obf/obf_bank.hpp"

namespace plsa::eval {

namespace {

// Each sample's schedule: the blend of the inputs up to k-1 through the lag
// (which starts settled at the first input), with the directions of change.
// Input side: each sample's own lagged input instead (the output side's
// schedule of sample k+1).
std::vector<ScheduleBlend> scheduleSamples(const DioPwlObfModel& model, const Eigen::MatrixXd& u) {
  const PwlPartition& partition = model.partition;
  const double schedule_pole = model.schedulePole();
  const Eigen::Index T = u.rows();
  std::vector<ScheduleBlend> schedule(static_cast<std::size_t>(T));
  DirectionState dir;
  Eigen::RowVectorXd du = Eigen::RowVectorXd::Zero(u.cols());
  Eigen::RowVectorXd lagged = T > 0 ? u.row(0) : Eigen::RowVectorXd();
  for (Eigen::Index k = 0; k < T; ++k) {
    const Eigen::Index prev = k == 0 ? 0 : k - 1;
    if (k >= 2) du = u.row(k - 1) - u.row(k - 2);
    if (k >= 2) partition.updateDirections(du, dir);
    if (k >= 2) lagged = schedule_pole * lagged + (1.0 - schedule_pole) * u.row(prev);
    partition.blend(lagged, dir, schedule[static_cast<std::size_t>(k)]);
  }
  if (model.schedule_side != ScheduleSide::kInput) return schedule;
  for (Eigen::Index k = 0; k < T; ++k) {
    ScheduleBlend& b = schedule[static_cast<std::size_t>(k)];
    if (k + 1 < T)
      b = schedule[static_cast<std::size_t>(k + 1)];
    else if (k > 0)
      partition.blend((schedule_pole * lagged + (1.0 - schedule_pole) * u.row(k)).eval(), dir, b);
  }
  return schedule;
}

// Input side: the weight each node gives rows from .. to - 1, one column per
// node; row -1, before the record, weighs nothing.
Eigen::MatrixXd nodeWeights(const std::vector<ScheduleBlend>& schedule, Eigen::Index from, Eigen::Index to, int nodes) {
  Eigen::MatrixXd w = Eigen::MatrixXd::Zero(to - from, nodes);
  for (Eigen::Index k = std::max<Eigen::Index>(from, 0); k < to; ++k) {
    const ScheduleBlend& b = schedule[static_cast<std::size_t>(k)];
    for (int m = 0; m < b.count; ++m)
      w(k - from, b.region[static_cast<std::size_t>(m)]) += b.weight[static_cast<std::size_t>(m)];
  }
  return w;
}

// Channel inputs: input j's shaped level through each of its play channels.
std::vector<std::vector<Eigen::VectorXd>> channelInputs(const InputShaping& shaping, const Eigen::MatrixXd& u) {
  const auto n_u = static_cast<std::size_t>(u.cols());
  PLSA_CHECK(shaping.play.empty() || shaping.play.size() == n_u, "modelRegressors: need one play list per input");
  Eigen::MatrixXd coupled;
  const bool shaped = shaping.shapesLevels();
  if (shaped) {
    coupled.resize(u.rows(), u.cols());
    for (Eigen::Index k = 0; k < u.rows(); ++k) {
      const double positive_sum = shaping.positiveSum(u.row(k));
      for (Eigen::Index j = 0; j < u.cols(); ++j) coupled(k, j) = shaping.level(u(k, j), positive_sum);
    }
  }
  const Eigen::MatrixXd& level = shaped ? coupled : u;
  std::vector<std::vector<Eigen::VectorXd>> channels(n_u);
  for (std::size_t j = 0; j < n_u; ++j) {
    const std::vector<PlayChannel> list =
        shaping.play.empty() ? std::vector<PlayChannel>{PlayChannel{}} : shaping.play[j];
    for (const PlayChannel& ch : list)
      channels[j].push_back(playedInput(level.col(static_cast<Eigen::Index>(j)), ch, shaping.start));
  }
  return channels;
}

// The filter recursion over a chunk's rows: keeps each row's states (copies
// x n, state i of copy r at now[i * copies + r]) as a row of `history`, steps
// them by A and B with that row's input increments (step_in[k * copies + r]),
// then writes the history into the copies' columns of phi in blocks of rows,
// a cache line per column at a time (row by row, a chunk's columns lie 32 KB
// apart and every store would miss). Returns the buffer holding the states
// after the last row. Raw loops: at five or six states Eigen's dynamic
// expressions cost more than the arithmetic; the loops over the copies vectorise.
struct FilterRows {
  const double *A, *B;
  int n, copies;
  const double* step_in;
  Eigen::Index len;
  double *now, *then, *history, *col0;
  int width;
};

__attribute__((always_inline)) inline double* filterRowsBody(FilterRows f) {
  const int states = f.n * f.copies;
  for (Eigen::Index k = 0; k < f.len; ++k) {
    std::copy(f.now, f.now + states, f.history + k * states);
    const double* const in = f.step_in + k * f.copies;
    for (int i = 0; i < f.n; ++i) {
      double* const to = f.then + i * f.copies;
      for (int r = 0; r < f.copies; ++r) to[r] = f.B[i] * in[r];
      for (int l = 0; l < f.n; ++l) {
        const double c = f.A[i + l * f.n];
        if (c == 0.0) continue;
        const double* const from = f.now + l * f.copies;
        for (int r = 0; r < f.copies; ++r) to[r] += c * from[r];
      }
    }
    std::swap(f.now, f.then);
  }
  constexpr Eigen::Index kBlock = 64;
  for (Eigen::Index k0 = 0; k0 < f.len; k0 += kBlock) {
    const Eigen::Index rows = std::min(kBlock, f.len - k0);
    for (int i = 0; i < f.n; ++i)
      for (int r = 0; r < f.copies; ++r) {
        double* const to = f.col0 + (static_cast<Eigen::Index>(r) * f.width + i) * f.len + k0;
        const double* const from = f.history + k0 * states + i * f.copies + r;
        for (Eigen::Index t = 0; t < rows; ++t) to[t] = from[t * states];
      }
  }
  return f.now;
}

double* filterRowsGeneric(const FilterRows& f) { return filterRowsBody(f); }

// The same built for AVX2 without FMA (the products and sums round as in the
// generic build, so both give the same regressors bit for bit), chosen at run
// time where the processor has it.
#if PLSA_X86_DISPATCH
__attribute__((target("avx2"))) double* filterRowsAvx2(const FilterRows& f) { return filterRowsBody(f); }
double* filterRows(const FilterRows& f) { return simd::cpuHasAvx2() ? filterRowsAvx2(f) : filterRowsGeneric(f); }
#else
double* filterRows(const FilterRows& f) { return filterRowsGeneric(f); }
#endif

// One input channel's bank for one output, its states carried from chunk to
// chunk: a state row per copy (input side: per node).
struct ChannelFilter {
  ObfBank<> bank;
  const Eigen::VectorXd* channel = nullptr;  ///< the stream's shaped input
  int offset = 0;                            ///< first column within each copy's block
  Eigen::MatrixXd x, scratch;                ///< copies x n, before the chunk's first row
  Eigen::MatrixXd step_in;                   ///< copies x rows: the chunk's input increments
  Eigen::MatrixXd history;                   ///< copies * n x rows: the chunk's states, row by row

  // Rows a .. a + len - 1 into phi (len x width * copies); `weight` holds
  // each copy's weight of rows a - 1 .. a + len - 1 (input side) or is empty.
  void run(Eigen::Index a, Eigen::Index len, const Eigen::MatrixXd& weight, double* phi, int width) {
    const auto copies = static_cast<int>(x.rows());
    const Eigen::VectorXd& v = *channel;
    auto drive = [&](Eigen::Index k, int r) { return weight.size() == 0 ? v(k) : weight(k - a + 1, r) * v(k); };
    step_in.resize(copies, len);
    for (Eigen::Index k = a; k < a + len; ++k)
      for (int r = 0; r < copies; ++r) step_in(r, k - a) = k == 0 ? 0.0 : drive(k, r) - drive(k - 1, r);
    history.resize(static_cast<Eigen::Index>(copies) * bank.size(), len);
    const double* now =
        filterRows({bank.A().data(), bank.B().data(), bank.size(), copies, step_in.data(), len, x.data(),
                    scratch.data(), history.data(), phi + static_cast<Eigen::Index>(offset) * len, width});
    if (now != x.data()) x.swap(scratch);
  }
};

// One output's filters, the largest value each regressor column has reached,
// and (input side) the filters' settled states at the record's first sample.
struct OutputFilters {
  std::vector<ChannelFilter> filters;
  int width = 0;  ///< columns per copy
  Eigen::RowVectorXd column_max;
  Eigen::RowVectorXd level0;
};

// Input side: which tiles of a chunk move each copy's columns at all (the
// coefficient fit skips the rest), against the columns' largest values so far.
void markLiveTiles(const Eigen::MatrixXd& phi, int copies, Eigen::RowVectorXd& column_max,
                   Eigen::Array<bool, Eigen::Dynamic, Eigen::Dynamic>& live) {
  const Eigen::Index T = phi.rows(), tile = ModelRegressors::kTileRows;
  const Eigen::Index width = copies > 0 ? phi.cols() / copies : 0;
  live.resize((T + tile - 1) / tile, copies);
  if (T == 0) return;
  column_max = column_max.cwiseMax(phi.cwiseAbs().colwise().maxCoeff());
  const Eigen::RowVectorXd negligible = std::numeric_limits<double>::epsilon() * column_max;
  for (Eigen::Index t = 0; t < live.rows(); ++t)
    for (int r = 0; r < copies; ++r)
      live(t, r) = (phi.block(t * tile, static_cast<Eigen::Index>(r) * width, std::min(tile, T - t * tile), width)
                        .cwiseAbs()
                        .colwise()
                        .maxCoeff()
                        .array() > negligible.segment(static_cast<Eigen::Index>(r) * width, width).array())
                       .any();
}

}  // namespace

struct RegressorStream::State {
  bool input_side = false;
  int copies = 1;
  Eigen::Index T = 0, at = 0;
  bool empty_given = false;
  std::vector<ScheduleBlend> schedule;
  std::vector<std::vector<Eigen::VectorXd>> channels;  ///< [input][play channel]
  std::vector<OutputFilters> outputs;

  void fillOutput(OutputFilters& of, Eigen::Index a, Eigen::Index len, const Eigen::MatrixXd& weight,
                  ModelRegressors& chunk, std::size_t o) {
    Eigen::MatrixXd& phi = chunk.phi[o];
    phi.resize(len, static_cast<Eigen::Index>(of.width) * copies);
    for (ChannelFilter& f : of.filters) f.run(a, len, weight, phi.data(), of.width);
    if (!input_side) return;
    markLiveTiles(phi, copies, of.column_max, chunk.live[o]);
    chunk.level0[o] = of.level0;
  }

  // Input side: DC gain times the first sample's weighted input, per filter and copy.
  void settleAtFirstSample(OutputFilters& of) const {
    of.level0.setZero(static_cast<Eigen::Index>(of.width) * copies);
    if (!input_side || T == 0) return;
    const Eigen::MatrixXd w0 = nodeWeights(schedule, 0, 1, copies);
    for (const ChannelFilter& f : of.filters) {
      const Eigen::RowVectorXd gain = f.bank.transfer(1.0).real().transpose();
      for (int r = 0; r < copies; ++r)
        of.level0.segment(static_cast<Eigen::Index>(r) * of.width + f.offset, f.bank.size()) =
            gain * (w0(0, r) * (*f.channel)(0));
    }
  }
};

RegressorStream::RegressorStream(const DioPwlObfModel& model, const Eigen::MatrixXd& u)
    : state_(std::make_unique<State>()) {
  PLSA_CHECK(!model.poles.empty(), "modelRegressors: no outputs");
  PLSA_CHECK(u.allFinite(), "modelRegressors: the inputs contain NaN or Inf");
  for (const auto& row : model.poles)
    PLSA_CHECK(row.size() == static_cast<std::size_t>(u.cols()), "modelRegressors: need one pole set per input");
  State& s = *state_;
  s.input_side = model.schedule_side == ScheduleSide::kInput;
  s.copies = s.input_side ? model.partition.regionCount() : 1;
  s.T = u.rows();
  s.schedule = scheduleSamples(model, u);
  s.channels = channelInputs(model.shaping, u);
  for (const auto& row : model.poles) {
    OutputFilters of;
    for (std::size_t j = 0; j < row.size(); ++j)
      for (const Eigen::VectorXd& v : s.channels[j]) {
        ChannelFilter f;
        f.bank = ObfBank<>(row[j]);
        f.channel = &v;
        f.offset = of.width;
        f.x = Eigen::MatrixXd::Zero(s.copies, f.bank.size());
        f.scratch = f.x;
        of.width += f.bank.size();
        of.filters.push_back(std::move(f));
      }
    of.column_max = Eigen::RowVectorXd::Zero(static_cast<Eigen::Index>(of.width) * s.copies);
    s.settleAtFirstSample(of);
    s.outputs.push_back(std::move(of));
  }
}

RegressorStream::~RegressorStream() = default;
RegressorStream::RegressorStream(RegressorStream&&) noexcept = default;
RegressorStream& RegressorStream::operator=(RegressorStream&&) noexcept = default;

Eigen::Index RegressorStream::rows() const { return state_->T; }

bool RegressorStream::next(ModelRegressors& chunk, Eigen::Index max_rows) {
  State& s = *state_;
  if (s.at >= s.T && (s.T > 0 || s.empty_given)) return false;  // an empty record gives one empty chunk
  const Eigen::Index tile = ModelRegressors::kTileRows;
  const Eigen::Index step = max_rows >= s.T - s.at ? s.T - s.at : std::max(tile, max_rows / tile * tile);
  const Eigen::Index a = s.at, len = std::min(step, s.T - a);
  const std::size_t outputs = s.outputs.size();
  chunk.first_row = a;
  chunk.schedule.assign(s.schedule.begin() + a, s.schedule.begin() + a + len);
  chunk.phi.resize(outputs);
  chunk.level0.resize(s.input_side ? outputs : 0);
  chunk.live.resize(s.input_side ? outputs : 0);
  // Row 0 is row a - 1's weight.
  const Eigen::MatrixXd w = s.input_side ? nodeWeights(s.schedule, a - 1, a + len, s.copies) : Eigen::MatrixXd();
  // The outputs' regressors are independent: one thread each, when the chunk is long enough to pay for them.
  parallelFor(outputs, len >= 2048 ? static_cast<int>(outputs) : 1,
              [&](std::size_t o) { s.fillOutput(s.outputs[o], a, len, w, chunk, o); });
  s.at = a + len;
  s.empty_given = true;
  return true;
}

namespace {

void fillRegressors(ModelRegressors& out, const DioPwlObfModel& model, const Eigen::MatrixXd& u) {
  RegressorStream stream(model, u);
  stream.next(out, std::numeric_limits<Eigen::Index>::max());  // one chunk: the whole record
}

}  // namespace

ModelRegressors modelRegressors(const DioPwlObfModel& model, const Eigen::MatrixXd& u) {
  ModelRegressors out;
  fillRegressors(out, model, u);
  return out;
}

void modelRegressors(const DioPwlObfModel& model, const Eigen::MatrixXd& u, ModelRegressors& out) {
  fillRegressors(out, model, u);
}

namespace {

// Input side: each coefficient set's increments of output o into its dy's
// rows from `row0`, from the chunk's live tiles (all of phi when none are
// marked). Each tile is read once for every set while it is in cache; each
// set's sums are the same as alone.
void inputSideIncrements(const ModelRegressors& reg, int o, Eigen::Index width,
                         const std::vector<Eigen::VectorXd>& coefficients, const std::vector<Eigen::MatrixXd*>& dy,
                         Eigen::Index row0) {
  const auto oo = static_cast<std::size_t>(o);
  const auto T = static_cast<Eigen::Index>(reg.schedule.size());
  if (reg.live.empty()) {
    for (std::size_t m = 0; m < coefficients.size(); ++m)
      dy[m]->col(o).segment(row0, T).noalias() = reg.phi[oo] * coefficients[m];
    return;
  }
  const Eigen::Index tile = ModelRegressors::kTileRows;
  for (Eigen::MatrixXd* d : dy) d->col(o).segment(row0, T).setZero();
  for (Eigen::Index t = 0; t < reg.live[oo].rows(); ++t)
    for (Eigen::Index r = 0; r < reg.live[oo].cols(); ++r)
      if (reg.live[oo](t, r)) {
        const Eigen::Index rows = std::min(tile, T - t * tile);
        const auto block = reg.phi[oo].block(t * tile, r * width, rows, width);
        for (std::size_t m = 0; m < coefficients.size(); ++m)
          dy[m]->col(o).segment(row0 + t * tile, rows).noalias() += block * coefficients[m].segment(r * width, width);
      }
}

// Output side: the model's increments into dy's rows from `row0`.
void outputSideIncrements(const DioPwlObfModel& model, const ModelRegressors& reg, Eigen::MatrixXd& dy,
                          Eigen::Index row0) {
  const auto T = static_cast<Eigen::Index>(reg.schedule.size());
  for (Eigen::Index k = 0; k < T; ++k) {
    const ScheduleBlend& b = reg.schedule[static_cast<std::size_t>(k)];
    for (int o = 0; o < model.outputCount(); ++o) {
      double v = 0.0;
      for (int m = 0; m < b.count; ++m)
        v += b.weight[static_cast<std::size_t>(m)] *
             reg.phi[static_cast<std::size_t>(o)].row(k).dot(model.coefficients[static_cast<std::size_t>(
                 b.region[static_cast<std::size_t>(m)])][static_cast<std::size_t>(o)]);
      dy(row0 + k, o) = v;
    }
  }
}

// Every model's increments over the chunk into its dy's rows from the
// chunk's first row; the models differ only in their coefficients, whose
// stacked form (input side) is given per output.
void chunkIncrements(const std::vector<const DioPwlObfModel*>& models,
                     const std::vector<std::vector<Eigen::VectorXd>>& stacked, const ModelRegressors& reg,
                     const std::vector<Eigen::MatrixXd*>& dy, Eigen::Index row0) {
  const DioPwlObfModel& first = *models.front();
  for (const DioPwlObfModel* m : models)
    PLSA_CHECK(reg.phi.size() == static_cast<std::size_t>(m->outputCount()),
               "modelIncrements: the regressors were made for another model");
  if (first.schedule_side == ScheduleSide::kInput) {
    for (int o = 0; o < first.outputCount(); ++o)
      inputSideIncrements(reg, o, first.regressorSize(o), stacked[static_cast<std::size_t>(o)], dy, row0);
    return;
  }
  for (std::size_t m = 0; m < models.size(); ++m) outputSideIncrements(*models[m], reg, *dy[m], row0);
}

// Input side: each output's stacked coefficients of every model ([output][model]).
std::vector<std::vector<Eigen::VectorXd>> coefficientsPerOutput(const std::vector<const DioPwlObfModel*>& models) {
  std::vector<std::vector<Eigen::VectorXd>> stacked;
  if (models.front()->schedule_side != ScheduleSide::kInput) return stacked;
  for (int o = 0; o < models.front()->outputCount(); ++o) {
    stacked.emplace_back();
    for (const DioPwlObfModel* m : models) stacked.back().push_back(m->stackedCoefficients(o));
  }
  return stacked;
}

}  // namespace

Eigen::MatrixXd modelIncrements(const DioPwlObfModel& model, const ModelRegressors& reg) {
  const std::vector<const DioPwlObfModel*> one{&model};
  Eigen::MatrixXd dy(static_cast<Eigen::Index>(reg.schedule.size()), model.outputCount());
  std::vector<Eigen::MatrixXd*> out{&dy};
  chunkIncrements(one, coefficientsPerOutput(one), reg, out, 0);
  return dy;
}

Eigen::MatrixXd modelIncrements(const DioPwlObfModel& model, const Eigen::MatrixXd& u) {
  return std::move(modelIncrements(std::vector<DioPwlObfModel>{model}, u).front());
}

std::vector<Eigen::MatrixXd> modelIncrements(const std::vector<DioPwlObfModel>& models, const Eigen::MatrixXd& u) {
  PLSA_CHECK(!models.empty(), "modelIncrements: no model");
  for (const DioPwlObfModel& m : models)
    PLSA_CHECK(u.cols() == m.inputCount(), "modelIncrements: the record has " + std::to_string(u.cols()) +
                                               " inputs, the model " + std::to_string(m.inputCount()));
  std::vector<Eigen::MatrixXd> dy(models.size(), Eigen::MatrixXd(u.rows(), models.front().outputCount()));
  std::vector<Eigen::MatrixXd*> out;
  for (Eigen::MatrixXd& d : dy) out.push_back(&d);
  std::vector<const DioPwlObfModel*> each;
  for (const DioPwlObfModel& m : models) each.push_back(&m);
  const std::vector<std::vector<Eigen::VectorXd>> stacked = coefficientsPerOutput(each);
  RegressorStream stream(models.front(), u);
  ModelRegressors chunk;
  while (stream.next(chunk)) chunkIncrements(each, stacked, chunk, out, chunk.first_row);
  return dy;
}

Eigen::MatrixXd modelLevels(const DioPwlObfModel& model, const Eigen::MatrixXd& u, const Eigen::MatrixXd& dy) {
  PLSA_CHECK(model.schedule_side == ScheduleSide::kInput,
             "modelLevels: only an input-side model has a level that is a function of its inputs");
  PLSA_CHECK(u.rows() >= 1, "modelLevels: empty record");
  PLSA_CHECK(dy.rows() == u.rows() && dy.cols() == model.outputCount(),
             "modelLevels: increments do not match the record");
  // Settled states depend on the first sample alone (its schedule, played and coupled level).
  const ModelRegressors first = modelRegressors(model, u.topRows(1));
  Eigen::MatrixXd level(u.rows(), model.outputCount());
  for (int o = 0; o < model.outputCount(); ++o) {
    double acc = first.level0[static_cast<std::size_t>(o)].dot(model.stackedCoefficients(o));
    level(0, o) = acc;
    for (Eigen::Index k = 1; k < u.rows(); ++k) level(k, o) = acc += dy(k, o);
  }
  return level;
}

Eigen::MatrixXd modelLevels(const DioPwlObfModel& model, const Eigen::MatrixXd& u) {
  return modelLevels(model, u, modelIncrements(model, u));
}

}  // namespace plsa::eval
