// The structure search on a sample of long logs (search_sample.hpp): where
// the windows fall, and that the chosen structure is still fitted on every
// sample; and the pole method the search keeps (pole_selection.cpp).
#include "plsa/identify/search_sample.hpp"
#include "support/identify_fixtures.hpp"

using namespace plsa;
using namespace plsa::identify;
using namespace plsa::test_fixtures;

namespace {

IdentifyOptions quickInputSide() {
  IdentifyOptions o;
  o.scheduling = SchedulingChoice::kInputSide;
  o.play_candidates = {{0.0}, {0.1}};
  o.play_coupling_candidates = {};
  o.schedule_lag_candidates = {};
  o.play_threshold_candidates = {};
  o.slow_pole_candidates = {};
  o.play_refine_evaluations = 0;
  return o;
}

void expectWindow(const SearchWindow& w, std::size_t log, Eigen::Index begin, Eigen::Index length) {
  EXPECT_EQ(w.log, log);
  EXPECT_EQ(w.begin, begin);
  EXPECT_EQ(w.length, length);
}

}  // namespace

TEST(SearchSample, WindowsSpreadOverLongLogsWithinTheBudget) {
  // Within the budget (or none): every log whole.
  std::vector<SearchWindow> w = searchWindows({300, 200}, 500, 100);
  ASSERT_EQ(w.size(), 2u);
  expectWindow(w[0], 0, 0, 300);
  expectWindow(w[1], 1, 0, 200);
  EXPECT_EQ(searchWindows({300, 200}, 0, 100).size(), 2u);
  // One long log: four windows centred at 1/8, 3/8, 5/8 and 7/8 of it.
  w = searchWindows({100000}, 32000, 8000);
  ASSERT_EQ(w.size(), 4u);
  for (std::size_t j = 0; j < 4; ++j) expectWindow(w[j], 0, 12500 + 25000 * static_cast<Eigen::Index>(j) - 4000, 8000);
  // Short logs: a window moves inside the log its centre falls in; a log no
  // longer than a window is taken whole.
  w = searchWindows({3000, 3000, 3000, 3000, 3000, 3000, 3000, 3000, 3000, 3000}, 12000, 2000);
  ASSERT_EQ(w.size(), 6u);
  const std::array<std::size_t, 6> logs{0, 2, 4, 5, 7, 9};
  const std::array<Eigen::Index, 6> begins{1000, 500, 0, 1000, 500, 0};
  for (std::size_t j = 0; j < 6; ++j) expectWindow(w[j], logs[j], begins[j], 2000);
  w = searchWindows({1000, 1000}, 1500, 10000);
  ASSERT_EQ(w.size(), 1u);
  expectWindow(w[0], 1, 0, 1000);
  // Two windows pushed against a log's end overlap: merged, within the budget.
  w = searchWindows({50, 10}, 50, 20);
  ASSERT_EQ(w.size(), 1u);
  expectWindow(w[0], 0, 3, 47);
  expectThrowContaining([] { searchWindows({100}, 50, 0); }, "at least one row");
  expectThrowContaining([] { searchWindows({100, -1}, 50, 10); }, "negative");
}

// A search on windows chooses a structure; the model returned is that
// structure fitted on every sample, not on the windows.
TEST(SearchSample, TheChosenStructureIsFittedOnEverySample) {
  const io::Log train = yawDriftRuns(0.0).train;  // no effect on
  IdentifyOptions o = quickInputSide();
  o.output_drift = OutputDriftChoice::kOff;
  o.search_max_samples = 6000;
  o.search_window_s = 25.0;  // 2000 rows at 80 Hz: three windows
  IdentifyReport rep;
  const DioPwlObfModel m = identifyModel({train}, o, &rep);
  const Eigen::MatrixXd U = train.columnsOf(o.inputs), Y = train.columnsOf(o.outputs);
  ASSERT_GT(U.rows(), 2 * o.search_max_samples);
  EXPECT_EQ(rep.search_samples, 6000);
  EXPECT_TRUE(std::any_of(rep.lines.begin(), rep.lines.end(), [](const std::string& l) {
    return l.find("structure search on 75 s of the") != std::string::npos && l.find("3 windows") != std::string::npos;
  }));
  DioPwlObfModel all = m, windows = m;
  fitCoefficients(all, {U}, {Y}, o.coefficients);
  fitOutputLevel(all, {U}, {Y});
  for (int out = 0; out < m.outputCount(); ++out)
    EXPECT_EQ(m.stackedCoefficients(out), all.stackedCoefficients(out)) << out;
  EXPECT_EQ(m.output_level, all.output_level);
  // The windows alone would have given other coefficients.
  std::vector<Eigen::MatrixXd> WU, WY;
  for (const SearchWindow& s : searchWindows({U.rows()}, o.search_max_samples, 2000)) {
    WU.push_back(U.middleRows(s.begin, s.length));
    WY.push_back(Y.middleRows(s.begin, s.length));
  }
  fitCoefficients(windows, WU, WY, o.coefficients);
  EXPECT_NE(m.stackedCoefficients(0), windows.stackedCoefficients(0));
  IdentifyOptions bad = o;
  bad.search_window_s = 0.0;
  expectThrowContaining([&] { identifyModel({train}, bad); }, "the search's windows must last");
  bad = o;
  bad.search_max_samples = -1;
  expectThrowContaining([&] { identifyModel({train}, bad); }, "sample size must be >= 0");
  bad = o;
  bad.search_max_samples = 1500;  // under one 25 s window: windows of warm-up, scored on nothing
  expectThrowContaining([&] { identifyModel({train}, bad); },
                        "--search-samples 1500 (18.75 s) is under one search window (25 s, whose first 10 s are not "
                        "scored): give at least 2000, or 0");
  bad = o;
  bad.cv_chunk_s = 1e18;  // rounded to whole samples this overflowed, and chunks of one sample were scored
  expectThrowContaining([&] { identifyModel({train}, bad); },
                        "--cv-chunk 1e+18 s puts every sample in one cross-validation fold");
  bad.cv_chunk_s = 25.0;  // one chunk per 25 s window: fold 0 holds everything
  expectThrowContaining([&] { identifyModel({train}, bad); }, "lasts 25 s; give a chunk under that");
  bad.cv_chunk_s = 0.001;  // found by a probe: one-sample chunks were scored (the folds leak), 15x slower
  expectThrowContaining([&] { identifyModel({train}, bad); },
                        "--cv-chunk 0.001 s is 1 sample(s) at 0.0125 s; give at least 0.2 s (16 samples)");
  bad.cv_chunk_s = 20.0;  // two chunks per window: the third fold is empty and left out of the scores
  EXPECT_NO_THROW(identifyModel({train}, bad));
  bad = o;
  bad.play_candidates = {{}, {0.1}};  // refused before any stage scores with it
  expectThrowContaining([&] { identifyModel({train}, bad); }, "a play channel set is empty");
  // No budget: the search runs on every sample and says nothing about windows.
  o.search_max_samples = 0;
  IdentifyReport whole;
  identifyModel({train}, o, &whole);
  EXPECT_EQ(whole.search_samples, U.rows());
  EXPECT_TRUE(std::none_of(whole.lines.begin(), whole.lines.end(),
                           [](const std::string& l) { return l.find("structure search on") != std::string::npos; }));
}

// pole_method "auto": on a joystick run (local windows: hundreds of local
// poles) fuzzy c-means' basis scores higher held out and is kept; on a
// staircase both methods find nearly the same poles, and the tie keeps the
// paper's FKcM, the model identical to asking for FKcM.
TEST(PoleMethod, AutoKeepsTheBasisThatScoresHigherHeldOut) {
  sim::ExperimentOptions eo;
  eo.seed = 9;
  eo.joystick_duration_s = 180;
  sim::Actuator a(sim::SimConfig{}, 9);
  const io::Log joystick = sim::runExperiment(a, sim::joystickExperiment(eo));
  IdentifyOptions o = quickInputSide();
  IdentifyReport rep;
  const DioPwlObfModel m = identifyModel({joystick}, o, &rep);
  // A joystick run has no steps: its windows' second-order poles are
  // candidates too, and lose here.
  ASSERT_EQ(rep.pole_method_scores.size(), 4u);
  EXPECT_EQ(rep.pole_method_scores[0].method, "fkcm");
  EXPECT_EQ(rep.pole_method_scores[1].method, "fcm");
  EXPECT_EQ(rep.pole_method_scores[2].method, "fkcm+order2");
  EXPECT_EQ(rep.pole_method_scores[3].method, "fcm+order2");
  const auto mean = [](const PoleMethodScore& s) { return 0.5 * (s.step_ahead + s.simulation); };
  for (std::size_t i : {0u, 2u, 3u})
    EXPECT_GT(mean(rep.pole_method_scores[1]), mean(rep.pole_method_scores[i]) + 0.1) << i;
  EXPECT_EQ(rep.pairs[0].chosen.method, "fuzzy c-means");
  o.pole_method = PoleMethod::kFuzzyCMeans;
  const DioPwlObfModel fcm = identifyModel({joystick}, o);
  EXPECT_EQ(m.stackedCoefficients(0), fcm.stackedCoefficients(0));
  EXPECT_TRUE(rep.used_windows);

  const io::Log staircase = yawDriftRuns(0.0).train;
  o.pole_method = PoleMethod::kAuto;
  IdentifyReport tie;
  const DioPwlObfModel m_auto = identifyModel({staircase}, o, &tie);
  ASSERT_EQ(tie.pole_method_scores.size(), 2u);
  EXPECT_NEAR(tie.pole_method_scores[0].step_ahead, tie.pole_method_scores[1].step_ahead, 0.1);
  EXPECT_EQ(tie.pairs[0].chosen.method.rfind("FKcM", 0), 0u) << tie.pairs[0].chosen.method;
  o.pole_method = PoleMethod::kFkcm;
  IdentifyReport paper;
  const DioPwlObfModel m_fkcm = identifyModel({staircase}, o, &paper);
  EXPECT_TRUE(paper.pole_method_scores.empty());
  for (int out = 0; out < m_auto.outputCount(); ++out)
    EXPECT_EQ(m_auto.stackedCoefficients(out), m_fkcm.stackedCoefficients(out));
  EXPECT_EQ(parseOption<PoleMethod>("auto"), PoleMethod::kAuto);
}
