#include "plsa/sim/sim_config.hpp"

#include <algorithm>
#include <map>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "plsa/core/text_file.hpp"
#include "plsa/io/strict_json.hpp"

namespace plsa::sim {
namespace {

using nlohmann::json;

// One table drives validation, JSON I/O and calibration access.
struct Field {
  std::string module;  // "" for top level
  ParamRef ref;
  std::string only_for = "";  // a formulation that alone uses it
  bool calibrated = true;     // among parameters(), which calibration moves
};

std::vector<Field> fields(SimConfig& c) {
  return {
      {"", {"sample_rate_hz", &c.sample_rate_hz, kMinSampleRateHz, kMaxSampleRateHz, "Hz"}},
      {"", {"internal_step_s", &c.internal_step_s, 1e-5, 0.01, "s"}},
      {"", {"max_pressure_bar", &c.max_pressure_bar, 0.01, 1.0, "bar"}},
      {"geometry", {"length_m", &c.geometry.length_m, 0.01, 1.0, "m"}},
      {"geometry", {"chamber_radius_m", &c.geometry.chamber_radius_m, 0.001, 0.1, "m"}},
      {"pneumatics", {"time_constant_s", &c.pneumatics.time_constant_s, 0.005, 2.0, "s"}},
      {"pneumatics", {"max_rate_bar_per_s", &c.pneumatics.max_rate_bar_per_s, 0.05, 100.0, "bar/s"}},
      {"elongation", {"strain_per_bar", &c.elongation.strain_per_bar, 0.01, 5.0, "1/bar"}},
      {"elongation", {"quadratic", &c.elongation.quadratic, -5.0, 5.0, "1/bar^2"}},
      {"bending", {"natural_freq_hz", &c.bending.natural_freq_hz, 0.05, 20.0, "Hz"}},
      {"bending", {"damping_ratio", &c.bending.damping_ratio, 0.05, 5.0, ""}},
      {"sensor", {"noise_deg", &c.sensor.noise_deg, 0.0, 10.0, "deg"}},
      {"deadzone", {"threshold_bar", &c.deadzone.threshold_bar, 0.0, 0.2, "bar"}},
      {"deadzone", {"smooth_width_bar", &c.deadzone.smooth_width_bar, 0.001, 0.1, "bar"}, "smooth"},
      {"hysteresis", {"width", &c.hysteresis.width, 0.0, 0.5, "fraction"}},
      {"hysteresis", {"weight_narrow", &c.hysteresis.weight_narrow, -1.0, 1.0, ""}, "weighted_pi"},
      {"hysteresis", {"weight_mid", &c.hysteresis.weight_mid, -1.0, 1.0, ""}, "weighted_pi"},
      {"hysteresis", {"weight_wide", &c.hysteresis.weight_wide, -1.0, 1.0, ""}, "weighted_pi"},
      {"hysteresis", {"fixed_band_share", &c.hysteresis.fixed_band_share, 0.0, 1.0, ""}, "weighted_pi"},
      {"hysteresis", {"weight_smooth", &c.hysteresis.weight_smooth, -1.0, 1.0, ""}, "weighted_pi"},
      {"hysteresis", {"smooth_saturation", &c.hysteresis.smooth_saturation, 0.05, 2.0, "fraction"}, "weighted_pi"},
      {"hysteresis", {"smooth_asymmetry", &c.hysteresis.smooth_asymmetry, -0.9, 0.9, ""}, "weighted_pi", false},
      {"stiffening", {"per_bar", &c.stiffening.per_bar, 0.0, 60.0, "1/bar"}},
      {"stiffening", {"exponent", &c.stiffening.exponent, 0.5, 3.0, ""}, "power"},
      {"stiffening", {"static_share", &c.stiffening.static_share, 0.0, 1.0, ""}, "power"},
      {"stiffening", {"per_rad2", &c.stiffening.per_rad2, 0.0, 40.0, "1/rad^2"}, "power"},
      {"coupling", {"per_bar", &c.coupling.per_bar, 0.0, 2.5, "1/bar"}},
      {"pneumatic_lag", {"fill_time_constant_s", &c.pneumatic_lag.fill_time_constant_s, 0.005, 2.0, "s"}},
      {"pneumatic_lag", {"vent_time_constant_s", &c.pneumatic_lag.vent_time_constant_s, 0.005, 2.0, "s"}},
      {"pneumatic_lag", {"delay_s", &c.pneumatic_lag.delay_s, 0.0, 0.5, "s"}},
      {"pneumatic_lag", {"exponent", &c.pneumatic_lag.exponent, 0.3, 1.0, ""}, "power"},
      {"pneumatic_lag", {"pressure_per_bar", &c.pneumatic_lag.pressure_per_bar, -4.0, 8.0, "1/bar"}, "power"},
      {"pneumatic_lag", {"line_time_constant_s", &c.pneumatic_lag.line_time_constant_s, 0.0, 0.5, "s"}, "power"},
      {"creep", {"fraction", &c.creep.fraction, 0.0, 0.5, ""}},
      {"creep", {"time_constant_s", &c.creep.time_constant_s, 0.1, 200.0, "s"}},
      {"sensor_bias", {"tilt_deg", &c.sensor_bias.tilt_deg, -15.0, 15.0, "deg"}},
      {"sensor_bias", {"yaw_deg", &c.sensor_bias.yaw_deg, -30.0, 30.0, "deg"}},
      {"sensor_bias", {"yaw_drift_deg_per_s", &c.sensor_bias.yaw_drift_deg_per_s, -1.0, 1.0, "deg/s"}},
      {"sensor_bias", {"offset_x_deg", &c.sensor_bias.offset_x_deg, -10.0, 10.0, "deg"}},
      {"sensor_bias", {"offset_y_deg", &c.sensor_bias.offset_y_deg, -10.0, 10.0, "deg"}},
      {"sensor_bias", {"drift_x_deg_per_s", &c.sensor_bias.drift_x_deg_per_s, -0.2, 0.2, "deg/s"}},
      {"sensor_bias", {"drift_y_deg_per_s", &c.sensor_bias.drift_y_deg_per_s, -0.2, 0.2, "deg/s"}},
  };
}

bool* enabledFlag(SimConfig& c, const std::string& effect) {
  if (effect == "deadzone") return &c.deadzone.enabled;
  if (effect == "hysteresis") return &c.hysteresis.enabled;
  if (effect == "stiffening") return &c.stiffening.enabled;
  if (effect == "coupling") return &c.coupling.enabled;
  if (effect == "pneumatic_lag") return &c.pneumatic_lag.enabled;
  if (effect == "creep") return &c.creep.enabled;
  if (effect == "sensor_bias") return &c.sensor_bias.enabled;
  std::string known;
  for (const auto& e : effectNames()) known += (known.empty() ? "" : ", ") + e;
  throw std::invalid_argument("unknown effect '" + effect + "' (known: " + known + ")");
}

std::string* formulation(SimConfig& c, const std::string& module) {
  if (module == "deadzone") return &c.deadzone.formulation;
  if (module == "hysteresis") return &c.hysteresis.formulation;
  if (module == "stiffening") return &c.stiffening.formulation;
  if (module == "coupling") return &c.coupling.formulation;
  if (module == "pneumatic_lag") return &c.pneumatic_lag.formulation;
  if (module == "creep") return &c.creep.formulation;
  if (module == "sensor_bias") return &c.sensor_bias.formulation;
  return nullptr;
}

}  // namespace

const std::vector<std::string>& formulationsOf(const std::string& module) {
  static const std::map<std::string, std::vector<std::string>> all = {
      {"deadzone", {"sharp", "smooth"}},
      {"hysteresis", {"play", "prandtl_ishlinskii", "weighted_pi"}},
      {"stiffening", {"linear", "quadratic", "exponential", "power"}},
      {"coupling", {"multiplicative", "saturating"}},
      {"pneumatic_lag", {"linear", "orifice", "choked", "power"}},
      {"creep", {"exponential", "two_rate"}},
      {"sensor_bias", {"linear_drift", "random_walk"}}};
  const auto it = all.find(module);
  if (it == all.end()) throw std::invalid_argument("no formulations for '" + module + "'");
  return it->second;
}

const std::vector<std::string>& integratorNames() {
  static const std::vector<std::string> names = {"euler", "exponential"};
  return names;
}

void requireIntegratorName(const std::string& name, const std::string& field) {
  const auto& names = integratorNames();
  if (std::find(names.begin(), names.end(), name) != names.end()) return;
  std::string list;
  for (const auto& n : names) list += (list.empty() ? "" : ", ") + n;
  throw std::invalid_argument(field + " '" + name + "' is not one of " + list);
}

std::string flexibleFormulationOf(const std::string& effect) {
  const auto& laws = formulationsOf(effect);
  if (effect == "hysteresis") return "weighted_pi";
  return std::find(laws.begin(), laws.end(), "power") != laws.end() ? "power" : "";
}

std::string& SimConfig::formulationOf(const std::string& effect) {
  std::string* f = formulation(*this, effect);
  if (!f) throw std::invalid_argument("unknown effect '" + effect + "'");
  return *f;
}

namespace {}  // namespace

bool SimConfig::effectEnabled(const std::string& effect) const {
  return *enabledFlag(const_cast<SimConfig&>(*this), effect);
}

void SimConfig::setEffectEnabled(const std::string& effect, bool on) { *enabledFlag(*this, effect) = on; }

std::vector<ParamRef> SimConfig::parameters(const std::string& module) {
  static const std::vector<std::string> nominal = {"pneumatics", "elongation", "bending"};
  std::vector<ParamRef> out;
  for (auto& f : fields(*this)) {
    const bool is_nominal = module == "nominal" && std::find(nominal.begin(), nominal.end(), f.module) != nominal.end();
    const bool used = f.only_for.empty() || *formulation(*this, f.module) == f.only_for;
    if ((is_nominal || f.module == module) && used && f.calibrated) out.push_back(f.ref);
  }
  if (out.empty() && module != "nominal") enabledFlag(*this, module);  // throws for unknown names
  return out;
}

void SimConfig::validate() const {
  SimConfig copy = *this;
  for (auto& f : fields(copy)) {
    const double v = *f.ref.value;
    const std::string name = (f.module.empty() ? "" : f.module + ".") + f.ref.name;
    if (!std::isfinite(v) || v < f.ref.lower || v > f.ref.upper) {
      std::ostringstream msg;
      msg << "sim config: " << name << " = " << v << " is outside [" << f.ref.lower << ", " << f.ref.upper << "] "
          << f.ref.unit;
      throw std::invalid_argument(msg.str());
    }
  }
  for (const std::string& m : effectNames()) {
    const std::string& f = *formulation(copy, m);
    const auto& ok = formulationsOf(m);
    if (std::find(ok.begin(), ok.end(), f) == ok.end()) {
      std::string list;
      for (const auto& name : ok) list += (list.empty() ? "" : ", ") + name;
      throw std::invalid_argument("sim config: " + m + ".formulation '" + f + "' is not one of " + list);
    }
  }
  requireIntegratorName(integrator, "sim config: integrator");
  // Chamber directions: angles on the circle (1e300 was taken), the three apart (at one direction the
  // segment bends in one plane and the steering subspaces are empty).
  for (std::size_t i = 0; i < 3; ++i) {
    const double d = geometry.bend_direction_deg[i];
    if (!(std::isfinite(d) && std::abs(d) <= 360.0)) {
      std::ostringstream msg;
      msg << "sim config: geometry.bend_direction_deg[" << i << "] = " << d << " is outside [-360, 360] deg";
      throw std::invalid_argument(msg.str());
    }
    for (std::size_t j = 0; j < i; ++j) {
      const double apart = std::fmod(std::abs(d - geometry.bend_direction_deg[j]), 360.0);
      if (std::min(apart, 360.0 - apart) < 1.0)
        throw std::invalid_argument("sim config: geometry.bend_direction_deg[" + std::to_string(j) + "] and [" +
                                    std::to_string(i) + "] are under 1 deg apart (three chambers around the axis)");
    }
  }
  // A chamber that shortened under more pressure would bend the segment backwards: a typo, not a device.
  const double a = elongation.strain_per_bar, q = elongation.quadratic;
  if (a + 2.0 * q * max_pressure_bar <= 0.0) {
    std::ostringstream msg;
    msg << "sim config: elongation " << a << " p + " << q << " p^2 stops rising at " << -a / (2.0 * q)
        << " bar, below max_pressure_bar = " << max_pressure_bar
        << " (a chamber must lengthen with pressure up to the maximum)";
    throw std::invalid_argument(msg.str());
  }
  if (1.0 / sample_rate_hz < internal_step_s)
    throw std::invalid_argument("sim config: internal_step_s is longer than the sample period");
}

SimConfig simConfigFromJson(const std::string& text, const std::string& source) {
  const json j = io::parseStrictJson(text, source);
  if (!j.is_object()) throw std::invalid_argument(source + ": the top level must be an object");
  SimConfig c;
  auto table = fields(c);
  auto number = [&](const json& v, const std::string& path) { return io::finiteNumber(v, path, source); };
  for (auto it = j.begin(); it != j.end(); ++it) {
    const std::string key = it.key();
    if (it->is_object()) {
      const bool is_effect = std::find(effectNames().begin(), effectNames().end(), key) != effectNames().end();
      bool known_module = is_effect;
      for (const auto& f : table) known_module = known_module || f.module == key;
      if (!known_module) throw std::invalid_argument(source + ": unknown section '" + key + "'");
      for (auto jt = it->begin(); jt != it->end(); ++jt) {
        const std::string path = key + "." + jt.key();
        if (is_effect && jt.key() == "enabled") {
          if (!jt->is_boolean()) throw std::invalid_argument(source + ": " + path + " must be true or false");
          c.setEffectEnabled(key, jt->get<bool>());
          continue;
        }
        if (jt.key() == "formulation" && formulation(c, key)) {
          if (!jt->is_string()) throw std::invalid_argument(source + ": " + path + " must be a string");
          *formulation(c, key) = jt->get<std::string>();
          continue;
        }
        if (key == "geometry" && jt.key() == "bend_direction_deg") {
          if (!jt->is_array() || jt->size() != 3)
            throw std::invalid_argument(source + ": " + path + " must be an array of 3 numbers");
          for (std::size_t i = 0; i < 3; ++i) c.geometry.bend_direction_deg[i] = number((*jt)[i], path);
          continue;
        }
        bool found = false;
        for (auto& f : table)
          if (f.module == key && f.ref.name == jt.key()) {
            *f.ref.value = number(*jt, path);
            found = true;
          }
        if (!found) throw std::invalid_argument(source + ": unknown key '" + path + "'");
      }
    } else if (key == "integrator") {
      if (!it->is_string()) throw std::invalid_argument(source + ": integrator must be a string");
      c.integrator = it->get<std::string>();
    } else {
      bool found = false;
      for (auto& f : table)
        if (f.module.empty() && f.ref.name == key) {
          *f.ref.value = number(*it, key);
          found = true;
        }
      if (!found) throw std::invalid_argument(source + ": unknown key '" + key + "'");
    }
  }
  try {
    c.validate();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(source + ": " + e.what());
  }
  return c;
}

SimConfig loadSimConfig(const std::string& path) {
  return simConfigFromJson(readTextFile(path, "simulator configuration"), path);
}

std::string simConfigToJson(const SimConfig& config) {
  SimConfig c = config;
  json j = json::object();
  for (auto& f : fields(c)) {
    if (f.module.empty())
      j[f.ref.name] = *f.ref.value;
    else
      j[f.module][f.ref.name] = *f.ref.value;
  }
  j["integrator"] = c.integrator;
  j["geometry"]["bend_direction_deg"] = c.geometry.bend_direction_deg;
  for (const auto& e : effectNames()) j[e]["enabled"] = c.effectEnabled(e);
  for (const auto& e : effectNames()) j[e]["formulation"] = *formulation(const_cast<SimConfig&>(c), e);
  return j.dump(2);
}

}  // namespace plsa::sim
