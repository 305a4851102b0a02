#include "plsa/identify/pole_clustering.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include <nlopt.hpp>

#include "plsa/core/angle_units.hpp"
#include "plsa/core/check.hpp"
#include "plsa/obf/decay_rate.hpp"

namespace plsa::identify {
namespace {

using C = std::complex<double>;
constexpr double kMaxModulus = 0.9995;

// Centres are parameterised as [real centres..., (radius, angle) per pair...].
struct Layout {
  int reals;
  int pairs;
  int size() const { return reals + 2 * pairs; }
  int clusters() const { return reals + pairs; }
};

Layout layoutOf(const ClusteringOptions& o) {
  PLSA_CHECK(o.centres >= 1, "pole clustering: need at least one centre");
  PLSA_CHECK(o.complex_pairs >= 0 && 2 * o.complex_pairs <= o.centres,
             "pole clustering: complex pairs must fit in the number of centres");
  // An infinite m weighs every pole alike (u^m -> 0): no clustering is left.
  PLSA_CHECK(o.fuzziness > 1.0 && std::isfinite(o.fuzziness),
             "pole clustering: fuzziness m must be finite and > 1, got " + std::to_string(o.fuzziness));
  return {o.centres - 2 * o.complex_pairs, o.complex_pairs};
}

void checkPoles(const std::vector<C>& poles) {
  PLSA_CHECK(!poles.empty(), "pole clustering: no identified poles to cluster");
  for (const auto& p : poles)
    PLSA_CHECK(std::isfinite(p.real()) && std::isfinite(p.imag()) && std::abs(p) < 1.0,
               "pole clustering: identified pole " + std::to_string(p.real()) + "+" + std::to_string(p.imag()) +
                   "i is not stable; drop it before clustering");
}

C clusterCentre(const Layout& L, const std::vector<double>& x, int i) {
  if (i < L.reals) return {x[static_cast<std::size_t>(i)], 0.0};
  const auto b = static_cast<std::size_t>(L.reals + 2 * (i - L.reals));
  return std::polar(x[b], x[b + 1]);
}

std::vector<C> expand(const Layout& L, const std::vector<double>& x) {
  std::vector<C> out;
  for (int i = 0; i < L.clusters(); ++i) {
    const C c = clusterCentre(L, x, i);
    out.push_back(c);
    if (i >= L.reals) out.push_back(std::conj(c));
  }
  return out;
}

// Kolmogorov distance to a cluster (a pair's nearer member).
double clusterDistance(const Layout& L, const std::vector<double>& x, int i, C z) {
  const C c = clusterCentre(L, x, i);
  double d = poleDistance(z, c);
  if (i >= L.reals) d = std::min(d, poleDistance(z, std::conj(c)));
  return d;
}

void bounds(const Layout& L, std::vector<double>& lo, std::vector<double>& hi) {
  lo.assign(static_cast<std::size_t>(L.size()), -kMaxModulus);
  hi.assign(static_cast<std::size_t>(L.size()), kMaxModulus);
  for (int p = 0; p < L.pairs; ++p) {
    const auto b = static_cast<std::size_t>(L.reals + 2 * p);
    lo[b] = 0.0;
    lo[b + 1] = 1e-3;
    hi[b + 1] = kPi - 1e-3;
  }
}

// Spread the real centres over the poles' quantiles; pairs start on the most complex poles.
std::vector<double> initialCentres(const Layout& L, const std::vector<C>& poles) {
  std::vector<double> re;
  for (const auto& p : poles) re.push_back(p.real());
  std::sort(re.begin(), re.end());
  std::vector<double> x;
  for (int i = 0; i < L.reals; ++i) {
    const double q = (i + 0.5) / L.reals * static_cast<double>(re.size() - 1);
    x.push_back(std::clamp(re[static_cast<std::size_t>(std::lround(q))], -kMaxModulus, kMaxModulus));
  }
  std::vector<C> byImag = poles;
  std::sort(byImag.begin(), byImag.end(), [](C a, C b) { return std::abs(a.imag()) > std::abs(b.imag()); });
  for (int p = 0; p < L.pairs; ++p) {
    const C c = byImag[static_cast<std::size_t>(p) % byImag.size()];
    x.push_back(std::min(std::abs(c), kMaxModulus));
    x.push_back(std::clamp(std::abs(std::arg(c)), 0.05, kPi - 0.05));
  }
  return x;
}

// Fuzzy memberships mu[i][k] from distances d[i][k] (columns sum to 1).
std::vector<std::vector<double>> memberships(const std::vector<std::vector<double>>& d, double m) {
  const std::size_t nc = d.size(), nz = d[0].size();
  std::vector<std::vector<double>> mu(nc, std::vector<double>(nz, 0.0));
  const double e = 2.0 / (m - 1.0);
  for (std::size_t k = 0; k < nz; ++k) {
    std::size_t zero = nc;
    for (std::size_t i = 0; i < nc; ++i)
      if (d[i][k] < 1e-12) zero = i;
    if (zero < nc) {
      mu[zero][k] = 1.0;
      continue;
    }
    for (std::size_t i = 0; i < nc; ++i) {
      double s = 0.0;
      for (std::size_t j = 0; j < nc; ++j) s += std::pow(d[i][k] / d[j][k], e);
      mu[i][k] = 1.0 / s;
    }
  }
  return mu;
}

// Poles closer than this (Kolmogorov distance) to one kept before them set
// the same constraint to within it: the minimax keeps one of each group.
constexpr double kSamePole = 1e-6;

// One of each group of near-identical poles. Near-identical constraints are
// degenerate for COBYLA's linear subproblem, which can spin inside it (no
// evaluation counted, so maxeval never stops it): 111 poles within 2e-7 of
// each other held it for four minutes. The max over the poles moves by less than kSamePole.
std::vector<C> distinctPoles(const std::vector<C>& poles) {
  std::vector<C> kept;
  for (const C& p : poles)
    if (std::none_of(kept.begin(), kept.end(), [&](C q) { return poleDistance(p, q) < kSamePole; })) kept.push_back(p);
  return kept;
}

// The minimax's variables: the centres' entries listed in `free` (the rest
// stay at `centres`' values), then the epigraph variable t.
struct EpigraphData {
  const Layout* L;
  const std::vector<C>* poles;
  const std::vector<std::vector<double>>* mum;  // mu^m
  std::vector<double> centres;
  std::vector<std::size_t> free;
};

std::vector<double> centresOf(const EpigraphData& e, const double* x) {
  std::vector<double> v = e.centres;
  for (std::size_t j = 0; j < e.free.size(); ++j) v[e.free[j]] = x[j];
  return v;
}

// Every entry free, or (with memberships) all but those of centres no pole
// weighs: the fuzzy sum does not depend on them, and a centre free to drift
// there ends wherever the optimiser's exploration left it (at the stability
// bound, 0.9995, on noise-free first-order data).
std::vector<std::size_t> freeEntries(const Layout& L, const std::vector<std::vector<double>>* mum) {
  std::vector<std::size_t> free;
  double total = 0.0;
  if (mum)
    for (const auto& row : *mum)
      for (double w : row) total += w;
  for (int i = 0; i < L.clusters(); ++i) {
    double weight = 0.0;
    if (mum)
      for (double w : (*mum)[static_cast<std::size_t>(i)]) weight += w;
    if (mum && weight <= 1e-14 * total) continue;
    const int first = i < L.reals ? i : L.reals + 2 * (i - L.reals), count = i < L.reals ? 1 : 2;
    for (int j = 0; j < count; ++j) free.push_back(static_cast<std::size_t>(first + j));
  }
  return free;
}

double epigraphObjective(unsigned n, const double* x, double* grad, void*) {
  if (grad) {
    for (unsigned i = 0; i + 1 < n; ++i) grad[i] = 0.0;
    grad[n - 1] = 1.0;
  }
  return x[n - 1];
}

// g_k = sum_i mu_ik^m d(z_k, v_i) - t <= 0 for every identified pole k.
void epigraphConstraints(unsigned m, double* result, unsigned n, const double* x, double* grad, void* data) {
  const auto* e = static_cast<const EpigraphData*>(data);
  const std::vector<double> v = centresOf(*e, x);
  for (unsigned k = 0; k < m; ++k) {
    double s = 0.0;
    for (int i = 0; i < e->L->clusters(); ++i)
      s += (*e->mum)[static_cast<std::size_t>(i)][k] * clusterDistance(*e->L, v, i, (*e->poles)[k]);
    result[k] = s - x[n - 1];
  }
  if (grad) std::fill(grad, grad + static_cast<std::size_t>(m) * n, 0.0);  // COBYLA ignores gradients
}

// g_k = sum_i log d(z_k, v_i) - t <= 0: the epigraph of log rho, the
// Kolmogorov criterion that FKcM's fuzzy sum stands in for.
void logRhoConstraints(unsigned m, double* result, unsigned n, const double* x, double* grad, void* data) {
  const auto* e = static_cast<const EpigraphData*>(data);
  const std::vector<double> v = centresOf(*e, x);
  for (unsigned k = 0; k < m; ++k) {
    double s = 0.0;
    for (const C& c : expand(*e->L, v)) s += std::log(std::max(poleDistance((*e->poles)[k], c), 1e-300));
    result[k] = s - x[n - 1];
  }
  if (grad) std::fill(grad, grad + static_cast<std::size_t>(m) * n, 0.0);  // COBYLA ignores gradients
}

// min t over (the free centre entries, t) subject to constraint(k) <= t for
// every pole, with COBYLA from (data.centres, t0); returns the centres it
// ends on (its best point when it stops on round-off).
std::vector<double> epigraphMinimax(nlopt::mfunc constraints, EpigraphData& data, const std::vector<double>& lo,
                                    const std::vector<double>& hi, double t0, double t_lower, double tol, double xtol) {
  const auto n = static_cast<unsigned>(data.free.size() + 1);
  nlopt::opt opt(nlopt::LN_COBYLA, n);
  std::vector<double> lb, ub, z;
  for (std::size_t j : data.free) {
    lb.push_back(lo[j]);
    ub.push_back(hi[j]);
    z.push_back(data.centres[j]);
  }
  lb.push_back(t_lower);
  ub.push_back(HUGE_VAL);
  z.push_back(t0);
  opt.set_lower_bounds(lb);
  opt.set_upper_bounds(ub);
  opt.set_min_objective(epigraphObjective, nullptr);
  opt.add_inequality_mconstraint(constraints, &data, std::vector<double>(data.poles->size(), tol));
  opt.set_xtol_abs(xtol);
  opt.set_maxeval(4000);
  double f = t0;
  try {
    opt.optimize(z, f);
  } catch (const nlopt::roundoff_limited&) {
    // COBYLA stopped on round-off: z holds its best point, which is what we want.
  }
  return centresOf(data, z.data());
}

ClusteringResult finish(std::string method, const Layout& L, const std::vector<double>& x, const std::vector<C>& poles,
                        double objective, int iterations) {
  ClusteringResult r;
  r.method = std::move(method);
  r.centres = expand(L, x);
  r.rho = decayRate(r.centres, poles);
  r.objective = objective;
  r.iterations = iterations;
  return r;
}

double rhoOf(const Layout& L, const std::vector<double>& x, const std::vector<C>& poles) {
  return decayRate(expand(L, x), poles);
}

// max_k sum_i mu_ik^m d(z_k, v_i): FKcM's criterion at centres x.
double largestWeightedSum(const Layout& L, const std::vector<double>& x, const std::vector<C>& poles,
                          const std::vector<std::vector<double>>& mum) {
  double worst = 0.0;
  for (std::size_t k = 0; k < poles.size(); ++k) {
    double s = 0.0;
    for (int i = 0; i < L.clusters(); ++i)
      s += mum[static_cast<std::size_t>(i)][k] * clusterDistance(L, x, i, poles[k]);
    worst = std::max(worst, s);
  }
  return worst;
}

// FKcM's centre update: memberships from the distances to the centres x,
// then min over the centres of the criterion in epigraph form. A minimax
// whose answer is worse than x (COBYLA can end on a worse point than it
// started from) leaves x where it is. Writes the criterion it ends on to *objective.
std::vector<double> fkcmStep(const Layout& L, const std::vector<double>& x, const std::vector<C>& poles,
                             const std::vector<double>& lo, const std::vector<double>& hi, double fuzziness,
                             double* objective) {
  std::vector<std::vector<double>> d(static_cast<std::size_t>(L.clusters()), std::vector<double>(poles.size()));
  for (int i = 0; i < L.clusters(); ++i)
    for (std::size_t k = 0; k < poles.size(); ++k)
      d[static_cast<std::size_t>(i)][k] = clusterDistance(L, x, i, poles[k]);
  std::vector<std::vector<double>> mum = memberships(d, fuzziness);
  for (auto& row : mum)
    for (double& v : row) v = std::pow(v, fuzziness);
  const double start = largestWeightedSum(L, x, poles, mum);
  EpigraphData data{&L, &poles, &mum, x, freeEntries(L, &mum)};
  const std::vector<double> z = epigraphMinimax(epigraphConstraints, data, lo, hi, start, 0.0, 1e-10, 1e-9);
  const double end = largestWeightedSum(L, z, poles, mum);
  *objective = std::min(start, end);
  return end <= start ? z : x;
}

}  // namespace

ClusteringResult fkcmClustering(const std::vector<C>& all_poles, const ClusteringOptions& o) {
  checkPoles(all_poles);
  const Layout L = layoutOf(o);
  const std::vector<C> poles = distinctPoles(all_poles);
  std::vector<double> x = initialCentres(L, all_poles);
  std::vector<double> lo, hi;
  bounds(L, lo, hi);
  double objective = 0.0;
  int it = 0;
  for (; it < o.max_iterations; ++it) {
    const std::vector<double> z = fkcmStep(L, x, poles, lo, hi, o.fuzziness, &objective);
    double moved = 0.0;
    for (std::size_t i = 0; i < x.size(); ++i) moved = std::max(moved, std::abs(z[i] - x[i]));
    x = z;
    if (moved < o.tolerance) {
      ++it;
      break;
    }
  }
  if (o.refine_on_rho) {
    // The fuzzy sum stands in for the Kolmogorov criterion max_k prod_i d(z_k, v_i),
    // i.e. rho: a last minimax on it (epigraph of log rho) from FKcM's centres,
    // kept only where it lowers rho over every identified pole.
    EpigraphData data{&L, &poles, nullptr, x, freeEntries(L, nullptr)};
    const std::vector<double> z = epigraphMinimax(
        logRhoConstraints, data, lo, hi, std::log(std::max(rhoOf(L, x, poles), 1e-300)), -HUGE_VAL, 1e-9, 1e-10);
    if (rhoOf(L, z, all_poles) < rhoOf(L, x, all_poles)) x = z;
  }
  return finish(o.refine_on_rho ? "FKcM+rho" : "FKcM", L, x, all_poles, objective, it);
}

ClusteringResult fuzzyCMeansClustering(const std::vector<C>& poles, const ClusteringOptions& o) {
  checkPoles(poles);
  const Layout L = layoutOf(o);
  PLSA_CHECK(L.pairs == 0, "fuzzy c-means here clusters real centres only");
  std::vector<double> x = initialCentres(L, poles);
  double objective = 0.0;
  int it = 0;
  for (; it < o.max_iterations; ++it) {
    std::vector<std::vector<double>> d(static_cast<std::size_t>(L.reals), std::vector<double>(poles.size()));
    for (int i = 0; i < L.reals; ++i)
      for (std::size_t k = 0; k < poles.size(); ++k)
        d[static_cast<std::size_t>(i)][k] = std::abs(poles[k] - C(x[static_cast<std::size_t>(i)], 0));
    const auto mu = memberships(d, o.fuzziness);
    double moved = 0.0;
    objective = 0.0;
    for (int i = 0; i < L.reals; ++i) {
      double num = 0.0, den = 0.0;
      for (std::size_t k = 0; k < poles.size(); ++k) {
        const double w = std::pow(mu[static_cast<std::size_t>(i)][k], o.fuzziness);
        num += w * poles[k].real();
        den += w;
        objective += w * d[static_cast<std::size_t>(i)][k] * d[static_cast<std::size_t>(i)][k];
      }
      // A centre no pole belongs to (one that coincides with another, which
      // took the poles sitting on both) stays where it is.
      const double next = den > 0.0 ? std::clamp(num / den, -kMaxModulus, kMaxModulus) : x[static_cast<std::size_t>(i)];
      moved = std::max(moved, std::abs(next - x[static_cast<std::size_t>(i)]));
      x[static_cast<std::size_t>(i)] = next;
    }
    if (moved < o.tolerance) {
      ++it;
      break;
    }
  }
  return finish("fuzzy c-means", L, x, poles, objective, it);
}

ClusteringResult kMeansClustering(const std::vector<C>& poles, const ClusteringOptions& o) {
  checkPoles(poles);
  const Layout L = layoutOf(o);
  PLSA_CHECK(L.pairs == 0, "k-means here clusters real centres only");
  std::mt19937_64 rng(o.seed);
  std::vector<double> best;
  double best_sse = std::numeric_limits<double>::infinity();
  int total_it = 0;
  for (int restart = 0; restart < 10; ++restart) {
    // k-means++ seeding on the real parts.
    std::vector<double> x;
    std::uniform_int_distribution<std::size_t> pick(0, poles.size() - 1);
    x.push_back(poles[pick(rng)].real());
    while (static_cast<int>(x.size()) < L.reals) {
      std::vector<double> w;
      for (const auto& p : poles) {
        double d = INFINITY;
        for (double c : x) d = std::min(d, (p.real() - c) * (p.real() - c));
        w.push_back(d + 1e-18);
      }
      std::discrete_distribution<std::size_t> dd(w.begin(), w.end());
      x.push_back(poles[dd(rng)].real());
    }
    double sse = 0.0;
    for (int it = 0; it < o.max_iterations; ++it, ++total_it) {
      std::vector<double> sum(x.size(), 0.0);
      std::vector<int> count(x.size(), 0);
      sse = 0.0;
      for (const auto& p : poles) {
        std::size_t arg = 0;
        for (std::size_t i = 1; i < x.size(); ++i)
          if (std::abs(p.real() - x[i]) < std::abs(p.real() - x[arg])) arg = i;
        sum[arg] += p.real();
        ++count[arg];
        sse += (p.real() - x[arg]) * (p.real() - x[arg]);
      }
      double moved = 0.0;
      for (std::size_t i = 0; i < x.size(); ++i) {
        if (count[i] == 0) continue;  // empty cluster keeps its centre
        const double next = sum[i] / count[i];
        moved = std::max(moved, std::abs(next - x[i]));
        x[i] = next;
      }
      if (moved < o.tolerance) break;
    }
    if (sse < best_sse) {
      best_sse = sse;
      best = x;
    }
  }
  std::sort(best.begin(), best.end());
  for (double& v : best) v = std::clamp(v, -kMaxModulus, kMaxModulus);
  return finish("k-means", L, best, poles, best_sse, total_it);
}

namespace {
struct RhoData {
  const Layout* L;
  const std::vector<C>* poles;
};
double rhoObjective(unsigned n, const double* x, double*, void* data) {
  const auto* r = static_cast<const RhoData*>(data);
  return rhoOf(*r->L, std::vector<double>(x, x + n), *r->poles);
}
}  // namespace

ClusteringResult globalRhoSearch(const std::vector<C>& poles, const ClusteringOptions& o) {
  checkPoles(poles);
  const Layout L = layoutOf(o);
  std::vector<double> lo, hi;
  bounds(L, lo, hi);
  // Real centres only need the poles' span (a centre outside it is never better).
  double pmin = 1.0, pmax = -1.0;
  for (const auto& p : poles) {
    pmin = std::min(pmin, p.real());
    pmax = std::max(pmax, p.real());
  }
  for (int i = 0; i < L.reals; ++i) {
    lo[static_cast<std::size_t>(i)] = std::max(-kMaxModulus, pmin - 1e-3);
    hi[static_cast<std::size_t>(i)] = std::min(kMaxModulus, pmax + 1e-3);
  }
  RhoData data{&L, &poles};
  const auto n = static_cast<unsigned>(L.size());
  std::vector<std::vector<double>> starts;
  {
    nlopt::opt g(nlopt::GN_DIRECT_L, n);
    g.set_lower_bounds(lo);
    g.set_upper_bounds(hi);
    g.set_min_objective(rhoObjective, &data);
    g.set_maxeval(o.global_evaluations);
    std::vector<double> x(n);
    for (unsigned i = 0; i < n; ++i) x[i] = 0.5 * (lo[i] + hi[i]);
    double f = 0.0;
    try {
      g.optimize(x, f);
    } catch (const nlopt::roundoff_limited&) {}
    starts.push_back(x);
  }
  starts.push_back(initialCentres(L, poles));
  if (L.pairs == 0) {
    for (const auto& r : {fkcmClustering(poles, o), fuzzyCMeansClustering(poles, o), kMeansClustering(poles, o)}) {
      std::vector<double> x;
      for (const auto& c : r.centres) x.push_back(std::clamp(c.real(), -kMaxModulus, kMaxModulus));
      for (unsigned i = 0; i < n; ++i) x[i] = std::clamp(x[i], lo[i], hi[i]);
      starts.push_back(x);
    }
  }
  std::vector<double> best;
  double best_f = INFINITY;
  for (auto x : starts) {
    nlopt::opt loc(nlopt::LN_NELDERMEAD, n);
    loc.set_lower_bounds(lo);
    loc.set_upper_bounds(hi);
    loc.set_min_objective(rhoObjective, &data);
    loc.set_maxeval(5000);
    loc.set_xtol_abs(1e-10);
    double f = rhoOf(L, x, poles);
    try {
      loc.optimize(x, f);
    } catch (const nlopt::roundoff_limited&) {}
    f = rhoOf(L, x, poles);
    if (f < best_f) {
      best_f = f;
      best = x;
    }
  }
  return finish("global search (DIRECT-L + Nelder-Mead)", L, best, poles, best_f, o.global_evaluations);
}

}  // namespace plsa::identify
