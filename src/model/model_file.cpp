#include "plsa/model/model_file.hpp"

#include <algorithm>
#include <array>
#include <climits>
#include <cstdint>
#include <initializer_list>
#include <sstream>
#include <string_view>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "plsa/core/number_text.hpp"
#include "plsa/core/text_file.hpp"
#include "plsa/io/csv_log.hpp"
#include "plsa/io/standard_columns.hpp"
#include "plsa/io/strict_json.hpp"

namespace plsa {
namespace {

using nlohmann::json;
constexpr const char* kSchema = "plsa.dio_pwl_obf";

json limit(double v) {
  if (std::isinf(v)) return v < 0 ? "-inf" : "inf";
  return v;
}

json polesJson(const DioPwlObfModel& m) {
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
  return poles;
}

// A fixed band is a plain number (as in files written before slopes existed).
json playJson(const InputShaping& shaping) {
  json play = json::array();
  for (const auto& list : shaping.play) {
    json l = json::array();
    for (const PlayChannel& c : list) {
      if (c.slope == 0.0)
        l.push_back(c.width);
      else
        l.push_back({{"width", c.width}, {"slope", c.slope}});
    }
    play.push_back(l);
  }
  return play;
}

json partitionJson(const PwlPartition& p) {
  json part;
  part["inputs"] = p.inputs();
  const bool interp = p.scheduling() == Scheduling::kInterpolated;
  part["scheduling"] = interp ? "interpolated" : "switched";
  part[interp ? "levels" : "breakpoints"] = p.breakpoints();
  part["direction_split"] = p.directionSplit();
  part["direction_threshold"] = p.directionThreshold();
  return part;
}

json regionsJson(const DioPwlObfModel& m) {
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
  return regions;
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
  j["poles"] = polesJson(m);
  j["input_play"] = playJson(m.shaping);
  j["play_start"] = m.shaping.start == PlayStart::kRising ? "rising" : "centred";
  j["play_coupling"] = m.shaping.coupling;
  j["play_threshold"] = m.shaping.threshold;
  j["play_softening"] = m.shaping.softening;
  j["schedule_lag_s"] = m.schedule_lag_s;
  j["schedule_side"] = m.schedule_side == ScheduleSide::kInput ? "input" : "output";
  if (!m.output_level.empty()) j["output_level"] = m.output_level;
  if (!m.training_drift_per_s.empty())
    j["training_output_drift"] = {{"rate_per_s", m.training_drift_per_s},
                                  {"reference_time_s", m.training_drift_reference_s}};
  j["output_frame"] = toString(m.output_frame);
  j["partition"] = partitionJson(m.partition);
  j["regions"] = regionsJson(m);
  return j.dump(1);
}

namespace {

// The keys each object of a model file may hold, by schema version 2; version
// 1 files hold a subset of them.
constexpr std::array<std::string_view, 21> kTopKeys = {
    "schema",         "version",        "sample_time_s",  "inputs",        "outputs",      "units",
    "input_range",    "input_ranges",   "poles",          "input_play",    "play_start",   "play_coupling",
    "play_threshold", "play_softening", "schedule_lag_s", "schedule_side", "output_level", "training_output_drift",
    "output_frame",   "partition",      "regions"};

// Reads one model file. Version 2 requires every field it writes; version 1
// gives the fields that did not exist yet the meaning they had then.
class ModelReader {
 public:
  ModelReader(const json& j, std::string source) : j_(j), source_(std::move(source)) {}

  DioPwlObfModel read() {
    object(j_, "");
    if (string(at(j_, "schema", ""), "schema") != kSchema) bad("schema is not '" + std::string(kSchema) + "'");
    version_ = static_cast<int>(io::integerIn(at(j_, "version", ""), 1, 1'000'000, "version", source_));
    if (version_ > DioPwlObfModel::kSchemaVersion)
      bad("schema version " + std::to_string(version_) + " is newer than this build reads (1 to " +
          std::to_string(DioPwlObfModel::kSchemaVersion) + "); update plsa");
    io::requireKnownKeysIn(j_, kTopKeys, "", source_);
    DioPwlObfModel m;
    m.sample_time_s = number(at(j_, "sample_time_s", ""), "sample_time_s");
    if (!(m.sample_time_s >= io::kMinSampleTimeS && m.sample_time_s <= io::kMaxSampleTimeS))
      bad("sample_time_s " + significantDigits(m.sample_time_s, 6) + " is outside " +
          significantDigits(io::kMinSampleTimeS, 6) + " to " + significantDigits(io::kMaxSampleTimeS, 6) + " s");
    m.inputs = names("inputs");
    m.outputs = names("outputs");
    readUnits(m);
    readRanges(m);
    readPoles(m);
    readPlay(m);
    readSchedule(m);
    readOutputs(m);
    readPartition(m);
    readRegions(m);
    try {
      m.validate();
    } catch (const std::invalid_argument& e) {
      bad(e.what());
    }
    return m;
  }

 private:
  [[noreturn]] void bad(const std::string& why) const { throw std::invalid_argument(source_ + ": " + why); }

  const json& at(const json& j, const std::string& key, const std::string& path) const {
    if (!j.is_object() || !j.contains(key)) bad("missing field '" + path + key + "'");
    return j.at(key);
  }
  // Optional in version 1 (absent: `fallback`), required from version 2.
  const json* optional(const std::string& key) const {
    if (j_.contains(key)) return &j_.at(key);
    if (version_ >= 2) bad("missing field '" + key + "'");
    return nullptr;
  }
  void object(const json& j, const std::string& path) const {
    if (!j.is_object()) bad("'" + (path.empty() ? std::string("the top level") : path) + "' must be an object");
  }
  double number(const json& j, const std::string& path) const { return io::finiteNumber(j, path, source_); }
  std::string string(const json& j, const std::string& path) const {
    if (!j.is_string()) bad("'" + path + "' must be a string");
    return j.get<std::string>();
  }
  const json& array(const json& j, const std::string& path) const {
    if (!j.is_array()) bad("'" + path + "' must be an array");
    return j;
  }
  std::vector<double> numbers(const json& j, const std::string& path) const {
    std::vector<double> out;
    for (const auto& v : array(j, path)) out.push_back(number(v, path + "[]"));
    return out;
  }
  // One of `allowed`, or `fallback` when the field is absent from a version 1 file.
  std::string choice(const std::string& key, std::initializer_list<const char*> allowed, const char* fallback) const {
    const json* v = optional(key);
    const std::string s = v ? string(*v, key) : fallback;
    std::string list;
    std::size_t k = 0;
    for (const char* a : allowed) {
      if (s == a) return s;
      list += std::string(k == 0 ? "" : k + 1 == allowed.size() ? " or " : ", ") + "'" + a + "'";
      ++k;
    }
    bad("'" + key + "' must be " + list + ", not '" + s + "'");
  }
  double scalar(const std::string& key, double fallback) const {
    const json* v = optional(key);
    return v ? number(*v, key) : fallback;
  }

  std::vector<std::string> names(const std::string& key) const {
    std::vector<std::string> out;
    for (const auto& s : array(at(j_, key, ""), key)) {
      out.push_back(string(s, key + "[]"));
      if (out.back().empty()) bad("'" + key + "' has an empty name");
      if (out.back() == io::standard_columns::kTime)
        bad("'" + key + "' names '" + out.back() + "', the logs' time, not an input or output");
      if (std::count(out.begin(), out.end(), out.back()) > 1) bad("'" + key + "' names '" + out.back() + "' twice");
    }
    return out;
  }

  void readUnits(DioPwlObfModel& m) const {
    const json& units = at(j_, "units", "");
    object(units, "units");
    io::requireKnownKeys(units, {"inputs", "outputs"}, "units.", source_);
    m.input_unit = string(at(units, "inputs", "units."), "units.inputs");
    m.output_unit = string(at(units, "outputs", "units."), "units.outputs");
  }

  // A bound: a finite number, or the string "-inf" (lower) / "inf" (upper) for none.
  double bound(const json& j, const std::string& path, bool lower) const {
    if (j.is_string()) {
      const std::string want = lower ? "-inf" : "inf";
      if (j.get<std::string>() != want) bad("'" + path + "' must be a number or \"" + want + "\"");
      return lower ? -INFINITY : INFINITY;
    }
    return number(j, path);
  }

  void readRanges(DioPwlObfModel& m) const {
    const json& range = array(at(j_, "input_range", ""), "input_range");
    if (range.size() != 2) bad("'input_range' must have two entries");
    m.input_min = bound(range[0], "input_range[0]", true);
    m.input_max = bound(range[1], "input_range[1]", false);
    if (!j_.contains("input_ranges")) return;
    for (const auto& r : array(j_.at("input_ranges"), "input_ranges")) {
      if (!r.is_array() || r.size() != 2) bad("'input_ranges' entries must be [min, max]");
      m.input_ranges.push_back({number(r[0], "input_ranges[][0]"), number(r[1], "input_ranges[][1]")});
    }
  }

  void readPoles(DioPwlObfModel& m) const {
    const json& poles = array(at(j_, "poles", ""), "poles");
    for (std::size_t o = 0; o < poles.size(); ++o) {
      std::vector<PoleSet> row;
      const json& sets = array(poles[o], "poles[" + std::to_string(o) + "]");
      for (std::size_t i = 0; i < sets.size(); ++i) {
        std::vector<std::complex<double>> list;
        const std::string path = "poles[" + std::to_string(o) + "][" + std::to_string(i) + "]";
        if (array(sets[i], path).size() > DioPwlObfModel::kMaxPolesPerBank)
          bad(path + ": more than " + std::to_string(DioPwlObfModel::kMaxPolesPerBank) + " poles");
        for (const auto& p : array(sets[i], path)) {
          if (!p.is_array() || p.size() != 2) bad(path + ": each pole is [re, im]");
          list.emplace_back(number(p[0], path), number(p[1], path));
        }
        try {
          row.emplace_back(list);
        } catch (const std::invalid_argument& e) {
          bad(path + ": " + e.what());
        }
      }
      m.poles.push_back(std::move(row));
    }
  }

  void readPlay(DioPwlObfModel& m) const {
    for (const auto& list : array(at(j_, "input_play", ""), "input_play")) {
      std::vector<PlayChannel> channels;
      for (const auto& v : array(list, "input_play[]")) {
        if (v.is_object()) {
          io::requireKnownKeys(v, {"width", "slope"}, "input_play[][].", source_);
          channels.emplace_back(number(at(v, "width", "input_play[][]."), "input_play[][].width"),
                                number(at(v, "slope", "input_play[][]."), "input_play[][].slope"));
        } else {
          channels.emplace_back(number(v, "input_play[][]"));
        }
      }
      m.shaping.play.push_back(std::move(channels));
    }
    // Files from before the field existed started their bands centred.
    m.shaping.start =
        choice("play_start", {"rising", "centred"}, "centred") == "rising" ? PlayStart::kRising : PlayStart::kCentred;
    m.shaping.coupling = scalar("play_coupling", 0.0);
    m.shaping.threshold = scalar("play_threshold", 0.0);
    m.shaping.softening = scalar("play_softening", 0.0);
  }

  void readSchedule(DioPwlObfModel& m) const {
    m.schedule_lag_s = scalar("schedule_lag_s", 0.0);
    m.schedule_side = choice("schedule_side", {"output", "input"}, "output") == "input" ? ScheduleSide::kInput
                                                                                        : ScheduleSide::kOutput;
    m.output_frame = outputFrameFromString(choice("output_frame", {"as_logged", "tip_cartesian"}, "as_logged"));
  }

  void readOutputs(DioPwlObfModel& m) const {
    if (j_.contains("output_level")) m.output_level = numbers(j_.at("output_level"), "output_level");
    if (!j_.contains("training_output_drift")) return;
    const json& d = j_.at("training_output_drift");
    object(d, "training_output_drift");
    io::requireKnownKeys(d, {"rate_per_s", "reference_time_s"}, "training_output_drift.", source_);
    m.training_drift_per_s = numbers(at(d, "rate_per_s", "training_output_drift."), "training_output_drift.rate_per_s");
    m.training_drift_reference_s =
        number(at(d, "reference_time_s", "training_output_drift."), "training_output_drift.reference_time_s");
  }

  void readPartition(DioPwlObfModel& m) const {
    const json& part = at(j_, "partition", "");
    object(part, "partition");
    const std::string mode = string(at(part, "scheduling", "partition."), "partition.scheduling");
    if (mode != "switched" && mode != "interpolated")
      bad("'partition.scheduling' must be 'switched' or 'interpolated', not '" + mode + "'");
    const std::string key = mode == "interpolated" ? "levels" : "breakpoints";
    io::requireKnownKeys(part, {"inputs", "scheduling", key, "direction_split", "direction_threshold"}, "partition.",
                         source_);
    std::vector<int> sched;
    for (const auto& v : array(at(part, "inputs", "partition."), "partition.inputs")) {
      sched.push_back(static_cast<int>(io::integerIn(v, 0, 1 << 20, "partition.inputs[]", source_)));
      if (std::count(sched.begin(), sched.end(), sched.back()) > 1)  // [0, 0] scheduled on p_1 twice, on p_2 never
        bad("'partition.inputs' names input " + std::to_string(sched.back()) + " twice");
    }
    std::vector<std::vector<double>> bps;
    for (const auto& list : array(at(part, key, "partition."), "partition." + key))
      bps.push_back(numbers(list, "partition." + key + "[]"));
    const json& split = at(part, "direction_split", "partition.");
    if (!split.is_boolean()) bad("'partition.direction_split' must be true or false");
    const double thr = number(at(part, "direction_threshold", "partition."), "partition.direction_threshold");
    try {
      m.partition = mode == "interpolated" ? PwlPartition::interpolated(sched, bps, split.get<bool>(), thr)
                                           : PwlPartition(sched, bps, split.get<bool>(), thr);
    } catch (const std::invalid_argument& e) {
      bad(e.what());
    }
  }

  void readRegions(DioPwlObfModel& m) const {
    const json& regions = array(at(j_, "regions", ""), "regions");
    if (regions.size() != static_cast<std::size_t>(m.partition.regionCount()))
      bad(std::to_string(regions.size()) + " regions for a partition of " + std::to_string(m.partition.regionCount()));
    for (std::size_t r = 0; r < regions.size(); ++r) {
      const std::string path = "regions[" + std::to_string(r) + "].";
      object(regions[r], "regions[" + std::to_string(r) + "]");
      io::requireKnownKeys(regions[r], {"samples", "fallback_from", "note", "coefficients"}, path, source_);
      RegionFit fit;
      fit.samples =
          static_cast<int>(io::integerIn(at(regions[r], "samples", path), 0, INT32_MAX, path + "samples", source_));
      fit.fallback_from =
          static_cast<int>(io::integerIn(at(regions[r], "fallback_from", path), -2,
                                         static_cast<long long>(regions.size()) - 1, path + "fallback_from", source_));
      if (fit.fallback_from == static_cast<int>(r)) bad("'" + path + "fallback_from' names the region itself");
      fit.note = string(at(regions[r], "note", path), path + "note");
      std::vector<Eigen::VectorXd> coefs;
      for (const auto& c : array(at(regions[r], "coefficients", path), path + "coefficients")) {
        const std::vector<double> v = numbers(c, path + "coefficients[]");
        coefs.push_back(Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size())));
      }
      m.coefficients.push_back(std::move(coefs));
      m.region_fits.push_back(fit);
    }
  }

  const json& j_;
  std::string source_;
  int version_ = 0;
};

}  // namespace

DioPwlObfModel modelFromJson(const std::string& text, const std::string& source) {
  const json j = io::parseStrictJson(text, source);
  return ModelReader(j, source).read();
}

void saveModel(const std::string& path, const DioPwlObfModel& model) {
  writeTextFile(path, modelToJson(model) + "\n", "model file");
}

DioPwlObfModel loadModel(const std::string& path) { return modelFromJson(readTextFile(path, "model file"), path); }

}  // namespace plsa
