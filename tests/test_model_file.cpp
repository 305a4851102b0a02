// Model files: round trips of every field and a clear error for each bad one.
#include "support/identify_fixtures.hpp"

using namespace plsa;
using namespace plsa::test_fixtures;
using C = std::complex<double>;

TEST(ModelFile, RoundTripsAndNamesWhatIsWrong) {
  DioPwlObfModel m = knownModel();
  m.poles = {{PoleSet({C(0.9, 0), C(0.6, 0.2), C(0.6, -0.2)})}};
  m.coefficients = {{Eigen::Vector3d(1, 2, 3)}, {Eigen::Vector3d(-1, 0.5, 1.0 / 3.0)}};
  const DioPwlObfModel back = modelFromJson(modelToJson(m));
  EXPECT_EQ(back.coefficients[1][0], m.coefficients[1][0]);
  EXPECT_EQ(back.poles[0][0].poles(), m.poles[0][0].poles());
  EXPECT_EQ(back.partition.breakpoints(), m.partition.breakpoints());
  auto error = [&](auto edit) {
    nlohmann::json j = nlohmann::json::parse(modelToJson(m));
    edit(j);
    try {
      modelFromJson(j.dump(), "m.json");
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_NE(error([](auto& j) { j.erase("sample_time_s"); }).find("missing field 'sample_time_s'"), std::string::npos);
  EXPECT_NE(error([](auto& j) { j["version"] = 7; }).find("version 7 is newer than this build reads"), std::string::npos);
  EXPECT_NE(error([](auto& j) { j["version"] = 1.0; }).find("'version' must be an integer"), std::string::npos);
  EXPECT_NE(error([](auto& j) { j["extra"] = 1; }).find("unknown key 'extra'"), std::string::npos);
  EXPECT_NE(error([](auto& j) { j["regions"][0]["extra"] = 1; }).find("unknown key 'regions[0].extra'"),
            std::string::npos);
  EXPECT_NE(error([](auto& j) { j["outputs"].push_back(j["outputs"][0]); }).find("twice"), std::string::npos);
  EXPECT_NE(error([](auto& j) { j["input_range"][0] = nullptr; }).find("'input_range[0]' must be a number"),
            std::string::npos);
  EXPECT_NE(error([](auto& j) { j["input_range"][1] = "-inf"; }).find("'input_range[1]' must be a number or \"inf\""),
            std::string::npos);
  EXPECT_NE(error([](auto& j) { j["regions"][0]["samples"] = 1e300; }).find("'regions[0].samples' must be an integer"),
            std::string::npos);
  // Version 2 files carry every field: one left out is an error, not a default.
  EXPECT_NE(error([](auto& j) { j.erase("play_start"); }).find("missing field 'play_start'"), std::string::npos);
  EXPECT_NE(error([](auto& j) { j["regions"][1]["coefficients"][0].push_back(1.0); }).find("expected 3"), std::string::npos);
  EXPECT_NE(error([](auto& j) { j["poles"][0][0][0] = {1.5, 0.0}; }).find(">= 1"), std::string::npos);
  EXPECT_NE(error([](auto& j) { j["partition"]["scheduling"] = "fuzzy"; }).find("'switched' or 'interpolated'"), std::string::npos);
  EXPECT_NE(error([](auto& j) { j["regions"][0]["coefficients"][0][0] = "x"; }).find("must be a number"), std::string::npos);
  EXPECT_NE(error([](auto& j) { j["play_start"] = "middle"; }).find("'rising' or 'centred'"), std::string::npos);
  EXPECT_NE(error([](auto& j) { j["input_play"][0][0] = {{"width", 0.1}}; }).find("input_play[][].slope"),
            std::string::npos);
}

TEST(ModelFile, OutputFrameRoundTripsAndIsChecked) {
  DioPwlObfModel m = knownModel();
  m.poles = {{PoleSet::real({0.9, 0.7})}, {PoleSet::real({0.8, 0.5})}};
  m.outputs = {"bend_deg", "steer_deg"};
  m.coefficients = {{Eigen::Vector2d(1, 2), Eigen::Vector2d(3, 4)}, {Eigen::Vector2d(-1, 0.5), Eigen::Vector2d(0, 1)}};
  m.output_frame = OutputFrame::kTipCartesian;
  EXPECT_EQ(modelFromJson(modelToJson(m)).output_frame, OutputFrame::kTipCartesian);
  nlohmann::json j = nlohmann::json::parse(modelToJson(m));
  j.erase("output_frame");  // version 1 files from before the field: the logged frame
  j["version"] = 1;
  EXPECT_EQ(modelFromJson(j.dump()).output_frame, OutputFrame::kAsLogged);
  j["output_frame"] = "polar";
  try {
    modelFromJson(j.dump(), "m.json");
    ADD_FAILURE() << "unknown frame accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'output_frame' must be 'as_logged' or 'tip_cartesian'"), std::string::npos)
        << e.what();
  }
  m.output_unit = "rad";
  EXPECT_THROW(m.validate(), std::invalid_argument);
  DioPwlObfModel one_output = knownModel();
  one_output.output_frame = OutputFrame::kTipCartesian;
  EXPECT_THROW(one_output.validate(), std::invalid_argument);
}

TEST(ModelFile, PlayChannelsAndStartRoundTrip) {
  DioPwlObfModel m = knownModel();
  m.shaping.play = {{0.02, PlayChannel(0.0, 0.12)}};
  m.poles = {{PoleSet::real({0.9, 0.7})}};
  m.coefficients = {{Eigen::Vector4d(1, 2, 3, 4)}, {Eigen::Vector4d(-1, 0.5, 0.25, 2)}};
  const DioPwlObfModel back = modelFromJson(modelToJson(m));
  m.shaping.coupling = 0.75;
  const DioPwlObfModel coupled = modelFromJson(modelToJson(m));
  EXPECT_EQ(coupled.shaping.coupling, 0.75);
  EXPECT_EQ(back.shaping.play, m.shaping.play);
  EXPECT_EQ(back.shaping.start, PlayStart::kRising);
  // A file written before the fields existed keeps its centred, uncoupled channels.
  nlohmann::json j = nlohmann::json::parse(modelToJson(m));
  j.erase("play_start");
  j.erase("play_coupling");
  j["version"] = 1;
  EXPECT_EQ(modelFromJson(j.dump()).shaping.start, PlayStart::kCentred);
  EXPECT_EQ(modelFromJson(j.dump()).shaping.coupling, 0.0);
  j["play_coupling"] = -1.0;
  EXPECT_THROW(modelFromJson(j.dump()), std::invalid_argument);
}

TEST(ModelFile, PlayThresholdRoundTripsAndIsChecked) {
  DioPwlObfModel m = knownModel();
  m.shaping.threshold = 0.07;
  EXPECT_EQ(modelFromJson(modelToJson(m)).shaping.threshold, 0.07);
  nlohmann::json j = nlohmann::json::parse(modelToJson(m));
  j.erase("play_threshold");  // version 1, written before the field existed: counted from zero
  j["version"] = 1;
  EXPECT_EQ(modelFromJson(j.dump()).shaping.threshold, 0.0);
  j["play_threshold"] = -0.01;
  try {
    modelFromJson(j.dump());
    ADD_FAILURE() << "a negative threshold was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("play_threshold"), std::string::npos) << e.what();
  }
  j["play_threshold"] = "high";
  EXPECT_THROW(modelFromJson(j.dump()), std::invalid_argument);
}

TEST(ModelFile, PlaySofteningRoundTripsAndIsChecked) {
  DioPwlObfModel m = knownModel();
  m.shaping.softening = 0.8;
  EXPECT_EQ(modelFromJson(modelToJson(m)).shaping.softening, 0.8);
  nlohmann::json j = nlohmann::json::parse(modelToJson(m));
  j.erase("play_softening");  // version 1, written before the field existed: linear
  j["version"] = 1;
  EXPECT_EQ(modelFromJson(j.dump()).shaping.softening, 0.0);
  j["play_softening"] = -0.5;
  try {
    modelFromJson(j.dump());
    ADD_FAILURE() << "a negative softening was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("play_softening"), std::string::npos) << e.what();
  }
  j["play_softening"] = "soft";
  EXPECT_THROW(modelFromJson(j.dump()), std::invalid_argument);
}

TEST(ModelFile, TrainingDriftRoundTripsAndIsChecked) {
  DioPwlObfModel m = knownModel();
  ASSERT_EQ(m.outputCount(), 1);
  EXPECT_EQ(nlohmann::json::parse(modelToJson(m)).count("training_output_drift"), 0u);  // none: not written
  m.training_drift_per_s = {0.0244};
  m.training_drift_reference_s = 115.5;
  const DioPwlObfModel back = modelFromJson(modelToJson(m));
  EXPECT_EQ(back.training_drift_per_s, m.training_drift_per_s);
  EXPECT_EQ(back.training_drift_reference_s, 115.5);
  nlohmann::json j = nlohmann::json::parse(modelToJson(m));
  const auto rejected = [&](const std::string& what) {
    try {
      modelFromJson(j.dump());
      ADD_FAILURE() << "accepted: " << j["training_output_drift"].dump();
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  j["training_output_drift"]["rate_per_s"] = {0.01, 0.02};  // two rates, one output
  rejected("training_output_drift");
  j["training_output_drift"]["rate_per_s"] = {"fast"};
  rejected("training_output_drift.rate_per_s");
  j["training_output_drift"]["rate_per_s"] = {0.01};
  j["training_output_drift"].erase("reference_time_s");
  rejected("training_output_drift.reference_time_s");
}

TEST(ModelFile, ScheduleLagRoundTripsAndOldFilesHaveNone) {
  DioPwlObfModel m = knownModel();
  m.schedule_lag_s = 0.4;
  EXPECT_EQ(modelFromJson(modelToJson(m)).schedule_lag_s, 0.4);
  EXPECT_NEAR(m.schedulePole(), std::exp(-m.sample_time_s / 0.4), 1e-15);
  nlohmann::json j = nlohmann::json::parse(modelToJson(m));
  j.erase("schedule_lag_s");
  j.erase("schedule_side");
  j["version"] = 1;
  EXPECT_EQ(modelFromJson(j.dump()).schedule_lag_s, 0.0);
  EXPECT_EQ(modelFromJson(j.dump()).schedulePole(), 0.0);
  j["schedule_lag_s"] = -0.1;
  EXPECT_THROW(modelFromJson(j.dump()), std::invalid_argument);
  j["schedule_lag_s"] = "slow";
  EXPECT_THROW(modelFromJson(j.dump()), std::invalid_argument);
  j["schedule_lag_s"] = 0.4;
  EXPECT_EQ(modelFromJson(j.dump()).schedule_side, ScheduleSide::kOutput);  // files from before the field
  EXPECT_TRUE(modelFromJson(j.dump()).output_level.empty());
  j["output_level"] = {1.5};  // the level of an output-side model is no function of its inputs
  try {
    modelFromJson(j.dump());
    ADD_FAILURE() << "accepted output_level on an output-side model";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("output_level needs input-side"), std::string::npos) << e.what();
  }
  j["output_level"] = {"high"};
  EXPECT_THROW(modelFromJson(j.dump()), std::invalid_argument);
  j.erase("output_level");
  j["schedule_side"] = "sideways";
  try {
    modelFromJson(j.dump());
    ADD_FAILURE() << "accepted schedule_side 'sideways'";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'output' or 'input'"), std::string::npos) << e.what();
  }
  j["schedule_side"] = "input";  // needs an interpolated partition; this one is switched
  try {
    modelFromJson(j.dump());
    ADD_FAILURE() << "accepted an input-side switched partition";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("interpolated partition"), std::string::npos) << e.what();
  }
}
