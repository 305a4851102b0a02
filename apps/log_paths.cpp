#include "log_paths.hpp"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <stdexcept>

namespace fs = std::filesystem;

namespace plsa::app {

namespace {

// lcm-logger names its files lcmlog-YYYY-MM-DD.NN: a log is known by its first word.
bool startsWithLcmSyncWord(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  unsigned char head[4] = {};
  return in.read(reinterpret_cast<char*>(head), 4) && head[0] == 0xED && head[1] == 0xA1 && head[2] == 0xDA &&
         head[3] == 0x01;
}

}  // namespace

std::vector<std::string> logPaths(const std::vector<std::string>& paths, const std::string& tool, bool folders) {
  std::vector<std::string> files;
  for (const auto& p : paths) {
    if (folders && fs::is_directory(p)) {
      std::vector<std::string> in;
      for (const auto& e : fs::directory_iterator(p))
        if (e.is_regular_file() && (e.path().extension() == ".csv" || e.path().extension() == ".lcmlog" ||
                                    startsWithLcmSyncWord(e.path())))
          in.push_back(e.path().string());
      if (in.empty())
        throw std::invalid_argument(tool + ": " + p + ": no logs in this folder (.csv, .lcmlog, or LCM event logs by content)");
      std::sort(in.begin(), in.end());
      files.insert(files.end(), in.begin(), in.end());
    } else if (fs::is_regular_file(p) || fs::is_fifo(p)) {
      files.push_back(p);
    } else {
      throw std::invalid_argument(tool + ": " + p + (fs::exists(p) ? ": not a log file" : ": no such file") +
                                  (folders ? " or folder" : ""));
    }
  }
  std::map<fs::path, std::string> seen;
  for (const auto& f : files) {
    const auto [at, fresh] = seen.emplace(fs::weakly_canonical(f), f);
    if (!fresh)
      throw std::invalid_argument(tool + ": " + f + " is given twice" +
                                  (at->second == f ? std::string() : " (also as " + at->second + ")") +
                                  "; each log may appear once");
  }
  return files;
}

}  // namespace plsa::app

#include <cstdio>
#include <system_error>

#if PLSA_WITH_LCM
#include "plsa/lcm/lcm_log.hpp"
#else
#include <fstream>
#endif

namespace plsa::app {

namespace {

bool sameFile(const fs::path& a, const fs::path& b) {
  std::error_code ec;
  if (fs::exists(a, ec) && fs::exists(b, ec)) {
    const bool same = fs::equivalent(a, b, ec);
    if (!ec) return same;
  }
  return fs::weakly_canonical(a, ec) == fs::weakly_canonical(b, ec);
}

}  // namespace

void refuseOverwritingInputs(const std::string& output, const std::string& option,
                             const std::vector<std::string>& inputs, const std::string& tool) {
  if (output.empty()) return;
  for (const auto& in : inputs)
    if (!in.empty() && sameFile(output, in))
      throw std::invalid_argument(tool + ": " + option + " " + output + " is " +
                                  (in == output ? std::string("an input") : "the input " + in) +
                                  "; plsa never writes over what it reads (choose another output path)");
}

io::Log readLogWithWarnings(const std::string& path, const io::CsvReadOptions& options, const std::string& tool) {
#if PLSA_WITH_LCM
  io::Log log = lcm::readLogFile(path, options);
#else
  {  // an LCM event log starts with its sync word, 0xEDA1DA01
    std::ifstream in(path, std::ios::binary);
    unsigned char head[4] = {};
    if (in.read(reinterpret_cast<char*>(head), 4) && head[0] == 0xED && head[1] == 0xA1 && head[2] == 0xDA &&
        head[3] == 0x01)
      throw std::invalid_argument(path + ": an LCM event log, and this build has no LCM (PLSA_WITH_LCM=OFF)");
  }
  io::Log log = io::readCsvLog(path, options);
#endif
  for (const auto& w : log.warnings) std::fprintf(stderr, "plsa %s: warning: %s\n", tool.c_str(), w.c_str());
  return log;
}

}  // namespace plsa::app
