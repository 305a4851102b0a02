// The turn between a tip_cartesian model's frame and its sensor's on a run.
// Identification takes a drifting sensor yaw out of the training outputs,
// so the model's frame is the sensor's at the training run's mean time; on
// a new run the sensor's frame is another. SensorYaw registers the turn over
// the first samples after a start, as the least-squares rotation of the
// model's tip (its level: output_level, the settled response to the first
// sample and the increments since, turned at the training run's yaw drift)
// onto the measured tip, weighing each sample by how far the tip is from the
// axis, then turns on at that drift. A tip near the axis has no direction to
// register (at rest the reading is the sensor's noise and the model's rest
// tip, in directions that have nothing to do with the yaw): only samples whose
// measured tip is bent at least a minimum count, and unless they are half the
// window or more the training yaw is kept (no offset). Tracking (a
// forgetting factor under 1) keeps registering after the window on every
// kTrackEvery-th sample, each standing for that many and every earlier one's
// terms weighed down by the factor per sample, so the turn follows the sensor
// wherever its yaw goes instead of extrapolating the training run's drift
// without bound; the simulation keeps the window's offset (windowOffset). One value, shared by validation's simulation and k-step
// predictions and the real-time predictor, so the three agree; no allocation.
#pragma once

#include <algorithm>
#include <cmath>
#include <string>

#include <Eigen/Dense>

#include "plsa/predict/compiled_model.hpp"

namespace plsa {

/// Samples a registration of `seconds` spans at `sample_time` (at least one
/// when > 0; 0: none).
inline int yawRegistrationWindow(double seconds, double sample_time) noexcept {
  if (!(seconds > 0.0) || !(sample_time > 0.0)) return 0;
  const double n = std::round(seconds / sample_time);
  return n < 1.0 ? 1 : n > 1e9 ? 1000000000 : static_cast<int>(n);
}

class SensorYaw {
 public:
  /// Registers over `window` samples from each start (0: never, no turn at
  /// all), turning the model's tip `drift_per_sample` rad per sample from the
  /// start; `delay` samples after the start first (a run that does not start
  /// at rest: validation's SimulationStart::settle_s), turned by the drift
  /// alone. Samples whose measured tip is less than `min_bend` from the axis
  /// (the tip components' unit) are not registered on. `forget` in (0, 1):
  /// past the window the registration goes on, every earlier sample's terms
  /// weighed down by it per sample (trackingForget); 1 (or anything else):
  /// the window's offset holds and the drift alone turns on.
  void configure(int window, double drift_per_sample, long delay = 0, double min_bend = 0.0,
                 double forget = 1.0) noexcept {
    window_ = window;
    delay_ = delay > 0 ? delay : 0;
    min_bend2_ = min_bend > 0.0 ? min_bend * min_bend : 0.0;
    drift_ = drift_per_sample;
    step_ = {std::cos(drift_per_sample), std::sin(drift_per_sample)};
    forget_ = forget > 0.0 && forget < 1.0 ? forget : 1.0;
    forget_every_ = std::pow(forget_, static_cast<double>(kTrackEvery));
  }
  /// Configured for a compiled model's registration (no delay).
  void configure(const CompiledModel& m) noexcept {
    configure(m.yaw_window, m.yaw_drift_per_sample, 0, m.yaw_min_bend, m.yaw_forget);
  }
  /// A model swapped in: registers afresh for `m` from the next sample, the
  /// turn in force carrying on until its window registers one; `tip` <- the
  /// measured tip (x, y) turned back into the model's frame by that turn, the
  /// new model's tip to go on from (its level at the carried states is not
  /// known), so the old model's tip, drift and memory are not mixed in.
  void reregister(const CompiledModel& m, double x, double y, double tip[2]) noexcept {
    const Turn t = turn_;
    const double in_force = angle();
    tip[0] = t.cos * x + t.sin * y;
    tip[1] = -t.sin * x + t.cos * y;
    configure(m);
    restart(in_force);
  }
  /// A (re)start: the next sample is the start's. `initial`: the turn (rad)
  /// in force until the window registers one, and kept if it registers
  /// nothing (a model swap's: the turn the old model was at); 0 after a start.
  void restart(double initial = 0.0) noexcept {
    cross_ = dot_ = held_cross_ = held_dot_ = 0.0;
    offset_ = window_offset_ = initial_ = initial;
    offset_turn_ = initial == 0.0 ? Turn{} : Turn{std::cos(initial), std::sin(initial)};
    offset_tracked_ = false;
    bent_weight_ = weight_ = 0.0;
    samples_ = bent_ = 0;
    window_registered_ = false;
    turn_ = drift_turn_ = Turn{};
  }
  /// Whether it follows the sensor's yaw past the window (a forgetting factor under 1).
  bool tracking() const noexcept { return window_ > 0 && forget_ < 1.0; }
  /// Past the window a tracked sample is every this many (the first past it
  /// one): its terms count for that many samples.
  static constexpr long kTrackEvery = 8;
  /// Whether the next sample is the window's (or its delay's).
  bool windowOpen() const noexcept { return window_ > 0 && samples_ < delay_ + window_; }
  /// Whether add() reads the model's tip on some sample from the next on (the
  /// window is still open, or tracking).
  bool registering() const noexcept { return window_ > 0 && (tracking() || windowOpen()); }
  /// Whether add() reads the model's tip on the next sample: the window's, or a tracked one.
  bool readsTip() const noexcept {
    return windowOpen() || (tracking() && (samples_ - delay_ - window_) % kTrackEvery == 0);
  }
  /// The next sample: the model's tip (level_x, level_y), in its frame, and
  /// the measured one. Once the window is full the offset is set.
  void add(double level_x, double level_y, double x, double y) noexcept {
    const long k = samples_++;
    if (window_ == 0) return;
    advanceDrift(k);
    const bool past = samples_ > delay_ + window_;
    if (past && (!tracking() || (k - delay_ - window_) % kTrackEvery != 0)) return composeTurn();
    const double c = drift_turn_.cos, s = drift_turn_.sin;
    const double tx = c * level_x - s * level_y, ty = s * level_x + c * level_y;
    const bool bent = x * x + y * y >= min_bend2_;
    if (past) return trackSample(tx, ty, x, y, bent);  // readsTip() was true
    if (samples_ > delay_ && bent) {
      cross_ += tx * y - ty * x;
      dot_ += tx * x + ty * y;
      ++bent_;
    }
    // Until the window is full the drift's turn alone (no offset yet): angle()
    if (samples_ < delay_ + window_) return composeTurn();
    // A tip measured near the axis over half the window or more, or on it
    // in both, has no direction to register: the model's frame.
    window_registered_ = holdsDirection(2.0 * static_cast<double>(bent_), static_cast<double>(window_), magnitude());
    offset_ = window_offset_ = window_registered_ ? std::atan2(cross_, dot_) : initial_;
    offset_turn_ = {std::cos(offset_), std::sin(offset_)};
    bent_weight_ = static_cast<double>(bent_);
    weight_ = static_cast<double>(window_);
    composeTurn();
  }
  /// The registered turn (rad), 0 until the window is full; tracking, the
  /// latest (the window's is windowOffset).
  double offset() const noexcept { return offset_tracked_ ? std::atan2(held_cross_, held_dot_) : offset_; }
  /// The turn the window registered (rad): the simulation's.
  double windowOffset() const noexcept { return window_offset_; }
  /// The window's samples so far whose measured tip was bent at least the minimum.
  long bentSamples() const noexcept { return bent_; }
  /// Whether the window's samples so far hold a direction to register (once
  /// it is full: whether the offset was registered, else the training yaw is
  /// kept): half the window or more bent at least the minimum, and a tip off
  /// the axis in both.
  bool registered() const noexcept {
    if (samples_ >= delay_ + window_ && window_ > 0) return window_registered_;
    return holdsDirection(2.0 * static_cast<double>(bent_), static_cast<double>(window_), magnitude());
  }
  /// The turn (rad) from the model's frame to the sensor's at the last sample
  /// added: the offset and the drift since the start.
  double angle() const noexcept {
    return window_ > 0 && samples_ > 0 ? offset() + drift_ * static_cast<double>(samples_ - 1) : 0.0;
  }
  /// cos and sin of angle(), kept by add() without trigonometry per sample
  /// (products of the offset's and the drift's turns): a prediction turns
  /// without it either.
  struct Turn {
    double cos = 1.0, sin = 0.0;
  };
  const Turn& turn() const noexcept { return turn_; }

 private:
  // The drift's turn at sample k: the last one's rotated by the drift's (a
  // complex product), taken afresh every kExactEvery samples so rounding
  // cannot build up.
  static constexpr long kExactEvery = 4096;
  void advanceDrift(long k) noexcept {
    if (k == 0) {
      drift_turn_ = {};
    } else if (k % kExactEvery == 0) {
      drift_turn_ = {std::cos(drift_ * static_cast<double>(k)), std::sin(drift_ * static_cast<double>(k))};
    } else {
      const Turn d = drift_turn_;
      drift_turn_ = {d.cos * step_.cos - d.sin * step_.sin, d.sin * step_.cos + d.cos * step_.sin};
    }
  }
  // turn_ <- the offset's turn followed by the drift's: angle()'s.
  void composeTurn() noexcept {
    const Turn& o = offset_turn_;
    const Turn& d = drift_turn_;
    turn_ = {o.cos * d.cos - o.sin * d.sin, o.sin * d.cos + o.cos * d.sin};
  }
  // |(cross, dot)|: a square root, hypot only where the squares overflow.
  double magnitude() const noexcept {
    const double r2 = cross_ * cross_ + dot_ * dot_;
    return std::isfinite(r2) ? std::sqrt(r2) : std::hypot(cross_, dot_);
  }

  static double faded(double v) noexcept { return std::abs(v) < 1e-150 ? 0.0 : v; }
  bool holdsDirection(double twice_bent, double weight, double magnitude) const noexcept {
    return window_ > 0 && twice_bent >= weight && magnitude > 1e-12 && std::isfinite(magnitude) &&
           std::isfinite(cross_) && std::isfinite(dot_);
  }
  // A tracked sample's terms. A reading farther than kGlitchRatio times the
  // model's tip from the axis is taken at that distance and stands for fewer
  // of the samples between tracked ones the farther it is (all of them at
  // kGlitchRatio, one at kTrackEvery times that: a glitch weighs as a few
  // samples, not for many memories), and a term that is not finite is not
  // added: one bad reading cannot take the registration over.
  static constexpr double kGlitchRatio = 4.0;
  void trackSample(double tx, double ty, double x, double y, bool bent) noexcept {
    const double t2 = tx * tx + ty * ty, m2 = x * x + y * y, most = kGlitchRatio * kGlitchRatio * t2;
    const double clip = m2 > most ? std::sqrt(most / m2) : 1.0;
    const double scale = clip * std::max(clip, 1.0 / static_cast<double>(kTrackEvery));
    const double cross = scale * (tx * y - ty * x), dot = scale * (tx * x + ty * y);
    track(cross, dot, bent && std::isfinite(cross) && std::isfinite(dot));
  }
  // Past the window, a tracked sample: the terms so far weighed down by the
  // factor over kTrackEvery samples, this one's added (counting for as many)
  // if its tip is bent; the offset follows while half the (weighed) samples
  // are bent, else the last one holds. Terms that a long straight tip has
  // faded below 1e-150 are dropped: they would turn subnormal where the
  // processor does not flush them.
  void track(double cross, double dot, bool bent) noexcept {
    constexpr auto n = static_cast<double>(kTrackEvery);
    const double f = forget_every_;
    cross_ = faded(f * cross_ + (bent ? n * cross : 0.0));
    dot_ = faded(f * dot_ + (bent ? n * dot : 0.0));
    bent_weight_ = faded(f * bent_weight_ + (bent ? n : 0.0));
    weight_ = f * weight_ + n;
    const double r = magnitude();
    if (holdsDirection(2.0 * bent_weight_, weight_, r)) {
      held_cross_ = cross_;  // offset() is their atan2, taken only when asked
      held_dot_ = dot_;
      offset_tracked_ = true;
      offset_turn_ = {dot_ / r, cross_ / r};
    }
    composeTurn();
  }

  int window_ = 0;
  long delay_ = 0;
  double drift_ = 0.0, min_bend2_ = 0.0;         // the minimum bend, squared
  double forget_ = 1.0, forget_every_ = 1.0;     // per sample, per tracked sample
  Turn step_, turn_, drift_turn_, offset_turn_;  // the drift's per sample, angle()'s, the drift's and the offset's
  double cross_ = 0.0, dot_ = 0.0, offset_ = 0.0, window_offset_ = 0.0, initial_ = 0.0;
  double held_cross_ = 0.0, held_dot_ = 0.0;  // tracking: the sums of the offset in force
  bool offset_tracked_ = false;               // whether tracking has moved it (offset() from the held sums)
  double bent_weight_ = 0.0, weight_ = 0.0;   // tracking: the bent samples' and all samples' weights
  long samples_ = 0, bent_ = 0;
  bool window_registered_ = false;
};

/// The longest yaw-tracking memory taken: past it exp(-dt / s) rounds to 1 at
/// any sample time, which would be no tracking under another name.
inline constexpr double kMaxYawTrackingS = 1e9;

/// Why `seconds` is not a yaw-tracking memory at `sample_time` ("" when it
/// is): 0 (none), or from one sample time (under it, the forgetting factor
/// rounds to 0, also no tracking) to kMaxYawTrackingS.
inline std::string yawTrackingProblem(double seconds, double sample_time) {
  if (seconds == 0.0 || (std::isfinite(seconds) && seconds >= sample_time && seconds <= kMaxYawTrackingS)) return {};
  return "the yaw tracking's memory of " + std::to_string(seconds) + " s is neither 0 (none) nor from the " +
         std::to_string(sample_time) + " s sample time to 1e9 s (outside, it rounds to no tracking)";
}

/// The per-sample forgetting factor of a yaw tracked with `seconds` of memory
/// (a sample's terms weigh e^-1 after them) at `sample_time`; 1 (none) for 0.
inline double trackingForget(double seconds, double sample_time) noexcept {
  if (!(seconds > 0.0) || !(sample_time > 0.0) || !std::isfinite(seconds)) return 1.0;
  return std::exp(-sample_time / seconds);
}

/// An input-side tip model's tip (its frame) at a start: its output level and
/// the filters' settled response to the start's inputs (each bank's DC gain
/// times its node weight and channel level), as validation's modelTip starts.
inline void settledTip(const CompiledModel& m, const Eigen::VectorXd& node_w, const Eigen::VectorXd& vc,
                       double tip[2]) noexcept {
  const StateSpaceForm& s = m.state_space;
  double settled[2] = {0.0, 0.0};
  for (std::size_t b = 0; b < s.bank_output.size(); ++b) {
    const int o = s.bank_output[b], j = s.bank_input[b];
    const double drive = node_w(s.bank_node[b]) * vc(s.bank_channel[b]);
    if (drive == 0.0 || o > 1) continue;
    const Eigen::VectorXd& gain = s.dc_gain[static_cast<std::size_t>(o * m.n_u + j)];
    settled[o] +=
        drive * s.coefficient[0][static_cast<std::size_t>(o)].segment(s.coefficient_offset[b], m.poles).dot(gain);
  }
  for (int o = 0; o < 2; ++o) tip[o] = m.output_level[static_cast<std::size_t>(o)] + settled[o];
}

/// Rows [0, horizon) of a tip prediction (components) turned by `turn` about
/// the anchor (x0, y0): the model's increments into the sensor's frame.
inline void turnIncrements(const SensorYaw::Turn& turn, double x0, double y0, int horizon,
                           Eigen::Ref<Eigen::MatrixXd> out) noexcept {
  if (turn.sin == 0.0 && turn.cos == 1.0) return;
  const double c = turn.cos, s = turn.sin;
  double* __restrict px = out.col(0).data();
  double* __restrict py = out.col(1).data();
  for (int h = 0; h < horizon; ++h) {  // the two columns: contiguous, vectorised
    const double dx = px[h] - x0, dy = py[h] - y0;
    px[h] = x0 + c * dx - s * dy;
    py[h] = y0 + s * dx + c * dy;
  }
}

}  // namespace plsa
