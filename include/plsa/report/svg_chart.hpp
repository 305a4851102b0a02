// Self-contained SVG charts for HTML reports (no external files): line charts
// of time series, a pole map on the unit disk, bar charts, heat maps. Every
// chart is drawn in full without scripts; a page that includes chartScript()
// also zooms and reads out its line charts.
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

/// A line chart holds at most this many samples per series for zoom and hover
/// (every k-th beyond it); its drawn lines hold about 1500 points.
inline constexpr Eigen::Index kMaxEmbeddedSamples = 20000;

/// Line chart of series over x (increasing), as a `div.plot` holding the SVG
/// and its samples (JSON). Long series are drawn thinned to about 1500 points;
/// with chartScript() on the page, zooming redraws them from the samples.
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

/// An inline script (no external files) that makes every line chart on the
/// page interactive: hover shows the time and each series' value at the
/// nearest sample; dragging across the plot zooms every chart with the same
/// x label to that span (y rescaled to what is visible, lines redrawn from
/// the samples, min and max kept per pixel); double-click zooms back out.
/// Put it once, after the last chart.
std::string chartScript();

/// How to use the charts chartScript() makes interactive, for the page's text.
inline constexpr const char* kChartHint =
    "Drag across a trace to zoom in (the page's traces zoom together), double-click to zoom out, and hover to "
    "read values.";

/// HTML escaping for text nodes.
std::string escape(const std::string& s);

}  // namespace plsa::report
