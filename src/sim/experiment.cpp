#include "plsa/sim/experiment.hpp"

#include <cmath>
#include <cstdio>
#include <random>
#include <sstream>
#include <stdexcept>
#include <utility>
#include <vector>

#include "plsa/core/angle_units.hpp"
#include "plsa/core/check.hpp"
#include "plsa/io/standard_columns.hpp"

namespace plsa::sim {
namespace {

// Refuses an experiment longer than kMaxExperimentSamples before it is built:
// a mistyped duration would otherwise die in bad_alloc (or lround overflow).
void requireSamples(const char* name, double samples, double rate) {
  if (samples <= static_cast<double>(kMaxExperimentSamples)) return;
  char msg[240];
  std::snprintf(msg, sizeof msg,
                "%s: %.4g s at %g Hz is %.4g samples, above the %lld one experiment holds (%.1f h at this rate); "
                "split it into several runs",
                name, samples / rate, rate, samples, static_cast<long long>(kMaxExperimentSamples),
                static_cast<double>(kMaxExperimentSamples) / rate / 3600.0);
  throw std::invalid_argument(msg);
}

class CommandWriter {
 public:
  CommandWriter(const char* name, double rate) : name_(name), rate_(rate) {}
  void hold(const Eigen::RowVector3d& cmd, double seconds) {
    requireRoom(static_cast<double>(rows_.size()) + seconds * rate_);
    const auto n = static_cast<Eigen::Index>(std::lround(seconds * rate_));
    for (Eigen::Index k = 0; k < n; ++k) rows_.push_back(cmd);
  }
  /// Unrecorded pre-roll: ramp from rest to `cmd` over 2 s, then hold the rest of `seconds`.
  void preroll(const Eigen::RowVector3d& cmd, double seconds) {
    const auto ramp = static_cast<Eigen::Index>(std::lround(std::min(2.0, seconds) * rate_));
    for (Eigen::Index k = 1; k <= ramp; ++k) rows_.push_back(cmd * static_cast<double>(k) / static_cast<double>(ramp));
    hold(cmd, seconds - static_cast<double>(ramp) / rate_);
    record_from_ = static_cast<Eigen::Index>(rows_.size());
  }
  Eigen::Index recordFrom() const { return record_from_; }
  Eigen::MatrixXd matrix() const {
    Eigen::MatrixXd m(static_cast<Eigen::Index>(rows_.size()), 3);
    for (std::size_t k = 0; k < rows_.size(); ++k) m.row(static_cast<Eigen::Index>(k)) = rows_[k];
    return m;
  }

 private:
  // The experiments whose length is not checked up front stop here, part way.
  void requireRoom(double samples) const {
    if (samples <= static_cast<double>(kMaxExperimentSamples)) return;
    char msg[240];
    std::snprintf(msg, sizeof msg,
                  "%s: longer than the %lld samples one experiment holds (%.1f h at %g Hz): it passes them within "
                  "its first %.4g s; split it into several runs",
                  name_, static_cast<long long>(kMaxExperimentSamples),
                  static_cast<double>(kMaxExperimentSamples) / rate_ / 3600.0, rate_, samples / rate_);
    throw std::invalid_argument(msg);
  }

  const char* name_;
  double rate_;
  std::vector<Eigen::RowVector3d> rows_;
  Eigen::Index record_from_ = 0;
};

void checkCommon(const ExperimentOptions& o) {
  PLSA_CHECK(o.sample_rate_hz > 0 && std::isfinite(o.sample_rate_hz),
             "experiment: sample_rate_hz must be a finite number above 0");
  PLSA_CHECK(o.hold_s > 0 && std::isfinite(o.hold_s), "experiment: hold_s must be a finite number above 0");
  PLSA_CHECK(o.initial_rest_s >= 0 && std::isfinite(o.initial_rest_s),
             "experiment: initial_rest_s must be a finite number >= 0");
  PLSA_CHECK(o.preroll_s >= 0 && std::isfinite(o.preroll_s), "experiment: preroll_s must be a finite number >= 0");
}

int chamberIndex(int chamber) {
  PLSA_CHECK(chamber >= 1 && chamber <= 3, "experiment: chambers are numbered 1 to 3, got " + std::to_string(chamber));
  return chamber - 1;
}

}  // namespace

Experiment staircaseExperiment(const ExperimentOptions& o) {
  checkCommon(o);
  PLSA_CHECK(o.staircase_steps >= 1, "staircase: need at least one step");
  PLSA_CHECK(o.staircase_max_bar > 0, "staircase: staircase_max_bar must be positive");
  const int c = chamberIndex(o.staircase_chamber);
  requireSamples("staircase1", (o.initial_rest_s + 2.0 * o.staircase_steps * o.hold_s) * o.sample_rate_hz,
                 o.sample_rate_hz);
  CommandWriter w("staircase1", o.sample_rate_hz);
  Eigen::RowVector3d cmd = Eigen::RowVector3d::Zero();
  w.hold(cmd, o.initial_rest_s);
  const int n = o.staircase_steps;
  for (int k = 1; k <= n; ++k) {  // increase cases
    cmd(c) = o.staircase_max_bar * k / n;
    w.hold(cmd, o.hold_s);
  }
  for (int k = n - 1; k >= 0; --k) {  // decrease cases
    cmd(c) = o.staircase_max_bar * k / n;
    w.hold(cmd, o.hold_s);
  }
  return {"staircase1", w.matrix()};
}

namespace {

Experiment gridWithOptionalJointPass(const ExperimentOptions& o, bool joint) {
  checkCommon(o);
  PLSA_CHECK(o.grid_levels_bar.size() >= 2, "grid2: need at least two levels per chamber");
  for (std::size_t i = 1; i < o.grid_levels_bar.size(); ++i)
    PLSA_CHECK(o.grid_levels_bar[i] > o.grid_levels_bar[i - 1], "grid2: levels must increase");
  const int a = chamberIndex(o.grid_chambers[0]);
  const int b = chamberIndex(o.grid_chambers[1]);
  PLSA_CHECK(a != b, "grid2: the two chambers must differ");
  const auto& L = o.grid_levels_bar;
  CommandWriter w(joint ? "grid2_joint" : "grid2", o.sample_rate_hz);
  Eigen::RowVector3d cmd = Eigen::RowVector3d::Zero();
  cmd(a) = L.front();
  cmd(b) = L.front();
  w.preroll(cmd, o.preroll_s);
  w.hold(cmd, 1.0);  // recorded: the level before the first step
  // One input moves at a time: for each level of the fixed input, the moving
  // input climbs through every level (icr) and comes back down (dcr).
  for (const auto& [moving, fixed] : {std::pair{a, b}, std::pair{b, a}}) {
    for (double level : L) {
      // Move the fixed input, then bring the moving one to its first level: one at a time.
      if (cmd(fixed) != level) {
        cmd(fixed) = level;
        w.hold(cmd, o.hold_s);
      }
      if (cmd(moving) != L.front()) {
        cmd(moving) = L.front();
        w.hold(cmd, o.hold_s);
      }
      for (std::size_t i = 1; i < L.size(); ++i) {
        cmd(moving) = L[i];
        w.hold(cmd, o.hold_s);
      }
      for (std::size_t i = L.size() - 1; i-- > 0;) {
        cmd(moving) = L[i];
        w.hold(cmd, o.hold_s);
      }
    }
  }
  if (joint) {
    // Out and back along each diagonal (both chambers a level up together) and
    // each anti-diagonal (one up as the other goes down) with two nodes or more.
    const int n = static_cast<int>(L.size());
    auto walk = [&](const std::vector<std::pair<int, int>>& nodes) {
      std::vector<std::pair<int, int>> path = nodes;
      path.insert(path.end(), nodes.rbegin() + 1, nodes.rend());
      for (const auto& [i, j] : path) {
        if (cmd(a) == L[static_cast<std::size_t>(i)] && cmd(b) == L[static_cast<std::size_t>(j)]) continue;
        cmd(a) = L[static_cast<std::size_t>(i)];
        cmd(b) = L[static_cast<std::size_t>(j)];
        w.hold(cmd, o.hold_s);
      }
    };
    for (int d = -(n - 2); d <= n - 2; ++d) {
      std::vector<std::pair<int, int>> nodes;
      for (int i = 0; i < n; ++i)
        if (i + d >= 0 && i + d < n) nodes.emplace_back(i, i + d);
      walk(nodes);
    }
    for (int s = 1; s <= 2 * n - 3; ++s) {
      std::vector<std::pair<int, int>> nodes;
      for (int i = 0; i < n; ++i)
        if (s - i >= 0 && s - i < n) nodes.emplace_back(i, s - i);
      walk(nodes);
    }
  }
  return {joint ? "grid2_joint" : "grid2", w.matrix(), w.recordFrom()};
}

}  // namespace

Experiment gridExperiment(const ExperimentOptions& o) { return gridWithOptionalJointPass(o, false); }

Experiment gridJointExperiment(const ExperimentOptions& o) { return gridWithOptionalJointPass(o, true); }

Experiment joystickExperiment(const ExperimentOptions& o) {
  checkCommon(o);
  PLSA_CHECK(o.joystick_duration_s > 0 && std::isfinite(o.joystick_duration_s),
             "joystick: duration must be a finite number above 0");
  PLSA_CHECK(o.joystick_max_bar > o.joystick_min_bar && o.joystick_min_bar >= 0,
             "joystick: need 0 <= joystick_min_bar < joystick_max_bar");
  PLSA_CHECK(o.joystick_preroll_s > 0 && std::isfinite(o.joystick_preroll_s),
             "joystick: joystick_preroll_s must be a finite number above 0");
  PLSA_CHECK(o.joystick_bandwidth_hz > 0 && o.joystick_bandwidth_hz <= o.sample_rate_hz / 2,
             "joystick: joystick_bandwidth_hz must be above 0 and at most half the sample rate");
  constexpr double kSettledS = 1.0;  // recorded, held at the starting point before the path moves
  // The trajectory is allocated before the writer sees it, so its length is checked here.
  requireSamples("joystick", (o.joystick_preroll_s + kSettledS + o.joystick_duration_s) * o.sample_rate_hz,
                 o.sample_rate_hz);
  const auto n = static_cast<Eigen::Index>(std::lround(o.joystick_duration_s * o.sample_rate_hz));
  if (n < 2) {
    char msg[160];
    std::snprintf(msg, sizeof msg, "joystick: a duration of %g s is under two samples at %g Hz (at least %g s)",
                  o.joystick_duration_s, o.sample_rate_hz, 1.5 / o.sample_rate_hz);
    throw std::invalid_argument(msg);
  }
  std::mt19937_64 rng(o.seed);
  std::normal_distribution<double> n01;
  // Two passes of a critically damped second-order low-pass on white noise.
  const double wn = 2.0 * kPi * o.joystick_bandwidth_hz / o.sample_rate_hz;
  const double alpha = 1.0 - std::exp(-wn);
  Eigen::MatrixXd traj = Eigen::MatrixXd::Zero(n, 3);
  for (int ch = 0; ch < 2; ++ch) {
    double s1 = 0, s2 = 0, s3 = 0, s4 = 0;
    Eigen::VectorXd x(n);
    for (Eigen::Index k = -4 * static_cast<Eigen::Index>(1.0 / alpha); k < n; ++k) {
      s1 += alpha * (n01(rng) - s1);
      s2 += alpha * (s1 - s2);
      s3 += alpha * (s2 - s3);
      s4 += alpha * (s3 - s4);
      if (k >= 0) x(k) = s4;
    }
    const double lo = x.minCoeff(), hi = x.maxCoeff();
    const double span = hi > lo ? hi - lo : 1.0;
    traj.col(ch) = ((x.array() - lo) / span * (o.joystick_max_bar - o.joystick_min_bar) + o.joystick_min_bar).matrix();
  }
  CommandWriter w("joystick", o.sample_rate_hz);
  w.preroll(traj.row(0), o.joystick_preroll_s);
  w.hold(traj.row(0), kSettledS);
  const Eigen::MatrixXd head = w.matrix();
  Experiment e{"joystick", Eigen::MatrixXd(head.rows() + n, 3), w.recordFrom()};
  e.commands.topRows(head.rows()) = head;
  e.commands.bottomRows(n) = traj;
  return e;
}

Experiment staticMapExperiment(const ExperimentOptions& o) {
  checkCommon(o);
  PLSA_CHECK(o.static_map_points >= 2 && o.static_map_points <= 100, "static_map: static_map_points must be 2 to 100");
  PLSA_CHECK(std::isfinite(o.static_map_base_bar) && o.static_map_base_bar >= 0,
             "static_map: static_map_base_bar must be a finite number >= 0");
  PLSA_CHECK(o.static_map_base_s > 0 && std::isfinite(o.static_map_base_s),
             "static_map: static_map_base_s must be a finite number above 0");
  PLSA_CHECK(o.static_map_hold_s > 0 && std::isfinite(o.static_map_hold_s),
             "static_map: static_map_hold_s must be a finite number above 0");
  PLSA_CHECK(o.grid_levels_bar.size() >= 2 && o.grid_levels_bar.back() > o.grid_levels_bar.front(),
             "static_map: the grid's levels must span a range");
  const int a = chamberIndex(o.grid_chambers[0]);
  const int b = chamberIndex(o.grid_chambers[1]);
  PLSA_CHECK(a != b, "static_map: the two chambers must differ");
  const double lo = o.grid_levels_bar.front(), hi = o.grid_levels_bar.back();
  PLSA_CHECK(o.static_map_base_bar <= lo, "static_map: the base must not be above the grid's lowest level");
  const int n = o.static_map_points;
  requireSamples("static_map", (o.preroll_s + n * n * (o.static_map_base_s + o.static_map_hold_s)) * o.sample_rate_hz,
                 o.sample_rate_hz);
  CommandWriter w("static_map", o.sample_rate_hz);
  Eigen::RowVector3d base = Eigen::RowVector3d::Zero();
  base(a) = base(b) = o.static_map_base_bar;
  w.preroll(base, o.preroll_s);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      Eigen::RowVector3d point = base;
      point(a) = lo + (hi - lo) * i / (n - 1);
      point(b) = lo + (hi - lo) * j / (n - 1);
      w.hold(base, o.static_map_base_s);
      w.hold(point, o.static_map_hold_s);
    }
  return {"static_map", w.matrix(), w.recordFrom()};
}

Experiment makeExperiment(const std::string& name, const ExperimentOptions& o) {
  if (name == "staircase1") return staircaseExperiment(o);
  if (name == "grid2") return gridExperiment(o);
  if (name == "joystick") return joystickExperiment(o);
  if (name == "static_map") return staticMapExperiment(o);
  if (name == "grid2_joint") return gridJointExperiment(o);
  throw std::invalid_argument("unknown experiment '" + name +
                              "' (choose staircase1, grid2, grid2_joint, joystick or static_map)");
}

io::Log runExperiment(Actuator& actuator, const Experiment& experiment) {
  PLSA_CHECK(experiment.commands.cols() == 3, "runExperiment: commands must have 3 columns");
  const Eigen::Index first = experiment.record_from;
  const Eigen::Index T = experiment.commands.rows() - first;
  PLSA_CHECK(first >= 0 && T >= 1, "runExperiment: the experiment records no samples");
  for (Eigen::Index k = 0; k < first; ++k)
    actuator.step({experiment.commands(k, 0), experiment.commands(k, 1), experiment.commands(k, 2)});
  actuator.startRecording();
  io::Log log;
  log.source = "plsa simulate (" + experiment.name + ")";
  log.columns = io::standard_columns::recorded();
  log.data.resize(T, 9);
  for (Eigen::Index k = 0; k < T; ++k) {
    const Eigen::RowVector3d c = experiment.commands.row(first + k);
    const ActuatorSample s = actuator.step({c(0), c(1), c(2)});
    log.data.row(k) << s.time_s, s.command_bar[0], s.command_bar[1], s.command_bar[2], s.pressure_bar[0],
        s.pressure_bar[1], s.pressure_bar[2], s.bend_deg, s.steer_deg;
    if (!log.data.row(k).allFinite())
      throw std::runtime_error(
          "simulate: the simulated actuator's state stopped being a finite number at t = " + std::to_string(s.time_s) +
          " s (" + experiment.name + "); no log is written. A shorter internal_step_s in the configuration may help");
  }
  const SimConfig& c = actuator.config();
  std::ostringstream rate;
  rate << c.sample_rate_hz;
  log.metadata["sample_rate_hz"] = rate.str();
  log.metadata["source"] = "plsa simulated actuator";
  log.metadata["experiment"] = experiment.name;
  log.metadata["units"] = "time_s s; cmd_*, p_* bar gauge; bend_deg, steer_deg deg";
  std::string on;
  for (const auto& e : effectNames())
    if (c.effectEnabled(e)) on += (on.empty() ? "" : " ") + e;
  log.metadata["effects"] = on.empty() ? "none" : on;
  return log;
}

}  // namespace plsa::sim
