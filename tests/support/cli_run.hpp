// The plsa tool run as a user runs it, for tests: PLSA_EXE names the
// binary; each test gets its own folder for files in and out.
#pragma once

#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace plsa::test {

namespace fs = std::filesystem;

class CliTest : public ::testing::Test {
 protected:
  void SetUp() override {
    exe_ = std::getenv("PLSA_EXE") ? std::getenv("PLSA_EXE") : "";
    ASSERT_TRUE(fs::exists(exe_)) << "PLSA_EXE does not name the plsa binary";
    dir_ = fs::temp_directory_path() / ("plsa_cli_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  // Runs plsa with args; returns the exit code, stderr in err_.
  int run(const std::string& args) {
    const std::string err = (dir_ / "stderr.txt").string();
    const int rc = std::system((exe_ + " " + args + " >" + (dir_ / "stdout.txt").string() + " 2>" + err).c_str());
    std::ifstream in(err);
    std::stringstream ss;
    ss << in.rdbuf();
    err_ = ss.str();
    return WEXITSTATUS(rc);
  }
  std::string file(const std::string& name) const { return (dir_ / name).string(); }
  static std::string slurp(const std::string& p) {
    std::ifstream in(p);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
  }
  std::string exe_, err_;
  fs::path dir_;
};

}  // namespace plsa::test
