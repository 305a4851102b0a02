// JSON and HTML renderings of a diagnosis.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <stdexcept>
#include <system_error>

#include <nlohmann/json.hpp>

#include "plsa/diagnose/diagnosis.hpp"
#include "plsa/core/text_file.hpp"
#include "plsa/sim/sim_config.hpp"
#include "plsa/report/svg_chart.hpp"

namespace plsa::diagnose {
namespace {

using nlohmann::json;

template <class T, class F>
json arrayOf(const std::vector<T>& items, F&& to_json) {
  json j = json::array();
  for (const auto& item : items) j.push_back(to_json(item));
  return j;
}

json gapJson(const Gap& g) {
  return {{"percent", g.percent()}, {"outputs", g.outputs}, {"pressures", g.pressures}, {"total", g.total}};
}

json paramsJson(const std::vector<std::pair<std::string, double>>& p) {
  json j = json::object();
  for (const auto& [k, v] : p) j[k] = v;
  return j;
}

json sharesJson(const std::vector<ResidualShare>& v) {
  return arrayOf(v, [](const ResidualShare& s) {
    return json{{"part", s.label}, {"rms", s.rms}, {"share", s.share}, {"samples", s.samples}};
  });
}

json placeJson(const GridPlace& g) {
  return {{"chamber", g.chamber}, {"from_bar", g.from_bar}, {"to_bar", g.to_bar},   {"direction", g.direction},
          {"rms", g.rms},         {"share", g.share},       {"samples", g.samples}, {"words", g.words}};
}

json breakdownJson(const Breakdown& b) {
  json j;
  j["by_output"] = sharesJson(b.by_output);
  j["by_direction"] = sharesJson(b.by_direction);
  j["by_state"] = sharesJson(b.by_state);
  j["by_band"] = sharesJson(b.by_band);
  j["by_region"] = arrayOf(b.by_region, placeJson);
  j["top_places"] = arrayOf(b.top_places, placeJson);
  j["grid_edges_bar"] = b.grid_edges_bar;
  json map = json::array();
  for (Eigen::Index r = 0; r < b.gap_map.rows(); ++r) {
    json row = json::array();
    for (Eigen::Index c = 0; c < b.gap_map.cols(); ++c)
      row.push_back(std::isfinite(b.gap_map(r, c)) ? json(b.gap_map(r, c)) : json(nullptr));
    map.push_back(row);
  }
  j["gap_map_rms"] = {{"rows", "chamber 2 band"}, {"cols", "chamber 1 band"}, {"values", map}};
  j["signatures"] = json::object();
  for (const auto& [k, s] : b.signatures)
    j["signatures"][k] = {{"score", s.score}, {"present", s.present}, {"evidence", s.evidence}};
  return j;
}

json candidateJson(const CandidateResult& c, const Gap& noise) {
  return {{"effect", c.effect},
          {"formulation", c.formulation},
          {"round", c.round},
          {"heldout_gap_before", c.heldout_before.percent()},
          {"heldout_gap_after", c.heldout_after.percent()},
          {"shrink_percent", c.shrink_percent},
          {"shrink_above_noise_percent", shrinkAboveNoise(c.heldout_before, c.heldout_after, noise)},
          {"train_gap_after", c.train_after.percent()},
          {"calibration",
           {{"starts", c.starts},
            {"evaluations", c.evaluations},
            {"train_gap_percent_per_start", c.train_gap_per_start},
            {"held", c.held}}},
          {"params", paramsJson(c.params)},
          {"signature",
           {{"score", c.signature.score}, {"present", c.signature.present}, {"evidence", c.signature.evidence}}}};
}

std::string fmt(double v, const char* f = "%.1f") {
  char b[64];
  std::snprintf(b, sizeof b, f, v);
  return b;
}

}  // namespace

std::string toJson(const Diagnosis& d) {
  json j;
  j["schema"] = "plsa.diagnosis v1";
  j["gap_unit"] = "percent: 100 sqrt(normalised mean squared residual); 0 = perfect, 100 = no better than the mean";
  j["train_runs"] = d.train_runs;
  j["heldout_runs"] = d.heldout_runs;
  j["output_map"] = d.map == OutputMap::kAngles ? "angles" : "affine";
  j["heldout_gap_uncalibrated"] = d.heldout_uncalibrated.percent();
  j["gap_before"] = d.gap_before.percent();
  j["gap_before_detail"] = gapJson(d.gap_before);
  j["train_gap_before"] = d.train_before.percent();
  j["noise_floor"] = d.noise.percent();
  j["nominal_params"] = paramsJson(d.nominal_params);
  j["nominal_evaluations"] = d.nominal_evaluations;
  j["calibration_step_s"] = d.calibration_step_s;
  j["calibration_integrator"] = d.calibration_integrator;
  j["calibration_step_trials"] = nlohmann::json::array();
  for (const auto& [step, moved] : d.calibration_step_trials)
    j["calibration_step_trials"].push_back({{"step_s", step}, {"training_gap_moved_points", moved}});
  const auto candidate = [&](const CandidateResult& c) { return candidateJson(c, d.noise); };
  j["ranking"] = arrayOf(d.ranking, candidate);
  j["later_rounds"] = arrayOf(d.later_rounds, candidate);
  j["selected"] = d.selected;
  j["steps"] = json::array();
  for (const auto& k : d.steps)
    j["steps"].push_back({{"effect", k.effect},
                          {"heldout_gap_chosen", k.heldout_chosen.percent()},
                          {"heldout_gap_after", k.heldout.percent()},
                          {"heldout_gap_final", k.heldout_final.percent()}});
  j["gap_after"] = d.gap_after.percent();
  j["shrink_above_noise_percent"] = shrinkAboveNoise(d.gap_before, d.gap_after, d.noise);
  j["final_params"] = paramsJson(d.final_params);
  j["where"] = breakdownJson(d.where);
  j["where_after"] = breakdownJson(d.where_after);
  j["verdict"] = d.verdict;
  j["notes"] = d.notes;
  j["identified_reference"] = {{"available", d.reference.available},
                               {"heldout_gap_percent", d.reference.gap.percent()},
                               {"note", d.reference.note}};
  j["confidence"] = {{"level", d.confidence},
                     {"runner_up", d.runner_up},
                     {"margin_over_recalibration", d.margin_over_recalibration},
                     {"margin_over_runner_up", d.margin_over_runner_up},
                     {"recalibrated_gap_percent", d.recalibrated_round1.percent()}};
  j["elapsed_s"] = d.elapsed_s;
  return j.dump(2);
}

namespace {

std::string outputUnit(const Diagnosis& d) {
  return d.map == OutputMap::kAngles ? "deg, bending vector" : "output units";
}

// An empty cell where there is no number (a gap-map cell without samples, no
// map with the selected effects): what spreadsheets and pandas read as missing.
std::string csvNumber(double v) {
  if (!std::isfinite(v)) return "";
  char b[40];
  std::snprintf(b, sizeof b, "%.17g", v);
  return b;
}

}  // namespace

std::vector<std::pair<std::string, std::string>> reportSeriesCsv(const Diagnosis& d) {
  std::ostringstream trace, map, shrink;
  trace << "time_s,real_1,real_2,calibrated_sim_1,calibrated_sim_2,with_effects_1,with_effects_2,"
           "residual_calibrated_sim_1,residual_calibrated_sim_2,residual_with_effects_1,residual_with_effects_2\n";
  for (Eigen::Index i = 0; i < d.trace_real.rows(); ++i) {
    trace << csvNumber(static_cast<double>(i) * d.trace_dt);
    for (const Eigen::MatrixXd* m : {&d.trace_real, &d.trace_before, &d.trace_after})
      for (Eigen::Index c = 0; c < 2; ++c) trace << ',' << csvNumber((*m)(i, c));
    for (const Eigen::MatrixXd* m : {&d.trace_before, &d.trace_after})
      for (Eigen::Index c = 0; c < 2; ++c) trace << ',' << csvNumber(d.trace_real(i, c) - (*m)(i, c));
    trace << '\n';
  }
  map << "chamber_1_from_bar,chamber_1_to_bar,chamber_2_from_bar,chamber_2_to_bar,rms_before,rms_after\n";
  const auto& edges = d.where.grid_edges_bar;
  for (Eigen::Index r = 0; r < d.where.gap_map.rows(); ++r)
    for (Eigen::Index c = 0; c < d.where.gap_map.cols(); ++c) {
      const auto rr = static_cast<std::size_t>(r), cc = static_cast<std::size_t>(c);
      const bool has_after = d.where_after.gap_map.rows() > r && d.where_after.gap_map.cols() > c;
      map << csvNumber(cc < edges.size() ? edges[cc] : NAN) << ','
          << csvNumber(cc + 1 < edges.size() ? edges[cc + 1] : NAN) << ','
          << csvNumber(rr < edges.size() ? edges[rr] : NAN) << ','
          << csvNumber(rr + 1 < edges.size() ? edges[rr + 1] : NAN) << ',' << csvNumber(d.where.gap_map(r, c)) << ','
          << csvNumber(has_after ? d.where_after.gap_map(r, c) : NAN) << '\n';
    }
  shrink << "effect,formulation,heldout_gap_before_percent,heldout_gap_after_percent,shrink_percent,kept\n";
  for (const auto& c : d.ranking) {
    const bool kept = std::find(d.selected.begin(), d.selected.end(), c.effect) != d.selected.end();
    shrink << c.effect << ',' << c.formulation << ',' << csvNumber(c.heldout_before.percent()) << ','
           << csvNumber(c.heldout_after.percent()) << ',' << csvNumber(c.shrink_percent) << ',' << (kept ? 1 : 0)
           << '\n';
  }
  return {{"trace.csv", trace.str()}, {"gap_map.csv", map.str()}, {"shrink.csv", shrink.str()}};
}

namespace {

/// The page's head, its verdict and the gaps it rests on.
void writeVerdict(std::ostream& h, const Diagnosis& d) {
  using report::escape;
  h << "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>plsa diagnosis</title>\n"
    << "<style>body{font-family:sans-serif;max-width:1000px;margin:2em auto;color:#222}"
    << "table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #ccc;padding:4px 8px;text-align:right}"
    << "th{background:#f4f4f4}td:first-child,th:first-child{text-align:left}.verdict{font-size:1.2em;background:#"
       "f6f8ff;"
    << "padding:1em;border-left:4px solid #4060c0}.note{color:#666;font-size:.9em}</style></head><body>\n";
  h << "<h1>Sim-to-real gap diagnosis</h1>\n<p class=\"verdict\" id=\"verdict\">" << escape(d.verdict) << "</p>\n";
  for (const auto& n : d.notes) h << "<p class=\"verdict\">Note: " << escape(n) << "</p>\n";
  h << "<p class=\"note\">Gap: 100 &times; sqrt(normalised mean squared residual) on held-out data ("
    << d.heldout_runs.size() << " run(s)); 0 is a perfect match, 100 no better than the mean. Simulator as given: "
    << fmt(d.heldout_uncalibrated.percent()) << "%; nominal physics calibrated: " << fmt(d.gap_before.percent())
    << "%; with the selected effects: " << fmt(d.gap_after.percent()) << "%; noise floor: " << fmt(d.noise.percent())
    << "%; "
    << (d.reference.available ? "an identified model (outputs only): " + fmt(d.reference.gap.percent()) + "%"
                              : "no identified reference (" + escape(d.reference.note) + ")")
    << ". Confidence: " << escape(d.confidence);
  if (!d.runner_up.empty())
    h << " (margin over re-calibration " << fmt(100 * d.margin_over_recalibration) << "%, over the runner-up, "
      << escape(d.runner_up) << ", " << fmt(100 * d.margin_over_runner_up) << "%)";
  h << ".</p>\n";
}

/// Where: the places, the gap maps and the residual's shares.
void writeWhere(std::ostream& h, const Diagnosis& d) {
  using report::escape;
  h << "<h2>Where</h2>\n<ul id=\"places\">";
  for (const auto& p : d.where.top_places) h << "<li>" << escape(p.words) << "</li>";
  h << "</ul>\n";
  std::vector<std::string> labels;
  for (std::size_t k = 0; k + 1 < d.where.grid_edges_bar.size(); ++k)
    labels.push_back(fmt(d.where.grid_edges_bar[k], "%.2f") + "-" + fmt(d.where.grid_edges_bar[k + 1], "%.2f"));
  // Both maps on the before map's colour scale, so "after" reads as lighter.
  const double scale = report::heatScale(d.where.gap_map);
  const std::string unit = "RMS residual (" + outputUnit(d) + ")";
  h << "<div id=\"gap-map\">"
    << report::heatMap("Gap map: RMS residual after nominal calibration", d.where.gap_map, labels, labels,
                       "chamber 2 (bar)", "chamber 1 (bar)", 64, scale, unit)
    << "</div>\n";
  if (!d.selected.empty())
    h << "<div id=\"gap-map-after\">"
      << report::heatMap("Gap map with the selected effects (same colour scale)", d.where_after.gap_map, labels, labels,
                         "chamber 2 (bar)", "chamber 1 (bar)", 64, scale, unit)
      << "</div>\n";
  h << "<p class=\"note\">Data behind the charts: <a href=\"gap_map.csv\">gap_map.csv</a>, "
       "<a href=\"shrink.csv\">shrink.csv</a>, <a href=\"trace.csv\">trace.csv</a>.</p>\n";
  auto table = [&](const char* title, const std::vector<ResidualShare>& v) {
    h << "<table><tr><th>" << title
      << "</th><th>RMS</th><th>share of squared residual</th><th>share of samples</th></tr>";
    for (const auto& s : v)
      h << "<tr><td>" << escape(s.label) << "</td><td>" << fmt(s.rms, "%.3g") << "</td><td>" << fmt(100 * s.share)
        << "%</td><td>" << (s.samples > 0 ? fmt(100 * s.samples) + "%" : "") << "</td></tr>";
    h << "</table>\n";
  };
  table("by output", d.where.by_output);
  table("by direction of change", d.where.by_direction);
  table("steady vs transient", d.where.by_state);
  table("by frequency band", d.where.by_band);
}

/// Which: each candidate effect's shrinkage, fitted law and calibration.
void writeWhich(std::ostream& h, const Diagnosis& d) {
  using report::escape;
  h << "<h2>Which</h2>\n";
  std::vector<report::Bar> bars;
  for (const auto& c : d.ranking) {
    const bool kept = std::find(d.selected.begin(), d.selected.end(), c.effect) != d.selected.end();
    bars.push_back({c.effect, c.shrink_percent, kept ? "#c04040" : "#8090b0"});
  }
  h << "<div id=\"shrink-chart\">"
    << report::barChart("Held-out gap shrinkage per candidate effect (round 1)", bars, "shrink (%)") << "</div>\n";
  h << "<table id=\"ranking\"><tr><th>effect (law calibrated)</th><th>held-out gap before</th><th>after</th>"
       "<th>shrink</th><th>signature</th><th>fitted parameters</th><th>calibration: starts, simulator runs, "
       "training gap per start</th></tr>";
  for (const auto& c : d.ranking) {
    std::string params;
    for (const auto& [k, v] : c.params)
      if (k.rfind(c.effect + ".", 0) == 0) params += k.substr(c.effect.size() + 1) + " = " + fmt(v, "%.4g") + "; ";
    h << "<tr><td>" << escape(c.effect) << " (" << escape(c.formulation) << ")</td><td>"
      << fmt(c.heldout_before.percent()) << "%</td><td>" << fmt(c.heldout_after.percent()) << "%</td><td>"
      << fmt(c.shrink_percent) << "%</td><td>" << (c.signature.present ? "supports: " : "")
      << escape(c.signature.evidence) << "</td><td>" << escape(params) << "</td><td>" << c.starts << ", "
      << c.evaluations << ";";
    for (double gap : c.train_gap_per_start) h << " " << fmt(gap) << "%";
    h << "</td></tr>";
  }
  h << "</table>\n";
  if (!d.later_rounds.empty()) {
    h << "<p>Later forward-selection rounds:</p><table><tr><th>round</th><th>effect</th><th>held-out gap before</th>"
         "<th>after</th><th>shrink</th></tr>";
    for (const auto& c : d.later_rounds)
      h << "<tr><td>" << c.round << "</td><td>" << escape(c.effect) << "</td><td>" << fmt(c.heldout_before.percent())
        << "%</td><td>" << fmt(c.heldout_after.percent()) << "%</td><td>" << fmt(c.shrink_percent) << "%</td></tr>";
    h << "</table>\n";
  }
}

/// How far: the held-out traces and the residual per region before and after.
void writeHowFar(std::ostream& h, const Diagnosis& d) {
  h << "<h2>How far</h2>\n";
  const Eigen::Index n = d.trace_real.rows();
  Eigen::VectorXd t(n);
  for (Eigen::Index i = 0; i < n; ++i) t(i) = i * d.trace_dt;
  const std::array<std::string, 2> names =
      d.map == OutputMap::kAngles ? std::array<std::string, 2>{"bending vector x (deg)", "bending vector y (deg)"}
                                  : std::array<std::string, 2>{"output 1", "output 2"};
  const std::string with =
      d.selected.empty() ? "sim (no effect kept)" : "sim + " + d.selected[0] + (d.selected.size() > 1 ? " + ..." : "");
  h << "<p class=\"note\">" << report::kChartHint << "</p>\n";
  for (int c = 0; c < 2; ++c) {
    const auto& name = names[static_cast<std::size_t>(c)];
    const Eigen::VectorXd real = d.trace_real.col(c);
    h << "<div class=\"trace\" id=\"trace-" << c + 1 << "\">"
      << report::lineChart("Held-out run: " + name, t,
                           {{"real", real, "#222222", false},
                            {"calibrated sim", d.trace_before.col(c), "#4060c0", true},
                            {with, d.trace_after.col(c), "#c04040", false}},
                           "time (s)", name)
      << report::lineChart("Held-out residual: real minus simulated, " + name, t,
                           {{"calibrated sim", real - d.trace_before.col(c), "#4060c0", true},
                            {with, real - d.trace_after.col(c), "#c04040", false}},
                           "time (s)", "residual, " + name, 900, 220)
      << "</div>\n";
  }
  h << "<table><tr><th>region (chamber, band, direction)</th><th>RMS before</th><th>RMS after</th></tr>";
  for (const auto& b : d.where.by_region)
    for (const auto& a : d.where_after.by_region)
      if (a.chamber == b.chamber && a.from_bar == b.from_bar && a.direction == b.direction && b.samples >= 0.03)
        h << "<tr><td>chamber " << b.chamber << ", " << fmt(b.from_bar, "%.2f") << "-" << fmt(b.to_bar, "%.2f")
          << " bar, " << b.direction << "</td><td>" << fmt(b.rms, "%.3g") << "</td><td>" << fmt(a.rms, "%.3g")
          << "</td></tr>";
  h << "</table>\n";
}

/// The calibrated nominal parameters and the page's foot.
void writeNominal(std::ostream& h, const Diagnosis& d) {
  using report::escape;
  h << "<h2>Calibrated nominal parameters</h2><p class=\"note\">" << d.nominal_evaluations
    << " simulator runs: the gain regression, a 27-point grid of frequency, damping and time constant, BOBYQA from "
       "the simulator as given and the best two grid points, then a restart from the best.</p>"
       "<table><tr><th>parameter</th><th>value</th></tr>";
  for (const auto& [k, v] : d.nominal_params)
    h << "<tr><td>" << escape(k) << "</td><td>" << fmt(v, "%.4g") << "</td></tr>";
  h << "</table>\n<p class=\"note\">Made by plsa diagnose in " << fmt(d.elapsed_s) << " s.</p>\n"
    << report::chartScript() << "</body></html>\n";
}

}  // namespace

std::string reportHtml(const Diagnosis& d) {
  std::ostringstream h;
  writeVerdict(h, d);
  writeWhere(h, d);
  writeWhich(h, d);
  writeHowFar(h, d);
  writeNominal(h, d);
  return h.str();
}

void writeDiagnosisFolder(const Diagnosis& d, const std::string& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (dir.empty() || ec || !std::filesystem::is_directory(dir))
    throw std::invalid_argument("diagnosis: cannot make the output folder '" + dir + "'" +
                                (ec ? ": " + ec.message() : std::string(": it exists and is not a folder")));
  const std::filesystem::path folder(dir);
  writeTextFile((folder / "diagnosis.json").string(), toJson(d), "diagnosis");
  writeTextFile((folder / "report.html").string(), reportHtml(d), "HTML report");
  for (const auto& [name, text] : reportSeriesCsv(d))
    writeTextFile((folder / name).string(), text, "report data " + name);
  writeTextFile((folder / "calibrated_sim.json").string(), sim::simConfigToJson(d.final_config),
                "calibrated simulator configuration");
}

}  // namespace plsa::diagnose
