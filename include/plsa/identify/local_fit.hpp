// Step 2: a local LTI model per local data set and input-output pair
// (paper: one pole, no zero), de-offset to the level before the step.
// Poles that are unstable or badly determined are reported, not passed on.
#pragma once

#include <complex>
#include <string>
#include <vector>

#include <Eigen/Dense>

namespace plsa::identify {

struct LocalFit {
  std::vector<std::complex<double>> poles;    ///< physical poles passed on
  std::vector<std::complex<double>> dropped;  ///< spare poles of a higher-order fit that sat on the noise
  double gain = 0.0;                          ///< steady-state gain of the fitted model
  double pole_std_error = 0.0;                ///< largest standard error of the AR coefficients
  double snr = 0.0;                           ///< response amplitude / residual std
  bool usable = false;
  /// Not usable, but only as badly determined or too small for the noise:
  /// its poles are physical (stable, not alternating), a last resort.
  bool uncertain = false;
  std::string reason;  ///< why not usable, in words
};

/// ARX(order, order) without feedthrough on the de-offset segment:
/// y_k = sum a_i y_{k-i} + sum b_i u_{k-i}. `u0`, `y0` are the levels
/// before the step. Usable if every pole is in [0, 1), the AR standard error
/// is below `max_std_error`, and the response stands `min_snr` times above the residual.
LocalFit fitLocalModel(const Eigen::VectorXd& u, const Eigen::VectorXd& y, double u0, double y0, int order = 1,
                       double max_std_error = 0.02, double min_snr = 8.0);

}  // namespace plsa::identify
