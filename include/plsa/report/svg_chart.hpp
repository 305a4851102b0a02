// Self-contained SVG charts for HTML reports (no scripts, no external files):
// line charts of time series, a pole map on the unit disk, bar charts.
#pragma once

#include <complex>
#include <string>
#include <vector>

#include <Eigen/Dense>

namespace plsa::report {

struct Series {
  std::string label;
  Eigen::VectorXd y;  ///< NaN where undefined (not drawn)
  std::string color;
  bool dashed = false;
};

/// Line chart of series over x; long series are thinned to about 1500 points.
std::string lineChart(const std::string& title, const Eigen::VectorXd& x, const std::vector<Series>& series,
                      const std::string& x_label, const std::string& y_label, int width = 900, int height = 280);

struct PoleGroup {
  std::string label;
  std::vector<std::complex<double>> poles;
  std::string color;
  bool cross = false;  ///< crosses instead of dots
};

/// Poles on the unit disk, zoomed to [zoom_min, 1] on the real axis when given.
std::string poleMap(const std::string& title, const std::vector<PoleGroup>& groups, double zoom_min = -1.0,
                    int size = 420);

struct Bar {
  std::string label;
  double value;
  std::string color;
};
std::string barChart(const std::string& title, const std::vector<Bar>& bars, const std::string& y_label,
                     int width = 600, int height = 280);

/// The largest finite value (0 when there is none): a heat map's default scale.
double heatScale(const Eigen::MatrixXd& values);

/// A grid of cells coloured by value (white = 0 .. dark red = scale_max, or
/// heatScale(values) when scale_max <= 0), with the value written in each;
/// NaN cells grey ("no data"), and a colour bar from 0 to the scale, labelled
/// with `unit`. Give maps to be compared the same scale_max.
std::string heatMap(const std::string& title, const Eigen::MatrixXd& values, const std::vector<std::string>& row_labels,
                    const std::vector<std::string>& col_labels, const std::string& row_axis,
                    const std::string& col_axis, int cell = 64, double scale_max = 0.0, const std::string& unit = "");

/// HTML escaping for text nodes.
std::string escape(const std::string& s);

}  // namespace plsa::report
