#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "plsa/io/csv_log.hpp"

namespace fs = std::filesystem;

namespace {

class CsvLogTest : public ::testing::Test {
 protected:
  std::string write(const std::string& text) {
    const std::string path = (fs::temp_directory_path() /
                              ("plsa_csv_" + std::to_string(::getpid()) + "_" + std::to_string(counter_++) + ".csv"))
                                 .string();
    std::ofstream(path) << text;
    files_.push_back(path);
    return path;
  }
  void expectError(const std::string& text, const std::string& needle) {
    const std::string path = write(text);
    try {
      plsa::io::readCsvLog(path);
      FAIL() << "accepted a malformed file; expected: " << needle;
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    }
  }
  void TearDown() override {
    for (const auto& f : files_) fs::remove(f);
  }
  std::vector<std::string> files_;
  int counter_ = 0;
};

}  // namespace

TEST_F(CsvLogTest, ReadsMetadataHeaderAndRows) {
  const auto path = write(
      "# sample_rate_hz: 80\n# measured on a test rig\ntime_s,cmd_1,bend_deg\n"
      "0.0,0.1,1.5\n0.0125,0.2,2.5\n");
  const auto log = plsa::io::readCsvLog(path);
  EXPECT_EQ(log.samples(), 2);
  EXPECT_EQ(log.metadata.at("sample_rate_hz"), "80");
  ASSERT_EQ(log.comments.size(), 1u);
  EXPECT_DOUBLE_EQ(log.column("bend_deg")(1), 2.5);
  EXPECT_EQ(log.columnsOf({"bend_deg", "cmd_1"})(0, 1), 0.1);
}

// A declared sample rate the time column contradicts is warned of (a probe:
// '# sample_rate_hz: 100' over an 80 Hz time column was read without a
// word); one that agrees, or is no number, says nothing.
TEST_F(CsvLogTest, ADeclaredRateTheTimeColumnContradictsIsWarnedOf) {
  std::string rows = "time_s,y\n";
  for (int k = 0; k < 20; ++k) rows += std::to_string(k * 0.0125) + ",1\n";
  const auto wrong = plsa::io::readCsvLog(write("# sample_rate_hz: 100\n" + rows));
  ASSERT_EQ(wrong.warnings.size(), 1u);
  EXPECT_NE(wrong.warnings[0].find("its '# sample_rate_hz: 100' disagrees with its time column, which steps at 80 Hz"),
            std::string::npos)
      << wrong.warnings[0];
  EXPECT_TRUE(plsa::io::readCsvLog(write("# sample_rate_hz: 80\n" + rows)).warnings.empty());
  EXPECT_TRUE(plsa::io::readCsvLog(write("# sample_rate_hz: about 80\n" + rows)).warnings.empty());
}

// Found by a probe: 40 million '#' lines (80 MB) took 2.5 GB, every comment kept.
TEST_F(CsvLogTest, KeepsAThousandCommentLinesAndCountsTheRest) {
  std::string text;
  for (int i = 0; i < 5000; ++i) text += "# comment " + std::to_string(i) + "\n# key" + std::to_string(i) + ": v\n";
  const auto log = plsa::io::readCsvLog(write(text + "# key3: later\ntime_s,y\n0,1\n0.1,2\n"));
  EXPECT_EQ(log.comments.size(), plsa::io::kKeptCommentLines);
  EXPECT_EQ(log.metadata.size(), plsa::io::kKeptCommentLines);
  EXPECT_EQ(log.metadata.at("key3"), "later");  // a key kept takes its later value
  EXPECT_EQ(log.comments.back(), "comment 999");
  ASSERT_EQ(log.warnings.size(), 1u);
  EXPECT_NE(log.warnings[0].find("8000 '#' lines past the first 1000"), std::string::npos) << log.warnings[0];
  EXPECT_EQ(log.samples(), 2);
}

TEST_F(CsvLogTest, RoundTripsExactly) {
  plsa::io::Log log;
  log.columns = {"time_s", "y"};
  log.data.resize(3, 2);
  log.data << 0.0, 1.0 / 3.0, 0.1, 2.0 / 7.0, 0.2, -1e-300;
  log.metadata["units"] = "s, deg";
  const auto path = write("");
  plsa::io::writeCsvLog(path, log);
  const auto back = plsa::io::readCsvLog(path);
  EXPECT_EQ(back.data, log.data);
  EXPECT_EQ(back.metadata.at("units"), "s, deg");
}

TEST_F(CsvLogTest, RejectsMalformedFilesWithLineAndReason) {
  expectError("time_s,y\n0,1\n0.1,2,3\n", ":3: row has 3 fields, header has 2");
  expectError("time_s,y\n0,1\n0.1,abc\n", ":3: column 'y': 'abc' is not a number");
  expectError("time_s,y\n0,1\n0.1,nan\n", ":3: column 'y': value 'nan' is not finite");
  expectError("time_s,y\n0,1\n0.1,\n", ":3: column 'y': '' is not a number");
  expectError("time_s,y\n0,1\n0.1,0x10\n", ":3: column 'y': '0x10' is not a decimal number");
  expectError("time_s,y\n0,1\n0.1,-0X1p3\n", ":3: column 'y': '-0X1p3' is not a decimal number");
  expectError("time_s,y\n0,1\n0.2,1\n0.1,1\n", ":4: time 0.1 is not after");
  expectError("time_s,y\n0,1\n0,1\n", ":3: time 0 is not after");
  expectError("time_s,y,y\n0,1,1\n", ":1: header names column 'y' twice");
  expectError("time_s,y\x01z\n0,1\n", ":1: header column 2 has the control character U+0001 at byte 1 of its name");
  expectError("time_s,y\x7f\n0,1\n", ":1: header column 2 has the control character U+007F at byte 1");
  // Found by a probe: a name outside UTF-8 was read, and failed only in the model's JSON after the whole fit.
  expectError("time_s,y\xffz\n0,1\n", ":1: header column 2 is not UTF-8 text at byte 1 of its name");
  expectError("time_s,y\xc2\x85\n0,1\n", ":1: header column 2 is not UTF-8 text at byte 1");        // C1 control U+0085
  expectError("time_s,y\xe2\x82\n0,1\n", ":1: header column 2 is not UTF-8 text at byte 1");        // cut sequence
  EXPECT_EQ(plsa::io::readCsvLog(write("time_s,\xce\xb8_deg\n0,1\n")).columns[1], "\xce\xb8_deg");  // theta reads
  // A 100 kB cell is quoted by its first 40 bytes and its size, not echoed whole.
  expectError("time_s,y\n0," + std::string(100000, '7') + "x\n",
              "'7777777777777777777777777777777777777777...' (100001 bytes) is not a number");
  expectError("# only a comment\n", "no header line");
  expectError("time_s,y\n", "no data rows");
}

// What a spreadsheet, an interrupted recorder or a wrong path hands the reader.
TEST_F(CsvLogTest, ByteOrderMarkCutLastLineBinaryAndEndlessLines) {
  // A UTF-8 BOM once hid the time column, and with it every time check.
  const auto bom = write("\xEF\xBB\xBFtime_s,y\n0,1\n0.1,2\n");
  const auto log = plsa::io::readCsvLog(bom);
  EXPECT_EQ(log.columns.front(), "time_s");
  expectError("\xEF\xBB\xBFtime_s,y\n0.2,1\n0.1,2\n", ":3: time 0.1 is not after");
  // A last line without its newline may be cut inside its last field: read, and said.
  const auto cut = write("time_s,y\n0,1\n0.1,2.7");
  const auto partial = plsa::io::readCsvLog(cut);
  EXPECT_EQ(partial.samples(), 2);
  ASSERT_EQ(partial.warnings.size(), 1u);
  EXPECT_NE(partial.warnings[0].find(cut + ":3: the file ends without a newline"), std::string::npos)
      << partial.warnings[0];
  EXPECT_TRUE(plsa::io::readCsvLog(write("time_s,y\n0,1\n")).warnings.empty());
  expectError(std::string("time_s,y\n0,\0\n", 12), ":2: NUL byte");
  // Lines ended by CR alone read as one line: said, not "no header line".
  expectError("time_s,y\r0,1\r0.1,2\r", ":1: a carriage return inside the line: lines end in CR alone");
  EXPECT_EQ(plsa::io::readCsvLog(write("time_s,y\r\n0,1\r\n0.1,2\r\n")).samples(), 2);  // CR LF is fine
  // Quoted header names (spreadsheets, pandas) read as the names; a missing one lists those there are.
  plsa::io::CsvReadOptions needs_u;
  needs_u.required = {"u"};
  EXPECT_EQ(plsa::io::readCsvLog(write("\"time_s\",\"u\"\n0,1\n0.1,2\n"), needs_u).columns[1], "u");
  try {
    plsa::io::readCsvLog(write("time_s,y\n0,1\n"), needs_u);
    ADD_FAILURE() << "a missing column was accepted";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("header has no column 'u' (it has: time_s, y)"), std::string::npos)
        << e.what();
  }
  expectError("time_s,y\n" + std::string(plsa::io::kMaxCsvLineBytes + 10, '1'), ":2: line longer than 1 MiB");
  // A header of 100000 names (under the 1 MiB line limit) reads, and a
  // message about it lists a few hundred characters of them, not all.
  std::string header = "time_s", row = "0";
  for (int i = 0; i < 100000; ++i) header += ",c" + std::to_string(i), row += ",0";
  const plsa::io::Log wide = plsa::io::readCsvLog(write(header + "\n" + row + "\n"));
  EXPECT_EQ(wide.columns.size(), 100001u);
  try {
    plsa::io::readCsvLog(write(header + "\n" + row + "\n"), needs_u);
    ADD_FAILURE() << "a missing column was accepted";
  } catch (const std::exception& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("(it has: time_s, c0, c1, "), std::string::npos) << what.substr(0, 400);
    EXPECT_NE(what.find(", ... (100001 columns))"), std::string::npos) << what.substr(0, 400);
    EXPECT_LT(what.size(), 500u);
  }
  expectError("time_s,y,y\n0,1,2\n", "header names column 'y' twice");
}

TEST_F(CsvLogTest, WritesAtomicallyAndLeavesNoTemporaryFile) {
  const auto path = write("old contents\n");
  const auto before = fs::status(path).permissions();
  plsa::io::Log log;
  log.columns = {"time_s", "y"};
  log.data = Eigen::MatrixXd::Ones(2, 2);
  log.data(1, 0) = 2;
  plsa::io::writeCsvLog(path, log);
  EXPECT_EQ(plsa::io::readCsvLog(path).data, log.data);
  EXPECT_EQ(fs::status(path).permissions(), before);
  for (const auto& e : fs::directory_iterator(fs::path(path).parent_path()))
    EXPECT_EQ(e.path().filename().string().find("." + fs::path(path).filename().string() + ".tmp"), std::string::npos)
        << "left behind: " << e.path();
  // A folder that does not exist: an error naming the file, and nothing written.
  try {
    plsa::io::writeCsvLog("/nonexistent-plsa-dir/x.csv", log);
    FAIL() << "wrote into a folder that does not exist";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent-plsa-dir/x.csv: cannot write the log"), std::string::npos)
        << e.what();
  }
}

TEST_F(CsvLogTest, RequiredColumnsAreChecked) {
  const auto path = write("time_s,u_1\n0,1\n");
  plsa::io::CsvReadOptions opt;
  opt.required = {"u_1", "y_1"};
  try {
    plsa::io::readCsvLog(path, opt);
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("no column 'y_1'"), std::string::npos) << e.what();
  }
  const auto log = plsa::io::readCsvLog(path);
  EXPECT_THROW(log.column("y_1"), std::invalid_argument);
}

TEST_F(CsvLogTest, MissingFileIsAClearError) {
  EXPECT_THROW(plsa::io::readCsvLog("/nonexistent/plsa.csv"), std::runtime_error);
}

TEST_F(CsvLogTest, SampleTimeAndGaps) {
  const auto ok = plsa::io::readCsvLog(write("time_s,y\n0,1\n0.0125,1\n0.025,1\n0.0375,2\n"));
  EXPECT_NEAR(plsa::io::checkedSampleTime(ok), 0.0125, 1e-15);
  const auto gap = plsa::io::readCsvLog(write("time_s,y\n0,1\n0.0125,1\n0.025,1\n0.5,2\n0.5125,1\n"));
  try {
    plsa::io::checkedSampleTime(gap);
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("time gap"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("row 4"), std::string::npos) << e.what();
  }
  // Found by a probe: every other sample dropped in a log's second half (a
  // second rate) passed as 80 Hz; so did a time column scaled by 1e250.
  auto refusal = [&](const std::string& text) -> std::string {
    try {
      plsa::io::checkedSampleTime(plsa::io::readCsvLog(write(text)), "time_s", plsa::io::kToleratedGapFactor);
    } catch (const std::runtime_error& e) {
      return e.what();
    }
    return "accepted";
  };
  std::string two_rates = "time_s,y\n", dropouts = "time_s,y\n";
  for (int k = 0; k < 400; ++k) two_rates += std::to_string(k < 200 ? 0.0125 * k : 2.5 + 0.025 * (k - 200)) + ",1\n";
  for (int k = 0; k < 400; ++k)
    dropouts += std::to_string(0.0125 * (k + (k > 100 ? 1 : 0) + (k > 300 ? 1 : 0))) + ",1\n";
  EXPECT_NE(refusal(two_rates).find("199 of 399 sample intervals (the first before data row 202) are over 1.5 times"),
            std::string::npos)
      << refusal(two_rates);
  EXPECT_EQ(refusal(dropouts), "accepted");  // two dropped samples: a hiccup, as the real arm's logs have
  EXPECT_NE(refusal("time_s,y\n0,1\n1e248,1\n2e248,1\n")
                .find("median sample time 1e+248 s of column 'time_s' is "
                      "outside 1e-05 to 60 s"),
            std::string::npos);
  EXPECT_NE(refusal("time_s,y\n0,1\n1e-9,1\n2e-9,1\n").find("is outside"), std::string::npos);
}

TEST(RealData, Bruder2021TrialsParse) {
  const char* shared = std::getenv("PLSA_SHARED_DATA_DIR");
  if (shared == nullptr) GTEST_SKIP() << "PLSA_SHARED_DATA_DIR is not set (ctest sets it)";
  const std::string dir = std::string(shared) + "/softarm-bruder2021";
  if (!fs::exists(dir)) GTEST_SKIP() << "shared data not found at " << dir;
  plsa::io::CsvReadOptions opt;
  opt.required = {"u_1", "u_2", "u_3", "y_1", "y_2"};
  const auto clean = plsa::io::readCsvLog(dir + "/trial-01.csv", opt);
  EXPECT_GT(clean.samples(), 3000);
  EXPECT_NEAR(plsa::io::checkedSampleTime(clean), 0.083, 0.002);
  // trial-00 lost a sample: the gap check must name where.
  const auto gappy = plsa::io::readCsvLog(dir + "/trial-00.csv", opt);
  try {
    plsa::io::checkedSampleTime(gappy);
    FAIL() << "missed the dropped sample in trial-00";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("before data row 1807"), std::string::npos) << e.what();
  }
}
