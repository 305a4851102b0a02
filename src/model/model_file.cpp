#include "plsa/model/model_file.hpp"

#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "plsa/core/text_file.hpp"

namespace plsa {
namespace {

using nlohmann::json;
constexpr const char* kSchema = "plsa.dio_pwl_obf";

[[noreturn]] void bad(const std::string& source, const std::string& why) {
  throw std::invalid_argument(source + ": " + why);
}

// Checked access: every field read names its path when it is missing or mistyped.
class Reader {
 public:
  explicit Reader(std::string source) : source_(std::move(source)) {}
  const json& at(const json& j, const std::string& key, const std::string& path) const {
    if (!j.is_object() || !j.contains(key)) bad(source_, "missing field '" + path + key + "'");
    return j.at(key);
  }
  double number(const json& j, const std::string& path) const {
    if (!j.is_number()) bad(source_, "'" + path + "' must be a number");
    return j.get<double>();
  }
  std::string string(const json& j, const std::string& path) const {
    if (!j.is_string()) bad(source_, "'" + path + "' must be a string");
    return j.get<std::string>();
  }
  const json& array(const json& j, const std::string& path) const {
    if (!j.is_array()) bad(source_, "'" + path + "' must be an array");
    return j;
  }
  const std::string& source() const { return source_; }

 private:
  std::string source_;
};

double finiteOrInf(const json& j) {
  if (j.is_string()) return j.get<std::string>() == "-inf" ? -INFINITY : INFINITY;
  return j.get<double>();
}

json limit(double v) {
  if (std::isinf(v)) return v < 0 ? "-inf" : "inf";
  return v;
}

}  // namespace

std::string modelToJson(const DioPwlObfModel& m) {
  m.validate();
  json j;
  j["schema"] = kSchema;
  j["version"] = DioPwlObfModel::kSchemaVersion;
  j["sample_time_s"] = m.sample_time_s;
  j["inputs"] = m.inputs;
  j["outputs"] = m.outputs;
  j["units"] = {{"inputs", m.input_unit}, {"outputs", m.output_unit}};
  j["input_range"] = {limit(m.input_min), limit(m.input_max)};
  if (!m.input_ranges.empty()) {
    json ranges = json::array();
    for (const auto& r : m.input_ranges) ranges.push_back({r[0], r[1]});
    j["input_ranges"] = ranges;
  }
  json poles = json::array();
  for (const auto& row : m.poles) {
    json r = json::array();
    for (const auto& ps : row) {
      json list = json::array();
      for (const auto& p : ps.poles()) list.push_back({p.real(), p.imag()});
      r.push_back(list);
    }
    poles.push_back(r);
  }
  j["poles"] = poles;
  // A fixed band is a plain number (as in files written before slopes existed).
  json play = json::array();
  for (const auto& list : m.input_play) {
    json l = json::array();
    for (const PlayChannel& c : list) {
      if (c.slope == 0.0)
        l.push_back(c.width);
      else
        l.push_back({{"width", c.width}, {"slope", c.slope}});
    }
    play.push_back(l);
  }
  j["input_play"] = play;
  j["play_start"] = m.play_start == PlayStart::kRising ? "rising" : "centred";
  j["play_coupling"] = m.play_coupling;
  j["play_threshold"] = m.play_threshold;
  j["play_softening"] = m.play_softening;
  j["schedule_lag_s"] = m.schedule_lag_s;
  j["schedule_side"] = m.schedule_side == ScheduleSide::kInput ? "input" : "output";
  if (!m.output_level.empty()) j["output_level"] = m.output_level;
  if (!m.training_drift_per_s.empty())
    j["training_output_drift"] = {{"rate_per_s", m.training_drift_per_s},
                                  {"reference_time_s", m.training_drift_reference_s}};
  j["output_frame"] = toString(m.output_frame);
  json part;
  part["inputs"] = m.partition.inputs();
  const bool interp = m.partition.scheduling() == Scheduling::kInterpolated;
  part["scheduling"] = interp ? "interpolated" : "switched";
  part[interp ? "levels" : "breakpoints"] = m.partition.breakpoints();
  part["direction_split"] = m.partition.directionSplit();
  part["direction_threshold"] = m.partition.directionThreshold();
  j["partition"] = part;
  json regions = json::array();
  for (std::size_t r = 0; r < m.coefficients.size(); ++r) {
    json reg;
    reg["samples"] = m.region_fits[r].samples;
    reg["fallback_from"] = m.region_fits[r].fallback_from;
    reg["note"] = m.region_fits[r].note;
    json coefs = json::array();
    for (const auto& c : m.coefficients[r]) coefs.push_back(std::vector<double>(c.data(), c.data() + c.size()));
    reg["coefficients"] = coefs;
    regions.push_back(reg);
  }
  j["regions"] = regions;
  return j.dump(1);
}

DioPwlObfModel modelFromJson(const std::string& text, const std::string& source) {
  json j;
  try {
    j = json::parse(text);
  } catch (const json::parse_error& e) {
    bad(source, std::string("not valid JSON: ") + e.what());
  }
  const Reader rd(source);
  if (rd.string(rd.at(j, "schema", ""), "schema") != kSchema) bad(source, "schema is not '" + std::string(kSchema) + "'");
  const double version = rd.number(rd.at(j, "version", ""), "version");
  if (version != DioPwlObfModel::kSchemaVersion)
    bad(source, "schema version " + std::to_string(static_cast<int>(version)) + " is not supported (this build reads " +
                    std::to_string(DioPwlObfModel::kSchemaVersion) + ")");
  DioPwlObfModel m;
  m.sample_time_s = rd.number(rd.at(j, "sample_time_s", ""), "sample_time_s");
  for (const auto& s : rd.array(rd.at(j, "inputs", ""), "inputs")) m.inputs.push_back(rd.string(s, "inputs[]"));
  for (const auto& s : rd.array(rd.at(j, "outputs", ""), "outputs")) m.outputs.push_back(rd.string(s, "outputs[]"));
  const json& units = rd.at(j, "units", "");
  m.input_unit = rd.string(rd.at(units, "inputs", "units."), "units.inputs");
  m.output_unit = rd.string(rd.at(units, "outputs", "units."), "units.outputs");
  const json& range = rd.array(rd.at(j, "input_range", ""), "input_range");
  if (range.size() != 2) bad(source, "'input_range' must have two entries");
  m.input_min = finiteOrInf(range[0]);
  m.input_max = finiteOrInf(range[1]);
  if (j.contains("input_ranges"))
    for (const auto& r : rd.array(j["input_ranges"], "input_ranges")) {
      if (!r.is_array() || r.size() != 2) bad(source, "'input_ranges' entries must be [min, max]");
      m.input_ranges.push_back({rd.number(r[0], "input_ranges[][0]"), rd.number(r[1], "input_ranges[][1]")});
    }
  const json& poles = rd.array(rd.at(j, "poles", ""), "poles");
  for (std::size_t o = 0; o < poles.size(); ++o) {
    std::vector<PoleSet> row;
    for (std::size_t i = 0; i < rd.array(poles[o], "poles[o]").size(); ++i) {
      std::vector<std::complex<double>> list;
      const std::string path = "poles[" + std::to_string(o) + "][" + std::to_string(i) + "]";
      for (const auto& p : rd.array(poles[o][i], path)) {
        if (!p.is_array() || p.size() != 2) bad(source, path + ": each pole is [re, im]");
        list.emplace_back(rd.number(p[0], path), rd.number(p[1], path));
      }
      try {
        row.emplace_back(list);
      } catch (const std::invalid_argument& e) {
        bad(source, path + ": " + e.what());
      }
    }
    m.poles.push_back(std::move(row));
  }
  for (const auto& list : rd.array(rd.at(j, "input_play", ""), "input_play")) {
    std::vector<PlayChannel> channels;
    for (const auto& v : rd.array(list, "input_play[]")) {
      if (v.is_object())
        channels.emplace_back(rd.number(rd.at(v, "width", "input_play[][]."), "input_play[][].width"),
                              rd.number(rd.at(v, "slope", "input_play[][]."), "input_play[][].slope"));
      else
        channels.emplace_back(rd.number(v, "input_play[][]"));
    }
    m.input_play.push_back(std::move(channels));
  }
  // Files from before the field existed started their bands centred.
  const std::string start = j.contains("play_start") ? rd.string(j["play_start"], "play_start") : "centred";
  if (start != "rising" && start != "centred")
    bad(source, "'play_start' must be 'rising' or 'centred', not '" + start + "'");
  m.play_start = start == "rising" ? PlayStart::kRising : PlayStart::kCentred;
  m.play_coupling = j.contains("play_coupling") ? rd.number(j["play_coupling"], "play_coupling") : 0.0;
  m.play_threshold = j.contains("play_threshold") ? rd.number(j["play_threshold"], "play_threshold") : 0.0;
  m.play_softening = j.contains("play_softening") ? rd.number(j["play_softening"], "play_softening") : 0.0;
  m.schedule_lag_s = j.contains("schedule_lag_s") ? rd.number(j["schedule_lag_s"], "schedule_lag_s") : 0.0;
  const std::string side = j.contains("schedule_side") ? rd.string(j["schedule_side"], "schedule_side") : "output";
  if (side != "output" && side != "input")
    bad(source, "'schedule_side' must be 'output' or 'input', not '" + side + "'");
  m.schedule_side = side == "input" ? ScheduleSide::kInput : ScheduleSide::kOutput;
  const std::string frame = j.contains("output_frame") ? rd.string(j["output_frame"], "output_frame") : "as_logged";
  if (frame != "as_logged" && frame != "tip_cartesian")
    bad(source, "'output_frame' must be 'as_logged' or 'tip_cartesian', not '" + frame + "'");
  m.output_frame = outputFrameFromString(frame);
  if (j.contains("output_level"))
    for (const auto& v : rd.array(j["output_level"], "output_level")) m.output_level.push_back(rd.number(v, "output_level[]"));
  if (j.contains("training_output_drift")) {
    const json& d = j["training_output_drift"];
    for (const auto& v : rd.array(rd.at(d, "rate_per_s", "training_output_drift."), "training_output_drift.rate_per_s"))
      m.training_drift_per_s.push_back(rd.number(v, "training_output_drift.rate_per_s[]"));
    m.training_drift_reference_s =
        rd.number(rd.at(d, "reference_time_s", "training_output_drift."), "training_output_drift.reference_time_s");
  }
  const json& part = rd.at(j, "partition", "");
  std::vector<int> sched;
  for (const auto& v : rd.array(rd.at(part, "inputs", "partition."), "partition.inputs")) {
    if (!v.is_number_integer()) bad(source, "'partition.inputs' must hold input indices");
    sched.push_back(v.get<int>());
  }
  const std::string mode = rd.string(rd.at(part, "scheduling", "partition."), "partition.scheduling");
  if (mode != "switched" && mode != "interpolated")
    bad(source, "'partition.scheduling' must be 'switched' or 'interpolated', not '" + mode + "'");
  const std::string key = mode == "interpolated" ? "levels" : "breakpoints";
  std::vector<std::vector<double>> bps;
  for (const auto& list : rd.array(rd.at(part, key, "partition."), "partition." + key)) {
    std::vector<double> b;
    for (const auto& v : rd.array(list, "partition." + key + "[]")) b.push_back(rd.number(v, "partition." + key + "[]"));
    bps.push_back(std::move(b));
  }
  const json& split = rd.at(part, "direction_split", "partition.");
  if (!split.is_boolean()) bad(source, "'partition.direction_split' must be true or false");
  try {
    const double thr = rd.number(rd.at(part, "direction_threshold", "partition."), "partition.direction_threshold");
    m.partition = mode == "interpolated" ? PwlPartition::interpolated(sched, bps, split.get<bool>(), thr)
                                         : PwlPartition(sched, bps, split.get<bool>(), thr);
  } catch (const std::invalid_argument& e) {
    bad(source, e.what());
  }
  const json& regions = rd.array(rd.at(j, "regions", ""), "regions");
  for (std::size_t r = 0; r < regions.size(); ++r) {
    const std::string path = "regions[" + std::to_string(r) + "].";
    RegionFit fit;
    fit.samples = static_cast<int>(rd.number(rd.at(regions[r], "samples", path), path + "samples"));
    fit.fallback_from = static_cast<int>(rd.number(rd.at(regions[r], "fallback_from", path), path + "fallback_from"));
    fit.note = rd.string(rd.at(regions[r], "note", path), path + "note");
    std::vector<Eigen::VectorXd> coefs;
    for (const auto& c : rd.array(rd.at(regions[r], "coefficients", path), path + "coefficients")) {
      const json& arr = rd.array(c, path + "coefficients[]");
      Eigen::VectorXd v(static_cast<Eigen::Index>(arr.size()));
      for (std::size_t i = 0; i < arr.size(); ++i) v(static_cast<Eigen::Index>(i)) = rd.number(arr[i], path + "coefficients[]");
      coefs.push_back(v);
    }
    m.coefficients.push_back(std::move(coefs));
    m.region_fits.push_back(fit);
  }
  try {
    m.validate();
  } catch (const std::invalid_argument& e) {
    bad(source, e.what());
  }
  return m;
}

void saveModel(const std::string& path, const DioPwlObfModel& model) {
  writeTextFile(path, modelToJson(model) + "\n", "model file");
}

DioPwlObfModel loadModel(const std::string& path) {
  return modelFromJson(readTextFile(path, "model file"), path);
}

}  // namespace plsa
