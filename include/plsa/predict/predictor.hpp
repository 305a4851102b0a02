// The real-time n-step-ahead predictor of a DIO-PWL-OBF model (method notes):
// update() once per tick with the measured inputs and outputs, predict() for
// yhat(k+1..k+H) from the measured y(k) and planned inputs. After
// construction neither allocates, locks, throws nor does I/O; they return
// status codes. A new model (same structure) can be installed from another
// thread while they run: it is adopted whole at the next update(), never torn.
#pragma once

#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

#include <Eigen/Dense>

#include "plsa/model/dio_pwl_obf_model.hpp"

namespace plsa {

/// Results of the real-time calls: 0 is OK; positive values accepted the
/// sample and say what else happened; negative values rejected it (state kept).
enum class PredictorStatus : int {
  kOk = 0,
  kTimeGap = 1,             ///< time jumped ahead: the filters restarted at rest at this sample
  kClockStepBack = 2,       ///< time went back for kClockStepSamples samples in a row: restarted at rest
  kNotFinite = -1,          ///< a NaN or Inf in the sample: rejected, state kept
  kInputOutOfRange = -2,    ///< an input outside the accepted range: rejected, state kept
  kTimeNotIncreasing = -3,  ///< time did not advance: rejected, state kept
  kHorizonTooLong = -5,     ///< horizon above the capacity set at construction
  kBadShape = -6,           ///< plan or output buffer of the wrong size
  kNotReady = -7,           ///< predict() before the first accepted sample
};

inline const char* toString(PredictorStatus s) {
  switch (s) {
    case PredictorStatus::kOk: return "ok";
    case PredictorStatus::kNotFinite: return "sample has NaN or Inf";
    case PredictorStatus::kInputOutOfRange: return "input outside the accepted range";
    case PredictorStatus::kTimeNotIncreasing: return "time did not increase";
    case PredictorStatus::kTimeGap: return "time gap: filters restarted";
    case PredictorStatus::kClockStepBack: return "clock stepped back: filters restarted";
    case PredictorStatus::kHorizonTooLong: return "horizon above capacity";
    case PredictorStatus::kBadShape: return "buffer of the wrong size";
    case PredictorStatus::kNotReady: return "no sample yet";
  }
  return "unknown";
}

/// Whether a status means the sample was taken (possibly with a restart).
inline bool accepted(PredictorStatus s) noexcept { return static_cast<int>(s) >= 0; }

/// Samples in a row, each later than the one before but all before the last
/// accepted time, after which the clock is taken to have stepped back (a wall
/// clock set back, or one sample stamped far in the future before them): the
/// filters restart at rest at the third. One stale or duplicated sample is
/// rejected; a clock that stands still never restarts anything.
inline constexpr int kClockStepSamples = 3;

/// Largest predict() capacity: setup tabulates every mode's power sums up to it
/// (100000 samples, about 21 min at 80 Hz: 8 MB per output for 2 inputs of 5 poles).
inline constexpr int kMaxPredictorHorizon = 100000;

struct PredictorOptions {
  int max_horizon = 400;         ///< capacity of predict(), preallocated
  double input_margin = 0.25;    ///< accepted inputs: model range widened by this share of it
  double max_gap_factor = 2.5;   ///< a time step above this many sample times is a gap
  bool simulate = false;         ///< free simulation: the output is never reset to a measurement
};

/// NP: poles per filter bank when every bank has the same number (fixed-size
/// fast path), or Eigen::Dynamic. update() and predict() belong to one
/// (real-time) thread; install() may be called from any other.
template <int NP = Eigen::Dynamic>
class Predictor {
 public:
  using BankMatrix = Eigen::Matrix<double, NP, NP>;
  using BankVector = Eigen::Matrix<double, NP, 1>;

  /// Validates and preallocates everything; throws std::invalid_argument.
  explicit Predictor(const DioPwlObfModel& model, const PredictorOptions& options = {})
      : options_(checked(options)), active_(makeSlot(model, nullptr, options_)),
        shape_(std::make_unique<Slot>(*active_)) {
    const Slot& s = *active_;
    const auto nu = static_cast<Eigen::Index>(s.n_u), nc = static_cast<Eigen::Index>(s.play.size());
    u_.setZero(nu);
    du_.setZero(nu);
    work_u_.setZero(nu);
    us_.setZero(nu);
    work_us_.setZero(nu);
    const Eigen::Index nodes = s.input_side ? s.node_partition.regionCount() : 0;
    node_w_.setZero(nodes);
    work_node_w_.setZero(nodes);
    next_node_w_.setZero(nodes);
    vc_.setZero(nc);
    work_vc_.setZero(nc);
    delta_.setZero(nc);
    x_.assign(s.A.size(), BankVector::Zero(s.bank_size));
    work_x_ = x_;
    tmp_.setZero(s.bank_size);
    y_.setZero(s.n_y);
    ym_.setZero(s.n_y);
    y_sim_.setZero(s.n_y);
    work_y_.setZero(s.n_y);
    dy_.setZero(s.n_y);
    for (int o = 0; o < s.n_y; ++o) blended_.emplace_back(Eigen::VectorXd::Zero(s.coef[0][static_cast<std::size_t>(o)].size()));
    mode_coef_.assign(static_cast<std::size_t>(s.n_y), Eigen::VectorXd::Zero(s.n_u * s.bank_size));
  }

  ~Predictor() {
    delete active_;
    delete pending_.exchange(nullptr);
    delete retired_.exchange(nullptr);
  }
  Predictor(const Predictor&) = delete;
  Predictor& operator=(const Predictor&) = delete;

  int inputCount() const noexcept { return shape_->n_u; }
  int outputCount() const noexcept { return shape_->n_y; }
  int maxHorizon() const noexcept { return options_.max_horizon; }
  /// True when held-input predictions run in modal coordinates (all poles
  /// real and distinct, well-conditioned bases); false: the cascade is stepped.
  bool heldPathIsModal() const noexcept { return active_->modal; }
  /// The model in force on the real-time thread (0 the first; each install adds 1).
  std::uint64_t modelId() const noexcept { return active_->id; }

  /// One tick: time (s), measured inputs (n_u) and outputs (n_y), any
  /// indexable vectors with size().
  template <class U, class Y>
  PredictorStatus update(double time_s, const U& u, const Y& y) noexcept {
    adoptPendingModel();
    const Slot& s = *active_;
    if (static_cast<int>(u.size()) != s.n_u || static_cast<int>(y.size()) != s.n_y) return PredictorStatus::kBadShape;
    if (!std::isfinite(time_s)) return PredictorStatus::kNotFinite;
    for (int j = 0; j < s.n_u; ++j) {
      if (!std::isfinite(u[j])) return PredictorStatus::kNotFinite;
      if (u[j] < s.accept_min || u[j] > s.accept_max) return PredictorStatus::kInputOutOfRange;
    }
    for (int o = 0; o < s.n_y; ++o)
      if (!std::isfinite(y[o])) return PredictorStatus::kNotFinite;
    if (s.frame == OutputFrame::kTipCartesian) {
      tipComponents(y[0], y[1], ym_(0), ym_(1));
    } else {
      for (int o = 0; o < s.n_y; ++o) ym_(o) = y[o];
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
      } else if (time_s - t_ > options_.max_gap_factor * s.sample_time) {
        samples_ = 0;  // restart at rest from this sample, as after construction
        status = PredictorStatus::kTimeGap;
      }
    }
    if (samples_ == 0) {
      for (auto& x : x_) x.setZero();
      for (int j = 0; j < s.n_u; ++j) u_(j) = u[j];
      us_ = u_;  // the schedule's lag starts settled
      const double positive_sum = positiveSumAbove(u_, s.threshold);
      for (std::size_t c = 0; c < s.play.size(); ++c)
        vc_(static_cast<Eigen::Index>(c)) =
            playStartState(coupledLevel(levelAbove(u_(s.channel_input[c]), s.threshold), positive_sum, s.coupling,
                                        s.softening),
                           s.play[c], s.play_start);
      dir_ = DirectionState{};
      if (s.input_side) nodeWeights(s, us_, node_w_);
      y_ = y_sim_ = ym_;
      steer_reference_ = s.frame == OutputFrame::kTipCartesian ? y[1] : 0.0;
      t_ = time_s;
      samples_ = 1;
      behind_ = 0;
      return status;
    }
    if (options_.simulate) {  // the increment predicted for this sample, before it is consumed
      increments(s, x_, us_, dir_, dy_);
      y_sim_ += dy_;
    }
    for (int j = 0; j < s.n_u; ++j) {
      du_(j) = u[j] - u_(j);
      u_(j) = u[j];
    }
    s.partition.updateDirections(du_, dir_);
    us_ = s.schedule_pole * us_ + (1.0 - s.schedule_pole) * u_;
    advance(s, x_, vc_, us_, node_w_, u_);
    y_ = ym_;
    if (s.frame == OutputFrame::kTipCartesian) steer_reference_ = y[1];
    t_ = time_s;
    ++samples_;
    behind_ = 0;
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
    const PredictorStatus status = predictInModelFrame(horizon, plan, out);
    if (status != PredictorStatus::kOk || active_->frame != OutputFrame::kTipCartesian) return status;
    double reference = steer_reference_;
    for (int h = 0; h < horizon; ++h) {
      tipAngles(out(h, 0), out(h, 1), reference, out(h, 0), out(h, 1));
      reference = out(h, 1);
    }
    return status;
  }

  /// Installs a model of the same structure (inputs, outputs, pole counts,
  /// play channels, partition, output frame) from any thread but the real-time one. It
  /// allocates, and throws std::invalid_argument on a structure mismatch. The
  /// real-time thread adopts it whole at its next update().
  void install(const DioPwlObfModel& model) {
    collectRetired();
    Slot* next = makeSlot(model, shape_.get(), options_);
    next->id = next_id_.fetch_add(1, std::memory_order_relaxed) + 1;
    delete pending_.exchange(next, std::memory_order_acq_rel);  // a newer model replaces one never adopted
  }
  /// Frees a model the real-time thread has let go of (install() does this too).
  void collectRetired() { delete retired_.exchange(nullptr, std::memory_order_acq_rel); }

 private:
  // predict() in the model's output frame.
  PredictorStatus predictInModelFrame(int horizon, const Eigen::Ref<const Eigen::MatrixXd>& plan,
                                      Eigen::Ref<Eigen::MatrixXd> out) noexcept {
    const Slot& s = *active_;
    if (samples_ == 0) return PredictorStatus::kNotReady;
    if (horizon < 1 || horizon > options_.max_horizon) return PredictorStatus::kHorizonTooLong;
    if (out.rows() < horizon || out.cols() != s.n_y || (plan.rows() > 0 && plan.cols() != s.n_u))
      return PredictorStatus::kBadShape;
    if (!plan.allFinite()) return PredictorStatus::kNotFinite;
    for (std::size_t b = 0; b < x_.size(); ++b) work_x_[b] = x_[b];
    work_y_ = options_.simulate ? y_sim_ : y_;
    // A held input keeps the schedule fixed only once its lag has settled.
    if (plan.rows() == 0 && us_ == u_) return predictHeld(s, horizon, out);
    work_u_ = u_;
    work_us_ = us_;
    work_vc_ = vc_;
    work_node_w_ = node_w_;
    DirectionState dir = dir_;
    for (int h = 0; h < horizon; ++h) {
      increments(s, work_x_, work_us_, dir, dy_);
      work_y_ += dy_;
      out.row(h) = work_y_.transpose();
      if (h + 1 == horizon) break;
      if (h < plan.rows()) {
        for (int j = 0; j < s.n_u; ++j) {
          du_(j) = plan(h, j) - work_u_(j);
          work_u_(j) = plan(h, j);
        }
        s.partition.updateDirections(du_, dir);
      }
      work_us_ = s.schedule_pole * work_us_ + (1.0 - s.schedule_pole) * work_u_;
      advance(s, work_x_, work_vc_, work_us_, work_node_w_, work_u_);
    }
    return PredictorStatus::kOk;
  }

  // An immutable, fully built model.
  struct Slot {
    std::uint64_t id = 0;
    int n_u = 0, n_y = 0;
    int bank_size = 0;
    OutputFrame frame = OutputFrame::kAsLogged;
    double sample_time = 0.0;
    double accept_min = 0.0, accept_max = 0.0;
    PwlPartition partition;
    std::vector<BankMatrix> A;
    std::vector<BankVector> B;
    // All poles real: each bank runs as its cascade of first-order all-pass
    // sections (method notes), about 4 flops a section instead of a dense row.
    bool cascade = false;
    std::vector<BankVector> xi, gain;
    std::vector<int> bank_channel;                  ///< bank -> play channel
    std::vector<std::vector<int>> banks_of_output;  ///< banks in regressor order
    std::vector<PlayChannel> play;                  ///< per channel
    PlayStart play_start = PlayStart::kRising;
    double coupling = 0.0;                          ///< coupledLevel's kappa
    double threshold = 0.0;                         ///< level the channels count from
    double softening = 0.0;                         ///< coupledLevel's softening
    double schedule_pole = 0.0;                     ///< lag of the scheduling inputs, per sample
    // Input side: one copy of every bank per grid node, fed the increments of
    // the node's weight times the played input; `partition` is then the single
    // region whose stacked coefficients weigh them all.
    bool input_side = false;
    PwlPartition node_partition;
    std::vector<int> bank_region;  ///< input side: bank -> grid node
    std::vector<int> channel_input;                 ///< per channel: its input
    std::vector<std::vector<Eigen::VectorXd>> coef;  ///< [region][output]
    // Held input, every bank diagonalisable with a well-conditioned basis:
    // the horizon runs in modal coordinates, where each mode is one multiply
    // a step and the increment a sum (exact algebra, not an approximation).
    bool modal = false;
    std::vector<BankMatrix> to_modal;                      ///< per bank: V^-1
    std::vector<int> mode_base;                            ///< per bank: first mode in its output's list
    std::vector<Eigen::VectorXd> mode_pole;                ///< [output]: n_u * bank_size eigenvalues
    std::vector<std::vector<Eigen::VectorXd>> modal_coef;  ///< [region][output]: coefficients times V
    std::vector<Eigen::MatrixXd> mode_sum;                 ///< [output]: row h = sum_{j<=h} lambda^j
  };

  // Largest condition number of an eigenvector basis we diagonalise with:
  // prediction error grows with it, and 1e5 keeps it near 1e-11.
  static constexpr double kMaxModalCondition = 1e5;

  static PredictorOptions checked(const PredictorOptions& o) {
    require(o.max_horizon >= 1 && o.max_horizon <= kMaxPredictorHorizon,
            "Predictor: max_horizon " + std::to_string(o.max_horizon) + " is outside 1.." +
                std::to_string(kMaxPredictorHorizon) + " samples");
    // Infinite values would switch the input-range or gap check off unannounced.
    require(std::isfinite(o.input_margin) && o.input_margin >= 0,
            "Predictor: input_margin must be finite and >= 0");
    require(std::isfinite(o.max_gap_factor) && o.max_gap_factor > 1,
            "Predictor: max_gap_factor must be finite and > 1");
    return o;
  }

  // Builds a slot; with `shape`, requires the same structure.
  static Slot* makeSlot(const DioPwlObfModel& m, const Slot* shape, const PredictorOptions& options) {
    m.validate();
    auto s = std::make_unique<Slot>();
    s->n_u = m.inputCount();
    s->n_y = m.outputCount();
    s->sample_time = m.sample_time_s;
    s->frame = m.output_frame;
    const double span = m.input_max - m.input_min, margin = options.input_margin;
    s->accept_min = std::isfinite(span) ? m.input_min - margin * span : -INFINITY;
    s->accept_max = std::isfinite(span) ? m.input_max + margin * span : INFINITY;
    s->input_side = m.schedule_side == ScheduleSide::kInput;
    s->partition = s->input_side ? PwlPartition::single() : m.partition;
    s->node_partition = m.partition;
    const int copies = s->input_side ? m.partition.regionCount() : 1;
    s->play_start = m.play_start;
    s->coupling = m.play_coupling;
    s->threshold = m.play_threshold;
    s->softening = m.play_softening;
    s->schedule_pole = m.schedulePole();
    std::vector<std::vector<int>> channels_of(static_cast<std::size_t>(s->n_u));
    for (int j = 0; j < s->n_u; ++j)
      for (const PlayChannel& r : m.input_play[static_cast<std::size_t>(j)]) {
        channels_of[static_cast<std::size_t>(j)].push_back(static_cast<int>(s->play.size()));
        s->play.push_back(r);
        s->channel_input.push_back(j);
      }
    s->banks_of_output.resize(static_cast<std::size_t>(s->n_y));
    bool all_real = true;
    for (int o = 0; o < s->n_y; ++o)
      for (int r = 0; r < copies; ++r)
        for (int j = 0; j < s->n_u; ++j) {
          const PoleSet& ps = m.poles[static_cast<std::size_t>(o)][static_cast<std::size_t>(j)];
          if (s->bank_size == 0) s->bank_size = ps.size();
          require(ps.size() == s->bank_size, "Predictor: every filter bank needs the same number of poles");
          if constexpr (NP != Eigen::Dynamic)
            require(ps.size() == NP, "Predictor<" + std::to_string(NP) + ">: the model's pole sets have " +
                                         std::to_string(ps.size()) + " poles");
          const ObfBank<> bank(ps);
          BankVector xi(ps.size()), gain(ps.size());
          bool real = ps.sections().size() == static_cast<std::size_t>(ps.size());  // no conjugate pair
          for (int i = 0; i < ps.size() && real; ++i) {
            xi(i) = ps.sections()[static_cast<std::size_t>(i)].pole.real();
            gain(i) = std::sqrt(1.0 - xi(i) * xi(i));
          }
          all_real = all_real && real;
          for (int c : channels_of[static_cast<std::size_t>(j)]) {
            s->A.push_back(bank.A());
            s->B.push_back(bank.B());
            s->xi.push_back(real ? xi : BankVector::Zero(ps.size()));
            s->gain.push_back(real ? gain : BankVector::Zero(ps.size()));
            s->bank_channel.push_back(c);
            s->bank_region.push_back(r);
            s->banks_of_output[static_cast<std::size_t>(o)].push_back(static_cast<int>(s->A.size()) - 1);
          }
        }
    s->cascade = all_real;
    s->coef = m.coefficients;
    if (s->input_side) {  // the nodes' coefficients stacked in bank order, as one region
      std::vector<Eigen::VectorXd> stacked;
      for (int o = 0; o < s->n_y; ++o) stacked.push_back(m.stackedCoefficients(o));
      s->coef = {stacked};
    }
    if (all_real) setUpModal(m, options.max_horizon, *s);
    if (shape) {
      const bool same = shape->n_u == s->n_u && shape->n_y == s->n_y && shape->bank_size == s->bank_size &&
                        shape->frame == s->frame &&
                        shape->bank_channel == s->bank_channel && shape->coef.size() == s->coef.size() &&
                        shape->partition.inputs() == s->partition.inputs() &&
                        shape->partition.scheduling() == s->partition.scheduling() &&
                        shape->partition.directionSplit() == s->partition.directionSplit() &&
                        shape->input_side == s->input_side && shape->bank_region == s->bank_region &&
                        shape->node_partition.inputs() == s->node_partition.inputs();
      require(same, "Predictor::install: the new model's structure differs from the running one");
      s->accept_min = shape->accept_min;
      s->accept_max = shape->accept_max;
    }
    return s.release();
  }

  // Diagonalises every bank (distinct real poles) when all bases are well
  // conditioned; otherwise the held path keeps stepping the cascade.
  static void setUpModal(const DioPwlObfModel& m, int max_horizon, Slot& s) {
    const Eigen::Index n = s.bank_size;
    std::vector<Eigen::MatrixXd> V(s.A.size());
    s.to_modal.resize(s.A.size());
    s.mode_base.resize(s.A.size());
    s.mode_pole.assign(static_cast<std::size_t>(s.n_y), Eigen::VectorXd::Zero(s.n_u * n));
    for (int o = 0; o < s.n_y; ++o)
      for (int b : s.banks_of_output[static_cast<std::size_t>(o)]) {
        const auto bb = static_cast<std::size_t>(b);
        const int j = s.channel_input[static_cast<std::size_t>(s.bank_channel[bb])];
        const PoleSet& ps = m.poles[static_cast<std::size_t>(o)][static_cast<std::size_t>(j)];
        Eigen::VectorXd lambda(n);
        for (Eigen::Index i = 0; i < n; ++i) lambda(i) = ps.sections()[static_cast<std::size_t>(i)].pole.real();
        for (Eigen::Index i = 0; i < n; ++i)
          for (Eigen::Index k = 0; k < i; ++k)
            if (lambda(i) == lambda(k)) return;  // repeated pole: a Jordan block, no eigenbasis
        // The cascade's A is lower triangular with the poles on its diagonal:
        // each eigenvector by forward substitution.
        const Eigen::MatrixXd A = s.A[bb];
        if (!A.template triangularView<Eigen::StrictlyUpper>().toDenseMatrix().isZero(0.0)) return;
        Eigen::MatrixXd v = Eigen::MatrixXd::Zero(n, n);
        for (Eigen::Index k = 0; k < n; ++k) {
          v(k, k) = 1.0;
          for (Eigen::Index i = k + 1; i < n; ++i)
            v(i, k) = A.row(i).segment(k, i - k).dot(v.col(k).segment(k, i - k)) / (lambda(k) - A(i, i));
          v.col(k).normalize();
        }
        const Eigen::MatrixXd vinv = v.inverse();
        if (!vinv.allFinite() || v.norm() * vinv.norm() > kMaxModalCondition) return;
        if ((v * lambda.asDiagonal() * vinv - A).cwiseAbs().maxCoeff() > 1e-9) return;  // guards the algebra, not rounding
        V[bb] = v;
        s.to_modal[bb] = vinv;
        s.mode_base[bb] = j * static_cast<int>(n);
        s.mode_pole[static_cast<std::size_t>(o)].segment(j * n, n) = lambda;
      }
    for (const Eigen::VectorXd& lambda : s.mode_pole) {
      Eigen::MatrixXd sum(max_horizon, lambda.size());
      Eigen::VectorXd power = Eigen::VectorXd::Ones(lambda.size());
      sum.row(0) = power.transpose();
      for (int h = 1; h < max_horizon; ++h) {
        power = power.cwiseProduct(lambda);
        sum.row(h) = sum.row(h - 1) + power.transpose();
      }
      s.mode_sum.push_back(std::move(sum));
    }
    s.modal_coef = s.coef;
    for (std::size_t r = 0; r < s.coef.size(); ++r)
      for (int o = 0; o < s.n_y; ++o) {
        const auto& banks = s.banks_of_output[static_cast<std::size_t>(o)];
        Eigen::VectorXd& mc = s.modal_coef[r][static_cast<std::size_t>(o)];
        const Eigen::VectorXd& c = s.coef[r][static_cast<std::size_t>(o)];
        for (std::size_t i = 0; i < banks.size(); ++i)
          mc.segment(static_cast<Eigen::Index>(i) * n, n) =
              V[static_cast<std::size_t>(banks[i])].transpose() * c.segment(static_cast<Eigen::Index>(i) * n, n);
      }
    s.modal = true;
  }

  // dy for the next sample from filter states x, scheduled on (u, dir): u is
  // the lagged input when the model has a schedule lag.
  void increments(const Slot& s, const std::vector<BankVector>& x, const Eigen::VectorXd& u,
                  const DirectionState& dir, Eigen::VectorXd& dy) const noexcept {
    ScheduleBlend blend;
    s.partition.blend(u, dir, blend);
    const Eigen::Index n = s.bank_size;
    for (int o = 0; o < s.n_y; ++o) {
      const auto& banks = s.banks_of_output[static_cast<std::size_t>(o)];
      double acc = 0.0;
      for (int m = 0; m < blend.count; ++m) {
        const Eigen::VectorXd& c =
            s.coef[static_cast<std::size_t>(blend.region[static_cast<std::size_t>(m)])][static_cast<std::size_t>(o)];
        double dot = 0.0;
        for (std::size_t i = 0; i < banks.size(); ++i) {
          const auto& xb = x[static_cast<std::size_t>(banks[i])];
          if constexpr (NP != Eigen::Dynamic)
            dot += c.template segment<NP>(static_cast<Eigen::Index>(i) * NP).dot(xb);
          else
            dot += c.segment(static_cast<Eigen::Index>(i) * n, n).dot(xb);
        }
        acc += blend.weight[static_cast<std::size_t>(m)] * dot;
      }
      dy(o) = acc;
    }
  }

  // x <- A x + B d for one bank.
  void stepBank(const Slot& s, std::size_t b, BankVector& x, double d) noexcept {
    if (s.cascade) {
      const BankVector& xi = s.xi[b];
      const BankVector& g = s.gain[b];
      double w = d;
      for (Eigen::Index i = 0; i < x.size(); ++i) {
        const double st = x(i);
        x(i) = xi(i) * st + g(i) * w;
        w = g(i) * st - xi(i) * w;
      }
      return;
    }
    tmp_.noalias() = s.A[b] * x;
    x = tmp_ + s.B[b] * d;
  }

  // Held input: the schedule and so the blended coefficients stay fixed over
  // the horizon, and the played inputs do not move (every delta is zero).
  PredictorStatus predictHeld(const Slot& s, int horizon, Eigen::Ref<Eigen::MatrixXd> out) noexcept {
    ScheduleBlend blend;
    s.partition.blend(u_, dir_, blend);
    if (s.modal && horizon > 2) return predictHeldModal(s, blend, horizon, out);  // its set-up costs about two steps
    for (int o = 0; o < s.n_y; ++o) {
      Eigen::VectorXd& c = blended_[static_cast<std::size_t>(o)];
      c.setZero();
      for (int m = 0; m < blend.count; ++m)
        c += blend.weight[static_cast<std::size_t>(m)] *
             s.coef[static_cast<std::size_t>(blend.region[static_cast<std::size_t>(m)])][static_cast<std::size_t>(o)];
    }
    const Eigen::Index n = s.bank_size;
    for (int h = 0; h < horizon; ++h) {
      for (int o = 0; o < s.n_y; ++o) {
        const auto& banks = s.banks_of_output[static_cast<std::size_t>(o)];
        const Eigen::VectorXd& c = blended_[static_cast<std::size_t>(o)];
        double dot = 0.0;
        for (std::size_t i = 0; i < banks.size(); ++i) {
          if constexpr (NP != Eigen::Dynamic)
            dot += c.template segment<NP>(static_cast<Eigen::Index>(i) * NP).dot(work_x_[static_cast<std::size_t>(banks[i])]);
          else
            dot += c.segment(static_cast<Eigen::Index>(i) * n, n).dot(work_x_[static_cast<std::size_t>(banks[i])]);
        }
        work_y_(o) += dot;
      }
      out.row(h) = work_y_.transpose();
      if (h + 1 == horizon) break;
      for (std::size_t b = 0; b < work_x_.size(); ++b) stepBank(s, b, work_x_[b], 0.0);
    }
    return PredictorStatus::kOk;
  }

  // With input held, x(k+h) = V diag(lambda)^h V^-1 x(k) per bank, so the
  // increment h steps ahead is sum_i c_i lambda_i^h with c the blended
  // coefficients times V, times the modal state; banks of one output that
  // share poles (an input and its played copies) share modes.
  PredictorStatus predictHeldModal(const Slot& s, const ScheduleBlend& blend, int horizon,
                                   Eigen::Ref<Eigen::MatrixXd> out) noexcept {
    const Eigen::Index n = s.bank_size;
    for (int o = 0; o < s.n_y; ++o) {
      const auto oo = static_cast<std::size_t>(o);
      Eigen::VectorXd& c = mode_coef_[oo];
      c.setZero();
      const auto& banks = s.banks_of_output[oo];
      for (std::size_t i = 0; i < banks.size(); ++i) {
        const auto b = static_cast<std::size_t>(banks[i]);
        tmp_.noalias() = s.to_modal[b] * work_x_[b];
        for (int m = 0; m < blend.count; ++m) {
          const Eigen::VectorXd& mc = s.modal_coef[static_cast<std::size_t>(blend.region[static_cast<std::size_t>(m)])][oo];
          if constexpr (NP != Eigen::Dynamic)
            c.template segment<NP>(s.mode_base[b]) +=
                blend.weight[static_cast<std::size_t>(m)] *
                mc.template segment<NP>(static_cast<Eigen::Index>(i) * NP).cwiseProduct(tmp_);
          else
            c.segment(s.mode_base[b], n) +=
                blend.weight[static_cast<std::size_t>(m)] * mc.segment(static_cast<Eigen::Index>(i) * n, n).cwiseProduct(tmp_);
        }
      }
    }
    for (int o = 0; o < s.n_y; ++o) {
      const auto oo = static_cast<std::size_t>(o);
      // y(k+1+h) = y(k) + sum_i c_i sum_{j<=h} lambda_i^j: one product with
      // a table built at set-up, vectorised over the horizon.
      auto column = out.col(o).head(horizon);
      column.noalias() = s.mode_sum[oo].topRows(horizon) * mode_coef_[oo];
      column.array() += work_y_(o);
    }
    return PredictorStatus::kOk;
  }

  // Dense node weights (input side) at the scheduling point us.
  void nodeWeights(const Slot& s, const Eigen::VectorXd& us, Eigen::VectorXd& w) const noexcept {
    ScheduleBlend blend;
    s.node_partition.blend(us, DirectionState{}, blend);
    w.setZero();
    for (int m = 0; m < blend.count; ++m)
      w(blend.region[static_cast<std::size_t>(m)]) += blend.weight[static_cast<std::size_t>(m)];
  }

  // Moves the played channels to the input u and steps every bank with its
  // increment; input side, the increment of its node's weight (at the lagged
  // input us; node_w holds the previous weights) times the channel.
  void advance(const Slot& s, std::vector<BankVector>& x, Eigen::VectorXd& vc, const Eigen::VectorXd& us,
               Eigen::VectorXd& node_w, const Eigen::VectorXd& u) noexcept {
    const double positive_sum = s.coupling != 0.0 ? positiveSumAbove(u, s.threshold) : 0.0;  // unused when uncoupled
    for (std::size_t c = 0; c < s.play.size(); ++c) {
      const auto cc = static_cast<Eigen::Index>(c);
      const double ui =
          coupledLevel(levelAbove(u(s.channel_input[c]), s.threshold), positive_sum, s.coupling, s.softening);
      const double next = s.play[c].follow(ui, vc(cc));
      delta_(cc) = next - vc(cc);
      vc(cc) = next;
    }
    if (!s.input_side) {
      for (std::size_t b = 0; b < x.size(); ++b) stepBank(s, b, x[b], delta_(s.bank_channel[b]));
      return;
    }
    nodeWeights(s, us, next_node_w_);
    for (std::size_t b = 0; b < x.size(); ++b) {
      const auto c = static_cast<Eigen::Index>(s.bank_channel[b]);
      const Eigen::Index r = s.bank_region[b];
      stepBank(s, b, x[b], next_node_w_(r) * vc(c) - node_w(r) * (vc(c) - delta_(c)));
    }
    node_w = next_node_w_;
  }

  void adoptPendingModel() noexcept {
    if (retired_.load(std::memory_order_acquire) != nullptr) return;  // the last one is not collected yet
    Slot* next = pending_.exchange(nullptr, std::memory_order_acq_rel);
    if (!next) return;
    retired_.store(active_, std::memory_order_release);
    active_ = next;
  }

  PredictorOptions options_;
  Slot* active_;                      // owned and read by the real-time thread only
  std::unique_ptr<const Slot> shape_;  // structure reference for install(); never changes
  std::atomic<Slot*> pending_{nullptr};
  std::atomic<Slot*> retired_{nullptr};
  std::atomic<std::uint64_t> next_id_{0};

  // Real-time state, all sized at construction.
  std::vector<BankVector> x_, work_x_;
  BankVector tmp_;
  Eigen::VectorXd node_w_, work_node_w_, next_node_w_;  // input side: node weights now, in predict(), next
  Eigen::VectorXd u_, du_, work_u_, us_, work_us_, vc_, work_vc_, delta_, y_, ym_, y_sim_, work_y_, dy_;
  std::vector<Eigen::VectorXd> blended_;    // per output, for held-input predictions
  std::vector<Eigen::VectorXd> mode_coef_;  // per output, modal held-input path
  DirectionState dir_;
  double t_ = 0.0;
  int behind_ = 0;             // samples in a row behind t_, each after the one before
  double behind_time_ = 0.0;
  double steer_reference_ = 0.0;  // tip_cartesian: the last measured steering angle
  std::int64_t samples_ = 0;
};

}  // namespace plsa
