// Model files: round trips of every field and a clear error for each bad one.
// One table row per field (or group of fields written together): how to set
// it on a model, how to compare what comes back, what a file written before
// the field existed (version 1) reads as, and the bad values with the words
// their error must carry.
#include <functional>
#include <ostream>

#include "support/identify_fixtures.hpp"
#include "plsa/io/strict_json.hpp"

using namespace plsa;
using namespace plsa::test_fixtures;
using C = std::complex<double>;

namespace {

/// A bad file: `edit` applied to the written file (version 2, every field
/// required) or to its version-1 form (FieldCase::old_file), and the words
/// its error must carry ("" = any std::invalid_argument).
struct BadValue {
  std::string what;
  bool on_old_file = false;
  std::function<void(nlohmann::json&)> edit;
  std::string words;
};

struct FieldCase {
  std::string name;                          ///< the case's name in the test list
  std::function<void(DioPwlObfModel&)> set;  ///< sets the field on knownModel()
  /// What was written against what was read back.
  std::function<void(const DioPwlObfModel& written, const DioPwlObfModel& read)> expect_same;
  /// Left out of the file when the field is unset (knownModel()); "" = always written.
  std::string omitted_when_unset;
  /// Keys erased to make the version-1 file; none: no version-1 check.
  std::vector<std::string> old_file_lacks;
  /// What a version-1 file without those keys reads as (given that file).
  std::function<void(const nlohmann::json& v1)> expect_old_default;
  std::vector<BadValue> bad;
};

void PrintTo(const FieldCase& c, std::ostream* os) { *os << c.name; }

DioPwlObfModel readBack(const nlohmann::json& j) { return modelFromJson(j.dump()); }

// A model with two play channels on its one input (the rows on play fields).
void setPlayChannels(DioPwlObfModel& m) {
  m.shaping.play = {{0.02, PlayChannel(0.0, 0.12)}};
  m.poles = {{PoleSet::real({0.9, 0.7})}};
  m.coefficients = {{Eigen::Vector4d(1, 2, 3, 4)}, {Eigen::Vector4d(-1, 0.5, 0.25, 2)}};
}

std::vector<FieldCase> fieldCases() {
  using J = nlohmann::json;
  std::vector<FieldCase> cases;

  // Poles, coefficients and partition; every other key's rejections in a version-2 file.
  cases.push_back(FieldCase{
      "PolesCoefficientsAndPartition",
      [](DioPwlObfModel& m) {
        m.poles = {{PoleSet({C(0.9, 0), C(0.6, 0.2), C(0.6, -0.2)})}};
        m.coefficients = {{Eigen::Vector3d(1, 2, 3)}, {Eigen::Vector3d(-1, 0.5, 1.0 / 3.0)}};
      },
      [](const DioPwlObfModel& m, const DioPwlObfModel& back) {
        EXPECT_EQ(back.coefficients[1][0], m.coefficients[1][0]);
        EXPECT_EQ(back.poles[0][0].poles(), m.poles[0][0].poles());
        EXPECT_EQ(back.partition.breakpoints(), m.partition.breakpoints());
      },
      "",
      {},
      nullptr,
      {
          {"no sample time", false, [](J& j) { j.erase("sample_time_s"); }, "missing field 'sample_time_s'"},
          {"a newer version", false, [](J& j) { j["version"] = 7; }, "version 7 is newer than this build reads"},
          {"a fractional version", false, [](J& j) { j["version"] = 1.0; }, "'version' must be an integer"},
          {"version 0", false, [](J& j) { j["version"] = 0; }, "'version' must be an integer in 1.."},
          {"65 poles in a bank", false,
           [](J& j) {
             j["poles"][0][0] = J::array();
             for (int i = 0; i < 65; ++i) j["poles"][0][0].push_back({0.5, 0.0});
           },
           "poles[0][0]: more than 64 poles"},
          {"an unknown key", false, [](J& j) { j["extra"] = 1; }, "unknown key 'extra'"},
          {"an unknown region key", false, [](J& j) { j["regions"][0]["extra"] = 1; },
           "unknown key 'regions[0].extra'"},
          {"an output twice", false, [](J& j) { j["outputs"].push_back(j["outputs"][0]); }, "twice"},
          {"a column both input and output", false, [](J& j) { j["outputs"][0] = j["inputs"][0]; },
           "column 'u' is both an input and an output"},
          {"a null range", false, [](J& j) { j["input_range"][0] = nullptr; }, "'input_range[0]' must be a number"},
          {"a range of \"-inf\"", false, [](J& j) { j["input_range"][1] = "-inf"; },
           "'input_range[1]' must be a number or \"inf\""},
          {"a sample count of 1e300", false, [](J& j) { j["regions"][0]["samples"] = 1e300; },
           "'regions[0].samples' must be an integer"},
          // Version 2 files carry every field: one left out is an error, not a default.
          {"no play_start in version 2", false, [](J& j) { j.erase("play_start"); }, "missing field 'play_start'"},
          {"a coefficient too many", false, [](J& j) { j["regions"][1]["coefficients"][0].push_back(1.0); },
           "expected 3"},
          {"an unstable pole", false,
           [](J& j) {
             j["poles"][0][0][0] = {1.5, 0.0};
           },
           ">= 1"},
          {"fuzzy scheduling", false, [](J& j) { j["partition"]["scheduling"] = "fuzzy"; },
           "'switched' or 'interpolated'"},
          {"a coefficient that is text", false, [](J& j) { j["regions"][0]["coefficients"][0][0] = "x"; },
           "must be a number"},
          {"play_start 'middle'", false, [](J& j) { j["play_start"] = "middle"; }, "'rising' or 'centred'"},
          {"a play channel without a slope", false,
           [](J& j) {
             j["input_play"][0][0] = {{"width", 0.1}};
           },
           "input_play[][].slope"},
      }});

  cases.push_back(FieldCase{"OutputFrame",
                            [](DioPwlObfModel& m) {
                              m.poles = {{PoleSet::real({0.9, 0.7})}, {PoleSet::real({0.8, 0.5})}};
                              m.outputs = {"bend_deg", "steer_deg"};
                              m.coefficients = {{Eigen::Vector2d(1, 2), Eigen::Vector2d(3, 4)},
                                                {Eigen::Vector2d(-1, 0.5), Eigen::Vector2d(0, 1)}};
                              m.output_frame = OutputFrame::kTipCartesian;
                            },
                            [](const DioPwlObfModel&, const DioPwlObfModel& back) {
                              EXPECT_EQ(back.output_frame, OutputFrame::kTipCartesian);
                            },
                            "",
                            {"output_frame"},  // version 1 files from before the field: the logged frame
                            [](const J& v1) { EXPECT_EQ(readBack(v1).output_frame, OutputFrame::kAsLogged); },
                            {
                                {"frame 'polar'", true, [](J& j) { j["output_frame"] = "polar"; },
                                 "'output_frame' must be 'as_logged' or 'tip_cartesian'"},
                            }});

  cases.push_back(FieldCase{"PlayChannelsAndStart",
                            setPlayChannels,
                            [](const DioPwlObfModel& m, const DioPwlObfModel& back) {
                              EXPECT_EQ(back.shaping.play, m.shaping.play);
                              EXPECT_EQ(back.shaping.start, PlayStart::kRising);
                            },
                            "",
                            {"play_start"},  // a file written before the field keeps its centred channels
                            [](const J& v1) { EXPECT_EQ(readBack(v1).shaping.start, PlayStart::kCentred); },
                            {}});

  cases.push_back(FieldCase{"PlayCoupling",
                            [](DioPwlObfModel& m) {
                              setPlayChannels(m);
                              m.shaping.coupling = 0.75;
                            },
                            [](const DioPwlObfModel& m, const DioPwlObfModel& back) {
                              EXPECT_EQ(back.shaping.coupling, 0.75);
                              EXPECT_EQ(back.shaping.play, m.shaping.play);
                            },
                            "",
                            {"play_start", "play_coupling"},  // ...and its uncoupled ones
                            [](const J& v1) {
                              EXPECT_EQ(readBack(v1).shaping.start, PlayStart::kCentred);
                              EXPECT_EQ(readBack(v1).shaping.coupling, 0.0);
                            },
                            {
                                {"a negative coupling", true, [](J& j) { j["play_coupling"] = -1.0; }, ""},
                            }});

  cases.push_back(
      FieldCase{"PlayThreshold",
                [](DioPwlObfModel& m) { m.shaping.threshold = 0.07; },
                [](const DioPwlObfModel&, const DioPwlObfModel& back) { EXPECT_EQ(back.shaping.threshold, 0.07); },
                "",
                {"play_threshold"},  // version 1, written before the field existed: counted from zero
                [](const J& v1) { EXPECT_EQ(readBack(v1).shaping.threshold, 0.0); },
                {
                    {"a negative threshold", true, [](J& j) { j["play_threshold"] = -0.01; }, "play_threshold"},
                    {"a threshold that is text", true, [](J& j) { j["play_threshold"] = "high"; }, ""},
                }});

  cases.push_back(
      FieldCase{"PlaySoftening",
                [](DioPwlObfModel& m) { m.shaping.softening = 0.8; },
                [](const DioPwlObfModel&, const DioPwlObfModel& back) { EXPECT_EQ(back.shaping.softening, 0.8); },
                "",
                {"play_softening"},  // version 1, written before the field existed: linear
                [](const J& v1) { EXPECT_EQ(readBack(v1).shaping.softening, 0.0); },
                {
                    {"a negative softening", true, [](J& j) { j["play_softening"] = -0.5; }, "play_softening"},
                    {"a softening that is text", true, [](J& j) { j["play_softening"] = "soft"; }, ""},
                }});

  cases.push_back(
      FieldCase{"TrainingDrift",
                [](DioPwlObfModel& m) {
                  ASSERT_EQ(m.outputCount(), 1);
                  m.training_drift_per_s = {0.0244};
                  m.training_drift_reference_s = 115.5;
                },
                [](const DioPwlObfModel& m, const DioPwlObfModel& back) {
                  EXPECT_EQ(back.training_drift_per_s, m.training_drift_per_s);
                  EXPECT_EQ(back.training_drift_reference_s, 115.5);
                },
                "training_output_drift",  // none: not written
                {},
                nullptr,
                {
                    {"two rates for one output", false,
                     [](J& j) {
                       j["training_output_drift"]["rate_per_s"] = {0.01, 0.02};
                     },
                     "training_output_drift"},
                    {"a rate that is text", false, [](J& j) { j["training_output_drift"]["rate_per_s"] = {"fast"}; },
                     "training_output_drift.rate_per_s"},
                    // Finite, and every sample would turn the predictor's yaw by it.
                    {"a rate of 1e300 deg/s", false, [](J& j) { j["training_output_drift"]["rate_per_s"] = {1e300}; },
                     "rate of 1e+300 deg/s is a turn a second or more"},
                    {"a rate of a turn a second", false,
                     [](J& j) { j["training_output_drift"]["rate_per_s"] = {-360.0}; }, "a turn a second or more"},
                    {"no reference time", false,
                     [](J& j) {
                       j["training_output_drift"]["rate_per_s"] = {0.01};
                       j["training_output_drift"].erase("reference_time_s");
                     },
                     "training_output_drift.reference_time_s"},
                }});

  // The schedule's lag and side, and the output level only the input side may have.
  cases.push_back(
      FieldCase{"ScheduleLagAndSide",
                [](DioPwlObfModel& m) { m.schedule_lag_s = 0.4; },
                [](const DioPwlObfModel& m, const DioPwlObfModel& back) {
                  EXPECT_EQ(back.schedule_lag_s, 0.4);
                  EXPECT_NEAR(m.schedulePole(), std::exp(-m.sample_time_s / 0.4), 1e-15);
                },
                "",
                {"schedule_lag_s", "schedule_side"},
                [](const J& v1) {
                  EXPECT_EQ(readBack(v1).schedule_lag_s, 0.0);
                  EXPECT_EQ(readBack(v1).schedulePole(), 0.0);
                  J lagged = v1;
                  lagged["schedule_lag_s"] = 0.4;
                  EXPECT_EQ(readBack(lagged).schedule_side, ScheduleSide::kOutput);  // files from before the field
                  EXPECT_TRUE(readBack(lagged).output_level.empty());
                },
                {
                    {"a negative lag", true, [](J& j) { j["schedule_lag_s"] = -0.1; }, ""},
                    {"a lag that is text", true, [](J& j) { j["schedule_lag_s"] = "slow"; }, ""},
                    // The level of an output-side model is no function of its inputs.
                    {"output_level on the output side", true,
                     [](J& j) {
                       j["schedule_lag_s"] = 0.4;
                       j["output_level"] = {1.5};
                     },
                     "output_level needs input-side"},
                    {"an output_level that is text", true,
                     [](J& j) {
                       j["schedule_lag_s"] = 0.4;
                       j["output_level"] = {"high"};
                     },
                     ""},
                    {"schedule_side 'sideways'", true,
                     [](J& j) {
                       j["schedule_lag_s"] = 0.4;
                       j["schedule_side"] = "sideways";
                     },
                     "'output' or 'input'"},
                    {"an input-side switched partition", true,  // input side needs an interpolated partition
                     [](J& j) {
                       j["schedule_lag_s"] = 0.4;
                       j["schedule_side"] = "input";
                     },
                     "interpolated partition"},
                }});
  cases.push_back(
      FieldCase{"SampleTime",
                [](DioPwlObfModel& m) { m.sample_time_s = 0.01; },
                [](const DioPwlObfModel&, const DioPwlObfModel& back) { EXPECT_EQ(back.sample_time_s, 0.01); },
                "",
                {},
                nullptr,
                {
                    {"a zero sample time", false, [](J& j) { j["sample_time_s"] = 0.0; }, "sample_time_s"},
                    {"a sample time that is text", false, [](J& j) { j["sample_time_s"] = "fast"; }, "sample_time_s"},
                }});

  cases.push_back(
      FieldCase{"UnitsAndAcceptedRange",
                [](DioPwlObfModel& m) {
                  m.input_unit = "kPa";
                  m.output_unit = "rad";
                  m.input_min = 0.0;
                  m.input_max = 300.0;
                },
                [](const DioPwlObfModel&, const DioPwlObfModel& back) {
                  EXPECT_EQ(back.input_unit, "kPa");
                  EXPECT_EQ(back.output_unit, "rad");
                  EXPECT_EQ(back.input_min, 0.0);
                  EXPECT_EQ(back.input_max, 300.0);
                },
                "",
                {},
                nullptr,
                {
                    {"a unit that is a number", false, [](J& j) { j["units"]["inputs"] = 1; }, "units"},
                    {"a range of one entry", false, [](J& j) { j["input_range"] = {0.0}; },
                     "'input_range' must have two entries"},
                    {"a range upside down", false,
                     [](J& j) {
                       j["input_range"] = {300.0, 0.0};
                     },
                     "input_min must be below input_max"},
                    // Found by a probe: each loaded, and validate scored it with exit 0
                    // (fits of -3.4e7) or ended in an error naming no file.
                    {"a threshold at the top of the range", false, [](J& j) { j["play_threshold"] = 300.0; },
                     "play_threshold 300.000000 is not below the top of input_range"},
                    {"a coupling over 1 across the range", false, [](J& j) { j["play_coupling"] = 0.01; },
                     "play_coupling times the input span above play_threshold is 3.000000, over 1"},
                    {"a softening that folds the level back", false, [](J& j) { j["play_softening"] = 0.002; },
                     "play_softening times the input span above play_threshold is 0.600000, over 0.5"},
                    {"a sample time of 1e300 s", false, [](J& j) { j["sample_time_s"] = 1e300; },
                     "m.json: sample_time_s 1e+300 is outside 1e-05 to 60 s"},
                    {"a sample time of 5e-324 s", false, [](J& j) { j["sample_time_s"] = 5e-324; },
                     "sample_time_s 4.94066e-324 is outside"},
                    {"the time as an output", false, [](J& j) { j["outputs"] = {"time_s"}; },
                     "'outputs' names 'time_s', the logs' time, not an input or output"},
                    {"the time as an input", false, [](J& j) { j["inputs"] = {"time_s"}; }, "'inputs' names 'time_s'"},
                }});

  cases.push_back(FieldCase{
      "InputRanges",
      [](DioPwlObfModel& m) {
        m.input_ranges = {{0.1, 0.9}};
      },
      [](const DioPwlObfModel& m, const DioPwlObfModel& back) { EXPECT_EQ(back.input_ranges, m.input_ranges); },
      "input_ranges",  // none: not written (files from before the field: the one input_range)
      {},
      nullptr,
      {
          {"a range of one entry", false, [](J& j) { j["input_ranges"][0] = {0.1}; }, "input_ranges"},
          {"a range upside down", false,
           [](J& j) {
             j["input_ranges"][0] = {0.9, 0.1};
           },
           "input_ranges"},
          {"two ranges for one input", false,
           [](J& j) {
             j["input_ranges"].push_back({0.1, 0.9});
           },
           "input_ranges"},
      }});

  // An input-side model: interpolated levels, a lag, and the output level it simulates from.
  cases.push_back(FieldCase{"InputSideLevelsAndOutputLevel",
                            [](DioPwlObfModel& m) {
                              m.partition = PwlPartition::interpolated({0}, {{0.2, 0.8}});
                              m.schedule_side = ScheduleSide::kInput;
                              m.schedule_lag_s = 0.3;
                              m.output_level = {1.5};
                            },
                            [](const DioPwlObfModel& m, const DioPwlObfModel& back) {
                              EXPECT_EQ(back.partition.scheduling(), Scheduling::kInterpolated);
                              EXPECT_EQ(back.partition.breakpoints(), m.partition.breakpoints());
                              EXPECT_EQ(back.schedule_side, ScheduleSide::kInput);
                              EXPECT_EQ(back.output_level, m.output_level);
                            },
                            "output_level",
                            {},
                            nullptr,
                            {
                                {"two levels for one output", false,
                                 [](J& j) {
                                   j["output_level"] = {1.0, 2.0};
                                 },
                                 "output_level"},
                                {"levels out of order", false,
                                 [](J& j) {
                                   j["partition"]["levels"][0] = {0.8, 0.2};
                                 },
                                 "must increase strictly"},
                                {"one input scheduled twice", false,
                                 [](J& j) {
                                   j["partition"]["inputs"] = {0, 0};
                                   j["partition"]["levels"] = {{0.2, 0.8}, {0.2, 0.8}};
                                 },
                                 "'partition.inputs' names input 0 twice"},
                                {"a switched partition on the input side", false,
                                 [](J& j) {
                                   j["partition"]["scheduling"] = "switched";
                                   j["partition"]["breakpoints"] = {{0.5}};
                                   j["partition"].erase("levels");
                                 },
                                 "interpolated partition"},
                            }});

  cases.push_back(FieldCase{
      "RegionFits",
      [](DioPwlObfModel& m) {
        m.region_fits[0].samples = 480;
        m.region_fits[1] = RegionFit{12, 0, "too few samples: region 0's coefficients"};
      },
      [](const DioPwlObfModel& m, const DioPwlObfModel& back) {
        ASSERT_EQ(back.region_fits.size(), 2u);
        EXPECT_EQ(back.region_fits[0].samples, 480);
        EXPECT_EQ(back.region_fits[1].samples, 12);
        EXPECT_EQ(back.region_fits[1].fallback_from, 0);
        EXPECT_EQ(back.region_fits[1].note, m.region_fits[1].note);
      },
      "",
      {},
      nullptr,
      {
          {"a fallback from -3", false, [](J& j) { j["regions"][1]["fallback_from"] = -3; },
           "regions[1].fallback_from"},
          {"a fallback from a region it does not have", false,
           [](J& j) { j["regions"][1]["fallback_from"] = static_cast<int>(j["regions"].size()); },
           "regions[1].fallback_from"},
          {"a fallback from itself", false, [](J& j) { j["regions"][1]["fallback_from"] = 1; },
           "'regions[1].fallback_from' names the region itself"},
          {"a negative sample count", false, [](J& j) { j["regions"][0]["samples"] = -1; }, "regions[0].samples"},
          {"a note that is a number", false, [](J& j) { j["regions"][0]["note"] = 5; }, "regions[0].note"},
      }});
  return cases;
}

class ModelFileField : public ::testing::TestWithParam<FieldCase> {};

}  // namespace

TEST_P(ModelFileField, RoundTripsAndIsChecked) {
  const FieldCase& c = GetParam();
  if (!c.omitted_when_unset.empty()) {
    EXPECT_EQ(nlohmann::json::parse(modelToJson(knownModel())).count(c.omitted_when_unset), 0u);
  }
  DioPwlObfModel m = knownModel();
  c.set(m);
  if (::testing::Test::HasFatalFailure()) return;
  c.expect_same(m, modelFromJson(modelToJson(m)));
  const nlohmann::json written = nlohmann::json::parse(modelToJson(m));
  nlohmann::json v1 = written;
  if (!c.old_file_lacks.empty()) {
    for (const std::string& key : c.old_file_lacks) v1.erase(key);
    v1["version"] = 1;
    c.expect_old_default(v1);
  }
  for (const BadValue& b : c.bad) {
    SCOPED_TRACE(b.what);
    ASSERT_TRUE(!b.on_old_file || !c.old_file_lacks.empty()) << "a bad value on an old file the case has not made";
    nlohmann::json j = b.on_old_file ? v1 : written;
    b.edit(j);
    expectThrowContaining([&] { modelFromJson(j.dump(), "m.json"); }, b.words);
  }
}

INSTANTIATE_TEST_SUITE_P(ModelFile, ModelFileField, ::testing::ValuesIn(fieldCases()),
                         [](const ::testing::TestParamInfo<FieldCase>& info) { return info.param.name; });

// The tip frame's own conditions, checked on the model (not its file).
TEST(ModelFile, OutputFrameTipCartesianNeedsTwoOutputsInDegreesOrRadians) {
  DioPwlObfModel m = knownModel();
  m.poles = {{PoleSet::real({0.9, 0.7})}, {PoleSet::real({0.8, 0.5})}};
  m.outputs = {"bend_deg", "steer_deg"};
  m.coefficients = {{Eigen::Vector2d(1, 2), Eigen::Vector2d(3, 4)}, {Eigen::Vector2d(-1, 0.5), Eigen::Vector2d(0, 1)}};
  m.output_frame = OutputFrame::kTipCartesian;
  EXPECT_NO_THROW(m.validate());
  m.output_unit = "rad";
  EXPECT_NO_THROW(m.validate());
  m.output_unit = "mm";
  try {
    m.validate();
    ADD_FAILURE() << "a tip frame in mm accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("deg or rad"), std::string::npos) << e.what();
  }
  DioPwlObfModel one_output = knownModel();
  one_output.output_frame = OutputFrame::kTipCartesian;
  EXPECT_THROW(one_output.validate(), std::invalid_argument);
}

// A number beyond double range is a parse error naming the file, not a raw
// json exception.
TEST(ModelFile, ANumberBeyondDoubleRangeIsNamed) {
  std::string text = modelToJson(knownModel());
  const std::string key = "\"sample_time_s\": ";
  const std::size_t at = text.find(key);
  ASSERT_NE(at, std::string::npos) << text;
  const std::size_t end = text.find_first_of(",\n}", at + key.size());
  text.replace(at + key.size(), end - at - key.size(), "1e400");
  expectThrowContaining([&] { modelFromJson(text, "m.json"); }, "m.json: not valid JSON");
  expectThrowContaining([&] { modelFromJson(text, "m.json"); }, "1e400");
}

// Objects and arrays cost about 40 times their text in memory: a document of
// more than kMaxJsonContainers is refused in the checking pass, before the
// document is built (64 MB of "{}" took 2.2 GB). A model-sized one is read.
TEST(ModelFile, ADocumentOfMillionsOfObjectsIsRefusedBeforeItIsBuilt) {
  std::string text = "[";
  for (long i = 0; i <= io::kMaxJsonContainers; ++i) text += i == 0 ? "{}" : ",{}";
  text += "]";
  expectThrowContaining([&] { modelFromJson(text, "m.json"); },
                        "m.json: more than 4000000 objects and arrays (is this the right file?)");
  text = "[";
  for (long i = 0; i + 2 < io::kMaxJsonContainers; ++i) text += i == 0 ? "{}" : ",{}";
  text += "]";  // within the limit: the check passes, the model reader names what is wrong
  expectThrowContaining([&] { modelFromJson(text, "m.json"); }, "m.json");
  try {
    modelFromJson(text, "m.json");
  } catch (const std::exception& e) {
    EXPECT_EQ(std::string(e.what()).find("objects and arrays"), std::string::npos) << e.what();
  }
}
