// The real-time n-step-ahead predictor of a DIO-PWL-OBF model (method notes):
// update() once per tick with the measured inputs and outputs, predict() for
// yhat(k+1..k+H) from the measured y(k) and planned inputs. After
// construction neither allocates, locks, throws nor does I/O; they return
// status codes. The model runs in its compiled form (compiled_model.hpp),
// which several predictors may share; a new one of the same structure can be
// installed from another thread while they run: it is adopted whole at the
// next update(), never torn, and the filter states carry over.
//
// Filter states below kTinyState are flushed to zero at every step, so no
// history (a long hold, decaying modes) ever leaves subnormal numbers to
// slow the arithmetic down.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "plsa/model/dio_pwl_obf_model.hpp"
#include "plsa/predict/compiled_model.hpp"
#include "plsa/predict/filter_states.hpp"
#include "plsa/predict/held_lagged.hpp"
#include "plsa/predict/kernels.hpp"
#include "plsa/predict/merged_modes.hpp"
#include "plsa/predict/model_handoff.hpp"
#include "plsa/predict/model_step.hpp"
#include "plsa/predict/plan_sensitivity.hpp"
#include "plsa/predict/predictor_options.hpp"
#include "plsa/predict/sensor_yaw.hpp"
#include "plsa/predict/tip_readout.hpp"
#include "plsa/predict/tip_angles.hpp"

namespace plsa {

/// The predictor for any number of poles per bank. update() and predict()
/// belong to one (real-time) thread; install() may be called from any other.
class NStepPredictor {
 public:
  /// Compiles `model` (may throw std::invalid_argument) and preallocates everything.
  explicit NStepPredictor(const DioPwlObfModel& model, const PredictorOptions& options = {})
      : NStepPredictor(compileModel(model, options), options) {}
  /// Shares an already compiled model; `options` must be those it was compiled with.
  NStepPredictor(std::shared_ptr<const CompiledModel> model, const PredictorOptions& options)
      : options_(options), handoff_(model) {
    PLSA_CHECK(model != nullptr, "Predictor: no compiled model");
    PLSA_CHECK(model->max_horizon == options.max_horizon,
               "Predictor: the compiled model holds tables for another max_horizon");
    allocate(*model);
  }

  NStepPredictor(const NStepPredictor&) = delete;
  NStepPredictor& operator=(const NStepPredictor&) = delete;

  int inputCount() const noexcept { return model().n_u; }
  int outputCount() const noexcept { return model().n_y; }
  int maxHorizon() const noexcept { return options_.max_horizon; }
  /// True when the model runs in modal form (all poles real and distinct,
  /// well-conditioned bases); false: its banks are stepped as state-space filters.
  bool heldPathIsModal() const noexcept { return model().modal; }
  /// The model in force on the real-time thread (0 the first; each install adds 1).
  std::uint64_t modelId() const noexcept { return handoff_.currentId(); }
  /// Filter states that are subnormal numbers (always 0: states below
  /// kTinyState are flushed at every step; for tests and benchmarks).
  int subnormalStates() const noexcept {
    int n = 0;
    for (Eigen::Index i = 0; i < state_.size(); ++i) n += std::fpclassify(state_(i)) == FP_SUBNORMAL;
    return n;
  }
  /// The compiled model in force (real-time thread, or before it starts).
  const std::shared_ptr<const CompiledModel>& compiledModel() const noexcept { return handoff_.currentShared(); }

  /// One tick: time (s), measured inputs (n_u) and outputs (n_y), any
  /// indexable vectors with size().
  template <class U, class Y>
  PredictorStatus update(double time_s, const U& u, const Y& y) noexcept {
    const SubnormalsFlushed flushed;
    handoff_.adopt([this](const CompiledModel& from, const CompiledModel& to) {
      // The last sample's tip, read from `from`'s states (the states' part
      // now holds this sample's increment, which `to` adds): summed on from
      // here if `to` does not register afresh; anchored again when its window closes.
      if (readout_anchored_) lastTipFromStates(from);
      readout_anchored_ = false;
      carryFilterStates(from, to, state_, work_state_, step_.bankScratch());
      // A swapped-in tip model registers its own frame (SensorYaw::reregister).
      if (to.frame == OutputFrame::kTipCartesian && samples_ > 0 && to.yaw_window > 0)
        yaw_.reregister(to, ym_(0), ym_(1), yaw_tip_);
    });
    const CompiledModel& m = model();
    if (static_cast<int>(u.size()) != m.n_u || static_cast<int>(y.size()) != m.n_y) return PredictorStatus::kBadShape;
    if (!std::isfinite(time_s)) return PredictorStatus::kNotFinite;
    for (int j = 0; j < m.n_u; ++j) {
      if (!std::isfinite(u[j])) return PredictorStatus::kNotFinite;
      if (u[j] < accept_min_ || u[j] > accept_max_) return PredictorStatus::kInputOutOfRange;
    }
    for (int o = 0; o < m.n_y; ++o)
      if (!std::isfinite(y[o])) return PredictorStatus::kNotFinite;
    SteeringReference steering;
    if (m.frame == OutputFrame::kTipCartesian) {
      steering = SteeringReference::of(y[1], m.rad_per_angle_unit, m.angle_unit_per_rad);  // tipComponents' own
      ym_(0) = y[0] * steering.cos;
      ym_(1) = y[0] * steering.sin;
    } else {
      for (int o = 0; o < m.n_y; ++o) ym_(o) = y[o];
    }
    PredictorStatus status = PredictorStatus::kOk;
    if (samples_ > 0) {
      if (!(time_s > t_)) {
        // Count samples behind the last accepted time that advance among themselves.
        behind_ = behind_ > 0 && time_s > behind_time_ ? behind_ + 1 : 1;
        behind_time_ = time_s;
        if (behind_ < kClockStepSamples) return PredictorStatus::kTimeNotIncreasing;
        samples_ = 0;
        status = PredictorStatus::kClockStepBack;
      } else if (time_s - t_ > options_.max_gap_factor * m.sample_time) {
        samples_ = 0;  // restart at rest from this sample, as after construction
        status = PredictorStatus::kTimeGap;
      }
    }
    behind_ = 0;
    t_ = time_s;
    steer_reference_ = steering;
    if (samples_ == 0) {
      restart(m, u);
      return status;
    }
    consumeIncrement(m);
    for (int j = 0; j < m.n_u; ++j) {
      du_(j) = u[j] - u_(j);
      u_(j) = u[j];
    }
    m.partition.updateDirections(du_, dir_);
    ModelStep::lagSchedule(m, u_, us_);
    step_.advance(m, state_, vc_, us_, node_w_, u_, resting_);
    y_ = ym_;
    ++samples_;
    return status;
  }

  /// yhat(k+1..k+horizon) into the first `horizon` rows of out (n_y columns),
  /// from the measured y(k) (or the simulated output in simulation mode).
  /// `plan` row h holds the planned input u(k+1+h); with fewer rows than
  /// horizon-1 the last input is held (0 rows: hold u(k)).
  /// A tip_cartesian model answers in bending and steering, each predicted
  /// steering angle on the branch nearest the one before it (the first: the
  /// last measured).
  PredictorStatus predict(int horizon, const Eigen::Ref<const Eigen::MatrixXd>& plan,
                          Eigen::Ref<Eigen::MatrixXd> out) noexcept {
    const SubnormalsFlushed flushed;
    const PredictorStatus status = predictInModelFrame(horizon, plan, out);
    if (status == PredictorStatus::kOk) toLoggedFrame(horizon, out);
    return status;
  }

  /// The sensitivity of predict(horizon, plan, ...) to the plan:
  /// jacobian(h * n_y + o, s * n_u + j) = d yhat_o(k+1+h) / d plan(s, j), with
  /// the schedule frozen where it is now. So it is exact for the
  /// scheduled-linear model at the current schedule point: for a model of one
  /// region, and for any model while its schedule does not move; the play
  /// channels, their threshold, coupling and softening are followed along the
  /// plan (a play channel's derivative is 0 inside its band, and its edge's
  /// when the input sits on an edge, as a held input does). `plan` needs
  /// horizon - 1 rows, `jacobian` horizon * n_y rows and (horizon - 1) * n_u
  /// columns. A tip_cartesian model answers in bending and steering (through
  /// the angles at the predicted trajectory). Modal form, at most 8 outputs,
  /// 16 inputs and 64 play channels (kUnsupported otherwise); no allocation. `fill`: every entry, or only the rows each
  /// plan step moves (JacobianFill::kMovingRows, for a matrix zeroed once and
  /// passed every tick).
  PredictorStatus sensitivity(int horizon, const Eigen::Ref<const Eigen::MatrixXd>& plan,
                              Eigen::Ref<Eigen::MatrixXd> jacobian, JacobianFill fill = JacobianFill::kWhole) noexcept {
    const SubnormalsFlushed flushed;
    const CompiledModel& m = model();
    if (samples_ == 0) return PredictorStatus::kNotReady;
    if (!m.modal || m.n_y > 8 || m.n_u > kMaxSensitivityInputs ||
        m.play.size() > static_cast<std::size_t>(kMaxSensitivityChannels))
      return PredictorStatus::kUnsupported;
    if (horizon < 2 || horizon > options_.max_horizon) return PredictorStatus::kHorizonOutOfRange;
    const Eigen::Index steps = horizon - 1;
    if (plan.rows() != steps || plan.cols() != m.n_u || jacobian.rows() != horizon * m.n_y ||
        jacobian.cols() != steps * m.n_u)
      return PredictorStatus::kBadShape;
    auto nominal = sens_nominal_.topRows(horizon);
    const PredictorStatus status = predictInModelFrame(horizon, plan, nominal);  // checks the plan first
    if (status != PredictorStatus::kOk) return status;
    sensitivity_.compute(m, horizon, plan, us_, dir_, node_w_, vc_, nominal, yaw_.turn(), jacobian, fill);
    return PredictorStatus::kOk;
  }

  /// sensitivity(), and the prediction it is taken at (what predict(horizon,
  /// plan, ...) gives) into the first `horizon` rows of `predicted` (n_y
  /// columns): one planned prediction for both, where a controller would
  /// otherwise call predict() too.
  PredictorStatus sensitivity(int horizon, const Eigen::Ref<const Eigen::MatrixXd>& plan,
                              Eigen::Ref<Eigen::MatrixXd> jacobian, JacobianFill fill,
                              Eigen::Ref<Eigen::MatrixXd> predicted) noexcept {
    if (predicted.rows() < horizon || predicted.cols() != model().n_y) return PredictorStatus::kBadShape;
    const PredictorStatus status = sensitivity(horizon, plan, jacobian, fill);
    if (status != PredictorStatus::kOk) return status;
    const SubnormalsFlushed flushed;
    predicted.topRows(horizon) = sens_nominal_.topRows(horizon);
    toLoggedFrame(horizon, predicted);
    return status;
  }

  /// Installs a model of the same structure (inputs, outputs, pole counts,
  /// play channels, partition, output frame) from any thread but the
  /// real-time one. It compiles (allocates), and throws std::invalid_argument
  /// on a structure mismatch. The real-time thread adopts it whole at its
  /// next update(), the filter states carried into its bases.
  void install(const DioPwlObfModel& model) { install(compileModel(model, options_)); }
  /// The same with an already compiled model (shared, e.g. by many segments).
  /// Installs from several threads at once take turns (a lock on the
  /// install side only): the model offered last is the one adopted.
  void install(std::shared_ptr<const CompiledModel> model) {
    PLSA_CHECK(model != nullptr && sameStructure(*shape_, *model),
               "Predictor::install: the new model's structure differs from the running one");
    const std::lock_guard<std::mutex> one_at_a_time(install_mutex_);
    handoff_.offer(std::move(model), ++installs_);
  }
  /// Frees a model the real-time thread has let go of (install() does this too).
  void collectRetired() { handoff_.collect(); }

 private:
  const CompiledModel& model() const noexcept { return handoff_.current(); }

  void allocate(const CompiledModel& m) {
    shape_ = handoff_.currentShared();
    accept_min_ = m.accept_min;
    accept_max_ = m.accept_max;
    const auto nu = static_cast<Eigen::Index>(m.n_u), nc = static_cast<Eigen::Index>(m.play.size());
    for (Eigen::VectorXd* v : {&u_, &du_, &us_, &work_u_, &work_us_}) v->setZero(nu);
    for (Eigen::VectorXd* v : {&vc_, &work_vc_}) v->setZero(nc);
    for (Eigen::VectorXd* v : {&y_, &ym_, &y_sim_, &work_y_, &dy_}) v->setZero(m.n_y);
    const Eigen::Index nodes = m.input_side ? m.nodes : 0;
    for (Eigen::VectorXd* v : {&node_w_, &work_node_w_}) v->setZero(nodes);
    state_.setZero(m.states());
    work_state_.setZero(m.states());
    step_.allocate(m);
    const Eigen::Index modes = static_cast<Eigen::Index>(m.n_u) * m.n_y * m.poles;
    zeta_.setZero(modes);
    const Eigen::Index slots = m.modal && m.input_side ? static_cast<Eigen::Index>(m.n_u) * m.modal_form.block : 0;
    for (Eigen::VectorXd* v : {&merged_, &g_}) v->setZero(slots);  // the planned path: modes, levels
    held_lagged_.allocate(m);
    zeta_of_output_.setZero(modes);
    turn_.setZero(2 * static_cast<Eigen::Index>(options_.max_horizon));  // turns, then lengths
    sens_nominal_.setZero(options_.max_horizon, m.n_y);
    sensitivity_.allocate(m, options_.max_horizon);
  }

  // The first sample, or the first after a gap: filters at rest, channels and lag settled here.
  template <class U>
  void restart(const CompiledModel& m, const U& u) noexcept {
    state_.setZero();
    resting_.fill(true);
    for (int j = 0; j < m.n_u; ++j) u_(j) = u[j];
    us_ = u_;  // the schedule's lag starts settled
    const double positive_sum = m.shaping.positiveSum(u_);
    for (std::size_t c = 0; c < m.play.size(); ++c)
      vc_(static_cast<Eigen::Index>(c)) =
          playStartState(m.shaping.level(u_(m.channel_input[c]), positive_sum), m.play[c], m.shaping.start);
    dir_ = DirectionState{};
    if (m.input_side) ModelStep::nodeWeights(m, us_, node_w_);
    y_ = y_sim_ = ym_;
    restartSensorYaw(m);
    samples_ = 1;
  }

  // The sensor's yaw registered afresh from this sample (settledTip).
  void restartSensorYaw(const CompiledModel& m) noexcept {
    yaw_.configure(m);
    yaw_.restart();
    readout_anchored_ = false;
    if (m.yaw_window == 0) return;
    settledTip(m, node_w_, vc_, yaw_tip_);
    yaw_.add(yaw_tip_[0], yaw_tip_[1], ym_(0), ym_(1));
    if (!yaw_.windowOpen()) anchorReadout(m);
  }

  // The increment predicted for this sample, before it is consumed: for the
  // simulation, and for the model's tip while the sensor's yaw is registered
  // (past the window, the tip is read from the states on the samples
  // tracking reads instead, where the model allows: TipReadout).
  void consumeIncrement(const CompiledModel& m) noexcept {
    const bool window = yaw_.windowOpen(), read_out = readout_anchored_ && !window;
    const bool summing = yaw_.registering() && !read_out;
    if (options_.simulate || summing) step_.increments(m, state_, us_, dir_, dy_);
    if (options_.simulate) y_sim_ += dy_;
    if (summing) {
      yaw_tip_[0] += dy_(0);
      yaw_tip_[1] += dy_(1);
    } else if (read_out && yaw_.readsTip()) {
      readout_.read(readoutPart(m), yaw_tip_);
    }
    if (m.frame == OutputFrame::kTipCartesian) yaw_.add(yaw_tip_[0], yaw_tip_[1], ym_(0), ym_(1));
    if (window && !yaw_.windowOpen()) anchorReadout(m);
  }
  // The window has just closed on this sample (the tip summed to it): the
  // tip is read from the states from here on if tracking needs it, the model
  // allows it and no simulation sums the increments anyway.
  void anchorReadout(const CompiledModel& m) noexcept {
    readout_anchored_ = yaw_.tracking() && !options_.simulate && TipReadout::available(m);
    if (readout_anchored_) readout_.anchor(yaw_tip_, readoutPart(m));
  }
  // yaw_tip_ <- the last sample's tip: the one read now less this sample's increment.
  void lastTipFromStates(const CompiledModel& m) noexcept {
    readout_.read(readoutPart(m), yaw_tip_);
    step_.increments(m, state_, us_, dir_, dy_);
    yaw_tip_[0] -= dy_(0);
    yaw_tip_[1] -= dy_(1);
  }
  // TipReadout's states' part now (before this sample's step).
  const double* readoutPart(const CompiledModel& m) noexcept {
    step_.mergeModes(m, state_, us_, dir_, zeta_);
    TipReadout::statesPart(m, zeta_, node_w_, vc_, readout_part_);
    return readout_part_;
  }

  // predict() in the model's output frame.
  PredictorStatus predictInModelFrame(int horizon, const Eigen::Ref<const Eigen::MatrixXd>& plan,
                                      Eigen::Ref<Eigen::MatrixXd> out) noexcept {
    const CompiledModel& m = model();
    if (samples_ == 0) return PredictorStatus::kNotReady;
    if (horizon < 1 || horizon > options_.max_horizon) return PredictorStatus::kHorizonOutOfRange;
    if (out.rows() < horizon || out.cols() != m.n_y || (plan.rows() > 0 && plan.cols() != m.n_u))
      return PredictorStatus::kBadShape;
    if (const PredictorStatus taken = planStatus(plan); taken != PredictorStatus::kOk) return taken;
    work_y_ = options_.simulate ? y_sim_ : y_;
    // A held input keeps the schedule fixed once its lag has settled: every
    // mode then decays on its own, y(k+1+h) = y(k) + sum_q zeta_q sum_{s<=h} lambda_q^s.
    PredictorStatus status;
    const bool merged = m.modal && m.input_side && m.n_y <= 8;  // the merged paths keep outputs in fixed arrays
    if (plan.rows() == 0 && us_ == u_ && m.modal)
      status = predictSettled(m, horizon, out);
    else if (merged && plan.rows() == 0 && !m.modal_form.lag_sum.empty())
      status = predictHeldLagged(m, horizon, out);
    else if (merged::fits(m))
      status = predictMergedModes(m, horizon, plan, out);
    else
      status = predictStepByStep(m, horizon, plan, out);
    if (status == PredictorStatus::kOk && m.frame == OutputFrame::kTipCartesian)
      turnIncrements(yaw_.turn(), y_(0), y_(1), horizon, out);  // never turned in simulation mode
    if (status == PredictorStatus::kOk && !finiteEverywhere(out.topRows(horizon)))
      return PredictorStatus::kPredictionNotFinite;
    return status;
  }

  // A plan is taken as update() takes an input: finite, inside the accepted
  // range. One branch-free pass on the common path (a NaN fails both
  // comparisons, so it counts as outside); what is wrong is told apart only
  // when something is.
  PredictorStatus planStatus(const Eigen::Ref<const Eigen::MatrixXd>& plan) const noexcept {
    Eigen::Index inside = 0;
    for (Eigen::Index c = 0; c < plan.cols(); ++c) {
      const double* v = plan.col(c).data();
      for (Eigen::Index r = 0; r < plan.rows(); ++r)
        inside += static_cast<Eigen::Index>((v[r] >= accept_min_) & (v[r] <= accept_max_));
    }
    const bool finite_range = std::isfinite(accept_min_) && std::isfinite(accept_max_);
    if (inside == plan.size() && finite_range) return PredictorStatus::kOk;
    if (!finiteEverywhere(plan)) return PredictorStatus::kNotFinite;
    return inside == plan.size() ? PredictorStatus::kOk : PredictorStatus::kInputOutOfRange;
  }

  // A prediction's first `horizon` rows from the model's frame into the
  // logged one: a tip_cartesian model's components into bending and steering.
  void toLoggedFrame(int horizon, Eigen::Ref<Eigen::MatrixXd> out) noexcept {
    if (model().frame == OutputFrame::kTipCartesian)
      tipAnglesFromComponents(horizon, steer_reference_, turn_.data(), turn_.data() + options_.max_horizon, out);
  }

  // Input side, input held while its lagged schedule still moves: the modes
  // merged at the schedule now, then the closed form (held_lagged.hpp).
  PredictorStatus predictHeldLagged(const CompiledModel& m, int horizon, Eigen::Ref<Eigen::MatrixXd> out) noexcept {
    step_.mergeModes(m, state_, us_, dir_, zeta_);
    held_lagged_.run(m, zeta_, us_, u_, vc_, work_y_, horizon, out);
    return PredictorStatus::kOk;
  }

  PredictorStatus predictSettled(const CompiledModel& m, int horizon, Eigen::Ref<Eigen::MatrixXd> out) noexcept {
    const ModalForm& f = m.modal_form;
    step_.mergeModes(m, state_, u_, dir_, zeta_);
    for (int o = 0; o < m.n_y; ++o) {
      const auto& modes = f.modes_of_output[static_cast<std::size_t>(o)];
      auto zeta = zeta_of_output_.head(static_cast<Eigen::Index>(modes.size()));
      for (std::size_t t = 0; t < modes.size(); ++t) zeta(static_cast<Eigen::Index>(t)) = zeta_(modes[t]);
      auto column = out.col(o).head(horizon);
      column.setConstant(work_y_(o));
      const Eigen::MatrixXd& sums = f.power_sum[static_cast<std::size_t>(o)];
      accumulateMovingGroups(sums.data(), sums.rows(), horizon, m.n_u, m.poles, zeta.data(), column.data());
    }
    return PredictorStatus::kOk;
  }

  // The input for step h of a plan (held past its last row).
  void planStep(const CompiledModel& m, const Eigen::Ref<const Eigen::MatrixXd>& plan, int h,
                DirectionState& dir) noexcept {
    if (h < plan.rows()) {
      for (int j = 0; j < m.n_u; ++j) {
        du_(j) = plan(h, j) - work_u_(j);
        work_u_(j) = plan(h, j);
      }
      m.partition.updateDirections(du_, dir);
    }
    ModelStep::lagSchedule(m, work_u_, work_us_);
  }

  // Input side, modal: the copies merged once into one state per mode; each
  // step then drives every mode with the change of its scheduled level,
  // g = sum over the active nodes of w_r times the channels, zeta <- lambda
  // zeta + beta (g' - g). The modes run in padded blocks (ModalForm::block),
  // whose usual sizes get kernels with the size fixed at compile time.
  PredictorStatus predictMergedModes(const CompiledModel& m, int horizon, const Eigen::Ref<const Eigen::MatrixXd>& plan,
                                     Eigen::Ref<Eigen::MatrixXd> out) noexcept {
    const bool avx2 = predictorUsesAvx2();
    switch (m.modal_form.block) {
      case 4:
        return avx2 ? runMergedAvx2<4>(m, horizon, plan, out) : runMerged<4>(m, horizon, plan, out);
      case 8:
        return avx2 ? runMergedAvx2<8>(m, horizon, plan, out) : runMerged<8>(m, horizon, plan, out);
      case 12:
        return avx2 ? runMergedAvx2<12>(m, horizon, plan, out) : runMerged<12>(m, horizon, plan, out);
      case 16:
        return avx2 ? runMergedAvx2<16>(m, horizon, plan, out) : runMerged<16>(m, horizon, plan, out);
      case 20:
        return avx2 ? runMergedAvx2<20>(m, horizon, plan, out) : runMerged<20>(m, horizon, plan, out);
      case 24:
        return avx2 ? runMergedAvx2<24>(m, horizon, plan, out) : runMerged<24>(m, horizon, plan, out);
      default:
        return runMerged<0>(m, horizon, plan, out);
    }
  }

  template <int B>
  PredictorStatus runMerged(const CompiledModel& m, int horizon, const Eigen::Ref<const Eigen::MatrixXd>& plan,
                            Eigen::Ref<Eigen::MatrixXd> out) noexcept {
    return runMergedBody<B>(m, horizon, plan, out);
  }
  template <int B>
  PLSA_TARGET_AVX2 PredictorStatus runMergedAvx2(const CompiledModel& m, int horizon,
                                                 const Eigen::Ref<const Eigen::MatrixXd>& plan,
                                                 Eigen::Ref<Eigen::MatrixXd> out) noexcept {
    return runMergedBody<B>(m, horizon, plan, out);
  }

  // B: the block size, or 0 for any (read from the model): the modes merged
  // at the schedule now, laid out a block per input, then merged::runPlanned.
  template <int B>
  PLSA_ALWAYS_INLINE PredictorStatus runMergedBody(const CompiledModel& m, int horizon,
                                                   const Eigen::Ref<const Eigen::MatrixXd>& plan,
                                                   Eigen::Ref<Eigen::MatrixXd> out) noexcept {
    const ModalForm& f = m.modal_form;
    const int block = B > 0 ? B : f.block, per_input = m.n_y * m.poles;
    PLSA_DEBUG_ASSERT(block == f.block && block % 4 == 0 && per_input <= block && merged::fits(m));
    PLSA_DEBUG_ASSERT(merged_.size() == static_cast<Eigen::Index>(m.n_u) * block && g_.size() == merged_.size());
    step_.mergeModes(m, state_, us_, dir_, zeta_);
    merged_.setZero();
    for (int j = 0; j < m.n_u; ++j) merged_.segment(j * block, per_input) = zeta_.segment(j * per_input, per_input);
    merged::PlannedSchedule schedule(m, u_, us_, vc_);
    const merged::MergedStart start{merged_.data(), g_.data(), work_y_.data()};
    merged::runPlanned<B>(m, schedule, start, horizon, plan.data(), plan.outerStride(), plan.rows(), out.data(),
                          out.outerStride(), work_y_.data());
    return PredictorStatus::kOk;
  }

  // Any form: the filters stepped on a copy of the state, the schedule
  // re-blended at every step.
  PredictorStatus predictStepByStep(const CompiledModel& m, int horizon, const Eigen::Ref<const Eigen::MatrixXd>& plan,
                                    Eigen::Ref<Eigen::MatrixXd> out) noexcept {
    work_state_ = state_;
    work_u_ = u_;
    work_us_ = us_;
    work_vc_ = vc_;
    work_node_w_ = node_w_;
    DirectionState dir = dir_;
    std::array<bool, kMaxRestingInputs> work_resting = resting_;
    for (int h = 0; h < horizon; ++h) {
      step_.increments(m, work_state_, work_us_, dir, dy_);
      work_y_ += dy_;
      out.row(h) = work_y_.transpose();
      if (h + 1 == horizon) break;
      planStep(m, plan, h, dir);
      step_.advance(m, work_state_, work_vc_, work_us_, work_node_w_, work_u_, work_resting);
    }
    return PredictorStatus::kOk;
  }

  PredictorOptions options_;
  ModelHandOff<CompiledModel> handoff_;
  std::shared_ptr<const CompiledModel> shape_;  // the first model: structure reference for install()
  std::mutex install_mutex_;                    // install() side only: offers in turn, ids in offer order
  std::uint64_t installs_ = 0;                  // install() side only, under install_mutex_
  double accept_min_ = 0.0, accept_max_ = 0.0;  // the first model's: a swap does not move them

  // Real-time state, all sized at construction.
  Eigen::VectorXd state_, work_state_;  // filter states: modal z, or banks' x, in the model's form
  ModelStep step_;                      // one sample of the banks, and its workspace
  Eigen::VectorXd zeta_, merged_, g_, zeta_of_output_;
  std::array<bool, kMaxRestingInputs> resting_{};  // per input: its filter states are all zero
  HeldLaggedForm held_lagged_;                     // held input with a moving lag
  Eigen::VectorXd turn_;                           // tip frame: each predicted row's turn
  Eigen::MatrixXd sens_nominal_;                   // sensitivity(): the nominal prediction
  PlanSensitivity sensitivity_;
  Eigen::VectorXd node_w_, work_node_w_;  // input side: node weights now, in predict()
  Eigen::VectorXd u_, du_, work_u_, us_, work_us_, vc_, work_vc_, y_, ym_, y_sim_, work_y_, dy_;
  DirectionState dir_;
  double t_ = 0.0;
  int behind_ = 0;  // samples in a row behind t_, each after the one before
  double behind_time_ = 0.0;
  SteeringReference steer_reference_;  // tip_cartesian: the last measured steering angle
  SensorYaw yaw_;                      // tip_cartesian: the turn from the model's frame to the sensor's
  double yaw_tip_[2] = {0.0, 0.0};     // while registering: the model's tip, in its frame
  TipReadout readout_;                 // past the window: the tip from the states, where anchored
  bool readout_anchored_ = false;
  double readout_part_[2] = {0.0, 0.0};
  std::int64_t samples_ = 0;
};

}  // namespace plsa
