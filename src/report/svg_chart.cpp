#include "plsa/report/svg_chart.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <sstream>

#include "plsa/core/angle_units.hpp"

namespace plsa::report {
namespace {

std::string num(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.2f", v);
  return b;
}

std::string tick(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.4g", v);
  return b;
}

// A "nice" step for about n ticks over a span.
double niceStep(double span, int n) {
  const double raw = span / std::max(1, n);
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (m * mag >= raw) return m * mag;
  return 10 * mag;
}

}  // namespace

std::string escape(const std::string& s) {
  std::string o;
  for (char c : s) {
    if (c == '<')
      o += "&lt;";
    else if (c == '>')
      o += "&gt;";
    else if (c == '&')
      o += "&amp;";
    else if (c == '"')
      o += "&quot;";
    else
      o += c;
  }
  return o;
}

namespace {

// Where a line chart's plot area sits and which values its edges show.
struct LineFrame {
  double ml = 60, mr = 150, mt = 30, mb = 40;
  double pw = 0, ph = 0;
  double xmin = 0, xmax = 1, ymin = 0, ymax = 1;
  double X(double v) const { return ml + (v - xmin) / std::max(1e-12, xmax - xmin) * pw; }
  double Y(double v) const { return mt + (ymax - v) / (ymax - ymin) * ph; }
};

LineFrame lineFrame(const Eigen::VectorXd& x, const std::vector<Series>& series, int width, int height) {
  LineFrame f;
  f.pw = width - f.ml - f.mr;
  f.ph = height - f.mt - f.mb;
  double ymin = INFINITY, ymax = -INFINITY;
  for (const auto& s : series)
    for (Eigen::Index i = 0; i < s.y.size(); ++i)
      if (std::isfinite(s.y(i))) {
        ymin = std::min(ymin, s.y(i));
        ymax = std::max(ymax, s.y(i));
      }
  if (!std::isfinite(ymin)) ymin = 0, ymax = 1;
  if (ymax - ymin < 1e-12) ymin -= 1, ymax += 1;
  const double pad = 0.05 * (ymax - ymin);
  f.ymin = ymin - pad;
  f.ymax = ymax + pad;
  if (x.size()) f.xmin = x.minCoeff(), f.xmax = x.maxCoeff();
  return f;
}

// Title, plot area, grid lines with their tick labels, and the axis labels.
// The ticks sit in their own groups, which the page's script redraws on zoom.
void writeLineAxes(std::ostream& o, const LineFrame& f, const std::string& title, const std::string& x_label,
                   const std::string& y_label, int height) {
  o << "<text x=\"" << f.ml << "\" y=\"18\" font-size=\"14\" font-weight=\"bold\">" << escape(title) << "</text>\n";
  o << "<rect class=\"plot-area\" x=\"" << f.ml << "\" y=\"" << f.mt << "\" width=\"" << f.pw << "\" height=\"" << f.ph
    << "\" fill=\"#fafafa\" stroke=\"#999\"/>\n<g class=\"y-ticks\">";
  const double ys = niceStep(f.ymax - f.ymin, 5);
  for (double v = std::ceil(f.ymin / ys) * ys; v <= f.ymax; v += ys)
    o << "<line x1=\"" << f.ml << "\" x2=\"" << f.ml + f.pw << "\" y1=\"" << num(f.Y(v)) << "\" y2=\"" << num(f.Y(v))
      << "\" stroke=\"#e3e3e3\"/><text x=\"" << f.ml - 6 << "\" y=\"" << num(f.Y(v) + 4)
      << "\" font-size=\"11\" text-anchor=\"end\">" << tick(v) << "</text>\n";
  o << "</g><g class=\"x-ticks\">";
  const double xs = niceStep(f.xmax - f.xmin, 8);
  for (double v = std::ceil(f.xmin / xs) * xs; v <= f.xmax; v += xs)
    o << "<text x=\"" << num(f.X(v)) << "\" y=\"" << f.mt + f.ph + 15 << "\" font-size=\"11\" text-anchor=\"middle\">"
      << tick(v) << "</text>\n";
  o << "</g>\n<text x=\"" << f.ml + f.pw / 2 << "\" y=\"" << height - 6 << "\" font-size=\"12\" text-anchor=\"middle\">"
    << escape(x_label) << "</text>\n";
  o << "<text x=\"14\" y=\"" << f.mt + f.ph / 2
    << "\" font-size=\"12\" text-anchor=\"middle\" transform=\"rotate(-90 14 " << f.mt + f.ph / 2 << ")\">"
    << escape(y_label) << "</text>\n";
}

// Each series as one path (about 1500 points; NaN breaks the line), then its legend entry.
void writeLineSeries(std::ostream& o, const LineFrame& f, const Eigen::VectorXd& x, const std::vector<Series>& series) {
  const Eigen::Index n = x.size();
  const Eigen::Index stride = std::max<Eigen::Index>(1, n / 1500);
  o << "<g class=\"traces\">\n";
  for (const auto& s : series) {
    o << "<path class=\"series\" fill=\"none\" stroke=\"" << s.color << "\" stroke-width=\"1.3\""
      << (s.dashed ? " stroke-dasharray=\"5,3\"" : "") << " d=\"";
    bool pen = false;
    for (Eigen::Index i = 0; i < std::min(n, s.y.size()); i += stride) {
      if (!std::isfinite(s.y(i))) {
        pen = false;
        continue;
      }
      o << (pen ? "L" : "M") << num(f.X(x(i))) << "," << num(f.Y(s.y(i))) << " ";
      pen = true;
    }
    o << "\"/>\n";
  }
  o << "</g>\n";
  int li = 0;
  for (const auto& s : series) {
    const double ly = f.mt + 14 + 18 * li++;
    o << "<line x1=\"" << f.ml + f.pw + 10 << "\" x2=\"" << f.ml + f.pw + 30 << "\" y1=\"" << ly << "\" y2=\"" << ly
      << "\" stroke=\"" << s.color << "\" stroke-width=\"2\"" << (s.dashed ? " stroke-dasharray=\"5,3\"" : "")
      << "/><text x=\"" << f.ml + f.pw + 34 << "\" y=\"" << ly + 4 << "\" font-size=\"11\">" << escape(s.label)
      << "</text>\n";
  }
}

// x keeps 15 significant digits: a time axis in epoch seconds still resolves
// a sample; values keep 7, beyond what a readout shows.
std::string jsonNumber(double v, int digits) {
  if (!std::isfinite(v)) return "null";
  char b[32];
  std::snprintf(b, sizeof b, "%.*g", digits, v);
  return b;
}

// The chart's samples as JSON for the page's zoom and hover (every k-th above
// kMaxEmbeddedSamples). '<' never occurs in it, so it cannot end its script element.
void writeLineData(std::ostream& o, const Eigen::VectorXd& x, const std::vector<Series>& series) {
  const Eigen::Index n = x.size();
  const Eigen::Index stride = std::max<Eigen::Index>(1, (n + kMaxEmbeddedSamples - 1) / kMaxEmbeddedSamples);
  auto column = [&](const Eigen::VectorXd& v, int digits) {
    o << '[';
    for (Eigen::Index i = 0; i < n; i += stride) o << (i ? "," : "") << jsonNumber(i < v.size() ? v(i) : NAN, digits);
    o << ']';
  };
  o << "<script type=\"application/json\" class=\"plot-data\">{\"x\":";
  column(x, 15);
  o << ",\"labels\":[";
  for (std::size_t s = 0; s < series.size(); ++s) {
    o << (s ? "," : "") << '"';
    for (char c : series[s].label) o << (c == '"' || c == '\\' || c == '<' || (c >= 0 && c < 0x20) ? ' ' : c);
    o << '"';
  }
  o << "],\"series\":[";
  for (std::size_t s = 0; s < series.size(); ++s) {
    if (s) o << ',';
    column(series[s].y, 7);
  }
  o << "]}</script>\n";
}

}  // namespace

std::string lineChart(const std::string& title, const Eigen::VectorXd& x, const std::vector<Series>& series,
                      const std::string& x_label, const std::string& y_label, int width, int height) {
  const LineFrame f = lineFrame(x, series, width, height);
  std::ostringstream o;
  o << "<div class=\"plot\" data-x-label=\"" << escape(x_label) << "\">\n";
  o << "<svg class=\"chart zoomable\" xmlns=\"http://www.w3.org/2000/svg\" width=\"" << width << "\" height=\""
    << height << "\" viewBox=\"0 0 " << width << " " << height << "\" role=\"img\" aria-label=\"" << escape(title)
    << "\" data-plot=\"" << f.ml << ' ' << f.mt << ' ' << f.pw << ' ' << f.ph << "\">\n";
  writeLineAxes(o, f, title, x_label, y_label, height);
  writeLineSeries(o, f, x, series);
  o << "</svg>\n";
  writeLineData(o, x, series);
  o << "</div>\n";
  return o.str();
}

std::string poleMap(const std::string& title, const std::vector<PoleGroup>& groups, double zoom_min, int size) {
  const double m = 40;
  const double lo = zoom_min, hi = 1.02;
  const double half = (hi - lo) / 2;
  const double cx = (lo + hi) / 2;
  auto X = [&](double re) { return m + (re - (cx - half)) / (2 * half) * (size - 2 * m); };
  auto Y = [&](double im) { return size / 2.0 - im / (2 * half) * (size - 2 * m); };
  std::ostringstream o;
  o << "<svg class=\"chart\" xmlns=\"http://www.w3.org/2000/svg\" width=\"" << size + 170 << "\" height=\"" << size
    << "\" role=\"img\" aria-label=\"" << escape(title) << "\">\n";
  o << "<text x=\"" << m << "\" y=\"18\" font-size=\"14\" font-weight=\"bold\">" << escape(title) << "</text>\n";
  o << "<rect x=\"" << m << "\" y=\"" << m << "\" width=\"" << size - 2 * m << "\" height=\"" << size - 2 * m
    << "\" fill=\"#fafafa\" stroke=\"#999\"/>\n";
  // Unit circle as a polyline clipped to the view.
  o << "<path fill=\"none\" stroke=\"#888\" d=\"";
  bool pen = false;
  for (int i = 0; i <= 720; ++i) {
    const double a = i * kPi / 360;
    const double re = std::cos(a), im = std::sin(a);
    const bool in = re >= cx - half && re <= cx + half && std::abs(im) <= half;
    if (!in) {
      pen = false;
      continue;
    }
    o << (pen ? "L" : "M") << num(X(re)) << "," << num(Y(im)) << " ";
    pen = true;
  }
  o << "\"/>\n";
  o << "<line x1=\"" << m << "\" x2=\"" << size - m << "\" y1=\"" << Y(0) << "\" y2=\"" << Y(0)
    << "\" stroke=\"#ccc\"/>\n";
  for (double v = std::ceil(lo * 20) / 20; v <= 1.0 + 1e-9; v += 0.05)
    o << "<text x=\"" << num(X(v)) << "\" y=\"" << size - m + 14 << "\" font-size=\"10\" text-anchor=\"middle\">"
      << tick(v) << "</text>\n";
  int li = 0;
  for (const auto& g : groups) {
    for (const auto& p : g.poles) {
      if (p.real() < cx - half || p.real() > cx + half || std::abs(p.imag()) > half) continue;
      const double x = X(p.real()), y = Y(p.imag());
      if (g.cross)
        o << "<path class=\"pole\" d=\"M" << num(x - 5) << "," << num(y - 5) << " L" << num(x + 5) << "," << num(y + 5)
          << " M" << num(x - 5) << "," << num(y + 5) << " L" << num(x + 5) << "," << num(y - 5) << "\" stroke=\""
          << g.color << "\" stroke-width=\"2\"/>\n";
      else
        o << "<circle class=\"pole\" cx=\"" << num(x) << "\" cy=\"" << num(y) << "\" r=\"3\" fill=\"" << g.color
          << "\" fill-opacity=\"0.6\"/>\n";
    }
    const double ly = m + 10 + 18 * li++;
    o << "<circle cx=\"" << size - m + 20 << "\" cy=\"" << ly << "\" r=\"4\" fill=\"" << g.color << "\"/><text x=\""
      << size - m + 30 << "\" y=\"" << ly + 4 << "\" font-size=\"11\">" << escape(g.label) << "</text>\n";
  }
  o << "</svg>\n";
  return o.str();
}

std::string barChart(const std::string& title, const std::vector<Bar>& bars, const std::string& y_label, int width,
                     int height) {
  const double ml = 60, mr = 20, mt = 30, mb = 70;
  const double pw = width - ml - mr, ph = height - mt - mb;
  double ymax = 0, ymin = 0;
  for (const auto& b : bars) {
    ymax = std::max(ymax, b.value);
    ymin = std::min(ymin, b.value);
  }
  if (ymax - ymin < 1e-12) ymax = ymin + 1;
  ymax += 0.1 * (ymax - ymin);  // room for the value written above the tallest bar
  auto Y = [&](double v) { return mt + (ymax - v) / (ymax - ymin) * ph; };
  std::ostringstream o;
  o << "<svg class=\"chart\" xmlns=\"http://www.w3.org/2000/svg\" width=\"" << width << "\" height=\"" << height
    << "\" role=\"img\" aria-label=\"" << escape(title) << "\">\n";
  o << "<text x=\"" << ml << "\" y=\"18\" font-size=\"14\" font-weight=\"bold\">" << escape(title) << "</text>\n";
  o << "<text x=\"14\" y=\"" << mt + ph / 2 << "\" font-size=\"12\" text-anchor=\"middle\" transform=\"rotate(-90 14 "
    << mt + ph / 2 << ")\">" << escape(y_label) << "</text>\n";
  const double bw = pw / std::max<std::size_t>(1, bars.size());
  for (std::size_t i = 0; i < bars.size(); ++i) {
    const double x = ml + i * bw + bw * 0.15;
    const double y0 = Y(0), y1 = Y(bars[i].value);
    o << "<rect class=\"bar\" x=\"" << num(x) << "\" y=\"" << num(std::min(y0, y1)) << "\" width=\"" << num(bw * 0.7)
      << "\" height=\"" << num(std::abs(y1 - y0)) << "\" fill=\"" << bars[i].color << "\"/>\n";
    o << "<text x=\"" << num(x + bw * 0.35) << "\" y=\"" << num(std::min(y0, y1) - 4)
      << "\" font-size=\"11\" text-anchor=\"middle\">" << tick(bars[i].value) << "</text>\n";
    o << "<text x=\"" << num(x + bw * 0.35) << "\" y=\"" << mt + ph + 14 << "\" font-size=\"11\" text-anchor=\"end\" "
      << "transform=\"rotate(-30 " << num(x + bw * 0.35) << " " << mt + ph + 14 << ")\">" << escape(bars[i].label)
      << "</text>\n";
  }
  o << "<line x1=\"" << ml << "\" x2=\"" << ml + pw << "\" y1=\"" << Y(0) << "\" y2=\"" << Y(0)
    << "\" stroke=\"#333\"/>\n";
  o << "</svg>\n";
  return o.str();
}

double heatScale(const Eigen::MatrixXd& values) {
  double vmax = 0.0;
  for (Eigen::Index i = 0; i < values.size(); ++i)
    if (std::isfinite(values(i))) vmax = std::max(vmax, values(i));
  return vmax;
}

namespace {

// The heat map's colours from 0 (bottom) to vmax (top), five ticks, the unit above.
std::string colourBar(double x, double y, double w, double h, double vmax, const std::string& unit,
                      const std::string& title) {
  // One gradient per map: ids must be unique on a page holding several.
  const std::string id = "heat-" + std::to_string(std::hash<std::string>{}(title) % 1000000007u);
  std::ostringstream o;
  o << "<g class=\"colour-bar\"><defs><linearGradient id=\"" << id << "\" x1=\"0\" y1=\"1\" x2=\"0\" y2=\"0\">"
    << "<stop offset=\"0\" stop-color=\"#ffffff\"/><stop offset=\"1\" "
       "stop-color=\"#ff3723\"/></linearGradient></defs>\n";
  o << "<rect x=\"" << num(x) << "\" y=\"" << num(y) << "\" width=\"" << num(w) << "\" height=\"" << num(h)
    << "\" fill=\"url(#" << id << ")\" stroke=\"#999\"/>\n";
  for (int k = 0; k <= 4; ++k) {
    const double v = vmax * k / 4.0, ty = y + h - h * k / 4.0;
    o << "<line x1=\"" << num(x + w) << "\" y1=\"" << num(ty) << "\" x2=\"" << num(x + w + 4) << "\" y2=\"" << num(ty)
      << "\" stroke=\"#666\"/><text x=\"" << num(x + w + 6) << "\" y=\"" << num(ty + 4) << "\" font-size=\"10\">"
      << tick(v) << "</text>\n";
  }
  if (!unit.empty())
    o << "<text x=\"" << num(x) << "\" y=\"" << num(y - 8) << "\" font-size=\"11\">" << escape(unit) << "</text>\n";
  o << "</g>\n";
  return o.str();
}

}  // namespace

std::string heatMap(const std::string& title, const Eigen::MatrixXd& values, const std::vector<std::string>& row_labels,
                    const std::vector<std::string>& col_labels, const std::string& row_axis,
                    const std::string& col_axis, int cell, double scale_max, const std::string& unit) {
  const double ml = 110, mt = 30, mb = 50, bar_w = 16, bar_gap = 24;
  const auto rows = values.rows(), cols = values.cols();
  const int width = static_cast<int>(ml + cols * cell + bar_gap + bar_w + 90),
            height = static_cast<int>(mt + rows * cell + mb);
  const double vmax = scale_max > 0 ? scale_max : heatScale(values);
  std::ostringstream o;
  o << "<svg class=\"chart heatmap\" xmlns=\"http://www.w3.org/2000/svg\" width=\"" << width << "\" height=\"" << height
    << "\" role=\"img\" aria-label=\"" << escape(title) << "\">\n";
  o << "<text x=\"10\" y=\"18\" font-size=\"14\" font-weight=\"bold\">" << escape(title) << "</text>\n";
  for (Eigen::Index r = 0; r < rows; ++r)
    for (Eigen::Index c = 0; c < cols; ++c) {
      // Row 0 at the bottom, like a plot's y axis.
      const double x = ml + c * cell, y = mt + (rows - 1 - r) * cell;
      const double v = values(r, c);
      std::string fill = "#dddddd";
      if (std::isfinite(v)) {
        const double t = vmax > 0 ? std::clamp(v / vmax, 0.0, 1.0) : 0.0;
        char b[16];
        std::snprintf(b, sizeof b, "#%02x%02x%02x", 255, static_cast<int>(255 - 200 * t),
                      static_cast<int>(255 - 220 * t));
        fill = b;
      }
      o << "<rect class=\"cell\" x=\"" << num(x) << "\" y=\"" << num(y) << "\" width=\"" << cell << "\" height=\""
        << cell << "\" fill=\"" << fill << "\" stroke=\"#fff\"/>\n";
      o << "<text x=\"" << num(x + cell / 2.0) << "\" y=\"" << num(y + cell / 2.0 + 4)
        << "\" font-size=\"11\" text-anchor=\"middle\">" << (std::isfinite(v) ? tick(v) : std::string("no data"))
        << "</text>\n";
    }
  for (Eigen::Index r = 0; r < rows && r < static_cast<Eigen::Index>(row_labels.size()); ++r)
    o << "<text x=\"" << ml - 6 << "\" y=\"" << num(mt + (rows - 1 - r) * cell + cell / 2.0 + 4)
      << "\" font-size=\"11\" text-anchor=\"end\">" << escape(row_labels[static_cast<std::size_t>(r)]) << "</text>\n";
  for (Eigen::Index c = 0; c < cols && c < static_cast<Eigen::Index>(col_labels.size()); ++c)
    o << "<text x=\"" << num(ml + c * cell + cell / 2.0) << "\" y=\"" << num(mt + rows * cell + 14)
      << "\" font-size=\"11\" text-anchor=\"middle\">" << escape(col_labels[static_cast<std::size_t>(c)])
      << "</text>\n";
  o << "<text x=\"" << num(ml + cols * cell / 2.0) << "\" y=\"" << num(mt + rows * cell + 36)
    << "\" font-size=\"12\" text-anchor=\"middle\">" << escape(col_axis) << "</text>\n";
  o << "<text x=\"14\" y=\"" << num(mt + rows * cell / 2.0)
    << "\" font-size=\"12\" text-anchor=\"middle\" transform=\"rotate(-90 14 " << num(mt + rows * cell / 2.0) << ")\">"
    << escape(row_axis) << "</text>\n";
  o << colourBar(ml + cols * cell + bar_gap, mt, bar_w, rows * cell, vmax, unit, title);
  o << "</svg>\n";
  return o.str();
}

}  // namespace plsa::report
