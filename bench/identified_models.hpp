// The models plsa-bench measures: identified by plsa itself on the built-in
// simulator, as a user's would be, in the structures users run (1 to 3
// chambers, input- and output-side scheduling, with and without the
// schedule lag, the slow pole and the tip frame), and the run they are
// driven with.
#pragma once

#include <string>
#include <vector>

#include "plsa/io/csv_log.hpp"
#include "plsa/model/dio_pwl_obf_model.hpp"

namespace plsa::bench {

struct BenchModel {
  std::string name;       ///< short label for tables
  std::string structure;  ///< what the model is, read off the model itself
  DioPwlObfModel model;
};

/// The demo's model first (`plsa demo`'s options on its grid run), then the
/// variants. Identification runs here (about 15 s); `say` gets progress lines.
std::vector<BenchModel> identifiedModels(std::uint64_t seed, void (*say)(const std::string&));

/// A joystick run of the simulator to drive them (the demo's validation run).
io::Log drivingRun(std::uint64_t seed);

/// Inputs, outputs, grid, lag, poles and frame in words.
std::string describe(const DioPwlObfModel& m);

}  // namespace plsa::bench
