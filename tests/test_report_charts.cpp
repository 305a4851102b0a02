// The report charts as a reader uses them: the samples each line chart holds,
// and zoom and hover driven by mouse events in headless Chromium.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include <nlohmann/json.hpp>

#include "plsa/report/svg_chart.hpp"
#include "support/headless_chromium.hpp"

using namespace plsa;
using nlohmann::json;

namespace {

// The JSON samples of the first chart in `html`.
json chartData(const std::string& html) {
  const std::string open = "<script type=\"application/json\" class=\"plot-data\">";
  const auto from = html.find(open) + open.size();
  return json::parse(html.substr(from, html.find("</script>", from) - from));
}

// 0 .. 100 s at 100 Hz: a sine, and a flat line with one sample at 10 that the
// static drawing (every 6th sample) steps over.
struct Traces {
  Eigen::VectorXd t = Eigen::VectorXd::LinSpaced(10001, 0.0, 100.0);
  Eigen::VectorXd sine = t.array().sin();
  Eigen::VectorXd spike = Eigen::VectorXd::Zero(10001);
  Traces() { spike(3751) = 10.0; }
};

}  // namespace

TEST(ReportCharts, LineChartHoldsItsSamplesWithGapsAsNull) {
  Traces tr;
  tr.sine(5) = NAN;
  const std::string html = report::lineChart("t", tr.t, {{"sine \"s\"", tr.sine, "#000", false}}, "time (s)", "y");
  const json data = chartData(html);
  ASSERT_EQ(data["x"].size(), 10001u);
  EXPECT_DOUBLE_EQ(data["x"][10000].get<double>(), 100.0);
  EXPECT_TRUE(data["series"][0][5].is_null());
  EXPECT_NEAR(data["series"][0][6].get<double>(), std::sin(0.06), 1e-7);
  EXPECT_EQ(data["labels"][0], "sine  s ") << "quotes cannot end the label";
  EXPECT_NE(html.find("data-x-label=\"time (s)\""), std::string::npos);

  // Beyond kMaxEmbeddedSamples the page holds every k-th sample.
  const Eigen::VectorXd long_t = Eigen::VectorXd::LinSpaced(50001, 0.0, 500.0);
  const json thinned = chartData(report::lineChart("t", long_t, {{"x", long_t, "#000", false}}, "time (s)", "y"));
  EXPECT_LE(thinned["x"].size(), static_cast<std::size_t>(report::kMaxEmbeddedSamples));
  EXPECT_EQ(thinned["x"].size(), 16667u);
  EXPECT_DOUBLE_EQ(thinned["x"][1].get<double>(), 0.03);

  // A time axis in epoch seconds keeps its samples apart.
  const Eigen::VectorXd epoch = Eigen::VectorXd::LinSpaced(81, 0.0, 1.0).array() + 1764201600.0;
  const json stamped =
      chartData(report::lineChart("t", epoch, {{"x", tr.sine.head(81), "#000", false}}, "time (s)", "y"));
  EXPECT_NEAR(stamped["x"][1].get<double>() - stamped["x"][0].get<double>(), 0.0125, 1e-6);
}

namespace {

// Mouse events on the page's charts, the way a reader drags and points, and
// what each chart shows after them, written into the page as JSON.
const char* kReader = R"JS(<script>
(function () {
  var divs = document.querySelectorAll('div.plot');
  function chart(k) { return divs[k].querySelector('svg'); }
  function plotBox(svg) { return svg.getAttribute('data-plot').split(' ').map(Number); }
  function client(svg, fx) {
    var g = plotBox(svg), p = svg.createSVGPoint();
    p.x = g[0] + fx * g[2]; p.y = g[1] + g[3] / 2;
    return p.matrixTransform(svg.getScreenCTM());
  }
  function mouse(svg, type, fx) {
    var c = client(svg, fx);
    svg.dispatchEvent(new MouseEvent(type, {clientX: c.x, clientY: c.y, bubbles: true}));
  }
  function ticks(k) {
    return Array.prototype.map.call(chart(k).querySelectorAll('g.x-ticks text'), function (t) { return Number(t.textContent); });
  }
  function state() {
    var a = chart(0);
    return {ticks: [ticks(0), ticks(1), ticks(2)],
            spike_top: a.querySelectorAll('g.traces path.series')[1].getBBox().y,
            readout: Array.prototype.map.call(a.querySelectorAll('g.readout text'), function (t) { return t.textContent; }),
            readout_visible: a.querySelector('g.readout').getAttribute('visibility')};
  }
  var out = {before: state()};
  var a = chart(0);
  mouse(a, 'mousedown', 0.25); mouse(a, 'mousemove', 0.4); mouse(a, 'mouseup', 0.5);
  mouse(a, 'mousemove', 0.75);
  out.zoomed = state();
  mouse(a, 'mouseleave', 0.75);
  out.left = state();
  a.dispatchEvent(new MouseEvent('dblclick', {bubbles: true}));
  out.reset = state();
  mouse(a, 'mousedown', 0.01); mouse(a, 'mouseup', 0.99);
  out.wide = state();
  var pre = document.createElement('pre');
  pre.id = 'reader';
  pre.textContent = JSON.stringify(out);
  document.body.appendChild(pre);
})();
</script>)JS";

json readerState(const test::RenderedPage& page) {
  const std::string open = "<pre id=\"reader\">";
  const auto from = page.dom.find(open);
  if (from == std::string::npos) return json();
  const auto start = from + open.size();
  return json::parse(page.dom.substr(start, page.dom.find("</pre>", start) - start));
}

}  // namespace

TEST(ReportCharts, DragZoomsLinkedChartsAndHoverReadsTheNearestSample) {
  Traces tr;
  const std::string page_html =
      "<!doctype html><html><body>" +
      report::lineChart("a", tr.t, {{"sine", tr.sine, "#000", false}, {"spike", tr.spike, "#c00", false}}, "time (s)",
                        "y") +
      report::lineChart("b", tr.t, {{"sine", tr.sine, "#000", false}}, "time (s)", "y", 900, 220) +
      report::lineChart("c", tr.t, {{"sine", tr.sine, "#000", false}}, "pressure (bar)", "y") + report::chartScript() +
      kReader + "</body></html>";
  const test::RenderedPage page = test::renderInChromium(page_html);
  if (!page.browser_found) GTEST_SKIP() << "chromium not installed: the charts were not opened in a browser";
  ASSERT_EQ(page.status, 0);
  const json s = readerState(page);
  ASSERT_TRUE(s.is_object()) << "the page's script did not run: " << page.dom.substr(0, 400);

  // Full span first: ticks from 0 to 100.
  EXPECT_EQ(s["before"]["ticks"][0].front(), 0.0);
  EXPECT_EQ(s["before"]["ticks"][0].back(), 100.0);
  EXPECT_EQ(s["before"]["readout_visible"], "hidden");
  // Dragging over 25%..50% of chart a zooms a and b (same x label) to 25..50 s; c stays.
  for (int k : {0, 1}) {
    const auto& ticks = s["zoomed"]["ticks"][k];
    ASSERT_GE(ticks.size(), 4u) << k;
    EXPECT_GE(ticks.front().get<double>(), 25.0) << k;
    EXPECT_LE(ticks.front().get<double>(), 27.5) << k;
    EXPECT_LE(ticks.back().get<double>(), 50.0) << k;
    EXPECT_GE(ticks.back().get<double>(), 47.5) << k;
  }
  EXPECT_EQ(s["zoomed"]["ticks"][2], s["before"]["ticks"][2]) << "another x axis is not linked";
  // Hovering at 75% of 25..50 s reads a sample near 43.75 s (mouse events land
  // on whole pixels, 0.04 s each here) and each series' value at that sample.
  const auto& readout = s["zoomed"]["readout"];
  ASSERT_EQ(readout.size(), 3u);
  const std::string time = readout[0].get<std::string>();
  ASSERT_EQ(time.rfind("time (s): ", 0), 0u) << time;
  const double t = std::stod(time.substr(10));
  EXPECT_NEAR(t, 43.75, 0.1);
  EXPECT_NEAR(t * 100, std::round(t * 100), 1e-6) << "a sample's time, on the 0.01 s grid";
  const std::string sine = readout[1].get<std::string>();
  ASSERT_EQ(sine.rfind("sine: ", 0), 0u) << sine;
  EXPECT_NEAR(std::stod(sine.substr(6)), std::sin(t), 5e-4) << sine;
  EXPECT_EQ(readout[2], "spike: 0");
  EXPECT_EQ(s["zoomed"]["readout_visible"], "visible");
  EXPECT_EQ(s["left"]["readout_visible"], "hidden") << "leaving the chart hides the readout";
  // Double-click zooms back out.
  EXPECT_EQ(s["reset"]["ticks"], s["before"]["ticks"]);
  // The static drawing steps over the one-sample spike; the zoomed drawing
  // keeps each pixel column's extremes, so it reaches the spike's top.
  const double before_top = s["before"]["spike_top"], wide_top = s["wide"]["spike_top"];
  EXPECT_GT(before_top, 150.0) << "the static line stays near 0";
  EXPECT_LT(wide_top, 45.0) << "the redrawn line reaches 10";
}
