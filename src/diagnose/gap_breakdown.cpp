#include "plsa/diagnose/gap_breakdown.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <numeric>

#include <unsupported/Eigen/FFT>

namespace plsa::diagnose {
namespace {

constexpr double kChange = 0.005;  // bar over the direction window: below this, holding

std::string fmt(const char* f, double a, double b = 0, double c = 0) {
  char buf[256];
  std::snprintf(buf, sizeof buf, f, a, b, c);
  return buf;
}

double correlation(const std::vector<double>& a, const std::vector<double>& b) {
  const std::size_t n = a.size();
  if (n < 10) return 0.0;
  double ma = 0, mb = 0;
  for (std::size_t i = 0; i < n; ++i) ma += a[i], mb += b[i];
  ma /= n, mb /= n;
  double sab = 0, saa = 0, sbb = 0;
  for (std::size_t i = 0; i < n; ++i) {
    sab += (a[i] - ma) * (b[i] - mb);
    saa += (a[i] - ma) * (a[i] - ma);
    sbb += (b[i] - mb) * (b[i] - mb);
  }
  return saa > 0 && sbb > 0 ? sab / std::sqrt(saa * sbb) : 0.0;
}

struct Sample {
  std::array<double, 3> cmd;
  std::array<int, 3> dir;  // +1 rising, -1 falling, 0 holding, per chamber
  double since_change_s;
  double r_sq;
  std::array<double, 2> parts;  // squared residual split (bending/steering, or y_1/y_2)
  Eigen::Vector2d r;
  double sim_sq = 0.0;  // squared size of the sim's output (bending vector)
  double t_s;
};

// The residual split, per output, along and across the simulated tip
// direction (angles with a simulation to refer to) or per output.
std::array<double, 2> residualParts(const Eigen::Vector2d& r, const BreakdownInputs& in, std::size_t run,
                                    Eigen::Index i) {
  if (in.map == OutputMap::kAngles && in.sim_outputs) {
    const Eigen::Vector2d v = (*in.sim_outputs)[run].row(i).transpose();
    const double norm = v.norm();
    if (!(norm > 1e-6)) return {r.squaredNorm(), 0.0};
    const Eigen::Vector2d u = v / norm, perp(-u.y(), u.x());
    return {std::pow(r.dot(u), 2), std::pow(r.dot(perp), 2)};
  }
  return {r(0) * r(0), r(1) * r(1)};
}

// Every sample of every run: commands, their direction of change over half
// a second, time since the last change, and the residual.
std::vector<Sample> samplesOf(const BreakdownInputs& in) {
  const auto& runs = *in.runs;
  const auto& res = *in.residuals;
  std::vector<Sample> all;
  for (std::size_t k = 0; k < runs.size(); ++k) {
    const RunData& run = runs[k];
    const auto w = std::max<Eigen::Index>(1, std::lround(0.5 / run.sample_time_s));
    double last_change = 0.0;
    for (Eigen::Index i = 0; i < run.samples(); ++i) {
      Sample s;
      s.t_s = i * run.sample_time_s;
      for (int c = 0; c < 3; ++c) {
        s.cmd[static_cast<std::size_t>(c)] = run.commands(i, c);
        const double d = run.commands(i, c) - run.commands(std::max<Eigen::Index>(0, i - w), c);
        s.dir[static_cast<std::size_t>(c)] = d > kChange ? 1 : (d < -kChange ? -1 : 0);
        if (i > 0 && std::abs(run.commands(i, c) - run.commands(i - 1, c)) > 1e-4) last_change = s.t_s;
      }
      s.since_change_s = s.t_s - last_change;
      s.r = res[k].row(i).transpose();
      s.r_sq = s.r.squaredNorm();
      if (in.sim_outputs) s.sim_sq = (*in.sim_outputs)[k].row(i).squaredNorm();
      s.parts = residualParts(s.r, in, k, i);
      all.push_back(s);
    }
  }
  return all;
}

// The samples with the totals every share divides by.
struct SamplePool {
  std::vector<Sample> all;
  double n = 0, total = 0, overall_rms = 0;
  std::array<std::string, 2> out_names;

  SamplePool(std::vector<Sample> samples, OutputMap map) : all(std::move(samples)) {
    n = static_cast<double>(all.size());
    for (const auto& s : all) total += s.r_sq;
    total = std::max(total, 1e-300);
    overall_rms = std::sqrt(total / n);
    out_names = map == OutputMap::kAngles ? std::array<std::string, 2>{"bending", "steering"}
                                          : std::array<std::string, 2>{"output 1", "output 2"};
  }
  template <typename Pick>
  ResidualShare share(const std::string& label, Pick pick) const {
    double sum = 0, count = 0;
    for (const auto& s : all)
      if (pick(s)) sum += s.r_sq, count += 1;
    return ResidualShare{label, count > 0 ? std::sqrt(sum / count) : 0.0, sum / total, count / n};
  }
};

void addByOutput(Breakdown& b, const SamplePool& p, bool angles) {
  for (int k = 0; k < 2; ++k) {
    double sum = 0;
    for (const auto& s : p.all) sum += s.parts[static_cast<std::size_t>(k)];
    b.by_output.push_back(
        {p.out_names[static_cast<std::size_t>(k)] +
             (angles ? (k == 0 ? " (along the tip direction, deg)" : " (across it, deg of arc)") : ""),
         std::sqrt(sum / p.n), sum / p.total, 1.0});
  }
}

void addByDirectionAndState(Breakdown& b, const SamplePool& p) {
  auto dominant = [](const Sample& s) {
    int best = 0;
    for (int c = 1; c < 3; ++c)
      if (std::abs(s.dir[static_cast<std::size_t>(c)]) > std::abs(s.dir[static_cast<std::size_t>(best)])) best = c;
    return s.dir[static_cast<std::size_t>(best)];
  };
  b.by_direction = {p.share("pressure rising", [&](const Sample& s) { return dominant(s) > 0; }),
                    p.share("pressure falling", [&](const Sample& s) { return dominant(s) < 0; }),
                    p.share("pressures holding", [&](const Sample& s) { return dominant(s) == 0; })};
  b.by_state = {
      p.share("steady (no command change for 1.5 s)", [](const Sample& s) { return s.since_change_s >= 1.5; }),
      p.share("transient", [](const Sample& s) { return s.since_change_s < 1.5; })};
}

// Frequency bands of the residual, by Parseval over each run's spectrum.
void addByBand(Breakdown& b, const BreakdownInputs& in, const SamplePool& p) {
  const auto& runs = *in.runs;
  const auto& res = *in.residuals;
  const std::vector<std::pair<double, std::string>> bands = {{0.05, "offset and drift (< 0.05 Hz)"},
                                                             {0.5, "slow (0.05-0.5 Hz)"},
                                                             {2.0, "bending dynamics (0.5-2 Hz)"},
                                                             {1e9, "fast (> 2 Hz)"}};
  std::vector<double> band_energy(bands.size(), 0.0);
  Eigen::FFT<double> fft;
  for (std::size_t k = 0; k < runs.size(); ++k)
    for (int c = 0; c < 2; ++c) {
      std::vector<double> x(static_cast<std::size_t>(res[k].rows()));
      for (std::size_t i = 0; i < x.size(); ++i) x[i] = res[k](static_cast<Eigen::Index>(i), c);
      std::vector<std::complex<double>> X;
      fft.fwd(X, x);
      const double df = 1.0 / (runs[k].sample_time_s * static_cast<double>(x.size()));
      for (std::size_t f = 0; f < X.size(); ++f) {
        const double hz = std::min(f, X.size() - f) * df;
        std::size_t band = 0;
        while (band + 1 < bands.size() && hz >= bands[band].first) ++band;
        band_energy[band] += std::norm(X[f]);
      }
    }
  const double band_total = std::max(1e-300, std::accumulate(band_energy.begin(), band_energy.end(), 0.0));
  for (std::size_t i = 0; i < bands.size(); ++i)
    b.by_band.push_back(
        {bands[i].second, p.overall_rms * std::sqrt(band_energy[i] / band_total), band_energy[i] / band_total, 0.0});
}

// The pressure grid: four equal bands per chamber, by direction of that
// chamber (by_region, top_places), and the chamber-1 x chamber-2 gap map.
constexpr int kBands = 4;
struct Cell {
  double sum = 0, count = 0;
  std::array<double, 2> parts{};
};
using PlaceCells = std::array<std::array<std::array<Cell, 3>, kBands>, 3>;  // [chamber][band][direction + 1]
using MapCells = std::array<std::array<Cell, kBands>, kBands>;              // [chamber 2 band][chamber 1 band]

GridPlace placeOf(const Cell& p, int c, int k, int d, const Breakdown& b, const SamplePool& pool) {
  static const std::array<std::string, 3> dir_names = {"falling", "holding", "rising"};
  GridPlace g;
  g.chamber = c + 1;
  g.from_bar = b.grid_edges_bar[static_cast<std::size_t>(k)];
  g.to_bar = b.grid_edges_bar[static_cast<std::size_t>(k + 1)];
  g.direction = dir_names[static_cast<std::size_t>(d + 1)];
  g.rms = std::sqrt(p.sum / p.count);
  g.share = p.sum / pool.total;
  g.samples = p.count / pool.n;
  const std::string what = p.parts[0] >= p.parts[1] ? pool.out_names[0] : pool.out_names[1];
  g.words = what + ", chamber " + std::to_string(c + 1) + fmt(" between %.2f and %.2f bar", g.from_bar, g.to_bar) +
            (d == 0 ? ", pressure holding" : (d > 0 ? ", pressure rising" : ", pressure falling")) +
            fmt(": residual %.3g RMS, %.1fx the overall RMS, %.0f%% of the samples", g.rms, g.rms / pool.overall_rms,
                100 * g.samples);
  return g;
}

void addByRegion(Breakdown& b, const BreakdownInputs& in, const SamplePool& pool) {
  for (int e = 0; e <= kBands; ++e) b.grid_edges_bar.push_back(in.max_pressure_bar * e / kBands);
  auto band_of = [&](double p) {
    return static_cast<std::size_t>(std::clamp(static_cast<int>(p / in.max_pressure_bar * kBands), 0, kBands - 1));
  };
  PlaceCells place{};
  MapCells grid{};
  for (const auto& s : pool.all) {  // one pass over the samples
    for (std::size_t c = 0; c < 3; ++c) {
      Cell& p = place[c][band_of(s.cmd[c])][static_cast<std::size_t>(s.dir[c] + 1)];
      p.sum += s.r_sq, p.count += 1;
      p.parts[0] += s.parts[0], p.parts[1] += s.parts[1];
    }
    Cell& g = grid[band_of(s.cmd[1])][band_of(s.cmd[0])];
    g.sum += s.r_sq, g.count += 1;
  }
  for (int c = 0; c < 3; ++c)
    for (int k = 0; k < kBands; ++k)
      for (int d = -1; d <= 1; ++d) {
        const Cell& p =
            place[static_cast<std::size_t>(c)][static_cast<std::size_t>(k)][static_cast<std::size_t>(d + 1)];
        if (p.count >= 5) b.by_region.push_back(placeOf(p, c, k, d, b, pool));
      }
  std::vector<GridPlace> ranked;
  for (const auto& g : b.by_region)
    if (g.samples >= 0.03) ranked.push_back(g);
  std::sort(ranked.begin(), ranked.end(), [](const GridPlace& a, const GridPlace& c) { return a.rms > c.rms; });
  ranked.resize(std::min<std::size_t>(3, ranked.size()));
  b.top_places = ranked;
  b.gap_map = Eigen::MatrixXd::Constant(kBands, kBands, NAN);
  for (int r = 0; r < kBands; ++r)
    for (int c = 0; c < kBands; ++c) {
      const Cell& g = grid[static_cast<std::size_t>(r)][static_cast<std::size_t>(c)];
      if (g.count >= 5) b.gap_map(r, c) = std::sqrt(g.sum / g.count);
    }
}

// Hysteresis: how much of the residual the direction of change explains.
Signature hysteresisSignature(const SamplePool& p) {
  const auto& all = p.all;
  Eigen::MatrixXd X(static_cast<Eigen::Index>(all.size()), 4);
  Eigen::MatrixXd R(static_cast<Eigen::Index>(all.size()), 2);
  for (std::size_t i = 0; i < all.size(); ++i) {
    X.row(static_cast<Eigen::Index>(i)) << 1.0, all[i].dir[0], all[i].dir[1], all[i].dir[2];
    R.row(static_cast<Eigen::Index>(i)) = all[i].r.transpose();
  }
  const Eigen::MatrixXd beta = X.colPivHouseholderQr().solve(R);
  Eigen::MatrixXd Xc = Eigen::MatrixXd::Ones(X.rows(), 1);
  const Eigen::MatrixXd mean_only = Xc.colPivHouseholderQr().solve(R);
  const double r2 = 1.0 - (R - X * beta).squaredNorm() / std::max(1e-300, (R - Xc * mean_only).squaredNorm());
  return {r2, r2 > 0.15, fmt("direction of pressure change explains %.0f%% of the residual", 100 * r2)};
}

// A deadzone: at low pressure the real tip barely moves while the sim
// bends, so the residual is large relative to the sim's own output there.
Signature deadzoneSignature(const SamplePool& p) {
  double low_r = 0, low_v = 0, high_r = 0, high_v = 0, low_n = 0;
  for (const auto& s : p.all) {
    if (s.since_change_s < 1.0) continue;
    const double m = std::max({s.cmd[0], s.cmd[1], s.cmd[2]});
    if (m > 0.005 && m < 0.12) low_r += s.r_sq, low_v += s.sim_sq, low_n += 1;
    if (m >= 0.12) high_r += s.r_sq, high_v += s.sim_sq;
  }
  const double rel_low = low_v > 0 ? std::sqrt(low_r / low_v) : 0.0;
  const double rel_high = high_v > 0 ? std::sqrt(high_r / high_v) : 0.0;
  const double ratio = rel_high > 0 && low_n / p.n > 0.02 ? rel_low / rel_high : 0.0;
  return {ratio, ratio > 2.0,
          fmt("relative residual below 0.12 bar is %.1fx that above (%.0f%% vs %.0f%% of the sim's output)", ratio,
              100 * rel_low, 100 * rel_high)};
}

Signature couplingSignature(const SamplePool& p) {
  auto pressurised = [](const Sample& s) { return (s.cmd[0] > 0.1) + (s.cmd[1] > 0.1) + (s.cmd[2] > 0.1); };
  const ResidualShare multi = p.share("multi", [&](const Sample& s) { return pressurised(s) >= 2; });
  const ResidualShare single = p.share("single", [&](const Sample& s) { return pressurised(s) == 1; });
  const double ratio = single.rms > 0 && multi.samples > 0.03 ? multi.rms / single.rms : 0.0;
  return {ratio, ratio > 1.5, fmt("residual with two or more chambers pressurised is %.2fx that with one", ratio)};
}

Signature creepSignature(const SamplePool& p) {
  std::vector<double> hold, mag;
  for (const auto& s : p.all)
    if (s.since_change_s >= 0.5 && std::max({s.cmd[0], s.cmd[1], s.cmd[2]}) > 0.05) {
      hold.push_back(std::min(s.since_change_s, 10.0));
      mag.push_back(std::sqrt(s.r_sq));
    }
  const double c = correlation(hold, mag);
  return {c, c > 0.3, fmt("residual grows during holds: correlation %.2f with time held", c)};
}

Signature lagSignature(const Breakdown& b) {
  const double steady = b.by_state[0].rms, transient = b.by_state[1].rms;
  const double ratio = steady > 0 ? transient / steady : 0.0;
  return {ratio, ratio > 2.5, fmt("transient residual is %.2fx the steady one", ratio)};
}

Signature stiffeningSignature(const SamplePool& p) {
  std::vector<double> level, mag;
  for (const auto& s : p.all)
    if (s.since_change_s >= 1.5) {
      level.push_back(s.cmd[0] + s.cmd[1] + s.cmd[2]);
      mag.push_back(std::sqrt(s.r_sq));
    }
  const double c = correlation(level, mag);
  return {c, c > 0.4, fmt("steady residual grows with total pressure: correlation %.2f", c)};
}

Signature sensorBiasSignature(const SamplePool& p) {
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const auto& s : p.all) mean += s.r;
  mean /= p.n;
  std::vector<double> t, proj;
  const Eigen::Vector2d dir = mean.norm() > 0 ? Eigen::Vector2d(mean / mean.norm()) : Eigen::Vector2d(1, 0);
  for (const auto& s : p.all) {
    t.push_back(s.t_s);
    proj.push_back(s.r.dot(dir));
  }
  const double offset = mean.norm() / std::max(1e-300, p.overall_rms);
  const double drift = std::abs(correlation(t, proj));
  const double score = std::max(offset, drift);
  return {score, score > 0.5,
          fmt("a constant offset makes %.0f%% of the residual RMS; drift correlation %.2f", 100 * offset, drift)};
}

}  // namespace

Breakdown breakdownGap(const BreakdownInputs& in) {
  const SamplePool pool(samplesOf(in), in.map);
  Breakdown b;
  addByOutput(b, pool, in.map == OutputMap::kAngles);
  addByDirectionAndState(b, pool);
  addByBand(b, in, pool);
  addByRegion(b, in, pool);
  b.signatures["hysteresis"] = hysteresisSignature(pool);
  b.signatures["deadzone"] = deadzoneSignature(pool);
  b.signatures["coupling"] = couplingSignature(pool);
  b.signatures["creep"] = creepSignature(pool);
  b.signatures["pneumatic_lag"] = lagSignature(b);
  b.signatures["stiffening"] = stiffeningSignature(pool);
  b.signatures["sensor_bias"] = sensorBiasSignature(pool);
  return b;
}

}  // namespace plsa::diagnose
