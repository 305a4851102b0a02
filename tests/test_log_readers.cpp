// The log-format registry: a reader chosen by content, then by extension,
// then the fallback; formats this build cannot read refused by name.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <thread>

#include <sys/stat.h>

#include "plsa/io/log_readers.hpp"

namespace fs = std::filesystem;
using plsa::io::Log;
using plsa::io::LogFormat;
using plsa::io::LogReaderRegistry;
using plsa::io::OnDuplicate;
using plsa::io::ReadOptions;

namespace {

// A format whose reader only says which format it is.
LogFormat fakeFormat(const std::string& name, std::vector<std::string> extensions, std::string magic = "") {
  LogFormat f;
  f.name = name;
  f.description = "a " + name + " log";
  f.plural = name + " logs";
  f.extensions = std::move(extensions);
  f.magic = std::move(magic);
  f.read = [name](std::istream& in, const std::string& source, const ReadOptions&) {
    Log log;
    log.source = source;
    log.metadata["format"] = name;
    log.metadata["first_line"] = "";
    std::getline(in, log.metadata["first_line"]);  // the stream starts at the file's start
    return log;
  };
  return f;
}

std::string message(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "(no exception)";
}

class LogReadersTest : public ::testing::Test {
 protected:
  std::string write(const std::string& name, const std::string& bytes) {
    const fs::path path = dir_ / name;
    std::ofstream(path, std::ios::binary) << bytes;
    return path.string();
  }
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("plsa_log_readers_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
  const std::string csv_ = "# a log\ntime_s,x\n0,1\n0.1,2\n";
  const std::string lcm_sync_ = std::string("\xED\xA1\xDA\x01", 4);
};

}  // namespace

TEST_F(LogReadersTest, PicksTheReaderByExtension) {
  LogReaderRegistry r;
  r.add(plsa::io::csvLogFormat());
  r.add(fakeFormat("tsv", {".tsv", ".tab"}));
  EXPECT_EQ(r.read(write("a.tsv", "time_s\tx\n")).metadata.at("format"), "tsv");
  EXPECT_EQ(r.read(write("a.tab", "time_s\tx\n")).metadata.at("format"), "tsv");
  const Log csv = r.read(write("a.csv", csv_));
  EXPECT_EQ(csv.samples(), 2);
  EXPECT_EQ(csv.columns, (std::vector<std::string>{"time_s", "x"}));
  // Anything else goes to the fallback, CSV; the name alone is no extension.
  EXPECT_EQ(r.read(write("log.txt", csv_)).samples(), 2);
  EXPECT_EQ(r.read(write(".tsv", csv_)).samples(), 2);
  EXPECT_EQ(r.recognise("x/a.tsv", "")->name, "tsv");
  EXPECT_EQ(r.recognise("x.tsv/a", "")->name, "csv");
}

TEST_F(LogReadersTest, PicksTheReaderByContentWhateverTheName) {
  LogReaderRegistry r;
  r.add(plsa::io::csvLogFormat());
  r.add(fakeFormat("tsv", {".tsv"}));
  r.add(fakeFormat("bin", {".bin"}, "PLSA\x01"));
  // Known by the first bytes: no extension, or another format's.
  EXPECT_EQ(r.read(write("lcmlog-2026-11-25.00", "PLSA\x01 rest")).metadata.at("format"), "bin");
  EXPECT_EQ(r.read(write("b.tsv", "PLSA\x01 rest")).metadata.at("format"), "bin");
  // The reader sees the file from its first byte.
  EXPECT_EQ(r.read(write("c.bin", "PLSA\x01 first\nsecond\n")).metadata.at("first_line"), "PLSA\x01 first");
  // A format with magic bytes is not taken on its extension alone.
  EXPECT_EQ(r.read(write("d.bin", csv_)).samples(), 2);
  // A file shorter than the magic bytes is not it.
  EXPECT_EQ(r.recognise("e", "PLS")->name, "csv");
  // Streams too: the source names the file and its extension.
  std::istringstream in("PLSA\x01 x");
  EXPECT_EQ(r.read(in, "piped").metadata.at("format"), "bin");
  std::istringstream tsv("time_s\tx\n");
  EXPECT_EQ(r.read(tsv, "piped.tsv").metadata.at("format"), "tsv");
}

TEST_F(LogReadersTest, RefusesAnUnknownFormatNamingTheFileAndWhatItReads) {
  LogReaderRegistry r;  // no fallback: only what is recognised is read
  r.add(fakeFormat("tsv", {".tsv"}));
  r.add(fakeFormat("bin", {".bin"}, "PLSA\x01"));
  const std::string path = write("x.dat", csv_);
  const std::string what = message([&] { r.read(path); });
  EXPECT_EQ(what, path + ": not a log format this build knows; it reads: tsv, bin");
  EXPECT_THROW(r.read(path), std::invalid_argument);
}

// A device or a folder is no log: refused by name before a byte is read (a
// probe's read_log("/dev/zero") took a gigabyte, the pipe limit, first). A
// pipe is read whole, as before.
TEST_F(LogReadersTest, ADeviceOrAFolderIsRefusedBeforeItIsRead) {
  LogReaderRegistry r;
  r.add(fakeFormat("tsv", {".tsv"}));
  EXPECT_EQ(message([&] { r.read("/dev/zero"); }), "/dev/zero: not a log file (a folder, a device or a socket)");
  const std::string folder = (dir_ / "folder.tsv").string();
  fs::create_directories(folder);
  EXPECT_EQ(message([&] { r.read(folder); }), folder + ": not a log file (a folder, a device or a socket)");
  const std::string fifo = (dir_ / "pipe.tsv").string();
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  std::thread writer([&] { std::ofstream(fifo) << "time_s\tx\n"; });
  EXPECT_EQ(r.read(fifo).metadata.at("format"), "tsv");
  writer.join();
}

TEST_F(LogReadersTest, ABuildWithoutTheLcmCodecNamesAnLcmLogItCannotRead) {
  // test_io links plsa_io alone: the tools' registry has CSV and the LCM placeholder.
  LogReaderRegistry r;
  r.add(plsa::io::csvLogFormat());
  r.add(plsa::io::lcmLogPlaceholder());
  EXPECT_EQ(r.readable(), std::vector<std::string>{"csv"});
  EXPECT_EQ(r.writable(), std::vector<std::string>{"csv"});
  EXPECT_EQ(r.names(), (std::vector<std::string>{"csv", "lcm"}));
  const std::string path = write("x.lcmlog", lcm_sync_ + "events");
  EXPECT_EQ(message([&] { r.read(path); }),
            path + ": an LCM event log, which this build cannot read (built without LCM); it reads: csv");
  // lcm-logger's names have no extension: the sync word tells.
  const std::string bare = write("lcmlog-2026-11-25.00", lcm_sync_ + "events");
  EXPECT_EQ(message([&] { r.read(bare); }),
            bare + ": an LCM event log, which this build cannot read (built without LCM); it reads: csv");
  const std::string out = (dir_ / "y.lcmlog").string();
  EXPECT_EQ(message([&] { r.write(out, Log{}); }),
            out + ": an LCM event log, which this build cannot write (built without LCM); it writes: csv");
  EXPECT_FALSE(fs::exists(out));

  Log log = r.read(write("a.csv", csv_));
  const std::string copy = (dir_ / "copy.txt").string();  // any other name is written as CSV
  r.write(copy, log);
  EXPECT_EQ(plsa::io::readCsvLog(copy).data, log.data);
}

TEST_F(LogReadersTest, TheToolsRegistryStartsWithCsvAndKnowsLcmLogsByContent) {
  LogReaderRegistry& r = plsa::io::logReaders();
  ASSERT_NE(r.find("csv"), nullptr);
  ASSERT_NE(r.find("lcm"), nullptr);
  EXPECT_TRUE(r.find("csv")->fallback);
  EXPECT_EQ(r.logFileKinds(), "(.csv, .lcmlog, or LCM event logs by content)");
  EXPECT_TRUE(r.looksLikeLog(write("a.csv", csv_)));
  EXPECT_TRUE(r.looksLikeLog(write("b.lcmlog", "")));
  EXPECT_TRUE(r.looksLikeLog(write("lcmlog-2026-11-25.00", lcm_sync_)));
  EXPECT_FALSE(r.looksLikeLog(write("notes.txt", "hello")));
  EXPECT_FALSE(r.looksLikeLog(write(".csv", csv_)));
  EXPECT_EQ(plsa::io::readLog(write("c.csv", csv_)).samples(), 2);
  const std::string missing = (dir_ / "missing.csv").string();
  EXPECT_EQ(message([&] { plsa::io::readLog(missing); }), missing + ": cannot open the log");
}

// A text format without magic bytes is known by a test of its first bytes:
// after every format's magic, before the extensions, and in a folder scan.
TEST_F(LogReadersTest, ASniffedFormatIsKnownByContentBeforeExtensions) {
  LogReaderRegistry r;
  r.add(plsa::io::csvLogFormat());
  r.add(fakeFormat("bin", {".bin"}, "BIN1"));
  LogFormat sniffed = fakeFormat("bus", {".bus"});
  std::string seen;
  sniffed.sniff = [&seen](const std::string& head) {
    seen = head;
    return head.rfind("(1.0) can0", 0) == 0;
  };
  r.add(std::move(sniffed));
  EXPECT_EQ(r.logFileKinds(), "(.csv, .bin, .bus, bin logs by content, or bus logs by content)");
  const std::string bus = "(1.0) can0 123#00\n" + std::string(400, 'x');
  EXPECT_EQ(r.read(write("candump.log", bus)).metadata.at("format"), "bus");
  EXPECT_EQ(seen.size(), plsa::io::kSniffBytes);                                  // the head it saw, no more
  EXPECT_EQ(r.read(write("named.csv", bus)).metadata.at("format"), "bus");        // content first
  EXPECT_EQ(r.read(write("magic.bus", "BIN1...")).metadata.at("format"), "bin");  // magic before sniff
  EXPECT_TRUE(r.looksLikeLog(write("bus-2026.log", bus)));
  EXPECT_FALSE(r.looksLikeLog(write("notes.log", "(2.0) can1 hello")));
}

TEST_F(LogReadersTest, ASecondRegistrationIsRefusedOrReplacesInPlace) {
  LogReaderRegistry r;
  EXPECT_FALSE(r.add(plsa::io::csvLogFormat()));
  EXPECT_FALSE(r.add(fakeFormat("tsv", {".tsv"})));
  EXPECT_EQ(message([&] { r.add(fakeFormat("csv", {".csv"})); }),
            "log formats: 'csv' is already registered (as a CSV log)");
  EXPECT_THROW(r.add(fakeFormat("csv", {".csv"}), OnDuplicate::Refuse), std::invalid_argument);
  EXPECT_EQ(r.read(write("a.csv", csv_)).samples(), 2);  // the first one stands

  // Replaced: the new one reads, in the old one's place; the old one, held, is unchanged.
  const auto old_csv = r.find("csv");
  LogFormat replacement = fakeFormat("csv", {".csv"});
  replacement.fallback = true;
  EXPECT_TRUE(r.add(replacement, OnDuplicate::Replace));
  EXPECT_TRUE(r.add(replacement, OnDuplicate::Replace));  // again: the same registry
  EXPECT_EQ(r.names(), (std::vector<std::string>{"csv", "tsv"}));
  EXPECT_EQ(r.read(write("b.csv", csv_)).metadata.at("format"), "csv");
  EXPECT_EQ(r.read(write("b.dat", csv_)).metadata.at("format"), "csv");
  EXPECT_EQ(old_csv->description, "a CSV log");

  // One fallback at most; a format needs a name.
  LogFormat second = fakeFormat("any", {});
  second.fallback = true;
  EXPECT_EQ(message([&] { r.add(second); }), "log formats: 'any' cannot also read unrecognised files: 'csv' does");
  EXPECT_THROW(r.add(fakeFormat("", {".x"})), std::invalid_argument);
  EXPECT_EQ(r.names(), (std::vector<std::string>{"csv", "tsv"}));
}
