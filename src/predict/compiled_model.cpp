#include "plsa/predict/compiled_model.hpp"

#include <cmath>
#include <string>

#include "plsa/core/check.hpp"
#include "plsa/obf/obf_bank.hpp"
#include "plsa/predict/sensor_yaw.hpp"

namespace plsa {
namespace {

// Largest condition number of an eigenbasis the modal form uses: prediction
// error grows with it, and 1e5 keeps it near 1e-11.
constexpr double kMaxModalCondition = 1e5;

void checkOptions(const PredictorOptions& o) {
  PLSA_CHECK(o.max_horizon >= 1 && o.max_horizon <= kMaxPredictorHorizon,
             "Predictor: max_horizon " + std::to_string(o.max_horizon) + " is outside 1.." +
                 std::to_string(kMaxPredictorHorizon) + " samples");
  // Infinite values would switch the input-range or gap check off unannounced.
  PLSA_CHECK(std::isfinite(o.input_margin) && o.input_margin >= 0, "Predictor: input_margin must be finite and >= 0");
  PLSA_CHECK(std::isfinite(o.max_gap_factor) && o.max_gap_factor > 1,
             "Predictor: max_gap_factor must be finite and > 1");
  PLSA_CHECK(std::isfinite(o.yaw_registration_s) && o.yaw_registration_s >= 0,
             "Predictor: yaw_registration_s must be finite and >= 0");
  PLSA_CHECK(std::isfinite(o.yaw_registration_min_bend_deg) && o.yaw_registration_min_bend_deg >= 0,
             "Predictor: yaw_registration_min_bend_deg must be finite and >= 0");
}

// Stage 1: what every form shares.
void compileCommon(const DioPwlObfModel& m, const PredictorOptions& o, CompiledModel& c) {
  c.n_u = m.inputCount();
  c.n_y = m.outputCount();
  c.frame = m.output_frame;
  if (m.output_frame == OutputFrame::kTipCartesian) {
    c.rad_per_angle_unit = m.radiansPerAngleUnit();
    c.angle_unit_per_rad = angleUnitsPerRadian(m.output_unit);
  }
  c.sample_time = m.sample_time_s;
  const std::string tracking = yawTrackingProblem(o.yaw_tracking_s, m.sample_time_s);
  PLSA_CHECK(tracking.empty(), "Predictor: " + tracking);
  c.output_level = m.output_level;
  if (m.output_frame == OutputFrame::kTipCartesian && m.schedule_side == ScheduleSide::kInput &&
      !m.output_level.empty() && !o.simulate) {
    c.yaw_window = yawRegistrationWindow(o.yaw_registration_s, m.sample_time_s);
    if (c.yaw_window > 0 && m.training_drift_per_s.size() == 2)
      c.yaw_drift_per_sample = m.training_drift_per_s[1] * c.rad_per_angle_unit * m.sample_time_s;
    c.yaw_min_bend = o.yaw_registration_min_bend_deg * kRadPerDeg / c.rad_per_angle_unit;
    c.yaw_forget = trackingForget(o.yaw_tracking_s, m.sample_time_s);
  }
  c.max_horizon = o.max_horizon;
  const double span = m.input_max - m.input_min;
  c.accept_min = std::isfinite(span) ? m.input_min - o.input_margin * span : -INFINITY;
  c.accept_max = std::isfinite(span) ? m.input_max + o.input_margin * span : INFINITY;
  c.input_side = m.schedule_side == ScheduleSide::kInput;
  c.partition = c.input_side ? PwlPartition::single() : m.partition;
  c.node_partition = m.partition;
  c.nodes = c.input_side ? m.partition.regionCount() : 1;
  if (c.input_side) {
    c.node_grid.inputs = m.partition.inputs();
    c.node_grid.levels = m.partition.breakpoints();
    int stride = 1;
    for (const auto& l : c.node_grid.levels) {
      c.node_grid.strides.push_back(stride);
      stride *= static_cast<int>(l.size());
    }
  }
  c.shaping = m.shaping;
  c.schedule_pole = m.schedulePole();
  c.first_channel.push_back(0);
  for (int j = 0; j < c.n_u; ++j) {
    for (const PlayChannel& r : m.shaping.play[static_cast<std::size_t>(j)]) {
      c.play.push_back(r);
      c.channel_input.push_back(j);
    }
    c.first_channel.push_back(static_cast<int>(c.play.size()));
  }
  c.poles = m.poles[0][0].size();
  for (int oo = 0; oo < c.n_y; ++oo)
    for (int j = 0; j < c.n_u; ++j) {
      const PoleSet& ps = m.poles[static_cast<std::size_t>(oo)][static_cast<std::size_t>(j)];
      PLSA_CHECK(ps.size() == c.poles, "Predictor: every filter bank needs the same number of poles");
      for (const auto& p : ps.poles()) c.pole_values.push_back(p.real()), c.pole_values.push_back(p.imag());
    }
  c.banks = c.n_y * c.nodes * static_cast<int>(c.play.size());
}

// Stage 2: the banks as state-space filters, in coefficient order.
void compileStateSpace(const DioPwlObfModel& m, CompiledModel& c) {
  StateSpaceForm& s = c.state_space;
  bool all_real = true;
  for (int o = 0; o < c.n_y; ++o)
    for (int j = 0; j < c.n_u; ++j) {
      const PoleSet& ps = m.poles[static_cast<std::size_t>(o)][static_cast<std::size_t>(j)];
      const ObfBank<> bank(ps);
      s.A.push_back(bank.A());
      s.B.push_back(bank.B());
      const bool real = ps.sections().size() == static_cast<std::size_t>(ps.size());  // no conjugate pair
      Eigen::VectorXd xi = Eigen::VectorXd::Zero(ps.size()), gain = Eigen::VectorXd::Zero(ps.size());
      for (int i = 0; i < ps.size() && real; ++i) {
        xi(i) = ps.sections()[static_cast<std::size_t>(i)].pole.real();
        gain(i) = std::sqrt(1.0 - xi(i) * xi(i));
      }
      all_real = all_real && real;
      s.xi.push_back(xi);
      s.gain.push_back(gain);
      s.dc_gain.push_back(bank.transfer(1.0).real());
    }
  s.cascade = all_real;
  for (int o = 0; o < c.n_y; ++o) {
    const int per_region = m.regressorSize(o);
    for (int r = 0; r < c.nodes; ++r)
      for (int j = 0; j < c.n_u; ++j)
        for (int ch = c.first_channel[static_cast<std::size_t>(j)];
             ch < c.first_channel[static_cast<std::size_t>(j) + 1]; ++ch) {
          s.bank_output.push_back(o);
          s.bank_node.push_back(r);
          s.bank_input.push_back(j);
          s.bank_channel.push_back(ch);
          s.coefficient_offset.push_back(r * per_region + ch * c.poles);
        }
  }
  s.coefficient = m.coefficients;
  if (c.input_side) {  // the nodes' coefficients stacked in bank order, as one region
    std::vector<Eigen::VectorXd> stacked;
    for (int o = 0; o < c.n_y; ++o) stacked.push_back(m.stackedCoefficients(o));
    s.coefficient = {stacked};
  }
}

// The eigenbasis of bank (o, j), or an empty matrix when it has none fit to
// use (a conjugate or repeated pole, or an ill-conditioned basis).
Eigen::MatrixXd eigenbasis(const StateSpaceForm& s, std::size_t group, int n) {
  if (!s.cascade) return {};
  const Eigen::VectorXd& lambda = s.xi[group];
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < i; ++k)
      if (lambda(i) == lambda(k)) return {};  // a Jordan block, no eigenbasis
  const Eigen::MatrixXd& A = s.A[group];
  if (!A.triangularView<Eigen::StrictlyUpper>().toDenseMatrix().isZero(0.0)) return {};
  // A is lower triangular with the poles on its diagonal: each eigenvector by forward substitution.
  Eigen::MatrixXd v = Eigen::MatrixXd::Zero(n, n);
  for (Eigen::Index k = 0; k < n; ++k) {
    v(k, k) = 1.0;
    for (Eigen::Index i = k + 1; i < n; ++i)
      v(i, k) = A.row(i).segment(k, i - k).dot(v.col(k).segment(k, i - k)) / (lambda(k) - A(i, i));
    v.col(k).normalize();
  }
  const Eigen::MatrixXd vinv = v.inverse();
  if (!vinv.allFinite() || v.norm() * vinv.norm() > kMaxModalCondition) return {};
  if ((v * lambda.asDiagonal() * vinv - A).cwiseAbs().maxCoeff() > 1e-9) return {};  // guards the algebra
  return v;
}

// A held input's lagged schedule in closed form (ModalForm::lag_sum): the
// stretch's KS_d columns are (S_lambda - S_rate) / (lambda - rate), rate =
// rho^d, so the rows need only the power sums of the modes and of each rate:
// each output's power_sum gains the columns S_rate, and lag_gap_inverse holds
// 1 / (lambda - rate), except where the two nearly coincide (the quotient
// would lose digits) and the pair keeps its own KS column (lag_coincident).
void addLagRates(const CompiledModel& c, ModalForm& f, int orders) {
  const auto modes = static_cast<Eigen::Index>(f.lambda.size());
  f.lag_power.resize(std::max({c.max_horizon, orders, 4}) + 1);
  f.lag_power(0) = 1.0;
  for (Eigen::Index h = 1; h < f.lag_power.size(); ++h)
    f.lag_power(h) = f.lag_power(h - 1) * c.schedule_pole < 1e-200 ? 0.0 : f.lag_power(h - 1) * c.schedule_pole;
  f.lag_gap_inverse = Eigen::MatrixXd::Zero(modes, orders);
  f.lag_coincident.assign(static_cast<std::size_t>(c.n_y), {});
  for (Eigen::Index q = 0; q < modes; ++q)
    for (int d = 1; d <= orders; ++d) {
      const double gap = f.lambda(q) - f.lag_power(d);
      if (std::abs(gap) >= kLagGapFloor)
        f.lag_gap_inverse(q, d - 1) = 1.0 / gap;
      else
        f.lag_coincident[static_cast<std::size_t>(q / c.poles % c.n_y)].push_back({static_cast<int>(q), d});
    }
  for (Eigen::MatrixXd& sum : f.power_sum) {
    const Eigen::Index first = sum.cols();
    sum.conservativeResize(Eigen::NoChange, first + orders);
    for (int d = 1; d <= orders; ++d) {
      const double rate = f.lag_power(d);
      double power = 1.0, acc = 0.0;
      for (int h = 0; h < c.max_horizon; ++h) {
        acc += power;
        sum(h, first + d - 1) = acc;
        power = power * rate < 1e-200 ? 0.0 : power * rate;  // no subnormal powers
      }
    }
  }
}

// The modal form's eigenbases, one per bank group; false when a group has
// none fit to use.
bool addModalBases(const StateSpaceForm& s, int n, ModalForm& f) {
  for (std::size_t g = 0; g < s.A.size(); ++g) {
    Eigen::MatrixXd v = eigenbasis(s, g, n);
    if (v.size() == 0) return false;
    f.basis_inverse.push_back(v.inverse());
    f.basis.push_back(std::move(v));
  }
  return true;
}

// Each mode's pole and input gain, and where its states' coefficients start.
void addModes(const CompiledModel& c, ModalForm& f) {
  const StateSpaceForm& s = c.state_space;
  const int n = c.poles, Q = c.n_u * c.n_y * n;
  f.lambda.resize(Q);
  f.beta.resize(Q);
  f.offset.assign(1, 0);
  for (int j = 0; j < c.n_u; ++j)
    for (int o = 0; o < c.n_y; ++o) {
      const auto g = static_cast<std::size_t>(o * c.n_u + j);
      const Eigen::VectorXd beta = f.basis_inverse[g] * s.B[g];
      for (int i = 0; i < n; ++i) {
        const int q = (j * c.n_y + o) * n + i;
        f.lambda(q) = s.xi[g](i);
        f.beta(q) = beta(i);
        f.offset.push_back(f.offset.back() + c.nodes * c.channels(j));
      }
    }
}

// Each bank's coefficients, carried into its eigenbasis (V^T c), go to its states.
void addModalCoefficients(const CompiledModel& c, ModalForm& f) {
  const StateSpaceForm& s = c.state_space;
  const int n = c.poles;
  const auto regions = static_cast<Eigen::Index>(s.coefficient.size());
  f.coefficient = RowMajorMatrix::Zero(regions, f.offset.back());
  for (std::size_t b = 0; b < s.bank_output.size(); ++b) {
    const int o = s.bank_output[b], j = s.bank_input[b], r = s.bank_node[b];
    const int k = r * c.channels(j) + (s.bank_channel[b] - c.first_channel[static_cast<std::size_t>(j)]);
    const Eigen::MatrixXd& v = f.basis[static_cast<std::size_t>(o * c.n_u + j)];
    for (Eigen::Index m = 0; m < regions; ++m) {
      const Eigen::VectorXd modal =
          v.transpose() *
          s.coefficient[static_cast<std::size_t>(m)][static_cast<std::size_t>(o)].segment(s.coefficient_offset[b], n);
      for (int i = 0; i < n; ++i)
        f.coefficient(m, f.offset[static_cast<std::size_t>((j * c.n_y + o) * n + i)] + k) = modal(i);
    }
  }
}

// Input side: each input's modes merged across outputs into blocks of four
// (merged_lambda, merged_beta) with their node coefficients (by_copy).
void addMergedBlocks(const CompiledModel& c, ModalForm& f) {
  const int n = c.poles;
  f.block = (c.n_y * n + 3) / 4 * 4;
  f.merged_lambda = Eigen::VectorXd::Zero(c.n_u * f.block);
  f.merged_beta = Eigen::VectorXd::Zero(c.n_u * f.block);
  f.output_mask = Eigen::VectorXd::Zero(c.n_y * f.block);
  for (int o = 0; o < c.n_y; ++o) f.output_mask.segment(o * f.block + o * n, n).setOnes();
  for (int j = 0; j < c.n_u; ++j) {
    RowMajorMatrix t = RowMajorMatrix::Zero(c.nodes * c.channels(j), f.block);
    for (int o = 0; o < c.n_y; ++o)
      for (int i = 0; i < n; ++i) {
        const int q = (j * c.n_y + o) * n + i, slot = j * f.block + o * n + i;
        f.merged_lambda(slot) = f.lambda(q);
        f.merged_beta(slot) = f.beta(q);
        for (Eigen::Index k = 0; k < t.rows(); ++k)
          t(k, o * n + i) = f.coefficient(0, f.offset[static_cast<std::size_t>(q)] + k);
      }
    f.by_copy.push_back(std::move(t));
  }
}

// Input side: the tables that read the output from the states (TipReadout),
// unless a mode does not settle.
void addReadout(const CompiledModel& c, ModalForm& f) {
  const int n = c.poles;
  const Eigen::VectorXd gap = Eigen::VectorXd::Ones(f.lambda.size()) - f.lambda;
  if (!(gap.size() > 0 && gap.cwiseAbs().minCoeff() > kReadoutGapFloor)) return;
  f.readout_mode = f.lambda.cwiseQuotient(gap);
  for (int j = 0; j < c.n_u; ++j) {
    Eigen::MatrixXd t = Eigen::MatrixXd::Zero(c.nodes * c.channels(j), c.n_y);
    for (int o = 0; o < c.n_y; ++o)
      for (int i = 0; i < n; ++i) {
        const int q = (j * c.n_y + o) * n + i;
        for (Eigen::Index k = 0; k < t.rows(); ++k)
          t(k, o) += f.beta(q) / gap(q) * f.coefficient(0, f.offset[static_cast<std::size_t>(q)] + k);
      }
    f.readout_level.push_back(std::move(t));
  }
}

// Per output, the running power sums of its modes over the horizon.
void addPowerSums(const CompiledModel& c, ModalForm& f) {
  const int n = c.poles, Q = c.n_u * c.n_y * n;
  f.modes_of_output.resize(static_cast<std::size_t>(c.n_y));
  for (int q = 0; q < Q; ++q) {
    const int o = q / n % c.n_y;
    f.modes_of_output[static_cast<std::size_t>(o)].push_back(q);
  }
  for (const auto& modes : f.modes_of_output) {
    Eigen::MatrixXd sum(c.max_horizon, static_cast<Eigen::Index>(modes.size()));
    for (std::size_t t = 0; t < modes.size(); ++t) {
      const double lambda = f.lambda(modes[t]);
      double power = 1.0, acc = 0.0;
      for (int h = 0; h < c.max_horizon; ++h) {
        acc += power;
        sum(h, static_cast<Eigen::Index>(t)) = acc;
        power = std::abs(power * lambda) < 1e-200 ? 0.0 : power * lambda;  // no subnormal powers
      }
    }
    f.power_sum.push_back(std::move(sum));
  }
}

// A held input's lagged schedule in closed form (lag_sum), when the table
// stays within kMaxHeldTableDoubles.
void addHeldLagSums(const CompiledModel& c, ModalForm& f) {
  const int n = c.poles, Q = c.n_u * c.n_y * n;
  const auto orders = static_cast<int>(c.node_grid.inputs.size());
  const std::size_t doubles = static_cast<std::size_t>(c.max_horizon) * static_cast<std::size_t>(Q) * (orders + 1);
  if (c.input_side && c.schedule_pole > 0.0 && orders > 0 && doubles <= kMaxHeldTableDoubles) {
    addLagRates(c, f, orders);
    for (int o = 0; o < c.n_y; ++o) {
      const int width = (orders + 1) * n;
      Eigen::MatrixXd sum(c.max_horizon, c.n_u * width);
      for (int j = 0; j < c.n_u; ++j)
        for (int i = 0; i < n; ++i) {
          const double lambda = f.lambda((j * c.n_y + o) * n + i);
          for (int d = 0; d <= orders; ++d) {
            const double rate = std::pow(c.schedule_pole, d);
            double k = d == 0 ? 1.0 : 0.0, power = 1.0, acc = 0.0;  // d = 0: lambda^h itself
            for (int h = 0; h < c.max_horizon; ++h) {
              acc += k;
              sum(h, j * width + d * n + i) = acc;
              k = d == 0 ? (std::abs(k * lambda) < 1e-200 ? 0.0 : k * lambda) : lambda * k + power;
              power = power * rate < 1e-200 ? 0.0 : power * rate;
            }
          }
        }
      f.lag_sum.push_back(std::move(sum));
    }
  }
}

// Stage 3 (when every bank allows): the modal form.
void compileModal(CompiledModel& c) {
  ModalForm f;
  if (!addModalBases(c.state_space, c.poles, f)) return;
  addModes(c, f);
  addModalCoefficients(c, f);
  if (c.input_side) addMergedBlocks(c, f);
  if (c.input_side) addReadout(c, f);
  addPowerSums(c, f);
  addHeldLagSums(c, f);
  c.modal_form = std::move(f);
  c.modal = true;
}

}  // namespace

std::shared_ptr<const CompiledModel> compileModel(const DioPwlObfModel& model, const PredictorOptions& options) {
  checkOptions(options);
  model.validate();
  auto c = std::make_shared<CompiledModel>();
  compileCommon(model, options, *c);
  compileStateSpace(model, *c);
  if (options.modal) compileModal(*c);
  return c;
}

bool sameStructure(const CompiledModel& a, const CompiledModel& b) {
  return a.n_u == b.n_u && a.n_y == b.n_y && a.poles == b.poles && a.nodes == b.nodes && a.banks == b.banks &&
         a.frame == b.frame && a.input_side == b.input_side && a.first_channel == b.first_channel &&
         a.state_space.coefficient.size() == b.state_space.coefficient.size() &&
         a.partition.inputs() == b.partition.inputs() && a.partition.scheduling() == b.partition.scheduling() &&
         a.partition.directionSplit() == b.partition.directionSplit() &&
         a.node_partition.inputs() == b.node_partition.inputs() &&
         a.node_partition.regionCount() == b.node_partition.regionCount() && a.max_horizon == b.max_horizon;
}

}  // namespace plsa
