// The same n-step prediction computed the straightforward way, as a first
// implementation would: every bank a dense state-space filter stepped with
// dynamic Eigen matrices, the schedule blended over every region each step,
// fresh copies and temporaries on every call. plsa-bench measures the
// predictor against it, on the same model in the same run, and checks first
// that both predict the same.
#pragma once

#include <vector>

#include <Eigen/Dense>

#include "plsa/model/dio_pwl_obf_model.hpp"
#include "plsa/predict/predictor_options.hpp"
#include "plsa/predict/sensor_yaw.hpp"
#include "plsa/obf/obf_bank.hpp"

namespace plsa::bench {

class StraightforwardPredictor {
 public:
  explicit StraightforwardPredictor(const DioPwlObfModel& m) : m_(m) {
    const int nodes = m.schedule_side == ScheduleSide::kInput ? m.partition.regionCount() : 1;
    for (int j = 0; j < m.inputCount(); ++j)
      for (const PlayChannel& c : m.shaping.play[static_cast<std::size_t>(j)]) {
        play_.push_back(c);
        channel_input_.push_back(j);
      }
    for (int o = 0; o < m.outputCount(); ++o) {
      int channel = 0;
      for (int r = 0; r < nodes; ++r) {
        channel = 0;
        for (int j = 0; j < m.inputCount(); ++j) {
          const ObfBank<> bank(m.poles[static_cast<std::size_t>(o)][static_cast<std::size_t>(j)]);
          for (std::size_t c = 0; c < m.shaping.play[static_cast<std::size_t>(j)].size(); ++c, ++channel)
            banks_.push_back({o, r, channel, bank.A(), bank.B(), r * m.regressorSize(o) + channel * bank.size()});
        }
      }
    }
    coefficients_ = m.coefficients;
    if (nodes > 1) {
      std::vector<Eigen::VectorXd> stacked;
      for (int o = 0; o < m.outputCount(); ++o) stacked.push_back(m.stackedCoefficients(o));
      coefficients_ = {stacked};
    }
  }

  void update(const Eigen::VectorXd& u, const Eigen::VectorXd& y_logged) {
    const Eigen::VectorXd y = toModel(y_logged);
    if (m_.output_frame == OutputFrame::kTipCartesian) steer_ = y_logged(1);
    if (x_.empty()) {
      for (const Bank& b : banks_) x_.push_back(Eigen::VectorXd::Zero(b.A.rows()));
      u_ = us_ = u;
      vc_ = Eigen::VectorXd(static_cast<Eigen::Index>(play_.size()));
      const double sum = positiveSumAbove(u_, m_.shaping.threshold);
      for (std::size_t c = 0; c < play_.size(); ++c)
        vc_(static_cast<Eigen::Index>(c)) =
            playStartState(coupledLevel(levelAbove(u_(channel_input_[c]), m_.shaping.threshold), sum,
                                        m_.shaping.coupling, m_.shaping.softening),
                           play_[c], m_.shaping.start);
      w_ = nodeWeights(us_);
      y_ = y;
      startSensorYaw(y);
      return;
    }
    if (yaw_.registering()) tip_ += increments(x_, us_, dir_);
    if (m_.output_frame == OutputFrame::kTipCartesian) yaw_.add(tip_(0), tip_(1), y(0), y(1));
    step(x_, u_, us_, vc_, w_, dir_, u);
    y_ = y;
  }

  /// The whole horizon, allocated afresh: rows are steps ahead, in the log's frame.
  Eigen::MatrixXd predict(int horizon, const Eigen::MatrixXd& plan) const {
    std::vector<Eigen::VectorXd> x = x_;
    Eigen::VectorXd u = u_, us = us_, vc = vc_, w = w_, y = y_;
    DirectionState dir = dir_;
    Eigen::MatrixXd out(horizon, m_.outputCount());
    for (int h = 0; h < horizon; ++h) {
      y += increments(x, us, dir);
      out.row(h) = y.transpose();
      if (h + 1 == horizon) break;
      const Eigen::VectorXd next = h < plan.rows() ? Eigen::VectorXd(plan.row(h).transpose()) : u;
      step(x, u, us, vc, w, dir, next);
    }
    if (m_.output_frame == OutputFrame::kTipCartesian) {
      const double a = yaw_.angle();  // the increments turned into the sensor's frame
      for (int h = 0; h < horizon && a != 0.0; ++h)
        out.row(h) = y_.transpose() + (Eigen::Rotation2Dd(a) * (out.row(h) - y_.transpose()).transpose()).transpose();
      double reference = steer_;
      for (int h = 0; h < horizon; ++h) {
        tipAngles(out(h, 0), out(h, 1), reference, m_.radiansPerAngleUnit(), out(h, 0), out(h, 1));
        reference = out(h, 1);
      }
    }
    return out;
  }

 private:
  struct Bank {
    int output, node, channel;
    Eigen::MatrixXd A;
    Eigen::VectorXd B;
    int offset;  // of its coefficients in its output's vector
  };

  // A tip-frame input-side model registers the sensor's yaw from its first
  // sample (the predictor's default window): its tip there is its output
  // level and each bank's settled state, (I - A)^-1 B, weighted as it is driven.
  void startSensorYaw(const Eigen::VectorXd& y) {
    if (m_.output_frame != OutputFrame::kTipCartesian || m_.schedule_side != ScheduleSide::kInput ||
        m_.output_level.empty())
      return;
    const double dt = m_.sample_time_s;
    const PredictorOptions defaults;  // in degrees, as the bench's models are
    yaw_.configure(yawRegistrationWindow(defaults.yaw_registration_s, dt),
                   m_.training_drift_per_s.size() == 2 ? m_.training_drift_per_s[1] * kRadPerDeg * dt : 0.0, 0,
                   defaults.yaw_registration_min_bend_deg, trackingForget(defaults.yaw_tracking_s, dt));
    yaw_.restart();
    tip_ = Eigen::Vector2d(m_.output_level[0], m_.output_level[1]);
    for (const Bank& b : banks_) {
      const Eigen::Index n = b.A.rows();
      const Eigen::VectorXd settled = (Eigen::MatrixXd::Identity(n, n) - b.A).partialPivLu().solve(b.B);
      tip_(b.output) += coefficients_[0][static_cast<std::size_t>(b.output)].segment(b.offset, n).dot(settled) *
                        w_(b.node) * vc_(b.channel);
    }
    yaw_.add(tip_(0), tip_(1), y(0), y(1));
  }

  Eigen::VectorXd toModel(const Eigen::VectorXd& y) const {
    Eigen::VectorXd m = y;
    if (m_.output_frame == OutputFrame::kTipCartesian) tipComponents(y(0), y(1), m_.radiansPerAngleUnit(), m(0), m(1));
    return m;
  }

  Eigen::VectorXd nodeWeights(const Eigen::VectorXd& us) const {
    Eigen::VectorXd w = Eigen::VectorXd::Zero(m_.partition.regionCount());
    ScheduleBlend blend;
    m_.partition.blend(us, DirectionState{}, blend);
    for (int k = 0; k < blend.count; ++k)
      w(blend.region[static_cast<std::size_t>(k)]) += blend.weight[static_cast<std::size_t>(k)];
    return w;
  }

  Eigen::VectorXd increments(const std::vector<Eigen::VectorXd>& x, const Eigen::VectorXd& us,
                             const DirectionState& dir) const {
    Eigen::VectorXd dy = Eigen::VectorXd::Zero(m_.outputCount());
    ScheduleBlend blend;
    if (m_.schedule_side == ScheduleSide::kInput) {
      blend.count = 1;
      blend.region[0] = 0;
      blend.weight[0] = 1.0;
    } else {
      m_.partition.blend(us, dir, blend);
    }
    for (std::size_t b = 0; b < banks_.size(); ++b)
      for (int k = 0; k < blend.count; ++k) {
        const Eigen::VectorXd& c = coefficients_[static_cast<std::size_t>(blend.region[static_cast<std::size_t>(k)])]
                                                [static_cast<std::size_t>(banks_[b].output)];
        dy(banks_[b].output) +=
            blend.weight[static_cast<std::size_t>(k)] * c.segment(banks_[b].offset, x[b].size()).dot(x[b]);
      }
    return dy;
  }

  void step(std::vector<Eigen::VectorXd>& x, Eigen::VectorXd& u, Eigen::VectorXd& us, Eigen::VectorXd& vc,
            Eigen::VectorXd& w, DirectionState& dir, const Eigen::VectorXd& next) const {
    m_.partition.updateDirections(Eigen::VectorXd(next - u), dir);
    u = next;
    const double pole = m_.schedulePole();
    us = pole * us + (1.0 - pole) * u;
    const double sum = positiveSumAbove(u, m_.shaping.threshold);
    Eigen::VectorXd delta(vc.size());
    for (std::size_t c = 0; c < play_.size(); ++c) {
      const auto cc = static_cast<Eigen::Index>(c);
      const double level = coupledLevel(levelAbove(u(channel_input_[c]), m_.shaping.threshold), sum,
                                        m_.shaping.coupling, m_.shaping.softening);
      const double v = play_[c].follow(level, vc(cc));
      delta(cc) = v - vc(cc);
      vc(cc) = v;
    }
    const bool input_side = m_.schedule_side == ScheduleSide::kInput;
    const Eigen::VectorXd w_next = input_side ? nodeWeights(us) : w;
    for (std::size_t b = 0; b < banks_.size(); ++b) {
      const Bank& bank = banks_[b];
      const double d =
          input_side ? w_next(bank.node) * vc(bank.channel) - w(bank.node) * (vc(bank.channel) - delta(bank.channel))
                     : delta(bank.channel);
      x[b] = bank.A * x[b] + bank.B * d;
    }
    w = w_next;
  }

  DioPwlObfModel m_;
  std::vector<PlayChannel> play_;
  std::vector<int> channel_input_;
  std::vector<Bank> banks_;
  std::vector<std::vector<Eigen::VectorXd>> coefficients_;
  std::vector<Eigen::VectorXd> x_;
  Eigen::VectorXd u_, us_, vc_, w_, y_;
  DirectionState dir_;
  double steer_ = 0.0;
  SensorYaw yaw_;  // tip frame: the turn from the model's frame into the sensor's
  Eigen::Vector2d tip_ = Eigen::Vector2d::Zero();
};

}  // namespace plsa::bench
