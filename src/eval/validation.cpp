#include "plsa/eval/validation.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <tuple>
#include <utility>

#include "plsa/core/number_text.hpp"
#include "plsa/eval/dio_prediction.hpp"
#include "plsa/io/standard_columns.hpp"
#include "plsa/predict/sensor_yaw.hpp"

namespace plsa::eval {

namespace {

// Seconds as samples, saturated far beyond any log's length: a window longer
// than the log is then refused by name (it leaves nothing to score) instead
// of overflowing the conversion.
constexpr double kSaturatedSamples = 1e15;
double samplesIn(double seconds, double sample_time_s) { return std::min(seconds / sample_time_s, kSaturatedSamples); }

// A sample count as the messages print it: a saturated one as what it is.
std::string samplesText(Eigen::Index n) {
  return static_cast<double>(n) >= kSaturatedSamples ? std::string("over 10^15") : std::to_string(n);
}

}  // namespace

Eigen::Index yawRegistrationSamples(const DioPwlObfModel& model, const SimulationStart& start) {
  PLSA_CHECK(std::isfinite(start.yaw_registration_s) && start.yaw_registration_s >= 0,
             "SimulationStart: the yaw registration window must be finite and >= 0 s, got " +
                 std::to_string(start.yaw_registration_s));
  if (model.output_level.empty() || model.output_frame != OutputFrame::kTipCartesian || start.yaw_registration_s == 0)
    return 0;
  return std::max<Eigen::Index>(1, std::llround(samplesIn(start.yaw_registration_s, model.sample_time_s)));
}

Eigen::Index settleSamples(const DioPwlObfModel& model, const SimulationStart& start) {
  PLSA_CHECK(std::isfinite(start.settle_s) && start.settle_s >= 0,
             "SimulationStart: the settling time must be finite and >= 0 s, got " + std::to_string(start.settle_s));
  return static_cast<Eigen::Index>(std::ceil(samplesIn(start.settle_s, model.sample_time_s) - 1e-9));
}

double carriedYawRate(const DioPwlObfModel& model, const SimulationStart& start) {
  // Only a registration anchors the turn on the new run; carrying the
  // training yaw carries its sensor state, drift included, unchanged.
  if (!start.carry_training_drift || yawRegistrationSamples(model, start) == 0 ||
      model.training_drift_per_s.size() != 2)
    return 0.0;
  return model.training_drift_per_s[1];
}

Eigen::MatrixXd modelTip(const DioPwlObfModel& model, const Eigen::MatrixXd& u, const Eigen::MatrixXd& dy) {
  Eigen::MatrixXd level = modelLevels(model, u, dy);
  for (int o = 0; o < model.outputCount(); ++o) level.col(o).array() += model.output_level[static_cast<std::size_t>(o)];
  return level;
}

namespace {

// SimulationStart::yaw_registration_min_bend_deg in the logged angles' unit.
double leastBend(const DioPwlObfModel& model, const SimulationStart& start) {
  return start.yaw_registration_min_bend_deg * kRadPerDeg / model.radiansPerAngleUnit();
}

}  // namespace

SensorYawTrack trackSensorYaw(const DioPwlObfModel& model, const Eigen::MatrixXd& level, const Eigen::MatrixXd& ym,
                              const SimulationStart& start) {
  PLSA_CHECK(level.rows() == ym.rows() && level.cols() >= 2 && ym.cols() >= 2,
             "trackSensorYaw: the model's tip does not match the record");
  SensorYaw yaw;
  PLSA_CHECK(std::isfinite(start.yaw_registration_min_bend_deg) && start.yaw_registration_min_bend_deg >= 0,
             "SimulationStart: the yaw registration's least bend must be finite and >= 0 deg, got " +
                 std::to_string(start.yaw_registration_min_bend_deg));
  const int window = static_cast<int>(yawRegistrationSamples(model, start));
  const std::string tracking = yawTrackingProblem(start.yaw_tracking_s, model.sample_time_s);
  PLSA_CHECK(tracking.empty(), "SimulationStart: " + tracking);
  yaw.configure(window, carriedYawRate(model, start) * model.radiansPerAngleUnit() * model.sample_time_s,
                static_cast<long>(settleSamples(model, start)), leastBend(model, start),
                trackingForget(start.yaw_tracking_s, model.sample_time_s));
  yaw.restart();
  SensorYawTrack track;
  track.angle.resize(ym.rows());
  for (Eigen::Index k = 0; k < ym.rows(); ++k) {
    yaw.add(level(k, 0), level(k, 1), ym(k, 0), ym(k, 1));
    track.angle(k) = yaw.angle();
  }
  track.offset = yaw.windowOffset();
  track.registered = yaw.registered();
  track.bent_share = window > 0 ? static_cast<double>(yaw.bentSamples()) / window : 0.0;
  return track;
}

namespace {

// The yaw registration's samples (yawRegistrationSamples), checked to leave
// something of a `rows`-sample record to simulate after them and the
// settling time.
Eigen::Index checkedRegistration(const DioPwlObfModel& model, const SimulationStart& start, Eigen::Index rows) {
  const Eigen::Index n = yawRegistrationSamples(model, start), settle = settleSamples(model, start);
  const std::string after = settle > 0 ? " after " + samplesText(settle) + " settling samples" : "";
  if (n > 0)
    PLSA_CHECK(settle + n < rows, "the yaw registration window (" + significantDigits(start.yaw_registration_s, 4) +
                                      " s, " + samplesText(n) + " samples)" + after + " leaves nothing of the " +
                                      std::to_string(rows) +
                                      "-sample record to simulate: give a longer log, or a shorter "
                                      "--yaw-registration or --settle");
  return n;
}

// simulateModel from the model's tip (modelTip) and its yaw track
// (trackSensorYaw on that tip; unused without a registration).
std::vector<AlignedPrediction> simulatedTip(const DioPwlObfModel& model, Eigen::MatrixXd level,
                                            const SensorYawTrack& track, const SimulationStart& start) {
  const Eigen::Index rows = level.rows(), n = checkedRegistration(model, start, rows);
  // The rotation that best maps the predicted tip components onto the
  // measured ones over the window (SensorYaw), after the drift's turn.
  const double offset = n > 0 ? track.offset : 0.0;
  if (const double yaw_rate = carriedYawRate(model, start); yaw_rate != 0.0) {
    // Turned from the record's start; the registration takes the turn's offset.
    const double rate = yaw_rate * model.radiansPerAngleUnit() * model.sample_time_s;
    for (Eigen::Index k = 0; k < rows; ++k) {
      const double c = std::cos(rate * static_cast<double>(k)), s = std::sin(rate * static_cast<double>(k));
      const double x = level(k, 0);
      level(k, 0) = c * x - s * level(k, 1);
      level(k, 1) = s * x + c * level(k, 1);
    }
  }
  if (offset != 0.0) {
    const double c = std::cos(offset), s = std::sin(offset);
    const Eigen::VectorXd x = level.col(0);
    level.col(0) = c * x - s * level.col(1);
    level.col(1) = s * x + c * level.col(1);
  }
  const Eigen::Index first = n > 0 ? settleSamples(model, start) + n : 1;
  std::vector<AlignedPrediction> out;
  for (int o = 0; o < model.outputCount(); ++o) {
    AlignedPrediction p;
    p.first = first;
    p.values = level.col(o).tail(rows - first);
    out.push_back(std::move(p));
  }
  return out;
}

}  // namespace

std::vector<AlignedPrediction> simulateModel(const DioPwlObfModel& model, const Eigen::MatrixXd& u,
                                             const Eigen::MatrixXd& y, const Eigen::MatrixXd& dy,
                                             const SimulationStart& start) {
  PLSA_CHECK(y.cols() == model.outputCount() && dy.cols() == model.outputCount() && y.rows() == u.rows() &&
                 dy.rows() == u.rows(),
             "simulateModel: the record does not match the model's outputs");
  const Eigen::Index n = yawRegistrationSamples(model, start);  // refuses a window that is not a duration
  std::vector<AlignedPrediction> out;
  if (model.output_level.empty()) {  // from the measured sample after the settling time
    const Eigen::Index settle = settleSamples(model, start), rows = y.rows() - settle;
    PLSA_CHECK(rows >= 2, "simulateModel: the settling time leaves fewer than two samples");
    for (int o = 0; o < model.outputCount(); ++o) {
      AlignedPrediction p = simulate(y.col(o).tail(rows), dy.col(o).tail(rows));
      p.first += settle;
      out.push_back(std::move(p));
    }
    return out;
  }
  PLSA_CHECK(u.rows() >= 2, "simulateModel: need at least two samples");
  Eigen::MatrixXd level = modelTip(model, u, dy);
  SensorYawTrack track;
  if (n > 0 && checkedRegistration(model, start, u.rows()) > 0) track = trackSensorYaw(model, level, y, start);
  return simulatedTip(model, std::move(level), track, start);
}

namespace {

// A tip_cartesian pair of predictions back to bending and steering;
// `reference(t)` is the steering angle whose branch sample t takes.
template <class Reference>
std::pair<AlignedPrediction, AlignedPrediction> toTipAngles(const AlignedPrediction& x, const AlignedPrediction& y,
                                                            double rad_per_unit, Reference reference) {
  std::pair<AlignedPrediction, AlignedPrediction> out{x, y};
  for (Eigen::Index i = 0; i < x.values.size(); ++i)
    tipAngles(x.values(i), y.values(i), reference(x.first + i, i == 0 ? 0.0 : out.second.values(i - 1)), rad_per_unit,
              out.first.values(i), out.second.values(i));
  return out;
}

// k-step predictions of a tip's two components: the measured tip k samples
// back plus the model's increments since, turned into the sensor's frame by
// that sample's angle (what Predictor::predict does).
std::pair<AlignedPrediction, AlignedPrediction> turnedKStepAhead(const Eigen::MatrixXd& ym, const Eigen::MatrixXd& dy,
                                                                 const Eigen::VectorXd& angle, int k) {
  const AlignedPrediction x = kStepAhead(ym.col(0), dy.col(0), k), y = kStepAhead(ym.col(1), dy.col(1), k);
  std::pair<AlignedPrediction, AlignedPrediction> out{x, y};
  for (Eigen::Index i = 0; i < x.values.size(); ++i) {
    const Eigen::Index anchor = x.first + i - k;
    const double a = angle(anchor);
    if (a == 0.0) continue;  // the model's frame: as kStepAhead gives it, to the bit
    const double c = std::cos(a), s = std::sin(a);
    const double wx = x.values(i) - ym(anchor, 0), wy = y.values(i) - ym(anchor, 1);
    out.first.values(i) = ym(anchor, 0) + c * wx - s * wy;
    out.second.values(i) = ym(anchor, 1) + s * wx + c * wy;
  }
  return out;
}

}  // namespace

std::vector<std::map<int, AlignedPrediction>> predictOutputs(const DioPwlObfModel& model, const Eigen::MatrixXd& u,
                                                             const Eigen::MatrixXd& y, const std::vector<int>& horizons,
                                                             bool with_simulation, const SimulationStart& start) {
  return predictOutputs(model, u, y, horizons, with_simulation, modelIncrements(model, u), start);
}

namespace {

// predictOutputs, with the yaw track its predictions turned by (`track`;
// empty when none was registered).
std::vector<std::map<int, AlignedPrediction>> predictTracked(const DioPwlObfModel& model, const Eigen::MatrixXd& u,
                                                             const Eigen::MatrixXd& y, const std::vector<int>& horizons,
                                                             bool with_simulation, const Eigen::MatrixXd& dy,
                                                             const SimulationStart& start, SensorYawTrack& track) {
  PLSA_CHECK(y.cols() == model.outputCount() && y.rows() == u.rows(),
             "predictOutputs: the record does not match the model's outputs");
  PLSA_CHECK(dy.rows() == u.rows() && dy.cols() == model.outputCount(),
             "predictOutputs: the increments do not match the record");
  const Eigen::MatrixXd ym = model.toModelFrame(y);
  std::vector<std::map<int, AlignedPrediction>> out(static_cast<std::size_t>(model.outputCount()));
  const bool tip = model.output_frame == OutputFrame::kTipCartesian;
  // A tip's k-step predictions turn into the sensor's frame as the predictor's do.
  const bool turned = tip && yawRegistrationSamples(model, start) > 0;
  // The model's tip, simulated once for the yaw track and the simulation
  // (simulateModel's own path refuses a record too short).
  const bool simulated = with_simulation && !model.output_level.empty() && u.rows() >= 2;
  Eigen::MatrixXd tip_level = turned || simulated ? modelTip(model, u, dy) : Eigen::MatrixXd();
  track = turned ? trackSensorYaw(model, tip_level, ym, start) : SensorYawTrack{};
  const Eigen::VectorXd& yaw = track.angle;
  for (int k : horizons) {
    PLSA_CHECK(k >= 1, "validate: horizons must be >= 1, got " + std::to_string(k));
    if (turned) {
      std::tie(out[0][k], out[1][k]) = turnedKStepAhead(ym, dy, yaw, k);
    } else {
      for (int o = 0; o < model.outputCount(); ++o)
        out[static_cast<std::size_t>(o)][k] = kStepAhead(ym.col(o), dy.col(o), k);
    }
    // As the simulation's below: each predicted direction written on the
    // branch of the measured angle at the same sample. (On the branch of the
    // angle it starts from, as the predictor writes it, a log whose angle
    // wraps at +-180 deg within the horizon scored a 2 deg miss as 358.)
    if (tip)
      std::tie(out[0][k], out[1][k]) = toTipAngles(out[0][k], out[1][k], model.radiansPerAngleUnit(),
                                                   [&](Eigen::Index t, double) { return y(t, 1); });
  }
  if (with_simulation) {
    const std::vector<AlignedPrediction> sims =
        simulated ? simulatedTip(model, std::move(tip_level), track, start) : simulateModel(model, u, ym, dy, start);
    for (int o = 0; o < model.outputCount(); ++o)
      out[static_cast<std::size_t>(o)][0] = sims[static_cast<std::size_t>(o)];
    // The simulated direction written on the branch (+-360 deg) of the
    // measured angle at the same sample: only how the same direction is
    // written, so the steering is compared as an angle. (Following its own
    // previous value, a simulation that passes near straight, where the
    // direction can turn half a turn in a sample, or a log whose angle wraps
    // at +-180 deg would keep a whole turn's error on every later sample.)
    if (model.output_frame == OutputFrame::kTipCartesian)
      std::tie(out[0][0], out[1][0]) = toTipAngles(out[0][0], out[1][0], model.radiansPerAngleUnit(),
                                                   [&](Eigen::Index t, double) { return y(t, 1); });
  }
  return out;
}

}  // namespace

std::vector<std::map<int, AlignedPrediction>> predictOutputs(const DioPwlObfModel& model, const Eigen::MatrixXd& u,
                                                             const Eigen::MatrixXd& y, const std::vector<int>& horizons,
                                                             bool with_simulation, const Eigen::MatrixXd& dy,
                                                             const SimulationStart& start) {
  SensorYawTrack track;
  return predictTracked(model, u, y, horizons, with_simulation, dy, start, track);
}

namespace {

// A fit or error that is not a number is no score: say what went wrong instead.
void requireFiniteScore(double value, const std::string& what, const std::string& output, const AlignedPrediction& p,
                        const std::string& source) {
  if (std::isfinite(value)) return;
  const double largest = p.values.size() ? p.values.cwiseAbs().maxCoeff() : 0.0;
  std::ostringstream msg;
  msg << source << ": the " << what << " of '" << output << "' is " << value << ": the model's predictions reach "
      << largest << ", beyond what a score can be computed on; the model is unusable on this log "
      << "(was it identified on data with a gross outlier?)";
  throw std::runtime_error(msg.str());
}

// The first sample every prediction of `pred` (all outputs, all keys) covers.
Eigen::Index scoringStart(const std::vector<std::map<int, AlignedPrediction>>& pred) {
  Eigen::Index first = 0;
  for (const auto& by_key : pred)
    for (const auto& [key, p] : by_key) {
      (void)key;
      first = std::max(first, p.first);
    }
  return first;
}

// The part of `p` from sample `from` on (p covers up to the record's end).
AlignedPrediction scoredPart(const AlignedPrediction& p, Eigen::Index from) {
  const Eigen::Index skip = from - p.first;
  return {from, p.values.tail(p.values.size() - skip)};
}

// ValidationResult::unsettled_starts: the validated simulations (their rms
// error and spread in `scored`, from `scored_from` on) against the same
// started kLater_s later, over the samples it would be scored on.
constexpr double kLater_s = 5.0, kLaterGain = 0.2, kLaterShareOfSpread = 0.02;
// The share of [from, to) on which a tip-frame model's measured tip (bending
// `bend`, logged units) is bent less than the yaw registration's least bend.
double straightShare(const DioPwlObfModel& model, const Eigen::VectorXd& bend, Eigen::Index from, Eigen::Index to,
                     const SimulationStart& start) {
  if (model.output_frame != OutputFrame::kTipCartesian || !(to > from)) return 0.0;
  const Eigen::Index straight = (bend.segment(from, to - from).array().abs() < leastBend(model, start)).count();
  return static_cast<double>(straight) / static_cast<double>(to - from);
}

std::vector<UnsettledStart> unsettledStartsOf(const DioPwlObfModel& model, const Eigen::MatrixXd& u,
                                              const Eigen::MatrixXd& y, const Eigen::MatrixXd& dy,
                                              const SimulationStart& start, Eigen::Index scored_from,
                                              const std::vector<OutputValidation>& scored) {
  SimulationStart later = start;
  later.settle_s = start.settle_s + kLater_s;
  const Eigen::Index settle = settleSamples(model, later), later_from = std::max(settle, scored_from);
  // Too short to tell: the later start must leave most of the log to score.
  if (settle + yawRegistrationSamples(model, later) > u.rows() / 2) return {};
  const auto sims = predictOutputs(model, u, y, {}, true, dy, later);
  std::vector<UnsettledStart> out;
  for (std::size_t o = 0; o < scored.size(); ++o) {
    const AlignedPrediction& then = sims[o].at(0);
    const double rms_now = scored[o].rms_sim, rms_then = rmsErrorOf(y.col(static_cast<Eigen::Index>(o)),
                                                                    scoredPart(then, std::max(then.first, later_from)));
    if (!(rms_then <= (1.0 - kLaterGain) * rms_now) || !(rms_now - rms_then > kLaterShareOfSpread * scored[o].spread))
      continue;
    const Eigen::Index left_out_to = std::min(std::max(then.first, later_from), y.rows());
    out.push_back({scored[o].name, later.settle_s, rms_now, rms_then,
                   o == 1 ? straightShare(model, y.col(0), scored_from, left_out_to, start) : 0.0});
  }
  return out;
}

// A settling time that is a duration (settleSamples refuses one that is
// not) and leaves a fit's two samples, else an error naming the log.
void requireSettlingTime(const DioPwlObfModel& model, const SimulationStart& start, const io::Log& log) {
  const Eigen::Index settle = settleSamples(model, start);
  if (settle > log.samples() - 2)
    throw std::invalid_argument(log.source + ": settling time " + significantDigits(start.settle_s, 4) + " s is " +
                                samplesText(settle) + " samples of the log's " + std::to_string(log.samples()) +
                                "; a fit needs 2 after it: give a longer log");
}

}  // namespace

ValidationResult validateModel(const DioPwlObfModel& model, const io::Log& log, const std::vector<int>& horizons,
                               const SimulationStart& start) {
  requireHorizons(horizons, "validate");
  requireSettlingTime(model, start, log);
  // A log at another rate would be scored on the wrong time scale without a word.
  if (log.hasColumn(io::standard_columns::kTime)) {
    const double dt = io::checkedSampleTime(log, io::standard_columns::kTime, io::kToleratedGapFactor);
    if (!io::sameSampleTime(dt, model.sample_time_s))
      throw std::invalid_argument(log.source + ": sample time " + std::to_string(dt) + " s differs from the model's " +
                                  std::to_string(model.sample_time_s) + " s; resample the log or identify at its rate");
  }
  for (int k : horizons)
    if (log.samples() - k < 2)
      throw std::invalid_argument(log.source + ": " + std::to_string(log.samples()) + " samples leave " +
                                  std::to_string(std::max<Eigen::Index>(0, log.samples() - k)) +
                                  " to score at horizon " + std::to_string(k) +
                                  " (a fit needs 2); give a longer log or a shorter horizon");
  const Eigen::MatrixXd u = log.columnsOf(model.inputs);
  const Eigen::MatrixXd y = log.columnsOf(model.outputs);
  const Eigen::MatrixXd dy = modelIncrements(model, u);
  ValidationResult res;
  const std::vector<std::map<int, AlignedPrediction>> pred =
      predictTracked(model, u, y, horizons, true, dy, start, res.yaw);
  res.time = log.hasColumn(io::standard_columns::kTime) ? log.column(io::standard_columns::kTime)
                                                        : Eigen::VectorXd::LinSpaced(u.rows(), 0, u.rows() - 1);
  res.outside_training = inputsOutsideTraining(model, u);
  // One window for every score: from the first sample every prediction
  // covers, after the settling time asked for.
  res.scored_from = std::max(scoringStart(pred), settleSamples(model, start));
  if (u.rows() - res.scored_from < 2)
    throw std::invalid_argument(log.source + ": " + std::to_string(u.rows()) + " samples leave " +
                                std::to_string(std::max<Eigen::Index>(0, u.rows() - res.scored_from)) +
                                " to score after the longest horizon, the simulation's start and the settling time "
                                "(sample " +
                                std::to_string(res.scored_from) + "); a fit needs 2: give a longer log");
  for (int o = 0; o < model.outputCount(); ++o) {
    OutputValidation ov;
    ov.name = model.outputs[static_cast<std::size_t>(o)];
    ov.measured = y.col(o);
    const auto scored = ov.measured.tail(u.rows() - res.scored_from);
    if (!(scored.maxCoeff() > scored.minCoeff()))
      throw std::invalid_argument(log.source + ": output '" + ov.name + "' is constant over the scored samples (from " +
                                  std::to_string(res.scored_from + 1) + "); a fit against it is undefined");
    // Values beyond about 1e154 square to infinity: the spread would be
    // infinite and every fit 100.
    if (!std::isfinite((scored.array() - scored.mean()).matrix().norm()))
      throw std::invalid_argument(log.source + ": output '" + ov.name + "' reaches " +
                                  significantDigits(scored.cwiseAbs().maxCoeff(), 4) +
                                  " over the scored samples, beyond what a fit can be computed on (a glitch?)");
    for (int k : horizons) {
      const AlignedPrediction p = scoredPart(pred[static_cast<std::size_t>(o)].at(k), res.scored_from);
      ov.fit_k[k] = fitOf(ov.measured, p);
      ov.rms_k[k] = rmsErrorOf(ov.measured, p);
      requireFiniteScore(ov.fit_k[k], std::to_string(k) + "-step fit", ov.name, p, log.source);
      requireFiniteScore(ov.rms_k[k], std::to_string(k) + "-step rms error", ov.name, p, log.source);
      ov.predicted_k[k] = placedOver(pred[static_cast<std::size_t>(o)].at(k), y.rows());
    }
    const AlignedPrediction s = scoredPart(pred[static_cast<std::size_t>(o)].at(0), res.scored_from);
    ov.fit_sim = fitOf(ov.measured, s);
    ov.rms_sim = rmsErrorOf(ov.measured, s);
    requireFiniteScore(ov.fit_sim, "simulation fit", ov.name, s, log.source);
    requireFiniteScore(ov.rms_sim, "simulation rms error", ov.name, s, log.source);
    ov.spread = spreadOf(ov.measured.segment(s.first, s.values.size()));
    ov.simulated = placedOver(pred[static_cast<std::size_t>(o)].at(0), y.rows());
    for (int k : horizons) ov.sim_error_kept[k] = simulationErrorKept(ov.measured, ov.simulated, res.scored_from, k);
    res.outputs.push_back(std::move(ov));
  }
  res.unsettled_starts = unsettledStartsOf(model, u, y, dy, start, res.scored_from, res.outputs);
  res.yaw_asked = yawRegistrationSamples(model, start) > 0;  // the track predictTracked turned by
  return res;
}

double simulationErrorKept(const Eigen::VectorXd& measured, const Eigen::VectorXd& simulated, Eigen::Index from,
                           int h) {
  PLSA_CHECK(measured.size() == simulated.size(), "simulationErrorKept: measured and simulated lengths differ");
  PLSA_CHECK(h >= 1 && from >= 0, "simulationErrorKept: need a horizon >= 1 and a start >= 0");
  double carried = 0.0, before = 0.0;
  for (Eigen::Index t = std::max<Eigen::Index>(from, h); t < measured.size(); ++t) {
    const double now = measured(t) - simulated(t), back = measured(t - h) - simulated(t - h);
    if (!std::isfinite(now) || !std::isfinite(back)) continue;
    carried += now * back;
    before += back * back;
  }
  return before > 0.0 ? carried / before : std::numeric_limits<double>::quiet_NaN();
}

namespace {

// The departure of one output's simulation from its measured range, or none
// when it stays within `tolerance` of the range's width.
std::optional<SimulationDeparture> departureOf(const OutputValidation& o, const Eigen::VectorXd& time,
                                               Eigen::Index from, double tolerance) {
  const Eigen::Index n = o.measured.size() - from;
  if (n < 1 || o.simulated.size() != o.measured.size()) return std::nullopt;
  const auto measured = o.measured.segment(from, n).array();
  const auto simulated = o.simulated.segment(from, n).array();
  SimulationDeparture d;
  d.output = o.name;
  d.measured_low = measured.minCoeff();
  d.measured_high = measured.maxCoeff();
  const double width = d.measured_high - d.measured_low;
  if (!(width > 0)) return std::nullopt;  // a constant output has no range to leave
  const Eigen::ArrayXd outside = (simulated - d.measured_high).max(d.measured_low - simulated).max(0.0);
  d.farthest = outside.maxCoeff();
  d.share = d.farthest / width;
  if (!(d.share > tolerance)) return std::nullopt;
  Eigen::Index first = 0;
  while (!(outside(first) > tolerance * width)) ++first;
  d.first_time_s = time(from + first);
  return d;
}

std::string formatted(const char* format, double value) {
  char b[48];
  std::snprintf(b, sizeof b, format, value);
  return b;
}

}  // namespace

std::vector<SimulationDeparture> simulationDepartures(const ValidationResult& v, double tolerance) {
  if (!(tolerance > 0) || !std::isfinite(tolerance))
    throw std::invalid_argument("simulationDepartures: tolerance " + std::to_string(tolerance) +
                                " must be positive and finite");
  std::vector<SimulationDeparture> out;
  for (const OutputValidation& o : v.outputs)
    if (auto d = departureOf(o, v.time, v.scored_from, tolerance)) out.push_back(*d);
  return out;
}

std::vector<std::string> simulationWarnings(const std::vector<SimulationDeparture>& departures) {
  std::vector<std::string> out;
  for (const SimulationDeparture& d : departures)
    out.push_back("the free simulation of " + d.output + " leaves the measured range [" +
                  formatted("%.4g", d.measured_low) + ", " + formatted("%.4g", d.measured_high) + "] by up to " +
                  formatted("%.4g", d.farthest) + " (" + formatted("%.0f", 100 * d.share) +
                  "% of its width), first at t = " + formatted("%.4g", d.first_time_s) +
                  " s: the model departs from this run; do not trust its long-horizon predictions here");
  return out;
}

std::vector<std::string> unsettledStartWarnings(const std::vector<UnsettledStart>& starts) {
  std::vector<std::string> out;
  for (const UnsettledStart& t : starts) {
    const std::string why =
        t.straight_share >= 0.05
            ? "the tip is straight on " + formatted("%.0f", 100.0 * t.straight_share) +
                  "% of the samples before then, where its steering angle is the sensor's noise, and that counts "
                  "against the model"
            : "the log may not start at rest (the simulation starts settled at its first inputs), and that start "
              "counts against the model";
    out.push_back("the free simulation of " + t.output + " is off by " + formatted("%.4g", t.rms_error) + " rms, by " +
                  formatted("%.4g", t.rms_later) + " when started and scored " + formatted("%.3g", t.later_s) +
                  " s into the log: " + why + "; --settle " + formatted("%.3g", t.later_s) +
                  " leaves it out of the scores");
  }
  return out;
}

io::Log predictionLog(const ValidationResult& v) {
  io::Log log;
  log.columns.push_back(io::standard_columns::kTime);
  for (const auto& o : v.outputs) {
    log.columns.push_back(o.name);
    for (const auto& [k, p] : o.predicted_k) log.columns.push_back(o.name + "_k" + std::to_string(k));
    log.columns.push_back(o.name + "_sim");
  }
  const Eigen::Index T = v.time.size() - v.scored_from;
  log.data.resize(T, static_cast<Eigen::Index>(log.columns.size()));
  Eigen::Index c = 0;
  log.data.col(c++) = v.time.tail(T);
  for (const auto& o : v.outputs) {
    log.data.col(c++) = o.measured.tail(T);
    for (const auto& [k, p] : o.predicted_k) log.data.col(c++) = p.tail(T);
    log.data.col(c++) = o.simulated.tail(T);
  }
  log.metadata["source"] = "plsa validate";
  return log;
}

}  // namespace plsa::eval
