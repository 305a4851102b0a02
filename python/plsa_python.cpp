// plsa's Python module (pybind11): identify a model from CSV logs, validate
// it, run the real-time predictor, and simulate the built-in actuator. Thin:
// every call is the C++ library's, errors arrive as ValueError with the
// library's message, matrices as NumPy arrays (float64, samples x columns).
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/functional.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <memory>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "plsa/identify/pipeline.hpp"
#include "plsa/diagnose/diagnosis.hpp"
#include "plsa/eval/validation.hpp"
#include "plsa/io/csv_log.hpp"
#include "plsa/io/log_readers.hpp"
#include "plsa/model/model_file.hpp"
#include "plsa/can/candump_log.hpp"
#if PLSA_WITH_LCM
#include "plsa/lcm/lcm_log.hpp"
#endif
#include "plsa/predict/predictor.hpp"
#include "plsa/sim/actuator.hpp"
#include "plsa/sim/experiment.hpp"
#include "plsa/sim/sim_config.hpp"

namespace py = pybind11;

namespace {
class PyPredictor;
}

// An object made by `Model.__new__(Model)` (or Predictor's) has no C++ value:
// pybind11 would hand each method uninitialised memory (a segfault). Every
// Model and Predictor argument, `self` included, is checked here first.
namespace pybind11::detail {
template <class T>
class ConstructedOnlyCaster : public type_caster_base<T> {
 public:
  bool load(handle src, bool convert) {
    if (src && isinstance<T>(src)) {
      auto* inst = reinterpret_cast<instance*>(src.ptr());
      const value_and_holder v = inst->get_value_and_holder(get_type_info(typeid(T)), false);
      if (v.inst != nullptr && !v.holder_constructed()) {
        const std::string type = Py_TYPE(src.ptr())->tp_name;  // plsa._plsa.Model
        throw type_error("this plsa." + type.substr(type.rfind('.') + 1) +
                         " was made by __new__ without __init__ and holds nothing (make a model with "
                         "plsa.Model.load or plsa.identify, a predictor with plsa.Predictor(model))");
      }
    }
    return type_caster_base<T>::load(src, convert);
  }
};
template <>
class type_caster<plsa::DioPwlObfModel> : public ConstructedOnlyCaster<plsa::DioPwlObfModel> {};
template <>
class type_caster<PyPredictor> : public ConstructedOnlyCaster<PyPredictor> {};
}  // namespace pybind11::detail

namespace {

std::vector<plsa::io::Log> readLogs(const std::vector<std::string>& paths) {
  if (paths.empty()) throw std::invalid_argument("identify: no logs given");
  std::vector<plsa::io::Log> logs;
  for (const std::string& p : paths) logs.push_back(plsa::io::readLog(p));
  return logs;
}

plsa::DioPwlObfModel identify(const std::vector<std::string>& logs, std::optional<std::vector<std::string>> inputs,
                              std::optional<std::vector<std::string>> outputs, int poles, const std::string& scheduling,
                              const std::string& cv_layout, const std::string& output_drift,
                              std::optional<std::string> output_frame, int refine_play,
                              std::function<void(const std::string&)> progress, int levels,
                              std::optional<std::string> angle_unit) {
  plsa::identify::IdentifyOptions o;
  if (inputs) o.inputs = *inputs;
  if (outputs) o.outputs = *outputs;
  o.poles_per_pair = poles;
  o.scheduling = plsa::identify::parseOption<plsa::identify::SchedulingChoice>(scheduling);
  o.cv_layout = plsa::identify::parseOption<plsa::identify::CvLayout>(cv_layout);
  o.output_drift = plsa::identify::parseOption<plsa::identify::OutputDriftChoice>(output_drift);
  if (output_frame && *output_frame != "auto") o.output_frame = plsa::outputFrameFromString(*output_frame);
  o.play_refine_evaluations = refine_play;
  o.quantile_levels = levels;
  if (angle_unit && *angle_unit != "auto") o.angle_unit = *angle_unit;
  if (progress)
    o.progress = [progress](const std::string& line) {
      py::gil_scoped_acquire gil;
      progress(line);
    };
  const std::vector<plsa::io::Log> read = readLogs(logs);
  py::gil_scoped_release unlocked;  // minutes on long logs: other Python threads run meanwhile
  return plsa::identify::identifyModel(read, o);
}

py::dict validate(const plsa::DioPwlObfModel& model, const std::string& log, const std::vector<int>& horizons,
                  double settle_s) {
  plsa::eval::SimulationStart start;
  start.settle_s = settle_s;
  const plsa::eval::ValidationResult v = plsa::eval::validateModel(model, plsa::io::readLog(log), horizons, start);
  const std::vector<plsa::eval::SimulationDeparture> departures = plsa::eval::simulationDepartures(v);
  py::dict result;
  for (const plsa::eval::OutputValidation& o : v.outputs) {
    py::dict entry;
    entry["fit"] = o.fit_k;
    entry["fit_sim"] = o.fit_sim;
    entry["rms"] = o.rms_k;
    entry["rms_sim"] = o.rms_sim;
    entry["sim_error_kept"] = o.sim_error_kept;  // {horizon: share}: below 0.5 the k-step fit loses to the simulation
    entry["measured"] = o.measured;
    entry["predicted"] = o.predicted_k;  // {horizon: array}, NaN before the first predicted sample
    entry["simulated"] = o.simulated;
    entry["scored_from"] = v.scored_from;
    entry["sim_departure"] = py::none();
    for (const plsa::eval::SimulationDeparture& d : departures)
      if (d.output == o.name)
        entry["sim_departure"] = py::dict(py::arg("farthest") = d.farthest, py::arg("share_of_width") = d.share,
                                          py::arg("first_time_s") = d.first_time_s);
    entry["unsettled_start"] = py::none();
    for (const plsa::eval::UnsettledStart& t : v.unsettled_starts)
      if (t.output == o.name)
        entry["unsettled_start"] =
            py::dict(py::arg("later_s") = t.later_s, py::arg("rms_error") = t.rms_error,
                     py::arg("rms_later") = t.rms_later, py::arg("straight_share") = t.straight_share);
    result[py::str(o.name)] = entry;
  }
  return result;
}

plsa::diagnose::RunColumns runColumns(std::optional<std::vector<std::string>> inputs,
                                      std::optional<std::vector<std::string>> outputs,
                                      std::optional<std::vector<std::string>> pressures, double input_scale,
                                      const std::string& output_map) {
  if (output_map != "angles" && output_map != "affine")
    throw std::invalid_argument("diagnose: output_map '" + output_map + "': expected angles or affine");
  plsa::diagnose::RunColumns c;
  if (inputs) c.inputs = *inputs;
  if (outputs) c.outputs = *outputs;
  if (pressures) c.pressures = *pressures;  // []: none measured
  c.input_scale = input_scale;
  c.map = output_map == "affine" ? plsa::diagnose::OutputMap::kAffine : plsa::diagnose::OutputMap::kAngles;
  return c;
}

// `plsa diagnose` from Python: the diagnosis as the dict its diagnosis.json
// holds, and the folder (report, CSVs, calibrated configuration) when `out`
// names one.
py::object diagnose(const std::string& sim, const std::vector<std::string>& real, const plsa::diagnose::RunColumns& c,
                    std::optional<std::vector<std::string>> candidates, std::optional<int> evaluations, int threads,
                    std::function<void(const std::string&)> progress, std::optional<std::string> out) {
  if (real.empty()) throw std::invalid_argument("diagnose: no real runs given");
  if (evaluations && (*evaluations < 20 || *evaluations > 100000))  // the command line's range
    throw std::invalid_argument("diagnose: evaluations must be 20 to 100000, got " + std::to_string(*evaluations));
  if (threads < 1 || threads > 64)
    throw std::invalid_argument("diagnose: threads must be 1 to 64, got " + std::to_string(threads));
  if (out)
    for (const std::string& input : real)
      for (const char* name : plsa::diagnose::kDiagnosisFiles)
        if (std::filesystem::weakly_canonical(std::filesystem::path(*out) / name) ==
            std::filesystem::weakly_canonical(input))
          throw std::invalid_argument("diagnose: out '" + *out + "' would write " + name + " over the input " + input);
  const plsa::sim::SimConfig config = plsa::sim::loadSimConfig(sim);
  plsa::diagnose::DiagnoseOptions o;
  o.calibration.gap.map = c.map;
  if (candidates) o.candidates = *candidates;
  if (evaluations) o.calibration.max_evaluations = *evaluations;
  o.threads = threads;
  if (progress)
    o.log = [progress](const std::string& line) {
      py::gil_scoped_acquire gil;
      progress(line);
    };
  std::vector<plsa::diagnose::RunData> runs;
  for (const std::string& path : real)
    runs.push_back(plsa::diagnose::runFromLog(plsa::io::readLog(path), c, config.max_pressure_bar));
  plsa::diagnose::Diagnosis d;
  {
    py::gil_scoped_release unlocked;  // minutes of simulator runs: other Python threads run meanwhile
    d = plsa::diagnose::runDiagnosis(config, runs, o);
  }
  if (out) plsa::diagnose::writeDiagnosisFolder(d, *out);
  return py::module_::import("json").attr("loads")(plsa::diagnose::toJson(d));
}

// The log as {column: array}, by index (a lookup by name per column was
// quadratic: 140k columns took 14 s).
py::dict columnsOf(const plsa::io::Log& log) {
  py::dict columns;
  for (std::size_t i = 0; i < log.columns.size(); ++i)
    columns[py::str(log.columns[i])] = Eigen::VectorXd(log.data.col(static_cast<Eigen::Index>(i)));
  return columns;
}

// A message as a Python exception; bytes that are not UTF-8 (a path or a
// name quoted from a file) are kept as \x escapes, not lost with the message.
void raise(PyObject* type, const char* what) {
  PyObject* text = PyUnicode_DecodeUTF8(what, static_cast<Py_ssize_t>(std::strlen(what)), "backslashreplace");
  if (!text) {
    PyErr_Clear();
    PyErr_SetString(type, "(a message that could not be decoded)");
    return;
  }
  PyErr_SetObject(type, text);
  Py_DECREF(text);
}

py::dict readLog(const std::string& path) { return columnsOf(plsa::io::readLog(path)); }

py::dict simulate(const std::string& experiment, const std::optional<std::string>& path, std::uint64_t seed,
                  double duration_s) {
  plsa::sim::ExperimentOptions eo;
  eo.seed = seed;
  if (!(std::isfinite(duration_s) && duration_s >= 0.0))  // -5 and NaN fell back to 60 s without a word
    throw std::invalid_argument("simulate: duration_s must be a finite number of seconds >= 0 (0: the default)");
  if (duration_s > 0 && experiment != "joystick")
    throw std::invalid_argument("simulate: duration_s sets the joystick run's length; " + experiment +
                                " has its own (leave duration_s at 0)");
  if (duration_s > 0) eo.joystick_duration_s = duration_s;
  plsa::sim::Experiment e;
  if (experiment == "grid2")
    e = plsa::sim::gridExperiment(eo);
  else if (experiment == "joystick")
    e = plsa::sim::joystickExperiment(eo);
  else
    throw std::invalid_argument("simulate: experiment '" + experiment + "': expected grid2 or joystick");
  plsa::sim::Actuator actuator(plsa::sim::SimConfig{}, seed);
  const plsa::io::Log log = plsa::sim::runExperiment(actuator, e);
  if (path) plsa::io::writeCsvLog(*path, log);
  return columnsOf(log);
}

using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// The predictor with its buffers: status codes become exceptions for the
// calls a Python user makes one at a time, names for update's.
class PyPredictor {
 public:
  PyPredictor(const plsa::DioPwlObfModel& model, int max_horizon)
      : options_(optionsFor(max_horizon)),
        p_(model, options_),
        plan_(max_horizon, model.inputCount()),
        out_(max_horizon, model.outputCount()) {}

  std::string update(double time_s, const Eigen::VectorXd& u, const Eigen::VectorXd& y) {
    if (u.size() != p_.inputCount() || y.size() != p_.outputCount())
      throw std::invalid_argument("update: the model has " + std::to_string(p_.inputCount()) + " inputs and " +
                                  std::to_string(p_.outputCount()) + " outputs, got " + std::to_string(u.size()) +
                                  " and " + std::to_string(y.size()));
    return plsa::toString(p_.update(time_s, u, y));
  }

  // The plan read in place when it is a C-ordered float64 array (numpy's
  // default), copied into the predictor's own buffer; the rows written into
  // the one array returned.
  py::array_t<double> predict(int horizon, std::optional<Eigen::Ref<const RowMajor>> plan) {
    checkHorizon(horizon);
    const Eigen::Index rows = plan ? takePlan(*plan) : 0;
    auto out = out_.topRows(horizon);
    check("predict", p_.predict(horizon, plan_.topRows(rows), out));
    py::array_t<double> result({static_cast<py::ssize_t>(horizon), static_cast<py::ssize_t>(p_.outputCount())});
    Eigen::Map<RowMajor>(result.mutable_data(), horizon, p_.outputCount()) = out;
    return result;
  }

  // The bench's reference: the p50 of `calls` C++ predict() calls on the
  // current state and this plan, each timed on its own (ns).
  double timePredictNs(int horizon, const Eigen::Ref<const RowMajor>& plan, int calls) {
    checkHorizon(horizon);
    if (calls < 1 || calls > 10'000'000) throw std::invalid_argument("_time_predict: calls 1 to 10^7");
    const Eigen::Index rows = takePlan(plan);
    auto out = out_.topRows(horizon);
    std::vector<double> ns(static_cast<std::size_t>(calls));
    for (auto& t : ns) {
      const auto t0 = std::chrono::steady_clock::now();
      check("predict", p_.predict(horizon, plan_.topRows(rows), out));
      t = std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - t0).count();
    }
    std::nth_element(ns.begin(), ns.begin() + calls / 2, ns.end());
    return ns[static_cast<std::size_t>(calls / 2)];
  }

  py::object sensitivity(int horizon, const Eigen::MatrixXd& plan, bool with_prediction) {
    checkHorizon(horizon);
    // The Jacobian grows with the square of the horizon (7000 took 2.3 GB): checked before it is allocated.
    if (horizon > kMaxSensitivityHorizon)
      throw std::invalid_argument("sensitivity: horizon " + std::to_string(horizon) + " is over " +
                                  std::to_string(kMaxSensitivityHorizon) + " (its Jacobian grows with its square)");
    if (plan.rows() < horizon - 1 || plan.cols() != p_.inputCount())
      throw std::invalid_argument("sensitivity: the plan needs at least " + std::to_string(horizon - 1) + " rows of " +
                                  std::to_string(p_.inputCount()) + " inputs, got " + std::to_string(plan.rows()) +
                                  " x " + std::to_string(plan.cols()));
    Eigen::MatrixXd jacobian(static_cast<Eigen::Index>(horizon) * p_.outputCount(),
                             static_cast<Eigen::Index>(horizon - 1) * p_.inputCount());
    if (!with_prediction) {
      check("sensitivity", p_.sensitivity(horizon, plan, jacobian));
      return py::cast(std::move(jacobian));
    }
    Eigen::MatrixXd predicted(horizon, p_.outputCount());
    check("sensitivity", p_.sensitivity(horizon, plan, jacobian, plsa::JacobianFill::kWhole, predicted));
    return py::make_tuple(std::move(jacobian), std::move(predicted));
  }

  // A re-identified model of the same structure, adopted at the next update.
  void install(const plsa::DioPwlObfModel& model) {
    py::gil_scoped_release unlocked;  // compiling may take a while: other Python threads run meanwhile
    p_.install(model);
  }
  std::uint64_t modelId() const { return p_.modelId(); }

  int inputs() const { return p_.inputCount(); }
  int outputs() const { return p_.outputCount(); }

 private:
  static constexpr int kMaxSensitivityHorizon = 1000;
  static plsa::PredictorOptions optionsFor(int max_horizon) {
    plsa::PredictorOptions o;
    o.max_horizon = max_horizon;
    return o;
  }
  void checkHorizon(int horizon) const {
    if (horizon < 1 || horizon > p_.maxHorizon())
      throw std::invalid_argument("horizon " + std::to_string(horizon) + " outside 1.." +
                                  std::to_string(p_.maxHorizon()) + " (max_horizon at construction)");
  }
  // The plan copied into the predictor's buffer; its rows. A plan of another
  // width or of more than max_horizon rows is refused as predict() refuses it.
  Eigen::Index takePlan(const Eigen::Ref<const RowMajor>& plan) {
    if (plan.rows() > plan_.rows() || plan.cols() != plan_.cols()) check("predict", plsa::PredictorStatus::kBadShape);
    plan_.topRows(plan.rows()) = plan;
    return plan.rows();
  }
  static void check(const char* what, plsa::PredictorStatus s) {
    if (static_cast<int>(s) < 0) throw std::invalid_argument(std::string(what) + ": " + plsa::toString(s));
  }

  plsa::PredictorOptions options_;
  plsa::Predictor<> p_;
  Eigen::MatrixXd plan_, out_;  // max_horizon rows: the plan as the predictor reads it, the rows it writes
};

void bindModel(py::module_& m) {
  py::class_<plsa::DioPwlObfModel>(m, "Model", "An identified DIO-PWL-OBF model")
      .def_static("load", &plsa::loadModel, py::arg("path"), "Read a model file (JSON)")
      .def(
          "save", [](const plsa::DioPwlObfModel& self, const std::string& path) { plsa::saveModel(path, self); },
          py::arg("path"), "Write the model file (JSON), atomically")
      .def_readonly("inputs", &plsa::DioPwlObfModel::inputs)
      .def_readonly("outputs", &plsa::DioPwlObfModel::outputs)
      .def_readonly("sample_time_s", &plsa::DioPwlObfModel::sample_time_s)
      .def_property_readonly("output_frame",
                             [](const plsa::DioPwlObfModel& self) { return plsa::toString(self.output_frame); })
      .def_readonly("output_unit", &plsa::DioPwlObfModel::output_unit)
      .def_property_readonly("regions", [](const plsa::DioPwlObfModel& self) { return self.partition.regionCount(); })
      .def("__repr__", [](const plsa::DioPwlObfModel& self) {
        return "<plsa.Model " + std::to_string(self.inputCount()) + " inputs, " + std::to_string(self.outputCount()) +
               " outputs, " + std::to_string(self.partition.regionCount()) + " regions, " +
               plsa::toString(self.output_frame) + ">";
      });
}

void bindTools(py::module_& m) {
  m.def("identify", &identify, py::arg("logs"), py::arg("inputs") = py::none(), py::arg("outputs") = py::none(),
        py::arg("poles") = 5, py::arg("scheduling") = "auto", py::arg("cv_layout") = "interleaved",
        py::arg("output_drift") = "off", py::arg("output_frame") = py::none(), py::arg("refine_play") = 0,
        py::arg("progress") = py::none(), py::arg("levels") = 0, py::arg("angle_unit") = py::none(),
        "Identify a model from CSV logs, as `plsa identify` (the same options and defaults; levels: its --levels, "
        "quantile levels per input for logs without a staircase, 0 to choose them; angle_unit: its --angle-unit, "
        "deg or rad, None to read it from the names or the data)");
  m.def("validate", &validate, py::arg("model"), py::arg("log"), py::arg("horizons") = std::vector<int>{40, 80},
        py::arg("settle_s") = 0.0,
        "Fits (%) and rms errors of a model on a CSV log, with what was scored: {output: {fit: {horizon: %}, "
        "fit_sim, rms, rms_sim, sim_error_kept: {horizon: share}, measured, predicted: {horizon: array}, simulated, "
        "scored_from, sim_departure, unsettled_start}}; settle_s: seconds at the log's start left out of the "
        "scores (a log not recorded from rest); unsettled_start, when not None, says what the log's start costs the "
        "simulation: its rms error rms_error, and rms_later when started and scored later_s seconds into the log "
        "(straight_share: a tip-frame model's steering, the share of the samples left out on which the tip is "
        "straight, where its angle is the sensor's noise); "
        "the arrays span the log (NaN where a horizon has no prediction), fits count samples from scored_from on; "
        "sim_departure is None, or how far the free simulation leaves the measured range (farthest, "
        "share_of_width, first_time_s) when it does by more than half its width");
  m.def(
      "diagnose",
      [](const std::string& sim, const std::vector<std::string>& real, std::optional<std::vector<std::string>> inputs,
         std::optional<std::vector<std::string>> outputs, std::optional<std::vector<std::string>> pressures,
         double input_scale, const std::string& output_map, std::optional<std::vector<std::string>> candidates,
         std::optional<int> evaluations, int threads, std::function<void(const std::string&)> progress,
         std::optional<std::string> out) {
        return diagnose(sim, real, runColumns(inputs, outputs, pressures, input_scale, output_map), candidates,
                        evaluations, threads, progress, out);
      },
      py::arg("sim"), py::arg("real"), py::arg("inputs") = py::none(), py::arg("outputs") = py::none(),
      py::arg("pressures") = py::none(), py::arg("input_scale") = 1.0, py::arg("output_map") = "angles",
      py::arg("candidates") = py::none(), py::arg("evaluations") = py::none(), py::arg("threads") = 2,
      py::arg("progress") = py::none(), py::arg("out") = py::none(),
      "Where and why a simulator (its configuration file) disagrees with real runs (logs), as `plsa diagnose`: "
      "returns what diagnosis.json holds (verdict, ranking, gaps, where), and writes the report folder to out "
      "when given; pressures=[] when none were measured");
  m.def("read_log", &readLog, py::arg("path"),
        "A log (CSV, a candump bus log decoded with plsa's CAN profile, or, in a build with LCM, an LCM event "
        "log's PLSA_STATE messages) as {column: array}, read (and checked) as the library reads it");
  m.def("simulate", &simulate, py::arg("experiment"), py::arg("path") = py::none(), py::arg("seed") = 1,
        py::arg("duration_s") = 0.0,
        "Run the built-in simulated actuator (all effects on) through grid2 or joystick (duration_s: the "
        "joystick run's length, default 60 s); returns the log as {column: array}, and writes it as a CSV log "
        "to path when one is given");
}

void bindPredictor(py::module_& m) {
  py::class_<PyPredictor>(m, "Predictor", "The real-time n-step predictor (plsa::Predictor<>)")
      .def(py::init<const plsa::DioPwlObfModel&, int>(), py::arg("model"), py::arg("max_horizon") = 400)
      .def("update", &PyPredictor::update, py::arg("time_s"), py::arg("u"), py::arg("y"),
           "Feed one measured sample; returns the status ('ok', or what was rejected or restarted)")
      .def("predict", &PyPredictor::predict, py::arg("horizon"), py::arg("plan") = py::none(),
           "horizon x outputs: the next samples under the plan (rows: inputs from the next sample on; none: hold)")
      .def("_time_predict", &PyPredictor::timePredictNs, py::arg("horizon"), py::arg("plan"), py::arg("calls"),
           "For the bench: the p50 (ns) of `calls` C++ predict() calls on the current state, each timed alone")
      .def("sensitivity", &PyPredictor::sensitivity, py::arg("horizon"), py::arg("plan"),
           py::arg("with_prediction") = false,
           "(horizon * outputs) x ((horizon - 1) * inputs): d prediction / d plan; with_prediction: the tuple "
           "(that, the prediction it is taken at, as predict(horizon, plan) gives it) from one planned prediction")
      .def("install", &PyPredictor::install, py::arg("model"),
           "A model of the same structure (e.g. re-identified), adopted whole at the next update; raises "
           "ValueError for another structure")
      .def_property_readonly("model_id", &PyPredictor::modelId,
                             "Which installed model the predictor runs: 0 the first, then one more per install")
      .def_property_readonly("inputs", &PyPredictor::inputs)
      .def_property_readonly("outputs", &PyPredictor::outputs);
}

}  // namespace

PYBIND11_MODULE(_plsa, m) {
  m.doc() = "plsa: identification and prediction of pneumatic soft actuators (DIO-PWL-OBF)";
  plsa::can::registerLogFormats();  // candump bus logs, as the tools read them
#if PLSA_WITH_LCM
  plsa::lcm::registerLogFormats();  // LCM event logs, as the tools read them
#endif
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const py::builtin_exception& e) {  // pybind11's own (type_error, value_error): as they are
      e.set_error();
    } catch (const std::invalid_argument& e) {
      raise(PyExc_ValueError, e.what());
    } catch (const std::runtime_error& e) {
      raise(PyExc_RuntimeError, e.what());
    }
  });

  bindModel(m);
  bindTools(m);
  bindPredictor(m);
}
