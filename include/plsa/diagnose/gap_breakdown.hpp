// Where a sim-to-real gap lies: the residual (real minus calibrated sim)
// broken down by output, by region of the pressure grid and direction of
// change, steady state versus transient, and frequency band; the places it
// concentrates named in words; and the signatures that point to an effect.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "plsa/diagnose/run_data.hpp"

namespace plsa::diagnose {

struct ResidualShare {
  std::string label;
  double rms = 0.0;      ///< RMS residual (output units) of the samples in this part
  double share = 0.0;    ///< this part's share of the total squared residual
  double samples = 0.0;  ///< share of the samples in this part
};

/// One place on the pressure grid: a chamber, a band of its pressure, a direction.
struct GridPlace {
  int chamber = 0;  ///< 1-based
  double from_bar = 0.0, to_bar = 0.0;
  std::string direction;  ///< "rising", "falling" or "holding"
  double rms = 0.0, share = 0.0, samples = 0.0;
  std::string words;  ///< "bending, chamber 1 between 0.05 and 0.10 bar, pressure rising: ..."
};

/// Evidence for one candidate effect: a score (larger = stronger) and whether
/// it clears the threshold that makes it count as support.
struct Signature {
  double score = 0.0;
  bool present = false;
  std::string evidence;  ///< in words, with the numbers
};

struct Breakdown {
  std::vector<ResidualShare> by_output;
  std::vector<ResidualShare> by_direction;  ///< rising / falling / holding (of the most-changing chamber)
  std::vector<ResidualShare> by_state;      ///< steady / transient
  std::vector<ResidualShare> by_band;       ///< frequency bands of the residual
  std::vector<GridPlace> by_region;         ///< every (chamber, band, direction) with data
  std::vector<GridPlace> top_places;        ///< where it concentrates, worst first (at most 3)
  std::vector<double> grid_edges_bar;       ///< band edges of the pressure grid
  Eigen::MatrixXd gap_map;  ///< RMS residual over chamber 1 (cols) x chamber 2 (rows) bands; NaN: no data
  std::map<std::string, Signature> signatures;  ///< by candidate effect name
};

struct BreakdownInputs {
  const std::vector<RunData>* runs = nullptr;
  const std::vector<Eigen::MatrixXd>* residuals = nullptr;    ///< per run, samples x 2 (real - sim)
  const std::vector<Eigen::MatrixXd>* sim_outputs = nullptr;  ///< per run, for bend/steer breakdowns (angles)
  OutputMap map = OutputMap::kAngles;
  std::array<double, 3> bend_direction_deg = {0.0, 120.0, 240.0};
  double max_pressure_bar = 0.4;
};

Breakdown breakdownGap(const BreakdownInputs& in);

}  // namespace plsa::diagnose
